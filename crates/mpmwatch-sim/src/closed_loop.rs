//! The closed loop of the paper's Figure 1: plant, nominal model in parallel, controller, dither
//! added to the controller output, coloured noise on the plant outputs.

use super::error::SimError;
use mpmwatch_core::io::{Table, TableError};
use mpmwatch_core::model::MimoModel;

/// A controller in the IMC structure: it reads the measured outputs, proposes its output
/// `uc(t)`, and is told the applied total input `u(t) = uc(t) + ud(t)` (its internal model runs on
/// that, like the plant).
pub trait Controller {
    /// `uc(t)` from the measurements `y(t)` and set points `r`.
    fn control(&mut self, y: &[f64], r: &[f64]) -> Result<Vec<f64>, SimError>;
    /// Advances the internal model with the applied input.
    fn apply(&mut self, u: &[f64]) -> Result<(), SimError>;
}

/// The signals of one closed-loop run, one series per input or output.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct LoopRecord {
    /// Total MVs `u = uc + ud`.
    pub u: Vec<Vec<f64>>,
    /// Controller outputs `uc`.
    pub uc: Vec<Vec<f64>>,
    /// Dithers `ud`.
    pub ud: Vec<Vec<f64>>,
    /// Measured CVs `y`.
    pub y: Vec<Vec<f64>>,
    /// Nominal model predictions `ŷ = G0(u)`.
    pub yhat: Vec<Vec<f64>>,
    /// Residuals `e = y − ŷ`.
    pub e: Vec<Vec<f64>>,
}

impl LoopRecord {
    /// The CSV table: `time` (sample index × `period`), then `u1..`, `ud1..`, `y1..`, `yhat1..`,
    /// `e1..`.
    pub fn to_table(&self, period: f64) -> Result<Table, TableError> {
        let n = self.y.first().map_or(0, Vec::len);
        let mut t = Table::new((0..n).map(|k| k as f64 * period).collect());
        for (prefix, series) in
            [("u", &self.u), ("ud", &self.ud), ("y", &self.y), ("yhat", &self.yhat), ("e", &self.e)]
        {
            for (i, s) in series.iter().enumerate() {
                t.push_column(format!("{prefix}{}", i + 1), s.clone())?;
            }
        }
        Ok(t)
    }
}

/// Everything a closed-loop run needs besides the controller.
pub struct ClosedLoop<'a> {
    /// The true plant.
    pub plant: &'a MimoModel,
    /// The nominal model `G0` whose residuals are recorded.
    pub nominal: &'a MimoModel,
    /// Dither per input (all the same length, the run length).
    pub dither: &'a [Vec<f64>],
    /// Output noise per output.
    pub noise: &'a [Vec<f64>],
    /// Constant set points.
    pub setpoint: &'a [f64],
    /// Input at which plant, model and controller are brought to steady state before recording.
    pub u_start: &'a [f64],
    /// Warm-up samples (not recorded).
    pub warm_up: usize,
    /// A signal beyond this magnitude stops the run with [`SimError::Diverged`].
    pub bound: f64,
}

impl ClosedLoop<'_> {
    /// Runs the loop: at each sample read `y(t)`, form `e(t) = y(t) − ŷ(t)`, ask the controller,
    /// add the dither, advance plant, model and controller.
    pub fn run<C: Controller>(&self, controller: &mut C) -> Result<LoopRecord, SimError> {
        let (nu, ny) = (self.plant.inputs(), self.plant.outputs());
        if self.nominal.inputs() != nu || self.nominal.outputs() != ny {
            return Err(SimError::parameter(
                "nominal model size",
                format!("{}x{}", self.nominal.outputs(), self.nominal.inputs()),
                &format!("must match the plant's {ny}x{nu}"),
            ));
        }
        if !self.plant.is_strictly_proper() || !self.nominal.is_strictly_proper() {
            return Err(SimError::parameter(
                "closed loop",
                "direct feed-through",
                "plant and model must be strictly proper",
            ));
        }
        if self.dither.len() != nu
            || self.noise.len() != ny
            || self.setpoint.len() != ny
            || self.u_start.len() != nu
        {
            return Err(SimError::parameter(
                "closed loop signals",
                format!(
                    "{} dithers, {} noises, {} set points, {} start inputs",
                    self.dither.len(),
                    self.noise.len(),
                    self.setpoint.len(),
                    self.u_start.len()
                ),
                &format!("need {nu} inputs and {ny} outputs"),
            ));
        }
        let n = self.dither[0].len();
        if self.dither.iter().chain(self.noise).any(|s| s.len() != n) {
            return Err(SimError::parameter(
                "closed loop signals",
                "unequal lengths",
                "dithers and noises must have the run length",
            ));
        }
        let mut plant = self.plant.state();
        let mut model = self.nominal.state();
        for _ in 0..self.warm_up {
            plant.step(self.u_start)?;
            model.step(self.u_start)?;
            controller.apply(self.u_start)?;
        }
        let mut rec = LoopRecord {
            u: vec![Vec::with_capacity(n); nu],
            uc: vec![Vec::with_capacity(n); nu],
            ud: vec![Vec::with_capacity(n); nu],
            y: vec![Vec::with_capacity(n); ny],
            yhat: vec![Vec::with_capacity(n); ny],
            e: vec![Vec::with_capacity(n); ny],
        };
        for t in 0..n {
            let y: Vec<f64> = plant.peek().iter().enumerate().map(|(j, v)| v + self.noise[j][t]).collect();
            let yhat = model.peek();
            let uc = controller.control(&y, self.setpoint)?;
            let u: Vec<f64> = (0..nu).map(|i| uc[i] + self.dither[i][t]).collect();
            for (name, v) in [("y", &y), ("u", &u)] {
                if let Some((j, bad)) = v.iter().enumerate().find(|(_, x)| x.abs() > self.bound || x.is_nan())
                {
                    return Err(SimError::Diverged {
                        sample: t,
                        signal: format!("{name}{}", j + 1),
                        value: *bad,
                    });
                }
            }
            plant.step(&u)?;
            model.step(&u)?;
            controller.apply(&u)?;
            for j in 0..ny {
                rec.y[j].push(y[j]);
                rec.yhat[j].push(yhat[j]);
                rec.e[j].push(y[j] - yhat[j]);
            }
            for i in 0..nu {
                rec.u[i].push(u[i]);
                rec.uc[i].push(uc[i]);
                rec.ud[i].push(self.dither[i][t]);
            }
        }
        Ok(rec)
    }
}
