//! Gyroflow's pixel pipeline written again for `tests/metric/lens_gyroflow.rs`,
//! from its `distortion_models/*.rs` and `lens_profile.rs` (read, not
//! copied), in f64 and independently of the library.

use serde_json::Value;

/// Gyroflow's pipeline for one profile at its calibration size, in f64.
pub struct Gf {
    size: (f64, f64),
    f: (f64, f64),
    c: (f64, f64),
    model: String,
    k: [f64; 12],
    digital: Option<String>,
    dp: [f64; 16],
    /// `opencv_fisheye`: the first theta in (0, pi/2] where the slope of
    /// theta_d(theta) is no longer positive (pi/2 - 1e-9 if none), by a scan
    /// of 100,000 steps. Gyroflow's Newton starts at theta_d and stays on the
    /// first branch; a profile whose slope turns negative and back to
    /// positive before pi/2 has no radial limit, but a bracket to pi/2 would
    /// hold the roots of later branches.
    first_turn: f64,
}

impl Gf {
    pub fn new(p: &Value) -> Gf {
        let (mut w, h) = (
            p["calib_dimension"]["w"].as_f64().unwrap(),
            p["calib_dimension"]["h"].as_f64().unwrap(),
        );
        let digital = p["digital_lens"].as_str().map(str::to_string);
        let aspect = (w / h * 100.0) as u64;
        match digital.as_deref() {
            Some("gopro_superview" | "gopro6_superview") if aspect == 133 => {
                w = (w * 1.3333333333333).round()
            }
            Some("gopro_hyperview") if aspect == 114 => w = (w * 1.55555555555).round(),
            _ => {}
        }
        let m = &p["fisheye_params"]["camera_matrix"];
        let crop = p["crop"].as_f64().unwrap_or(1.0);
        let (mut cx, mut cy) = (w / 2.0, h / 2.0);
        if p["asymmetrical"].as_bool() == Some(true) {
            cx = m[0][2].as_f64().unwrap();
            cy = m[1][2].as_f64().unwrap();
        }
        let mut k = [0.0; 12];
        for (i, v) in p["fisheye_params"]["distortion_coeffs"]
            .as_array()
            .into_iter()
            .flatten()
            .enumerate()
        {
            k[i] = v.as_f64().unwrap();
        }
        let mut dp = [0.0; 16];
        for (i, v) in p["digital_lens_params"]
            .as_array()
            .into_iter()
            .flatten()
            .enumerate()
        {
            dp[i] = v.as_f64().unwrap();
        }
        Gf {
            size: (w, h),
            // Gyroflow's KernelParams take fx, fy as they are (a mirrored
            // calibration's negative focal length only mirrors the image).
            f: (
                m[0][0].as_f64().unwrap().abs() / crop,
                m[1][1].as_f64().unwrap().abs() / crop,
            ),
            c: (cx, cy),
            model: p["distortion_model"]
                .as_str()
                .unwrap_or("opencv_fisheye")
                .to_string(),
            k,
            digital,
            dp,
            first_turn: first_turn(&k),
        }
    }

    /// `distort_point` of the model, on the ray `(x, y, 1)`.
    pub fn distort(&self, x: f64, y: f64) -> (f64, f64) {
        let k = &self.k;
        if k.iter().all(|&v| v == 0.0) {
            return (x, y);
        }
        let r2 = x * x + y * y;
        let r = r2.sqrt();
        let scale = |s: f64| (x * s, y * s);
        match self.model.as_str() {
            "opencv_fisheye" | "sony" | "generic_polynomial" => {
                let th = r.atan();
                let thd = match self.model.as_str() {
                    "opencv_fisheye" => {
                        let t2 = th * th;
                        th * (1.0
                            + k[0] * t2
                            + k[1] * t2 * t2
                            + k[2] * t2.powi(3)
                            + k[3] * t2.powi(4))
                    }
                    m => {
                        let n = if m == "sony" { 6 } else { 12 };
                        (0..n).map(|i| k[i] * th.powi(i as i32 + 1)).sum()
                    }
                };
                scale(if r == 0.0 { 1.0 } else { thd / r })
            }
            "poly3" => scale(k[0] * r2 + 1.0),
            "poly5" => scale(1.0 + k[0] * r2 + k[1] * r2 * r2),
            "ptlens" => scale(k[0] * r2 * r + k[1] * r2 + k[2] * r + 1.0),
            "opencv_standard" => {
                let (r4, r6) = (r2 * r2, r2 * r2 * r2);
                let rad = (1.0 + k[0] * r2 + k[1] * r4 + k[4] * r6)
                    / (1.0 + k[5] * r2 + k[6] * r4 + k[7] * r6);
                (
                    x * rad
                        + 2.0 * k[2] * x * y
                        + k[3] * (r2 + 2.0 * x * x)
                        + k[8] * r2
                        + k[9] * r4,
                    y * rad
                        + k[2] * (r2 + 2.0 * y * y)
                        + 2.0 * k[3] * x * y
                        + k[10] * r2
                        + k[11] * r4,
                )
            }
            "insta360" => {
                let len = (x * x + y * y + 1.0).sqrt();
                let (x, y) = (
                    (x / len) / (1.0 / len + k[5]),
                    (y / len) / (1.0 / len + k[5]),
                );
                let r2 = x * x + y * y;
                let rad = 1.0 + k[0] * r2 + k[1] * r2 * r2 + k[2] * r2 * r2 * r2;
                (
                    x * rad + 2.0 * k[3] * x * y + k[4] * (r2 + 2.0 * x * x),
                    y * rad + 2.0 * k[4] * x * y + k[3] * (r2 + 2.0 * y * y),
                )
            }
            m => panic!("no model {m}"),
        }
    }

    /// The ray of a distorted normalised point: Newton on `distort` with a
    /// numerical Jacobian from the point itself (the radial models' and
    /// Gyroflow's iterations converge to the same first-branch root).
    pub fn undistort(&self, xd: f64, yd: f64) -> Option<(f64, f64)> {
        let (mut x, mut y) = (xd, yd);
        if self.k.iter().all(|&v| v == 0.0) {
            return Some((xd, yd)); // Gyroflow's early return: a pinhole
        }
        if self.model == "opencv_fisheye" {
            // The first-branch root of theta_d(theta) = r_d, by bisection on
            // [0, the turning point] (Gyroflow's Newton from 0 finds the same
            // root where its f32 iterations converge).
            let k = &self.k;
            let thd = xd.hypot(yd);
            if thd < 1e-15 {
                return Some((xd, yd));
            }
            let g = |th: f64| {
                let t2 = th * th;
                th * (1.0 + k[0] * t2 + k[1] * t2 * t2 + k[2] * t2.powi(3) + k[3] * t2.powi(4))
            };
            // Bracket: up to Gyroflow's radial limit, and never past the
            // polynomial's first turning point (see `first_turn`).
            let top = self
                .r_limit()
                .map_or(std::f64::consts::FRAC_PI_2 - 1e-9, f64::atan)
                .min(self.first_turn);
            if g(top) < thd {
                return None;
            }
            let (mut lo, mut hi) = (0.0, top);
            for _ in 0..200 {
                let mid = 0.5 * (lo + hi);
                if g(mid) < thd {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            let s = (0.5 * (lo + hi)).tan() / thd;
            return Some((xd * s, yd * s));
        }
        for _ in 0..200 {
            let (fx, fy) = self.distort(x, y);
            let (ex, ey) = (fx - xd, fy - yd);
            if ex.hypot(ey) < 1e-15 {
                break;
            }
            let h = 1e-7 * (1.0 + x.hypot(y));
            let (a, b) = (self.distort(x + h, y), self.distort(x, y + h));
            let j = [
                [(a.0 - fx) / h, (b.0 - fx) / h],
                [(a.1 - fy) / h, (b.1 - fy) / h],
            ];
            let det = j[0][0] * j[1][1] - j[0][1] * j[1][0];
            x -= (j[1][1] * ex - j[0][1] * ey) / det;
            y -= (-j[1][0] * ex + j[0][0] * ey) / det;
        }
        let (fx, fy) = self.distort(x, y);
        ((fx - xd).hypot(fy - yd) < 1e-11).then_some((x, y))
    }

    /// Gyroflow's digital `superview`-like map (recorded to wide, centred coordinates).
    pub fn wide(&self, x: f64, y: f64) -> (f64, f64) {
        let (x2, y2) = (x * x, y * y);
        match self.digital.as_deref().unwrap() {
            "gopro_superview" => (
                x * (1.2100393 + x2 * (-1.2758402 + x2 * 1.7751845)) / 1.333333333,
                y * (0.9364505
                    + (0.4465308 - 0.7683315 * y2) * y2
                    + (-0.3574087 + 1.1584653 * y2 + 0.3529348 * x2) * x2),
            ),
            "gopro6_superview" => {
                let mut u = x * (1.0 - 0.48 * x.abs());
                u *= 0.943396 * (1.0 + 0.157895 * u.abs());
                (u, y * 0.943396 * (1.0 + 0.06 * (y * 2.0).abs()))
            }
            "gopro_hyperview" => (
                x * (1.5805143
                    + x2 * (-8.1668825
                        + x2 * (74.5198746
                            + x2 * (-451.5002441
                                + x2 * (1551.2922363
                                    + x2 * (-2735.5422363 + x2 * 1923.1572266)))))
                    + y2 * -0.1086027)
                    / 1.555555555,
                y * (1.0238225 + y2 * -0.1025671 + x2 * (-0.2639930 + x2 * 0.2979266)),
            ),
            "digital_stretch" => ((x + 0.5) / self.dp[0] - 0.5, (y + 0.5) / self.dp[1] - 0.5),
            d => panic!("no digital lens {d}"),
        }
    }

    /// Ray to recorded pixel.
    pub fn project(&self, r: [f64; 3]) -> Option<(f64, f64)> {
        if r[2] <= 0.0 {
            return None;
        }
        let (xd, yd) = self.distort(r[0] / r[2], r[1] / r[2]);
        let (u, v) = (self.f.0 * xd + self.c.0, self.f.1 * yd + self.c.1);
        if self.digital.is_none() {
            return Some((u, v));
        }
        // Gyroflow's digital distort_point: the fixed-point inverse of `wide`.
        let t = (u / self.size.0 - 0.5, v / self.size.1 - 0.5);
        let mut p = t;
        for _ in 0..400 {
            let w = self.wide(p.0, p.1);
            p = (p.0 - (w.0 - t.0), p.1 - (w.1 - t.1));
        }
        let w = self.wide(p.0, p.1);
        assert!(
            (w.0 - t.0).hypot(w.1 - t.1) < 1e-12,
            "digital distort converges"
        );
        Some(((p.0 + 0.5) * self.size.0, (p.1 + 0.5) * self.size.1))
    }

    /// Recorded pixel to ray `(x, y, 1)`.
    pub fn ray(&self, px: f64, py: f64) -> Option<(f64, f64)> {
        let (mut u, mut v) = (px, py);
        if self.digital.is_some() {
            let w = self.wide(u / self.size.0 - 0.5, v / self.size.1 - 0.5);
            (u, v) = ((w.0 + 0.5) * self.size.0, (w.1 + 0.5) * self.size.1);
        }
        self.undistort((u - self.c.0) / self.f.0, (v - self.c.1) / self.f.1)
    }

    /// Gyroflow's radial distortion limit of `opencv_fisheye` (its bisection
    /// on the slope over [0, pi/2], here to 1e-13): `tan(theta_max)`, or none.
    pub fn r_limit(&self) -> Option<f64> {
        if self.model != "opencv_fisheye" || self.k.iter().all(|&v| v == 0.0) {
            return None;
        }
        let k = &self.k;
        let (mut lo, mut hi) = (0.0, std::f64::consts::FRAC_PI_2);
        while hi - lo > 1e-13 {
            let t: f64 = 0.5 * (lo + hi);
            let t2 = t * t;
            let d = 1.0
                + 3.0 * k[0] * t2
                + 5.0 * k[1] * t2 * t2
                + 7.0 * k[2] * t2.powi(3)
                + 9.0 * k[3] * t2.powi(4);
            if d > 0.0 {
                lo = t;
            } else {
                hi = t;
            }
        }
        let t: f64 = 0.5 * (lo + hi);
        ((t - std::f64::consts::FRAC_PI_2).abs() > 0.001).then(|| t.tan())
    }

    /// The mean speed (mm/s, with the camera's pitch) over an `nu x nv`
    /// grid's cell centres of the recorded frame under rotation `w` rad/s,
    /// by central differences of projected rays; the masked share.
    pub fn mean_speed(&self, w: [f64; 3], pitch: (f64, f64), nu: u32, nv: u32) -> (f64, f64) {
        let dt = 1e-5;
        let rot = |r: [f64; 3], s: f64| {
            // Rodrigues: rotate r by the angle |w| s about w.
            let a = (w[0] * w[0] + w[1] * w[1] + w[2] * w[2]).sqrt() * s;
            let n = [w[0] * s / a, w[1] * s / a, w[2] * s / a];
            let (c, si) = (a.cos(), a.sin());
            let d = n[0] * r[0] + n[1] * r[1] + n[2] * r[2];
            let x = [
                n[1] * r[2] - n[2] * r[1],
                n[2] * r[0] - n[0] * r[2],
                n[0] * r[1] - n[1] * r[0],
            ];
            [0, 1, 2].map(|i| r[i] * c + x[i] * si + n[i] * d * (1.0 - c))
        };
        let lim = self.r_limit();
        let (mut sum, mut n, mut masked) = (0.0, 0u64, 0u64);
        for j in 0..nv {
            for i in 0..nu {
                let px = (i as f64 + 0.5) * self.size.0 / nu as f64;
                let py = (j as f64 + 0.5) * self.size.1 / nv as f64;
                let ray = self
                    .ray(px, py)
                    .filter(|r| lim.is_none_or(|l| r.0.hypot(r.1) <= l));
                let Some((x, y)) = ray else {
                    masked += 1;
                    continue;
                };
                let (a, b) = (
                    self.project(rot([x, y, 1.0], dt)).unwrap(),
                    self.project(rot([x, y, 1.0], -dt)).unwrap(),
                );
                sum += ((a.0 - b.0) * pitch.0).hypot((a.1 - b.1) * pitch.1) / (2.0 * dt);
                n += 1;
            }
        }
        (sum / n as f64, masked as f64 / (nu * nv) as f64)
    }
}

/// [`Gf::first_turn`] of the fisheye coefficients `k`.
fn first_turn(k: &[f64; 12]) -> f64 {
    let slope = |th: f64| {
        let t2 = th * th;
        1.0 + 3.0 * k[0] * t2
            + 5.0 * k[1] * t2 * t2
            + 7.0 * k[2] * t2.powi(3)
            + 9.0 * k[3] * t2.powi(4)
    };
    let n = 100_000;
    (1..=n)
        .map(|i| i as f64 * std::f64::consts::FRAC_PI_2 / n as f64)
        .find(|&th| slope(th) <= 0.0)
        .unwrap_or(std::f64::consts::FRAC_PI_2 - 1e-9)
}
