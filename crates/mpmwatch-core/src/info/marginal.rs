//! Neighbour counts in one dimension by binary search on a sorted copy of the series.
//!
//! KSG's marginal counts ask "how many samples lie within distance r of sample i" for every i;
//! on a sorted array that is two binary searches, O(log N), and exact ties cost nothing extra
//! (a linear walk over ties, as some libraries do, is what makes binary dithers slow).

/// A series sorted ascending, for counting neighbours within a radius, with the position of
/// each original sample in the sorted order.
#[derive(Debug, Clone)]
pub struct SortedMarginal {
    sorted: Vec<f64>,
    position: Vec<u32>,
}

impl SortedMarginal {
    /// Sorts a copy of `values` (which must be finite).
    pub fn new(values: &[f64]) -> Self {
        // (key, index) pairs compared in place by an integer key, where sorting indices would
        // fetch both values and re-derive `total_cmp`'s order at every comparison.
        let mut pairs: Vec<(i64, u32)> =
            values.iter().enumerate().map(|(i, &v)| (total_order(v.to_bits() as i64), i as u32)).collect();
        pairs.sort_unstable_by_key(|p| p.0);
        let mut position = vec![0u32; values.len()];
        for (p, &(_, i)) in pairs.iter().enumerate() {
            position[i as usize] = p as u32;
        }
        let sorted = pairs.iter().map(|&(key, _)| f64::from_bits(total_order(key) as u64)).collect();
        Self { sorted, position }
    }

    /// Number of samples strictly within `r` of sample `i` (itself included). KSG's counts are
    /// small: when the samples `WINDOW` places either side of `i`'s sorted position are both at
    /// least `r` away, each end is found by a branch-free bisection of the window (a fixed
    /// number of steps, no branch on the data for the processor to mispredict); otherwise the
    /// count gallops outwards from the position, O(log count).
    pub fn count_strictly_within_sample(&self, i: usize, r: f64) -> usize {
        const WINDOW: usize = 256;
        let s = &self.sorted;
        let p = self.position[i] as usize;
        let c = s[p];
        if p >= WINDOW && p + WINDOW < s.len() && c - s[p - WINDOW] >= r && s[p + WINDOW] - c >= r {
            // Last of s[p..p + WINDOW] with v − c < r (s[p] qualifies), and the first of
            // s[p − WINDOW..=p] with c − v < r (s[p] qualifies).
            let (mut hi, mut lo) = (p, p - WINDOW);
            let mut len = WINDOW;
            while len > 1 {
                let half = len / 2;
                hi = if s[hi + half] - c < r { hi + half } else { hi };
                lo = if c - s[lo + half] >= r { lo + half } else { lo };
                len -= half;
            }
            return hi - lo;
        }
        count_strictly_within_at(s, p, r)
    }

    /// The sorted values.
    pub fn values(&self) -> &[f64] {
        &self.sorted
    }

    /// Number of samples `v` with `|v − c| ≤ r`.
    pub fn count_within(&self, c: f64, r: f64) -> usize {
        count_within(&self.sorted, c, r)
    }
}

/// The bits of an `f64` as an integer ordered as `f64::total_cmp` orders the floats (the
/// magnitude bits of negatives flipped, as `total_cmp` does); its own inverse.
pub(crate) fn total_order(bits: i64) -> i64 {
    bits ^ (((bits >> 63) as u64) >> 1) as i64
}

/// Number of elements of the sorted slice strictly within `r` of the element at position `p`
/// (itself included), galloping outwards from `p`: O(log count) rather than O(log N).
pub fn count_strictly_within_at(s: &[f64], p: usize, r: f64) -> usize {
    let c = s[p];
    // Last index (≥ p) with v − c < r, and first index (≤ p) with c − v < r.
    let mut step = 1;
    let mut hi = p;
    while hi + step < s.len() && s[hi + step] - c < r {
        hi += step;
        step *= 2;
    }
    let end = (hi + step + 1).min(s.len());
    let hi = hi + s[hi..end].partition_point(|&v| v - c < r);
    let mut step = 1;
    let mut lo = p;
    while lo >= step && c - s[lo - step] < r {
        lo -= step;
        step *= 2;
    }
    let start = lo.saturating_sub(step);
    let lo = start + s[start..lo].partition_point(|&v| c - v >= r);
    hi - lo
}

/// [`SortedMarginal::count_within`] on a borrowed sorted slice.
pub fn count_within(sorted: &[f64], c: f64, r: f64) -> usize {
    let lo = sorted.partition_point(|&v| c - v > r);
    let hi = sorted.partition_point(|&v| v - c <= r);
    hi.saturating_sub(lo)
}

/// Distance from position `p` of a sorted array to its `k`-th nearest other element. Requires
/// `sorted.len() > k`.
///
/// The k nearest elements with `p` itself are k + 1 consecutive ones, so the distance is the
/// smallest, over the windows of k + 1 consecutive elements that hold `p`, of the window's
/// largest distance from `p`. This evaluates all k + 1 windows without a branch, where a walk
/// outwards from `p` chooses left or right at each step on a branch no processor predicts.
/// Whatever the ties, the elements k + 1 places away on either side lie at least this far.
#[inline]
pub fn kth_neighbour_distance(sorted: &[f64], p: usize, k: usize) -> f64 {
    let c = sorted[p];
    let first = p.saturating_sub(k);
    let last = p.min(sorted.len() - 1 - k);
    let span = &sorted[first..=last + k];
    let mut d = f64::INFINITY;
    for (&a, &b) in span.iter().zip(&span[k..]) {
        // Plain comparisons: the values are finite, so no NaN rule is needed.
        let far = if c - a > b - c { c - a } else { b - c };
        d = if far < d { far } else { d };
    }
    d
}

/// Number of elements of `s[lower..upper]` strictly within `r` of `c = s[p]`, for a range known
/// to hold every element of the sorted slice `s` that is (for Ross's estimator: between the
/// class neighbours k + 1 places away, see [`kth_neighbour_distance`]). A short range is
/// counted in one branch-free pass, which beats a search whose branches the processor cannot
/// predict; a long one is searched from `p`.
#[inline]
pub fn count_strictly_within_range(s: &[f64], lower: usize, upper: usize, p: usize, r: f64) -> usize {
    const LINEAR: usize = 64;
    let c = s[p];
    if upper - lower <= LINEAR {
        s[lower..upper].iter().map(|&v| usize::from((v - c).abs() < r)).sum()
    } else {
        count_strictly_within_at(s, p, r)
    }
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
        for (i, &c) in v.iter().enumerate() {
            for r in [0.0, 0.25, 0.5, 1.0, 1.5, 10.0] {
                assert_eq!(m.count_strictly_within_sample(i, r), brute_count(&v, c, r, true), "c={c} r={r}");
                assert_eq!(m.count_within(c, r), brute_count(&v, c, r, false), "c={c} r={r}");
            }
        }
    }

    #[test]
    fn galloping_counts_match_brute_force() {
        let v: Vec<f64> = (0..300).map(|i| (((i * 7919) % 311) as f64 / 10.0).floor()).collect();
        let m = SortedMarginal::new(&v);
        for (i, &c) in v.iter().enumerate() {
            for r in [0.05, 0.5, 1.0, 3.0, 7.5, 40.0] {
                assert_eq!(m.count_strictly_within_sample(i, r), brute_count(&v, c, r, true), "i={i} r={r}");
            }
        }
    }

    #[test]
    fn windowed_bisection_counts_match_brute_force() {
        // Enough samples for the 256-wide windows either side of a position to fit, with ties
        // (a quarter of the values repeat) and radii from below the spacing to past the window.
        let v: Vec<f64> = (0..1500).map(|i| (((i * 7919) % 1201) as f64 / 4.0).floor() * 0.01).collect();
        let m = SortedMarginal::new(&v);
        for (i, &c) in v.iter().enumerate() {
            for r in [0.005, 0.01, 0.2, 0.8, 1.3, 3.0] {
                assert_eq!(m.count_strictly_within_sample(i, r), brute_count(&v, c, r, true), "i={i} r={r}");
            }
        }
    }

    #[test]
    fn counts_between_the_class_neighbours_k_plus_one_away_match_brute_force() {
        // A class is every third element of a sorted array with ties across classes; counting
        // between the class's elements k + 1 places either side of the centre gives the whole
        // array's count.
        let whole: Vec<f64> = {
            let mut v: Vec<f64> = (0..400).map(|i| (((i * 7919) % 331) as f64 / 7.0).floor()).collect();
            v.sort_by(f64::total_cmp);
            v
        };
        let positions: Vec<usize> = (0..whole.len()).step_by(3).collect();
        let class: Vec<f64> = positions.iter().map(|&p| whole[p]).collect();
        for k in [1, 4, 9] {
            for (q, &p) in positions.iter().enumerate() {
                let r = kth_neighbour_distance(&class, q, k);
                let lower = if q > k { positions[q - k - 1] + 1 } else { 0 };
                let upper = positions.get(q + k + 1).copied().unwrap_or(whole.len());
                let want = brute_count(&whole, whole[p], r, true);
                assert_eq!(count_strictly_within_range(&whole, lower, upper, p, r), want, "p={p} k={k}");
                assert_eq!(count_strictly_within_at(&whole, p, r), want, "p={p} k={k}");
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
