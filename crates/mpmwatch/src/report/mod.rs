//! Reports: figures (SVG and PNG through plotters) and the JSON summary of an analysis.
//! Everything here writes files; the numbers come from `detect/` and `info/`.

pub mod figures;
pub mod reproduce;
mod summary;

pub use summary::{ChannelSummary, summarise};
