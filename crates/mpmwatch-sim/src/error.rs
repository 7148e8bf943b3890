//! Errors of the simulators and controllers. Each names the offending parameter or case.

use mpmwatch_core::model::ModelError;

/// What can go wrong building or running a simulation.
#[derive(Debug, thiserror::Error)]
pub enum SimError {
    /// A PRBS order outside the tabulated maximal-length feedback polynomials.
    #[error("PRBS order {order} is out of range: supported orders are {min}..={max}")]
    PrbsOrder {
        /// The order asked for.
        order: u32,
        /// Smallest supported order.
        min: u32,
        /// Largest supported order.
        max: u32,
    },
    /// A numeric parameter is out of its valid range.
    #[error("parameter `{name}` = {value}: {why}")]
    Parameter {
        /// The parameter name.
        name: String,
        /// Its value, as text.
        value: String,
        /// What is required.
        why: String,
    },
    /// A case name that does not exist.
    #[error("unknown case `{0}`; the cases are: model1, continuous2x3, hammerstein3x3")]
    UnknownCase(String),
    /// A mismatch specification a case does not understand.
    #[error("case `{case}`: unknown mismatch `{given}`; accepted: {accepted}")]
    Mismatch {
        /// The case.
        case: String,
        /// What was given.
        given: String,
        /// What the case accepts.
        accepted: String,
    },
    /// A model could not be built or run.
    #[error(transparent)]
    Model(#[from] ModelError),
    /// The closed loop left the bounded region (a diverging simulation is a bug, not data).
    #[error("closed loop diverged at sample {sample}: {signal} = {value}")]
    Diverged {
        /// Sample index.
        sample: usize,
        /// Which signal.
        signal: String,
        /// Its value.
        value: f64,
    },
    /// A concealed scenario whose closed loop runs away at every strength tried: no case.
    #[error(
        "scenario `{case}`: the loop runs away at every strength tried (no run whose effect stays under {limit:e} times the disturbance's variance), so it is no concealed case"
    )]
    Runaway {
        /// The scenario's name.
        case: String,
        /// The largest effect-to-disturbance variance ratio a run may reach.
        limit: f64,
    },
    /// The output table could not be built.
    #[error(transparent)]
    Table(#[from] mpmwatch_core::io::TableError),
    /// The QP solver could not be set up.
    #[error("QP solver: {0}")]
    Solver(String),
}

impl SimError {
    /// Shorthand for [`SimError::Parameter`].
    pub fn parameter(name: &str, value: impl ToString, why: &str) -> Self {
        Self::Parameter { name: name.to_string(), value: value.to_string(), why: why.to_string() }
    }
}
