//! Replay of a recorded sequence through the firmware path: device frames, driver, sampling queue,
//! calibration sequence, core. The same [`run_replay`] runs in the firmware under QEMU (frames read
//! through semihosting) and on the host (`sinscal calibrate --on host`), so both see identical values.
//!
//! File format (little-endian), written by the host from a recording:
//! ```text
//! magic "SSRP", version u16 = 3
//! the configuration (crate::instrument::wire::configuration: IMU, estimator, site, schedule, prefilter,
//!                    dwell value, limits of rest)
//! frames u32
//! frames x (table u8: 0 = moving, k = in position k of the list (1-based), 255 = in position without a
//!           number (`TABLE_IN_POSITION`, as a GPIO reports it); burst bytes of the model)
//! ```
//! The outcome file is the outcome's wire encoding (crate::instrument::wire::outcome).
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
