//! The `mpmwatch` binary's library half: what the command-line verbs share and the integration
//! tests call, that belongs to no library crate. Figures and reports, the paper reproduced, the
//! timings behind `bench`, the demo plant, the load generator, and the cascaded-tanks benchmark
//! model the casebook hands to the diagnosis.
//!
//! The numerics live in `mpmwatch-core`, the plants in `mpmwatch-sim`, the diagnosis in
//! `mpmwatch-diagnose` and the online monitor in `mpmwatch-service`.

#![warn(missing_docs)]

pub mod accuracy;
pub mod benchmark;
pub mod demo;
pub mod loadgen;
pub mod power;
pub mod report;
pub mod tanks;
