//! Errors of diagnosis: every one names the offending signal or option.

use thiserror::Error;

/// Why a diagnosis could not be made.
#[derive(Debug, Error)]
pub enum DiagnoseError {
    /// Two signals that must share a time axis do not have the same length.
    #[error("`{name}` has {found} samples but `{reference}` has {expected}: the time axes do not match")]
    LengthMismatch {
        /// The offending signal.
        name: String,
        /// Its length.
        found: usize,
        /// The reference signal.
        reference: String,
        /// The reference length.
        expected: usize,
    },
    /// A value is NaN or infinite.
    #[error("`{name}` has a non-finite value ({value}) at row {index}")]
    NotFinite {
        /// The offending signal.
        name: String,
        /// Row (0-based, without the header).
        index: usize,
        /// The value.
        value: f64,
    },
    /// An option or the shape of the input is unusable.
    #[error("invalid {what}: {reason}")]
    Invalid {
        /// What is invalid.
        what: String,
        /// Why.
        reason: String,
    },
    /// The MI matrix could not be computed.
    #[error("MI matrix: {0}")]
    Info(#[from] mpmwatch_core::info::InfoError),
}

impl DiagnoseError {
    pub(crate) fn invalid(what: impl Into<String>, reason: impl Into<String>) -> Self {
        Self::Invalid { what: what.into(), reason: reason.into() }
    }
}
