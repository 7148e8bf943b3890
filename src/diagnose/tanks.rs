//! A Torricelli two-tank simulation (upper tank drains into the lower one through an orifice,
//! outflow ∝ √level) that leaves the upper tank's overflow out, and its calibration on samples
//! where the measured level stays below the overflow/clip region. Pure.

/// Parameters: `dh1/dt = −k1√h1 + k4·u`, `dh2/dt = k2√h1 − k3√h2`, `y = h2 + offset`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TwoTanks {
    /// Upper-tank outflow coefficient.
    pub k1: f64,
    /// Lower-tank inflow coefficient.
    pub k2: f64,
    /// Lower-tank outflow coefficient.
    pub k3: f64,
    /// Pump coefficient.
    pub k4: f64,
    /// Sensor offset.
    pub offset: f64,
}

impl TwoTanks {
    /// Simulates with sample time `ts` (four Euler sub-steps per sample), both tanks started at
    /// the steady state of the first input, never overflowing.
    pub fn simulate(&self, u: &[f64], ts: f64) -> Vec<f64> {
        let u0 = u.first().copied().unwrap_or(0.0).max(0.0);
        let mut h1 = (self.k4 * u0 / self.k1).powi(2);
        let mut h2 = (self.k2 * h1.sqrt() / self.k3).powi(2);
        let dt = ts / 4.0;
        u.iter()
            .map(|&v| {
                let y = h2 + self.offset;
                for _ in 0..4 {
                    let q1 = self.k1 * h1.max(0.0).sqrt();
                    h1 = (h1 + dt * (-q1 + self.k4 * v)).max(0.0);
                    h2 = (h2 + dt * (self.k2 * h1.sqrt() - self.k3 * h2.max(0.0).sqrt())).max(0.0);
                }
                y
            })
            .collect()
    }
}

/// Calibrates [`TwoTanks`] on the samples whose level is below `0.8·max(y)` (away from overflow
/// and the sensor clip) by a log-space coordinate search on the squared simulation error, and
/// returns the simulation over the whole record.
pub fn calibrate_and_simulate(u: &[f64], y: &[f64], ts: f64) -> Vec<f64> {
    calibrate(u, y, ts).simulate(u, ts)
}

/// The calibration of [`calibrate_and_simulate`].
pub fn calibrate(u: &[f64], y: &[f64], ts: f64) -> TwoTanks {
    let ymax = y.iter().fold(f64::MIN, |a, &b| a.max(b));
    let mask: Vec<bool> = y.iter().map(|&v| v < 0.8 * ymax).collect();
    let cost = |p: &TwoTanks| -> f64 {
        let s = p.simulate(u, ts);
        let c: f64 = s.iter().zip(y).zip(&mask).filter(|(_, m)| **m).map(|((a, b), _)| (a - b).powi(2)).sum();
        if c.is_finite() { c } else { f64::INFINITY }
    };
    let mut p = TwoTanks { k1: 0.05, k2: 0.05, k3: 0.05, k4: 0.05, offset: 0.0 };
    let mut best = cost(&p);
    let mut step = 1.0f64;
    for _ in 0..60 {
        let mut improved = false;
        for k in 0..5 {
            for dir in [-1.0, 1.0] {
                let mut q = p;
                match k {
                    0 => q.k1 *= (dir * step).exp(),
                    1 => q.k2 *= (dir * step).exp(),
                    2 => q.k3 *= (dir * step).exp(),
                    3 => q.k4 *= (dir * step).exp(),
                    _ => q.offset += dir * step,
                }
                let c = cost(&q);
                if c < best {
                    best = c;
                    p = q;
                    improved = true;
                }
            }
        }
        if !improved {
            step *= 0.5;
            if step < 1e-3 {
                break;
            }
        }
    }
    p
}
