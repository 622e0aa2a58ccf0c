//! The thesis experiment end to end (being built).

pub mod figures;
