//! # mpmwatch
//!
//! Detects model–plant mismatch (MPM) in model-based control loops (MPC, IMC) from the mutual
//! information between the dithers injected on the manipulated variables and the model residuals,
//! following Chen, Xie, Zeng, Chu and Gu (Ind. Eng. Chem. Res. 2013, 52, 1927–1938), and goes past
//! the paper where its recipe breaks (see `DESIGN.md` §2 in the shared folder).
//!
//! The crate is a functional core with an imperative shell:
//!
//! * [`info`]: the information-theory core (KSG estimators, entropies, lagged profiles,
//!   surrogates, significance, correlation baselines). Pure and synchronous.
//! * [`model`]: nominal models and their simulation. Pure.
//! * [`sim`]: the paper's plants, controllers and dither generators. Pure and seeded.
//! * [`io`]: the time-aligned data table and its CSV form.
//! * [`benchmark`]: timings of the core behind `mpmwatch bench`.
//! * [`service`]: the online monitor behind `mpmwatch serve` and `mpmwatch demo`.

pub mod benchmark;
pub mod detect;
pub mod diagnose;
pub mod info;
pub mod io;
pub mod model;
pub mod report;
pub mod service;
pub mod sim;
