//! The lab's experiment (library): the walk, the CPU path, the benefit map.
//!
//! One test binary of the subject; each module is one former test file
//! (`tests/experiment/NAME.rs`, see docs/testing.md).

mod common;

#[path = "experiment/experiment.rs"]
mod experiment;
#[path = "experiment/experiment_cpu.rs"]
mod experiment_cpu;
#[path = "experiment/experiment_map.rs"]
mod experiment_map;
