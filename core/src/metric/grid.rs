//! Fixed real-time rules: the thesis's midpoint (Riemann) grid and tensor Gauss-Legendre.

use crate::camera::{Camera, SensorRect};
use crate::error::{Error, Result};
use crate::model::flow::FlowPoly;

/// MMBM* (thesis eq. 4.1): the mean of the flow speed at the centres of an
/// `nu x nv` grid of equal cells covering the sensor, mm/s.
pub fn riemann(poly: &FlowPoly, r: &SensorRect, nu: u32, nv: u32) -> f64 {
    super::avx2::riemann(poly, r, nu, nv)
}

/// Gauss-Legendre nodes and weights on `[-1, 1]` (Newton on the Legendre
/// recurrence; accurate to ~1e-15 for n up to a few hundred).
pub fn gauss_legendre(n: usize) -> (Vec<f64>, Vec<f64>) {
    let mut x = vec![0.0; n];
    let mut w = vec![0.0; n];
    for i in 0..n.div_ceil(2) {
        let mut z = (std::f64::consts::PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
        let mut dp = 1.0;
        for _ in 0..100 {
            let (mut p0, mut p1) = (1.0, z);
            for k in 2..=n {
                let p2 = ((2 * k - 1) as f64 * z * p1 - (k - 1) as f64 * p0) / k as f64;
                p0 = p1;
                p1 = p2;
            }
            let pn = if n == 1 { z } else { p1 };
            let pm = if n == 1 { 1.0 } else { p0 };
            dp = n as f64 * (z * pn - pm) / (z * z - 1.0);
            let dz = pn / dp;
            z -= dz;
            if dz.abs() < 1e-16 {
                break;
            }
        }
        if n == 1 {
            x[0] = 0.0;
            w[0] = 2.0;
            break;
        }
        x[i] = -z;
        x[n - 1 - i] = z;
        let wi = 2.0 / ((1.0 - z * z) * dp * dp);
        w[i] = wi;
        w[n - 1 - i] = wi;
    }
    (x, w)
}

/// A reusable point rule on the sensor: points `(u, v)` in mm with weights
/// summing to 1 (so it returns a mean), stored as structure-of-arrays of the
/// monomials `u, v, u^2, uv, v^2`, padded with zero-weight points to a
/// multiple of 8, so that [`GridRule::mean_speed`] vectorises.
///
/// With lens distortion ([`GridRule::distorted`]) the nodes stay where they
/// are on the (distorted) sensor, the monomials are those of their undistorted
/// points and the distortion's Jacobian at each is kept: the speed at a node is
/// `|J flow(u, v)|` (docs/spec.md section 9).
#[derive(Debug, Clone)]
pub struct GridRule {
    m: [Vec<f64>; 5],
    w: Vec<f64>,
    len: usize,
    jac: Option<Vec<[f64; 4]>>,
}

impl GridRule {
    /// A rule of the given sensor points `(u, v)` mm and weights (for a mean,
    /// the weights sum to 1; a part of a rule keeps its share).
    pub fn from_points(points: &[(f64, f64)], weights: &[f64]) -> Self {
        let n = points.len().div_ceil(8) * 8;
        let mut m: [Vec<f64>; 5] = Default::default();
        for v in m.iter_mut() {
            v.resize(n, 0.0);
        }
        let mut w = vec![0.0; n];
        for (k, (&(u, v), &wk)) in points.iter().zip(weights).enumerate() {
            m[0][k] = u;
            m[1][k] = v;
            m[2][k] = u * u;
            m[3][k] = u * v;
            m[4][k] = v * v;
            w[k] = wk;
        }
        GridRule {
            m,
            w,
            len: points.len(),
            jac: None,
        }
    }

    /// This rule's nodes seen through `cam`'s lens distortion (unchanged
    /// without distortion). Nodes beyond the radial distortion limit are
    /// masked: dropped, the others' weights rescaled to sum to 1 (the mean
    /// over the unmasked sensor). Errors when an unmasked node does not
    /// undistort, or every node is masked.
    pub fn distorted(self, cam: &Camera) -> Result<Self> {
        if cam.distortion.is_none() {
            return Ok(self);
        }
        let mut points = Vec::with_capacity(self.len);
        let mut jac = Vec::with_capacity(self.len);
        let mut w = Vec::with_capacity(self.len);
        for k in 0..self.len {
            let (ud, vd) = (self.m[0][k], self.m[1][k]);
            if cam.is_masked_mm(ud, vd) {
                continue;
            }
            let (u, v) = cam.undistort_mm(ud, vd).ok_or_else(|| {
                Error::invalid(
                    "distortion",
                    format!("the sensor point ({ud:.4}, {vd:.4}) mm does not undistort"),
                )
            })?;
            let j = cam.distortion_jacobian(u, v);
            points.push((u, v));
            jac.push([j[0][0], j[0][1], j[1][0], j[1][1]]);
            w.push(self.w[k]);
        }
        let total: f64 = w.iter().sum();
        if points.is_empty() || total.is_nan() || total <= 0.0 {
            return Err(Error::invalid(
                "distortion",
                "every node of the rule lies beyond the lens's radial distortion limit",
            ));
        }
        w.iter_mut().for_each(|x| *x /= total);
        let mut rule = Self::from_points(&points, &w);
        rule.jac = Some(jac);
        Ok(rule)
    }

    /// The midpoint (Riemann) rule: centres of `nu x nv` equal cells over `r`.
    pub fn riemann(r: &SensorRect, nu: u32, nv: u32) -> Self {
        let (pts, w) = riemann_points(r, nu, nv);
        Self::from_points(&pts, &w)
    }

    /// Tensor Gauss-Legendre rule with `nu x nv` nodes over `r`.
    pub fn gauss(r: &SensorRect, nu: u32, nv: u32) -> Self {
        let (pts, w) = gauss_points(r, nu, nv);
        Self::from_points(&pts, &w)
    }

    /// Number of points (without padding).
    pub fn len(&self) -> usize {
        self.len
    }

    /// True when the rule has no points.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// The flow (mm/s, through the distortion's Jacobian when the rule has
    /// one) at each node, with the node's weight: `(weight, (du, dv))`, in
    /// node order, padding left out.
    pub fn node_flows<'a>(
        &'a self,
        poly: &'a FlowPoly,
    ) -> impl Iterator<Item = (f64, (f64, f64))> + 'a {
        (0..self.len).map(move |k| {
            let (a, b) = poly.eval(self.m[0][k], self.m[1][k]);
            let f = match &self.jac {
                None => (a, b),
                Some(jac) => {
                    let j = &jac[k];
                    (j[0] * a + j[1] * b, j[2] * a + j[3] * b)
                }
            };
            (self.w[k], f)
        })
    }

    /// The rule's estimate of the mean flow speed, mm/s.
    pub fn mean_speed(&self, poly: &FlowPoly) -> f64 {
        match &self.jac {
            None => super::avx2::rule_mean(&self.m, &self.w, poly),
            Some(jac) => {
                let mut sum = 0.0;
                for (k, j) in jac.iter().enumerate() {
                    let (a, b) = poly.eval(self.m[0][k], self.m[1][k]);
                    let (x, y) = (j[0] * a + j[1] * b, j[2] * a + j[3] * b);
                    sum += self.w[k] * (x * x + y * y).sqrt();
                }
                sum
            }
        }
    }
}

impl GridRule {
    /// The rule's estimate of the mean of `|m J flow|`: the speed after the
    /// linear map `m` (row-major 2 x 2, applied after the distortion's
    /// Jacobian if any), e.g. the true pixel speed, px/s, with the camera's
    /// pixel map ([`super::pixel_map`]).
    pub fn mean_mapped_speed(&self, poly: &FlowPoly, m: [f64; 4]) -> f64 {
        match &self.jac {
            None => super::avx2::rule_mean(&self.m, &self.w, &poly.mapped(m)),
            Some(jac) => {
                let mut sum = 0.0;
                for (k, j) in jac.iter().enumerate() {
                    let (a, b) = poly.eval(self.m[0][k], self.m[1][k]);
                    let (x, y) = (j[0] * a + j[1] * b, j[2] * a + j[3] * b);
                    let (x, y) = (m[0] * x + m[1] * y, m[2] * x + m[3] * y);
                    sum += self.w[k] * (x * x + y * y).sqrt();
                }
                sum
            }
        }
    }
}

/// Points (mm, row by row) and weights (summing to 1) of the midpoint rule
/// on `nu x nv` equal cells over `r`.
pub fn riemann_points(r: &SensorRect, nu: u32, nv: u32) -> (Vec<(f64, f64)>, Vec<f64>) {
    let du = (r.u1 - r.u0) / nu as f64;
    let dv = (r.v1 - r.v0) / nv as f64;
    let mut pts = Vec::with_capacity((nu * nv) as usize);
    for j in 0..nv {
        for i in 0..nu {
            pts.push((r.u0 + (i as f64 + 0.5) * du, r.v0 + (j as f64 + 0.5) * dv));
        }
    }
    let w = vec![1.0 / pts.len() as f64; pts.len()];
    (pts, w)
}

/// Points (mm, row by row) and weights (summing to 1) of the tensor
/// Gauss-Legendre rule with `nu x nv` nodes over `r`.
pub fn gauss_points(r: &SensorRect, nu: u32, nv: u32) -> (Vec<(f64, f64)>, Vec<f64>) {
    let (xu, wu) = gauss_legendre(nu as usize);
    let (xv, wv) = gauss_legendre(nv as usize);
    let (cu, hu) = ((r.u0 + r.u1) / 2.0, (r.u1 - r.u0) / 2.0);
    let (cv, hv) = ((r.v0 + r.v1) / 2.0, (r.v1 - r.v0) / 2.0);
    let mut points = Vec::new();
    let mut weights = Vec::new();
    for (yv, ww) in xv.iter().zip(&wv) {
        for (yu, wu) in xu.iter().zip(&wu) {
            points.push((cu + hu * yu, cv + hv * yv));
            weights.push(wu * ww / 4.0);
        }
    }
    (points, weights)
}

/// Tensor Gauss-Legendre estimate of MMBM with `nu x nv` nodes, mm/s.
pub fn gauss(poly: &FlowPoly, r: &SensorRect, nu: u32, nv: u32) -> f64 {
    GridRule::gauss(r, nu, nv).mean_speed(poly)
}
