//! Host side of sinscal: the `sinscal` command line's building blocks. Every calibration formula is the
//! no_std core's (`sinscal` crate); this crate reads and writes files, simulates (labelled as
//! simulation), analyses, and reports.
//!
//! The product only: the laboratory (trial campaigns, rotation Monte Carlo, bounds, estimator comparisons,
//! the fuzz harness) is the crate `sinscal-lab` (host-tests/lab/). The modules in layer order, lowest first;
//! a module imports only the layers below it (tests/repository.rs checks this):
//!
//! | layer | module | what |
//! |---|---|---|
//! | 0 | [`io`] | recordings, importers, the calibration model to compensate with, standard output |
//! | 1 | [`model`] | the sensor model and effect catalogue, the scenario simulator, synthetic data with known truth |
//! | 1 | [`stats`] | least squares and likelihoods, noise statistics |
//! | 2 | [`calibration`] | a recording through the core: directly, through the firmware path on the host, in QEMU; the calibration result (JSON, summary); the Monte Carlo of `sinscal montecarlo` |
//! | 3 | [`navigation`] | `sinscal align`: the coarse alignment of every dwell; `sinscal navigate`: the strapdown engine and the static navigation check |
//! | 3 | [`device`] | `sinscal device`: the calibration firmware as an instrument, over its serial link (in QEMU) |
//! | 4 | [`plot`] | figures (PNG): the navigation check, the axes the reports share |
//! | 5 | [`analysis`] | `sinscal analyze`: the base model, the catalogue's candidates, the verdict, the report |
//! | 5 | [`study`] | `sinscal study`: a measured data set against a simulation of it, the report |
//! | 6 | [`cmd`] | one file per subcommand: its arguments, its run and its human summary |
#![deny(missing_docs)]

pub mod analysis;
pub mod calibration;
pub mod cmd;
pub mod device;
pub mod io;
pub mod model;
pub mod navigation;
pub mod plot;
pub mod stats;
pub mod study;
