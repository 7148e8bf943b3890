//! Detection and localisation: the lagged MI matrix between dithers and residuals (eqs 20–21),
//! each element with its own surrogate critical value, and the verdict per MV→CV channel from
//! Propositions 1–4 of the paper. Pure and synchronous; the online service and the `analyze`
//! verb both call [`analyze`].

mod matrix;
mod partial;
mod pool;
mod verdict;
mod whiten;

pub use matrix::{
    CcfBaseline, Cell, Decision, ElementTest, Evidence, LagChoice, MatrixOptions, MatrixResult, Method,
    Signal, analyze, analyze_segments,
};
pub use partial::{PartialPlan, partial_out};
pub use verdict::{Channel, Verdict, localise};
pub use whiten::ArWhitener;
