//! SIMULATION models: the sensor-error model and the effect catalogue (docs/conventions.md,
//! docs/formats.md), the scenario simulator of `sinscal simulate`, and the synthetic sessions with known
//! truth of the built-in example, the tests and the Monte Carlo.

pub mod catalogue;
pub mod simulator;
pub mod synth;
