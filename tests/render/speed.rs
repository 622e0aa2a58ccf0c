//! A window of a frame (`render::render_window`): the same pixels as the
//! whole frame's render, bit for bit, for both integrators and a textured
//! surround; a noisy camera and a window outside the image are refused.

use glam::DVec3;
use mmbm::camera::Noise;
use mmbm::render::{
    self, render_window, Backend, Background, Integrator, RenderJob, Target, Trajectory, Window,
};
use mmbm::{Camera, Twist};

fn job(integrator: Integrator) -> RenderJob {
    let cam = Camera::thesis().with_resolution(160, 120);
    let tw = Twist::new(DVec3::new(0.6, -0.9, 0.4), DVec3::new(0.05, 0.02, -0.1));
    let tr = Trajectory::from_twist(tw, 0.02).unwrap();
    let mut t = Target::blobs(0.5, 2.0);
    t.surround = Background::Poster;
    let mut j = RenderJob::new(cam, 0.02, tr, t);
    j.backend = Backend::Cpu { threads: None };
    j.integrator = integrator;
    j.with_maps = false;
    j.seed = 7;
    j
}

#[test]
fn a_window_is_the_whole_frames_pixels() {
    for integrator in [Integrator::Analytic, Integrator::Lattice] {
        let j = job(integrator);
        let whole = render::render_frame(&j).unwrap().rgb;
        for win in [
            Window {
                x0: 37,
                y0: 21,
                w: 61,
                h: 45,
            },
            Window {
                x0: 0,
                y0: 0,
                w: 160,
                h: 120,
            },
            Window {
                x0: 159,
                y0: 119,
                w: 1,
                h: 1,
            },
        ] {
            let part = render_window(&j, win).unwrap();
            assert_eq!(part.len(), (win.w * win.h * 3) as usize);
            let cut = win.cut(160, &whole);
            // Bit for bit: the same pass over the same pixels.
            let same = part
                .iter()
                .zip(&cut)
                .all(|(a, b)| a.to_bits() == b.to_bits());
            assert!(same, "{integrator:?} {win:?}");
            // The image is not flat there: the comparison has something to see.
            assert!(cut.iter().any(|&v| (v - cut[0]).abs() > 1e-3), "{win:?}");
        }
    }
}

#[test]
fn noise_and_windows_outside_the_image_are_refused() {
    let j = job(Integrator::Auto);
    for win in [
        Window {
            x0: 150,
            y0: 0,
            w: 11,
            h: 10,
        },
        Window {
            x0: 0,
            y0: 0,
            w: 0,
            h: 10,
        },
        Window {
            x0: 0,
            y0: 115,
            w: 10,
            h: 6,
        },
    ] {
        let e = render_window(&j, win).unwrap_err().to_string();
        assert!(e.contains("window") && e.contains("outside"), "{e}");
    }
    let mut noisy = j.clone();
    noisy.camera.noise = Some(Noise::at_light(20_000.0));
    let e = render_window(
        &noisy,
        Window {
            x0: 0,
            y0: 0,
            w: 8,
            h: 8,
        },
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("noise"), "{e}");
}
