//! Nominal models (discrete transfer functions in q⁻¹ with dead times, ZOH-discretised continuous
//! transfer functions, ARX, state space, Hammerstein blocks) and their SISO/MIMO simulation.
//! Pure: no I/O. The simulators, the online service and diagnosis all use this one module.
//!
//! Every simulator has two faces: a whole-record call (`simulate`) and a step-by-step state
//! (`step(u) -> y`, `peek()` for the part of the next output already fixed by the past) so that
//! an online service can compute `G0(u)` sample by sample and a closed loop can read `y(k)`
//! before choosing `u(k)`.

mod arx;
mod error;
mod hammerstein;
mod mimo;
mod state_space;
mod transfer;
mod zoh;

pub use arx::{Arx, ArxOrders, ArxPredictor};
pub use error::ModelError;
pub use hammerstein::{Hammerstein, HammersteinFilter, StaticMap};
pub use mimo::{MimoModel, MimoState};
pub use state_space::{Mat, SsState, StateSpace};
pub use transfer::{DiscreteTf, TfFilter};
pub use zoh::ContinuousTf;
