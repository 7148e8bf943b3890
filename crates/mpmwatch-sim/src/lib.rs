//! The paper's plants, their controllers (PI, IMC, MPC, NMPC), the dither generators and the
//! scenarios behind `mpmwatch simulate`. Pure and seeded: every random draw comes from a
//! `ChaCha8Rng` built from the caller's seed, so one seed always gives the same record.

#![warn(missing_docs)]

pub mod cases;
mod closed_loop;
mod dither;
mod error;
mod imc;
mod mpc;
mod nmpc;
mod noise;
pub mod physical_cases;
mod pi;
mod qp;
pub mod scenarios;

pub use closed_loop::{ClosedLoop, Controller, LoopRecord};
pub use dither::{Excitation, Lfsr, MultilevelPrbs, PRBS_MAX_ORDER, PRBS_MIN_ORDER, Prbs};
pub use error::SimError;
pub use imc::Imc;
pub use mpc::{LinearMpc, MpcConfig, MpcStats};
pub use nmpc::Nmpc;
pub use noise::{coloured_noise, white_gaussian};
pub use pi::Pi;
