//! # mpmwatch-core
//!
//! The numerical core of mpmwatch: it detects model–plant mismatch (MPM) in model-based control
//! loops from the mutual information between the dithers injected on the manipulated variables
//! and the model residuals, following Chen, Xie, Zeng, Chu and Gu (Ind. Eng. Chem. Res. 2013, 52,
//! 1927–1938), and goes past the paper where its recipe breaks.
//!
//! Pure and synchronous: no async runtime, sockets, database, plotting or command line.
//!
//! * [`info`]: the information-theory core (KSG estimators, entropies, lagged profiles,
//!   surrogates, significance, correlation baselines).
//! * [`detect`]: the lagged MI matrix, its thresholds and the verdict per channel.
//! * [`model`]: nominal models (transfer functions, ARX, state space, Hammerstein) and their
//!   simulation.
//! * [`io`]: the time-aligned data table and its CSV form.
//! * [`numerics`]: least squares, instrumental variables, projections and order statistics.

#![warn(missing_docs)]

pub mod detect;
pub mod info;
pub mod io;
pub mod model;
pub mod numerics;
