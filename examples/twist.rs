//! MMBM of one twist: the thesis camera turning at 1 rad/s about every axis.
//!
//! `cargo run --release --example twist`

use mmbm::{mmbm, Method, Scene, Twist};

fn main() -> mmbm::Result<()> {
    let scene = Scene::thesis(); // f = 4.2548 mm, 4.65 um pixels, 640 x 480, no plane
    let twist = Twist::rotation(1.0, 1.0, 1.0); // rad/s, camera frame (x right, y down, z forward)
    let exact = mmbm(&scene, &twist, Method::Exact { tol: 1e-9 })?;
    let thesis = mmbm(&scene, &twist, Method::default())?; // riemann:8x6, the thesis's MMBM*
    println!(
        "exact: {:.6} mm/s ({:.1} px/s, error estimate {:.1e} mm/s)",
        exact.mm_s,
        exact.px_s,
        exact.error_estimate.unwrap_or(f64::NAN)
    );
    println!("riemann:8x6: {:.6} mm/s", thesis.mm_s);
    Ok(())
}
