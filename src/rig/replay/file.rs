//! The replay file (a header and the frames, written by the host from a recording) and the outcome file (what
//! the firmware path produced, written back), both little-endian; the layout is in the parent module. The
//! header's configuration and the outcome are the instrument's wire formats ([`crate::instrument::wire`]).

use embedded_hal::spi;

use crate::calib::angles::MAX_POSITIONS;
use crate::instrument::wire::configuration::{Configuration, Thresholds, FIXED_BYTES, MAX_BYTES, POSITION_BYTES};
use crate::instrument::wire::{Reader, WireError, Writer};
use crate::run::sequence::{SequenceError, SequenceSettings};

/// File magic.
pub const MAGIC: [u8; 4] = *b"SSRP";
/// File version.
pub const VERSION: u16 = 6;

/// Bytes of a replay file's header with `positions` positions: magic and version, the configuration, the frame
/// count.
pub const fn replay_header_bytes(positions: usize) -> usize {
    6 + FIXED_BYTES + POSITION_BYTES * positions + 4
}

/// Errors of a replay.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum ReplayError {
    /// The source ended early or could not be read.
    Read,
    /// Not a replay file, or another version.
    Format,
    /// The sequence could not be set up.
    Sequence(SequenceError),
    /// The driver failed during initialisation.
    Init,
}

impl From<WireError> for ReplayError {
    fn from(_: WireError) -> ReplayError {
        ReplayError::Format
    }
}

impl core::fmt::Display for ReplayError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            ReplayError::Read => f.write_str("replay file ended early or could not be read"),
            ReplayError::Format => write!(f, "not a sinscal replay file (version {VERSION})"),
            ReplayError::Sequence(e) => write!(f, "calibration sequence: {e:?}"),
            ReplayError::Init => f.write_str("IMU initialisation failed"),
        }
    }
}

impl core::error::Error for ReplayError {}

impl spi::Error for ReplayError {
    fn kind(&self) -> spi::ErrorKind {
        spi::ErrorKind::Other
    }
}

/// A byte stream (a file through semihosting, or a slice on the host).
pub trait ByteSource {
    /// Fills `buf` completely or fails.
    fn read_exact(&mut self, buf: &mut [u8]) -> Result<(), ReplayError>;
}

impl ByteSource for &[u8] {
    fn read_exact(&mut self, buf: &mut [u8]) -> Result<(), ReplayError> {
        if self.len() < buf.len() {
            return Err(ReplayError::Read);
        }
        let (head, tail) = self.split_at(buf.len());
        buf.copy_from_slice(head);
        *self = tail;
        Ok(())
    }
}

/// The header of a replay file.
#[derive(Clone, Debug, PartialEq)]
pub struct ReplayHeader {
    /// What the recording asks of the calibration.
    pub configuration: Configuration,
    /// Number of frames that follow.
    pub frames: u32,
}

impl ReplayHeader {
    /// The settings of the replayed sequence: the configuration's, with [`Thresholds::REPLAY`] (no settling,
    /// dwells delimited by the table signal, as recorded).
    pub fn settings(&self) -> SequenceSettings {
        self.configuration.sequence_settings(Thresholds::REPLAY)
    }

    /// Writes the header (magic, version, configuration, frame count); [`replay_header_bytes`] long.
    pub fn encode(&self, w: &mut Writer<'_>) {
        w.bytes(&MAGIC).u16(VERSION);
        self.configuration.encode(w);
        w.u32(self.frames);
    }
}

/// Reads the header.
pub fn read_header<R: ByteSource>(source: &mut R) -> Result<ReplayHeader, ReplayError> {
    let mut magic = [0u8; 6];
    source.read_exact(&mut magic)?;
    if magic[..4] != MAGIC || u16::from_le_bytes([magic[4], magic[5]]) != VERSION {
        return Err(ReplayError::Format);
    }
    // The configuration: its fixed part says how many positions follow.
    let mut bytes = [0u8; MAX_BYTES];
    source.read_exact(&mut bytes[..FIXED_BYTES])?;
    let positions = Configuration::positions_announced(&bytes[..FIXED_BYTES]).ok_or(ReplayError::Format)?;
    let len = FIXED_BYTES + POSITION_BYTES * positions;
    source.read_exact(&mut bytes[FIXED_BYTES..len])?;
    let configuration = Configuration::decode(&mut Reader::new(&bytes[..len]))?;
    let mut n = [0u8; 4];
    source.read_exact(&mut n)?;
    Ok(ReplayHeader { configuration, frames: u32::from_le_bytes(n) })
}

const _: () = assert!(MAX_POSITIONS <= 64, "the frames' table byte holds every position");
