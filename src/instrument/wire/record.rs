//! The calibration record: what the device stores in flash after a calibration, and reads on every boot.
//!
//! Layout (little-endian), version [`RECORD_VERSION`]:
//! ```text
//! record version u16, compensation bytes u16, configuration bytes u16, note bytes u16, outcome bytes u32
//! compensation   the model that compensates every sample (calib::compensation's encoding), read at boot
//! configuration  the configure message's body: sensor, site, schedule, estimator, prefilter, thresholds
//! note           the provenance the workstation sent (what it knows of the recording), kept verbatim
//! outcome        the calibration's outcome: counters, every dwell's statistics, the solution with its
//!                covariance ([`super::outcome`])
//! ```
//! The store ([`crate::instrument::store`]) adds its own header (sequence number, length, CRC) around it. The record is
//! written in parts as the store asks for them; nothing holds the whole of it.

use super::outcome::{encode_part, OutcomeView};
use crate::calib::compensation::{self, Compensation};

/// Version of the record layout (2: a dwell's spikes counted, no prefilter start term).
pub const RECORD_VERSION: u16 = 4;
/// Bytes of the record's head.
pub const RECORD_HEAD_BYTES: usize = 12;

/// The head of a record: its version and the length of each part.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RecordHead {
    /// Bytes of the compensation.
    pub compensation_bytes: u16,
    /// Bytes of the configuration.
    pub configuration_bytes: u16,
    /// Bytes of the note.
    pub note_bytes: u16,
    /// Bytes of the outcome.
    pub outcome_bytes: u32,
}

impl RecordHead {
    /// The head's bytes.
    pub fn encode(&self) -> [u8; RECORD_HEAD_BYTES] {
        let mut b = [0u8; RECORD_HEAD_BYTES];
        b[0..2].copy_from_slice(&RECORD_VERSION.to_le_bytes());
        b[2..4].copy_from_slice(&self.compensation_bytes.to_le_bytes());
        b[4..6].copy_from_slice(&self.configuration_bytes.to_le_bytes());
        b[6..8].copy_from_slice(&self.note_bytes.to_le_bytes());
        b[8..12].copy_from_slice(&self.outcome_bytes.to_le_bytes());
        b
    }

    /// The head of a record's first bytes; `None` for another version or a compensation of another size.
    pub fn decode(b: &[u8]) -> Option<RecordHead> {
        let u16_at = |i: usize| Some(u16::from_le_bytes([*b.get(i)?, *b.get(i + 1)?]));
        if u16_at(0)? != RECORD_VERSION {
            return None;
        }
        let head = RecordHead {
            compensation_bytes: u16_at(2)?,
            configuration_bytes: u16_at(4)?,
            note_bytes: u16_at(6)?,
            outcome_bytes: u32::from_le_bytes(b.get(8..12)?.try_into().ok()?),
        };
        (head.compensation_bytes as usize == compensation::ENCODED_BYTES).then_some(head)
    }

    /// Where each part starts and its length: compensation, configuration, note, outcome.
    pub fn parts(&self) -> [(usize, usize); 4] {
        let c = RECORD_HEAD_BYTES;
        let k = c + self.compensation_bytes as usize;
        let n = k + self.configuration_bytes as usize;
        let o = n + self.note_bytes as usize;
        [
            (c, self.compensation_bytes as usize),
            (k, self.configuration_bytes as usize),
            (n, self.note_bytes as usize),
            (o, self.outcome_bytes as usize),
        ]
    }

    /// The record's length, bytes.
    pub fn record_bytes(&self) -> usize {
        let [.., (o, len)] = self.parts();
        o + len
    }
}

/// The largest record a run can store, bytes: its head, compensation, configuration (`configuration_bytes`),
/// note (`note_bytes`) and the largest outcome of `positions` positions solved by `estimator`. A device refuses
/// to start a run whose record could pass its storage slot, before the run rather than after it.
pub const fn max_record_bytes(
    configuration_bytes: usize,
    note_bytes: usize,
    positions: usize,
    estimator: super::codes::EstimatorCode,
) -> usize {
    RECORD_HEAD_BYTES
        + compensation::ENCODED_BYTES
        + configuration_bytes
        + note_bytes
        + super::outcome::max_bytes_for(positions, estimator)
}

/// A record to store, from its parts.
pub struct Record<'a> {
    compensation: Compensation,
    configuration: &'a [u8],
    note: &'a [u8],
    outcome: OutcomeView<'a>,
    head: RecordHead,
}

impl<'a> Record<'a> {
    /// The record of these parts (the outcome's encoded length is computed once, here).
    pub fn new(
        compensation: Compensation,
        configuration: &'a [u8],
        note: &'a [u8],
        outcome: OutcomeView<'a>,
    ) -> Record<'a> {
        let head = RecordHead {
            compensation_bytes: compensation::ENCODED_BYTES as u16,
            configuration_bytes: configuration.len() as u16,
            note_bytes: note.len() as u16,
            outcome_bytes: encode_part(&outcome, 0, &mut []) as u32,
        };
        Record { compensation, configuration, note, outcome, head }
    }

    /// The compensation the record gives.
    pub fn compensation(&self) -> &Compensation {
        &self.compensation
    }

    /// The head.
    pub fn head(&self) -> RecordHead {
        self.head
    }

    /// The record's length, bytes.
    pub fn record_bytes(&self) -> usize {
        self.head.record_bytes()
    }

    /// Writes the record's bytes from `offset` into `out` (as many as fit, up to the record's end).
    pub fn write_part(&self, offset: usize, out: &mut [u8]) {
        let head = self.head;
        let mut compensation = [0u8; compensation::ENCODED_BYTES];
        self.compensation.encode(&mut compensation);
        let [(c, _), (k, _), (n, _), (o, _)] = head.parts();
        let fixed: [(usize, &[u8]); 4] =
            [(0, &head.encode()), (c, &compensation), (k, self.configuration), (n, self.note)];
        for (start, bytes) in fixed {
            copy_overlap(start, bytes, offset, out);
        }
        if offset + out.len() > o {
            let (skip, from) = if offset >= o { (0, offset - o) } else { (o - offset, 0) };
            encode_part(&self.outcome, from, &mut out[skip..]);
        }
    }
}

/// Copies the part of `bytes` (at `start` in the record) that falls into the window `out` at `offset`.
fn copy_overlap(start: usize, bytes: &[u8], offset: usize, out: &mut [u8]) {
    let from = start.max(offset);
    let to = (start + bytes.len()).min(offset + out.len());
    if from < to {
        out[from - offset..to - offset].copy_from_slice(&bytes[from - start..to - start]);
    }
}
