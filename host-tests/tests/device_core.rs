//! The core's `Device` on the host, without QEMU: every request and refusal in a fixed order (configure during a
//! run is refused every time, not only when the emulator is slow enough), the result and the record through the
//! same frames the firmware sends, compensation from the stored record at the next "boot", and the stream.

use embedded_storage::nor_flash::{ErrorType, NorFlash, NorFlashErrorKind, ReadNorFlash};
use sinscal::instrument::device::Device;
use sinscal::instrument::link::{encode_frame, Frame, FrameReceiver, MAX_WIRE_BYTES};
use sinscal::instrument::message::{kind, DeviceState, ErrorCode};
use sinscal::instrument::store::RecordStore;
use sinscal::instrument::wire::Reader;
use sinscal::rig::replay::{read_header, ReplayDevice};
use sinscal::run::sampling::{on_data_ready, process_next, QueueItem, SamplingStats, QUEUE_SLOTS};
use sinscal::sensor::adis::{Adis, Model, BURST32_LEN};
use sinscal_host::calibration::Options;
use sinscal_host::device::configuration_body;
use sinscal_host::model::synth::Scenario;

/// Two 16 KiB sectors of RAM with NOR semantics (a write clears bits).
#[derive(Clone)]
struct RamFlash(Vec<u8>);

impl ErrorType for RamFlash {
    type Error = NorFlashErrorKind;
}

impl ReadNorFlash for RamFlash {
    const READ_SIZE: usize = 1;
    fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), Self::Error> {
        let at = offset as usize;
        bytes.copy_from_slice(self.0.get(at..at + bytes.len()).ok_or(NorFlashErrorKind::OutOfBounds)?);
        Ok(())
    }
    fn capacity(&self) -> usize {
        self.0.len()
    }
}

impl NorFlash for RamFlash {
    const WRITE_SIZE: usize = 4;
    const ERASE_SIZE: usize = 16 * 1024;
    fn erase(&mut self, from: u32, to: u32) -> Result<(), Self::Error> {
        self.0[from as usize..to as usize].fill(0xFF);
        Ok(())
    }
    fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), Self::Error> {
        let at = offset as usize;
        for (d, s) in self.0[at..at + bytes.len()].iter_mut().zip(bytes) {
            *d &= *s;
        }
        Ok(())
    }
}

/// The one frame on `wire`, received and checked: kind, seq, body.
fn receive(wire: &[u8]) -> (u8, u8, Vec<u8>) {
    let mut rx = FrameReceiver::new();
    for &b in wire {
        if let Some(f) = rx.push(b) {
            let f = f.unwrap();
            return (f.kind, f.seq, f.body.to_vec());
        }
    }
    panic!("no frame on the wire");
}

/// A device on a RAM flash, and a workstation's end of the frames.
struct Bench {
    device: Device<RamFlash>,
    seq: u8,
    stats: SamplingStats,
}

impl Bench {
    fn boot(flash: RamFlash) -> Bench {
        let store = RecordStore::new(flash, 16 * 1024).unwrap();
        Bench { device: Device::new(Model::Adis16505_2, store), seq: 0, stats: SamplingStats::default() }
    }

    /// A request through the frame encoding, and the device's reply decoded: (kind, body).
    fn ask(&mut self, k: u8, body: &[u8]) -> (u8, Vec<u8>) {
        self.seq = self.seq.wrapping_add(1);
        let mut wire = vec![0u8; MAX_WIRE_BYTES];
        let n = encode_frame(k, self.seq, body, &mut wire).unwrap();
        let (rk, rs, rb) = receive(&wire[..n]);
        let mut reply = vec![0u8; MAX_WIRE_BYTES];
        let (m, _) = self.device.on_frame(Ok(Frame { kind: rk, seq: rs, body: &rb }), &self.stats, &mut reply);
        let (fk, fs, fb) = receive(&reply[..m]);
        assert!(fk == kind::ERROR || fs == self.seq, "a reply carries its request's sequence number");
        (fk, fb)
    }

    fn ok(&mut self, k: u8, body: &[u8]) -> Vec<u8> {
        let (rk, b) = self.ask(k, body);
        assert_eq!(rk, k | kind::REPLY, "request {k:#04x} refused: {:?}", Reader::new(&b).u8());
        b
    }

    fn refused(&mut self, k: u8, body: &[u8]) -> ErrorCode {
        let (rk, b) = self.ask(k, body);
        assert_eq!(rk, kind::ERROR, "request {k:#04x} accepted");
        ErrorCode::from_code(b[0]).unwrap()
    }

    fn state(&mut self) -> DeviceState {
        DeviceState::from_code(self.ok(kind::STATUS, &[])[0]).unwrap()
    }

    fn read_all(&mut self, k: u8) -> Vec<u8> {
        let mut all = Vec::new();
        loop {
            let b = self.ok(k, &(all.len() as u32).to_le_bytes());
            let total = u32::from_le_bytes(b[0..4].try_into().unwrap()) as usize;
            all.extend_from_slice(&b[8..]);
            if all.len() >= total {
                return all;
            }
        }
    }

    /// Feeds the replay's frames, as the device firmware does (one frame, then the queue emptied); the
    /// compensated samples the stream would send.
    fn feed(&mut self, replay: &[u8], frames: usize) -> Vec<[f32; 6]> {
        let header = read_header(&mut &replay[..]).unwrap();
        let start = sinscal::rig::replay::replay_header_bytes(header.configuration.schedule.len());
        let mut imu = Adis::new(ReplayDevice::new(Model::Adis16505_2), Model::Adis16505_2);
        imu.init(&mut sinscal::rig::replay::NoDelay).unwrap();
        let mut queue: heapless::spsc::Queue<QueueItem, QUEUE_SLOTS> = heapless::spsc::Queue::new();
        let (mut producer, mut consumer) = queue.split();
        let mut streamed = Vec::new();
        let record = 1 + BURST32_LEN;
        for k in 0..frames.min(header.frames as usize) {
            let frame = &replay[start + k * record..start + (k + 1) * record];
            imu.spi_mut().load_frame(&frame[1..]);
            on_data_ready(&mut imu, &mut producer, &mut self.stats, frame[0]);
            let stats = self.stats;
            while let Some(out) = process_next(&mut consumer, |item| self.device.on_sample(item, &stats, |_| {})) {
                if let Some(s) = out {
                    let [r, f] = [s.rate_b_radps, s.force_b_mps2];
                    streamed.push([r[0], r[1], r[2], f[0], f[1], f[2]]);
                }
            }
        }
        if frames >= header.frames as usize {
            let stats = self.stats;
            self.device.end_of_samples(&stats, |_| {});
        }
        streamed
    }
}

#[test]
fn every_request_and_refusal_in_order_then_the_record_at_the_next_boot() {
    let rec = Scenario { dwell_s: 30.0, ..Scenario::example() }.recording(5, "example.csv");
    let (replay, _) = sinscal_host::calibration::firmware_path::replay_file(&rec, &Options::default()).unwrap();
    let header_len = sinscal::rig::replay::replay_header_bytes(6);
    let config = configuration_body(&replay[..header_len]).unwrap();
    let mut b = Bench::boot(RamFlash(vec![0xFF; 32 * 1024]));
    println!(
        "memory: Device {} bytes, of which the calibration sequence {} bytes; the general estimator {} and its \
         solution {} bytes (size_of on the host)",
        std::mem::size_of::<Device<RamFlash>>(),
        std::mem::size_of::<Option<sinscal::CalibrationSequence>>(),
        std::mem::size_of::<sinscal::calib::general::ChannelEstimator>(),
        std::mem::size_of::<sinscal::calib::general::ChannelSolution>()
    );
    assert_eq!(b.state(), DeviceState::Idle);
    assert_eq!(b.refused(kind::START, &[]), ErrorCode::NotConfigured);
    assert_eq!(b.refused(kind::STORE, &[]), ErrorCode::NoResult);
    assert_eq!(b.refused(kind::READ_RECORD, &0u32.to_le_bytes()), ErrorCode::NothingStored);
    assert_eq!(b.refused(kind::CONFIGURE, &config[..config.len() - 1]), ErrorCode::Configuration);
    assert_eq!(b.refused(0x55, &[]), ErrorCode::UnknownKind);
    b.ok(kind::CONFIGURE, &config);
    let note = br#"{"what":"a note"}"#;
    let mut annotate = vec![0, 0];
    annotate.extend_from_slice(&(note.len() as u16).to_le_bytes());
    annotate.extend_from_slice(note);
    b.ok(kind::ANNOTATE, &annotate);
    b.ok(kind::START, &[]);
    assert_eq!(b.state(), DeviceState::Running);
    // During the run: configure, start, store and erase are refused, every time.
    assert_eq!(b.refused(kind::CONFIGURE, &config), ErrorCode::Busy);
    assert_eq!(b.refused(kind::START, &[]), ErrorCode::Busy);
    assert_eq!(b.refused(kind::STORE, &[]), ErrorCode::Busy);
    assert_eq!(b.refused(kind::ERASE, &[]), ErrorCode::Busy);
    assert_eq!(b.refused(kind::READ_RESULT, &0u32.to_le_bytes()), ErrorCode::NoResult);
    b.feed(&replay, usize::MAX);
    assert_eq!(b.state(), DeviceState::Solved);
    let result = b.read_all(kind::READ_RESULT);
    // The same bytes as the replay's outcome on the host path (every counter, every dwell, the solution).
    let host = sinscal::rig::replay::run_replay(&replay[..], |_| {}).unwrap();
    let mut expected = vec![0u8; sinscal::instrument::wire::outcome::MAX_BYTES];
    let n = host.encode(&mut expected).unwrap();
    assert_eq!(result, &expected[..n], "the device's result is the host replay's outcome, byte for byte");
    let stored = b.ok(kind::STORE, &[]);
    let erases = u32::from_le_bytes(stored[5..9].try_into().unwrap());
    let bytes = u32::from_le_bytes(stored[9..13].try_into().unwrap());
    println!("store: record of {bytes} bytes, {erases} sector erase(s)");
    assert_eq!(erases, 1);
    let record = b.read_all(kind::READ_RECORD);
    assert_eq!(record.len(), bytes as usize);
    // Past the end: refused as such (the detail is the length), not as a flash fault; at the end, an empty part.
    let (k, past) = b.ask(kind::READ_RECORD, &(bytes + 1).to_le_bytes());
    assert_eq!((k, ErrorCode::from_code(past[0])), (kind::ERROR, Some(ErrorCode::PastEnd)));
    assert_eq!(u32::from_le_bytes(past[1..5].try_into().unwrap()), bytes);
    assert_eq!(b.ok(kind::READ_RECORD, &bytes.to_le_bytes()).len(), 8);
    let (k, past) = b.ask(kind::READ_RESULT, &u32::MAX.to_le_bytes());
    assert_eq!((k, ErrorCode::from_code(past[0])), (kind::ERROR, Some(ErrorCode::PastEnd)));
    // A second calibration on the same device (the sequence started again in place): the same result.
    b.ok(kind::CONFIGURE, &config);
    assert_eq!(b.refused(kind::READ_RESULT, &0u32.to_le_bytes()), ErrorCode::NoResult, "configure drops the result");
    b.ok(kind::START, &[]);
    b.feed(&replay, usize::MAX);
    // The counters are those since the start; the rest is the same run again.
    let second = b.read_all(kind::READ_RESULT);
    assert!(second == expected[..n], "the second run differs from the first ({} and {} bytes)", second.len(), n);
    let parts = sinscal_host::device::split_record(&record).unwrap();
    assert_eq!((parts.configuration, parts.note, parts.outcome), (&config[..], &note[..], &expected[..n]));
    // The raw samples: a device without a record streams them as measured.
    let mut raw_device = Bench::boot(RamFlash(vec![0xFF; 32 * 1024]));
    raw_device.ok(kind::STREAM, &[1]);
    let raw = raw_device.feed(&replay, 200);
    // The next boot on the same flash: the record is found and compensates the stream.
    let mut again = Bench::boot(b.device.into_store().release());
    let status = again.ok(kind::STATUS, &[]);
    let tail = &status[status.len() - 12..];
    assert_eq!(
        (tail[0], u32::from_le_bytes(tail[1..5].try_into().unwrap()), tail[5], tail[7]),
        (1, 1, 1, 0),
        "stored, seq 1, compensating, no damaged newer record"
    );
    again.ok(kind::STREAM, &[1]);
    let streamed = again.feed(&replay, 200);
    assert_eq!(streamed.len(), 200);
    // The stream is the raw samples compensated with the record's compensation, bit for bit.
    let compensation = sinscal::calib::compensation::Compensation::decode(parts.compensation).unwrap();
    assert_eq!(again.device.compensation(), &compensation);
    assert_ne!(compensation, sinscal::calib::compensation::Compensation::IDENTITY);
    for (c, r) in streamed.iter().zip(&raw) {
        let sample = sinscal::ImuSample { rate_b_radps: [r[0], r[1], r[2]], force_b_mps2: [r[3], r[4], r[5]] };
        let expected = compensation.apply(&sample);
        let e = [expected.rate_b_radps, expected.force_b_mps2].concat();
        assert_eq!(c.map(f32::to_bits).to_vec(), e.iter().map(|x| x.to_bits()).collect::<Vec<_>>());
    }
    assert_ne!(streamed[0], raw[0], "the compensation changes the samples");
    // Erase: nothing stored, no compensation.
    let erased = again.ok(kind::ERASE, &[]);
    assert_eq!(u32::from_le_bytes(erased[..4].try_into().unwrap()), 2);
    assert_eq!(again.refused(kind::READ_RECORD, &0u32.to_le_bytes()), ErrorCode::NothingStored);
    assert!(!again.device.compensating());
}

/// A schedule whose record could not fit the storage slot is refused at the start, with the largest record the
/// run could store as the detail, not after the whole run; the same schedule with the general estimator's
/// smallest configuration that fits starts.
#[test]
fn a_run_whose_record_could_not_fit_the_slot_is_refused_before_it_starts() {
    use sinscal::instrument::wire::configuration::DeviceConfiguration;
    use sinscal::instrument::wire::record::max_record_bytes;
    let rec = Scenario { dwell_s: 30.0, ..Scenario::example() }.recording(5, "example.csv");
    let (replay, _) = sinscal_host::calibration::firmware_path::replay_file(&rec, &Options::default()).unwrap();
    let config = configuration_body(&replay[..sinscal::rig::replay::replay_header_bytes(6)]).unwrap();
    let mut configured = DeviceConfiguration::decode(&config).unwrap();
    // 24 positions: the six poses four times over.
    let (poses, labels) = (configured.configuration.schedule.clone(), configured.configuration.labels.clone());
    for k in 1..4 {
        for (p, l) in poses.iter().zip(&labels) {
            configured.configuration.schedule.push(*p).unwrap();
            configured.configuration.labels.push(l + 10 * k).unwrap();
        }
    }
    let mut long = vec![0u8; sinscal::instrument::wire::configuration::MAX_DEVICE_BYTES];
    let mut w = sinscal::instrument::wire::Writer::new(&mut long);
    configured.encode(&mut w);
    let n = w.written().unwrap();
    long.truncate(n);
    let mut b = Bench::boot(RamFlash(vec![0xFF; 32 * 1024]));
    b.ok(kind::CONFIGURE, &long);
    let c = &configured.configuration;
    let bound = max_record_bytes(long.len(), 0, 24, c.estimator);
    assert!(bound > 16 * 1024 - 20, "{bound}");
    let (k, body) = b.ask(kind::START, &[]);
    assert_eq!(k, kind::ERROR);
    assert_eq!(ErrorCode::from_code(body[0]), Some(ErrorCode::TooLarge));
    assert_eq!(u32::from_le_bytes(body[1..5].try_into().unwrap()) as usize, bound, "the detail is the bound");
    assert_eq!(b.state(), DeviceState::Configured, "nothing started");
    // The six positions fit, and start.
    b.ok(kind::CONFIGURE, &config);
    b.ok(kind::START, &[]);
    assert_eq!(b.state(), DeviceState::Running);
}
