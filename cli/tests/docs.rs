//! The README and the manuals in `docs/`: links, examples, and the limits table against the code.
//!
//! One test binary of the subject; each module is one former test file
//! (`cli/tests/docs/NAME.rs`, see docs/testing.md).

mod common;

#[path = "docs/docs.rs"]
mod docs;
#[path = "docs/ffmpeg_lines.rs"]
mod ffmpeg_lines;
#[path = "docs/limits_doc.rs"]
mod limits_doc;
