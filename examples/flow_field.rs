//! The per-pixel flow field of a twist (rotation plus a step forward, seen
//! against a wall 1 m ahead) on the GPU, or on its CPU twin where there is no
//! adapter, and its mean speed against the exact cubature.
//!
//! `cargo run --release --example flow_field`

use glam::DVec3;
use mmbm::field::{flow_field, Backend};
use mmbm::{mmbm, Method, Plane, Scene, Twist};

fn main() -> mmbm::Result<()> {
    let scene = Scene {
        plane: Some(Plane::fronto(1.0)), // a fronto-parallel wall at 1 m: translation needs a depth
        ..Scene::thesis()
    };
    // Turning (rad/s) while moving forward at 0.25 m/s.
    let twist = Twist::new(DVec3::new(0.3, -0.2, 0.5), DVec3::new(0.0, 0.0, 0.25));
    // 0 x 0: every pixel centre of the 640 x 480 sensor.
    let field = flow_field(&scene, &twist, 0, 0, Backend::Auto)?;
    let speed = field.speed(); // px/s per pixel, row-major, top row first
    let (w, h) = (field.width as usize, field.height as usize);
    let fastest = speed.iter().copied().fold(0.0f32, f32::max);
    println!(
        "{w} x {h} field: centre pixel (u, v) = ({:.1}, {:.1}) px/s, fastest pixel {fastest:.1} px/s",
        field.u[(h / 2) * w + w / 2],
        field.v[(h / 2) * w + w / 2]
    );
    let exact = mmbm(&scene, &twist, Method::Exact { tol: 1e-9 })?;
    println!(
        "mean speed {:.6} mm/s (field) vs {:.6} mm/s (exact)",
        field.mmbm.mm_s, exact.mm_s
    );
    Ok(())
}
