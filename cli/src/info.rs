//! `mmbm info`: GPU adapters.

use mmbm::error::Result;

pub fn run() -> Result<()> {
    println!(
        "WGPU_BACKEND={}",
        std::env::var("WGPU_BACKEND").unwrap_or_else(|_| "<unset>".into())
    );
    let all = mmbm::gpu::context::list_adapters();
    println!("adapters found: {}", all.len());
    for a in &all {
        println!("  {a}");
    }
    let ctx = mmbm::gpu::gpu()?;
    println!("using: {} (shader f64: {})", ctx.description, ctx.has_f64);
    Ok(())
}
