//! Host files for the firmware under QEMU, through semihosting (target only): the command line given to
//! QEMU (`-semihosting-config ...,arg=...`) and files named on it.

use core::ffi::CStr;

use semihosting::fs::File;
use semihosting::io::{Read, Write};

use crate::rig::replay::{ByteSource, ReplayError};

/// Longest path accepted, bytes.
pub const MAX_PATH: usize = 255;

/// A path as a NUL-terminated string in a fixed buffer.
pub struct CPath {
    buf: [u8; MAX_PATH + 1],
}

impl CPath {
    /// Copies `path`; `None` if it is too long or contains a NUL.
    pub fn new(path: &str) -> Option<CPath> {
        let b = path.as_bytes();
        if b.len() > MAX_PATH || b.contains(&0) {
            return None;
        }
        let mut buf = [0u8; MAX_PATH + 1];
        buf[..b.len()].copy_from_slice(b);
        Some(CPath { buf })
    }

    /// The path as a C string.
    pub fn as_c_str(&self) -> &CStr {
        // `new` guarantees exactly one NUL, at or after the end of the path.
        CStr::from_bytes_until_nul(&self.buf).unwrap_or(c"")
    }
}

/// Argument `index` of the command line (0 = the program name), as a path.
pub fn arg_path(index: usize) -> Option<CPath> {
    let args = semihosting::experimental::env::args::<512>().ok()?;
    let arg = (&args).flatten().nth(index)?;
    CPath::new(arg)
}

/// Creates (or truncates) the file at `path` and writes `bytes`; whether it worked.
pub fn write_file(path: &CPath, bytes: &[u8]) -> bool {
    match File::create(path.as_c_str()) {
        Ok(mut f) => f.write_all(bytes).is_ok(),
        Err(_) => false,
    }
}

/// Buffered reader of a host file through semihosting.
pub struct FileSource {
    file: File,
    buf: [u8; 4096],
    start: usize,
    end: usize,
}

impl FileSource {
    /// Opens the host file at `path` for reading; `None` if it cannot be opened.
    pub fn open(path: &CPath) -> Option<FileSource> {
        let file = File::open(path.as_c_str()).ok()?;
        Some(FileSource { file, buf: [0; 4096], start: 0, end: 0 })
    }
}

impl ByteSource for FileSource {
    fn read_exact(&mut self, out: &mut [u8]) -> Result<(), ReplayError> {
        let mut done = 0;
        while done < out.len() {
            if self.start == self.end {
                self.end = self.file.read(&mut self.buf).map_err(|_| ReplayError::Read)?;
                self.start = 0;
                if self.end == 0 {
                    return Err(ReplayError::Read);
                }
            }
            let n = (self.end - self.start).min(out.len() - done);
            out[done..done + n].copy_from_slice(&self.buf[self.start..self.start + n]);
            self.start += n;
            done += n;
        }
        Ok(())
    }
}
