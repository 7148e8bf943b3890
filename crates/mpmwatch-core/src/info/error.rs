//! Errors of the estimation core. Each names the offending input so a caller can say which
//! column, lag or parameter is wrong.

/// What can be wrong with the inputs of an estimator.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum InfoError {
    /// A value is NaN or infinite.
    #[error("{series} has a non-finite value ({value}) at index {index}")]
    NonFinite {
        /// Which series (`x`, `y`, or a caller's name).
        series: String,
        /// Zero-based sample index.
        index: usize,
        /// The value found.
        value: f64,
    },
    /// A series has no variation, so no information can be measured.
    #[error("{series} is constant (every value is {value}); mutual information is undefined")]
    Constant {
        /// Which series.
        series: String,
        /// The constant value.
        value: f64,
    },
    /// Two series that must pair sample by sample have different lengths.
    #[error("length mismatch: {left} has {left_len} samples, {right} has {right_len}")]
    LengthMismatch {
        /// First series.
        left: String,
        /// Its length.
        left_len: usize,
        /// Second series.
        right: String,
        /// Its length.
        right_len: usize,
    },
    /// Too few samples for the requested number of neighbours (or lags).
    #[error("{what}: {n} samples, at least {needed} needed")]
    TooFewSamples {
        /// What was being estimated.
        what: String,
        /// Samples available.
        n: usize,
        /// Samples needed.
        needed: usize,
    },
    /// A parameter is out of its domain.
    #[error("invalid parameter {name} = {value}: {reason}")]
    InvalidParameter {
        /// Parameter name as the user sees it (`k`, `lag`, `z`…).
        name: &'static str,
        /// The value given, as text.
        value: String,
        /// Why it is invalid.
        reason: &'static str,
    },
    /// A series declared discrete has more distinct levels than the discrete path supports.
    #[error("{series} has {levels} distinct values; the discrete estimator takes at most {max}")]
    TooManyLevels {
        /// Which series.
        series: String,
        /// Levels found.
        levels: usize,
        /// The limit.
        max: usize,
    },
}
