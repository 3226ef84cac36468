//! Files in and out: the recording reader and writer, the importers of measured data sets, the
//! calibration model to compensate with, standard output. The lowest host layer: it imports nothing else of
//! the crate (the writers of the calibration result, the analysis and the study reports and the figures live
//! next to what they write). Formats: docs/formats.md.

pub mod calibration_model;
pub mod dwell_tally;
pub mod error;
pub mod import;
pub mod noise_file;
pub mod recording;

use std::io::Write as _;
use std::path::Path;

/// Arcseconds per radian.
pub const ARCSEC_PER_RAD: f64 = 206_264.806_247_096_36;

/// Standard output could not be written: the reader closed it (a broken pipe: `sinscal ... | head`), or
/// it failed (a full disk, `/dev/full`). `main` ends quietly with status 0 on a broken pipe (the reader
/// wanted no more) and with the error and status 1 otherwise; nothing panics.
#[derive(Debug)]
pub struct StdoutError(pub std::io::Error);

impl std::fmt::Display for StdoutError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "writing to standard output: {}", self.0)
    }
}

impl std::error::Error for StdoutError {}

/// Writes `text` to standard output (and flushes it), with a [`StdoutError`] when that fails.
pub fn out(text: &str) -> anyhow::Result<()> {
    let mut stdout = std::io::stdout().lock();
    stdout.write_all(text.as_bytes()).and_then(|()| stdout.flush()).map_err(|e| StdoutError(e).into())
}

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
    /// Removes the file, or the directory and what it holds when one was made at the path (the device link's
    /// socket directory): a directory left behind, its name made again by a later process of the same id,
    /// held a stale socket that the next bind refused ("Address already in use").
    fn drop(&mut self) {
        if self.0.is_dir() {
            let _ = std::fs::remove_dir_all(&self.0);
        } else {
            let _ = std::fs::remove_file(&self.0);
        }
    }
}
