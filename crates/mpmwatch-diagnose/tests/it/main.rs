//! Integration tests of mpmwatch-diagnose: every physics class on a generated closed-loop case,
//! and the open-loop physical cases through the grey-box step.
//! One test binary per crate, each test file a module, so the dependencies link once.

mod closed_loop_study;
mod diagnose_classes;
mod physical_cases;
mod physical_study;
