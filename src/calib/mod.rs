//! Calibration: the HMM/KF prefilter ([`prefilter`]), one dwell's statistics ([`dwell`]), the analytic
//! coarse alignment and misalignment angles ([`align`]), the weighted least-squares bias solution
//! ([`solve`]) and the whole calibration with its refinement passes ([`calibration`]): the paper's angle
//! method. The general estimator ([`channels`]) fits every channel of every dwell; [`session`] loads a
//! session's dwells into it, and [`moves`] turns the moves between dwells into observations of the gyro terms. [`compensation`] inverts the sensor model for every sample on the device
//! (docs/compensation.md). The method is described in docs/method.md.

pub mod align;
pub mod calibration;
pub mod channels;
pub mod compensation;
pub mod dwell;
pub mod moves;
pub mod prefilter;
pub mod session;
pub mod solve;
