//! The slow tier: `mmbm demo` (minutes). Ignored by a plain `cargo test`; run by the README's test command (`cargo test --release -p mmbm-cli --test demo -- --ignored`).
//!
//! One test binary of the subject; each module is one former test file
//! (`cli/tests/demo/NAME.rs`, see docs/testing.md).

mod common;

#[path = "demo/demo.rs"]
mod demo;
