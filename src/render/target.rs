//! Planar targets (docs/spec.md section 4): `checker:S`, `blobs[:SCALE]` (the thesis
//! board) and `image:PATH:WIDTH_M`, on a plane at `distance` m along the
//! optical axis at exposure start, optionally tilted and offset.
//!
//! Plane frame: origin `O = (offset_x, offset_y, distance)` (camera frame at
//! exposure start = world), in-plane axes `e1` (right), `e2` (down) and
//! normal `n` (away from the camera) are the columns of
//! `R_y(tilt_y) * R_x(tilt_x)`. A point `P` on the plane has target
//! coordinates `(a, b) = ((P - O).e1, (P - O).e2)` in metres. With no tilt and
//! no offset, `(a, b)` are docs/spec.md's `(X, Y)`.

use super::poster::Background;
use super::texture::MipTexture;
use crate::board::Board;
use crate::camera::Camera;
use crate::check::{finite, positive};
use crate::error::{Error, Result};
use crate::model::trajectory::Pose;
use glam::{DMat3, DVec3};
use std::path::PathBuf;
use std::sync::Arc;

/// Default background (where rays miss the target), linear grey.
pub const DEFAULT_BACKGROUND: [f32; 3] = [0.25, 0.25, 0.25];

/// What is painted on the plane.
#[derive(Debug, Clone, PartialEq)]
pub enum TargetKind {
    /// Infinite checkerboard with squares of `size` m; white (1.0) where
    /// `floor(a/S) + floor(b/S)` is even, black (0.0) otherwise.
    Checker {
        /// Square side, m.
        size: f64,
    },
    /// Thesis board: 4 x 4 red squares of `0.10 * scale` m with gaps of
    /// `0.02 * scale` m, centred on `O`, on a white board with a margin of one
    /// square side around the grid; background beyond the board.
    Blobs {
        /// Size factor (1 = thesis Fig. 6.4, 0.5 = Table 6.2).
        scale: f64,
    },
    /// An image `width_m` wide (height from the aspect ratio), centred on `O`.
    Image {
        /// The file it came from.
        path: PathBuf,
        /// Physical width, m.
        width_m: f64,
        /// The decoded, mip-mapped texture.
        texture: Arc<MipTexture>,
    },
}

/// A target on a plane in front of the camera at exposure start.
#[derive(Debug, Clone, PartialEq)]
pub struct Target {
    /// What is painted.
    pub kind: TargetKind,
    /// Distance of the plane origin along the optical axis, m.
    pub distance: f64,
    /// Tilt about the board's horizontal and vertical axes, degrees.
    pub tilt_deg: [f64; 2],
    /// Offset of the board origin in X (right) and Y (down), m.
    pub offset: [f64; 2],
    /// Linear RGB where rays miss the target (and the poster's mean level).
    pub background: [f32; 3],
    /// What is in the plane around a blob board or an image: the plain
    /// `background` (default) or the poster ([`super::poster`]).
    pub surround: Background,
}

/// The plane's frame in world coordinates.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlaneFrame {
    /// Origin, m.
    pub origin: DVec3,
    /// In-plane right axis (unit).
    pub e1: DVec3,
    /// In-plane down axis (unit).
    pub e2: DVec3,
    /// Normal, away from the camera (unit).
    pub normal: DVec3,
}

fn num(spec: &str, s: &str, what: &str) -> Result<f64> {
    let x: f64 = s
        .trim()
        .parse()
        .map_err(|_| Error::invalid("target", format!("'{spec}': {what} '{s}' is not a number")))?;
    positive(&format!("target '{spec}' {what}"), x)
}

impl Target {
    /// Parses `checker:S` (S in m), `blobs` / `blobs:SCALE` (`blobs-half` is
    /// `blobs:0.5`, the name `mmbm blobs` also takes), or `image:PATH:WIDTH_M`
    /// (the texture is loaded now; errors name the file).
    pub fn parse(spec: &str, distance: f64) -> Result<Self> {
        let (name, rest) = spec.split_once(':').unwrap_or((spec, ""));
        let kind = match name.trim() {
            "checker" => TargetKind::Checker {
                size: num(spec, rest, "square size (m)")?,
            },
            "blobs" if rest.is_empty() => TargetKind::Blobs { scale: 1.0 },
            "blobs-half" if rest.is_empty() => TargetKind::Blobs { scale: 0.5 },
            "blobs" => TargetKind::Blobs {
                scale: num(spec, rest, "scale")?,
            },
            "image" => {
                let (path, w) = rest.rsplit_once(':').ok_or_else(|| {
                    Error::invalid("target", format!("'{spec}': expected image:PATH:WIDTH_M"))
                })?;
                let width_m = num(spec, w, "width (m)")?;
                let path = PathBuf::from(path);
                let texture = Arc::new(MipTexture::load(&path)?);
                TargetKind::Image {
                    path,
                    width_m,
                    texture,
                }
            }
            _ => {
                return Err(Error::invalid(
                    "target",
                    format!("'{spec}': expected checker:S, blobs[:SCALE] or image:PATH:WIDTH_M"),
                ))
            }
        };
        Ok(Target {
            kind,
            distance,
            tilt_deg: [0.0, 0.0],
            offset: [0.0, 0.0],
            background: DEFAULT_BACKGROUND,
            surround: Background::Plain,
        })
    }

    /// A fronto-parallel checkerboard of `size` m squares at `distance` m.
    pub fn checker(size: f64, distance: f64) -> Self {
        Target {
            kind: TargetKind::Checker { size },
            distance,
            tilt_deg: [0.0, 0.0],
            offset: [0.0, 0.0],
            background: DEFAULT_BACKGROUND,
            surround: Background::Plain,
        }
    }

    /// An image texture `width_m` wide, fronto-parallel at `distance` m
    /// (from memory: its `path` is `<array>`).
    pub fn from_texture(texture: MipTexture, width_m: f64, distance: f64) -> Self {
        Target {
            kind: TargetKind::Image {
                path: PathBuf::from("<array>"),
                width_m,
                texture: Arc::new(texture),
            },
            ..Self::checker(1.0, distance)
        }
    }

    /// The thesis blob board (scale 1 or 0.5) at `distance` m.
    pub fn blobs(scale: f64, distance: f64) -> Self {
        Target {
            kind: TargetKind::Blobs { scale },
            ..Self::checker(1.0, distance)
        }
    }

    /// The plane's frame.
    pub fn frame(&self) -> PlaneFrame {
        let (ax, ay) = (self.tilt_deg[0].to_radians(), self.tilt_deg[1].to_radians());
        let m = DMat3::from_rotation_y(ay) * DMat3::from_rotation_x(ax);
        PlaneFrame {
            origin: DVec3::new(self.offset[0], self.offset[1], self.distance),
            e1: m.x_axis,
            e2: m.y_axis,
            normal: m.z_axis,
        }
    }

    /// Checks sizes, distance and that the plane is in front of the camera
    /// over the whole sensor at exposure start.
    pub fn validate_for(&self, cam: &Camera) -> Result<()> {
        cam.validate()?;
        finite("target distance (m)", self.distance)?;
        if self.distance <= 0.0 {
            return Err(Error::invalid(
                "target distance",
                format!(
                    "{} m: the plane must be in front of the camera (distance > 0)",
                    self.distance
                ),
            ));
        }
        for (w, x) in [
            ("tilt x (deg)", self.tilt_deg[0]),
            ("tilt y (deg)", self.tilt_deg[1]),
            ("offset x (m)", self.offset[0]),
            ("offset y (m)", self.offset[1]),
        ] {
            finite(w, x)?;
        }
        match &self.kind {
            TargetKind::Checker { size } => positive("checker size (m)", *size).map(|_| ())?,
            TargetKind::Blobs { scale } => positive("blobs scale", *scale).map(|_| ())?,
            TargetKind::Image { width_m, .. } => {
                positive("image width (m)", *width_m).map(|_| ())?
            }
        }
        let f = self.frame();
        let dn = f.normal.dot(f.origin);
        let r = cam.sensor_rect();
        for (u, v) in [(r.u0, r.v0), (r.u1, r.v0), (r.u0, r.v1), (r.u1, r.v1)] {
            let d = DVec3::new(u / cam.focal_mm, v / cam.focal_mm, 1.0);
            let den = f.normal.dot(d);
            if dn <= 0.0 || den <= 1e-9 || dn / den <= 0.0 {
                return Err(Error::invalid(
                    "target plane",
                    format!(
                        "distance {} m, tilt ({}, {}) deg: the plane is behind the camera or \
                         seen edge-on at sensor corner ({u:.3}, {v:.3}) mm",
                        self.distance, self.tilt_deg[0], self.tilt_deg[1]
                    ),
                ));
            }
        }
        Ok(())
    }

    /// World point (camera-at-start frame, m) at target coordinates `(a, b)` m.
    pub fn point(&self, a: f64, b: f64) -> DVec3 {
        let f = self.frame();
        f.origin + f.e1 * a + f.e2 * b
    }

    /// Half extents `(a, b)` of the finite target (board or image), m; `None` for the checker.
    pub fn half_extent_m(&self) -> Option<(f64, f64)> {
        match &self.kind {
            TargetKind::Checker { .. } => None,
            TargetKind::Blobs { .. } => {
                let h = self.board().unwrap_or_else(Board::thesis).half_width_m();
                Some((h, h))
            }
            TargetKind::Image {
                width_m, texture, ..
            } => Some((0.5 * width_m, 0.5 * width_m / texture.aspect())),
        }
    }

    /// Half extents of what is painted on the plane: the target's, or the
    /// poster's around it ([`super::poster::SCALE`] times) when it has one.
    pub fn painted_half_extent_m(&self) -> Option<(f64, f64)> {
        let (a, b) = self.half_extent_m()?;
        Some(match self.surround {
            Background::Plain => (a, b),
            Background::Poster => (super::poster::SCALE * a, super::poster::SCALE * b),
        })
    }

    /// The painted board (`None` unless this is a blob board): the thesis
    /// board ([`Board::thesis`]) at this target's scale.
    pub fn board(&self) -> Option<Board> {
        match self.kind {
            TargetKind::Blobs { scale } => Some(Board::thesis().scaled(scale)),
            _ => None,
        }
    }

    /// World coordinates (m) of the blob centres, row by row from the top
    /// left (`None` unless this is a blob board).
    pub fn blob_centres(&self) -> Option<Vec<DVec3>> {
        let board = self.board()?;
        Some(
            board
                .centres_m()
                .into_iter()
                .map(|(a, b)| self.point(a, b))
                .collect(),
        )
    }

    /// Intersection of the ray through pixel coordinates `(x, y)` (fractional,
    /// `(0,0)` = top-left corner) at pose `pose` with the plane: the world
    /// point, or `None` when the ray misses (plane behind or parallel).
    pub fn intersect(&self, cam: &Camera, pose: &Pose, x: f64, y: f64) -> Option<DVec3> {
        let (rx, ry) = cam.pixel_to_ray(x, y)?;
        let d = pose.0 * DVec3::new(rx, ry, 1.0);
        let f = self.frame();
        let den = f.normal.dot(d);
        let s = (f.normal.dot(f.origin) - f.normal.dot(pose.1)) / den;
        (den.abs() > 1e-12 && s > 0.0 && s.is_finite()).then(|| pose.1 + d * s)
    }
}

/// Pixel coordinates (fractional, `(0,0)` = top-left corner) of world point
/// `p` seen from `pose` (through the lens distortion, if any), or `None` when
/// it is behind the camera.
pub fn project(cam: &Camera, pose: &Pose, p: DVec3) -> Option<(f64, f64)> {
    let pc = pose.0.inverse() * (p - pose.1);
    (pc.z > 1e-12).then(|| {
        if cam.distortion.is_none() {
            cam.mm_to_pixel(cam.focal_mm * pc.x / pc.z, cam.focal_mm * pc.y / pc.z)
        } else {
            cam.ray_to_pixel(pc.x / pc.z, pc.y / pc.z)
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DQuat;

    #[test]
    fn parse_and_errors() {
        let t = Target::parse("checker:0.05", 2.0).unwrap();
        assert_eq!(t.kind, TargetKind::Checker { size: 0.05 });
        assert_eq!(
            Target::parse("blobs:0.5", 2.0).unwrap().kind,
            TargetKind::Blobs { scale: 0.5 }
        );
        // `blobs-half` (the name `mmbm blobs` takes too) is `blobs:0.5`.
        assert_eq!(
            Target::parse("blobs-half", 2.0).unwrap().kind,
            TargetKind::Blobs { scale: 0.5 }
        );
        assert!(Target::parse("checker:-1", 2.0).is_err());
        assert!(Target::parse("checker", 2.0).is_err());
        assert!(Target::parse("stripes:1", 2.0).is_err());
        let e = Target::parse("image:/no/such/file.png:1.0", 2.0).unwrap_err();
        assert!(e.to_string().contains("/no/such/file.png"), "{e}");
        let cam = Camera::thesis();
        assert!(Target::checker(0.1, -1.0).validate_for(&cam).is_err());
        assert!(Target::checker(0.1, 0.0).validate_for(&cam).is_err());
        let mut tilted = Target::checker(0.1, 1.0);
        tilted.tilt_deg = [0.0, 80.0];
        assert!(tilted.validate_for(&cam).is_err());
        tilted.tilt_deg = [20.0, 30.0];
        assert!(tilted.validate_for(&cam).is_ok());
    }

    #[test]
    fn blob_centres_project_symmetrically() {
        let cam = Camera::thesis();
        let t = Target::blobs(1.0, 3.0);
        let c = t.blob_centres().unwrap();
        assert_eq!(c.len(), 16);
        assert!((c[0].x + 0.18).abs() < 1e-12 && (c[15].y - 0.18).abs() < 1e-12);
        let id = (DQuat::IDENTITY, DVec3::ZERO);
        let (x0, y0) = project(&cam, &id, c[0]).unwrap();
        let (x1, y1) = project(&cam, &id, c[15]).unwrap();
        assert!((x0 + x1 - 640.0).abs() < 1e-9 && (y0 + y1 - 480.0).abs() < 1e-9);
        let p = t.intersect(&cam, &id, x0, y0).unwrap();
        assert!((p - c[0]).length() < 1e-12);
        assert!(Target::checker(1.0, 1.0).blob_centres().is_none());
    }
}
