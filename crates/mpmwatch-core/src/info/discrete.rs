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
        // Levels compare by their bits (what `total_cmp` calls equal); a dither has few, so a
        // linear scan finds a value's level faster than a search.
        let mut values: Vec<f64> = Vec::new();
        for &v in x {
            if !values.iter().any(|p| p.to_bits() == v.to_bits()) {
                if values.len() == max_levels {
                    return None;
                }
                values.push(v);
            }
        }
        values.sort_unstable_by(f64::total_cmp);
        let labels = x
            .iter()
            .map(|v| {
                values.iter().position(|p| p.to_bits() == v.to_bits()).expect("every value is a level") as u16
            })
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
    // so positions stay ascending within a class).
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
    ross_classes(y_sorted, &values, &position, &offset, k)
}

/// The estimator's sum, given the whole sample sorted (`y_sorted`) and each class's slice
/// `offset[c]..offset[c + 1]` of `values` (its samples, ascending) and of `position` (where each
/// sits in `y_sorted`). Classes with fewer than two members must already be left out. The k-th
/// in-class neighbour is found by walking the class's values, and the count within its radius
/// by scanning (or galloping through) the whole between the class neighbours one further out.
fn ross_classes(y_sorted: &[f64], values: &[f64], position: &[u32], offset: &[usize], k: usize) -> f64 {
    let mut acc = 0.0;
    let mut used = 0usize;
    for c in 0..offset.len() - 1 {
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
///
/// Each class is sorted on its own, on the integers whose order is `f64::total_cmp`'s (a sort
/// of plain integers, the fastest the standard library has), and the classes are merged into
/// the whole: the merge yields each class's positions in the whole directly.
pub(crate) fn ross(levels: &Levels, y: &[f64], k: usize) -> f64 {
    let n_classes = levels.count();
    let mut counts = vec![0usize; n_classes];
    levels.labels.iter().for_each(|&l| counts[l as usize] += 1);
    // Singleton classes have no in-class neighbour and leave the sample altogether.
    let kept: Vec<usize> = (0..n_classes).filter(|&c| counts[c] > 1).collect();
    let mut offset = vec![0usize; kept.len() + 1];
    let mut slot_of = vec![usize::MAX; n_classes];
    for (s, &c) in kept.iter().enumerate() {
        offset[s + 1] = offset[s] + counts[c];
        slot_of[c] = s;
    }
    let n = offset[kept.len()];
    let mut keys = vec![0i64; n];
    let mut fill = offset.clone();
    for (&v, &l) in y.iter().zip(&levels.labels) {
        let s = slot_of[l as usize];
        if s != usize::MAX {
            keys[fill[s]] = total_order(v.to_bits() as i64);
            fill[s] += 1;
        }
    }
    for s in 0..kept.len() {
        keys[offset[s]..offset[s + 1]].sort_unstable();
    }
    let mut y_sorted = vec![0.0; n];
    let mut position = vec![0u32; n];
    let mut put = |p: usize, at: usize| {
        y_sorted[p] = f64::from_bits(total_order(keys[at]) as u64);
        position[at] = p as u32;
    };
    let mut head = offset.clone();
    let mut p = 0;
    if kept.len() == 2 {
        // The binary dither's case, without a branch on the data while both classes last.
        let (end_a, end_b) = (offset[1], offset[2]);
        let (mut a, mut b) = (head[0], head[1]);
        while a < end_a && b < end_b {
            let take_a = keys[a] <= keys[b];
            put(p, if take_a { a } else { b });
            a += usize::from(take_a);
            b += usize::from(!take_a);
            p += 1;
        }
        (head[0], head[1]) = (a, b);
    }
    // At each step the smallest head among the classes (ties go to the lower class).
    while p < n {
        let mut best = usize::MAX;
        for s in 0..kept.len() {
            if head[s] < offset[s + 1] && (best == usize::MAX || keys[head[s]] < keys[head[best]]) {
                best = s;
            }
        }
        put(p, head[best]);
        head[best] += 1;
        p += 1;
    }
    let values: Vec<f64> = keys.into_iter().map(|key| f64::from_bits(total_order(key) as u64)).collect();
    ross_classes(&y_sorted, &values, &position, &offset, k)
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

    /// The merge of separately sorted classes against the whole sorted at once: two, four and
    /// five levels, a singleton class (left out by both), ties in y within and across classes.
    #[test]
    fn merged_classes_equal_the_whole_sorted_at_once() {
        let x: Vec<f64> = (0..500)
            .map(|i| match (i * 37 + i / 7) % 5 {
                0 | 1 => 1.0,
                2 => -1.0,
                3 => 0.5,
                _ => 2.0,
            })
            .collect();
        let mut with_singleton = x.clone();
        with_singleton[17] = 9.0;
        // Two classes (the branch-free merge), alone and with a singleton left out.
        let binary: Vec<f64> = x.iter().map(|&v| if v > 0.75 { 1.0 } else { -1.0 }).collect();
        let mut binary_with_singleton = binary.clone();
        binary_with_singleton[3] = 0.0;
        // Every other sample is a whole number whatever its class: ties within and across classes.
        let y: Vec<f64> = (0..500)
            .map(|i| (((i * 7919) % 613) as f64 / 20.0).floor() + if i % 2 == 0 { 0.1 * x[i] } else { 0.0 })
            .collect();
        for xs in [&x, &with_singleton, &binary, &binary_with_singleton] {
            let levels = Levels::of(xs, 8).unwrap();
            let mut order: Vec<usize> = (0..y.len()).collect();
            order.sort_by(|&a, &b| y[a].total_cmp(&y[b]));
            let ys: Vec<f64> = order.iter().map(|&i| y[i]).collect();
            let ls: Vec<u16> = order.iter().map(|&i| levels.labels[i]).collect();
            for k in [1, 3, 4, 8] {
                let a = ross(&levels, &y, k);
                let b = ross_sorted(&ys, &ls, levels.count(), k);
                assert!((a - b).abs() < 1e-12, "k={k}: {a} vs {b}");
            }
        }
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
