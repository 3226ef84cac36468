//! Host side of sinscal: the `sinscal` command line's building blocks. Every calibration formula is the
//! no_std core's (`sinscal` crate); this crate reads and writes files, simulates (labelled as
//! simulation), and reports.
#![deny(missing_docs)]

pub mod analysis_report;
pub mod analyze;
pub mod calibrate;
pub mod error;
pub mod hidden;
pub mod import;
pub mod linfit;
pub mod montecarlo;
pub mod navcheck;
pub mod navigate;
pub mod noise;
pub mod output;
pub mod plot;
pub mod qemu;
pub mod recording;
pub mod replayfile;
pub mod simulate;
pub mod study;
pub mod synth;
