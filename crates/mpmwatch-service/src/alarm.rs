//! Alarm debounce per MV→CV channel: raise after `raise_after` significant runs in a row, clear
//! after `clear_after` clean runs in a row. One noisy run neither raises nor clears an alarm.

use serde::{Deserialize, Serialize};

/// What a run changed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Transition {
    /// The alarm rose.
    Raise,
    /// The alarm cleared.
    Clear,
}

impl Transition {
    /// The JSON/SQL name.
    pub fn as_str(self) -> &'static str {
        match self {
            Self::Raise => "raise",
            Self::Clear => "clear",
        }
    }
}

/// The debounce state of one channel.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Debounce {
    /// Alarm active.
    pub active: bool,
    significant_run: u32,
    clean_run: u32,
}

impl Debounce {
    /// A state with the alarm already active (restored from the store).
    pub fn active() -> Self {
        Self { active: true, ..Self::default() }
    }

    /// Feeds one run's outcome; returns the transition it caused, if any.
    pub fn update(&mut self, significant: bool, raise_after: u32, clear_after: u32) -> Option<Transition> {
        if significant {
            self.significant_run += 1;
            self.clean_run = 0;
            if !self.active && self.significant_run >= raise_after {
                self.active = true;
                return Some(Transition::Raise);
            }
        } else {
            self.clean_run += 1;
            self.significant_run = 0;
            if self.active && self.clean_run >= clear_after {
                self.active = false;
                return Some(Transition::Clear);
            }
        }
        None
    }
}

/// An alarm event as published on `<prefix>/<controller>/alarm` and kept in the history.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct AlarmEvent {
    /// Controller id.
    pub controller: String,
    /// `raise` or `clear`.
    pub event: Transition,
    /// `dither→cv`, e.g. `ud1→y1`.
    pub channel: String,
    /// MV tag.
    pub mv: String,
    /// Dither tag.
    pub dither: String,
    /// CV tag.
    pub cv: String,
    /// Which statistic decided: `lag_mi` (MI at one lag), `joint_mi` (two-lag embedding),
    /// `ccf` (cross-correlation at one lag) or, under method `paper`, `norm_mi`.
    pub statistic: String,
    /// Its value: bits for MI statistics, the absolute correlation for `ccf`.
    pub value_bits: f64,
    /// Its critical value, same units.
    pub critical_bits: f64,
    /// The element's p-value in that run (absent in events stored before it was recorded).
    #[serde(default)]
    pub p_value: Option<f64>,
    /// The channel's verdict in that run (`mismatch`, `clean`, `implicated_by_feedback`).
    pub verdict: String,
    /// Wall-clock time of the run, RFC 3339.
    pub time: String,
    /// Source time of the newest sample analysed, seconds.
    pub data_time: f64,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn raises_after_n_and_clears_after_m_in_a_row() {
        let mut d = Debounce::default();
        let seq = [true, false, true, true, true, false, false, true, false, false, false];
        let got: Vec<Option<Transition>> = seq.iter().map(|&s| d.update(s, 2, 3)).collect();
        use Transition::*;
        assert_eq!(got, vec![None, None, None, Some(Raise), None, None, None, None, None, None, Some(Clear)]);
        assert!(!d.active);
    }

    #[test]
    fn one_run_is_enough_when_configured() {
        let mut d = Debounce::default();
        assert_eq!(d.update(true, 1, 1), Some(Transition::Raise));
        assert_eq!(d.update(false, 1, 1), Some(Transition::Clear));
        let mut r = Debounce::active();
        assert_eq!(r.update(true, 1, 1), None);
    }
}
