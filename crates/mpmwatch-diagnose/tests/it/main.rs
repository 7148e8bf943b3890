//! Integration tests of mpmwatch-diagnose: every physics class on a generated closed-loop case.
//! One test binary per crate, each test file a module, so the dependencies link once.

mod diagnose_classes;
mod physical_study;
