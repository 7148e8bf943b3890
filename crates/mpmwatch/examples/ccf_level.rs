//! The level of the whitened-CCF baseline on the power study's null elements, many times over:
//! the power study's cases (`mpmwatch::power`) for each seed in FIRST..END, prepared by the
//! default analysis (partialling-out, whitening), and only the CCF read. The MI side runs the
//! paper's rule with two surrogates, which the CCF does not use; it is there because the CCF
//! comes out of the same `analyze` call as in the study. Prints the share of null elements whose
//! largest |CCF| over lags 1–20 crosses the Bonferroni limit at 0.05 and 0.01, per noise kind,
//! with Wilson 95 % intervals.
//!
//! With `FAMILY=1` it runs the family rule as the power study does (alpha 0.01, joint embedding,
//! sequential surrogates) on the study's no-mismatch cases only, and reports the family p-values
//! of their null elements beside the CCF on the same elements.
//!
//! `cargo run --release --example ccf_level -- FIRST_SEED END_SEED` (docs/detection.md).

use mpmwatch::power::{Noise, PowerOptions, Rate, cases, generate};
use mpmwatch_core::detect::{LagChoice, MatrixOptions, Method, Signal, analyze};
use mpmwatch_core::info::{Lags, SurrogateOptions, family_wise_z};
use rayon::prelude::*;

fn main() {
    let args: Vec<u64> = std::env::args().skip(1).filter_map(|a| a.parse().ok()).collect();
    let [from, to] = args[..] else {
        eprintln!("usage: ccf_level FIRST_SEED END_SEED (END exclusive)");
        std::process::exit(2);
    };
    let levels = [0.05, 0.01, 0.001];
    let family = std::env::var("FAMILY").is_ok_and(|v| v == "1");
    // (noise kind, largest |CCF|·√n, family p-value) of every null element.
    let mut nulls: Vec<(&'static str, f64, f64)> = Vec::new();
    for seed in from..to {
        let mut opts = PowerOptions { seed, ..PowerOptions::default() };
        if family {
            opts.binary_cases = 0;
            opts.uniform_cases = 0;
        }
        let all = cases(&opts);
        let found: Vec<Vec<(&'static str, f64, f64)>> = all
            .par_iter()
            .map(|case| {
                let (d1, d2, e) = generate(case, opts.n);
                let d = [Signal { name: "d1", values: &d1 }, Signal { name: "d2", values: &d2 }];
                let r = [Signal { name: "e", values: &e }];
                let lags = LagChoice::Fixed(Lags::new(1, opts.max_lag).expect("lags 1..=20"));
                let sur = SurrogateOptions { seed: case.seed, ..SurrogateOptions::default() };
                let mo = if family {
                    MatrixOptions {
                        lags,
                        alpha: opts.alpha,
                        ccf_alpha: opts.alpha,
                        surrogates: sur,
                        ..MatrixOptions::default()
                    }
                } else {
                    MatrixOptions {
                        lags,
                        method: Method::Paper,
                        joint_embedding: false,
                        surrogates: SurrogateOptions { count: 2, ..sur },
                        ..MatrixOptions::default()
                    }
                };
                let m = analyze(&d, &r, &mo).expect("a generated case analyses");
                let kind = match case.noise {
                    Noise::Ar1 { a } if a >= 0.99 => "drift",
                    Noise::Ar1 { .. } => "ar1",
                    Noise::Ar2 { .. } => "ar2",
                };
                let acting = usize::from(case.size > 0.0);
                (acting..2)
                    .map(|mv| {
                        let c = m.cell(mv, 0).expect("both dithers are excited");
                        let max = c.ccf.values.iter().fold(0.0f64, |a, v| a.max(v.abs()));
                        (kind, max * (c.ccf.n as f64).sqrt(), c.decision.p_value)
                    })
                    .collect()
            })
            .collect();
        nulls.extend(found.into_iter().flatten());
        eprintln!("seed {seed}: {} null elements so far", nulls.len());
    }
    let rate = |k: usize, n: usize| {
        let r = Rate::of(k, n);
        format!("{} ({:.2} %, {:.2}–{:.2} %)", r.k, 100.0 * r.value(), 100.0 * r.low, 100.0 * r.high)
    };
    for kind in ["ar1", "ar2", "drift", "all"] {
        let of_kind: Vec<(f64, f64)> =
            nulls.iter().filter(|(k, ..)| kind == "all" || *k == kind).map(|&(_, z, p)| (z, p)).collect();
        let n = of_kind.len();
        let ccf: Vec<String> = levels
            .iter()
            .map(|&a| {
                format!("{a}: {}", rate(of_kind.iter().filter(|(z, _)| *z > family_wise_z(a, 20)).count(), n))
            })
            .collect();
        println!("{kind:>5} ({n} null elements, seeds {from}..{to}) CCF {}", ccf.join("; "));
        if family {
            let fam: Vec<String> = levels
                .iter()
                .map(|&a| format!("p <= {a}: {}", rate(of_kind.iter().filter(|(_, p)| *p <= a).count(), n)))
                .collect();
            println!("{kind:>5} family {}", fam.join("; "));
        }
    }
}
