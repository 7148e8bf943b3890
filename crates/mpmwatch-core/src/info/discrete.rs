//! Mutual information between a discrete X (a PRBS or multilevel dither) and a continuous Y.
//!
//! KSG algorithm 1 with X discrete reduces to Ross's estimator (Ross 2014, PLoS ONE 9 e87357):
//! for sample i of class c, d_i is the distance to its k-th nearest neighbour among the samples
//! of the same class, m_i the number of samples of any class strictly within d_i, and
//! `I = ψ(N) + ⟨ψ(k)⟩ − ⟨ψ(N_c)⟩ − ⟨ψ(m_i)⟩`. In one dimension everything is sorting and binary
//! search: O(N log N), no tree, and exact ties in X cost nothing (DESIGN.md §2.1).
//!
//! As in scikit-learn's `_compute_mi_cd`, a class with fewer than k + 1 members uses
//! k = N_c − 1, and singleton classes are left out. Ties in Y that put the k-th neighbour at
//! distance 0 follow Gao et al. (2017): k becomes the number of in-class samples at distance 0
//! and m_i counts samples at distance 0.

use super::digamma::digamma;
use super::marginal::{count_strictly_within_range, count_within, kth_neighbour_distance, total_order};

/// The distinct levels of a discrete series and each sample's level index.
#[derive(Debug, Clone, PartialEq)]
pub struct Levels {
    /// Distinct values, ascending.
    pub values: Vec<f64>,
    /// For each sample, the index of its value in `values`.
    pub labels: Vec<u16>,
}

impl Levels {
    /// The levels of `x`, or `None` when it has more than `max_levels` distinct values.
    pub fn of(x: &[f64], max_levels: usize) -> Option<Self> {
        let mut values: Vec<f64> = Vec::new();
        for &v in x {
            if let Err(pos) = values.binary_search_by(|p| p.total_cmp(&v)) {
                if values.len() == max_levels {
                    return None;
                }
                values.insert(pos, v);
            }
        }
        let labels = x
            .iter()
            .map(|v| values.binary_search_by(|p| p.total_cmp(v)).expect("every value is a level") as u16)
            .collect();
        Some(Self { values, labels })
    }

    /// Number of levels.
    pub fn count(&self) -> usize {
        self.values.len()
    }
}

/// Ross's estimator in nats on data already sorted by y: `y_sorted` ascending and `labels[i]`
/// the class of the sample whose y is `y_sorted[i]`. Classes are `0..n_classes`.
///
/// Taking sorted input lets the lagged profile and circular-shift surrogates sort the residual
/// once and only relabel it, instead of sorting at every lag and every surrogate.
pub(crate) fn ross_sorted(y_sorted: &[f64], labels: &[u16], n_classes: usize, k: usize) -> f64 {
    let mut counts = vec![0usize; n_classes];
    for &l in labels {
        counts[l as usize] += 1;
    }
    if counts.contains(&1) {
        // Singleton classes have no in-class neighbour and leave the sample altogether.
        let (ys, ls): (Vec<f64>, Vec<u16>) = y_sorted
            .iter()
            .zip(labels)
            .filter(|&(_, &l)| counts[l as usize] > 1)
            .map(|(&v, &l)| (v, l))
            .unzip();
        return ross_sorted(&ys, &ls, n_classes, k);
    }
    // Each class's samples, by their position in the whole sorted sample (a counting sort,
    // so positions stay ascending within a class): the k-th in-class neighbour is found by
    // walking the class's values, and the count within its radius by galloping from the
    // sample's own position in the whole, where the count is small.
    let mut offset = vec![0usize; n_classes + 1];
    for c in 0..n_classes {
        offset[c + 1] = offset[c] + counts[c];
    }
    let mut fill = offset.clone();
    let mut position = vec![0u32; y_sorted.len()];
    let mut values = vec![0.0; y_sorted.len()];
    for (p, (&v, &l)) in y_sorted.iter().zip(labels).enumerate() {
        let slot = &mut fill[l as usize];
        position[*slot] = p as u32;
        values[*slot] = v;
        *slot += 1;
    }
    let mut acc = 0.0;
    let mut used = 0usize;
    for c in 0..n_classes {
        let range = offset[c]..offset[c + 1];
        let n_c = range.len();
        if n_c < 2 {
            continue;
        }
        let vals = &values[range.clone()];
        let k_c = k.min(n_c - 1);
        let psi_nc = digamma(n_c);
        let at = &position[range.clone()];
        for (p, &centre) in vals.iter().enumerate() {
            let r = kth_neighbour_distance(vals, p, k_c);
            let (k_i, m_i) = if r > 0.0 {
                let lower = if p > k_c { at[p - k_c - 1] as usize + 1 } else { 0 };
                let upper = at.get(p + k_c + 1).map_or(y_sorted.len(), |&a| a as usize);
                (k_c, count_strictly_within_range(y_sorted, lower, upper, at[p] as usize, r))
            } else {
                (count_within(vals, centre, 0.0) - 1, count_within(y_sorted, centre, 0.0))
            };
            acc += digamma(k_i) - psi_nc - digamma(m_i);
        }
        used += n_c;
    }
    if used == 0 {
        return 0.0;
    }
    digamma(used) + acc / used as f64
}

/// Ross's estimator in nats for labelled X and continuous Y (inputs validated by the caller).
pub(crate) fn ross(levels: &Levels, y: &[f64], k: usize) -> f64 {
    // Sorting the (value, label) pairs themselves compares in place, where sorting indices
    // would fetch both values from elsewhere at every comparison.
    // Each value is mapped once to the integer whose order is `f64::total_cmp`'s, so the sort
    // compares integers instead of re-deriving that key at every comparison.
    let mut pairs: Vec<(i64, u16)> =
        y.iter().map(|&v| total_order(v.to_bits() as i64)).zip(levels.labels.iter().copied()).collect();
    pairs.sort_unstable_by_key(|p| p.0);
    let (y_sorted, labels): (Vec<f64>, Vec<u16>) =
        pairs.into_iter().map(|(k, l)| (f64::from_bits(total_order(k) as u64), l)).unzip();
    ross_sorted(&y_sorted, &labels, levels.count(), k)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_sort_key_orders_as_total_cmp_and_inverts() {
        let v = [-f64::INFINITY, -3.5, -1e-300, -0.0, 0.0, 1e-300, 2.0, f64::INFINITY];
        let k: Vec<i64> = v.iter().map(|x| total_order(x.to_bits() as i64)).collect();
        assert!(k.windows(2).all(|w| w[0] < w[1]), "{k:?}");
        for (x, &k) in v.iter().zip(&k) {
            assert_eq!(f64::from_bits(total_order(k) as u64).to_bits(), x.to_bits());
        }
    }

    #[test]
    fn levels_are_found_and_capped() {
        let l = Levels::of(&[1.0, -1.0, 1.0, 0.5], 8).unwrap();
        assert_eq!(l.values, vec![-1.0, 0.5, 1.0]);
        assert_eq!(l.labels, vec![2, 0, 2, 1]);
        assert!(Levels::of(&[1.0, 2.0, 3.0], 2).is_none());
    }

    /// Brute force from the definition (sklearn's `_compute_mi_cd` semantics).
    fn brute(x: &[f64], y: &[f64], k: usize) -> f64 {
        let n = x.len();
        let mut acc = 0.0;
        for i in 0..n {
            let same: Vec<usize> = (0..n).filter(|&j| j != i && x[j] == x[i]).collect();
            let mut d: Vec<f64> = same.iter().map(|&j| (y[j] - y[i]).abs()).collect();
            d.sort_by(f64::total_cmp);
            let r = d[k - 1];
            let m = (0..n).filter(|&j| (y[j] - y[i]).abs() < r).count();
            acc += digamma(k) - digamma(same.len() + 1) - digamma(m);
        }
        digamma(n) + acc / n as f64
    }

    #[test]
    fn sorted_version_equals_brute_force() {
        let x: Vec<f64> = (0..400).map(|i| if (i * 37 + i / 7) % 3 == 0 { 1.0 } else { -1.0 }).collect();
        let y: Vec<f64> = (0..400).map(|i| 0.4 * x[i] + ((i * 7919) % 1009) as f64 / 1009.0).collect();
        let levels = Levels::of(&x, 2).unwrap();
        for k in [1, 3, 4, 8] {
            let a = ross(&levels, &y, k);
            let b = brute(&x, &y, k);
            assert!((a - b).abs() < 1e-12, "k={k}: {a} vs {b}");
        }
    }
}
