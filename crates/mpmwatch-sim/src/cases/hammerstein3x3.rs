//! `hammerstein3x3` (paper §4.2, eqs 27–30): a discrete 3×3 Hammerstein plant under an NMPC.
//!
//! Our reading of the garbled eq 27 (see `docs/plants.md`): `y = G(q) [u1, u2², sin(u3)]ᵀ + v`,
//!
//! ```text
//!      ⎡ (0.1q⁻¹+0.2q⁻²)/(1−0.8q⁻¹)  (0.3q⁻¹+0.2q⁻²)/(1−1.2q⁻¹+0.35q⁻²)  q⁻¹/(1−0.7q⁻¹)                   ⎤
//! G =  ⎢ (q⁻¹+0.5q⁻²)/(1+0.4q⁻¹)     q⁻¹/(1−0.48q⁻¹)                      (−0.11q⁻¹−0.058q⁻²)/(1−1.05q⁻¹+0.136q⁻²) ⎥
//!      ⎣ 0.59q⁻¹/(1−0.607q⁻¹)         0.85q⁻¹/(1−0.717q⁻¹)                  0.098q⁻¹/(1−0.95q⁻¹)              ⎦
//! ```
//!
//! `v = diag(1/(1−0.5q⁻¹), 1/(1+0.8q⁻¹), 1/(1−0.1q⁻¹)) a`, `a` white with variance 0.1 per channel;
//! eq 30 changes it to `diag(1/(1+0.7q⁻¹), 1/(1−0.2q⁻¹), 1/(1+0.9q⁻¹))`.
//!
//! Mismatches (eqs 28–29, paper notation `gᵢⱼ` = MV i → CV j): `g21` (MV2 → CV1, matrix entry
//! (1,2)) becomes `2q⁻¹/(1−0.2q⁻¹)`; `g31` (MV3 → CV1, entry (1,3)) `q⁻¹/(1−0.7q⁻¹)` becomes
//! `0.59q⁻¹/(1−0.607q⁻¹)`. MV2 enters through u2², an even map, which is why linear
//! correlation can miss g21.
//!
//! The closed loop: the NMPC of [`crate::Nmpc`] on the nominal model, operating point
//! `u = (0, 1, 0)` (at u2 = 0 the slope of u2² is zero and a ±1 dither gives u2² ≡ 1, so nothing
//! about g21 would be observable), set points the nominal mean steady outputs there under the
//! dither (see [`super::dithered_set_point`]), ±1 PRBS dithers.
//!
//! Columns: `time, u1..u3, ud1..ud3, y1..y3, yhat1..yhat3, e1..e3`.

use super::{CaseOptions, CaseOutput, DITHER_STREAM, Disturbance, NOISE_STREAM, stream};
use crate::closed_loop::ClosedLoop;
use crate::error::SimError;
use crate::mpc::MpcConfig;
use crate::nmpc::Nmpc;
use crate::noise::coloured_noise;
use mpmwatch_core::model::{DiscreteTf, Hammerstein, MimoModel, StaticMap};

/// Operating input.
pub const U_OP: [f64; 3] = [0.0, 1.0, 0.0];
/// Variance of each white noise source.
pub const NOISE_VARIANCE: f64 = 0.1;
const WARM_UP: usize = 200;

/// Which submodels of the plant differ from the nominal model.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Mismatch {
    /// Eq 28: MV2 → CV1.
    pub g21: bool,
    /// Eq 29: MV3 → CV1.
    pub g31: bool,
}

impl Mismatch {
    /// Parses `none`, `g21`, `g31` or `both` (the default, the paper's scenario).
    pub fn parse(spec: Option<&str>) -> Result<Self, SimError> {
        match spec.unwrap_or("both") {
            "none" => Ok(Self { g21: false, g31: false }),
            "g21" => Ok(Self { g21: true, g31: false }),
            "g31" => Ok(Self { g21: false, g31: true }),
            "both" => Ok(Self { g21: true, g31: true }),
            other => Err(SimError::Mismatch {
                case: "hammerstein3x3".into(),
                given: other.into(),
                accepted: "none, g21, g31, both (default both)".into(),
            }),
        }
    }
}

fn tf(b: &[f64], a: &[f64]) -> DiscreteTf {
    DiscreteTf::new(b.to_vec(), a.to_vec(), 0).expect("constant coefficients")
}

/// The linear part of eq 27, row by row.
fn linear_matrix() -> Vec<Vec<DiscreteTf>> {
    vec![
        vec![
            tf(&[0.0, 0.1, 0.2], &[1.0, -0.8]),
            tf(&[0.0, 0.3, 0.2], &[1.0, -1.2, 0.35]),
            tf(&[0.0, 1.0], &[1.0, -0.7]),
        ],
        vec![
            tf(&[0.0, 1.0, 0.5], &[1.0, 0.4]),
            tf(&[0.0, 1.0], &[1.0, -0.48]),
            tf(&[0.0, -0.11, -0.058], &[1.0, -1.05, 0.136]),
        ],
        vec![
            tf(&[0.0, 0.59], &[1.0, -0.607]),
            tf(&[0.0, 0.85], &[1.0, -0.717]),
            tf(&[0.0, 0.098], &[1.0, -0.95]),
        ],
    ]
}

/// The input maps of eq 27, one per MV.
pub fn maps() -> [StaticMap; 3] {
    [StaticMap::Identity, StaticMap::Square, StaticMap::Sine]
}

fn assemble(linear: Vec<Vec<DiscreteTf>>) -> MimoModel {
    let maps = maps();
    let rows = linear
        .into_iter()
        .map(|row| {
            row.into_iter()
                .enumerate()
                .map(|(i, g)| Some(Hammerstein { map: maps[i].clone(), tf: g }))
                .collect()
        })
        .collect();
    MimoModel::new(rows).expect("3×3 by construction")
}

/// The nominal model G0 of eq 27.
pub fn nominal() -> MimoModel {
    assemble(linear_matrix())
}

/// The plant: eq 27 with the chosen submodel changes of eqs 28–29.
pub fn plant(m: Mismatch) -> MimoModel {
    let mut g = linear_matrix();
    if m.g21 {
        g[0][1] = tf(&[0.0, 2.0], &[1.0, -0.2]);
    }
    if m.g31 {
        g[0][2] = tf(&[0.0, 0.59], &[1.0, -0.607]);
    }
    assemble(g)
}

/// The noise filters of eq 27 or, changed, of eq 30.
pub fn noise_filters(d: Disturbance) -> Vec<DiscreteTf> {
    let poles: [f64; 3] = match d {
        Disturbance::Nominal => [0.5, -0.8, 0.1],
        Disturbance::Changed => [-0.7, 0.2, -0.9],
    };
    poles.iter().map(|p| tf(&[1.0], &[1.0, -p])).collect()
}

/// The NMPC tuning used by the case.
pub fn nmpc_config() -> MpcConfig {
    MpcConfig {
        np: 10,
        nc: 3,
        q: vec![1.0; 3],
        r: vec![0.5; 3],
        u_min: U_OP.iter().map(|u| u - 1.5).collect(),
        u_max: U_OP.iter().map(|u| u + 1.5).collect(),
        du_max: vec![0.5; 3],
    }
}

/// Runs the case.
pub(crate) fn run(n: usize, opts: &CaseOptions) -> Result<CaseOutput, SimError> {
    let m = Mismatch::parse(opts.mismatch.as_deref())?;
    let plant = self::plant(m);
    let nominal = nominal();
    let dither =
        opts.excitation.generate_many(n, 3, opts.dither_std, &mut stream(opts.seed, DITHER_STREAM))?;
    let mut noise_rng = stream(opts.seed, NOISE_STREAM);
    let variance = NOISE_VARIANCE * opts.noise_scale * opts.noise_scale;
    let noise = noise_filters(opts.disturbance)
        .iter()
        .map(|h| coloured_noise(h, n, variance, 200, &mut noise_rng))
        .collect::<Result<Vec<_>, _>>()?;
    let setpoint = super::dithered_set_point(&nominal, &U_OP, &dither)?;
    let mut nmpc = Nmpc::new(nominal.clone(), U_OP.to_vec(), nmpc_config(), 2, 0.5)?;
    let rec = ClosedLoop {
        plant: &plant,
        nominal: &nominal,
        dither: &dither,
        noise: &noise,
        setpoint: &setpoint,
        u_start: &U_OP,
        warm_up: WARM_UP,
        bound: 1e3,
    }
    .run(&mut nmpc)?;
    Ok(CaseOutput {
        table: rec.to_table(1.0)?,
        controller: Some(nmpc.stats().clone()),
        summary: format!(
            "hammerstein3x3: eq 27, mismatch g21={} g31={}, disturbance {:?}, NMPC, {:?} dithers (std {})",
            m.g21, m.g31, opts.disturbance, opts.excitation, opts.dither_std
        ),
    })
}
