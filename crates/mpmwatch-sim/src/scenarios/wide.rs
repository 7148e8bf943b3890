//! A wider generator of concealed closed-loop scenarios than the casebook's fixed list: each
//! case draws its plant (gains, poles, dead times, couplings), its PI tuning, its disturbance
//! spectrum (AR(1), resonant or two-pole AR(2), with or without load steps), its dither level,
//! its effect, channel, size and concealment ratio (0.1–0.8). Meant for developing and measuring
//! the diagnosis on cases nobody picked by hand. Pure and seeded.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::Serialize;

use super::{Effect, Fopdt, ScenarioSpec, simulate};
use crate::Excitation;

/// Burn-in of the disturbance filter, dropped before use.
const BURN_IN: usize = 200;

/// A disturbance: `x(t) = a1·x(t−1) + a2·x(t−2) + e(t)` scaled to standard deviation `std`, plus
/// `steps` load steps of standard deviation `step_std` at random times.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct NoiseDraw {
    /// First AR coefficient.
    pub a1: f64,
    /// Second AR coefficient.
    pub a2: f64,
    /// Standard deviation of the AR part.
    pub std: f64,
    /// Number of load steps.
    pub steps: usize,
    /// Standard deviation of each step.
    pub step_std: f64,
}

impl NoiseDraw {
    /// Filters `e` (white, `n + 200` samples) into `n` samples of the disturbance; the step
    /// times and sizes come from `rng`.
    pub fn filter(&self, e: &[f64], rng: &mut impl Rng) -> Vec<f64> {
        let (mut x1, mut x2) = (0.0, 0.0);
        let mut x: Vec<f64> = e
            .iter()
            .map(|w| {
                let x0 = self.a1 * x1 + self.a2 * x2 + w;
                x2 = x1;
                x1 = x0;
                x0
            })
            .skip(BURN_IN)
            .collect();
        let n = x.len();
        let mean = x.iter().sum::<f64>() / n.max(1) as f64;
        let sd = (x.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / n.max(1) as f64).sqrt();
        let g = if sd > 0.0 { self.std / sd } else { 0.0 };
        x.iter_mut().for_each(|v| *v = (*v - mean) * g);
        for _ in 0..self.steps {
            let at = rng.random_range(0..n.max(1));
            let size = self.step_std * gaussian(rng);
            x[at..].iter_mut().for_each(|v| *v += size);
        }
        x
    }

    /// The disturbance of a disturbance-only case: slower (pole 0.98), twice as large, with
    /// three more load steps.
    pub fn slowed(&self) -> Self {
        Self {
            a1: 0.98,
            a2: 0.0,
            std: 2.0 * self.std,
            steps: self.steps + 3,
            step_std: self.step_std.max(self.std),
        }
    }
}

/// Everything [`wide_specs`] draws besides the effect: `channels[output][input]`, a diagonal PI
/// per loop (`pi_gain`, `pi_ti` in samples), the disturbance and the dithers' standard deviation.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PlantDraw {
    /// Plant (and model) channels, `[output][input]`.
    pub channels: Vec<Vec<Fopdt>>,
    /// Proportional gain of each loop's PI.
    pub pi_gain: Vec<f64>,
    /// Integral time of each loop's PI, in samples.
    pub pi_ti: Vec<f64>,
    /// Disturbance on every output (independent draws of the same spectrum).
    pub noise: NoiseDraw,
    /// Standard deviation of every dither.
    pub dither_std: f64,
}

fn gaussian(rng: &mut impl Rng) -> f64 {
    let (u1, u2): (f64, f64) = (rng.random_range(f64::EPSILON..1.0), rng.random());
    (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
}

fn draw_plant(size: usize, rng: &mut impl Rng) -> PlantDraw {
    let channels: Vec<Vec<Fopdt>> = (0..size)
        .map(|j| {
            (0..size)
                .map(|i| {
                    if i == j {
                        Fopdt {
                            k: (rng.random_range(0.5f64.ln()..2.0f64.ln())).exp(),
                            a: rng.random_range(0.6..0.92),
                            d: rng.random_range(0..=3),
                        }
                    } else {
                        let sign = if rng.random::<bool>() { 1.0 } else { -1.0 };
                        Fopdt {
                            k: sign * rng.random_range(0.1..0.5),
                            a: rng.random_range(0.5..0.9),
                            d: rng.random_range(1..=4),
                        }
                    }
                })
                .collect()
        })
        .collect();
    let pi_gain = (0..size).map(|j| rng.random_range(0.15..0.5) / channels[j][j].k).collect();
    let pi_ti = (0..size).map(|j| -1.0 / channels[j][j].a.ln() * rng.random_range(0.7..1.5)).collect();
    let (a1, a2) = match rng.random_range(0..3) {
        0 => (rng.random_range(0.3..0.98), 0.0),
        1 => {
            let (r, th): (f64, f64) = (rng.random_range(0.7..0.95), rng.random_range(0.1..1.0));
            (2.0 * r * th.cos(), -r * r)
        }
        _ => {
            let (p1, p2): (f64, f64) = (rng.random_range(0.5..0.95), rng.random_range(0.0..0.6));
            (p1 + p2, -p1 * p2)
        }
    };
    let std = rng.random_range(0.1..0.5);
    let steps = if rng.random::<f64>() < 0.3 { rng.random_range(1..=3) } else { 0 };
    PlantDraw {
        channels,
        pi_gain,
        pi_ti,
        noise: NoiseDraw { a1, a2, std, steps, step_std: std },
        dither_std: rng.random_range(0.5..1.5),
    }
}

/// Whether the nominal loop (no effect) stays bounded: a drawn PI on a drawn coupled plant can
/// be unstable, and such a draw is redrawn.
fn loop_is_stable(spec: &ScenarioSpec) -> bool {
    let Some(p) = &spec.plant else { return true };
    let probe = ScenarioSpec { effect: Effect::NoChange, ..spec.clone() };
    let n = probe.n;
    let zeros = vec![vec![0.0; n]; probe.size];
    let ones: Vec<Vec<f64>> = (0..probe.size)
        .map(|i| (0..n).map(|k| if (k / 50 + i) % 2 == 0 { p.dither_std } else { -p.dither_std }).collect())
        .collect();
    let rec = simulate(&probe, 0.0, &ones, &zeros);
    let bound = 20.0 * p.dither_std * p.channels.iter().flatten().map(|c| c.k.abs()).sum::<f64>();
    rec.y.iter().chain(rec.u.iter()).flatten().all(|v| v.is_finite() && v.abs() < bound)
}

/// Which way a drawn gain, time-constant or dead-time change goes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Directions {
    /// Up only: a larger gain, a slower response, a longer delay (every study up to stop 78
    /// drew these).
    #[default]
    Up,
    /// Up or down with equal chance: also a gain drop (a fouled exchanger, a worn valve), a
    /// faster response and a delay shorter than the model's. Drawn after everything else, so
    /// every other draw of a seed is the same as under [`Directions::Up`].
    Both,
}

/// `count` scenarios of `n` samples drawn from seed `seed` (case `k` from `seed + k`): every
/// mismatch effect of [`Effect`] and the two null cases equally likely, size 1–3 (2–3 for a
/// missing coupling), binary or uniform dithers, concealment ratio uniform in 0.1–0.8. The
/// linear changes sit on any channel, and go the ways `directions` allows; the effects at the
/// actuator or sensor on a loop's own channel, as in the casebook.
pub fn wide_specs(count: usize, n: usize, seed: u64, directions: Directions) -> Vec<ScenarioSpec> {
    use Effect::*;
    // In this order: the seeds of the studies (docs/diagnose-history.md, docs/status.md) draw by
    // index into it.
    const EFFECTS: [Effect; 15] = [
        Gain,
        TimeConstant,
        DeadTime,
        MissingCoupling,
        DeadZone,
        Saturation,
        Quadratic,
        Cubic,
        CubicOutput,
        Bilinear,
        Backlash,
        CoulombFriction,
        AbsSensor,
        NoChange,
        DisturbanceOnly,
    ];
    (0..count as u64)
        .map(|k| {
            let mut rng = ChaCha8Rng::seed_from_u64(seed.wrapping_add(k).wrapping_mul(0x9E37_79B9_7F4A_7C15));
            let effect = EFFECTS[rng.random_range(0..EFFECTS.len())];
            let size =
                if effect == MissingCoupling { rng.random_range(2..=3) } else { rng.random_range(1..=3) };
            let channel = match effect {
                MissingCoupling => {
                    let i = rng.random_range(0..size);
                    (i, (i + rng.random_range(1..size)) % size)
                }
                Gain | TimeConstant | DeadTime => (rng.random_range(0..size), rng.random_range(0..size)),
                _ => {
                    let i = rng.random_range(0..size);
                    (i, i)
                }
            };
            let excitation = if rng.random::<bool>() { Excitation::Prbs } else { Excitation::Uniform };
            let target_ratio = if effect.is_mismatch() { rng.random_range(0.1..0.8) } else { 0.0 };
            let mut spec = ScenarioSpec {
                name: format!("w{:04}_{}_{size}x{size}", seed.wrapping_add(k), effect_name(effect)),
                effect,
                size,
                channel,
                excitation,
                n,
                seed: seed.wrapping_add(k),
                target_ratio,
                plant: None,
                decrease: false,
            };
            for _ in 0..50 {
                spec.plant = Some(draw_plant(size, &mut rng));
                if loop_is_stable(&spec) {
                    break;
                }
            }
            if directions == Directions::Both && matches!(effect, Gain | TimeConstant | DeadTime) {
                spec.decrease = rng.random::<bool>();
            }
            spec
        })
        .collect()
}

fn effect_name(e: Effect) -> String {
    serde_json::to_value(e).ok().and_then(|v| v.as_str().map(str::to_string)).unwrap_or_default()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn draws_are_seeded_and_stable() {
        let a = wide_specs(30, 600, 7, Directions::Up);
        assert_eq!(a, wide_specs(30, 600, 7, Directions::Up));
        assert_ne!(a, wide_specs(30, 600, 8, Directions::Up));
        for s in &a {
            assert!(loop_is_stable(s), "{} drawn unstable", s.name);
            if s.effect == Effect::MissingCoupling {
                assert_ne!(s.channel.0, s.channel.1, "{}", s.name);
            }
            assert!(s.effect.is_mismatch() == (s.target_ratio > 0.0), "{}", s.name);
        }
    }

    /// Both ways changes only the direction of gain, time-constant and dead-time changes, and
    /// draws each way: over 200 draws (about 40 such changes, each down with chance ½) the
    /// chance that all go one way is below 10⁻¹¹.
    #[test]
    fn both_ways_draws_drops_and_leaves_the_rest_of_each_draw_alone() {
        let up = wide_specs(200, 600, 11, Directions::Up);
        let both = wide_specs(200, 600, 11, Directions::Both);
        let mut downs = [0, 0];
        for (u, b) in up.iter().zip(&both) {
            assert_eq!(*u, ScenarioSpec { decrease: false, ..b.clone() }, "{}", u.name);
            assert!(!u.decrease);
            if matches!(b.effect, Effect::Gain | Effect::TimeConstant | Effect::DeadTime) {
                downs[usize::from(b.decrease)] += 1;
            } else {
                assert!(!b.decrease, "{}", b.name);
            }
        }
        assert!(downs[0] > 0 && downs[1] > 0, "up/down {downs:?}");
    }

    /// A drawn gain drop is simulated as one: on a 1×1 plant the true output driven by the
    /// recorded MV is the nominal's times `1 − strength` (same pole, same dead time, zero start),
    /// to rounding.
    #[test]
    fn a_gain_drop_is_simulated_as_a_drop() {
        let both = wide_specs(600, 600, 11, Directions::Both);
        let drop = both
            .iter()
            .find(|s| s.effect == Effect::Gain && s.decrease && s.size == 1)
            .expect("a 1×1 drop among 600 draws");
        let rec = super::super::run(drop).expect("a case");
        let t = rec.strength;
        assert!(t > 0.0 && t < 1.0, "strength {t}");
        assert!(drop.describe(t).starts_with("gain ×0."), "{}", drop.describe(t));
        for (p, s) in rec.plant_output[0].iter().zip(&rec.s[0]) {
            assert!((p - (1.0 - t) * s).abs() <= 1e-9 * (1.0 + s.abs()), "{p} against {}", (1.0 - t) * s);
        }
    }

    /// A drawn shorter delay is the model's longer one: on a 1×1 plant the nominal driven by
    /// the recorded MV is the true output shifted late by the strength's samples, exactly.
    #[test]
    fn a_shorter_delay_is_the_models_longer_one() {
        let both = wide_specs(600, 600, 11, Directions::Both);
        let spec = both
            .iter()
            .find(|s| s.effect == Effect::DeadTime && s.decrease && s.size == 1)
            .expect("a 1×1 shorter delay among 600 draws");
        let rec = super::super::run(spec).expect("a case");
        let t = rec.strength as usize;
        assert!((1..=6).contains(&t), "strength {}", rec.strength);
        assert_eq!(spec.describe(rec.strength), format!("−{t} samples dead time"));
        let (p, s) = (&rec.plant_output[0], &rec.s[0]);
        assert!(s[..t].iter().all(|v| *v == 0.0), "the nominal starts {t} samples later");
        for k in t..p.len() {
            assert!((s[k] - p[k - t]).abs() <= 1e-12 * (1.0 + p[k - t].abs()), "row {k}");
        }
    }

    #[test]
    fn the_disturbance_has_the_drawn_std_and_spectrum() {
        let noise = NoiseDraw { a1: 0.8, a2: 0.0, std: 0.3, steps: 0, step_std: 0.0 };
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let e: Vec<f64> = (0..20_200).map(|_| gaussian(&mut rng)).collect();
        let x = noise.filter(&e, &mut rng);
        let var = x.iter().map(|v| v * v).sum::<f64>() / x.len() as f64;
        assert!((var.sqrt() - 0.3).abs() < 1e-9, "scaled to the std exactly: {}", var.sqrt());
        // Lag-1 autocorrelation of an AR(1) is its pole; its standard error at N = 20 000 is
        // about √((1 − 0.64)/20 000) ≈ 0.004, so 0.02 is five of them.
        let r1 = x.windows(2).map(|w| w[0] * w[1]).sum::<f64>() / x.len() as f64 / var;
        assert!((r1 - 0.8).abs() < 0.02, "lag-1 autocorrelation {r1}");
    }
}
