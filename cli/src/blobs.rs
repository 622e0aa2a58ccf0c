//! `mmbm blobs`: extract the 16 red blobs of the thesis target from an image.

use super::args::CameraArgs;
use clap::Args;
use mmbm::board::blobs::{components, evaluate, red_mask, Blob, BlobParams, BlobResult};
use mmbm::board::{board_centres_px, Board};
use mmbm::error::{Error, Result};
use std::path::{Path, PathBuf};

/// Which board the expected centres come from: the same names as
/// `render --target` (`blobs`, `blobs:SCALE`), plus `blobs-half` (= `blobs:0.5`).
fn parse_board(s: &str) -> std::result::Result<Board, String> {
    match s {
        "blobs" => Ok(Board::thesis()),
        "blobs-half" => Ok(Board::half()),
        _ => match s.strip_prefix("blobs:").map(str::parse::<f64>) {
            Some(Ok(k)) if k.is_finite() && k > 0.0 => Ok(Board::thesis().scaled(k)),
            _ => Err(format!(
                "'{s}': expected blobs (the thesis board: 4x4 red 10 cm squares, 2 cm gaps), \
                 blobs:SCALE (every length times SCALE > 0) or blobs-half (= blobs:0.5, thesis Table 6.2)"
            )),
        },
    }
}

/// Extract the red blobs of the thesis target (and check them against the truth).
#[derive(Args, Debug)]
#[command(
    after_help = "Redness = R - max(G,B) on the sRGB values; red when above the threshold
(adaptive by default: half the 99.9th-percentile redness, at least 40).
Success: exactly as many blobs as expected and each within half a pitch of its true centre.

Examples:
  mmbm blobs frame.png
  mmbm blobs frame.png --target blobs --distance 6 --json
  mmbm blobs frame.png --expected truth.json --mask mask.png
truth.json: {\"centres_px\": [[x, y], ...], \"pitch_px\": 18.3}"
)]
pub struct BlobsArgs {
    /// Image (PNG/JPEG, sRGB).
    #[arg(value_name = "IMAGE")]
    pub image: PathBuf,
    /// Expected centres: JSON {"centres_px": [[x,y],...], "pitch_px": P}.
    #[arg(long, value_name = "FILE", conflicts_with_all = ["distance", "target"])]
    pub expected: Option<PathBuf>,
    /// Board whose projected centres are expected (with --distance): blobs
    /// (default), blobs:SCALE as in `render --target`, or blobs-half (= blobs:0.5).
    #[arg(long, value_name = "BOARD", value_parser = parse_board, requires = "distance")]
    pub target: Option<Board>,
    /// Distance of the fronto-parallel board on the optical axis, m.
    #[arg(allow_negative_numbers = true, long, value_name = "M")]
    pub distance: Option<f64>,
    /// Fixed redness threshold 0..255 (default: adaptive).
    #[arg(allow_negative_numbers = true, long, value_name = "T")]
    pub threshold: Option<f64>,
    /// Smallest blob kept, pixels.
    #[arg(long, value_name = "PX", default_value_t = 4)]
    pub min_area: u32,
    /// Write the red mask as a PNG.
    #[arg(long, value_name = "PNG")]
    pub mask: Option<PathBuf>,
    /// Print JSON instead of text.
    #[arg(long)]
    pub json: bool,
    #[command(flatten)]
    pub camera: CameraArgs,
}

#[derive(serde::Deserialize)]
struct Expected {
    centres_px: Vec<(f64, f64)>,
    pitch_px: f64,
}

fn read_expected(path: &Path) -> Result<(Vec<(f64, f64)>, f64)> {
    let s = mmbm::io::input::read_text(path)?;
    let e: Expected = serde_json::from_str(&s).map_err(|e| Error::Config {
        path: path.into(),
        message: e.to_string(),
    })?;
    Ok((e.centres_px, e.pitch_px))
}

pub fn run(a: BlobsArgs) -> Result<()> {
    // The output's place, against every input, before any work.
    mmbm::io::guard::OutputGuard::new()
        .output("--mask", a.mask.as_deref())
        .input("IMAGE", Some(&a.image))
        .input("--expected", a.expected.as_deref())
        .input("--camera", a.camera.camera.as_deref())
        .check()?;
    let img = mmbm::io::images::read_rgb8(&a.image)?;
    let params = BlobParams {
        threshold: a.threshold,
        min_area: a.min_area,
        ..BlobParams::default()
    };
    let expected = if let Some(p) = &a.expected {
        Some(read_expected(p)?)
    } else if let Some(d) = a.distance {
        let cam = a.camera.camera()?;
        if (cam.width, cam.height) != img.dimensions() {
            return Err(Error::invalid(
                "camera",
                format!(
                    "{}: image is {}x{} but the camera is {}x{} (use --sensor WxH)",
                    a.image.display(),
                    img.width(),
                    img.height(),
                    cam.width,
                    cam.height
                ),
            ));
        }
        let board = a.target.unwrap_or_else(Board::thesis);
        Some(board_centres_px(&cam, &board, d)?)
    } else {
        None
    };
    let (mask, t) = red_mask(&img, &params)?;
    let blobs = components(&mask, &params);
    let result = match &expected {
        Some((c, p)) => Some(evaluate(&blobs, c, *p)?),
        None => None,
    };
    if let Some(p) = &a.mask {
        mmbm::io::atomic::write_atomic_path(p, |tmp| {
            mask.save_with_format(tmp, image::ImageFormat::Png)
                .map_err(|e| Error::Image {
                    path: p.clone(),
                    message: e.to_string(),
                })
        })?;
    }
    if a.json {
        let o = serde_json::json!({
            "path": a.image.display().to_string(),
            "threshold": t,
            "blobs": blobs,
            "result": result,
            "expected_px": expected.as_ref().map(|e| &e.0),
            "pitch_px": expected.as_ref().map(|e| e.1),
        });
        println!("{o}");
    } else {
        print_text(&a.image, t, &blobs, result.as_ref());
    }
    Ok(())
}

fn print_text(path: &Path, t: f64, blobs: &[Blob], r: Option<&BlobResult>) {
    println!(
        "{}: {} blobs (redness threshold {t:.1})",
        path.display(),
        blobs.len()
    );
    for (i, b) in blobs.iter().enumerate() {
        println!(
            "  {i:2}: centre ({:8.2}, {:8.2}) px, area {} px",
            b.centre.0, b.centre.1, b.area
        );
    }
    if let Some(r) = r {
        println!(
            "found {} matched {} missed {} false {} -> {}{}",
            r.found,
            r.matched,
            r.missed,
            r.false_blobs,
            if r.ok { "OK" } else { "FAIL" },
            r.max_error_px
                .map_or(String::new(), |e| format!(" (max centre error {e:.2} px)"))
        );
    }
}
