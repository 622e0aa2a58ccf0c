//! CPU twins of `field.wgsl` (the lens module's are in [`crate::gpu::lens`]): the same f32 formula and summation
//! order as the kernels (single-threaded and rayon), plus an f64 reference
//! built from the library's own [`crate::model::flow::flow_distorted`] and [`Camera`] maps.

use super::kernel::{FlowParams, Grid, TwistGpu, CHUNK, TILE, WG};
use super::table::{valid_len, LensSample, LensTable};
use crate::camera::Camera;
use crate::error::Result;
use crate::gpu::lens::{MODEL_NONE, MODEL_TABLE};
use crate::model::flow::flow_distorted;
use crate::model::motion::{Plane, Twist};
use rayon::prelude::*;

/// Twin of the shader's `sensor_point`: centre of grid cell `(i, j)`, mm.
#[inline(always)]
pub fn sensor_point(p: &FlowParams, i: u32, j: u32) -> (f32, f32) {
    let x = (i as f32 + 0.5) * p.step_x;
    let y = (j as f32 + 0.5) * p.step_y;
    let v = (y - p.cy) * p.pitch_y;
    let u = (x - p.cx - p.skew_over_f * v) * p.pitch_x;
    (u, v)
}

/// Twin of the shader's `flow_mm`: flow (mm/s) at sensor point `(u, v)` mm.
#[inline(always)]
pub fn flow_mm(p: &FlowParams, tw: &TwistGpu, u: f32, v: f32) -> (f32, f32) {
    let f = p.f_mm;
    let [wx, wy, wz, _] = tw.omega;
    let [tx, ty, tz, _] = tw.velocity;
    let iz = tw.inv_depth[0] + tw.inv_depth[1] * u + tw.inv_depth[2] * v;
    let du = wz * v - wy * f - (wy / f) * u * u + (wx / f) * u * v - f * iz * tx + u * iz * tz;
    let dv = -wz * u + wx * f - (wy / f) * u * v + (wx / f) * v * v - f * iz * ty + v * iz * tz;
    (du, dv)
}

/// The lens functions' twins are the lens module's ([`crate::gpu::lens`]).
pub use crate::gpu::lens::{atan_poly, distort, jacobian, undistort, UNDISTORT_STEPS};

/// Twin of the shader's `sample_flow`: the flow (mm/s on the distorted
/// sensor) at the centre of grid cell `(i, j)`; in table mode (model 3) the
/// pinhole flow at the sample's `q` through its Jacobian, from `lens`
/// (the grid's [`LensTable::samples`]; unused by the other models).
#[inline(always)]
pub fn sample_flow(
    p: &FlowParams,
    lens: &[LensSample],
    tw: &TwistGpu,
    i: u32,
    j: u32,
) -> (f32, f32) {
    if p.lens.model == MODEL_TABLE {
        let s = &lens[(j * p.grid_w + i) as usize];
        let (a, b) = flow_mm(p, tw, s.q[0] * p.f_mm, s.q[1] * p.f_mm);
        return (s.j0[0] * a + s.j0[1] * b, s.j1[0] * a + s.j1[1] * b);
    }
    let (u, v) = sensor_point(p, i, j);
    if p.lens.model == MODEL_NONE {
        return flow_mm(p, tw, u, v);
    }
    let f = p.f_mm;
    let (x, y) = undistort(&p.lens, u / f, v / f);
    let (a, b) = flow_mm(p, tw, x * f, y * f);
    let jm = jacobian(&p.lens, x, y);
    (jm[0][0] * a + jm[0][1] * b, jm[1][0] * a + jm[1][1] * b)
}

/// Twin of the shader's `px_velocity`: mm/s to px/s.
#[inline(always)]
pub fn px_velocity(p: &FlowParams, du: f32, dv: f32) -> [f32; 2] {
    [du / p.pitch_x + p.skew_over_f * dv, dv / p.pitch_y]
}

/// Twin of one workgroup of `flow_tiles`: writes the tile's field samples (px/s)
/// into `field` (the tile's slice, or empty to skip) and returns its sum of speeds (mm/s).
/// Samples are visited in memory order; thread `lid`'s register sum gets the
/// same terms in the same order as on the GPU.
fn tile(
    p: &FlowParams,
    lens: &[LensSample],
    tw: &TwistGpu,
    tile: u32,
    field: &mut [[f32; 2]],
) -> f32 {
    let n = p.grid_w * p.grid_h;
    let base = tile * TILE;
    let mut sums = [0f32; WG as usize];
    let (mut i, mut j) = (base % p.grid_w, base / p.grid_w);
    'chunk: for k in 0..CHUNK {
        for (lid, acc) in sums.iter_mut().enumerate() {
            let off = k * WG + lid as u32;
            if base + off >= n {
                break 'chunk;
            }
            let (du, dv) = sample_flow(p, lens, tw, i, j);
            *acc += (du * du + dv * dv).sqrt();
            if let Some(f) = field.get_mut(off as usize) {
                *f = px_velocity(p, du, dv);
            }
            i += 1;
            if i == p.grid_w {
                i = 0;
                j += 1;
            }
        }
    }
    sums.iter().fold(0.0, |s, &x| s + x)
}

/// A field (px/s, row-major) and the mean speed (mm/s) of its samples.
#[derive(Debug, Clone, PartialEq)]
pub struct FieldMean {
    /// Per-sample flow `[u, v]` in px/s; empty when not requested.
    pub field: Vec<[f32; 2]>,
    /// Mean speed, mm/s (partials summed in f64, over the valid samples).
    pub mean_mm_s: f64,
}

/// Twin of `flow_tiles` for one twist, on the current rayon pool (tiles in
/// parallel), with the grid's lens table when it uses one
/// ([`LensTable::cached`]; its errors are this function's): masked samples
/// are 0 in the field (as on the GPU) and out of the mean.
pub fn flow_tiles(grid: &Grid, tw: &TwistGpu, with_field: bool) -> Result<FieldMean> {
    let lens = LensTable::cached(grid)?;
    let lens = lens.as_deref();
    let p = grid.params(1, with_field);
    let table = lens.map_or(&[][..], |t| &t.samples);
    let n = grid.len();
    let mut field = if with_field {
        vec![[0f32; 2]; n]
    } else {
        Vec::new()
    };
    // Once a stop is requested (crate::cancel) the tiles left are skipped;
    // the caller checks the token and drops the field.
    let stop = crate::cancel::current();
    let partials: Vec<f32> = if with_field {
        field
            .par_chunks_mut(TILE as usize)
            .enumerate()
            .map(|(t, f)| {
                if stop.is_cancelled() {
                    return 0.0;
                }
                tile(&p, table, tw, t as u32, f)
            })
            .collect()
    } else {
        (0..p.tiles)
            .into_par_iter()
            .map(|t| tile(&p, table, tw, t, &mut []))
            .collect()
    };
    let total: f64 = partials.iter().map(|&x| x as f64).sum();
    Ok(FieldMean {
        field,
        mean_mm_s: total / valid_len(grid, lens) as f64,
    })
}

/// Twin of `rows_per_twist`: the row sums of speeds (mm/s) of one twist
/// (`lens`: the grid's [`LensTable::samples`] in table mode).
pub fn rows_per_twist(p: &FlowParams, lens: &[LensSample], tw: &TwistGpu) -> Vec<f32> {
    (0..p.grid_h)
        .map(|j| {
            let mut row = 0f32;
            for i in 0..p.grid_w {
                let (du, dv) = sample_flow(p, lens, tw, i, j);
                row += (du * du + dv * dv).sqrt();
            }
            row
        })
        .collect()
}

/// Batched means (mm/s) like the GPU batch path, f32 twin, rayon over
/// twists; the lens table as in [`flow_tiles`].
pub fn batch_means(grid: &Grid, twists: &[TwistGpu]) -> Result<Vec<f64>> {
    let lens = LensTable::cached(grid)?;
    let lens = lens.as_deref();
    let p = grid.params(twists.len() as u32, false);
    let table = lens.map_or(&[][..], |t| &t.samples);
    let n = valid_len(grid, lens) as f64;
    Ok(twists
        .par_iter()
        .map(|tw| {
            rows_per_twist(&p, table, tw)
                .iter()
                .map(|&x| x as f64)
                .sum::<f64>()
                / n
        })
        .collect())
}

/// f64 reference: the field (px/s) at the grid's cell centres from
/// [`Camera::pixel_to_mm`], [`flow_distorted`] (the library's f64 undistortion
/// and Jacobian) and [`Camera::mm_to_px_velocity`], and the mean speed (mm/s)
/// over the samples within the radial distortion limit (NaN in the field
/// beyond it).
pub fn reference_f64(grid: &Grid, tw: &Twist, plane: Option<&Plane>) -> (Vec<[f64; 2]>, f64) {
    let c: &Camera = &grid.camera;
    let (sx, sy) = grid.step();
    let mut field = Vec::with_capacity(grid.len());
    let mut sum = 0.0;
    let mut n = 0usize;
    for j in 0..grid.height {
        let mut row = 0.0;
        for i in 0..grid.width {
            let (ud, vd) = c.pixel_to_mm((i as f64 + 0.5) * sx, (j as f64 + 0.5) * sy);
            if c.is_masked_mm(ud, vd) {
                field.push([f64::NAN; 2]);
                continue;
            }
            n += 1;
            let (du, dv) = flow_distorted(c, ud, vd, tw, plane).unwrap_or((f64::NAN, f64::NAN));
            row += du.hypot(dv);
            let (a, b) = c.mm_to_px_velocity(du, dv);
            field.push([a, b]);
        }
        sum += row;
    }
    (field, sum / n as f64)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    #[test]
    fn atan_poly_is_within_its_bound() {
        let mut worst: f64 = 0.0;
        for k in 0..=20_000 {
            let x = k as f64 * 0.001; // 0..20
            worst = worst.max((atan_poly(x as f32) as f64 - x.atan()).abs());
        }
        // 2e-8 (the polynomial) + f32 rounding.
        assert!(worst < 3e-7, "{worst}");
    }

    #[test]
    fn f32_twin_matches_f64_reference() {
        let cam = Camera::thesis().with_resolution(64, 48);
        let mut cam = cam;
        cam.skew = 0.7;
        let grid = Grid::new(&cam, 0, 0).unwrap();
        let tw = Twist::new(DVec3::new(0.3, -0.8, 0.5), DVec3::new(0.1, -0.2, 0.4));
        let plane = Plane {
            normal: DVec3::new(0.2, -0.1, 1.0),
            d: 1.5,
        };
        let g = TwistGpu::new(cam.focal_mm, &tw, Some(&plane));
        let twin = flow_tiles(&grid, &g, true).unwrap();
        let (reff, mean) = reference_f64(&grid, &tw, Some(&plane));
        let max = reff.iter().map(|a| a[0].hypot(a[1])).fold(0.0, f64::max);
        for (a, b) in twin.field.iter().zip(&reff) {
            assert!((a[0] as f64 - b[0]).abs() < 1e-6 * max, "{a:?} {b:?}");
            assert!((a[1] as f64 - b[1]).abs() < 1e-6 * max, "{a:?} {b:?}");
        }
        assert!((twin.mean_mm_s - mean).abs() < 1e-6 * mean);
        let rows = batch_means(&grid, &[g]).unwrap();
        assert!((rows[0] - mean).abs() < 1e-6 * mean);
    }
}
