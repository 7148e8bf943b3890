//! The bounded ring buffer of aligned rows a controller is analysed on. Its length is the
//! config's `window`, so memory is bounded whatever the input rate.

use std::collections::VecDeque;

use super::align::WindowRow;

/// The most recent rows, in slot order.
#[derive(Debug, Clone)]
pub struct Window {
    cap: usize,
    rows: VecDeque<WindowRow>,
}

/// The data one analysis runs on: every stretch of the window without a gap that is long
/// enough to hold lagged pairs, laid end to end with their lengths, so that the analysis can
/// keep every pair inside one stretch (`detect::analyze_segments`).
#[derive(Debug, Clone, PartialEq)]
pub struct Snapshot {
    /// First slot.
    pub first_slot: i64,
    /// Last slot.
    pub last_slot: i64,
    /// Dither series, one per MV.
    pub dither: Vec<Vec<f64>>,
    /// Residual series, one per CV.
    pub residual: Vec<Vec<f64>>,
    /// Lengths of the contiguous stretches, oldest first (they sum to the series' length).
    pub segments: Vec<usize>,
}

/// Not enough usable rows for an analysis.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Insufficient {
    /// Rows in stretches without a gap of at least the shortest useful length.
    pub usable: usize,
    /// Rows needed.
    pub needed: usize,
}

impl Window {
    /// An empty window of `cap` rows.
    pub fn new(cap: usize) -> Self {
        // Grows as rows come: a long window of a quiet controller costs nothing up front.
        Self { cap, rows: VecDeque::with_capacity(cap.min(4096)) }
    }

    /// Appends a row, evicting the oldest when full. A row not after the last one is refused
    /// (returns false): the aligner closes rows in order, so this only guards restored data.
    pub fn push(&mut self, row: WindowRow) -> bool {
        if self.rows.back().is_some_and(|last| last.slot >= row.slot) {
            return false;
        }
        if self.rows.len() == self.cap {
            self.rows.pop_front();
        }
        self.rows.push_back(row);
        true
    }

    /// Puts a back-filled row at its slot: it replaces the row of that slot or fills a gap, and
    /// evicts the oldest row when full. Refused (false) when it is older than every row of a
    /// full window, since it would leave at once.
    pub fn insert(&mut self, row: WindowRow) -> bool {
        match self.rows.binary_search_by_key(&row.slot, |r| r.slot) {
            Ok(k) => {
                self.rows[k] = row;
                true
            }
            Err(k) if k == self.rows.len() => self.push(row),
            Err(0) if self.rows.len() == self.cap => false,
            Err(k) => {
                self.rows.insert(k, row);
                if self.rows.len() > self.cap {
                    self.rows.pop_front();
                }
                true
            }
        }
    }

    /// The rows, oldest first, for rewriting their residuals.
    pub fn rows_mut(&mut self) -> impl Iterator<Item = &mut WindowRow> {
        self.rows.iter_mut()
    }

    /// Drops every row (after the source clock jumped back: the rows lie in its future).
    pub fn clear(&mut self) {
        self.rows.clear();
    }

    /// Rows held.
    pub fn len(&self) -> usize {
        self.rows.len()
    }

    /// True when empty.
    pub fn is_empty(&self) -> bool {
        self.rows.is_empty()
    }

    /// Capacity.
    pub fn capacity(&self) -> usize {
        self.cap
    }

    /// Fill fraction, 0..=1.
    pub fn fill(&self) -> f64 {
        self.rows.len() as f64 / self.cap as f64
    }

    /// The rows, oldest first.
    pub fn rows(&self) -> impl Iterator<Item = &WindowRow> {
        self.rows.iter()
    }

    /// Slot of the newest row.
    pub fn last_slot(&self) -> Option<i64> {
        self.rows.back().map(|r| r.slot)
    }

    /// Rows at the end of the window whose slots follow one another without a gap.
    pub fn contiguous_tail(&self) -> usize {
        let mut n = 0;
        let mut next: Option<i64> = None;
        for r in self.rows.iter().rev() {
            if next.is_some_and(|s| r.slot != s - 1) {
                break;
            }
            next = Some(r.slot);
            n += 1;
        }
        n
    }

    /// Copies every stretch without a gap of at least `min_segment` rows, if together they
    /// hold at least `needed` rows (shorter stretches cannot hold a lagged pair after the
    /// analysis trims their heads, so they are left out).
    pub fn snapshot(&self, needed: usize, min_segment: usize) -> Result<Snapshot, Insufficient> {
        let mut runs: Vec<(usize, usize)> = Vec::new();
        let mut start = 0;
        for k in 1..=self.rows.len() {
            if k == self.rows.len() || self.rows[k].slot != self.rows[k - 1].slot + 1 {
                if k - start >= min_segment.max(1) {
                    runs.push((start, k));
                }
                start = k;
            }
        }
        let usable: usize = runs.iter().map(|(a, b)| b - a).sum();
        if usable < needed || usable == 0 {
            return Err(Insufficient { usable, needed });
        }
        let rows: Vec<&WindowRow> = runs.iter().flat_map(|&(a, b)| self.rows.range(a..b)).collect();
        let (nd, nr) = (rows[0].dither.len(), rows[0].residual.len());
        Ok(Snapshot {
            first_slot: rows[0].slot,
            last_slot: rows[rows.len() - 1].slot,
            dither: (0..nd).map(|i| rows.iter().map(|r| r.dither[i]).collect()).collect(),
            residual: (0..nr).map(|j| rows.iter().map(|r| r.residual[j]).collect()).collect(),
            segments: runs.iter().map(|(a, b)| b - a).collect(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(slot: i64) -> WindowRow {
        WindowRow {
            slot,
            mv: vec![0.0],
            dither: vec![slot as f64],
            cv: vec![0.0],
            residual: vec![-(slot as f64)],
        }
    }

    #[test]
    fn ring_buffer_keeps_the_newest_rows() {
        let mut w = Window::new(4);
        for s in 0..10 {
            assert!(w.push(row(s)));
        }
        assert_eq!(w.len(), 4);
        assert_eq!(w.rows().map(|r| r.slot).collect::<Vec<_>>(), vec![6, 7, 8, 9]);
        assert!(!w.push(row(9)), "a repeated slot is refused");
        assert_eq!(w.fill(), 1.0);
    }

    #[test]
    fn a_back_filled_row_fills_its_gap_or_replaces_its_slot() {
        let mut w = Window::new(5);
        for s in [1, 2, 4, 5] {
            w.push(row(s));
        }
        assert!(w.insert(row(3)));
        assert_eq!(w.rows().map(|r| r.slot).collect::<Vec<_>>(), vec![1, 2, 3, 4, 5]);
        let mut again = row(3);
        again.cv = vec![7.0];
        assert!(w.insert(again));
        assert_eq!(w.rows().nth(2).unwrap().cv, vec![7.0]);
        assert!(!w.insert(row(0)), "older than a full window");
        assert!(w.insert(row(6)));
        assert_eq!(w.rows().map(|r| r.slot).collect::<Vec<_>>(), vec![2, 3, 4, 5, 6]);
        assert_eq!(w.contiguous_tail(), 5);
    }

    #[test]
    fn snapshots_keep_every_long_enough_stretch_and_say_where_the_gaps_are() {
        let mut w = Window::new(100);
        for s in (0..20).chain(25..35) {
            w.push(row(s));
        }
        assert_eq!(w.contiguous_tail(), 10);
        // Both stretches, laid end to end, with their lengths.
        let s = w.snapshot(30, 5).unwrap();
        assert_eq!((s.first_slot, s.last_slot, s.segments.clone()), (0, 34, vec![20, 10]));
        assert_eq!(s.dither[0], (0..20).chain(25..35).map(|v| v as f64).collect::<Vec<_>>());
        // A stretch shorter than the minimum is left out.
        let s = w.snapshot(10, 15).unwrap();
        assert_eq!((s.first_slot, s.segments.clone()), (0, vec![20]));
        assert_eq!(w.snapshot(31, 5), Err(Insufficient { usable: 30, needed: 31 }));
        assert_eq!(w.snapshot(25, 15), Err(Insufficient { usable: 20, needed: 25 }));
        assert_eq!(Window::new(5).snapshot(1, 1), Err(Insufficient { usable: 0, needed: 1 }));
    }
}
