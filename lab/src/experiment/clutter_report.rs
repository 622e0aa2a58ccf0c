//! The report's section on clutter and the second task metric, per walk and
//! policy, computed from the rendered frames: blob success, false alarms
//! (blobs away from every board place) and corner repeatability
//! ([`super::corners`]), with a sentence drawn from the table.

use super::corners::REPEAT_OK;
use super::measure::FrameRecord;
use super::walk::Walk;
use crate::stats::mean;
use crate::trigger::PolicySpec;

/// One row: a policy on one walk.
struct Row {
    walk: String,
    policy: PolicySpec,
    rendered: usize,
    ok: usize,
    with_false: usize,
    false_alarms: usize,
    rep: Option<f64>,
    vo: usize,
    seconds: f64,
    blur_with_false: Option<f64>,
    blur_without: Option<f64>,
}

fn rows(walks: &[Walk], records: &[FrameRecord]) -> Vec<Row> {
    let mut out = Vec::new();
    for w in walks {
        let seconds = match (w.samples.first(), w.samples.last()) {
            (Some(a), Some(b)) => b.t - a.t,
            _ => 0.0,
        };
        for (p, _) in &w.runs {
            let ms: Vec<_> = records
                .iter()
                .filter(|r| r.walk == w.name && r.seed == w.seed && r.frame.policy == *p)
                .filter_map(|r| r.measure.as_ref())
                .collect();
            let reps: Vec<f64> = ms
                .iter()
                .map(|m| m.corner_rep)
                .filter(|x| x.is_finite())
                .collect();
            let blur = |with: bool| -> Vec<f64> {
                ms.iter()
                    .filter(|m| (m.blobs_false > 0) == with)
                    .map(|m| m.blur_px)
                    .collect()
            };
            out.push(Row {
                walk: w.name.clone(),
                policy: p.clone(),
                rendered: ms.len(),
                ok: ms.iter().filter(|m| m.blobs_ok).count(),
                with_false: ms.iter().filter(|m| m.blobs_false > 0).count(),
                false_alarms: ms.iter().map(|m| m.blobs_false).sum(),
                rep: mean(&reps),
                vo: reps.iter().filter(|&&r| r >= REPEAT_OK).count(),
                seconds,
                blur_with_false: mean(&blur(true)),
                blur_without: mean(&blur(false)),
            });
        }
    }
    out
}

/// The section: a table per walk and policy and the sentences computed from it.
pub fn clutter_md(background: &str, walks: &[Walk], records: &[FrameRecord]) -> String {
    let rows = rows(walks, records);
    let mut s =
        String::from("## Clutter and corners: false alarms and repeatability per policy\n\n");
    s += &format!(
        "Background `{background}`. False alarms: blobs found farther than half a pitch from every board place \
         (a frame with one fails the blob verdict). Repeatability: share of the sharp frame's FAST corners re-found \
         within 2 px (see the map's second metric); VO frames: repeatability >= {REPEAT_OK}, per second of walk. \
         Over the rendered frames.\n\n"
    );
    s += "| walk | policy | rendered | all 16 blobs | frames with a false alarm | false alarms per frame | mean repeatability | VO frames/s |\n";
    s += "|---|---|---|---|---|---|---|---|\n";
    let pct = |a: usize, b: usize| 100.0 * a as f64 / b.max(1) as f64;
    for r in &rows {
        s += &format!(
            "| {} | `{}` | {} | {:.0} % | {} ({:.0} %) | {:.2} | {} | {:.2} |\n",
            r.walk,
            r.policy,
            r.rendered,
            pct(r.ok, r.rendered),
            r.with_false,
            pct(r.with_false, r.rendered),
            r.false_alarms as f64 / r.rendered.max(1) as f64,
            r.rep.map_or("-".into(), |x| format!("{x:.2}")),
            if r.seconds > 0.0 {
                r.vo as f64 / r.seconds
            } else {
                f64::NAN
            },
        );
    }
    let total: usize = rows.iter().map(|r| r.rendered).sum();
    let with: usize = rows.iter().map(|r| r.with_false).sum();
    s += &format!(
        "\n{with} of {total} rendered frames ({:.1} %) have a false alarm",
        pct(with, total)
    );
    let (bw, bn): (Vec<f64>, Vec<f64>) = (
        rows.iter()
            .filter_map(|r| r.blur_with_false.map(|b| b * r.with_false as f64))
            .collect(),
        rows.iter()
            .filter_map(|r| {
                r.blur_without
                    .map(|b| b * (r.rendered - r.with_false) as f64)
            })
            .collect(),
    );
    let (nw, nn) = (with as f64, (total - with) as f64);
    if with > 0 && total > with {
        s += &format!(
            "; their mean ground-truth blur is {:.1} px, against {:.1} px for the frames without",
            bw.iter().sum::<f64>() / nw,
            bn.iter().sum::<f64>() / nn
        );
    }
    s += ".";
    if let Some(best) = rows
        .iter()
        .filter(|r| r.rendered > 0)
        .max_by(|a, b| (a.vo as f64 / a.seconds).total_cmp(&(b.vo as f64 / b.seconds)))
    {
        s += &format!(
            " The most VO frames per second: `{}` on the {} walk ({:.2}/s, mean repeatability {}).",
            best.policy,
            best.walk,
            best.vo as f64 / best.seconds,
            best.rep.map_or("-".into(), |x| format!("{x:.2}"))
        );
    }
    s += "\n\n";
    s
}
