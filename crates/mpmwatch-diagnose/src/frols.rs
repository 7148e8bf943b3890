//! Forward regression with orthogonal least squares (FROLS): which few of many candidate
//! columns explain a series, in order of importance (used to choose a bilinear term's lags).

/// Forward regression with orthogonal least squares (FROLS, Billings 2013 §3.5): repeatedly
/// picks the candidate column whose part orthogonal to the already chosen ones explains the most
/// of `y` (the error reduction ratio, ERR), until `max_terms` are chosen or the best ERR falls
/// below `min_err`. Returns the chosen indices with their ERR, in order of choice.
pub fn frols(
    cands: &[Vec<f64>],
    y: &[f64],
    rows: &[usize],
    max_terms: usize,
    min_err: f64,
) -> Vec<(usize, f64)> {
    let pick = |c: &[f64]| -> Vec<f64> { rows.iter().map(|&t| c[t]).collect() };
    let yy: Vec<f64> = pick(y);
    let sigma = dot(&yy, &yy);
    if sigma == 0.0 {
        return Vec::new();
    }
    let mut basis: Vec<Vec<f64>> = Vec::new();
    let mut chosen: Vec<(usize, f64)> = Vec::new();
    for _ in 0..max_terms {
        let mut best: Option<(usize, f64, Vec<f64>)> = None;
        for (m, c) in cands.iter().enumerate() {
            if chosen.iter().any(|&(k, _)| k == m) {
                continue;
            }
            let cr = pick(c);
            let mut w: Vec<f64> = cr.clone();
            for q in &basis {
                let a = dot(q, &w) / dot(q, q);
                w.iter_mut().zip(q).for_each(|(wi, qi)| *wi -= a * qi);
            }
            let ww = dot(&w, &w);
            if ww <= 1e-12 * dot(&cr, &cr).max(f64::MIN_POSITIVE) {
                continue;
            }
            let g = dot(&w, &yy);
            let err = g * g / (ww * sigma);
            if best.as_ref().is_none_or(|b| err > b.1) {
                best = Some((m, err, w));
            }
        }
        match best {
            Some((m, err, w)) if err >= min_err => {
                chosen.push((m, err));
                basis.push(w);
            }
            _ => break,
        }
    }
    chosen
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frols_picks_the_true_terms_first() {
        let c: Vec<Vec<f64>> =
            (0..5).map(|k| (0..200).map(|t| ((t * (k + 2)) as f64 * 0.7).sin()).collect()).collect();
        let y: Vec<f64> = (0..200).map(|t| 3.0 * c[3][t] + 0.5 * c[1][t]).collect();
        let rows: Vec<usize> = (0..200).collect();
        let chosen = frols(&c, &y, &rows, 4, 1e-6);
        assert_eq!(chosen[0].0, 3);
        assert_eq!(chosen[1].0, 1);
        assert_eq!(chosen.len(), 2);
    }
}
