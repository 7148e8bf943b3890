//! Nominal models (discrete transfer functions in q⁻¹ with dead times, ZOH-discretised continuous
//! transfer functions, ARX, state space, Hammerstein blocks) and their SISO/MIMO simulation.
//! Pure: no I/O. The simulators, the online service and diagnosis all use this one module.
