//! The wire formats, each defined once with its `encode` and `decode`: what the workstation, the device, the
//! replay rig and the record store exchange. Little-endian, fixed layouts, every f32 as its bit pattern, every
//! code an enum ([`codes`]).
//!
//! - [`configuration`]: the calibration's configuration (IMU, estimator, site, schedule, prefilter, dwell
//!   value, limits of rest) and the device's thresholds; the replay file's header and the configure message
//!   carry the same bytes.
//! - [`outcome`]: what a calibration produced (counters, every dwell's statistics, the failure or the
//!   solution with its covariance); a link reply, an outcome file and a record carry it.
//! - [`record`]: the calibration record kept in flash (compensation, configuration, note, outcome).
//! - [`status`]: the device's status reply (state, counters, the record in use and a damaged newer one).
//!
//! Layouts, in order (docs/device.md and docs/formats.md#replay-file describe the same):
//! ```text
//! configuration  imu u8 (ImuCode), estimator u8 (EstimatorCode), latitude_rad f32, gravity_mps2 f32,
//!                positions u16, terms u16 (the general estimator's, Model::stored_bits),
//!                prefilter u8 (PrefilterCode), dwell value u8 (DwellValueCode), passes u8,
//!                estimate reference offset u8, a_gyro f32, a_accel f32,
//!                rest limits: max | |f| - g | (m/s^2) f32, max gravity angle (rad) f32, max |rate| (rad/s) f32,
//!                pose tolerance (rad) f32,
//!                noise model: sample interval (s, 0 = none) f32, 6 channels x 7 terms f32 (Q, N, B,
//!                             Gauss-Markov sigma and time, K, R; calib::noise_model),
//!                positions x (pitch_rad f32, roll_rad f32, heading_rad f32, label u16,
//!                             flags u16: bit 0 = heading unknown)
//! thresholds     settle samples u32, dwell samples u32, fewest samples u32 (the configure message only)
//! ```
//!
//! Why hand-written and not a serialisation crate: the outcome is up to 34,408 bytes and is encoded in windows
//! (a link reply of 1 KiB, a flash page) without a buffer of the whole ([`Writer::window`]); the formats are
//! fixed little-endian layouts that stored records and replay files already use; and the encoders are a few
//! hundred bytes of flash (docs/firmware.md).

pub mod codes;
pub mod configuration;
pub mod outcome;
pub mod record;
pub mod status;

/// A wire format could not be decoded (too short, an unknown code, a value out of range) or an encoding did
/// not fit its buffer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct WireError;

impl core::fmt::Display for WireError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str("bytes that do not decode as the format (too short, an unknown code or a value out of range)")
    }
}

impl core::error::Error for WireError {}

/// Writes little-endian fields into a slice: the whole encoding from its start ([`Writer::new`]; remembers
/// whether everything fitted), or only the window of `out.len()` bytes that starts at a given offset of the
/// encoding ([`Writer::window`]; the rest is computed and dropped, so a part of a long encoding needs no
/// buffer of the whole).
pub struct Writer<'a> {
    out: &'a mut [u8],
    at: usize,
    window_start: Option<usize>,
    fits: bool,
}

impl<'a> Writer<'a> {
    /// A writer of the whole encoding into `out`.
    pub fn new(out: &'a mut [u8]) -> Writer<'a> {
        Writer { out, at: 0, window_start: None, fits: true }
    }

    /// A writer that keeps only the bytes from `start` of the encoding, as many as `out` holds.
    pub fn window(out: &'a mut [u8], start: usize) -> Writer<'a> {
        Writer { out, at: 0, window_start: Some(start), fits: true }
    }

    /// Appends bytes. (Inlined: each field's copy is then of a constant length, as a store.)
    #[inline(always)]
    pub fn bytes(&mut self, b: &[u8]) -> &mut Self {
        let end = self.at + b.len();
        match self.window_start {
            None => match self.out.get_mut(self.at..end) {
                Some(dst) => dst.copy_from_slice(b),
                None => self.fits = false,
            },
            Some(start) => {
                let (from, to) = (self.at.max(start), end.min(start + self.out.len()));
                if from < to {
                    self.out[from - start..to - start].copy_from_slice(&b[from - self.at..to - self.at]);
                }
            }
        }
        self.at = end;
        self
    }
    /// Appends a byte.
    pub fn u8(&mut self, v: u8) -> &mut Self {
        self.bytes(&[v])
    }
    /// Appends a u16.
    pub fn u16(&mut self, v: u16) -> &mut Self {
        self.bytes(&v.to_le_bytes())
    }
    /// Appends a u32.
    pub fn u32(&mut self, v: u32) -> &mut Self {
        self.bytes(&v.to_le_bytes())
    }
    /// Appends a u64 as two u32 words, the low one first.
    pub fn u64(&mut self, v: u64) -> &mut Self {
        self.u32(v as u32).u32((v >> 32) as u32)
    }
    /// Appends an f32 (its bits).
    pub fn f32(&mut self, v: f32) -> &mut Self {
        self.bytes(&v.to_bits().to_le_bytes())
    }
    /// Appends f32s.
    pub fn f32s(&mut self, v: &[f32]) -> &mut Self {
        for x in v {
            self.f32(*x);
        }
        self
    }
    /// The encoding's length so far (in a window: the whole encoding's, not the window's).
    pub fn position(&self) -> usize {
        self.at
    }
    /// The bytes written, or `None` if something did not fit (a window always fits).
    pub fn written(&self) -> Option<usize> {
        self.fits.then_some(self.at)
    }
}

/// Reads little-endian fields from bytes; `None` past their end.
pub struct Reader<'a> {
    body: &'a [u8],
}

impl<'a> Reader<'a> {
    /// A reader at the start of `body`.
    pub fn new(body: &'a [u8]) -> Reader<'a> {
        Reader { body }
    }
    /// The next `n` bytes.
    pub fn bytes(&mut self, n: usize) -> Option<&'a [u8]> {
        if self.body.len() < n {
            return None;
        }
        let (head, tail) = self.body.split_at(n);
        self.body = tail;
        Some(head)
    }
    /// The next byte.
    pub fn u8(&mut self) -> Option<u8> {
        Some(self.bytes(1)?[0])
    }
    /// The next u16.
    pub fn u16(&mut self) -> Option<u16> {
        let b = self.bytes(2)?;
        Some(u16::from_le_bytes([b[0], b[1]]))
    }
    /// The next u32.
    pub fn u32(&mut self) -> Option<u32> {
        let b = self.bytes(4)?;
        Some(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    }
    /// The next u64 (two u32 words, the low one first).
    pub fn u64(&mut self) -> Option<u64> {
        Some(self.u32()? as u64 | (self.u32()? as u64) << 32)
    }
    /// The next f32.
    pub fn f32(&mut self) -> Option<f32> {
        Some(f32::from_bits(self.u32()?))
    }
    /// The next three f32s.
    pub fn vec3(&mut self) -> Option<[f32; 3]> {
        Some([self.f32()?, self.f32()?, self.f32()?])
    }
    /// Fills `out` with f32s.
    pub fn f32s(&mut self, out: &mut [f32]) -> Option<()> {
        for x in out.iter_mut() {
            *x = self.f32()?;
        }
        Some(())
    }
    /// The bytes not yet read.
    pub fn rest(&mut self) -> &'a [u8] {
        core::mem::take(&mut self.body)
    }
    /// Whether every byte was read.
    pub fn is_empty(&self) -> bool {
        self.body.is_empty()
    }
}

#[cfg(test)]
mod writer_tests {
    use super::*;

    #[test]
    fn a_window_holds_the_same_bytes_as_the_whole() {
        let encode = |w: &mut Writer<'_>| {
            w.u8(7).u16(0x1234).u32(0xdead_beef).u64(u64::MAX - 5).f32(-1.5).f32s(&[2.0, 3.0]);
            w.position()
        };
        let mut whole = [0u8; 64];
        let n = encode(&mut Writer::new(&mut whole));
        assert_eq!(n, 1 + 2 + 4 + 8 + 4 + 8);
        for start in 0..n {
            for len in 1..=n - start {
                let mut part = [0u8; 64];
                let total = encode(&mut Writer::window(&mut part[..len], start));
                assert_eq!(total, n);
                assert_eq!(&part[..len], &whole[start..start + len], "window {start}+{len}");
            }
        }
        let mut r = Reader::new(&whole[..n]);
        assert_eq!(
            (r.u8(), r.u16(), r.u32(), r.u64(), r.f32(), r.vec3()),
            (Some(7), Some(0x1234), Some(0xdead_beef), Some(u64::MAX - 5), Some(-1.5), None)
        );
    }

    #[test]
    fn a_writer_says_when_it_does_not_fit() {
        let mut out = [0u8; 3];
        let mut w = Writer::new(&mut out);
        w.u16(1);
        assert_eq!(w.written(), Some(2));
        w.u16(2);
        assert_eq!(w.written(), None);
    }
}

#[cfg(test)]
mod tests;
