//! `mmbm tables`: thesis sensitivity tables and the grid-error study.

use clap::Args;
use mmbm::error::Result;
use mmbm_lab::tables;
use std::path::PathBuf;

/// Regenerate thesis Tables 4.1-4.5 and the Fig. 4.6 grid-rule error.
#[derive(Args, Debug)]
#[command(after_help = "Examples:
  mmbm tables
  mmbm tables --json > tables.json
  mmbm tables --plot fig46.png")]
pub struct TablesArgs {
    /// Print JSON instead of Markdown.
    #[arg(long)]
    pub json: bool,
    /// Also draw the grid-error curves (Fig. 4.6 style) to this PNG.
    #[arg(long, value_name = "FILE.png")]
    pub plot: Option<PathBuf>,
}

pub fn run(a: TablesArgs) -> Result<()> {
    // The output's place (writable), before any work.
    mmbm::io::guard::OutputGuard::new()
        .output("--plot", a.plot.as_deref())
        .check()?;
    let ts = tables::all_tables()?;
    let grid = tables::grid_error()?;
    if a.json {
        println!(
            "{}",
            serde_json::json!({ "tables": ts, "grid_error": grid })
        );
    } else {
        println!("MMBM in mm/s, thesis camera (f = 4.2548 mm, 4.65 um, 640x480); exact to rel. tol {:e}.\n", tables::EXACT_TOL);
        for t in &ts {
            println!("{}", tables::to_markdown(t));
        }
        println!("### Fig. 4.6: error of real-time rules vs exact, 100*(mu - mu*)/mu, {} rotation directions\n", tables::study_motions().len());
        println!("| rule | grid | points | mean % | max abs % |\n|---|---|---|---|---|");
        for r in &grid {
            println!(
                "| {} | {}x{} | {} | {:+.4} | {:.4} |",
                r.rule,
                r.nu,
                r.nv,
                r.nu * r.nv,
                r.mean_pct,
                r.max_abs_pct
            );
        }
    }
    if let Some(p) = &a.plot {
        mmbm_lab::tables::grid_error_plot(&grid, p)?;
        eprintln!("wrote {}", p.display());
    }
    Ok(())
}
