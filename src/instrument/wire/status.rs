//! The device's status reply, defined once: the device encodes it, the workstation decodes it.
//!
//! ```text
//! status  state u8 (DeviceState), position u16, positions u16,
//!         sampling counters 10 x u32 (SamplingStats::COUNTER_NAMES), link counters 6 x u32 (requests, CRC
//!         errors, frame errors, version errors, refused, receive overruns),
//!         stored u8, its sequence u32, compensating u8, streaming u8, damaged newer u8, its sequence u32
//! ```

use super::{Reader, WireError, Writer};
use crate::instrument::message::DeviceState;

/// Sampling counters in the reply ([`crate::run::sampling::SamplingStats::counters`]).
pub const SAMPLING_COUNTERS: usize = 10;
/// Link counters in the reply.
pub const LINK_COUNTERS: usize = 6;
/// Bytes of the reply.
pub const BYTES: usize = 5 + 4 * (SAMPLING_COUNTERS + LINK_COUNTERS) + 5 + 2 + 5;

/// What the device reports of itself.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Status {
    /// State.
    pub state: DeviceState,
    /// Position being worked on (0-based).
    pub position: u16,
    /// Positions of the schedule.
    pub positions: u16,
    /// The sampling counters, in the order of [`crate::run::sampling::SamplingStats::COUNTER_NAMES`].
    pub sampling: [u32; SAMPLING_COUNTERS],
    /// Link counters: requests, CRC errors, frame errors, version errors, refused, receive overruns.
    pub link: [u32; LINK_COUNTERS],
    /// The sequence number of the stored record in use, if any.
    pub stored: Option<u32>,
    /// Whether the stored calibration compensates the samples.
    pub compensating: bool,
    /// Whether the sample stream is on.
    pub streaming: bool,
    /// The sequence number of a damaged record newer than the stored one in use (the device fell back).
    pub damaged_newer: Option<u32>,
}

impl Status {
    /// Encodes into `out`; the bytes written, `None` when `out` is shorter than [`BYTES`].
    pub fn encode(&self, out: &mut [u8]) -> Option<usize> {
        let mut w = Writer::new(out);
        w.u8(self.state as u8).u16(self.position).u16(self.positions);
        for &v in self.sampling.iter().chain(&self.link) {
            w.u32(v);
        }
        let flag = |v: Option<u32>| (u8::from(v.is_some()), v.unwrap_or(0));
        let (stored, damaged) = (flag(self.stored), flag(self.damaged_newer));
        w.u8(stored.0).u32(stored.1).u8(u8::from(self.compensating)).u8(u8::from(self.streaming));
        w.u8(damaged.0).u32(damaged.1);
        w.written()
    }

    /// Decodes a reply of exactly [`BYTES`] bytes.
    pub fn decode(bytes: &[u8]) -> Result<Status, WireError> {
        if bytes.len() != BYTES {
            return Err(WireError);
        }
        let mut r = Reader::new(bytes);
        let mut parse = || -> Option<Status> {
            let state = DeviceState::from_code(r.u8()?)?;
            let (position, positions) = (r.u16()?, r.u16()?);
            let mut sampling = [0u32; SAMPLING_COUNTERS];
            for v in sampling.iter_mut() {
                *v = r.u32()?;
            }
            let mut link = [0u32; LINK_COUNTERS];
            for v in link.iter_mut() {
                *v = r.u32()?;
            }
            let flagged = |r: &mut Reader<'_>| -> Option<Option<u32>> {
                let (has, sequence) = (r.u8()?, r.u32()?);
                Some((has != 0).then_some(sequence))
            };
            let stored = flagged(&mut r)?;
            let (compensating, streaming) = (r.u8()? != 0, r.u8()? != 0);
            let damaged_newer = flagged(&mut r)?;
            Some(Status { state, position, positions, sampling, link, stored, compensating, streaming, damaged_newer })
        };
        parse().ok_or(WireError)
    }
}
