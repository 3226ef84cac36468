//! SIMULATION models: the effect catalogue ([`catalogue`]) and the static sensor model ([`sensor`])
//! (docs/formats.md#effect-catalogue, docs/conventions.md#sensor-model), the scenario simulator of
//! `sinscal simulate`, and the synthetic sessions with known truth of the built-in example, the tests and
//! the Monte Carlo.

pub mod catalogue;
pub mod sensor;
pub mod simulator;
pub mod synth;
