//! Host side of sinscal: the `sinscal` command line's building blocks. Every calibration formula is the
//! no_std core's (`sinscal` crate); this crate reads and writes files, simulates (labelled as
//! simulation), analyses, and reports.
//!
//! | module | what |
//! |---|---|
//! | [`cmd`] | one file per subcommand: its arguments, its run and its human summary |
//! | [`io`] | recordings, importers, calibration JSON and summary, the calibration model to compensate with, reports and figures |
//! | [`model`] | the sensor model and effect catalogue, the scenario simulator, synthetic data with known truth |
//! | [`stats`] | least squares and likelihoods, noise statistics |
//! | [`calibration`] | a recording through the core: directly, through the firmware path on the host, in QEMU; Monte Carlo |
//! | [`analysis`] | `sinscal analyze`: the base model, the catalogue's candidates, the verdict; hidden-effect trials |
//! | [`study`] | `sinscal study`: a measured data set against a simulation of it |
//! | [`navigation`] | `sinscal align`: the coarse alignment of every dwell; `sinscal navigate`: the strapdown engine and the static navigation check |
#![deny(missing_docs)]

pub mod analysis;
pub mod calibration;
pub mod cmd;
pub mod device;
pub mod fuzz;
pub mod io;
pub mod model;
pub mod navigation;
pub mod plot;
pub mod stats;
pub mod study;
