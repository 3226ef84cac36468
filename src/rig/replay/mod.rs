//! Replay of a recorded sequence through the firmware path: device frames, driver, sampling queue,
//! calibration sequence, core. The same [`run_replay`] runs in the firmware under QEMU (frames read
//! through semihosting) and on the host (`sinscal calibrate --on host`), so both see identical values.
//!
//! File format (little-endian), written by the host from a recording:
//! ```text
//! magic "SSRP", version u16 = 3, model u8 (0 = ADIS16470, 1 = ADIS16505-2),
//! estimator u8 (0 = the angle method, 1 = the general estimator, 2 = the general estimator without gyros)
//! latitude_rad f32, gravity_mps2 f32, positions u16, terms u16 (the general estimator's, bit i = Term::ALL[i])
//! prefilter u8 (0 = none, 1 = HMM/KF with the paper's Q and R), dwell value u8 (0 = mean, 1 = settled),
//! passes u8, estimate reference offset u8, a_gyro f32, a_accel f32
//! the limits of rest of the sequence's checks: max | |f| - g | (m/s^2) f32, max gravity angle (rad) f32,
//! max |rate| (rad/s) f32
//! positions x (pitch_rad f32, roll_rad f32, heading_rad f32, label u16, flags u16: bit 0 = heading unknown)
//! frames u32
//! frames x (table u8: 0 = moving, k = in position k of the list (1-based), 255 = in position without a
//!           number (`TABLE_IN_POSITION`, as a GPIO reports it); burst bytes of the model)
//! ```
//!
//! Three parts: [`file`](mod@file) (the replay file and the outcome file: header, frames, encoding), [`device`] (the
//! emulated ADIS on the SPI bus that serves the recorded frames to the real driver) and [`run`] (the whole
//! firmware path over a replay file).

pub mod device;
pub mod file;
pub mod run;

pub use device::*;
pub use file::*;
pub use run::*;
