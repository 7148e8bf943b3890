//! Neighbour counts in one dimension by binary search on a sorted copy of the series.
//!
//! KSG's marginal counts ask "how many samples lie within distance r of sample i" for every i;
//! on a sorted array that is two binary searches, O(log N), and exact ties cost nothing extra
//! (a linear walk over ties, as some libraries do, is what makes binary dithers slow).

/// A series sorted ascending, for counting neighbours within a radius.
#[derive(Debug, Clone)]
pub struct SortedMarginal {
    sorted: Vec<f64>,
}

impl SortedMarginal {
    /// Sorts a copy of `values` (which must be finite).
    pub fn new(values: &[f64]) -> Self {
        let mut sorted = values.to_vec();
        sorted.sort_unstable_by(f64::total_cmp);
        Self { sorted }
    }

    /// Wraps values that are already sorted ascending.
    pub fn from_sorted(sorted: Vec<f64>) -> Self {
        debug_assert!(sorted.windows(2).all(|w| w[0] <= w[1]));
        Self { sorted }
    }

    /// The sorted values.
    pub fn values(&self) -> &[f64] {
        &self.sorted
    }

    /// Number of samples `v` with `|v − c| < r`, the centre itself included when it is a sample.
    ///
    /// The distances are compared as `c − v` and `v − c`, the same floating-point expressions a
    /// neighbour search computes, so a neighbour found at exactly distance `r` is excluded.
    pub fn count_strictly_within(&self, c: f64, r: f64) -> usize {
        count_strictly_within(&self.sorted, c, r)
    }

    /// Number of samples `v` with `|v − c| ≤ r`.
    pub fn count_within(&self, c: f64, r: f64) -> usize {
        count_within(&self.sorted, c, r)
    }
}

/// [`SortedMarginal::count_strictly_within`] on a borrowed sorted slice.
pub fn count_strictly_within(sorted: &[f64], c: f64, r: f64) -> usize {
    let lo = sorted.partition_point(|&v| c - v >= r);
    let hi = sorted.partition_point(|&v| v - c < r);
    hi.saturating_sub(lo)
}

/// [`SortedMarginal::count_within`] on a borrowed sorted slice.
pub fn count_within(sorted: &[f64], c: f64, r: f64) -> usize {
    let lo = sorted.partition_point(|&v| c - v > r);
    let hi = sorted.partition_point(|&v| v - c <= r);
    hi.saturating_sub(lo)
}

/// Distance from position `p` of a sorted array to its `k`-th nearest other element, found by
/// walking outwards from `p` (O(k)). Requires `sorted.len() > k`.
pub fn kth_neighbour_distance(sorted: &[f64], p: usize, k: usize) -> f64 {
    let c = sorted[p];
    let (mut lo, mut hi) = (p, p + 1);
    let mut d = 0.0;
    for _ in 0..k {
        let left = if lo > 0 { Some(c - sorted[lo - 1]) } else { None };
        let right = sorted.get(hi).map(|&v| v - c);
        d = match (left, right) {
            (Some(l), Some(r)) if l <= r => {
                lo -= 1;
                l
            }
            (Some(l), None) => {
                lo -= 1;
                l
            }
            (_, Some(r)) => {
                hi += 1;
                r
            }
            (None, None) => unreachable!("fewer than k + 1 elements"),
        };
    }
    d
}

#[cfg(test)]
mod tests {
    use super::*;

    fn brute_count(v: &[f64], c: f64, r: f64, strict: bool) -> usize {
        v.iter().filter(|&&x| if strict { (x - c).abs() < r } else { (x - c).abs() <= r }).count()
    }

    #[test]
    fn counts_match_brute_force_with_ties() {
        let v = [0.0, 0.5, 0.5, 0.5, 1.0, 1.5, 2.0, 2.0, 3.0];
        let m = SortedMarginal::new(&v);
        for &c in &v {
            for r in [0.0, 0.25, 0.5, 1.0, 1.5, 10.0] {
                assert_eq!(m.count_strictly_within(c, r), brute_count(&v, c, r, true), "c={c} r={r}");
                assert_eq!(m.count_within(c, r), brute_count(&v, c, r, false), "c={c} r={r}");
            }
        }
    }

    #[test]
    fn kth_neighbour_matches_brute_force() {
        let v: [f64; 7] = [0.0, 0.1, 0.1, 0.4, 0.45, 1.0, 2.5];
        for p in 0..v.len() {
            let mut d: Vec<f64> = (0..v.len()).filter(|&j| j != p).map(|j| (v[j] - v[p]).abs()).collect();
            d.sort_by(f64::total_cmp);
            for k in 1..v.len() {
                assert_eq!(kth_neighbour_distance(&v, p, k), d[k - 1], "p={p} k={k}");
            }
        }
    }
}
