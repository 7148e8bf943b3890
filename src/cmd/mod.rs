//! One module per command-line verb; each parses its own arguments and calls the library.

pub mod analyze;
pub mod bench;
pub mod casebook;
pub mod demo;
pub mod diagnose;
pub mod loadgen;
pub mod mi;
pub mod reproduce;
pub mod serve;
pub mod simulate;
