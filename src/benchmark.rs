//! Timings of the estimation core behind `mpmwatch bench`.
