//! `frames.csv`, the experiment's table of frames: one row per triggered
//! frame of every walk and policy, its measurements empty when the frame was
//! not rendered. Written through `csv` + serde from [`FrameRow`], whose fields
//! are the columns of [`FRAMES_HEADER`] in order.

use super::measure::{FrameMeasure, FrameRecord};
use crate::error::{Error, Result};
use serde::{Serialize, Serializer};

/// Columns of `frames.csv` (the first six are the contract).
pub const FRAMES_HEADER: &str = "policy,trigger_t,blur_px,jnbm,blobs_found,blobs_ok,walk,exposure_start,exposure_end,\
mmbm_trigger_mm_s,mmbm_exposure_mm_s,kept,rendered,distance_m,disp_px,cpbd,blur_effect,laplacian_var,\
blobs_matched,samples_per_pixel,render_ms,pose_err_m,pose_err_deg,quality,seed,blobs_ok_fixed,\
blur_h_px,blur_v_px,jnbm_2d,cpbd_2d,gain,family,blobs_false,corner_repeatability";

/// An f64 written as Rust's `Display` shows it (shortest round-trip digits,
/// never an exponent: `1`, `0.0000001`, `NaN`, `inf`), not as the `csv`
/// crate's own float format (`1.0`, `1e-7`).
struct Shown(f64);

impl Serialize for Shown {
    fn serialize<S: Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        s.collect_str(&self.0)
    }
}

/// A measured value: empty when the frame was not rendered or the value is
/// not finite, else as [`Shown`].
struct Measured(Option<f64>);

impl Serialize for Measured {
    fn serialize<S: Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        match self.0 {
            Some(x) if x.is_finite() => s.collect_str(&x),
            _ => s.serialize_str(""),
        }
    }
}

/// One line of `frames.csv`: the fields in [`FRAMES_HEADER`]'s order, named
/// as its columns (a unit test holds the two together). Flags are 0 or 1.
#[derive(Serialize)]
struct FrameRow<'a> {
    policy: &'a str,
    trigger_t: Shown,
    blur_px: Measured,
    jnbm: Measured,
    blobs_found: Option<usize>,
    blobs_ok: Option<u8>,
    walk: &'a str,
    exposure_start: Shown,
    exposure_end: Shown,
    mmbm_trigger_mm_s: Shown,
    mmbm_exposure_mm_s: Shown,
    kept: u8,
    rendered: u8,
    distance_m: Measured,
    disp_px: Measured,
    cpbd: Measured,
    blur_effect: Measured,
    laplacian_var: Measured,
    blobs_matched: Option<usize>,
    samples_per_pixel: Option<u32>,
    render_ms: Measured,
    pose_err_m: Measured,
    pose_err_deg: Measured,
    quality: &'a str,
    seed: u64,
    blobs_ok_fixed: Option<u8>,
    blur_h_px: Measured,
    blur_v_px: Measured,
    jnbm_2d: Measured,
    cpbd_2d: Measured,
    gain: Shown,
    /// docs/spec.md section 10's family of the policy (`fixed`, `fixed-exposure`,
    /// `auto-exposure`, `mmbm`, `oracle`).
    family: &'static str,
    /// Blobs found away from every board place (false alarms).
    blobs_false: Option<usize>,
    /// Share of the sharp frame's corners re-found within 2 px.
    corner_repeatability: Measured,
}

impl<'a> FrameRow<'a> {
    fn new(r: &'a FrameRecord, quality: &'a str) -> Self {
        let f = &r.frame;
        let m = r.measure.as_ref();
        let v = |get: fn(&FrameMeasure) -> f64| Measured(m.map(get));
        FrameRow {
            policy: r.frame.policy.as_str(),
            trigger_t: Shown(f.trigger_t),
            blur_px: v(|m| m.blur_px),
            jnbm: v(|m| m.jnbm),
            blobs_found: m.map(|m| m.blobs_found),
            blobs_ok: m.map(|m| m.blobs_ok as u8),
            walk: &r.walk,
            exposure_start: Shown(f.exposure_start),
            exposure_end: Shown(f.exposure_end),
            mmbm_trigger_mm_s: Shown(f.mmbm_trigger_mm_s),
            mmbm_exposure_mm_s: Shown(f.mmbm_exposure_mm_s),
            kept: f.kept as u8,
            rendered: m.is_some() as u8,
            distance_m: v(|m| m.distance_m),
            disp_px: v(|m| m.disp_px),
            cpbd: v(|m| m.cpbd),
            blur_effect: v(|m| m.blur_effect),
            laplacian_var: v(|m| m.laplacian_var),
            blobs_matched: m.map(|m| m.blobs_matched),
            samples_per_pixel: m.map(|m| m.samples_per_pixel),
            render_ms: v(|m| m.render_ms),
            pose_err_m: v(|m| m.pose_err_m),
            pose_err_deg: v(|m| m.pose_err_deg),
            quality: if m.is_some() { quality } else { "" },
            seed: r.seed,
            blobs_ok_fixed: m.map(|m| m.blobs_ok_fixed as u8),
            blur_h_px: v(|m| m.blur_h_px),
            blur_v_px: v(|m| m.blur_v_px),
            jnbm_2d: v(|m| m.jnbm_2d),
            cpbd_2d: v(|m| m.cpbd_2d),
            gain: Shown(f.gain),
            family: r.frame.policy.policy_family().name(),
            blobs_false: m.map(|m| m.blobs_false),
            corner_repeatability: v(|m| m.corner_rep),
        }
    }
}

/// `frames.csv` text; `quality` is the render preset, written for rendered frames.
pub fn frames_csv(records: &[FrameRecord], quality: &str) -> Result<String> {
    let e = |e: csv::Error| Error::invalid("frames.csv", e.to_string());
    // The header is written by hand so that it is there even with no rows.
    let mut w = csv::WriterBuilder::new()
        .has_headers(false)
        .from_writer(Vec::new());
    w.write_record(FRAMES_HEADER.split(',')).map_err(e)?;
    for r in records {
        w.serialize(FrameRow::new(r, quality)).map_err(e)?;
    }
    let bytes = w
        .into_inner()
        .map_err(|x| Error::invalid("frames.csv", x.to_string()))?;
    String::from_utf8(bytes).map_err(|x| Error::invalid("frames.csv", x.to_string()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::trigger::Frame;

    /// Two records: a rendered frame with awkward numbers (integral floats,
    /// tiny and huge magnitudes, NaN, infinity) and a skipped frame.
    fn records() -> Vec<FrameRecord> {
        let frame = Frame {
            policy: "deadline:5:0.4".parse().unwrap(),
            index: 7,
            trigger_t: 0.1 + 0.2,
            exposure_start: 1.0,
            exposure_end: 1e-7,
            mmbm_trigger_mm_s: 1e21,
            mmbm_exposure_mm_s: -0.0,
            kept: true,
            gain: 1.0,
        };
        let measure = FrameMeasure {
            distance_m: 5.999652405925646,
            blur_px: 2.0,
            disp_px: f64::NAN,
            blur_h_px: f64::INFINITY,
            blur_v_px: 1e-10,
            jnbm: 0.25,
            cpbd: 123456789.125,
            jnbm_2d: -1.5,
            cpbd_2d: 0.0,
            blur_effect: 0.41040770904235263,
            laplacian_var: 73.92057289971574,
            blobs_found: 16,
            blobs_matched: 15,
            blobs_false: 2,
            corner_rep: 0.375,
            blobs_ok: true,
            blobs_ok_fixed: false,
            pose_err_m: f64::NEG_INFINITY,
            pose_err_deg: 11.599904771512902,
            samples_per_pixel: 64,
            render_ms: 52.500659,
        };
        vec![
            FrameRecord {
                walk: "slow".into(),
                seed: 3,
                frame: frame.clone(),
                measure: Some(measure),
            },
            FrameRecord {
                walk: "fast".into(),
                seed: u64::MAX,
                frame: Frame {
                    policy: "fixed:5+exp:2:0.02".parse().unwrap(),
                    trigger_t: f64::NAN,
                    exposure_end: f64::INFINITY,
                    kept: false,
                    gain: 2.5,
                    ..frame
                },
                measure: None,
            },
        ]
    }

    /// The text as the hand-written `writeln!` produced it before `frames.csv`
    /// went through `csv` + serde (byte for byte), with the two columns
    /// appended since (`blobs_false`, `corner_repeatability`).
    #[test]
    fn frames_csv_text_is_unchanged() {
        let want = format!(
            "{FRAMES_HEADER}\n\
             deadline:5:0.4,0.30000000000000004,2,0.25,16,1,slow,1,0.0000001,\
             1000000000000000000000,-0,1,1,5.999652405925646,,123456789.125,\
             0.41040770904235263,73.92057289971574,15,64,52.500659,,11.599904771512902,\
             fast,3,0,,0.0000000001,-1.5,0,1,mmbm,2,0.375\n\
             fixed:5+exp:2:0.02,NaN,,,,,fast,1,inf,1000000000000000000000,-0,0,0,\
             ,,,,,,,,,,,18446744073709551615,,,,,,2.5,gyro-exposure,,\n"
        );
        assert_eq!(frames_csv(&records(), "fast").unwrap(), want);
        assert_eq!(
            frames_csv(&[], "fast").unwrap(),
            format!("{FRAMES_HEADER}\n")
        );
    }

    /// The row struct and the header name the same columns in the same order,
    /// and every record, rendered or not, has one field per column.
    #[test]
    fn frames_csv_rows_match_the_header() {
        let text = frames_csv(&records(), "fast").unwrap();
        let mut rd = csv::Reader::from_reader(text.as_bytes());
        let header: Vec<String> = rd.headers().unwrap().iter().map(String::from).collect();
        assert_eq!(header.len(), 34);
        let rows: Vec<csv::StringRecord> = rd.records().map(|r| r.unwrap()).collect();
        assert_eq!(rows.len(), 2);
        let col = |row: &csv::StringRecord, name: &str| -> String {
            let i = header.iter().position(|h| h == name).unwrap();
            row[i].to_string()
        };
        for row in &rows {
            assert_eq!(row.len(), header.len());
        }
        assert_eq!(col(&rows[0], "policy"), "deadline:5:0.4");
        assert_eq!(col(&rows[0], "blobs_matched"), "15");
        assert_eq!(col(&rows[0], "quality"), "fast");
        assert_eq!(col(&rows[0], "blur_v_px"), "0.0000000001");
        assert_eq!(col(&rows[0], "gain"), "1");
        assert_eq!(col(&rows[1], "rendered"), "0");
        assert_eq!(col(&rows[1], "seed"), "18446744073709551615");
        assert_eq!(col(&rows[1], "gain"), "2.5");
        assert_eq!(col(&rows[1], "family"), "gyro-exposure");
        assert_eq!(col(&rows[0], "blobs_false"), "2");
        assert_eq!(col(&rows[0], "corner_repeatability"), "0.375");
        assert_eq!(col(&rows[1], "corner_repeatability"), "");
        // The struct's own field names, as serde writes them, are the header.
        let mut w = csv::Writer::from_writer(Vec::new());
        w.serialize(FrameRow::new(&records()[1], "fast")).unwrap();
        let own = String::from_utf8(w.into_inner().unwrap()).unwrap();
        assert_eq!(own.lines().next(), Some(FRAMES_HEADER));
    }

    /// A custom policy's frame: its label in the `policy` column and family
    /// `custom`, both from the frame's spec.
    #[test]
    fn a_custom_policy_is_written_by_its_label() {
        let mut r = records().remove(1);
        r.frame.policy = crate::trigger::PolicySpec::custom("mine:1, \"quoted\"");
        let text = frames_csv(&[r], "fast").unwrap();
        let mut rd = csv::Reader::from_reader(text.as_bytes());
        let header: Vec<String> = rd.headers().unwrap().iter().map(String::from).collect();
        let row = rd.records().next().unwrap().unwrap();
        let col = |name: &str| row[header.iter().position(|h| h == name).unwrap()].to_string();
        assert_eq!(col("policy"), "mine:1, \"quoted\"");
        assert_eq!(col("family"), "custom");
    }
}
