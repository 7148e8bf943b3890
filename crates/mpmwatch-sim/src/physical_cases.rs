//! Open-loop physical cases for the diagnosis: a plant with one piece of physics (a cubic
//! spring, Coulomb friction, a heater driven through V², a clipping sensor, a diode between two
//! filters, an overflowing tank, an actuator dead zone, a transport delay) or none (a linear
//! plant), recorded with coloured measurement noise, and the nominal a user would bring: an
//! ARX model fitted by least squares on the record, simulated from the recorded input.
//!
//! Every parameter is drawn from wide ranges by the seed (time scales, strengths, input
//! signals, noise spectrum and level), so that a diagnosis developed on some seeds can be
//! measured on others. Pure and seeded.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use serde::Serialize;

use mpmwatch_core::model::{Arx, ArxOrders};

use super::SimError;

/// The physics of a case.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum PhysicalCase {
    /// Linear second-order plant: nothing is left out.
    Linear,
    /// A mass on a hardening spring (Duffing): `ẍ + 2ζω ẋ + ω² x + k₃ x³ = b u`.
    Duffing,
    /// A mass pushed against viscous and Coulomb friction; the output is its velocity.
    FrictionMass,
    /// A heater driven by a voltage: power goes with V², the temperature lags it.
    HeaterVoltage,
    /// A linear plant read through a sensor that clips above a level (a Wiener system).
    ClippingSensor,
    /// A diode-like soft limit between two linear filters (a Wiener–Hammerstein circuit).
    DiodeCircuit,
    /// Two tanks in cascade (Torricelli outflow); the upper one overflows at its rim.
    TankOverflow,
    /// An actuator that does not move for small commands.
    ActuatorDeadZone,
    /// A transport delay longer than the one the user's model assumes.
    TransportDelay,
}

impl PhysicalCase {
    /// Every case.
    pub const ALL: [PhysicalCase; 9] = [
        PhysicalCase::Linear,
        PhysicalCase::Duffing,
        PhysicalCase::FrictionMass,
        PhysicalCase::HeaterVoltage,
        PhysicalCase::ClippingSensor,
        PhysicalCase::DiodeCircuit,
        PhysicalCase::TankOverflow,
        PhysicalCase::ActuatorDeadZone,
        PhysicalCase::TransportDelay,
    ];

    /// The case's name.
    pub fn name(self) -> &'static str {
        match self {
            PhysicalCase::Linear => "linear",
            PhysicalCase::Duffing => "duffing",
            PhysicalCase::FrictionMass => "friction_mass",
            PhysicalCase::HeaterVoltage => "heater_voltage",
            PhysicalCase::ClippingSensor => "clipping_sensor",
            PhysicalCase::DiodeCircuit => "diode_circuit",
            PhysicalCase::TankOverflow => "tank_overflow",
            PhysicalCase::ActuatorDeadZone => "actuator_dead_zone",
            PhysicalCase::TransportDelay => "transport_delay",
        }
    }

    /// The diagnosis vocabulary names that describe the physics correctly (empty: no nonlinear
    /// physics is there, so a right answer is no finding or a linear change).
    ///
    /// A soft compression between two filters is named correctly as a saturation or as an odd
    /// polynomial: the vocabulary has no class for a map between two linear blocks.
    pub fn accepted(self) -> &'static [&'static str] {
        match self {
            PhysicalCase::Linear => &[],
            PhysicalCase::Duffing => &["cubic"],
            PhysicalCase::FrictionMass => &["coulomb_friction"],
            PhysicalCase::HeaterVoltage => &["quadratic"],
            PhysicalCase::ClippingSensor => &["saturation"],
            PhysicalCase::DiodeCircuit => &["saturation", "cubic"],
            PhysicalCase::TankOverflow => &["saturation"],
            PhysicalCase::ActuatorDeadZone => &["dead_zone"],
            PhysicalCase::TransportDelay => &["dead_time"],
        }
    }

    /// Whether the plant is linear (the left-out physics, if any, is a linear change).
    pub fn is_linear(self) -> bool {
        matches!(self, PhysicalCase::Linear | PhysicalCase::TransportDelay)
    }
}

/// A recorded open-loop case with the user's nominal simulation.
#[derive(Debug, Clone, PartialEq)]
pub struct PhysicalRecord {
    /// The case.
    pub case: PhysicalCase,
    /// Seed of every draw.
    pub seed: u64,
    /// Input.
    pub u: Vec<f64>,
    /// Recorded output (plant plus measurement noise).
    pub y: Vec<f64>,
    /// The plant's own output, noise-free: the simulation of an exact model (a no-change case).
    pub plant: Vec<f64>,
    /// The nominal ARX model's simulation from `u` (least squares on the whole record).
    pub s: Vec<f64>,
    /// The drawn parameters, in words.
    pub description: String,
    /// Share of the noise in the recorded output's variance.
    pub noise_share: f64,
    /// Where the plant's kink acts, per sample of the plant's own time (the rows of `plant`),
    /// for the classes with one (the tank at its rim, the sensor clipping, the input the plant
    /// receives inside the dead zone, the mass stuck); `None` for the smooth nonlinearities,
    /// the delay and the linear plant. A study reads it to tell a miss the record could not
    /// show (the kink never reached on the training rows) from one it could.
    pub acting: Option<Vec<bool>>,
}

/// The nominal's structure: `A(q)y = B(q)u(t − 1) + c` with two poles and two numerator
/// coefficients, what a user fits first (`arx(data, [2 2 1])`).
pub const NOMINAL_ORDERS: (usize, usize, usize) = (2, 2, 1);

fn uniform(rng: &mut ChaCha8Rng, lo: f64, hi: f64) -> f64 {
    lo + (hi - lo) * rng.random::<f64>()
}

/// The input signal a case is recorded under.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Signal {
    /// The generator's own: a staircase of uniform levels held for about the plant's settling
    /// time, or (one seed in three) low-pass filtered Gaussian noise.
    #[default]
    Drawn,
    /// A random-phase multisine: 40 sines of equal amplitude at frequencies spread evenly from
    /// one period per record up to the staircase's shortest hold, the kind of signal the
    /// nonlinear benchmarks record with (theirs are periodic; this one's frequencies are not on
    /// the record's DFT bins).
    Multisine,
    /// The staircase held a quarter as long (a quarter of the shortest hold up to the shortest),
    /// an experiment that moves faster than the plant settles.
    FastSteps,
}

/// A staircase of uniform levels in `[lo, hi]` held for `hold.0..hold.1` samples, or (one seed
/// in three) Gaussian noise low-pass filtered with a time constant of `hold.0` samples, scaled
/// to the same range; other signals by `signal` ([`Signal`]).
fn input(rng: &mut ChaCha8Rng, n: usize, lo: f64, hi: f64, hold: (usize, usize), signal: Signal) -> Vec<f64> {
    let (mid, half) = ((lo + hi) / 2.0, (hi - lo) / 2.0);
    let hold = match signal {
        Signal::Multisine => {
            let top = 1.0 / hold.0.max(2) as f64;
            let lines = 40;
            let phases: Vec<f64> = (0..lines).map(|_| std::f64::consts::TAU * rng.random::<f64>()).collect();
            let raw: Vec<f64> = (0..n)
                .map(|t| {
                    (0..lines)
                        .map(|k| {
                            let f = 1.0 / n as f64 + (top - 1.0 / n as f64) * k as f64 / (lines - 1) as f64;
                            (std::f64::consts::TAU * f * t as f64 + phases[k]).sin()
                        })
                        .sum::<f64>()
                })
                .collect();
            // Scaled as the filtered noise is: 1.8 standard deviations to the range's edge.
            let sd = var(&raw).sqrt().max(f64::MIN_POSITIVE);
            return raw.iter().map(|v| (mid + half * v / (1.8 * sd)).clamp(lo, hi)).collect();
        }
        Signal::FastSteps => ((hold.0 / 4).max(1), hold.0.max(1)),
        Signal::Drawn => hold,
    };
    if signal == Signal::Drawn && rng.random::<f64>() < 1.0 / 3.0 {
        let a = (-1.0 / hold.0.max(1) as f64).exp();
        let mut x = 0.0;
        let raw: Vec<f64> = (0..n)
            .map(|_| {
                let w: f64 = StandardNormal.sample(rng);
                x = a * x + (1.0 - a * a).sqrt() * w;
                x
            })
            .collect();
        return raw.iter().map(|v| (mid + half * v / 1.8).clamp(lo, hi)).collect();
    }
    let mut u = Vec::with_capacity(n);
    while u.len() < n {
        let level = uniform(rng, lo, hi);
        let len = rng.random_range(hold.0..=hold.1.max(hold.0));
        u.extend(std::iter::repeat_n(level, len));
    }
    u.truncate(n);
    u
}

fn var(x: &[f64]) -> f64 {
    let m = x.iter().sum::<f64>() / x.len().max(1) as f64;
    x.iter().map(|v| (v - m).powi(2)).sum::<f64>() / x.len().max(1) as f64
}

/// A second-order mass–spring–damper stepped `sub` times per sample (semi-implicit Euler), with
/// an extra force `extra(x, v)`; returns position and velocity at each sample.
fn oscillator(
    u: &[f64],
    omega: f64,
    zeta: f64,
    sub: usize,
    extra: impl Fn(f64, f64) -> f64,
) -> (Vec<f64>, Vec<f64>) {
    let h = 1.0 / sub as f64;
    let (mut x, mut v) = (0.0, 0.0);
    let mut xs = Vec::with_capacity(u.len());
    let mut vs = Vec::with_capacity(u.len());
    for &uk in u {
        xs.push(x);
        vs.push(v);
        for _ in 0..sub {
            let a = omega * omega * uk - 2.0 * zeta * omega * v - omega * omega * x + extra(x, v);
            v += h * a;
            x += h * v;
        }
    }
    (xs, vs)
}

/// First-order lag `x(t) = a x(t−1) + (1 − a) w(t−1)` from rest at `w(0)`.
fn lag(w: &[f64], a: f64) -> Vec<f64> {
    let mut x = w.first().copied().unwrap_or(0.0);
    w.iter()
        .map(|&wk| {
            let out = x;
            x = a * x + (1.0 - a) * wk;
            out
        })
        .collect()
}

/// Simulates one case of `n` samples from `seed`.
pub fn run(case: PhysicalCase, n: usize, seed: u64) -> Result<PhysicalRecord, SimError> {
    run_with(case, n, seed, Signal::Drawn)
}

/// [`run`] under another input signal ([`Signal`]), for studies of how the diagnosis fares on
/// experiments other than the generator's own. The plant's dynamics, drawn before the input,
/// are the seed's own under every signal; what is drawn after it (the nonlinearity's size, the
/// clip and rim quantiles, the noise) takes other values from the same ranges.
pub fn run_with(case: PhysicalCase, n: usize, seed: u64, signal: Signal) -> Result<PhysicalRecord, SimError> {
    if n < 500 {
        return Err(SimError::parameter("physical case length", n, "at least 500 samples"));
    }
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ (case as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15));
    let mut acting = None;
    let (u, x, description) = match case {
        PhysicalCase::Linear => {
            let (omega, zeta) = (uniform(&mut rng, 0.05, 0.4), uniform(&mut rng, 0.3, 1.5));
            let hold = (3.0 / omega) as usize;
            let u = input(&mut rng, n, -1.0, 1.0, (hold, 4 * hold), signal);
            let (x, _) = oscillator(&u, omega, zeta, 8, |_, _| 0.0);
            (u, x, format!("ω {omega:.3} rad/sample, ζ {zeta:.2}"))
        }
        PhysicalCase::Duffing => {
            let (omega, zeta) = (uniform(&mut rng, 0.05, 0.3), uniform(&mut rng, 0.05, 0.4));
            let hold = (2.0 / omega) as usize;
            let amp = uniform(&mut rng, 0.5, 2.0);
            let u = input(&mut rng, n, -amp, amp, (hold, 4 * hold), signal);
            // The cubic force at the typical excursion `amp` is `share` of the linear one.
            let share = uniform(&mut rng, 0.15, 0.8);
            let k3 = share / (amp * amp);
            let (x, _) = oscillator(&u, omega, zeta, 8, |x, _| -omega * omega * k3 * x.powi(3));
            (
                u,
                x,
                format!(
                    "ω {omega:.3}, ζ {zeta:.2}, cubic force {share:.2} of the linear at the input's amplitude"
                ),
            )
        }
        PhysicalCase::FrictionMass => {
            let a = uniform(&mut rng, 0.8, 0.97);
            let amp = uniform(&mut rng, 0.5, 2.0);
            let hold = (3.0 / (1.0 - a)) as usize;
            let u = input(&mut rng, n, -amp, amp, (hold / 2 + 1, 2 * hold), signal);
            let fc = uniform(&mut rng, 0.1, 0.45) * amp;
            // Velocity of a mass under viscous drag, v(t+1) = a v + (1 − a)(u − Fc sign v),
            // with sticking: a mass at rest stays there while |u| ≤ Fc, and a mass whose
            // velocity would change sign under such a force stops.
            let mut v = 0.0f64;
            let x: Vec<f64> = u
                .iter()
                .map(|&uk| {
                    let out = v;
                    let direction = if v != 0.0 { v.signum() } else { uk.signum() };
                    v = if v == 0.0 && uk.abs() <= fc {
                        0.0
                    } else {
                        let next = a * v + (1.0 - a) * (uk - fc * direction);
                        if next.signum() != direction && uk.abs() <= fc { 0.0 } else { next }
                    };
                    out
                })
                .collect();
            acting = Some(x.iter().map(|&v| v == 0.0).collect());
            (u, x, format!("pole {a:.3}, Coulomb force {:.2} of the input amplitude", fc / amp))
        }
        PhysicalCase::HeaterVoltage => {
            let a = uniform(&mut rng, 0.9, 0.99);
            let hold = (2.0 / (1.0 - a)) as usize;
            let vmax = uniform(&mut rng, 5.0, 12.0);
            let vmin = uniform(&mut rng, 0.0, 0.5) * vmax;
            let u = input(&mut rng, n, vmin, vmax, (hold / 2 + 1, 2 * hold), signal);
            let k = uniform(&mut rng, 0.2, 1.0);
            let sensor = uniform(&mut rng, 0.0, 0.8);
            let p: Vec<f64> = u.iter().map(|v| k * v * v).collect();
            let x = lag(&lag(&p, a), sensor);
            (u, x, format!("V in [{vmin:.1}, {vmax:.1}], pole {a:.3}, sensor pole {sensor:.2}"))
        }
        PhysicalCase::ClippingSensor => {
            let (omega, zeta) = (uniform(&mut rng, 0.05, 0.4), uniform(&mut rng, 0.5, 1.5));
            let hold = (3.0 / omega) as usize;
            let u = input(&mut rng, n, -1.0, 1.0, (hold, 4 * hold), signal);
            let (x, _) = oscillator(&u, omega, zeta, 8, |_, _| 0.0);
            let mut sorted = x.clone();
            sorted.sort_by(f64::total_cmp);
            let q = uniform(&mut rng, 0.6, 0.85);
            let hi = sorted[(q * (n - 1) as f64) as usize];
            acting = Some(x.iter().map(|&v| v >= hi).collect());
            (
                u,
                x.iter().map(|v| v.min(hi)).collect(),
                format!("ω {omega:.3}, ζ {zeta:.2}, sensor clips above its {:.0} % quantile", 100.0 * q),
            )
        }
        PhysicalCase::DiodeCircuit => {
            let (a1, a2) = (uniform(&mut rng, 0.5, 0.95), uniform(&mut rng, 0.3, 0.9));
            let hold = (3.0 / (1.0 - a1)) as usize;
            let u = input(&mut rng, n, -1.0, 1.0, (hold / 2 + 1, 2 * hold), signal);
            let w = lag(&u, a1);
            let sd = var(&w).sqrt();
            let c = uniform(&mut rng, 0.6, 1.8) * sd;
            let z: Vec<f64> = w.iter().map(|v| c * (v / c).tanh()).collect();
            (u, lag(&z, a2), format!("poles {a1:.2} and {a2:.2}, tanh limit {:.2} input std", c / sd))
        }
        PhysicalCase::TankOverflow => {
            let (k1, k2) = (uniform(&mut rng, 0.02, 0.06), uniform(&mut rng, 0.02, 0.06));
            let pump = uniform(&mut rng, 0.03, 0.08);
            let hold = (1.5 / k1.min(k2)) as usize;
            let u = input(&mut rng, n, 1.0, 10.0, (hold / 2 + 1, 2 * hold), signal);
            // Levels without a rim, to set the rim below the upper tank's high levels.
            let run_tanks = |rim: f64| -> (Vec<f64>, Vec<f64>) {
                let (mut h1, mut h2) = ((pump * 5.0 / k1).powi(2), (pump * 5.0 / k2).powi(2));
                let mut out = Vec::with_capacity(n);
                let mut upper = Vec::with_capacity(n);
                for &uk in &u {
                    out.push(h2);
                    upper.push(h1);
                    for _ in 0..4 {
                        let q1 = k1 * h1.max(0.0).sqrt();
                        h1 = (h1 + 0.25 * (pump * uk - q1)).clamp(0.0, rim);
                        h2 = (h2 + 0.25 * (q1 - k2 * h2.max(0.0).sqrt())).max(0.0);
                    }
                }
                (out, upper)
            };
            let (_, upper) = run_tanks(f64::INFINITY);
            let mut sorted = upper.clone();
            sorted.sort_by(f64::total_cmp);
            let q = uniform(&mut rng, 0.7, 0.9);
            let rim = sorted[(q * (n - 1) as f64) as usize];
            let (x, upper) = run_tanks(rim);
            acting = Some(upper.iter().map(|&h| h >= rim).collect());
            (
                u,
                x,
                format!(
                    "outflows {k1:.4}, {k2:.4}, pump {pump:.4}, rim at the upper level's {:.0} % quantile ({rim:.3})",
                    100.0 * q
                ),
            )
        }
        PhysicalCase::ActuatorDeadZone => {
            let (omega, zeta) = (uniform(&mut rng, 0.05, 0.4), uniform(&mut rng, 0.5, 1.5));
            let hold = (3.0 / omega) as usize;
            let u = input(&mut rng, n, -1.0, 1.0, (hold, 4 * hold), signal);
            let w = uniform(&mut rng, 0.1, 0.45);
            let dz: Vec<f64> = u.iter().map(|v| v.signum() * (v.abs() - w).max(0.0)).collect();
            acting = Some(u.iter().map(|v| v.abs() <= w).collect());
            let (x, _) = oscillator(&dz, omega, zeta, 8, |_, _| 0.0);
            (u, x, format!("ω {omega:.3}, ζ {zeta:.2}, dead zone ±{w:.2} of a ±1 input"))
        }
        PhysicalCase::TransportDelay => {
            let a = uniform(&mut rng, 0.6, 0.95);
            let d = rng.random_range(3..=12usize);
            let hold = (2.0 / (1.0 - a)) as usize + d;
            let u = input(&mut rng, n, -1.0, 1.0, (hold / 2 + 1, 2 * hold), signal);
            let delayed: Vec<f64> = (0..n).map(|t| u[t.saturating_sub(d)]).collect();
            (u, lag(&delayed, a), format!("pole {a:.2}, transport delay {d} samples"))
        }
    };
    // Coloured measurement noise: AR(1) with a drawn pole, its variance a drawn share of the
    // plant output's.
    let pole = uniform(&mut rng, 0.0, 0.95);
    let share = uniform(&mut rng, 0.02, 0.15);
    let sd = (share * var(&x)).sqrt();
    let mut e = 0.0;
    let noise: Vec<f64> = (0..n)
        .map(|_| {
            let w: f64 = StandardNormal.sample(&mut rng);
            e = pole * e + (1.0 - pole * pole).sqrt() * w;
            sd * e
        })
        .collect();
    let y: Vec<f64> = x.iter().zip(&noise).map(|(a, b)| a + b).collect();
    if y.iter().any(|v| !v.is_finite()) {
        return Err(SimError::parameter("physical case seed", seed, "the plant diverged"));
    }
    let s = nominal_simulation(&u, &y)?;
    Ok(PhysicalRecord {
        case,
        seed,
        u,
        y,
        plant: x,
        s,
        description: format!(
            "{description}; noise AR(1) pole {pole:.2}, {:.0} % of the variance",
            100.0 * share
        ),
        noise_share: share,
        acting,
    })
}

/// The user's nominal: an ARX model of [`NOMINAL_ORDERS`] fitted by least squares on the whole
/// record, simulated from the recorded input in steady state at its first sample.
pub fn nominal_simulation(u: &[f64], y: &[f64]) -> Result<Vec<f64>, SimError> {
    nominal_simulation_of(u, y, NOMINAL_ORDERS)
}

/// [`nominal_simulation`] with other ARX orders `(na, nb, nk)`: a user who fits another model
/// first (a first-order lag, a higher order), for studies of how the diagnosis fares when the
/// nominal is not the one it was developed against.
pub fn nominal_simulation_of(
    u: &[f64],
    y: &[f64],
    orders: (usize, usize, usize),
) -> Result<Vec<f64>, SimError> {
    nominal_simulation_on(&[u], y, orders, &[u])
}

/// [`nominal_simulation_of`] fitted on one record (inputs `u_fit`, output `y_fit`) and simulated
/// on other inputs `u`, from rest at their first sample: a nominal identified on an earlier
/// experiment (a commissioning record) and run over a later one, as a user runs a model over a
/// new record. Several inputs make one MISO ARX (one denominator, a numerator and the dead time
/// `nk` per input), as `arx` fits a multi-input record. An ARX without a steady state (an
/// integrator) starts at the fit record's first output.
pub fn nominal_simulation_on(
    u_fit: &[&[f64]],
    y_fit: &[f64],
    (na, nb, nk): (usize, usize, usize),
    u: &[&[f64]],
) -> Result<Vec<f64>, SimError> {
    let orders = ArxOrders { na, nb, delays: vec![nk; u_fit.len()] };
    let arx = Arx::fit(y_fit, u_fit, &orders, 0..y_fit.len())
        .ok_or_else(|| SimError::parameter("nominal ARX fit", y_fit.len(), "least squares failed"))?;
    let first: Vec<f64> = u.iter().map(|x| x.first().copied().unwrap_or(f64::NAN)).collect();
    let y0 = arx.rest_output(&first);
    let s = arx
        .simulate_from(u, if y0.is_finite() { y0 } else { y_fit[0] })
        .map_err(|e| SimError::parameter("nominal ARX simulation", 0, &e.to_string()))?;
    if s.iter().any(|v| !v.is_finite() || v.abs() > 1e6 * (1.0 + var(y_fit).sqrt())) {
        return Err(SimError::parameter("nominal ARX simulation", 0, "the fitted model is unstable"));
    }
    Ok(s)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The orders reach the fit: a noise-free first-order lag with two samples of dead time,
    /// `y(t) = 0.9 y(t−1) + 0.1 u(t−2)`, started at rest at its first input as the nominal's
    /// simulation is, is reproduced exactly by an ARX [1 1 2] (to the least-squares solve's
    /// rounding; 1e-9 of a unit step) and not by an ARX [1 1 1], which has no way to wait the
    /// second sample.
    #[test]
    fn the_nominal_takes_the_orders_it_is_given() {
        let n = 600;
        let u: Vec<f64> = (0..n).map(|t| if (t / 25) % 2 == 0 { 1.0 } else { -1.0 }).collect();
        let mut y = vec![u[0]; n];
        for t in 2..n {
            y[t] = 0.9 * y[t - 1] + 0.1 * u[t - 2];
        }
        let err = |s: &[f64]| s.iter().zip(&y).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
        assert!(err(&nominal_simulation_of(&u, &y, (1, 1, 2)).unwrap()) < 1e-9);
        assert!(err(&nominal_simulation_of(&u, &y, (1, 1, 1)).unwrap()) > 1e-3);
        // Fitted on the first half and run over the second from rest at its first input: the
        // same plant, so the same response as the plant started there at rest.
        let (u2, y2) = (&u[300..], &y[300..]);
        let s2 = nominal_simulation_on(&[&u[..300]], &y[..300], (1, 1, 2), &[u2]).unwrap();
        let mut at_rest = vec![u2[0]; 300];
        for t in 2..300 {
            at_rest[t] = 0.9 * at_rest[t - 1] + 0.1 * u2[t - 2];
        }
        let gap = s2.iter().zip(&at_rest).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
        assert!(gap < 1e-9, "{gap}");
        // The plant itself ran on from the first half: its second half differs at the start.
        assert!((y2[0] - at_rest[0]).abs() > 1e-3 || (y2[1] - at_rest[1]).abs() > 1e-3);
    }

    /// Two inputs make one MISO ARX: a noise-free `y(t) = 0.8 y(t−1) + 0.3 u1(t−1) − 0.1 u2(t−1)`
    /// started at rest is reproduced by an ARX [1 1 1] on both inputs (to the solve's rounding,
    /// 1e-9 of a unit step), and not by one that leaves the second input out.
    #[test]
    fn two_inputs_make_one_miso_arx() {
        let n = 800;
        let u1: Vec<f64> = (0..n).map(|t| if (t / 23) % 2 == 0 { 1.0 } else { -1.0 }).collect();
        let u2: Vec<f64> = (0..n).map(|t| if (t / 37) % 3 == 0 { 2.0 } else { 0.5 }).collect();
        let mut y = vec![(0.3 * u1[0] - 0.1 * u2[0]) / 0.2; n];
        for t in 1..n {
            y[t] = 0.8 * y[t - 1] + 0.3 * u1[t - 1] - 0.1 * u2[t - 1];
        }
        let err = |s: &[f64]| s.iter().zip(&y).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
        let both = nominal_simulation_on(&[&u1, &u2], &y, (1, 1, 1), &[&u1, &u2]).unwrap();
        assert!(err(&both) < 1e-9, "{}", err(&both));
        assert!(err(&nominal_simulation_of(&u1, &y, (1, 1, 1)).unwrap()) > 1e-3);
    }

    /// Every case runs on a few seeds, its nominal is finite, and the nominal of the linear
    /// case fits its noise-free part well (an ARX [2 2 1] of a sampled second-order plant is
    /// close to exact; the noise is at most 15 % of the variance, so the simulation's FIT
    /// against the recorded output stays above 50 %).
    #[test]
    fn every_case_runs_and_the_linear_nominal_fits() {
        for case in PhysicalCase::ALL {
            for seed in 1..=3 {
                let r = run(case, 1500, seed).unwrap();
                assert_eq!(r.u.len(), 1500);
                assert!(r.s.iter().all(|v| v.is_finite()), "{case:?} {seed}");
                assert!(var(&r.y) > 0.0, "{case:?} {seed}");
            }
        }
        for seed in 1..=3 {
            let r = run(PhysicalCase::Linear, 1500, seed).unwrap();
            let m = r.y.iter().sum::<f64>() / 1500.0;
            let num: f64 = r.y.iter().zip(&r.s).map(|(a, b)| (a - b).powi(2)).sum::<f64>().sqrt();
            let den: f64 = r.y.iter().map(|a| (a - m).powi(2)).sum::<f64>().sqrt();
            assert!(1.0 - num / den > 0.5, "seed {seed}: FIT {}", 100.0 * (1.0 - num / den));
        }
    }

    /// Every case runs under the other signals with an input that moves inside the envelope of
    /// the cases' ranges (±2, the heater's 0 to 12 V, the pump's 1 to 10); the multisine, scaled
    /// to 1.8 standard deviations at the range's edge, is clipped there on few rows (a Gaussian
    /// signal would be on 7 %; 15 % leaves room for a sum of 40 sines); and the fast staircase
    /// changes level more often than the drawn one: its holds are a quarter of the shortest
    /// drawn hold up to that hold. A seed whose drawn input is the filtered noise (it changes
    /// every sample) is skipped for that comparison, which needs a staircase.
    #[test]
    fn the_other_signals_stay_in_range_and_the_fast_one_moves_faster() {
        let changes = |u: &[f64]| u.windows(2).filter(|w| w[0] != w[1]).count();
        let mut compared = 0;
        for case in PhysicalCase::ALL {
            for seed in 1..=3 {
                let drawn = run(case, 1500, seed).unwrap();
                let (lo, hi) = match case {
                    PhysicalCase::HeaterVoltage => (0.0, 12.0),
                    PhysicalCase::TankOverflow => (1.0, 10.0),
                    _ => (-2.0, 2.0),
                };
                for signal in [Signal::Multisine, Signal::FastSteps] {
                    let r = run_with(case, 1500, seed, signal).unwrap();
                    assert!(r.u.iter().all(|v| (lo..=hi).contains(v)), "{case:?} {seed} {signal:?}");
                    assert!(var(&r.u) > 0.0, "{case:?} {seed} {signal:?}");
                    if signal == Signal::Multisine {
                        let (min, max) =
                            r.u.iter()
                                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| (a.min(v), b.max(v)));
                        let at_edge = r.u.iter().filter(|&&v| v == min || v == max).count();
                        assert!(at_edge < 1500 * 15 / 100, "{case:?} {seed}: {at_edge} rows clipped");
                    }
                }
                if changes(&drawn.u) < 1000 {
                    let fast = run_with(case, 1500, seed, Signal::FastSteps).unwrap();
                    assert!(changes(&fast.u) > changes(&drawn.u), "{case:?} {seed}");
                    compared += 1;
                }
            }
        }
        assert!(compared >= 9, "only {compared} staircases compared");
    }

    #[test]
    fn same_seed_same_record() {
        let a = run(PhysicalCase::Duffing, 800, 5).unwrap();
        let b = run(PhysicalCase::Duffing, 800, 5).unwrap();
        assert_eq!(a, b);
    }
}
