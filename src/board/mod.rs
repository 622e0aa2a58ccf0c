//! The thesis blob board, defined once ([`Board`], its colours), and what is
//! done with it on images: red blob extraction and matching ([`blobs`]) and
//! the camera pose from the blob centres (`pose`). The renderer paints the
//! same board (`render::target`).

pub mod blobs;
#[doc(hidden)]
pub mod pose;

use crate::camera::Camera;
use crate::check::{finite, positive};
use crate::error::{Error, Result};
use serde::Serialize;

/// Linear RGB of the thesis board's red squares.
pub const BLOB_RED: [f32; 3] = [0.8, 0.03, 0.03];
/// Linear RGB of the white board (and checker white).
pub const BOARD_WHITE: [f32; 3] = [1.0, 1.0, 1.0];

/// The blob target: a `cols x rows` grid of squares of side `square_m` with
/// `gap_m` between them, centred on the optical axis, fronto-parallel.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Board {
    /// Squares per row.
    pub cols: u32,
    /// Squares per column.
    pub rows: u32,
    /// Square side, m.
    pub square_m: f64,
    /// Gap between squares, m.
    pub gap_m: f64,
}

impl Board {
    /// The thesis board: 4 x 4 squares of 10 cm, 2 cm gaps (pitch 12 cm).
    pub fn thesis() -> Self {
        Board {
            cols: 4,
            rows: 4,
            square_m: 0.10,
            gap_m: 0.02,
        }
    }

    /// The half-size board of thesis Table 6.2 (5 cm squares, 1 cm gaps).
    pub fn half() -> Self {
        Board {
            square_m: 0.05,
            gap_m: 0.01,
            ..Self::thesis()
        }
    }

    /// The board with every length multiplied by `scale` (`blobs:SCALE`).
    pub fn scaled(&self, scale: f64) -> Self {
        Board {
            square_m: self.square_m * scale,
            gap_m: self.gap_m * scale,
            ..*self
        }
    }

    /// Half the width of the white board (m): the grid of squares plus a
    /// margin of one square side on each side.
    pub fn half_width_m(&self) -> f64 {
        (self.cols as f64 * self.square_m + (self.cols as f64 - 1.0) * self.gap_m) / 2.0
            + self.square_m
    }

    /// Centre-to-centre distance, m.
    pub fn pitch_m(&self) -> f64 {
        self.square_m + self.gap_m
    }

    /// Square centres `(X, Y)` in m on the board (x right, y down, origin at
    /// the board centre), row by row.
    pub fn centres_m(&self) -> Vec<(f64, f64)> {
        let p = self.pitch_m();
        let (ox, oy) = (
            (self.cols as f64 - 1.0) / 2.0,
            (self.rows as f64 - 1.0) / 2.0,
        );
        (0..self.rows)
            .flat_map(|r| (0..self.cols).map(move |c| ((c as f64 - ox) * p, (r as f64 - oy) * p)))
            .collect()
    }

    /// Rejects empty grids and non-positive sizes.
    pub fn validate(&self) -> Result<()> {
        if self.cols == 0 || self.rows == 0 {
            return Err(Error::invalid("board", "needs at least one square"));
        }
        positive("board square size (m)", self.square_m)?;
        finite("board gap (m)", self.gap_m)?;
        if self.gap_m < 0.0 {
            return Err(Error::invalid("board gap (m)", "must be >= 0"));
        }
        Ok(())
    }
}

/// Pixel positions of the square centres of `board` fronto-parallel at
/// `distance_m` on the optical axis, and the pitch in pixels (x):
/// `(c_x + f X / (D p_x), c_y + f Y / (D p_y))`.
pub fn board_centres_px(
    camera: &Camera,
    board: &Board,
    distance_m: f64,
) -> Result<(Vec<(f64, f64)>, f64)> {
    camera.validate()?;
    board.validate()?;
    positive("board distance (m)", distance_m)?;
    let f = camera.focal_mm;
    let pts = board
        .centres_m()
        .into_iter()
        .map(|(x, y)| camera.mm_to_pixel(f * x / distance_m, f * y / distance_m))
        .collect();
    let pitch_px = f * board.pitch_m() / distance_m / camera.pitch_x_mm;
    Ok((pts, pitch_px))
}
