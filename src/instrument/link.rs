//! Frames of the host link: what travels over the serial line between a workstation and the device.
//!
//! A frame is `version u8, kind u8, seq u8, body (0 to MAX_BODY_BYTES bytes), CRC-32 u32 LE` (the CRC of everything
//! before it), sent COBS-encoded (consistent-overhead byte stuffing: no zero byte inside) and ended by one zero
//! byte. A receiver that loses bytes, or starts in the middle of a frame, is in step again at the next zero: a
//! truncated frame costs that frame only. Frames are bounded ([`MAX_FRAME_BYTES`]); nothing is allocated.

use super::crc::Crc32;

/// Version of the link protocol (the first byte of every frame).
pub const PROTOCOL_VERSION: u8 = 1;
/// Longest body of a frame, bytes.
pub const MAX_BODY_BYTES: usize = 1312;
/// Bytes of a frame around its body: version, kind, seq, CRC.
pub const FRAME_OVERHEAD_BYTES: usize = 3 + 4;
/// Longest frame before stuffing, bytes.
pub const MAX_FRAME_BYTES: usize = MAX_BODY_BYTES + FRAME_OVERHEAD_BYTES;
/// Longest frame on the wire: COBS adds one byte per 254 and one more, then the zero delimiter.
pub const MAX_WIRE_BYTES: usize = MAX_FRAME_BYTES + MAX_FRAME_BYTES / 254 + 2;

/// Why a received frame was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum FrameError {
    /// Longer than [`MAX_WIRE_BYTES`] before its delimiter (the rest up to the delimiter was dropped).
    TooLong,
    /// The COBS stuffing is broken (a truncated frame, or noise).
    Stuffing,
    /// Shorter than a frame's fixed fields.
    TooShort,
    /// The CRC does not match.
    Crc,
    /// Another protocol version.
    Version(u8),
}

impl core::fmt::Display for FrameError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            FrameError::TooLong => write!(f, "frame longer than {MAX_WIRE_BYTES} bytes"),
            FrameError::Stuffing => f.write_str("broken frame stuffing (truncated frame?)"),
            FrameError::TooShort => f.write_str("frame shorter than its fixed fields"),
            FrameError::Crc => f.write_str("frame CRC mismatch"),
            FrameError::Version(v) => write!(f, "link protocol version {v}, this end speaks {PROTOCOL_VERSION}"),
        }
    }
}

/// A frame received and checked.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Frame<'a> {
    /// Message kind.
    pub kind: u8,
    /// Sequence number: a reply carries its request's.
    pub seq: u8,
    /// The body.
    pub body: &'a [u8],
}

/// COBS encoder writing into a slice; `None` once the slice is full.
struct Stuffer<'a> {
    out: &'a mut [u8],
    code_at: usize,
    at: usize,
}

impl Stuffer<'_> {
    fn new(out: &mut [u8]) -> Option<Stuffer<'_>> {
        if out.is_empty() {
            return None;
        }
        Some(Stuffer { out, code_at: 0, at: 1 })
    }

    fn close_block(&mut self) -> Option<()> {
        *self.out.get_mut(self.code_at)? = (self.at - self.code_at) as u8;
        self.code_at = self.at;
        self.at += 1;
        (self.at <= self.out.len()).then_some(())
    }

    fn push(&mut self, byte: u8) -> Option<()> {
        if byte == 0 {
            return self.close_block();
        }
        *self.out.get_mut(self.at)? = byte;
        self.at += 1;
        if self.at - self.code_at == 255 {
            self.close_block()?;
        }
        Some(())
    }

    /// Closes the last block and appends the delimiter; the length on the wire.
    fn finish(self) -> Option<usize> {
        *self.out.get_mut(self.code_at)? = (self.at - self.code_at) as u8;
        *self.out.get_mut(self.at)? = 0;
        Some(self.at + 1)
    }
}

/// Encodes a frame of `kind`, `seq` and `body` for the wire (stuffed, with its delimiter) into `out`; the
/// number of bytes, or `None` if the body is longer than [`MAX_BODY_BYTES`] or `out` is too short ([`MAX_WIRE_BYTES`] is
/// always enough).
pub fn encode_frame(kind: u8, seq: u8, body: &[u8], out: &mut [u8]) -> Option<usize> {
    if body.len() > MAX_BODY_BYTES {
        return None;
    }
    let head = [PROTOCOL_VERSION, kind, seq];
    let mut crc = Crc32::new();
    crc.update(&head);
    crc.update(body);
    let mut s = Stuffer::new(out)?;
    for &b in head.iter().chain(body).chain(&crc.finish().to_le_bytes()) {
        s.push(b)?;
    }
    s.finish()
}

/// Undoes COBS in place on `buf` (one frame without its delimiter); the decoded length.
fn unstuff(buf: &mut [u8]) -> Result<usize, FrameError> {
    let (mut read, mut write) = (0, 0);
    while read < buf.len() {
        let code = buf[read] as usize;
        if code == 0 || read + code > buf.len() {
            return Err(FrameError::Stuffing);
        }
        read += 1;
        for _ in 1..code {
            buf[write] = buf[read];
            write += 1;
            read += 1;
        }
        if code < 255 && read < buf.len() {
            buf[write] = 0;
            write += 1;
        }
    }
    Ok(write)
}

/// Checks a decoded frame: length, CRC, version.
fn check(frame: &[u8]) -> Result<Frame<'_>, FrameError> {
    if frame.len() < FRAME_OVERHEAD_BYTES {
        return Err(FrameError::TooShort);
    }
    let (content, crc) = frame.split_at(frame.len() - 4);
    let mut c = Crc32::new();
    c.update(content);
    if c.finish().to_le_bytes() != crc {
        return Err(FrameError::Crc);
    }
    if content[0] != PROTOCOL_VERSION {
        return Err(FrameError::Version(content[0]));
    }
    Ok(Frame { kind: content[1], seq: content[2], body: &content[3..] })
}

/// Collects received bytes into frames: [`FrameReceiver::push`] each byte as it arrives; at a delimiter it
/// returns the frame, checked, or why it was refused. Empty frames (two delimiters in a row) are skipped.
pub struct FrameReceiver {
    buf: [u8; MAX_WIRE_BYTES],
    len: usize,
    overflow: bool,
}

impl Default for FrameReceiver {
    fn default() -> Self {
        FrameReceiver::new()
    }
}

impl FrameReceiver {
    /// A receiver waiting for the first frame.
    pub const fn new() -> FrameReceiver {
        FrameReceiver { buf: [0; MAX_WIRE_BYTES], len: 0, overflow: false }
    }

    /// Takes one byte; at a frame's end, the frame or its error.
    pub fn push(&mut self, byte: u8) -> Option<Result<Frame<'_>, FrameError>> {
        if byte != 0 {
            match self.buf.get_mut(self.len) {
                Some(slot) => {
                    *slot = byte;
                    self.len += 1;
                }
                None => self.overflow = true,
            }
            return None;
        }
        let (len, overflow) = (self.len, self.overflow);
        self.len = 0;
        self.overflow = false;
        if overflow {
            return Some(Err(FrameError::TooLong));
        }
        if len == 0 {
            return None;
        }
        Some(unstuff(&mut self.buf[..len]).and_then(|n| check(&self.buf[..n])))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A received frame: kind, seq, body.
    type Received = Result<(u8, u8, std::vec::Vec<u8>), FrameError>;

    fn receive_all(wire: &[u8]) -> std::vec::Vec<Received> {
        let mut rx = FrameReceiver::new();
        let mut got = std::vec::Vec::new();
        for &b in wire {
            if let Some(r) = rx.push(b) {
                got.push(r.map(|f| (f.kind, f.seq, f.body.to_vec())));
            }
        }
        got
    }

    #[test]
    fn frames_of_every_length_and_content_round_trip() {
        let mut wire = [0u8; MAX_WIRE_BYTES];
        for len in [0, 1, 2, 250, 251, 252, 253, 254, 255, 508, 509, 1000, MAX_BODY_BYTES] {
            for fill in [0u8, 1, 0xFF] {
                let body: std::vec::Vec<u8> =
                    (0..len).map(|i| if fill == 1 { (i * 7 % 256) as u8 } else { fill }).collect();
                let n = encode_frame(0x42, 7, &body, &mut wire).expect("fits MAX_WIRE_BYTES");
                assert!(n <= MAX_WIRE_BYTES);
                assert_eq!(wire[n - 1], 0, "delimiter");
                assert!(!wire[..n - 1].contains(&0), "no zero inside a stuffed frame");
                assert_eq!(receive_all(&wire[..n]), [Ok((0x42, 7, body.clone()))], "length {len}, fill {fill}");
            }
        }
        assert_eq!(encode_frame(1, 1, &[0; MAX_BODY_BYTES + 1], &mut wire), None);
        assert_eq!(encode_frame(1, 1, &[0; 10], &mut wire[..12]), None, "output too short");
    }

    #[test]
    fn a_truncated_or_corrupt_frame_costs_that_frame_only() {
        let mut a = [0u8; MAX_WIRE_BYTES];
        let mut b = [0u8; MAX_WIRE_BYTES];
        let na = encode_frame(1, 1, b"first frame", &mut a).unwrap();
        let nb = encode_frame(2, 2, b"second", &mut b).unwrap();
        // Truncated: the first frame loses its last 5 bytes and its delimiter; the next delimiter ends it.
        for cut in 1..na - 1 {
            let mut wire = a[..cut].to_vec();
            wire.extend_from_slice(&b[..nb]);
            let got = receive_all(&wire);
            assert_eq!(got.len(), 1, "cut at {cut}: one frame (the merged bytes) refused or, never, accepted");
            assert!(got[0].is_err(), "cut at {cut}: the merged bytes must be refused, got {:?}", got[0]);
            // The following frame arrives intact.
            let mut wire2 = a[..cut].to_vec();
            wire2.push(0);
            wire2.extend_from_slice(&b[..nb]);
            let got2 = receive_all(&wire2);
            assert_eq!(got2.last(), Some(&Ok((2, 2, b"second".to_vec()))), "cut at {cut}");
        }
        // One flipped bit anywhere before the delimiter: refused.
        for i in 0..na - 1 {
            for bit in 0..8 {
                let mut wire = a[..na].to_vec();
                wire[i] ^= 1 << bit;
                for r in receive_all(&wire) {
                    assert!(r.is_err(), "byte {i} bit {bit} flipped and accepted");
                }
            }
        }
    }

    #[test]
    fn refusals_name_their_reason() {
        let mut wire = [0u8; MAX_WIRE_BYTES];
        let n = encode_frame(3, 9, b"x", &mut wire).unwrap();
        // Another protocol version with a correct CRC.
        let mut raw = [PROTOCOL_VERSION + 1, 3, 9, b'x', 0, 0, 0, 0];
        let crc = super::super::crc::crc32(&raw[..4]);
        raw[4..].copy_from_slice(&crc.to_le_bytes());
        let mut s = Stuffer::new(&mut wire[n..]).unwrap();
        raw.iter().for_each(|&b| s.push(b).unwrap());
        let m = s.finish().unwrap();
        assert_eq!(receive_all(&wire[n..n + m]), [Err(FrameError::Version(PROTOCOL_VERSION + 1))]);
        assert_eq!(receive_all(&[1, 0]), [Err(FrameError::TooShort)]);
        assert_eq!(receive_all(&[5, 1, 0]), [Err(FrameError::Stuffing)]);
        let long = [1u8; MAX_WIRE_BYTES + 10];
        let mut wire_long = long.to_vec();
        wire_long.push(0);
        wire_long.extend_from_slice(&wire[..n]);
        assert_eq!(receive_all(&wire_long), [Err(FrameError::TooLong), Ok((3, 9, b"x".to_vec()))]);
        assert_eq!(receive_all(&[0, 0, 0]), []);
    }
}
