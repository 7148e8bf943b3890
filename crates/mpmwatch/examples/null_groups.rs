//! False alarms of the family rule where many elements share surrogates: null 20×5 matrices
//! (20 binary dithers of one design, so each residual's 20 elements form one pooled group, against
//! 5 coloured residuals), the default analysis at `ALPHA` (default 0.01). Seed s draws matrix s.
//! With `BIAS=b`, half of the dithers are +1 with probability ½ + b and half with ½ − b (i.i.d.),
//! to check designs that differ by up to the pooling tolerance.
//!
//! `cargo run --release --example null_groups -- FIRST_SEED END_SEED` (docs/detection.md).

use mpmwatch_core::detect::{MatrixOptions, Signal, analyze};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;

fn main() {
    let args: Vec<u64> = std::env::args().skip(1).filter_map(|a| a.parse().ok()).collect();
    let [from, to] = args[..] else {
        eprintln!("usage: null_groups FIRST_SEED END_SEED (END exclusive)");
        std::process::exit(2);
    };
    let env =
        |name: &str, default: f64| std::env::var(name).ok().and_then(|v| v.parse().ok()).unwrap_or(default);
    let (alpha, bias) = (env("ALPHA", 0.01), env("BIAS", 0.0));
    let n = 2048;
    let (mut elements, mut flagged, mut below_05, mut largest_group) = (0, 0, 0, 0);
    for seed in from..to {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let switch: f64 = rng.random_range(0.2..0.6);
        let dithers: Vec<Vec<f64>> = (0..20)
            .map(|i| {
                if bias > 0.0 {
                    let q = if i % 2 == 0 { 0.5 + bias } else { 0.5 - bias };
                    return (0..n).map(|_| if rng.random::<f64>() < q { 1.0 } else { -1.0 }).collect();
                }
                let mut v = 1.0;
                (0..n)
                    .map(|_| {
                        if rng.random::<f64>() < switch {
                            v = -v;
                        }
                        v
                    })
                    .collect()
            })
            .collect();
        let residuals: Vec<Vec<f64>> = (0..5)
            .map(|_| {
                let kind = rng.random_range(0..3);
                let a = rng.random_range(-0.5..0.95);
                let mut y = vec![0.0f64; n];
                for t in 2..n {
                    let e: f64 = rng.sample(StandardNormal);
                    y[t] = e + match kind {
                        0 => a * y[t - 1],
                        1 => 1.6 * y[t - 1] - 0.8 * y[t - 2],
                        _ => 0.99 * y[t - 1],
                    };
                }
                y
            })
            .collect();
        let dn: Vec<String> = (0..20).map(|i| format!("d{i}")).collect();
        let rn: Vec<String> = (0..5).map(|i| format!("e{i}")).collect();
        let d: Vec<Signal> = dithers.iter().zip(&dn).map(|(v, name)| Signal { name, values: v }).collect();
        let r: Vec<Signal> = residuals.iter().zip(&rn).map(|(v, name)| Signal { name, values: v }).collect();
        let m = match analyze(&d, &r, &MatrixOptions { alpha, ..MatrixOptions::default() }) {
            Ok(m) => m,
            Err(e) => {
                eprintln!("seed {seed}: {e}");
                std::process::exit(1);
            }
        };
        let f = m.cells.iter().filter(|c| c.significant).count();
        let group = m.cells.iter().filter_map(|c| c.family.as_ref().map(|t| t.pooled)).max().unwrap_or(1);
        eprintln!("seed {seed}: {f} flagged, largest group {group}");
        elements += m.cells.len();
        flagged += f;
        below_05 += m.cells.iter().filter(|c| c.decision.p_value <= 0.05).count();
        largest_group = largest_group.max(group);
    }
    let pct = |k: usize| 100.0 * k as f64 / elements as f64;
    println!(
        "{elements} null elements (seeds {from}..{to}, alpha {alpha}, bias {bias}, largest group {largest_group}): \
         {flagged} flagged ({:.2} %), {below_05} with p <= 0.05 ({:.2} %)",
        pct(flagged),
        pct(below_05)
    );
}
