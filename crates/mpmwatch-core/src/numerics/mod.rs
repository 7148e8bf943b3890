//! The one numerics layer every crate uses: least squares and instrumental variables over
//! nalgebra, and the few order statistics the diagnosis and the reports need. ARX models are
//! identified by [`crate::model::Arx::fit`] on top of [`least_squares`]; signals are filtered by
//! [`crate::model::DiscreteTf`].

mod lstsq;
mod stats;

pub use lstsq::{BlockLeastSquares, Projector, instrumental, least_squares, least_squares_rows, r_squared};
pub use stats::{lagged, mean, median, minus_mean, minus_median, quantile, rms, std_dev};
