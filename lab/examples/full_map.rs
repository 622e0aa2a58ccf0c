//! The benefit map of `mmbm demo --full` alone, without its experiment stage
//! (the thesis tables): three gaits, both boards, six lights, seeds 1-5, the
//! same frames, windows, verdict and report section as `demo --full`. Writes
//! `OUT/report.md` (the three lines, the map with the timing, second-task and
//! goal sections, the headline read from the map, the configuration) and
//! `OUT/benefit_map.png` (the report states the map's time); prints the
//! map's answer lines.
//!
//! ```text
//! cargo run --release -p mmbm-lab --example full_map -- OUT
//! ```
use mmbm::error::Error;
use mmbm::io::atomic::write_atomic;
use mmbm::render::Quality;
use mmbm_lab::experiment::{
    benefit_map_with, headline_view_md, heat_map_png, map_answer, opening_md, ExperimentConfig,
    Renders,
};
use std::path::PathBuf;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let out = PathBuf::from(
        std::env::args()
            .nth(1)
            .unwrap_or_else(|| "mmbm-full-map".into()),
    );
    let cfg = ExperimentConfig::demo_full();
    cfg.validate()?;
    let quality: Quality = cfg.quality.parse()?;
    let map =
        benefit_map_with(&cfg, quality, true, Renders::Shared)?.ok_or("demo --full has a map")?;
    std::fs::create_dir_all(&out).map_err(|e| Error::io(&out, e))?;
    let figure = "benefit_map.png";
    heat_map_png(&out.join(figure), &map)?;
    let mut s = String::from("# The benefit map of `mmbm demo --full`\n\n");
    s += &format!(
        "The map alone (`cargo run --release -p mmbm-lab --example full_map`; the experiment stage of `demo --full` not run): \
         {} frames rendered, each judged at {} lights, in {:.1} s.\n\n",
        map.renders,
        map.lights.len(),
        map.seconds
    );
    s += &opening_md(&map, Some(figure));
    if let Some(view) = headline_view_md(&cfg, &map) {
        s += &view;
    }
    s += "\n## Configuration\n\n```toml\n";
    s += &cfg.to_toml();
    s += "```\n";
    let report = out.join("report.md");
    write_atomic(&report, |w| {
        w.write_all(s.as_bytes()).map_err(|e| Error::io(&report, e))
    })?;
    for line in map_answer(&map, &report) {
        println!("{line}");
    }
    Ok(())
}
