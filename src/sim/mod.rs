//! The paper's plants, their controllers (PI, IMC, MPC, NMPC), the dither generators and the
//! scenarios behind `mpmwatch simulate`. Pure and seeded.
