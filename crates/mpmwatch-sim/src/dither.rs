//! Dither (excitation) generators: maximal-length PRBS, multilevel PRBS, uniform and Gaussian
//! white noise. All draws come from the caller's seeded generator.

use rand::Rng;
use rand_distr::{Distribution, Normal};

use super::error::SimError;

/// Smallest PRBS order (shift-register length) supported.
pub const PRBS_MIN_ORDER: u32 = 2;
/// Largest PRBS order supported (a period of 16 777 215 bits).
pub const PRBS_MAX_ORDER: u32 = 24;

/// Feedback taps of primitive polynomials `x^n + …` (the standard maximal-length LFSR table),
/// indexed by order − 2. The `sim_dither` tests check each gives period 2^n − 1.
const TAPS: [&[u32]; 23] = [
    &[2, 1],
    &[3, 2],
    &[4, 3],
    &[5, 3],
    &[6, 5],
    &[7, 6],
    &[8, 6, 5, 4],
    &[9, 5],
    &[10, 7],
    &[11, 9],
    &[12, 11, 10, 4],
    &[13, 12, 11, 8],
    &[14, 13, 12, 2],
    &[15, 14],
    &[16, 15, 13, 4],
    &[17, 14],
    &[18, 11],
    &[19, 18, 17, 14],
    &[20, 17],
    &[21, 19],
    &[22, 21],
    &[23, 18],
    &[24, 23, 22, 17],
];

/// A Fibonacci linear-feedback shift register of order `n` with a primitive feedback polynomial:
/// its bit sequence has the maximal period 2^n − 1 and holds 2^(n−1) ones per period.
#[derive(Debug, Clone)]
pub struct Lfsr {
    order: u32,
    state: u32,
    taps: Vec<u32>,
}

impl Lfsr {
    /// A register of order `n` starting from `state` (reduced to n bits; zero is replaced by one,
    /// because the all-zero state is a fixed point).
    pub fn new(order: u32, state: u32) -> Result<Self, SimError> {
        if !(PRBS_MIN_ORDER..=PRBS_MAX_ORDER).contains(&order) {
            return Err(SimError::PrbsOrder { order, min: PRBS_MIN_ORDER, max: PRBS_MAX_ORDER });
        }
        let mask = (1u32 << order) - 1;
        let state = match state & mask {
            0 => 1,
            s => s,
        };
        Ok(Self { order, state, taps: TAPS[(order - PRBS_MIN_ORDER) as usize].to_vec() })
    }

    /// A register of order `n` on its `index`-th maximal-length feedback polynomial: index 0 is
    /// the standard table's, further ones are found by searching two- and four-tap feedbacks
    /// in a fixed order and keeping those whose period is 2^n − 1. Different polynomials give
    /// different m-sequences, not shifts of one another.
    pub fn with_polynomial(order: u32, index: usize, state: u32) -> Result<Self, SimError> {
        let mut lfsr = Self::new(order, state)?;
        if index > 0 {
            lfsr.taps = maximal_taps(order, index).ok_or_else(|| {
                SimError::parameter("PRBS polynomial index", index, "exceeds the polynomials searched")
            })?;
        }
        Ok(lfsr)
    }

    /// The current register contents.
    pub fn state(&self) -> u32 {
        self.state
    }

    /// The period of the bit sequence, 2^n − 1.
    pub fn period(&self) -> usize {
        (1usize << self.order) - 1
    }

    /// The next bit.
    pub fn next_bit(&mut self) -> bool {
        let n = self.order;
        let out = self.state & 1 == 1;
        let fb = self.taps.iter().fold(0, |acc, &t| acc ^ (self.state >> (n - t)) & 1);
        self.state = (self.state >> 1) | (fb << (n - 1));
        out
    }
}

/// Whether feedback `taps` on an order-`n` register cycle through all 2^n − 1 non-zero states.
fn is_maximal(n: u32, taps: &[u32]) -> bool {
    let period = (1u64 << n) - 1;
    let mut state = 1u32;
    for step in 1..=period {
        let fb = taps.iter().fold(0, |acc, &t| acc ^ (state >> (n - t)) & 1);
        state = (state >> 1) | (fb << (n - 1));
        if state == 1 {
            return step == period;
        }
    }
    false
}

/// The `index`-th maximal-length feedback of order n other than the table's (index ≥ 1).
fn maximal_taps(n: u32, index: usize) -> Option<Vec<u32>> {
    let table = TAPS[(n - PRBS_MIN_ORDER) as usize];
    let pairs = (1..n).rev().map(|k| vec![n, k]);
    let quads = (1..n)
        .rev()
        .flat_map(move |a| (1..a).rev().flat_map(move |b| (1..b).rev().map(move |c| vec![n, a, b, c])));
    pairs.chain(quads).filter(|t| t.as_slice() != table).filter(|t| is_maximal(n, t)).nth(index - 1)
}

/// A maximal-length PRBS: ±`amplitude`, each bit held for `clock` samples.
#[derive(Debug, Clone, PartialEq)]
pub struct Prbs {
    /// Shift-register length n; the bit period is 2^n − 1.
    pub order: u32,
    /// Output levels are ±amplitude.
    pub amplitude: f64,
    /// Samples per bit (the clock period).
    pub clock: usize,
}

impl Prbs {
    /// Validates the design.
    pub fn new(order: u32, amplitude: f64, clock: usize) -> Result<Self, SimError> {
        Lfsr::new(order, 1)?;
        if !(amplitude.is_finite() && amplitude > 0.0) {
            return Err(SimError::parameter("PRBS amplitude", amplitude, "must be positive and finite"));
        }
        if clock == 0 {
            return Err(SimError::parameter("PRBS clock period", clock, "must be at least one sample"));
        }
        Ok(Self { order, amplitude, clock })
    }

    /// The smallest order whose period covers `n` samples at clock period 1 (capped at the
    /// largest order; longer records repeat the sequence).
    pub fn order_for(n: usize) -> u32 {
        let mut order = PRBS_MIN_ORDER;
        while order < PRBS_MAX_ORDER && ((1usize << order) - 1) < n {
            order += 1;
        }
        order
    }

    /// One period in samples: (2^n − 1)·clock.
    pub fn period(&self) -> usize {
        ((1usize << self.order) - 1) * self.clock
    }

    /// `n` samples starting from a register state drawn from `rng` (a random circular shift of
    /// the one m-sequence of this order).
    pub fn generate(&self, n: usize, rng: &mut impl Rng) -> Vec<f64> {
        let start = rng.random::<u32>();
        self.generate_from_state(n, start)
    }

    /// `n` samples starting from a given register state (deterministic).
    pub fn generate_from_state(&self, n: usize, state: u32) -> Vec<f64> {
        let lfsr = Lfsr::new(self.order, state).expect("order validated in Prbs::new");
        self.generate_from(lfsr, n)
    }

    /// `n` samples from a given register.
    pub fn generate_from(&self, mut lfsr: Lfsr, n: usize) -> Vec<f64> {
        let mut out = Vec::with_capacity(n);
        while out.len() < n {
            let v = if lfsr.next_bit() { self.amplitude } else { -self.amplitude };
            for _ in 0..self.clock.min(n - out.len()) {
                out.push(v);
            }
        }
        out
    }
}

/// A pseudo-random multilevel sequence: each clock period takes one of `levels` equally spaced
/// values in [−amplitude, amplitude], drawn uniformly. Unlike a binary PRBS it excites a static
/// nonlinearity at more than two points.
#[derive(Debug, Clone, PartialEq)]
pub struct MultilevelPrbs {
    /// Number of levels (≥ 2).
    pub levels: usize,
    /// Extreme level.
    pub amplitude: f64,
    /// Samples per level.
    pub clock: usize,
}

impl MultilevelPrbs {
    /// Validates the design.
    pub fn new(levels: usize, amplitude: f64, clock: usize) -> Result<Self, SimError> {
        if levels < 2 {
            return Err(SimError::parameter("multilevel PRBS levels", levels, "must be at least 2"));
        }
        if !(amplitude.is_finite() && amplitude > 0.0) {
            return Err(SimError::parameter(
                "multilevel PRBS amplitude",
                amplitude,
                "must be positive and finite",
            ));
        }
        if clock == 0 {
            return Err(SimError::parameter(
                "multilevel PRBS clock period",
                clock,
                "must be at least one sample",
            ));
        }
        Ok(Self { levels, amplitude, clock })
    }

    /// Variance of the level distribution: a²(L+1)/(3(L−1)).
    pub fn variance(&self) -> f64 {
        let l = self.levels as f64;
        self.amplitude * self.amplitude * (l + 1.0) / (3.0 * (l - 1.0))
    }

    /// `n` samples.
    pub fn generate(&self, n: usize, rng: &mut impl Rng) -> Vec<f64> {
        let step = 2.0 * self.amplitude / (self.levels - 1) as f64;
        let mut out = Vec::with_capacity(n);
        while out.len() < n {
            let v = -self.amplitude + step * rng.random_range(0..self.levels) as f64;
            for _ in 0..self.clock.min(n - out.len()) {
                out.push(v);
            }
        }
        out
    }
}

/// The excitation types of the paper's Figure 6, each scaled to a given standard deviation.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Excitation {
    /// Binary maximal-length PRBS, ±σ, clock period one sample.
    Prbs,
    /// Five-level pseudo-random sequence scaled to standard deviation σ.
    Multilevel,
    /// Uniform white noise on [−√3σ, √3σ].
    Uniform,
    /// Gaussian white noise N(0, σ²).
    Gaussian,
}

impl Excitation {
    /// Parses `prbs`, `multilevel`, `uniform` or `gaussian`.
    pub fn parse(s: &str) -> Result<Self, SimError> {
        match s.to_ascii_lowercase().as_str() {
            "prbs" => Ok(Self::Prbs),
            "multilevel" | "mprbs" => Ok(Self::Multilevel),
            "uniform" => Ok(Self::Uniform),
            "gaussian" | "normal" => Ok(Self::Gaussian),
            _ => Err(SimError::parameter("excitation", s, "one of prbs, multilevel, uniform, gaussian")),
        }
    }

    /// `count` dithers of `n` samples each, one per MV.
    ///
    /// For the PRBS each MV gets a different m-sequence (the i-th maximal-length feedback
    /// polynomial of the order) from a seeded random state. Shifted copies of one m-sequence
    /// would not do for a nonlinear plant: by the shift-and-add property the product of two
    /// shifts of an m-sequence is a third shift, so a quadratic mismatch on MV 1 puts an exact
    /// copy of another MV's dither into the residual (measured: false CCF alarms on ud3 in the
    /// continuous 2×3 case). The other types draw independent sequences.
    pub fn generate_many(
        self,
        n: usize,
        count: usize,
        std: f64,
        rng: &mut impl Rng,
    ) -> Result<Vec<Vec<f64>>, SimError> {
        if self != Self::Prbs {
            return (0..count).map(|_| self.generate(n, std, rng)).collect();
        }
        if !(std.is_finite() && std > 0.0) {
            return Err(SimError::parameter("dither standard deviation", std, "must be positive and finite"));
        }
        let prbs = Prbs::new(Prbs::order_for(n), std, 1)?;
        (0..count)
            .map(|i| Ok(prbs.generate_from(Lfsr::with_polynomial(prbs.order, i, rng.random::<u32>())?, n)))
            .collect()
    }

    /// `n` samples of zero mean and standard deviation `std`.
    pub fn generate(self, n: usize, std: f64, rng: &mut impl Rng) -> Result<Vec<f64>, SimError> {
        if !(std.is_finite() && std > 0.0) {
            return Err(SimError::parameter("dither standard deviation", std, "must be positive and finite"));
        }
        Ok(match self {
            Self::Prbs => Prbs::new(Prbs::order_for(n), std, 1)?.generate(n, rng),
            Self::Multilevel => {
                let unit = MultilevelPrbs::new(5, 1.0, 1)?;
                MultilevelPrbs::new(5, std / unit.variance().sqrt(), 1)?.generate(n, rng)
            }
            Self::Uniform => {
                let a = 3f64.sqrt() * std;
                (0..n).map(|_| rng.random_range(-a..=a)).collect()
            }
            Self::Gaussian => {
                let d = Normal::new(0.0, std)
                    .map_err(|e| SimError::parameter("dither standard deviation", std, &e.to_string()))?;
                (0..n).map(|_| d.sample(rng)).collect()
            }
        })
    }
}
