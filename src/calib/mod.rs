//! Calibration: the HMM/KF prefilter ([`prefilter`]), one dwell's statistics ([`dwell`]), the analytic coarse
//! alignment and misalignment angles ([`align`]), and the two estimators. The general estimator ([`general`],
//! the default) fits every channel of every dwell with the sensor-model terms selectable; [`session`] loads a
//! session's dwells into it, and [`moves`] turns the moves between dwells into observations of the gyro terms.
//! The paper's angle method ([`angles`]) solves for the biases from the alignment angles of every position, with
//! its refinement passes. [`limits`] holds the rest and pose thresholds. [`noise_model`] turns a channel's
//! noise terms, named once from a static run, into the variance of a dwell mean. [`compensation`] inverts the sensor model for every sample on the device
//! (docs/compensation.md). The methods are described in docs/method.md.

pub mod align;
pub mod angles;
pub mod compensation;
pub mod dwell;
pub mod general;
pub mod limits;
pub mod moves;
pub mod noise_model;
pub mod prefilter;
pub mod session;
