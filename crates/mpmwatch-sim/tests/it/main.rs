//! Integration tests of mpmwatch-sim: dithers, controllers, the paper's cases.
//! One test binary per crate, each test file a module, so the dependencies link once.

mod sim_cases;
mod sim_dither;
mod sim_mpc;
