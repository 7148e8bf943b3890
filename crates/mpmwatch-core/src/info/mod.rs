//! Information-theory core: KSG mutual information, entropies, lagged profiles, surrogates,
//! significance and correlation baselines. Pure functions, no I/O, no async.
//!
//! Everything is computed in nats; [`Units`] converts to the paper's bits for output.
//! Estimates are never clipped at zero, so surrogate statistics stay unbiased.

pub mod correlation;
mod digamma;
pub mod discrete;
pub mod entropy;
mod error;
mod estimator;
mod ksg;
pub mod lagged;
pub mod marginal;
pub mod normalized;
pub mod significance;
pub mod surrogate;
pub mod validate;

pub use digamma::digamma;
pub use error::InfoError;
pub use estimator::{
    Estimator, MiEstimate, MiOptions, Units, XKind, mutual_information, mutual_information_multi,
};
pub use lagged::{LaggedPair, LaggedProfile, Lags, auto_tmax, lagged_profile};
pub use significance::{LaggedTest, SurrogateMethod, SurrogateOptions, Threshold, lagged_test};
pub use surrogate::{Iaaft, IaaftOptions, IaaftReport};
