//! Blob extraction on frames from the renderer, with known answers: a sharp
//! board gives 16/16 at the projected centres (computed independently by
//! `blobs::board_centres_px` from the board geometry), heavy blur fails.

use glam::DVec3;
use mmbm::board::blobs::{evaluate, extract, BlobParams};
use mmbm::board::{board_centres_px, Board};
use mmbm::render::{render_frame, Quality, RenderJob, Target, Trajectory};
use mmbm::{Camera, Twist};

fn frame(tw: Twist, distance: f64) -> image::RgbImage {
    let cam = Camera::thesis().with_resolution(320, 240);
    let traj = Trajectory::from_twist(tw, 0.07).unwrap();
    let mut job = RenderJob::new(cam, 0.07, traj, Target::parse("blobs", distance).unwrap());
    job.quality = Quality::Custom {
        min_samples: 64,
        max_spacing_px: 0.5,
    };
    job.with_maps = false;
    let out = render_frame(&job).unwrap();
    let bytes = out
        .rgb
        .iter()
        .map(|&x| mmbm::io::images::linear_to_srgb8(x))
        .collect();
    image::RgbImage::from_raw(320, 240, bytes).unwrap()
}

#[test]
fn sharp_rendered_board_gives_all_16_at_their_true_centres() {
    let cam = Camera::thesis().with_resolution(320, 240);
    for d in [3.0, 6.0] {
        let img = frame(Twist::default(), d);
        let (expected, pitch) = board_centres_px(&cam, &Board::thesis(), d).unwrap();
        let blobs = extract(&img, &BlobParams::default()).unwrap();
        let r = evaluate(&blobs, &expected, pitch).unwrap();
        assert!(r.ok, "d = {d}: {r:?}");
        assert_eq!((r.found, r.matched), (16, 16));
        // Sub-pixel agreement between the renderer's board and the blob geometry.
        let e = r.max_error_px.unwrap();
        assert!(e < 0.5, "d = {d}: max centre error {e} px");
    }
}

#[test]
fn heavily_blurred_rendered_board_fails() {
    let cam = Camera::thesis().with_resolution(320, 240);
    // Pitching at 1.5 rad/s for 70 ms smears ~96 px vertically, far over the 26 px pitch at 6 m.
    let img = frame(Twist::new(DVec3::new(1.5, 0.0, 0.0), DVec3::ZERO), 6.0);
    let (expected, pitch) = board_centres_px(&cam, &Board::thesis(), 6.0).unwrap();
    let blobs = extract(&img, &BlobParams::default()).unwrap();
    let r = evaluate(&blobs, &expected, pitch).unwrap();
    assert!(!r.ok, "{r:?}");
    assert!(r.matched < 16, "{r:?}");
}
