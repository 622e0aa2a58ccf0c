//! Bad input (docs/limits.md): tables of bad inputs over every subcommand, guarded outputs, caps, argument parsing.
//!
//! One test binary of the subject; each module is one former test file
//! (`cli/tests/refusals/NAME.rs`, see docs/testing.md).

mod common;
#[path = "refusals/robust.rs"]
mod robust;

#[path = "refusals/caps.rs"]
mod caps;
#[path = "refusals/output_guard.rs"]
mod output_guard;
#[path = "refusals/parsing.rs"]
mod parsing;
#[path = "refusals/robustness.rs"]
mod robustness;
#[path = "refusals/robustness_round3.rs"]
mod robustness_round3;
