//! The types a user needs first: `use mmbm::prelude::*;`.
//!
//! The camera and its shutter, motion (twist, plane, the trajectory over an
//! exposure), the gyro log and its reader, the metric, the flow field, the
//! blur renderer and the error type. Everything else is at its module's path.

pub use crate::camera::{Camera, Distortion, Readout, Shutter};
pub use crate::error::{Error, Result};
pub use crate::field::{flow_field, FlowField};
pub use crate::gpu::Backend;
pub use crate::io::gyro::{read_log, GyroOptions};
pub use crate::metric::{mmbm, AnyMethod, Method, Mmbm, Scene};
pub use crate::model::log::{GyroSample, ImuLog};
pub use crate::model::motion::{Plane, Twist};
pub use crate::model::trajectory::{Pose, Trajectory};
pub use crate::render::{blur_maps, render_frame, BlurMaps, Quality, RenderJob, RenderOutput};
