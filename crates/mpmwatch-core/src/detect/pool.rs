//! Which dithers are alike enough to share surrogates in the family test
//! ([`crate::info::family_test_group`]).
//!
//! The null distribution of an element's statistics depends on the dither only through what
//! the estimators see of it: Ross's MI and the joint-lag MI see the class labels, not the
//! levels' values, and the standardised cross-correlation is scale-free. Two discrete dithers
//! with the same number of levels, the same share of each level and the same shares of each
//! pair of consecutive levels (what the joint embedding sees) therefore give the same null.
//! Continuous dithers (iAAFT surrogates, which keep each dither's own spectrum) are never pooled.
//!
//! The shares are compared with a tolerance of four standard errors of the difference of two
//! shares estimated from n samples, `4·√(2·p(1−p)/n)` at the worst case p = ½: dithers of one
//! design (a plant's PRBS generators are usually identical) fall together, and designs that differ
//! in balance or in switching rate by more than sampling noise do not.

use crate::info::MiOptions;

/// A discrete dither's level count and its level and level-pair shares.
#[derive(Debug, Clone, PartialEq)]
struct Signature {
    levels: usize,
    shares: Vec<f64>,
}

impl Signature {
    fn of(x: &[f64], mi: &MiOptions) -> Option<Self> {
        let levels = mi.discrete_levels(x).ok().flatten()?;
        let c = levels.count();
        let n = x.len();
        let mut shares = vec![0.0; c + c * c];
        for &l in &levels.labels {
            shares[l as usize] += 1.0 / n as f64;
        }
        for w in levels.labels.windows(2) {
            shares[c + w[0] as usize * c + w[1] as usize] += 1.0 / (n - 1) as f64;
        }
        Some(Self { levels: c, shares })
    }

    fn alike(&self, other: &Self, n: usize) -> bool {
        let tolerance = 4.0 * (0.5 / n as f64).sqrt();
        self.levels == other.levels
            && self.shares.iter().zip(&other.shares).all(|(a, b)| (a - b).abs() <= tolerance)
    }
}

/// Partitions the dithers `candidates` (indices into `dithers`) into groups that may share
/// surrogates: each discrete dither joins the first group whose first member it is alike to;
/// every continuous dither is a group of its own. Groups keep the candidates' order.
pub(crate) fn exchangeable_groups(
    dithers: &[&[f64]],
    candidates: &[usize],
    mi: &MiOptions,
) -> Vec<Vec<usize>> {
    let mut groups: Vec<(Option<Signature>, Vec<usize>)> = Vec::new();
    for &i in candidates {
        let x = dithers[i];
        let sig = Signature::of(x, mi);
        let home = sig
            .as_ref()
            .and_then(|s| groups.iter().position(|(g, _)| g.as_ref().is_some_and(|g| g.alike(s, x.len()))));
        match home {
            Some(k) => groups[k].1.push(i),
            None => groups.push((sig, vec![i])),
        }
    }
    groups.into_iter().map(|(_, members)| members).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::info::significance::stream;
    use rand::Rng;

    fn binary(seed: u64, n: usize, switch: f64, scale: f64) -> Vec<f64> {
        let mut rng = stream(seed, 0);
        let mut v = scale;
        (0..n)
            .map(|_| {
                if rng.random::<f64>() < switch {
                    v = -v;
                }
                v
            })
            .collect()
    }

    #[test]
    fn dithers_of_one_design_share_and_other_designs_do_not() {
        let n = 2048;
        let d: Vec<Vec<f64>> = vec![
            binary(1, n, 0.5, 1.0),
            binary(2, n, 0.5, 0.1), // the same design at another amplitude: the labels are alike
            binary(3, n, 0.2, 1.0), // switches far less often: the pairs' shares differ
            (0..n).map(|t| (t as f64 * 0.37).sin()).collect(), // continuous
            binary(4, n, 0.5, 1.0),
        ];
        let refs: Vec<&[f64]> = d.iter().map(Vec::as_slice).collect();
        let groups = exchangeable_groups(&refs, &[0, 1, 2, 3, 4], &MiOptions::default());
        assert_eq!(groups, vec![vec![0, 1, 4], vec![2], vec![3]]);
    }
}
