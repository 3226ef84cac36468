//! Files in and out: the recording reader and writer, the importers of measured data sets, the
//! calibration result (JSON and summary), the analysis report and the figures. Formats: docs/formats.md.

pub mod analysis_report;
pub mod calibration_model;
pub mod calibration_result;
pub mod error;
pub mod import;
pub mod plot;
pub mod recording;
pub mod study_report;
