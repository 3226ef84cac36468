//! Host files for the firmware under QEMU, through semihosting (target only): the command line given to
//! QEMU (`-semihosting-config ...,arg=...`), files named on it, and [`HostFileFlash`], the NOR flash of the
//! calibration record kept in a host file.

use core::ffi::CStr;

use embedded_storage::nor_flash::{
    check_erase, check_read, check_write, ErrorType, NorFlash, NorFlashErrorKind, ReadNorFlash,
};
use semihosting::fs::File;
use semihosting::io::{Read, Seek, SeekFrom, Write};

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

    /// This path with `suffix` appended; `None` if that is too long or `suffix` contains a NUL.
    pub fn with_suffix(&self, suffix: &str) -> Option<CPath> {
        let len = self.buf.iter().position(|&b| b == 0)?;
        let s = suffix.as_bytes();
        if len + s.len() > MAX_PATH || s.contains(&0) {
            return None;
        }
        let mut buf = self.buf;
        buf[len..len + s.len()].copy_from_slice(s);
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

/// The QEMU stand-in for the flash that holds the calibration record (docs/storage.md#the-flash-in-qemu): a NOR
/// flash of two 16-KiB sectors whose contents live in a host file, read and written through semihosting.
/// QEMU's mps2-an386 models no flash controller (its address 0 is RAM that the image is loaded into), so
/// there is no flash to program; this keeps the record across runs of the emulator as a real flash keeps it
/// across power cycles.
///
/// NOR semantics: a write ANDs its bytes into the contents (it can only clear bits), an erase sets a sector to
/// 0xFF, offsets and lengths are checked against WRITE_SIZE, ERASE_SIZE and the capacity. A missing file, or
/// the part of the capacity past a short file's end, reads as erased; the first write or erase creates the file
/// and extends it with 0xFF to the whole capacity. Host I/O failures are `NorFlashErrorKind::Other`.
pub struct HostFileFlash {
    path: CPath,
    /// The file, opened for reading and writing, once it exists.
    file: Option<File>,
    /// Its length, bytes, when opened.
    file_len: usize,
}

/// Bytes moved per semihosting call.
const HOST_FLASH_CHUNK_BYTES: usize = 256;

/// A semihosting I/O failure as a flash error.
fn host_io<T>(r: semihosting::io::Result<T>) -> Result<T, NorFlashErrorKind> {
    r.map_err(|_| NorFlashErrorKind::Other)
}

impl HostFileFlash {
    /// Bytes per erase sector (the boards' sector size).
    pub const SECTOR_BYTES: usize = 16 * 1024;
    /// Capacity: two sectors, one per slot of the record store.
    pub const CAPACITY_BYTES: usize = 2 * Self::SECTOR_BYTES;

    /// The flash kept in the host file at `path` (opened now if it exists; created on the first write or
    /// erase).
    pub fn open(path: CPath) -> HostFileFlash {
        let mut flash = HostFileFlash { path, file: None, file_len: 0 };
        flash.open_existing();
        flash
    }

    /// Opens the file for reading and writing if it exists ("r+b"), with its length.
    fn open_existing(&mut self) {
        self.file = None;
        self.file_len = 0;
        if let Ok(file) = File::options().read(true).write(true).open(self.path.as_c_str()) {
            self.file_len = file.metadata().map_or(0, |m| m.len() as usize);
            self.file = Some(file);
        }
    }

    /// The file, created if missing and extended with erased bytes to the whole capacity.
    fn full_file(&mut self) -> Result<&mut File, NorFlashErrorKind> {
        if self.file.is_none() || self.file_len < Self::CAPACITY_BYTES {
            // Append mode ("ab") creates the file without truncating it; then it is opened "r+b" again.
            self.file = None;
            let mut append = host_io(File::options().write(true).append(true).create(true).open(self.path.as_c_str()))?;
            let mut len = host_io(append.metadata())?.len() as usize;
            let ones = [0xFFu8; HOST_FLASH_CHUNK_BYTES];
            while len < Self::CAPACITY_BYTES {
                let n = (Self::CAPACITY_BYTES - len).min(ones.len());
                host_io(append.write_all(&ones[..n]))?;
                len += n;
            }
            drop(append);
            self.open_existing();
        }
        self.file.as_mut().ok_or(NorFlashErrorKind::Other)
    }

    /// Gives the path back.
    pub fn into_path(self) -> CPath {
        self.path
    }
}

impl ErrorType for HostFileFlash {
    type Error = NorFlashErrorKind;
}

impl ReadNorFlash for HostFileFlash {
    const READ_SIZE: usize = 1;

    fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), Self::Error> {
        check_read(self, offset, bytes.len())?;
        bytes.fill(0xFF);
        let offset = offset as usize;
        let in_file = self.file_len.saturating_sub(offset).min(bytes.len());
        if let (Some(file), true) = (self.file.as_mut(), in_file > 0) {
            host_io(file.seek(SeekFrom::Start(offset as u64)))?;
            host_io(file.read_exact(&mut bytes[..in_file]))?;
        }
        Ok(())
    }

    fn capacity(&self) -> usize {
        Self::CAPACITY_BYTES
    }
}

impl NorFlash for HostFileFlash {
    const WRITE_SIZE: usize = 4;
    const ERASE_SIZE: usize = Self::SECTOR_BYTES;

    fn erase(&mut self, from: u32, to: u32) -> Result<(), Self::Error> {
        check_erase(self, from, to)?;
        let file = self.full_file()?;
        host_io(file.seek(SeekFrom::Start(u64::from(from))))?;
        let ones = [0xFFu8; HOST_FLASH_CHUNK_BYTES];
        let mut at = from as usize;
        while at < to as usize {
            let n = (to as usize - at).min(ones.len());
            host_io(file.write_all(&ones[..n]))?;
            at += n;
        }
        Ok(())
    }

    fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), Self::Error> {
        check_write(self, offset, bytes.len())?;
        let file = self.full_file()?;
        let mut buf = [0u8; HOST_FLASH_CHUNK_BYTES];
        for (k, chunk) in bytes.chunks(HOST_FLASH_CHUNK_BYTES).enumerate() {
            let at = u64::from(offset) + (k * HOST_FLASH_CHUNK_BYTES) as u64;
            let old = &mut buf[..chunk.len()];
            host_io(file.seek(SeekFrom::Start(at)))?;
            host_io(file.read_exact(old))?;
            // NOR programming clears bits only.
            for (o, &b) in old.iter_mut().zip(chunk) {
                *o &= b;
            }
            host_io(file.seek(SeekFrom::Start(at)))?;
            host_io(file.write_all(old))?;
        }
        Ok(())
    }
}
