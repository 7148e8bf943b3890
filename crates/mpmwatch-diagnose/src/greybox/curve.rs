//! A fitted element drawn as what it is, for its figure: its static map over the range the
//! record visits, the loop an element with memory traces, or (built in [`super::linear_change`])
//! a linear change's two step responses.

use super::{Data, Fitted, Model};
use crate::candidates::Physics;

/// A fitted element drawn as what it is: its static map over the range the record visits, the
/// loop an element with memory traces over that range, or, for a linear change, the channel's
/// re-fitted step response beside the model's.
#[derive(Debug, Clone, PartialEq)]
pub struct ElementCurve {
    /// The element's class.
    pub physics: Physics,
    /// Name of the map's argument.
    pub x_label: String,
    /// Name of its value.
    pub y_label: String,
    /// The map, 201 points over the range; for an element with memory, its loop (401 points,
    /// down the range and up again).
    pub points: Vec<(f64, f64)>,
    /// What the nominal assumes in its place: the identity for a map on a signal, no force
    /// for a feedback element, the model's own step response for a linear change.
    pub baseline: Vec<(f64, f64)>,
    /// Legend of `points`.
    pub label: String,
    /// Legend of `baseline`.
    pub baseline_label: String,
}

impl Model<'_> {
    /// The fitted element's map ([`Element::map_at`], [`Element::map_from_gains`]) or loop
    /// ([`Element::trace`]) over its range, `None` when it has none.
    pub fn curve(&self, f: &Fitted, d: &Data<'_>, input: &str, output: &str) -> Option<ElementCurve> {
        let sig = self.element.signals(&f.p, &d.u, self.input).len();
        let l = self.layout(sig);
        let gamma = &f.theta[l.gamma()];
        let (x_label, (lo, hi), y_label) = self.element.map_axes(d, self.input, input, output);
        let pad = 0.1 * (hi - lo).max(f64::MIN_POSITIVE);
        let at = |k: usize| lo - pad + (hi - lo + 2.0 * pad) * k as f64 / 200.0;
        // An element with memory is driven up, down and up again over the range; the last two
        // legs, which start from a state the first leg has set, close its loop.
        let sweep: Vec<f64> = (0..=200).chain((0..200).rev()).chain(1..=200).map(at).collect();
        if let Some(out) = self.element.trace(&f.p, &sweep) {
            let points: Vec<(f64, f64)> = sweep.iter().copied().zip(out).skip(200).collect();
            let baseline = points.iter().map(|&(v, _)| (v, v)).collect();
            return Some(ElementCurve::against_the_model(
                self.element.physics(),
                x_label,
                y_label,
                points,
                baseline,
            ));
        }
        // Steady-state gain of each signal's numerator through its channel's poles.
        let dc: Vec<f64> = (0..sig)
            .map(|s| {
                let poles = 1.0 - f.theta[l.alpha(l.channel(s))].iter().sum::<f64>();
                f.theta[l.beta(s)].iter().sum::<f64>() / poles
            })
            .collect();
        let points = (0..=200)
            .map(|k| {
                let v = at(k);
                self.element
                    .map_at(&f.p, gamma, v)
                    .or_else(|| self.element.map_from_gains(&f.p, &dc, self.input, v))
                    .map(|m| (v, m))
            })
            .collect::<Option<Vec<_>>>()?;
        let fed_back = self.element.feedbacks() > 0;
        let baseline = points.iter().map(|&(v, _)| (v, if fed_back { 0.0 } else { v })).collect();
        Some(ElementCurve::against_the_model(self.element.physics(), x_label, y_label, points, baseline))
    }
}

impl ElementCurve {
    /// A fitted element's curve beside what the nominal assumes without it.
    fn against_the_model(
        physics: Physics,
        x_label: String,
        y_label: String,
        points: Vec<(f64, f64)>,
        baseline: Vec<(f64, f64)>,
    ) -> Self {
        Self {
            physics,
            x_label,
            y_label,
            points,
            baseline,
            label: format!("fitted {}", physics.name()),
            baseline_label: "nominal (without it)".into(),
        }
    }
}
