//! The commands end to end: the core verbs, `live`, `assess`, `blobs`, the benefit story, pixel speeds.
//!
//! One test binary of the subject; each module is one former test file
//! (`cli/tests/commands/NAME.rs`, see docs/testing.md).

mod common;
#[path = "../../tests/experiment/tiny_map.rs"]
mod tiny_map;

#[path = "commands/assess.rs"]
mod assess;
#[path = "commands/benefit_story.rs"]
mod benefit_story;
#[path = "commands/blobs.rs"]
mod blobs;
#[path = "commands/cli_core.rs"]
mod cli_core;
#[path = "commands/cli_e2e.rs"]
mod cli_e2e;
#[path = "commands/clip.rs"]
mod clip;
#[path = "commands/live.rs"]
mod live;
#[path = "commands/px_speed.rs"]
mod px_speed;
