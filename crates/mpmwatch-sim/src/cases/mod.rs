//! The paper's scenarios behind `mpmwatch simulate`, each a pure function of its options and
//! seed returning the CSV table of DESIGN.md §4.1.

pub mod continuous2x3;
pub mod hammerstein3x3;
pub mod model1;

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use super::dither::Excitation;
use super::error::SimError;
use super::mpc::MpcStats;
use mpmwatch_core::io::Table;
use mpmwatch_core::model::MimoModel;

/// The cases `mpmwatch simulate` knows.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CaseName {
    /// Eq 12–14: SISO nonlinear ARX-like system, open loop, four residual candidates.
    Model1,
    /// Eqs 25–26: continuous 3-input 2-output plant under a linear MPC.
    Continuous2x3,
    /// Eqs 27–30: discrete 3×3 Hammerstein plant under an NMPC.
    Hammerstein3x3,
}

impl CaseName {
    /// Every case, in the paper's order.
    pub const ALL: [CaseName; 3] = [CaseName::Model1, CaseName::Continuous2x3, CaseName::Hammerstein3x3];

    /// Parses a case name; the error lists the valid ones.
    pub fn parse(s: &str) -> Result<Self, SimError> {
        match s {
            "model1" => Ok(Self::Model1),
            "continuous2x3" => Ok(Self::Continuous2x3),
            "hammerstein3x3" => Ok(Self::Hammerstein3x3),
            other => Err(SimError::UnknownCase(other.to_string())),
        }
    }

    /// The command-line name.
    pub fn name(self) -> &'static str {
        match self {
            Self::Model1 => "model1",
            Self::Continuous2x3 => "continuous2x3",
            Self::Hammerstein3x3 => "hammerstein3x3",
        }
    }

    /// Default number of samples (the paper's 2047 = 2^11 − 1, one PRBS period).
    pub fn default_samples(self) -> usize {
        2047
    }
}

/// Which disturbance dynamics the Hammerstein case uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Disturbance {
    /// The coloured noise of eq 27.
    #[default]
    Nominal,
    /// The changed dynamics of eq 30 (must not raise a mismatch alarm).
    Changed,
}

impl Disturbance {
    /// Parses `nominal` or `changed`.
    pub fn parse(s: &str) -> Result<Self, SimError> {
        match s {
            "nominal" => Ok(Self::Nominal),
            "changed" | "eq30" => Ok(Self::Changed),
            _ => Err(SimError::parameter("disturbance", s, "one of nominal, changed")),
        }
    }
}

/// Options shared by the cases (the §3.1 studies are these parameters).
#[derive(Debug, Clone, PartialEq)]
pub struct CaseOptions {
    /// Seed of every random draw.
    pub seed: u64,
    /// Record length; `None` for the case's default.
    pub samples: Option<usize>,
    /// Mismatch specification (case-specific; `None` for the paper's scenario).
    pub mismatch: Option<String>,
    /// Excitation type of the dithers / input (Figure 6).
    pub excitation: Excitation,
    /// Standard deviation of each dither (1 = the paper's ±1 PRBS and unit variance).
    pub dither_std: f64,
    /// Multiplies the standard deviation of every white noise source.
    pub noise_scale: f64,
    /// model1 only: noise-to-signal ratio of ε2 (Figure 5), overriding `noise_scale`.
    pub noise_ratio: Option<f64>,
    /// hammerstein3x3 only: disturbance dynamics.
    pub disturbance: Disturbance,
}

impl Default for CaseOptions {
    fn default() -> Self {
        Self {
            seed: 1,
            samples: None,
            mismatch: None,
            excitation: Excitation::Prbs,
            dither_std: 1.0,
            noise_scale: 1.0,
            noise_ratio: None,
            disturbance: Disturbance::Nominal,
        }
    }
}

/// A simulated record and what the controller did.
#[derive(Debug, Clone)]
pub struct CaseOutput {
    /// The CSV table.
    pub table: Table,
    /// Controller counters (closed-loop cases).
    pub controller: Option<MpcStats>,
    /// One-line description of the scenario actually run (plant parameters, variant).
    pub summary: String,
}

/// Runs one case.
pub fn run(case: CaseName, opts: &CaseOptions) -> Result<CaseOutput, SimError> {
    let n = opts.samples.unwrap_or(case.default_samples());
    if n < 3 {
        return Err(SimError::parameter("samples", n, "must be at least 3"));
    }
    if !(opts.noise_scale.is_finite() && opts.noise_scale >= 0.0) {
        return Err(SimError::parameter("noise scale", opts.noise_scale, "must be finite and non-negative"));
    }
    match case {
        CaseName::Model1 => model1::run(n, opts),
        CaseName::Continuous2x3 => continuous2x3::run(n, opts),
        CaseName::Hammerstein3x3 => hammerstein3x3::run(n, opts),
    }
}

/// Independent random stream `stream` of `seed`: the dither and the noise draw from different
/// streams, so changing one never shifts the other.
pub(crate) fn stream(seed: u64, stream: u64) -> ChaCha8Rng {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(stream);
    rng
}

/// Stream numbers.
pub(crate) const DITHER_STREAM: u64 = 1;
pub(crate) const NOISE_STREAM: u64 = 2;

/// Set points consistent with the dithered operating point: the nominal model's mean steady
/// output when each input is `u_op` plus its dither, `rⱼ = Σᵢ Gⱼᵢ(1) · mean_t fⱼᵢ(u_opᵢ + udᵢ(t))`.
///
/// The dither's power shifts the mean of an even map (`E[(u+ud)²] = u² + σ²`); a set point taken
/// at the undithered `u_op` would be unreachable and pin the controller to a bound even without
/// mismatch.
pub fn dithered_set_point(
    model: &MimoModel,
    u_op: &[f64],
    dither: &[Vec<f64>],
) -> Result<Vec<f64>, SimError> {
    if u_op.len() != model.inputs() || dither.len() != model.inputs() {
        return Err(SimError::parameter(
            "set point inputs",
            u_op.len(),
            &format!("need {} inputs and dithers", model.inputs()),
        ));
    }
    (0..model.outputs())
        .map(|j| {
            let mut r = 0.0;
            for i in 0..model.inputs() {
                if let Some(ch) = model.channel(j, i) {
                    let gain = ch.tf.dc_gain().ok_or_else(|| {
                        SimError::parameter(
                            "set point",
                            format!("channel u{} → y{}", i + 1, j + 1),
                            "has no finite static gain",
                        )
                    })?;
                    let d = &dither[i];
                    let mean =
                        d.iter().map(|v| ch.map.value(u_op[i] + v)).sum::<f64>() / d.len().max(1) as f64;
                    r += gain * mean;
                }
            }
            Ok(r)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use mpmwatch_core::model::{DiscreteTf, Hammerstein, StaticMap};

    #[test]
    fn set_point_includes_the_dither_power_of_an_even_map() {
        let g = DiscreteTf::new(vec![0.0, 0.5], vec![1.0, -0.5], 0).unwrap(); // static gain 1
        let m = MimoModel::new(vec![vec![
            Some(Hammerstein::new(StaticMap::Square, g.clone()).unwrap()),
            Some(Hammerstein::linear(g)),
        ]])
        .unwrap();
        let dither = vec![vec![1.0, -1.0, 1.0, -1.0], vec![1.0, -1.0, -1.0, 1.0]];
        // E[(1 + ud)²] = 1 + 1 = 2; E[3 + ud] = 3
        let r = dithered_set_point(&m, &[1.0, 3.0], &dither).unwrap();
        assert!((r[0] - 5.0).abs() < 1e-12, "{r:?}");
        assert!(dithered_set_point(&m, &[1.0], &dither).is_err());
    }
}
