//! `mmbm assess`: image blur metrics (JNBM, CPBD and their direction-aware
//! variants, blur effect, Laplacian variance).

use clap::Args;
use mmbm::assess::{assess, load_grey, Assessment};
use mmbm::error::{Error, Result};
use std::path::{Path, PathBuf};

/// Image blur metrics of one or more images.
#[derive(Args, Debug)]
#[command(
    after_help = "Colour images are reduced to Rec. 601 luma of the sRGB values.
JNBM: higher = sharper (null/n/a when the image has no edge block);
CPBD: 0 blurred .. 1 sharp (both as the authors' MATLAB code computes them:
edge widths along rows only, blind to vertical blur);
jnbm_2d, cpbd_2d: the same with widths along rows and columns;
blur_effect: 0 sharp .. 1 blurred; laplacian_var: grey levels^2, higher = sharper.

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
                    "jnbm_2d": r.jnbm_2d,
                    "cpbd_2d": r.cpbd_2d,
                    "blur_effect": r.blur_effect,
                    "laplacian_var": r.laplacian_var,
                })
            })
            .collect();
        println!("{}", serde_json::Value::Array(arr));
    } else {
        println!(
            "{:>10} {:>8} {:>10} {:>8} {:>12} {:>14}  path",
            "jnbm", "cpbd", "jnbm_2d", "cpbd_2d", "blur_effect", "laplacian_var"
        );
        let opt = |v: Option<f64>| v.map_or("n/a".to_string(), |v| format!("{v:.4}"));
        for (p, r) in a.images.iter().zip(&results) {
            println!(
                "{:>10} {:>8.4} {:>10} {:>8.4} {:>12.4} {:>14.2}  {}",
                opt(r.jnbm),
                r.cpbd,
                opt(r.jnbm_2d),
                r.cpbd_2d,
                r.blur_effect,
                r.laplacian_var,
                p.display()
            );
        }
    }
    Ok(())
}
