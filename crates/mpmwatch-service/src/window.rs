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

/// The data one analysis runs on: the most recent contiguous stretch of the window, so that no
/// lagged pair straddles a gap.
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
}

/// Not enough contiguous rows for an analysis.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Insufficient {
    /// Contiguous rows at the end of the window.
    pub contiguous: usize,
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

    /// Copies the contiguous tail if it has at least `needed` rows.
    pub fn snapshot(&self, needed: usize) -> Result<Snapshot, Insufficient> {
        let n = self.contiguous_tail();
        if n < needed || n == 0 {
            return Err(Insufficient { contiguous: n, needed });
        }
        let tail: Vec<&WindowRow> = self.rows.iter().skip(self.rows.len() - n).collect();
        let (nd, nr) = (tail[0].dither.len(), tail[0].residual.len());
        Ok(Snapshot {
            first_slot: tail[0].slot,
            last_slot: tail[n - 1].slot,
            dither: (0..nd).map(|i| tail.iter().map(|r| r.dither[i]).collect()).collect(),
            residual: (0..nr).map(|j| tail.iter().map(|r| r.residual[j]).collect()).collect(),
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
    fn snapshots_never_straddle_a_gap() {
        let mut w = Window::new(100);
        for s in (0..20).chain(25..35) {
            w.push(row(s));
        }
        assert_eq!(w.contiguous_tail(), 10);
        let s = w.snapshot(10).unwrap();
        assert_eq!((s.first_slot, s.last_slot), (25, 34));
        assert_eq!(s.dither[0], (25..35).map(|v| v as f64).collect::<Vec<_>>());
        assert_eq!(w.snapshot(11), Err(Insufficient { contiguous: 10, needed: 11 }));
        assert_eq!(Window::new(5).snapshot(1), Err(Insufficient { contiguous: 0, needed: 1 }));
    }
}
