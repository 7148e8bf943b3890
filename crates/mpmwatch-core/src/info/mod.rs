//! Information-theory core: KSG mutual information, entropies, lagged profiles, surrogates,
//! significance and correlation baselines. Pure functions, no I/O, no async.
//!
//! Everything is computed in nats; [`Units`] converts to the paper's bits for output.
//! Estimates are never clipped at zero, so surrogate statistics stay unbiased.

pub(crate) mod correlation;
mod digamma;
pub(crate) mod discrete;
pub(crate) mod entropy;
mod error;
mod estimator;
pub(crate) mod family;
mod ksg;
pub(crate) mod lagged;
pub(crate) mod marginal;
pub(crate) mod normalized;
pub(crate) mod shift_moments;
pub(crate) mod significance;
pub(crate) mod surrogate;
pub(crate) mod validate;

pub use correlation::{Pearson, ccf, ccf_limit, family_wise_z, normal_quantile, pearson};
pub use digamma::digamma;
pub use entropy::kozachenko_leonenko;
pub use error::InfoError;
pub use estimator::{
    Estimator, MiEstimate, MiOptions, Units, XKind, mutual_information, mutual_information_multi,
};
pub use family::{
    Element, FamilyOptions, FamilyTest, PValueSource, Statistic, StatisticProfile, family_test,
    family_test_group,
};
pub use lagged::{LaggedPair, LaggedProfile, Lags, auto_tmax, lagged_profile};
pub use normalized::{estevez, joe};
pub use significance::{LaggedTest, SurrogateMethod, SurrogateOptions, Threshold, lagged_test};
pub use surrogate::{Iaaft, IaaftOptions, IaaftReport, draw_shift, shift_bounds};
pub use validate::not_constant;
