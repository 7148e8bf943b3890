//! One module per command-line verb; each parses its own arguments and calls the library.

pub mod analyze;
pub mod bench;
pub mod demo;
pub mod mi;
pub mod reproduce;
pub mod serve;
pub mod simulate;
