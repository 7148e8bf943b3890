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
        let mut order: Vec<u32> = (0..values.len() as u32).collect();
        order.sort_unstable_by(|&a, &b| values[a as usize].total_cmp(&values[b as usize]));
        let mut position = vec![0u32; values.len()];
        for (p, &i) in order.iter().enumerate() {
            position[i as usize] = p as u32;
        }
        let sorted = order.iter().map(|&i| values[i as usize]).collect();
        Self { sorted, position }
    }

    /// Number of samples strictly within `r` of sample `i` (itself included), found by
    /// galloping outwards from its sorted position: O(log count) rather than O(log N), which
    /// matters because KSG's counts are small.
    pub fn count_strictly_within_sample(&self, i: usize, r: f64) -> usize {
        count_strictly_within_at(&self.sorted, self.position[i] as usize, r)
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
