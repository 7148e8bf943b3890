//! How far a held-out tail leaves the range its training part visited ([`BeyondTraining`]):
//! a caution on the held-out FIT, since every correction is fitted within that range.

use crate::describe::num;
use crate::report::BeyondTraining;

impl BeyondTraining {
    /// The held-out tail `x[start..]` against the training part `x[..start]`; `None` when the
    /// tail stays within the training range, or either part is empty or not finite.
    pub fn of(signal: &str, x: &[f64], start: usize) -> Option<Self> {
        let (train, tail) = x.split_at_checked(start)?;
        if train.is_empty() || tail.is_empty() {
            return None;
        }
        let range = |v: &[f64]| {
            v.iter().try_fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &t| {
                t.is_finite().then_some((a.min(t), b.max(t)))
            })
        };
        let ((lo, hi), (tlo, thi)) = (range(train)?, range(tail)?);
        let outside = tail.iter().filter(|&&t| t < lo || t > hi).count();
        if outside == 0 {
            return None;
        }
        // A width at rounding level (a constant part stored as decimals) measures nothing, and
        // a percentage of it could overflow to a non-finite number, which JSON cannot carry.
        let width = hi - lo;
        let measurable = width > 1e-12 * lo.abs().max(hi.abs());
        let excess = (lo - tlo).max(thi - hi);
        Some(BeyondTraining {
            signal: signal.to_string(),
            training: [lo, hi],
            holdout: [tlo, thi],
            share_pct: 100.0 * outside as f64 / tail.len() as f64,
            excess_pct: measurable.then(|| 100.0 * excess / width),
        })
    }

    /// One sentence for a person: where the tail goes and why it matters.
    pub fn sentence(&self) -> String {
        let by =
            self.excess_pct.map_or(String::new(), |e| format!(", up to {e:.0} % of its width beyond it"));
        format!(
            "held-out {}: {:.1} % of the rows lie outside the training range [{}, {}]{by} (the tail spans [{}, {}]); the corrections were fitted within that range and are extrapolated there",
            self.signal,
            self.share_pct,
            num(self.training[0]),
            num(self.training[1]),
            num(self.holdout[0]),
            num(self.holdout[1]),
        )
    }
}

#[cfg(test)]
mod tests {
    use crate::report::BeyondTraining;

    /// Closed forms on a ramp: training 0..=9, a tail that reaches 14 on 5 of its 10 rows, 5
    /// units beyond a width of 9; a tail within the range, an empty part or a NaN is `None`.
    #[test]
    fn a_tail_beyond_the_training_range_is_measured() {
        let x: Vec<f64> = (0..10).map(f64::from).chain((5..15).map(f64::from)).collect();
        let b = BeyondTraining::of("y1", &x, 10).expect("the tail leaves the range");
        assert_eq!((b.training, b.holdout), ([0.0, 9.0], [5.0, 14.0]));
        assert_eq!(
            b.sentence(),
            "held-out y1: 50.0 % of the rows lie outside the training range [0, 9.000], up to 56 % of its width beyond it (the tail spans [5.000, 14.00]); the corrections were fitted within that range and are extrapolated there"
        );
        assert_eq!(b.share_pct, 50.0);
        assert!((b.excess_pct.unwrap() - 500.0 / 9.0).abs() < 1e-12);
        // Below the range counts as beyond too.
        let low: Vec<f64> = (0..10).map(f64::from).chain([-1.0, 3.0]).collect();
        let b = BeyondTraining::of("u1", &low, 10).unwrap();
        assert_eq!((b.share_pct, b.excess_pct), (50.0, Some(100.0 / 9.0)));
        let within: Vec<f64> = (0..10).map(f64::from).chain([0.0, 9.0, 4.5]).collect();
        assert_eq!(BeyondTraining::of("y1", &within, 10), None);
        assert_eq!(BeyondTraining::of("y1", &x, 0), None);
        assert_eq!(BeyondTraining::of("y1", &x, x.len()), None);
        assert_eq!(BeyondTraining::of("y1", &x, 99), None);
        let mut bad = x.clone();
        bad[3] = f64::NAN;
        assert_eq!(BeyondTraining::of("y1", &bad, 10), None);
        // A constant training part has no width to measure the excursion by, nor one that
        // differs only in its last bits.
        let flat = [2.0, 2.0, 2.0, 3.0];
        let b = BeyondTraining::of("y1", &flat, 3).unwrap();
        assert_eq!((b.share_pct, b.excess_pct), (100.0, None));
        let nearly = [0.1 + 0.2, 0.3, 0.3, 1.0];
        assert_eq!(BeyondTraining::of("y1", &nearly, 3).unwrap().excess_pct, None);
    }
}
