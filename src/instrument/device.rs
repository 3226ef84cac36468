//! The device behind the link: it answers the workstation's requests (configure, start, status, result, store,
//! read the record, erase, stream), runs the calibration sequence on the samples the data-ready interrupt
//! queued, keeps the calibration record in flash, and compensates every sample with the stored calibration.
//!
//! The same [`Device`] runs in every firmware (the board gives it the flash and moves bytes and samples) and in
//! host tests. Nothing is allocated; every request gets a reply, an error reply for a bad one, and the device
//! keeps running.

use embedded_storage::nor_flash::NorFlash;
use heapless::Vec;

use super::link::{encode_frame, Frame, FrameError, MAX_BODY_BYTES};
use super::message::{kind, DeviceState, ErrorCode, MAX_CHUNK_BYTES, MAX_NOTE_BYTES};
use super::store::{DamagedRecord, RecordInfo, RecordStore};
use super::wire::codes::{ConfigurationRefusal, ImuCode};
use super::wire::configuration::{DeviceConfiguration, MAX_DEVICE_BYTES, THRESHOLD_BYTES};
use super::wire::outcome::{encode_part, OutcomeView};
use super::wire::record::{max_record_bytes, Record, RecordHead, RECORD_HEAD_BYTES, RECORD_VERSION};
use super::wire::status::Status;
use super::wire::{Reader, Writer};
use crate::calib::angles::MAX_POSITIONS;
use crate::calib::compensation::{self, Compensation};
use crate::run::sampling::{QueueItem, SamplingStats};
use crate::run::sequence::{feed_sequence, CalibrationSequence, Event, SequenceFailure, SequenceSolution};
use crate::sensor::adis::Model;
use crate::sensor::sample::ImuSample;

/// The firmware's version, as the identify reply reports it (16 bytes, NUL-padded).
pub const FIRMWARE_VERSION: &str = concat!("sinscal ", env!("CARGO_PKG_VERSION"));

/// Counters of the link.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct LinkStats {
    /// Requests answered (with a reply or an error reply).
    pub requests: u32,
    /// Frames refused for their CRC.
    pub crc_errors: u32,
    /// Frames refused for their stuffing or length (truncated, too long).
    pub frame_errors: u32,
    /// Frames of another protocol version.
    pub version_errors: u32,
    /// Requests refused (unknown kind, bad body, refused in this state).
    pub refused: u32,
    /// Bytes lost because the receive queue was full.
    pub rx_overruns: u32,
}

/// What a request asks the board to do besides replying.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Action {
    /// Nothing more.
    None,
    /// A calibration started: feed it samples (a replay device starts its frames from the first).
    Started,
}

/// The device: configuration, sequence, record store, compensation, link counters.
pub struct Device<F: NorFlash> {
    model: Model,
    state: DeviceState,
    configuration: Vec<u8, MAX_DEVICE_BYTES>,
    configured: Option<DeviceConfiguration>,
    note: Vec<u8, MAX_NOTE_BYTES>,
    sequence: Option<CalibrationSequence>,
    run: RunCounters,
    store: RecordStore<F>,
    stored: Option<RecordInfo>,
    /// A damaged record newer than `stored`: the device fell back to an older record (or to none).
    damaged: Option<DamagedRecord>,
    compensation: Compensation,
    compensation_from_record: bool,
    streaming: bool,
    busy_hook: Option<fn()>,
    /// Link counters.
    pub link: LinkStats,
}

/// What the outcome of a calibration counts besides the sequence's own state.
#[derive(Clone, Copy, Debug, Default)]
struct RunCounters {
    /// The interrupt's counters when the calibration started and when it ended.
    sampling_at_start: SamplingStats,
    sampling_at_end: SamplingStats,
    aborted_dwells: u32,
    failure: Option<SequenceFailure>,
}

/// The outcome of the last calibration (solved or failed), as the result encoding sees it.
fn outcome_of<'a>(
    state: DeviceState,
    sequence: &'a Option<CalibrationSequence>,
    run: &RunCounters,
) -> Option<OutcomeView<'a>> {
    let sequence = sequence.as_ref()?;
    matches!(state, DeviceState::Solved | DeviceState::Failed).then(|| OutcomeView {
        sampling: run.sampling_at_end,
        aborted_dwells: run.aborted_dwells,
        failure: run.failure,
        positions: sequence.completed(),
        result: sequence.result(),
    })
}

impl<F: NorFlash> Device<F> {
    /// A device with an IMU of `model` and its record store; the stored calibration, if one is readable, is
    /// loaded and compensates every sample from now on. (Kept out of line: the sequence it builds passes through
    /// its frame once, at boot, not through the caller's for good.)
    #[inline(never)]
    pub fn new(model: Model, mut store: RecordStore<F>) -> Device<F> {
        // The store is read before the device is built, so that the device is built once, in its final place
        // (a method called on it before it is returned made the compiler build it in this frame and copy it out:
        // 66 KB of stack instead of 9 KB).
        let scan = store.scan().unwrap_or_default();
        let compensation = scan.newest.and_then(|info| compensation_of_record(&mut store, &info));
        Device {
            model,
            state: DeviceState::Idle,
            configuration: Vec::new(),
            configured: None,
            note: Vec::new(),
            // A sequence built once, here, and started again in place by every start (a second one on the
            // stack would cost tens of kilobytes); until a start it holds no result and is never reported.
            sequence: CalibrationSequence::new(
                &[crate::nav::frames::Attitude::from_degrees(0.0, 0.0, 0.0)],
                crate::nav::earth::Site::with_normal_gravity(0.0, 0.0),
                crate::run::sequence::SequenceSettings::default(),
            )
            .ok(),
            run: RunCounters::default(),
            store,
            stored: scan.newest,
            damaged: scan.damaged_newer,
            compensation: compensation.unwrap_or(Compensation::IDENTITY),
            compensation_from_record: compensation.is_some(),
            streaming: false,
            busy_hook: None,
            link: LinkStats::default(),
        }
    }

    /// Finds the newest valid record and a damaged newer one (neither when the flash cannot be read).
    fn scan_store(&mut self) {
        let scan = self.store.scan().unwrap_or_default();
        self.stored = scan.newest;
        self.damaged = scan.damaged_newer;
    }

    /// The stored record in use, if any.
    pub fn stored_record(&self) -> Option<RecordInfo> {
        self.stored
    }

    /// A damaged record newer than the one in use: the device fell back to an older record (or to none).
    pub fn damaged_record(&self) -> Option<DamagedRecord> {
        self.damaged
    }

    /// A function called between the flash operations of a store (a board feeds its watchdog there: a store
    /// erases and writes for longer than the watchdog's period).
    pub fn set_busy_hook(&mut self, hook: fn()) {
        self.busy_hook = Some(hook);
    }

    /// The state.
    pub fn state(&self) -> DeviceState {
        self.state
    }

    /// Whether the stored calibration compensates the samples (otherwise they leave uncompensated).
    pub fn compensating(&self) -> bool {
        self.compensation_from_record
    }

    /// Whether the device wants samples (a calibration runs).
    pub fn running(&self) -> bool {
        self.state == DeviceState::Running
    }

    /// The record store (and through it the flash), for a board that stops the device.
    pub fn into_store(self) -> RecordStore<F> {
        self.store
    }

    /// The compensation in use.
    pub fn compensation(&self) -> &Compensation {
        &self.compensation
    }

    /// One queued sample: compensated for the stream (returned when the stream is on), and fed raw to a running
    /// calibration. `on_event` sees the sequence's events; `sampling` is the interrupt's counters now.
    pub fn on_sample(
        &mut self,
        item: &QueueItem,
        sampling: &SamplingStats,
        mut on_event: impl FnMut(&Event),
    ) -> Option<ImuSample> {
        let compensated = match &item.reading {
            Ok(r) if self.streaming => Some(self.compensation.apply(&r.sample)),
            _ => None,
        };
        if self.state == DeviceState::Running {
            if let Some(sequence) = self.sequence.as_mut() {
                for event in feed_sequence(sequence, item).into_iter().flatten() {
                    self.on_event(&event, sampling);
                    on_event(&event);
                }
            }
        }
        compensated
    }

    /// The end of the samples (a replay's last frame): the sequence closes its last dwell and solves.
    pub fn end_of_samples(&mut self, sampling: &SamplingStats, mut on_event: impl FnMut(&Event)) {
        if self.state != DeviceState::Running {
            return;
        }
        while let Some(event) = self.sequence.as_mut().and_then(|s| s.finish()) {
            self.on_event(&event, sampling);
            on_event(&event);
        }
        if self.state == DeviceState::Running {
            // The samples ended before the last position: the sequence neither solved nor failed.
            self.run.sampling_at_end = sampling.since(&self.run.sampling_at_start);
            self.state = DeviceState::Failed;
        }
    }

    fn on_event(&mut self, event: &Event, sampling: &SamplingStats) {
        match event {
            Event::DwellAborted { .. } => self.run.aborted_dwells = self.run.aborted_dwells.saturating_add(1),
            Event::Solved => {
                self.run.sampling_at_end = sampling.since(&self.run.sampling_at_start);
                self.state = DeviceState::Solved;
            }
            Event::Failed(f) => {
                self.run.failure = Some(*f);
                self.run.sampling_at_end = sampling.since(&self.run.sampling_at_start);
                self.state = DeviceState::Failed;
            }
            _ => {}
        }
    }

    fn outcome(&self) -> Option<OutcomeView<'_>> {
        outcome_of(self.state, &self.sequence, &self.run)
    }

    /// A received frame (or why it was refused): the reply, written to `wire` ready to send (its length), and
    /// what the board must do. `sampling` is the interrupt's counters now.
    pub fn on_frame(
        &mut self,
        frame: Result<Frame<'_>, FrameError>,
        sampling: &SamplingStats,
        wire: &mut [u8],
    ) -> (usize, Action) {
        let mut body = [0u8; MAX_BODY_BYTES];
        let (seq, reply_kind, reply) = match frame {
            Err(e) => {
                let (code, detail) = match e {
                    FrameError::Crc => (ErrorCode::Crc, 0),
                    FrameError::Version(v) => (ErrorCode::Version, v as u32),
                    FrameError::TooLong | FrameError::Stuffing | FrameError::TooShort => (ErrorCode::Frame, 0),
                };
                match code {
                    ErrorCode::Crc => self.link.crc_errors = self.link.crc_errors.saturating_add(1),
                    ErrorCode::Version => self.link.version_errors = self.link.version_errors.saturating_add(1),
                    _ => self.link.frame_errors = self.link.frame_errors.saturating_add(1),
                }
                (0, kind::ERROR, Err((code, detail)))
            }
            Ok(f) => {
                self.link.requests = self.link.requests.saturating_add(1);
                (f.seq, f.kind | kind::REPLY, self.request(f.kind, f.body, sampling, &mut body))
            }
        };
        let (reply_kind, len, action) = match reply {
            Ok((len, action)) => (reply_kind, len, action),
            Err((code, detail)) => {
                if frame.is_ok() {
                    self.link.refused = self.link.refused.saturating_add(1);
                }
                let mut w = Writer::new(&mut body);
                w.u8(code as u8).u32(detail);
                (kind::ERROR, 5, Action::None)
            }
        };
        (encode_frame(reply_kind, seq, &body[..len], wire).unwrap_or(0), action)
    }
}

/// A sample for the stream, framed (kind [`kind::SAMPLE`]): rate (rad/s) and force (m/s^2), body frame,
/// compensated, as f32. Its length in `wire`.
pub fn sample_frame(sample: &ImuSample, wire: &mut [u8]) -> usize {
    let mut body = [0u8; 24];
    let mut w = Writer::new(&mut body);
    for v in sample.rate_b_radps.iter().chain(&sample.force_b_mps2) {
        w.f32(*v);
    }
    encode_frame(kind::SAMPLE, 0, &body, wire).unwrap_or(0)
}

/// The record of the last solved calibration (`outcome`), with the compensation it gives.
fn record_of<'a>(
    outcome: Option<OutcomeView<'a>>,
    configuration: &'a [u8],
    note: &'a [u8],
) -> Result<Record<'a>, (ErrorCode, u32)> {
    let outcome = outcome.filter(|o| o.result.is_some()).ok_or((ErrorCode::NoResult, 0))?;
    let compensation = match outcome.result {
        Some(SequenceSolution::Channels(c)) => {
            Compensation::from_channels(c).map_err(|_| (ErrorCode::NoCompensation, 0))?
        }
        Some(SequenceSolution::Angles(r)) => {
            Compensation::from_angles(r).map_err(|_| (ErrorCode::NoCompensation, 0))?
        }
        None => return Err((ErrorCode::NoResult, 0)),
    };
    Ok(Record::new(compensation, configuration, note, outcome))
}

/// The compensation of the record `info` (`None` if it cannot be read or decoded).
fn compensation_of_record<F: NorFlash>(store: &mut RecordStore<F>, info: &RecordInfo) -> Option<Compensation> {
    let mut head = [0u8; RECORD_HEAD_BYTES];
    store.read(info, 0, &mut head).ok()?;
    let h = RecordHead::decode(&head)?;
    let mut bytes = [0u8; compensation::ENCODED_BYTES];
    store.read(info, RECORD_HEAD_BYTES, &mut bytes).ok()?;
    Compensation::decode(bytes.get(..h.compensation_bytes as usize)?)
}

/// A reply body's length and the board's action, or the error of an error reply.
type Reply = Result<(usize, Action), (ErrorCode, u32)>;

/// A reply body of `len` bytes with no action.
fn body_of(len: Option<usize>) -> Reply {
    len.map(|n| (n, Action::None)).ok_or((ErrorCode::Body, 0))
}

impl<F: NorFlash> Device<F> {
    fn request(&mut self, k: u8, body: &[u8], sampling: &SamplingStats, out: &mut [u8]) -> Reply {
        // A body of exactly `n` bytes, or the refusal (with the body's length).
        let exact = |n: usize| if body.len() == n { Ok(()) } else { Err((ErrorCode::Body, body.len() as u32)) };
        let offset = || exact(4).map(|()| u32::from_le_bytes([body[0], body[1], body[2], body[3]]) as usize);
        match k {
            kind::IDENTIFY => exact(0).and_then(|()| self.identify(out)),
            kind::CONFIGURE => self.configure(body),
            kind::ANNOTATE => self.annotate(&mut Reader::new(body)),
            kind::START => exact(0).and_then(|()| self.start(sampling)),
            kind::ABORT => {
                exact(0)?;
                self.state = if self.configured.is_some() { DeviceState::Configured } else { DeviceState::Idle };
                Ok((0, Action::None))
            }
            kind::STATUS => exact(0).and_then(|()| self.status(sampling, out)),
            kind::READ_RESULT => self.read_result(offset()?, out),
            kind::STORE => exact(0).and_then(|()| self.store_record(out)),
            kind::READ_RECORD => self.read_record(offset()?, out),
            kind::ERASE => exact(0).and_then(|()| self.erase(out)),
            kind::STREAM => {
                exact(1)?;
                self.streaming = body[0] != 0;
                Ok((0, Action::None))
            }
            other => Err((ErrorCode::UnknownKind, other as u32)),
        }
    }

    #[inline(never)]
    fn identify(&self, out: &mut [u8]) -> Reply {
        let mut version = [0u8; 16];
        let v = FIRMWARE_VERSION.as_bytes();
        let n = v.len().min(16);
        version[..n].copy_from_slice(&v[..n]);
        let mut w = Writer::new(out);
        w.u8(super::link::PROTOCOL_VERSION).bytes(&version);
        w.u8(ImuCode::of(self.model).code());
        w.u16(RECORD_VERSION).u16(MAX_POSITIONS as u16).u16(MAX_CHUNK_BYTES as u16).u16(MAX_NOTE_BYTES as u16);
        w.u32(self.store.max_payload() as u32);
        body_of(w.written())
    }

    #[inline(never)]
    fn configure(&mut self, body: &[u8]) -> Reply {
        if self.state == DeviceState::Running {
            return Err((ErrorCode::Busy, 0));
        }
        let refused = |why: ConfigurationRefusal| Err((ErrorCode::Configuration, why.code()));
        if body.len() < THRESHOLD_BYTES || body.len() > MAX_DEVICE_BYTES {
            return refused(ConfigurationRefusal::Length);
        }
        let Ok(configured) = DeviceConfiguration::decode(body) else { return refused(ConfigurationRefusal::Content) };
        if configured.configuration.imu != self.model {
            return refused(ConfigurationRefusal::Imu);
        }
        if CalibrationSequence::check(&configured.configuration.schedule, &configured.sequence_settings()).is_err() {
            return refused(ConfigurationRefusal::Sequence);
        }
        self.configuration.clear();
        // The length is checked above against the capacity.
        let _ = self.configuration.extend_from_slice(body);
        self.configured = Some(configured);
        // The last result, if any, is no longer offered: the state says configured.
        self.state = DeviceState::Configured;
        Ok((0, Action::None))
    }

    #[inline(never)]
    fn annotate(&mut self, r: &mut Reader<'_>) -> Reply {
        let (Some(offset), Some(total)) = (r.u16(), r.u16()) else { return Err((ErrorCode::Body, 0)) };
        let part = r.rest();
        if total as usize > MAX_NOTE_BYTES {
            return Err((ErrorCode::NoteTooLong, MAX_NOTE_BYTES as u32));
        }
        if offset == 0 {
            self.note.clear();
        }
        let fits = offset as usize == self.note.len() && self.note.len() + part.len() <= total as usize;
        if !fits || self.note.extend_from_slice(part).is_err() {
            return Err((ErrorCode::Body, offset as u32));
        }
        Ok((0, Action::None))
    }

    #[inline(never)]
    fn start(&mut self, sampling: &SamplingStats) -> Reply {
        if self.state == DeviceState::Running {
            return Err((ErrorCode::Busy, 0));
        }
        let Some(configured) = &self.configured else { return Err((ErrorCode::NotConfigured, 0)) };
        // The record this run could store must fit the slot: refused now, not after the whole run.
        let c = &configured.configuration;
        let record_bytes = max_record_bytes(self.configuration.len(), self.note.len(), c.schedule.len(), c.estimator);
        if record_bytes > self.store.max_payload() {
            return Err((ErrorCode::TooLarge, record_bytes as u32));
        }
        let refused = (ErrorCode::Configuration, ConfigurationRefusal::Sequence.code());
        // The sequence built at boot, started again in place (never a second one on the stack).
        let sequence = self.sequence.as_mut().ok_or(refused)?;
        sequence.restart(&c.schedule, c.site, configured.sequence_settings()).map_err(|_| refused)?;
        self.run = RunCounters { sampling_at_start: *sampling, ..RunCounters::default() };
        self.state = DeviceState::Running;
        Ok((0, Action::Started))
    }

    #[inline(never)]
    fn status(&self, sampling: &SamplingStats, out: &mut [u8]) -> Reply {
        let (position, positions) = match (&self.sequence, &self.configured) {
            (Some(s), Some(c)) => (s.position() as u16, c.configuration.schedule.len() as u16),
            (None, Some(c)) => (0, c.configuration.schedule.len() as u16),
            _ => (0, 0),
        };
        let l = &self.link;
        let status = Status {
            state: self.state,
            position,
            positions,
            sampling: sampling.counters(),
            link: [l.requests, l.crc_errors, l.frame_errors, l.version_errors, l.refused, l.rx_overruns],
            stored: self.stored.map(|s| s.sequence),
            compensating: self.compensation_from_record,
            streaming: self.streaming,
            damaged_newer: self.damaged.map(|d| d.sequence),
        };
        body_of(status.encode(out))
    }

    #[inline(never)]
    fn read_result(&self, offset: usize, out: &mut [u8]) -> Reply {
        let outcome = self.outcome().ok_or((ErrorCode::NoResult, 0))?;
        let (head, part) = out.split_at_mut(8);
        let part = &mut part[..MAX_CHUNK_BYTES];
        let total = encode_part(&outcome, offset, part);
        if offset > total {
            return Err((ErrorCode::PastEnd, total as u32));
        }
        let n = total.saturating_sub(offset).min(MAX_CHUNK_BYTES);
        Writer::new(head).u32(total as u32).u32(offset as u32);
        Ok((8 + n, Action::None))
    }

    #[inline(never)]
    fn store_record(&mut self, out: &mut [u8]) -> Reply {
        if self.state == DeviceState::Running {
            return Err((ErrorCode::Busy, 0));
        }
        let record = record_of(outcome_of(self.state, &self.sequence, &self.run), &self.configuration, &self.note)?;
        let compensation = *record.compensation();
        let len = record.record_bytes();
        if len > self.store.max_payload() {
            return Err((ErrorCode::TooLarge, len as u32));
        }
        let hook = self.busy_hook;
        let report = self
            .store
            .store(len, |offset, chunk| {
                if let Some(h) = hook {
                    h();
                }
                record.write_part(offset, chunk);
                Ok(())
            })
            .map_err(|_| (ErrorCode::Flash, 0))?;
        self.scan_store();
        self.compensation = compensation;
        self.compensation_from_record = true;
        let mut w = Writer::new(out);
        w.u32(report.sequence).u8(report.slot).u32(report.erases).u32(len as u32);
        body_of(w.written())
    }

    #[inline(never)]
    fn read_record(&mut self, offset: usize, out: &mut [u8]) -> Reply {
        let info = self.stored.ok_or((ErrorCode::NothingStored, 0))?;
        let total = info.len;
        if offset > total {
            return Err((ErrorCode::PastEnd, total as u32));
        }
        let n = total.saturating_sub(offset).min(MAX_CHUNK_BYTES);
        let (head, part) = out.split_at_mut(8);
        self.store.read(&info, offset, &mut part[..n]).map_err(|_| (ErrorCode::Flash, 0))?;
        Writer::new(head).u32(total as u32).u32(offset as u32);
        Ok((8 + n, Action::None))
    }

    #[inline(never)]
    fn erase(&mut self, out: &mut [u8]) -> Reply {
        if self.state == DeviceState::Running {
            return Err((ErrorCode::Busy, 0));
        }
        let erases = self.store.erase_all().map_err(|_| (ErrorCode::Flash, 0))?;
        self.stored = None;
        self.damaged = None;
        self.compensation = Compensation::IDENTITY;
        self.compensation_from_record = false;
        let mut w = Writer::new(out);
        w.u32(erases);
        body_of(w.written())
    }
}
