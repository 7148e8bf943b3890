//! Input checks shared by every estimator: finite values, equal lengths, enough samples, some
//! variation. Run once at the public entry points so the inner loops can assume clean data.

use super::InfoError;

/// Fails on the first NaN or infinity, naming the series and index.
pub fn finite(name: &str, v: &[f64]) -> Result<(), InfoError> {
    match v.iter().position(|x| !x.is_finite()) {
        Some(index) => Err(InfoError::NonFinite { series: name.to_string(), index, value: v[index] }),
        None => Ok(()),
    }
}

/// Fails when every value is the same.
pub fn not_constant(name: &str, v: &[f64]) -> Result<(), InfoError> {
    match v.first() {
        Some(&first) if v.iter().all(|&x| x == first) => {
            Err(InfoError::Constant { series: name.to_string(), value: first })
        }
        _ => Ok(()),
    }
}

/// Fails when the two lengths differ.
pub fn same_length(left: &str, a: usize, right: &str, b: usize) -> Result<(), InfoError> {
    if a == b {
        Ok(())
    } else {
        Err(InfoError::LengthMismatch {
            left: left.to_string(),
            left_len: a,
            right: right.to_string(),
            right_len: b,
        })
    }
}

/// Checks `k ≥ 1` and that there are more than `k` samples.
pub fn neighbours(what: &str, n: usize, k: usize) -> Result<(), InfoError> {
    if k == 0 {
        return Err(InfoError::InvalidParameter {
            name: "k",
            value: "0".into(),
            reason: "the number of neighbours must be at least 1",
        });
    }
    if n < k + 1 {
        return Err(InfoError::TooFewSamples { what: what.to_string(), n, needed: k + 1 });
    }
    Ok(())
}

/// All the checks for one (x, y) pair.
pub fn pair(x: &[f64], y: &[f64], k: usize) -> Result<(), InfoError> {
    same_length("x", x.len(), "y", y.len())?;
    neighbours("mutual information", x.len(), k)?;
    finite("x", x)?;
    finite("y", y)?;
    not_constant("x", x)?;
    not_constant("y", y)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_problem_is_named() {
        let e = pair(&[1.0, f64::NAN, 2.0], &[1.0, 2.0, 3.0], 1).unwrap_err();
        assert!(matches!(e, InfoError::NonFinite { ref series, index: 1, .. } if series == "x"), "{e}");
        assert!(matches!(pair(&[1.0, 2.0], &[1.0], 1), Err(InfoError::LengthMismatch { .. })));
        assert!(matches!(pair(&[1.0, 2.0], &[1.0, 2.0], 2), Err(InfoError::TooFewSamples { .. })));
        assert!(matches!(pair(&[1.0, 2.0], &[1.0, 2.0], 0), Err(InfoError::InvalidParameter { .. })));
        assert!(matches!(
            pair(&[1.0, 2.0, 3.0], &[5.0, 5.0, 5.0], 1),
            Err(InfoError::Constant { ref series, .. }) if series == "y"
        ));
        assert!(matches!(
            pair(&[1.0, 2.0, f64::INFINITY], &[5.0, 6.0, 5.0], 1),
            Err(InfoError::NonFinite { index: 2, .. })
        ));
    }
}
