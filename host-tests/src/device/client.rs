//! The workstation's end of the device link: requests and their replies over any byte stream (a QEMU serial
//! socket, a serial port), with the core's own frame and message code.

use std::io::{Read, Write};
use std::time::{Duration, Instant};

use sinscal::instrument::link::{encode_frame, FrameReceiver, MAX_WIRE_BYTES};
use sinscal::instrument::message::{kind, ErrorCode, MAX_CHUNK_BYTES, MAX_NOTE_BYTES};
use sinscal::instrument::wire::Reader;

/// A failure of the link or a refusal of the device.
#[derive(Debug, thiserror::Error)]
pub enum LinkError {
    /// The stream failed.
    #[error("link: {0}")]
    Io(#[from] std::io::Error),
    /// No reply in time.
    #[error("link: no reply from the device within {0:?} (request kind {1:#04x})")]
    Timeout(Duration, u8),
    /// The device refused the request.
    #[error("the device refused {what}: {code} (detail {detail})")]
    Refused {
        /// What was asked.
        what: &'static str,
        /// Why.
        code: ErrorCode,
        /// The code's detail.
        detail: u32,
    },
    /// A reply that does not follow the protocol.
    #[error("link: malformed reply to {0}")]
    Malformed(&'static str),
    /// The record a run could store is larger than the device's storage slot: refused before the run starts.
    #[error(
        "refused before the run starts: the record of this run could take {len} bytes ({positions} positions, a note \
         of {note} bytes), the device's storage slot holds {max}: fewer positions, or shorter labels"
    )]
    RecordTooLarge {
        /// The largest record the run could store, bytes.
        len: usize,
        /// The slot's limit, bytes.
        max: usize,
        /// Positions of the schedule.
        positions: usize,
        /// The note's length, bytes.
        note: usize,
    },
    /// The host built a provenance note longer than the device keeps: refused before it is sent.
    #[error(
        "the provenance note is {len} bytes, the device keeps at most {max} (its calibration options and one line \
         per position: fewer positions, or shorter labels)"
    )]
    NoteTooLong {
        /// The note's length, bytes.
        len: usize,
        /// The device's limit, bytes.
        max: usize,
    },
}

/// The device's identity.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Identity {
    /// Link protocol version.
    pub protocol: u8,
    /// Firmware version text.
    pub firmware: String,
    /// IMU model code (0 ADIS16470, 1 ADIS16505-2).
    pub imu_model: u8,
    /// Calibration record version.
    pub record_version: u16,
    /// Most positions of a schedule.
    pub max_positions: u16,
    /// Largest part of a result or record per reply, bytes.
    pub max_chunk: u16,
    /// Longest provenance note, bytes.
    pub max_note: u16,
    /// Largest record the storage slot holds, bytes.
    pub max_record_bytes: u32,
}

/// What the device reports of itself (the core's typed status reply).
pub use sinscal::instrument::wire::status::Status;

/// What a store did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Stored {
    /// Sequence number of the new record.
    pub sequence: u32,
    /// Slot it went to.
    pub slot: u8,
    /// Sector erases of this store.
    pub erases: u32,
    /// Bytes of the record.
    pub bytes: u32,
}

/// A link to a device over a byte stream.
pub struct Client<T> {
    io: T,
    receiver: FrameReceiver,
    seq: u8,
    /// How long a reply may take.
    pub timeout: Duration,
    /// Streamed samples received while waiting for replies: rate (rad/s) and force (m/s^2), body frame.
    pub samples: Vec<[f32; 6]>,
}

impl<T: Read + Write> Client<T> {
    /// A client on `io`, which must return from `read` within a short time (a read timeout) when nothing comes.
    pub fn new(io: T) -> Client<T> {
        Client { io, receiver: FrameReceiver::new(), seq: 0, timeout: Duration::from_secs(20), samples: Vec::new() }
    }

    /// Sends raw bytes (tests of bad frames).
    pub fn send_raw(&mut self, bytes: &[u8]) -> Result<(), LinkError> {
        self.io.write_all(bytes)?;
        Ok(self.io.flush()?)
    }

    /// Sends a request and waits for its reply: the reply's body, or the device's refusal.
    pub fn request(&mut self, what: &'static str, k: u8, body: &[u8]) -> Result<Vec<u8>, LinkError> {
        self.seq = self.seq.wrapping_add(1);
        let mut wire = vec![0u8; MAX_WIRE_BYTES];
        let n = encode_frame(k, self.seq, body, &mut wire).ok_or(LinkError::Malformed(what))?;
        self.send_raw(&wire[..n])?;
        let (reply_kind, body) = self.reply(what, k, Some(self.seq))?;
        if reply_kind != k | kind::REPLY {
            return Err(LinkError::Malformed(what));
        }
        Ok(body)
    }

    /// Waits for the next reply (with sequence number `seq`, or any); streamed samples are kept. An error
    /// reply becomes [`LinkError::Refused`].
    pub fn reply(&mut self, what: &'static str, k: u8, seq: Option<u8>) -> Result<(u8, Vec<u8>), LinkError> {
        let deadline = Instant::now() + self.timeout;
        let mut buf = [0u8; 4096];
        loop {
            if Instant::now() > deadline {
                return Err(LinkError::Timeout(self.timeout, k));
            }
            let n = match self.io.read(&mut buf) {
                Ok(0) => return Err(LinkError::Io(std::io::ErrorKind::UnexpectedEof.into())),
                Ok(n) => n,
                Err(e) if matches!(e.kind(), std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut) => continue,
                Err(e) => return Err(e.into()),
            };
            for &b in &buf[..n] {
                let Some(Ok(frame)) = self.receiver.push(b) else { continue };
                if frame.kind == kind::SAMPLE {
                    let mut r = Reader::new(frame.body);
                    let v: Option<Vec<f32>> = (0..6).map(|_| r.f32()).collect();
                    if let Some(v) = v {
                        self.samples.push([v[0], v[1], v[2], v[3], v[4], v[5]]);
                    }
                    continue;
                }
                if seq.is_some_and(|s| s != frame.seq) && frame.kind != kind::ERROR {
                    continue;
                }
                if frame.kind == kind::ERROR {
                    let mut r = Reader::new(frame.body);
                    let (code, detail) = (r.u8().and_then(ErrorCode::from_code), r.u32());
                    return match (code, detail) {
                        (Some(code), Some(detail)) => Err(LinkError::Refused { what, code, detail }),
                        _ => Err(LinkError::Malformed(what)),
                    };
                }
                return Ok((frame.kind, frame.body.to_vec()));
            }
        }
    }

    /// Identify.
    pub fn identify(&mut self) -> Result<Identity, LinkError> {
        let body = self.request("identify", kind::IDENTIFY, &[])?;
        let mut r = Reader::new(&body);
        let parse = |r: &mut Reader<'_>| -> Option<Identity> {
            let protocol = r.u8()?;
            let text = r.bytes(16)?;
            let firmware = String::from_utf8_lossy(text).trim_end_matches('\0').to_string();
            Some(Identity {
                protocol,
                firmware,
                imu_model: r.u8()?,
                record_version: r.u16()?,
                max_positions: r.u16()?,
                max_chunk: r.u16()?,
                max_note: r.u16()?,
                max_record_bytes: r.u32()?,
            })
        };
        parse(&mut r).ok_or(LinkError::Malformed("identify"))
    }

    /// Identify, asked again once a second for at most `total` while the device may still be booting: a request
    /// that arrives before its serial port is enabled is lost (no reply), and one whose first bytes are lost is
    /// refused as a broken frame. Any other answer ends the wait. The reply timeout is restored afterwards.
    pub fn identify_after_boot(&mut self, total: Duration) -> Result<Identity, LinkError> {
        let timeout = self.timeout;
        self.timeout = Duration::from_secs(1);
        let deadline = Instant::now() + total;
        let identity = loop {
            let answer = self.identify();
            let booting = matches!(
                answer,
                Err(LinkError::Timeout(..) | LinkError::Refused { code: ErrorCode::Frame | ErrorCode::Crc, .. })
            );
            if !booting || Instant::now() >= deadline {
                break answer;
            }
        };
        self.timeout = timeout;
        identity
    }

    /// Status.
    pub fn status(&mut self) -> Result<Status, LinkError> {
        let body = self.request("status", kind::STATUS, &[])?;
        Status::decode(&body).map_err(|_| LinkError::Malformed("status"))
    }

    /// Configure with a configuration body.
    pub fn configure(&mut self, body: &[u8]) -> Result<(), LinkError> {
        self.request("the configuration", kind::CONFIGURE, body).map(drop)
    }

    /// Sends the provenance note in parts.
    pub fn annotate(&mut self, note: &[u8]) -> Result<(), LinkError> {
        if note.len() > MAX_NOTE_BYTES {
            return Err(LinkError::NoteTooLong { len: note.len(), max: MAX_NOTE_BYTES });
        }
        let total = note.len() as u16;
        let mut offset = 0;
        loop {
            let part = &note[offset..(offset + MAX_CHUNK_BYTES).min(note.len())];
            let mut body = Vec::with_capacity(4 + part.len());
            body.extend_from_slice(&(offset as u16).to_le_bytes());
            body.extend_from_slice(&total.to_le_bytes());
            body.extend_from_slice(part);
            self.request("the note", kind::ANNOTATE, &body)?;
            offset += part.len();
            if offset >= note.len() {
                return Ok(());
            }
        }
    }

    /// Reads a result or a record in parts (`k` = READ_RESULT or READ_RECORD).
    pub fn read_all(&mut self, what: &'static str, k: u8) -> Result<Vec<u8>, LinkError> {
        let mut all = Vec::new();
        loop {
            let body = self.request(what, k, &(all.len() as u32).to_le_bytes())?;
            let mut r = Reader::new(&body);
            let (total, offset) = (r.u32(), r.u32());
            let part = r.rest();
            match (total, offset) {
                (Some(total), Some(offset)) if offset as usize == all.len() && !part.is_empty() => {
                    all.extend_from_slice(part);
                    if all.len() >= total as usize {
                        all.truncate(total as usize);
                        return Ok(all);
                    }
                }
                (Some(0), Some(0)) => return Ok(all),
                _ => return Err(LinkError::Malformed(what)),
            }
        }
    }

    /// Store the result as the calibration record.
    pub fn store(&mut self) -> Result<Stored, LinkError> {
        let body = self.request("store", kind::STORE, &[])?;
        let mut r = Reader::new(&body);
        let parse =
            |r: &mut Reader<'_>| Some(Stored { sequence: r.u32()?, slot: r.u8()?, erases: r.u32()?, bytes: r.u32()? });
        parse(&mut r).ok_or(LinkError::Malformed("store"))
    }

    /// Erase the stored record; the sector erases.
    pub fn erase(&mut self) -> Result<u32, LinkError> {
        let body = self.request("erase", kind::ERASE, &[])?;
        Reader::new(&body).u32().ok_or(LinkError::Malformed("erase"))
    }
}
