//! A window of a frame (`render::render_window`): the same pixels as the
//! whole frame's render, bit for bit, for both integrators and a textured
//! surround; a noisy camera and a window outside the image are refused; a
//! job's `spacing_window` spaces its instants for that window.

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

/// A job's `spacing_window` spaces the instants for that window's pixels:
/// the whole image as the window is the default pass bit for bit; a central
/// window under a mostly rolling camera needs fewer instants than the
/// sensor's corners, its window render is still the cut of the same job's
/// whole frame, and it stays within the `default` preset's accuracy contract
/// (mean 0.5/255, p99 3/255) of a render four times as finely spaced.
#[test]
fn a_spacing_window_spaces_the_instants_for_its_pixels() {
    let cam = Camera::thesis().with_resolution(160, 120);
    let tw = Twist::new(DVec3::new(0.2, -0.1, 4.0), DVec3::ZERO);
    let tr = Trajectory::from_twist(tw, 0.03).unwrap();
    let mut t = Target::blobs(0.5, 2.0);
    t.surround = Background::Poster;
    let mut j = RenderJob::new(cam, 0.03, tr.clone(), t.clone());
    j.backend = Backend::Cpu { threads: None };
    j.with_maps = false;
    let whole_image = Window {
        x0: 0,
        y0: 0,
        w: 160,
        h: 120,
    };
    let centre = Window {
        x0: 50,
        y0: 38,
        w: 60,
        h: 44,
    };
    let (l_all, l_whole, l_centre) = (
        render::maps::max_path_px(&cam, &t, &tr),
        render::maps::max_path_px_in(&cam, &t, &tr, Some([0, 0, 160, 120])),
        render::maps::max_path_px_in(&cam, &t, &tr, Some([50, 38, 60, 44])),
    );
    assert_eq!(l_all.to_bits(), l_whole.to_bits());
    // About the optical axis the image moves in proportion to the radius.
    assert!(l_centre < 0.7 * l_all, "{l_centre} vs {l_all}");
    let frame = render::render_frame(&j).unwrap().rgb;
    let with_whole = render::render_frame(&RenderJob {
        spacing_window: Some(whole_image),
        ..j.clone()
    })
    .unwrap()
    .rgb;
    assert!(frame
        .iter()
        .zip(&with_whole)
        .all(|(a, b)| a.to_bits() == b.to_bits()));
    let jw = RenderJob {
        spacing_window: Some(centre),
        ..j.clone()
    };
    let part = render_window(&jw, centre).unwrap();
    let cut = centre.cut(160, &render::render_frame(&jw).unwrap().rgb);
    assert!(part
        .iter()
        .zip(&cut)
        .all(|(a, b)| a.to_bits() == b.to_bits()));
    let fine = RenderJob {
        quality: render::Quality::Custom {
            min_samples: 1,
            max_spacing_px: 0.0625,
        },
        ..j.clone()
    };
    let reference = render_window(&fine, centre).unwrap();
    let mut d: Vec<f64> = part
        .iter()
        .zip(&reference)
        .map(|(a, b)| f64::from((a - b).abs()) * 255.0)
        .collect();
    d.sort_by(f64::total_cmp);
    let mean = d.iter().sum::<f64>() / d.len() as f64;
    let p99 = d[d.len() * 99 / 100];
    assert!(mean <= 0.5 && p99 <= 3.0, "mean {mean}/255, p99 {p99}/255");
    // The reference differs from the window render: the comparison can fail.
    assert!(d.last().unwrap() > &0.0);
    // A spacing window outside the image is refused, naming it.
    let bad = RenderJob {
        spacing_window: Some(Window {
            x0: 150,
            y0: 0,
            w: 11,
            h: 10,
        }),
        ..j
    };
    let e = render::render_frame(&bad).unwrap_err().to_string();
    assert!(e.contains("spacing_window") && e.contains("outside"), "{e}");
}
