//! The sample every gyro source yields, before the reader's options.

use glam::DVec3;

/// One sample as a source reads it: the file's units and axes, before the
/// reader's options (units, rotation, offset).
#[derive(Debug, Clone, Copy)]
pub(super) struct Raw {
    /// The sample's line in the file (1-based).
    pub line: u64,
    /// Time, in the file's unit.
    pub t: f64,
    /// Angular velocity, in the file's unit and IMU axes.
    pub w: DVec3,
    /// Linear velocity, m/s, IMU axes, when the log has `vx, vy, vz`.
    pub v: Option<DVec3>,
    /// Scene depth, m, when the log has `depth`.
    pub depth: Option<f64>,
}
