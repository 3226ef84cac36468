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

use std::path::Path;

/// Whether `a` and `b` are the same existing file (also through links or different spellings of the path).
pub fn same_file(a: &Path, b: &Path) -> bool {
    if !b.exists() || !a.exists() {
        return false;
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt as _;
        if let (Ok(ma), Ok(mb)) = (std::fs::metadata(a), std::fs::metadata(b)) {
            return ma.dev() == mb.dev() && ma.ino() == mb.ino();
        }
    }
    matches!((std::fs::canonicalize(a), std::fs::canonicalize(b)), (Ok(x), Ok(y)) if x == y)
}
