//! `mmbm assess`: image blur metrics (JNBM, CPBD, blur effect, Laplacian variance).

use clap::Args;
use mmbm::assess::{assess, load_grey, Assessment};
use mmbm::error::{Error, Result};
use std::path::{Path, PathBuf};

/// Image blur metrics of one or more images.
#[derive(Args, Debug)]
#[command(
    after_help = "Colour images are reduced to Rec. 601 luma of the sRGB values.
JNBM: higher = sharper (null/n/a when the image has no edge block);
CPBD: 0 blurred .. 1 sharp; blur_effect: 0 sharp .. 1 blurred;
laplacian_var: grey levels^2, higher = sharper.

Examples:
  mmbm assess frame.png
  mmbm assess a.png b.png --json"
)]
pub struct AssessArgs {
    /// Images (PNG/JPEG), each at least 64x64 px.
    #[arg(required = true, value_name = "IMAGE")]
    pub images: Vec<PathBuf>,
    /// Print a JSON array (one object per image, in argument order) instead of a table.
    #[arg(long)]
    pub json: bool,
}

fn one(path: &Path) -> Result<Assessment> {
    let g = load_grey(path)?;
    assess(&g).map_err(|e| match e {
        Error::Invalid { what, message } => Error::Image {
            path: path.into(),
            message: format!("{what}: {message}"),
        },
        e => e,
    })
}

pub fn run(a: AssessArgs) -> Result<()> {
    // compute everything first: nothing is printed when one image fails
    let results = a
        .images
        .iter()
        .map(|p| one(p))
        .collect::<Result<Vec<_>>>()?;
    if a.json {
        let arr: Vec<serde_json::Value> = a
            .images
            .iter()
            .zip(&results)
            .map(|(p, r)| {
                serde_json::json!({
                    "path": p.display().to_string(),
                    "jnbm": r.jnbm,
                    "cpbd": r.cpbd,
                    "blur_effect": r.blur_effect,
                    "laplacian_var": r.laplacian_var,
                })
            })
            .collect();
        println!("{}", serde_json::Value::Array(arr));
    } else {
        println!(
            "{:>10} {:>8} {:>12} {:>14}  path",
            "jnbm", "cpbd", "blur_effect", "laplacian_var"
        );
        for (p, r) in a.images.iter().zip(&results) {
            let j = r.jnbm.map_or("n/a".to_string(), |v| format!("{v:.4}"));
            println!(
                "{:>10} {:>8.4} {:>12.4} {:>14.2}  {}",
                j,
                r.cpbd,
                r.blur_effect,
                r.laplacian_var,
                p.display()
            );
        }
    }
    Ok(())
}
