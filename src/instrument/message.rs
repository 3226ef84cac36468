//! Messages of the host link: what a workstation asks of the device and what the device answers, each the
//! body of one [`link`](super::link) frame. Little-endian, fixed layouts; the frame's kind byte says which.
//!
//! A reply carries its request's sequence number and the request's kind with bit 7 set, or the kind
//! [`kind::ERROR`] with an [`ErrorCode`]. Streamed samples come unasked, with kind [`kind::SAMPLE`].

use super::wire::codes::wire_codes;

/// Kind bytes of the frames.
pub mod kind {
    /// Identify the device: firmware, IMU, record version, limits.
    pub const IDENTIFY: u8 = 0x01;
    /// Configure the calibration (site, schedule, estimator, prefilter, thresholds).
    pub const CONFIGURE: u8 = 0x02;
    /// A part of the provenance note kept with the record (what the workstation knows of the recording).
    pub const ANNOTATE: u8 = 0x03;
    /// Start the calibration sequence.
    pub const START: u8 = 0x04;
    /// Abort the calibration sequence.
    pub const ABORT: u8 = 0x05;
    /// Status and every fault counter.
    pub const STATUS: u8 = 0x06;
    /// A part of the result (the encoded outcome of the sequence).
    pub const READ_RESULT: u8 = 0x07;
    /// Store the result as the calibration record in non-volatile memory.
    pub const STORE: u8 = 0x08;
    /// A part of the stored record.
    pub const READ_RECORD: u8 = 0x09;
    /// Erase the stored record.
    pub const ERASE: u8 = 0x0A;
    /// Start or stop the stream of compensated samples.
    pub const STREAM: u8 = 0x0B;
    /// Bit set in a reply's kind.
    pub const REPLY: u8 = 0x80;
    /// A compensated sample of the stream (device to host, unasked).
    pub const SAMPLE: u8 = 0xC0;
    /// An error reply.
    pub const ERROR: u8 = 0xFF;
}

wire_codes! {
    /// Why the device refused a request (the body of an error reply: code u8, detail u32).
    pub enum ErrorCode: u8 {
        /// The frame's CRC did not match (detail: 0).
        Crc = 1,
        /// The frame's stuffing was broken or it was too short or too long (a truncated frame).
        Frame = 2,
        /// Another protocol version (detail: the version received).
        Version = 3,
        /// An unknown kind (detail: the kind).
        UnknownKind = 4,
        /// The body's length or content does not fit the kind (detail: the body's length).
        Body = 5,
        /// The configuration is not one the core can run (detail: a
        /// [`ConfigurationRefusal`](super::wire::codes::ConfigurationRefusal) code).
        Configuration = 6,
        /// Not while a calibration runs (configure, store, erase).
        Busy = 7,
        /// Start without a configuration.
        NotConfigured = 8,
        /// No result yet (read result, store).
        NoResult = 9,
        /// The record would not fit the storage slot (detail: its length in bytes; refusing a start, the largest
        /// record the run could store).
        TooLarge = 10,
        /// The flash failed (detail: 0).
        Flash = 11,
        /// Nothing is stored (read record).
        NothingStored = 12,
        /// The note is longer than the device keeps (detail: the largest length accepted).
        NoteTooLong = 13,
        /// The solution gives no usable compensation (a term beyond what the compensation accepts); nothing stored.
        NoCompensation = 14,
        /// A read (result or record) from an offset past its end (detail: its length in bytes).
        PastEnd = 15,
    }
}

impl core::fmt::Display for ErrorCode {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            ErrorCode::Crc => "frame CRC mismatch",
            ErrorCode::Frame => "malformed frame (truncated, too short or too long)",
            ErrorCode::Version => "unknown protocol version",
            ErrorCode::UnknownKind => "unknown message kind",
            ErrorCode::Body => "message body does not fit its kind",
            ErrorCode::Configuration => "configuration refused",
            ErrorCode::Busy => "busy: a calibration is running",
            ErrorCode::NotConfigured => "not configured",
            ErrorCode::NoResult => "no result",
            ErrorCode::TooLarge => "record larger than the storage slot",
            ErrorCode::Flash => "flash failure",
            ErrorCode::NothingStored => "no calibration record stored",
            ErrorCode::NoteTooLong => "note longer than the device keeps",
            ErrorCode::NoCompensation => "the solution gives no usable compensation: nothing stored",
            ErrorCode::PastEnd => "read from an offset past the end (the detail is the length)",
        })
    }
}

/// Largest part of a result or record in one reply, bytes (with its total and offset, within
/// [`MAX_BODY_BYTES`](super::link::MAX_BODY_BYTES)).
pub const MAX_CHUNK_BYTES: usize = 1024;

/// Longest provenance note the device keeps with a record, bytes.
pub const MAX_NOTE_BYTES: usize = 2048;

wire_codes! {
    /// The state of the device in a status reply.
    pub enum DeviceState: u8 {
        /// Waiting for a configuration.
        Idle = 0,
        /// Configured, not started.
        Configured = 1,
        /// The calibration sequence runs.
        Running = 2,
        /// The sequence ended with a result.
        Solved = 3,
        /// The sequence ended without a result (the result holds the failure).
        Failed = 4,
    }
}
