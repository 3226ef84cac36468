//! # sinscal core
//!
//! Fast calibration of a strapdown IMU on a turntable (docs/method.md): the two-state HMM/KF prefilter,
//! dwell statistics, and the general estimator (the default: the sensor model's terms fitted to every channel
//! of every dwell, with standard errors and structural observability) beside the paper's angle method
//! (analytic coarse alignment and the weighted least-squares bias solution); the ADIS driver, the sampling queue and the calibration sequence
//! of the firmware. `no_std`, f32, no allocation, no panics on the data path: the same code runs on a
//! Cortex-M4F and, through the `sinscal` tool, on a workstation.
//!
//! Conventions (docs/conventions.md): navigation frame East-North-Up; body frame x right, y forward, z up;
//! `C_b^n = Rz(-heading) Rx(pitch) Ry(roll)`; specific force at rest `[0, 0, +g]`; misalignment
//! `C_hat_b^n = (I - [phi x]) C_b^n`. SI units everywhere; names carry unit and frame
//! (`rate_b_radps`, `force_b_mps2`, `phi_n_rad`, `c_b_n`).
//!
//! ## Layers
//! Each layer uses only the layers listed before it (a test checks this):
//!
//! | layer | what |
//! |---|---|
//! | [`math`] | 3-vectors, 3x3 matrices, dwell accumulators, the online octave Allan variance |
//! | [`nav`] | frames, attitudes, Earth rate and gravity: every sign convention |
//! | [`sensor`] | [`ImuSample`], the [`ImuSource`] trait, the ADIS driver |
//! | [`calib`] | prefilter, dwell statistics, alignment, the two estimators (general, angles), the moves, the compensation of samples |
//! | [`run`] | the data-ready handler and its queue, the calibration sequence |
//! | [`instrument`] | the device: the host link (frames, messages), the wire formats (configuration, outcome, record: [`instrument::wire`]), the calibration record in NOR flash, compensation |
//! | `rig` | replay of a recording through the firmware path, exact synthetic data, semihosting (emulation and tests; feature `rig`) |
//! | `board` | register-level code of QEMU's board, the panic handler and the defmt logger (target only, feature `mps2-an386`, not a default) |
//!
//! ## Data flow
//! On the firmware, at 100 Hz:
//! 1. the data-ready interrupt calls [`run::sampling::on_data_ready`]: the driver
//!    ([`sensor::adis::Adis`], an [`ImuSource`]) reads one burst, checks and converts it to an
//!    [`ImuSample`] in SI units, and the reading is queued (every fault counted, never unwrapped);
//! 2. the main loop hands each queued reading to the [`CalibrationSequence`] with the turntable's
//!    "in position" signal: it waits, lets the table settle, and feeds the dwell's
//!    [`DwellCollector`] (HMM/KF prefilter and statistics per channel, with the octave Allan variance that
//!    gives the honest noise of each dwell mean), aborting a dwell that moves;
//! 3. after the last position, the general estimator (the default, docs/method.md#general-estimator):
//!    [`calib::session::session_estimator`] loads every dwell's means and their honest variances into a
//!    [`ChannelEstimator`], which fits the sensor model's terms ([`Model`] of [`Term`]s: biases, scale factors,
//!    misalignments, g-sensitivity, reference offset) to every channel of every dwell by Gauss-Newton, with the
//!    moves between dwells ([`calib::moves`]) as observations of the gyro terms, and gives a [`ChannelSolution`]:
//!    the parameters with their covariance, the structural blind spots, the residuals. The paper's angle method
//!    ([`calib::angles`]: alignment of every dwell, the angles' bias solution, refinement) is the other
//!    estimator, chosen in the sequence's settings.
//!
//! On the workstation, `sinscal calibrate` runs steps 2 and 3 on a recording's rows directly, or the whole
//! path through the test rig's replay (`rig::replay`, feature `rig`: `--on host`), or the firmware itself in
//! QEMU (`--on qemu`).
#![cfg_attr(not(test), no_std)]
#![deny(missing_docs)]
#![deny(unsafe_code)]

#[cfg(all(target_os = "none", feature = "mps2-an386"))]
#[allow(unsafe_code)] // memory-mapped registers
pub mod board;
pub mod calib;
pub mod instrument;
pub mod math;
pub mod nav;
#[cfg(feature = "rig")]
pub mod rig;
pub mod run;
pub mod sensor;

pub use calib::dwell::{DwellCollector, DwellSummary, Prefilter};
pub use calib::general::{ChannelDwell, ChannelError, ChannelEstimator, ChannelSettings, ChannelSolution, Model, Term};
pub use math::linalg::{Mat3, Vec3};
pub use nav::earth::Site;
pub use nav::frames::Attitude;
pub use run::sequence::CalibrationSequence;
pub use sensor::sample::{ImuReading, ImuSample};
pub use sensor::source::ImuSource;
