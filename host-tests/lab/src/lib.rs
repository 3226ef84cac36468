//! The sinscal laboratory: campaigns that measure the product (`sinscal-host`) and the core (`sinscal`), not
//! part of the `sinscal` command line. Everything here is SIMULATION or a replay of measured data with known
//! planted truth; the product's library never names this crate (tests/repository.rs checks it).
//!
//! | module | what |
//! |---|---|
//! | [`hidden`] | hidden-effect trials: a simulated Table 1 session with one effect of the catalogue hidden, through `analyze` |
//! | [`planted`] | the same trials in the measured noise of a real recording |
//! | [`own_poses`] | planted effects in the three measured data sets with their own poses and time base, at 3, 5 and 10 standard errors |
//! | [`bound`] | the Cramer-Rao bound of a calibration from its dwell means under coloured noise |
//! | [`rotation_mc`] | the rotation Monte Carlo: the general estimator with moves against its bound |
//! | [`compare`] | estimator comparisons: the general estimator against the paper's angle method on the same runs |
//! | [`fuzz`] | the fuzz harness: seeds and readers for the stable mutation fuzzer and the cargo-fuzz targets (host-tests/fuzz/) |
#![deny(missing_docs)]

pub mod bound;
pub mod compare;
pub mod fuzz;
pub mod hidden;
pub mod own_poses;
pub mod planted;
pub mod rotation_mc;
