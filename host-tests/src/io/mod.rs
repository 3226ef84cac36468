//! Files in and out: the recording reader and writer, the importers of measured data sets, the
//! calibration result (JSON and summary), the analysis report and the figures. Formats: docs/formats.md.

pub mod analysis_report;
pub mod calibration_model;
pub mod calibration_result;
pub mod dwell_tally;
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

/// A file in the system's temporary folder, unique to this process and call, removed when dropped.
#[derive(Debug)]
pub struct ScratchFile(std::path::PathBuf);

impl ScratchFile {
    /// A new scratch file name ending in `name` (nothing is created yet).
    pub fn new(name: &str) -> ScratchFile {
        static NEXT: std::sync::atomic::AtomicU32 = std::sync::atomic::AtomicU32::new(0);
        let n = NEXT.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        ScratchFile(std::env::temp_dir().join(format!("sinscal-{}-{n}-{name}", std::process::id())))
    }

    /// Its path.
    pub fn path(&self) -> &Path {
        &self.0
    }
}

impl Drop for ScratchFile {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.0);
    }
}
