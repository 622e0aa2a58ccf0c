//! The thesis experiment end to end (being built).

pub mod config;
pub mod figures;
