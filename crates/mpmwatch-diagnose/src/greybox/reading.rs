//! The range an output's instrument can read, when the record shows it: a transmitter at the
//! end of its span, an analogue input at full scale (the cascaded tanks' level sensor, pinned
//! at 10 V). A physical element acts on the plant; the range acts on every reading of it, so a
//! record that shows one is read through it by every structure and by the nominal it is
//! compared with ([`super::Orders::reading`], [`super::explain`]), and the range alone is a
//! finding when nothing else is ([`super::clip_sensor::ClipSensor`]).
//!
//! The record shows a range by a pile-up: a clip returns the same number every time the
//! signal is beyond it, where a noisy reading of a continuous signal hardly repeats a value and
//! a quantised one repeats each of its steps, the extremes no more than the rest. A side is
//! pinned when its extreme value is held on at least [`MIN_PINNED_SHARE`] of the rows (and
//! [`MIN_PINNED_ROWS`]) and at least [`PILE_UP`] times as often as the record holds a value on
//! average (its rows over its distinct values).

use std::collections::HashMap;

/// The least share of the rows a pinned extreme must hold: the share a named element's kink must
/// act on ([`super::explain::MIN_ACTING`]), so that a range is read only where a clip would act.
pub const MIN_PINNED_SHARE: f64 = 0.01;

/// The least number of rows a pinned extreme must hold, on a short record.
pub const MIN_PINNED_ROWS: usize = 5;

/// How many times as often as the record holds a value on average a pinned extreme must be
/// held. A quantised reading's extremes are held about as often as its steps on average or
/// less (TCLab's 0.32 °C steps: extremes held 1 to 95 times where the records hold a value 6 to
/// 24 times on average); the cascaded tanks' level sensor holds 10 V 47 times where the
/// estimation record holds a value 1.1 times on average, and a rounded continuous reading
/// about once.
pub const PILE_UP: f64 = 10.0;

/// A range the record's instrument reads within: `lower` and `upper`, each −∞ or +∞ on a side
/// the record does not show pinned, and the rows held at each.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Reading {
    /// Lowest value read (−∞: not pinned).
    pub lower: f64,
    /// Highest value read (+∞: not pinned).
    pub upper: f64,
    /// Rows held at `lower`.
    pub at_lower: usize,
    /// Rows held at `upper`.
    pub at_upper: usize,
}

impl Reading {
    /// `v` as the instrument reads it (a NaN stays NaN). `max` then `min`, not `clamp`: a range
    /// built by hand with its ends crossed or NaN must not panic (the upper end then wins).
    pub fn read(&self, v: f64) -> f64 {
        if v.is_nan() { v } else { v.max(self.lower).min(self.upper) }
    }

    /// Whether `v` is strictly inside the range, where a reading is the value itself.
    pub fn inside(&self, v: f64) -> bool {
        v > self.lower && v < self.upper
    }

    /// The range in words, for a finding on `output`.
    pub fn describe(&self, output: &str) -> String {
        let side =
            |v: f64, rows: usize| format!("{} ({rows} training rows sit there)", crate::describe::num(v));
        match (self.lower.is_finite(), self.upper.is_finite()) {
            (true, true) => format!(
                "{output}'s instrument reads between {} and {}",
                side(self.lower, self.at_lower),
                side(self.upper, self.at_upper)
            ),
            (false, true) => {
                format!("{output}'s instrument reads no higher than {}", side(self.upper, self.at_upper))
            }
            (true, false) => {
                format!("{output}'s instrument reads no lower than {}", side(self.lower, self.at_lower))
            }
            (false, false) => format!("{output}'s instrument shows no range"),
        }
    }
}

/// The range the rows `y` show pinned, `None` when neither side is.
pub fn pinned(y: &[f64]) -> Option<Reading> {
    let finite: Vec<f64> = y.iter().copied().filter(|v| v.is_finite()).collect();
    if finite.is_empty() {
        return None;
    }
    let mut counts: HashMap<u64, usize> = HashMap::new();
    for v in &finite {
        // +0.0 and −0.0 are one reading.
        *counts.entry((v + 0.0).to_bits()).or_default() += 1;
    }
    let lo = finite.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = finite.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let held = |v: f64| counts.get(&(v + 0.0).to_bits()).copied().unwrap_or(0);
    let need = MIN_PINNED_ROWS.max((MIN_PINNED_SHARE * finite.len() as f64).ceil() as usize);
    let average = finite.len() as f64 / counts.len() as f64;
    let is_pinned = |v: f64| held(v) >= need && held(v) as f64 >= PILE_UP * average;
    // A record held at one value throughout has no range to read: it has no other value.
    if lo == hi {
        return None;
    }
    let (pin_lo, pin_hi) = (is_pinned(lo), is_pinned(hi));
    (pin_lo || pin_hi).then(|| Reading {
        lower: if pin_lo { lo } else { f64::NEG_INFINITY },
        upper: if pin_hi { hi } else { f64::INFINITY },
        at_lower: if pin_lo { held(lo) } else { 0 },
        at_upper: if pin_hi { held(hi) } else { 0 },
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A sine of 1000 samples with a little deterministic jitter (hardly a value repeats), the
    /// same clipped at 0.9 (the top ~14 % of a sine's samples held at one value), the clip at
    /// the bottom, and the sine read in steps of 0.05 (41 steps held 24 times each on average,
    /// the extremes, where a sine dwells, about 70: under ten times the average). Only the
    /// clipped ones show a range, on their clipped side, with the rows held there counted.
    #[test]
    fn a_clip_shows_its_range_and_a_quantised_or_continuous_reading_does_not() {
        let x: Vec<f64> =
            (0..1000).map(|t| (t as f64 * 0.0377).sin() + 1e-4 * ((t * 7919 % 101) as f64)).collect();
        assert_eq!(pinned(&x), None);
        let top: Vec<f64> = x.iter().map(|v| v.min(0.9)).collect();
        let r = pinned(&top).expect("a clip at 0.9");
        assert_eq!((r.lower, r.upper), (f64::NEG_INFINITY, 0.9));
        assert_eq!(r.at_upper, x.iter().filter(|&&v| v >= 0.9).count());
        assert!(r.at_upper >= 100, "{}", r.at_upper);
        let bottom: Vec<f64> = x.iter().map(|v| v.max(-0.8)).collect();
        let r = pinned(&bottom).expect("a clip at −0.8");
        assert_eq!((r.lower, r.upper), (-0.8, f64::INFINITY));
        let steps: Vec<f64> = x.iter().map(|v| (v / 0.05).round() * 0.05).collect();
        assert_eq!(pinned(&steps), None);
        // A constant record, and one whose extreme is held on a handful of rows, show none.
        assert_eq!(pinned(&[1.0; 50]), None);
        let mut few = x.clone();
        few[..4].iter_mut().for_each(|v| *v = 2.0);
        assert_eq!(pinned(&few), None);
    }

    /// The range reads a value as the instrument would, and says where the reading is the value.
    #[test]
    fn a_range_reads_inside_itself() {
        let r = Reading { lower: f64::NEG_INFINITY, upper: 10.0, at_lower: 0, at_upper: 47 };
        assert_eq!(r.read(13.0), 10.0);
        assert_eq!(r.read(-5.0), -5.0);
        let crossed = Reading { lower: 2.0, upper: 1.0, at_lower: 5, at_upper: 5 };
        assert_eq!(crossed.read(0.0), 1.0);
        assert!(r.read(f64::NAN).is_nan());
        assert!(r.inside(9.99) && !r.inside(10.0));
        assert_eq!(r.describe("y"), "y's instrument reads no higher than 10.00 (47 training rows sit there)");
    }
}
