//! `mmbm dataset`: shards, portability, safety of concurrent runs, trust of resumed runs, WebDataset tars.
//!
//! One test binary of the subject; each module is one former test file
//! (`cli/tests/dataset/NAME.rs`, see docs/testing.md).

mod common;

#[path = "dataset/dataset.rs"]
mod dataset;
#[path = "dataset/dataset_portable.rs"]
mod dataset_portable;
#[path = "dataset/dataset_safety.rs"]
mod dataset_safety;
#[path = "dataset/dataset_trust.rs"]
mod dataset_trust;
#[path = "dataset/dataset_webdataset.rs"]
mod dataset_webdataset;
