//! How the image blur metrics follow the ground truth: per-metric Spearman
//! correlations with the renderer's blur, and the measured split of that
//! blur into horizontal and vertical motion. Every sentence is computed.

use super::measure::{FrameMeasure, FrameRecord};
use crate::stats::{mean, spearman};

/// One image metric: its name, whether higher means sharper, and its value.
struct Metric {
    name: &'static str,
    sharper_is_higher: bool,
    value: fn(&FrameMeasure) -> f64,
}

const METRICS: [Metric; 6] = [
    Metric {
        name: "JNBM (authors' code)",
        sharper_is_higher: true,
        value: |m| m.jnbm,
    },
    Metric {
        name: "CPBD (authors' code)",
        sharper_is_higher: true,
        value: |m| m.cpbd,
    },
    Metric {
        name: "JNBM, both axes (`jnbm_2d`)",
        sharper_is_higher: true,
        value: |m| m.jnbm_2d,
    },
    Metric {
        name: "CPBD, both axes (`cpbd_2d`)",
        sharper_is_higher: true,
        value: |m| m.cpbd_2d,
    },
    Metric {
        name: "blur effect (Crete)",
        sharper_is_higher: false,
        value: |m| m.blur_effect,
    },
    Metric {
        name: "Laplacian variance",
        sharper_is_higher: true,
        value: |m| m.laplacian_var,
    },
];

/// A correlation as text ("n/a" when undefined).
fn rho(x: Option<f64>) -> String {
    x.map_or("n/a".into(), |r| format!("{r:+.2}"))
}

/// The Markdown section: blur split and per-metric Spearman correlations over
/// every rendered frame. Empty when fewer than 3 frames were rendered.
pub fn metrics_md(records: &[FrameRecord]) -> String {
    let ms: Vec<&FrameMeasure> = records.iter().filter_map(|r| r.measure.as_ref()).collect();
    if ms.len() < 3 {
        return String::new();
    }
    let col = |f: fn(&FrameMeasure) -> f64| ms.iter().map(|m| f(m)).collect::<Vec<f64>>();
    let (blur, h, v) = (
        col(|m| m.blur_px),
        col(|m| m.blur_h_px),
        col(|m| m.blur_v_px),
    );
    let finite_mean = |x: &[f64]| {
        let f: Vec<f64> = x.iter().copied().filter(|v| v.is_finite()).collect();
        mean(&f).unwrap_or(0.0)
    };
    let (mh, mv) = (finite_mean(&h), finite_mean(&v));
    let vshare = 100.0 * mv / (mh + mv);
    let mut s = String::from("\n## Image metrics against the ground truth\n\n");
    s += &format!(
        "Over the {} rendered frames (every walk, seed and policy), the image motion over the exposure is \
         {:.1} px horizontally and {:.1} px vertically on average (sums of |dx| and |dy| along the tracks of \
         a 32 x 24 grid of pixels): vertical motion is {:.0} % of it{}.\n\n",
        ms.len(),
        mh,
        mv,
        vshare,
        if vshare > 60.0 {
            ", most of the blur"
        } else if vshare < 40.0 {
            "; horizontal motion is most of the blur"
        } else {
            "; neither direction dominates"
        }
    );
    s += "Spearman rank correlation of each metric with the ground-truth blur (sensor-mean path length), \
          and with its horizontal and vertical parts. A metric that follows the truth correlates \
          negatively when higher means sharper (positively for the blur effect).\n\n";
    s += "| metric | higher = | with blur | with horizontal | with vertical | verdict |\n|---|---|---|---|---|---|\n";
    let mut best: Option<(&str, f64)> = None;
    let mut wrong = Vec::new();
    for m in &METRICS {
        let x = col(m.value);
        let (rb, rh, rv) = (spearman(&x, &blur), spearman(&x, &h), spearman(&x, &v));
        // Oriented so that positive = follows the truth.
        let sign = if m.sharper_is_higher { -1.0 } else { 1.0 };
        let oriented = rb.map(|r| sign * r);
        let verdict = match oriented {
            None => "undefined",
            Some(r) if r >= 0.5 => "follows the blur",
            Some(r) if r > 0.0 => "follows it weakly",
            Some(_) => {
                wrong.push(m.name);
                "wrong direction"
            }
        };
        if let Some(r) = oriented {
            if best.is_none_or(|(_, b)| r > b) {
                best = Some((m.name, r));
            }
        }
        s += &format!(
            "| {} | {} | {} | {} | {} | {} |\n",
            m.name,
            if m.sharper_is_higher {
                "sharper"
            } else {
                "blurrier"
            },
            rho(rb),
            rho(rh),
            rho(rv),
            verdict
        );
    }
    s.push('\n');
    if let Some((name, r)) = best {
        s += &format!("The metric closest to the ground truth is {name} (|Spearman| {r:.2}). ",);
    }
    if wrong.is_empty() {
        s += "Every metric moves in the right direction.\n";
    } else {
        s += &format!(
            "Moving the wrong way (calling blurred frames sharper): {}.\n",
            wrong.join(", ")
        );
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::trigger::Frame;

    fn rec(blur: f64, h: f64, v: f64, jnbm: f64) -> FrameRecord {
        FrameRecord {
            walk: "w".into(),
            seed: 1,
            frame: Frame {
                policy: "fixed:5".parse().unwrap(),
                index: 0,
                trigger_t: 0.0,
                exposure_start: 0.0,
                exposure_end: 0.07,
                mmbm_trigger_mm_s: 0.0,
                mmbm_exposure_mm_s: 0.0,
                kept: true,
                gain: 1.0,
            },
            measure: Some(FrameMeasure {
                blur_px: blur,
                blur_h_px: h,
                blur_v_px: v,
                jnbm,
                cpbd: blur, // wrong direction on purpose
                jnbm_2d: f64::NAN,
                cpbd_2d: f64::NAN,
                blur_effect: blur * blur,
                laplacian_var: 1.0 / blur,
                ..FrameMeasure::default()
            }),
        }
    }

    #[test]
    fn split_and_correlations_are_computed() {
        let r = vec![
            rec(1.0, 0.5, 1.0, 3.0),
            rec(2.0, 0.5, 2.0, 2.0),
            rec(4.0, 1.0, 3.5, 1.5),
            rec(8.0, 1.0, 7.5, 1.0),
        ];
        let s = metrics_md(&r);
        // 0.75 px horizontal, 3.5 px vertical: 82 % vertical.
        assert!(
            s.contains("0.8 px horizontally and 3.5 px vertically"),
            "{s}"
        );
        assert!(
            s.contains("vertical motion is 82 % of it, most of the blur"),
            "{s}"
        );
        assert!(
            s.contains("| JNBM (authors' code) | sharper | -1.00 |"),
            "{s}"
        );
        assert!(
            s.contains("| CPBD (authors' code) | sharper | +1.00 |"),
            "{s}"
        );
        assert!(s.contains(
            "Moving the wrong way (calling blurred frames sharper): CPBD (authors' code)."
        ));
        assert!(
            s.contains("| JNBM, both axes (`jnbm_2d`) | sharper | n/a |"),
            "{s}"
        );
        assert!(metrics_md(&r[..2]).is_empty());
    }
}
