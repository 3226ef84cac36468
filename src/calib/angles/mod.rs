//! The paper's angle method (docs/method.md, steps 4 and 5): every position aligned analytically, its
//! misalignment angles `phi` against the turntable's attitude stacked in a weighted least-squares solution
//! for the three gyro drifts, the three accelerometer biases and the reference offset ([`BiasSolver`],
//! file `solve.rs`), and the whole calibration with its refinement passes ([`calibrate_positions`], file
//! `calibration.rs`). The default estimator is the general one ([`crate::calib::general`]); this one is chosen
//! with `--method angles` on the host and `run::sequence::Estimator::Angles` on the device.

mod calibration;
mod solve;

pub use calibration::{
    attitude_difference_rad, calibrate_positions, CalibrationError, CalibrationResult, CalibrationSettings,
    PositionInput, MAX_HEADING_MISALIGNMENT_RAD, MAX_LEVEL_MISALIGNMENT_RAD,
};
pub use solve::{
    design_rows_si, table1_pair_solution, BiasSolution, BiasSolver, Estimate, Parameter, SolveError, SolverSettings,
    MAX_PARAMETERS, MAX_POSITIONS, TABLE1_POSITIONS_DEG,
};
