//! Dither generators: maximal period, balance, clock period, seeding, unit variance.

use mpmwatch_sim::{Excitation, Lfsr, MultilevelPrbs, PRBS_MAX_ORDER, PRBS_MIN_ORDER, Prbs, SimError};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

#[test]
fn every_order_has_maximal_period() {
    for order in PRBS_MIN_ORDER..=PRBS_MAX_ORDER {
        let mut lfsr = Lfsr::new(order, 1).unwrap();
        let start = lfsr.state();
        let mut steps = 0usize;
        loop {
            lfsr.next_bit();
            steps += 1;
            if lfsr.state() == start {
                break;
            }
            assert!(steps <= lfsr.period(), "order {order}: no return within 2^n − 1 steps");
        }
        // the first return after exactly 2^n − 1 steps means every non-zero state was visited
        assert_eq!(steps, (1usize << order) - 1, "order {order}");
    }
}

#[test]
fn one_period_is_balanced() {
    for order in [3, 7, 11, 15] {
        let p = Prbs::new(order, 2.5, 1).unwrap();
        let x = p.generate_from_state(p.period(), 12345);
        let ones = x.iter().filter(|v| **v == 2.5).count();
        let minus = x.iter().filter(|v| **v == -2.5).count();
        assert_eq!(ones, 1 << (order - 1), "order {order}");
        assert_eq!(minus, (1 << (order - 1)) - 1, "order {order}");
    }
}

#[test]
fn sequence_repeats_with_its_period_and_clock() {
    let p = Prbs::new(5, 1.0, 3).unwrap();
    assert_eq!(p.period(), 93);
    let x = p.generate_from_state(3 * p.period(), 7);
    for k in 0..2 * p.period() {
        assert_eq!(x[k], x[k + p.period()]);
    }
    for chunk in x.chunks(3) {
        assert!(chunk.iter().all(|v| *v == chunk[0]), "each bit is held for the clock period");
    }
    // the held sequence is not periodic with the unheld period
    assert!((0..p.period()).any(|k| x[k] != x[k + 31]));
}

#[test]
fn out_of_range_orders_and_bad_designs_are_errors() {
    for order in [0, 1, PRBS_MAX_ORDER + 1, 64] {
        let err = Prbs::new(order, 1.0, 1).unwrap_err();
        assert!(matches!(err, SimError::PrbsOrder { .. }), "{err}");
        assert!(err.to_string().contains(&order.to_string()));
    }
    assert!(Prbs::new(8, 0.0, 1).is_err());
    assert!(Prbs::new(8, 1.0, 0).is_err());
    assert!(MultilevelPrbs::new(1, 1.0, 1).is_err());
    assert!(Excitation::parse("pink").unwrap_err().to_string().contains("pink"));
}

#[test]
fn the_seed_decides_the_shift() {
    let p = Prbs::new(11, 1.0, 1).unwrap();
    let a = p.generate(2047, &mut ChaCha8Rng::seed_from_u64(3));
    let b = p.generate(2047, &mut ChaCha8Rng::seed_from_u64(3));
    let c = p.generate(2047, &mut ChaCha8Rng::seed_from_u64(4));
    assert_eq!(a, b);
    assert_ne!(a, c);
    // c is a circular shift of a: the same m-sequence
    let shift = (0..2047).find(|s| (0..2047).all(|k| c[k] == a[(k + s) % 2047]));
    assert!(shift.is_some());
}

#[test]
fn excitations_have_the_requested_variance() {
    let n = 200_000;
    for (ex, tol) in [
        (Excitation::Prbs, 1e-3),
        (Excitation::Uniform, 0.02),
        (Excitation::Gaussian, 0.02),
        (Excitation::Multilevel, 0.02),
    ] {
        let x = ex.generate(n, 1.0, &mut ChaCha8Rng::seed_from_u64(9)).unwrap();
        let mean = x.iter().sum::<f64>() / n as f64;
        let var = x.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / n as f64;
        assert!((var - 1.0).abs() < tol, "{ex:?}: variance {var}");
        assert!(mean.abs() < 0.02, "{ex:?}: mean {mean}");
    }
    let u = Excitation::Uniform.generate(n, 2.0, &mut ChaCha8Rng::seed_from_u64(1)).unwrap();
    let bound = 2.0 * 3f64.sqrt();
    assert!(u.iter().all(|v| v.abs() <= bound));
    assert!(u.iter().any(|v| v.abs() > 0.99 * bound), "uniform reaches its bounds");
    let m = Excitation::Multilevel.generate(1000, 1.0, &mut ChaCha8Rng::seed_from_u64(1)).unwrap();
    let mut levels: Vec<i64> = m.iter().map(|v| (v * 1e9).round() as i64).collect();
    levels.sort_unstable();
    levels.dedup();
    assert_eq!(levels.len(), 5);
}

#[test]
fn mimo_prbs_dithers_are_distinct_m_sequences() {
    let d = Excitation::Prbs.generate_many(2047, 3, 1.0, &mut ChaCha8Rng::seed_from_u64(5)).unwrap();
    // Each is a full-period m-sequence (balanced: 1024 ones), and no dither is a circular shift
    // of another, nor of a product of two shifts of another (shift-and-add would make it one).
    for x in &d {
        assert_eq!(x.iter().filter(|&&v| v > 0.0).count(), 1024);
    }
    let is_shift_of = |a: &[f64], b: &[f64]| (0..2047).any(|s| (0..2047).all(|k| b[k] == a[(k + s) % 2047]));
    for (i, j) in [(0, 1), (0, 2), (1, 2)] {
        assert!(!is_shift_of(&d[i], &d[j]), "dither {j} is a shift of dither {i}");
        let product: Vec<f64> = (0..2047).map(|k| d[i][k] * d[i][(k + 1) % 2047]).collect();
        assert!(!is_shift_of(&product, &d[j]), "dither {j} is a shift of dither {i}'s shift-and-add product");
    }
    // no pair is correlated at any lag a profile looks at
    for (i, j) in [(0, 1), (0, 2), (1, 2)] {
        for lag in 0..50 {
            let c: f64 = (0..2047 - lag).map(|k| d[i][k] * d[j][k + lag]).sum::<f64>() / (2047 - lag) as f64;
            assert!(c.abs() < 0.1, "dithers {i},{j} correlate {c} at lag {lag}");
        }
    }
    let g = Excitation::Gaussian.generate_many(100, 2, 1.0, &mut ChaCha8Rng::seed_from_u64(5)).unwrap();
    assert_ne!(g[0], g[1]);
}

#[test]
fn alternative_polynomials_have_maximal_period() {
    for order in [5u32, 7, 11] {
        for index in 0..3 {
            let mut l = mpmwatch_sim::Lfsr::with_polynomial(order, index, 1).unwrap();
            let period = (1usize << order) - 1;
            let first = l.state();
            let mut steps = 0;
            loop {
                l.next_bit();
                steps += 1;
                if l.state() == first {
                    break;
                }
            }
            assert_eq!(steps, period, "order {order}, polynomial {index}");
        }
    }
}
