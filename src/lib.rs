//! # sinscal core
//!
//! Fast six-position bias calibration of a strapdown IMU on a turntable (METHOD.md of the project): the
//! two-state HMM/KF prefilter, dwell statistics, analytic coarse alignment, and the weighted
//! least-squares bias solution with standard errors and observability. `no_std`, f32, no allocation,
//! no panics on the data path: the same code runs on a Cortex-M4F and, through the `sinscal` tool, on a
//! workstation.
//!
//! Conventions (SPEC.md section 1): navigation frame East-North-Up; body frame x right, y forward, z up;
//! `C_b^n = Rz(-heading) Rx(pitch) Ry(roll)`; specific force at rest `[0, 0, +g]`; misalignment
//! `C_hat_b^n = (I - [phi x]) C_b^n`. SI units everywhere; names carry unit and frame
//! (`rate_b_radps`, `force_b_mps2`, `phi_n_rad`, `c_b_n`).
//!
//! Data flow for one calibration:
//! 1. per position, [`dwell::DwellCollector`] takes the samples of the dwell (prefilter + statistics);
//! 2. [`align::position_angles`] aligns the dwell and measures `phi` against the turntable attitude;
//! 3. [`solve::BiasSolver`] stacks the positions and solves for gyro and accelerometer biases.
#![cfg_attr(not(test), no_std)]
#![deny(missing_docs)]
#![forbid(unsafe_code)]

pub mod accumulate;
pub mod adis;
pub mod align;
pub mod calibration;
pub mod dwell;
pub mod earth;
pub mod frames;
pub mod imu;
pub mod linalg;
pub mod prefilter;
pub mod replay;
pub mod sampling;
#[cfg(target_os = "none")]
pub mod semihost;
pub mod sequence;
pub mod solve;
