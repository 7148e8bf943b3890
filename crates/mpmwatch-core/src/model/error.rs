//! Errors of model construction and simulation. Each names the offending model part.

/// What can be wrong with a model or its input.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ModelError {
    /// A polynomial has no coefficients.
    #[error("{what}: the polynomial is empty")]
    Empty {
        /// Which polynomial.
        what: String,
    },
    /// The leading (q⁰ or highest power of s) coefficient of a denominator is zero.
    #[error("{what}: the leading coefficient of the denominator is zero")]
    ZeroLeading {
        /// Which denominator.
        what: String,
    },
    /// A coefficient is NaN or infinite.
    #[error("{what}: coefficient {index} is not finite ({value})")]
    NotFinite {
        /// Which polynomial.
        what: String,
        /// Position of the coefficient.
        index: usize,
        /// The value.
        value: f64,
    },
    /// A denominator has a root on or outside the unit circle where stability is required.
    #[error("{what}: the denominator {coefficients:?} is not stable (a pole on or outside the unit circle)")]
    Unstable {
        /// Which model.
        what: String,
        /// The offending denominator.
        coefficients: Vec<f64>,
    },
    /// A continuous transfer function has a numerator of higher degree than its denominator.
    #[error("{what}: improper transfer function (numerator degree {num} > denominator degree {den})")]
    Improper {
        /// Which transfer function.
        what: String,
        /// Numerator degree.
        num: usize,
        /// Denominator degree.
        den: usize,
    },
    /// A sample period is not a positive finite number.
    #[error("sample period must be positive and finite, got {0}")]
    BadSamplePeriod(f64),
    /// A continuous dead time is not a whole number of sample periods.
    #[error("{what}: dead time {delay} s is not a whole number of sample periods of {period} s")]
    FractionalDelay {
        /// Which transfer function.
        what: String,
        /// The dead time in seconds.
        delay: f64,
        /// The sample period in seconds.
        period: f64,
    },
    /// Sizes disagree (inputs, outputs, matrix dimensions, record lengths).
    #[error("{what}: expected {expected}, found {found}")]
    Dimension {
        /// What was being sized.
        what: String,
        /// The expected size.
        expected: usize,
        /// The size given.
        found: usize,
    },
    /// A static map parameter is invalid.
    #[error("static map: {0}")]
    BadMap(String),
}

/// Checks that every coefficient is finite and that there is at least one.
pub(crate) fn check_poly(what: &str, p: &[f64]) -> Result<(), ModelError> {
    if p.is_empty() {
        return Err(ModelError::Empty { what: what.to_string() });
    }
    if let Some((index, &value)) = p.iter().enumerate().find(|(_, v)| !v.is_finite()) {
        return Err(ModelError::NotFinite { what: what.to_string(), index, value });
    }
    Ok(())
}
