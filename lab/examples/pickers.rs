//! Issue 36's proof: gyro-based frame picking against the image-only
//! pickers (Laplacian variance, Tenengrad, ffmpeg `blurdetect`), the
//! hybrid and the oracle, on rendered clips with ground truth
//! ([`mmbm_lab::pickers`]). Prints the tables and the throughput, and
//! writes `docs/pickers.md` (with `--quick`: `OUT/pickers.md` only).
//!
//! `cargo run --release -p mmbm-lab --example pickers -- [--quick] [--out DIR]`

use mmbm_lab::pickers::{report, run, Config};
use std::path::{Path, PathBuf};

fn command(cmd: &str, args: &[&str]) -> String {
    std::process::Command::new(cmd)
        .args(args)
        .output()
        .ok()
        .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
        .unwrap_or_default()
}

fn load() -> String {
    std::fs::read_to_string("/proc/loadavg")
        .ok()
        .and_then(|s| s.split_whitespace().next().map(str::to_string))
        .unwrap_or_else(|| "unknown".into())
}

fn cpu() -> String {
    let model = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split_once(':'))
                .map(|(_, v)| v.trim().to_string())
        })
        .unwrap_or_else(|| "an unknown CPU".into());
    let cores = std::thread::available_parallelism().map_or(0, |n| n.get());
    format!("{model}, {cores} cores")
}

fn main() {
    if let Err(e) = bench() {
        eprintln!("pickers: {e}");
        std::process::exit(1);
    }
}

fn bench() -> mmbm::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let quick = args.iter().any(|a| a == "--quick");
    let repo = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let out = match args.iter().position(|a| a == "--out") {
        Some(i) => PathBuf::from(
            args.get(i + 1)
                .ok_or_else(|| mmbm::error::Error::invalid("--out", "needs a folder: --out DIR"))?,
        ),
        None => repo.join("target/pickers"),
    };
    if let Some(a) = args
        .iter()
        .enumerate()
        .find(|&(i, a)| a != "--quick" && a != "--out" && (i == 0 || args[i - 1] != "--out"))
    {
        return Err(mmbm::error::Error::invalid(
            "pickers",
            format!("unknown argument '{}': takes [--quick] [--out DIR]", a.1),
        ));
    }
    let load_start = load();
    let date = command("date", &["-u", "+%Y-%m-%d %H:%M UTC"]);
    let o = run(Config::new(repo.clone(), out.clone(), quick))?;
    let machine = report::Machine {
        cpu: cpu(),
        load: format!("{load_start} at the start, {} at the end", load()),
        date,
    };
    println!("{}", report::picks_table(&o));
    println!("{}", report::goals(&o));
    println!("{}", report::losses(&o));
    for c in &o.clips {
        let m = &c.measures;
        println!(
            "{}: render {:.1} s ({:.0} ms/frame); per frame: gyro {:.3} ms ({:.0} frames/s), \
             Laplacian {:.2} ms, Tenengrad {:.2} ms, blurdetect {:.2} ms",
            c.spec.name,
            c.clip.render_s,
            1e3 * c.clip.render_s / c.clip.frames() as f64,
            m.gyro_ms,
            1e3 / m.gyro_ms,
            m.laplacian_ms,
            m.tenengrad_ms,
            m.blurdetect_ms
        );
    }
    let page = report::page(&o, &machine);
    let to = if quick {
        out.join("pickers.md")
    } else {
        repo.join("docs/pickers.md")
    };
    mmbm::io::atomic::write_atomic(&to, |w| {
        w.write_all(page.as_bytes())
            .map_err(|e| mmbm::error::Error::io(&to, e))
    })?;
    println!("wrote {} ({:.0} s in all)", to.display(), o.total_s);
    Ok(())
}
