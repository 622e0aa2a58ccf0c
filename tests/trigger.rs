//! Trigger policies and the gait simulation (library).
//!
//! One test binary of the subject; each module is one former test file
//! (`tests/trigger/NAME.rs`, see docs/testing.md).

mod common;

#[path = "trigger/sim.rs"]
mod sim;
#[path = "trigger/trigger.rs"]
mod trigger;
