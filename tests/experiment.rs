//! The lab's experiment (library): the walk, the benefit map (the CPU fallback is
//! `tests/experiment_cpu.rs`, a binary of its own: it sets the process's
//! adapter filter before the GPU context exists).
//!
//! One test binary of the subject; each module is one former test file
//! (`tests/experiment/NAME.rs`, see docs/testing.md).

mod common;
#[path = "experiment/tiny_map.rs"]
mod tiny_map;

#[path = "experiment/benefit_agree.rs"]
mod benefit_agree;

#[path = "experiment/experiment.rs"]
mod experiment;
#[path = "experiment/experiment_map.rs"]
mod experiment_map;
#[path = "experiment/policy_config.rs"]
mod policy_config;
#[path = "experiment/speed.rs"]
mod speed;
#[path = "experiment/vo.rs"]
mod vo;
