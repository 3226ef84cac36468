//! The firmware path on the host: replay file -> replay SPI device -> ADIS driver -> sampling queue ->
//! calibration sequence -> core. SIMULATION data with known truth; faults and motion injected into the
//! device frames to see that the sequence reports them instead of using them.

use sinscal::rig::replay::{read_header, run_replay};
use sinscal::run::sequence::{AbortReason, Event, SequenceFailure};
use sinscal::sensor::adis::{decode_burst, encode_burst, Model, BURST32_LEN};
use sinscal_host::calibration::firmware_path::{calibrate_on_host, replay_file};
use sinscal_host::calibration::{calibrate, Options};
use sinscal_host::io::recording::Recording;
use sinscal_host::model::synth::{Scenario, DEG_PER_HOUR, MICRO_G};

fn example(seconds: f64) -> Recording {
    Scenario { dwell_s: seconds, ..Scenario::example() }.recording(4, "example.csv")
}

/// Offset of frame k's record in a replay file.
fn frame_offset(file: &[u8], k: usize) -> usize {
    let header = read_header(&mut &file[..]).unwrap();
    let header_len = sinscal::rig::replay::replay_header_bytes(header.configuration.schedule.len());
    header_len + k * (1 + BURST32_LEN)
}

#[test]
fn replay_matches_the_direct_calibration_to_the_device_quantisation() {
    let rec = example(60.0);
    let direct = calibrate(&rec, &Options::angles()).unwrap();
    let replayed = calibrate_on_host(&rec, &Options::angles()).unwrap();
    let s = replayed.sampling.unwrap();
    assert_eq!((s.events as usize, s.readings as usize), (rec.rows.len(), rec.rows.len()));
    assert_eq!(s.faults() + s.queue_full + s.missed_samples, 0);
    // The JSON lists every fault counter: bus, checksum, stalled counter, status flag, dead bus.
    let json = serde_json::to_value(sinscal_host::calibration::result::CalibrationJson::new(&replayed)).unwrap();
    assert_eq!(json["sampling"]["faults"], serde_json::json!([0, 0, 0, 0, 0]));
    assert_eq!(json["sampling"]["readings"].as_u64(), Some(rec.rows.len() as u64));
    for (a, b) in direct.positions.iter().zip(&replayed.positions) {
        assert_eq!(a.summary.samples, b.summary.samples);
    }
    // The ADIS16505-2's 32-bit LSB is 6.7e-9 rad/s and 3.7e-8 m/s^2; averaged over a dwell the difference
    // is far below the standard errors.
    for i in 0..3 {
        let (d, r) = (
            direct.solution.unwrap().gyro_bias_b_radps[i].unwrap(),
            replayed.solution.unwrap().gyro_bias_b_radps[i].unwrap(),
        );
        assert!((d.value - r.value).abs() < 0.02 * d.std_error, "gyro {i}");
        assert!((d.value - r.value).abs() < 1e-4 * DEG_PER_HOUR as f32);
        let (d, r) = (
            direct.solution.unwrap().accel_bias_b_mps2[i].unwrap(),
            replayed.solution.unwrap().accel_bias_b_mps2[i].unwrap(),
        );
        assert!((d.value - r.value).abs() < 0.02 * d.std_error, "accel {i}");
        assert!((d.value - r.value).abs() < 0.05 * MICRO_G as f32);
    }
}

/// The example with the headings of positions 2 and 5 removed from every row.
fn without_headings(mut rec: Recording) -> Recording {
    for row in rec.rows.iter_mut().filter(|r| r.pos == 2 || r.pos == 5) {
        row.heading_deg = None;
    }
    rec
}

#[test]
fn general_estimator_on_the_firmware_path_matches_the_direct_one() {
    let rec = example(60.0);
    let full = Options { model: sinscal::calib::general::Model::FULL, ..Options::default() };
    for (rec, options) in
        [(rec.clone(), Options::default()), (without_headings(rec.clone()), Options::default()), (rec, full)]
    {
        let direct = calibrate(&rec, &options).unwrap();
        let replayed = calibrate_on_host(&rec, &options).unwrap();
        let (d, r) = (direct.channels.as_ref().unwrap(), replayed.channels.as_ref().unwrap());
        assert_eq!((d.observable, d.unobservable, d.dwells), (r.observable, r.unobservable, r.dwells));
        // The device's 32-bit LSB (6.7e-9 rad/s, 3.7e-8 m/s^2) moves every estimate by far less than its
        // standard error.
        let mut compared = 0;
        for i in 0..sinscal::calib::general::PARAMETERS {
            if let (Some((dv, ds)), Some((rv, _))) = (d.estimate(i), r.estimate(i)) {
                assert!(
                    (dv - rv).abs() < 0.02 * ds,
                    "{}: {dv} vs {rv} (std {ds})",
                    sinscal::calib::general::parameter_name(i)
                );
                compared += 1;
            }
        }
        assert!(compared >= 8 && compared == d.observable.count_ones(), "{compared} parameters compared");
        for k in [1, 4] {
            if rec.rows.iter().any(|row| row.pos == k as u32 + 1 && row.heading_deg.is_none()) {
                assert!(r.heading_std_rad[k] > 0.0, "position {} heading estimated", k + 1);
                assert!((d.heading_rad[k] - r.heading_rad[k]).abs() < 0.02 * d.heading_std_rad[k]);
            }
        }
        assert_eq!(replayed.options.method, sinscal_host::calibration::Method::Channels);
    }
}

/// The capacity of the calibration sequence: 64 positions (the six of Table 1 at eleven headings, less two),
/// 3-s dwells. SIMULATION. The firmware path solves them all, as the direct path does, and the outcome file
/// holds them.
#[test]
fn sixty_four_positions_fit_the_firmware_path() {
    let capacity = sinscal::calib::angles::MAX_POSITIONS;
    assert_eq!(capacity, sinscal::calib::general::MAX_DWELLS);
    let positions_deg: Vec<[f64; 3]> = (0..capacity)
        .map(|k| {
            let [p, r, h] = sinscal_host::model::synth::TABLE1_DEG[k % 6];
            [p, r, h + 30.0 * (k / 6) as f64]
        })
        .collect();
    let rec = Scenario { dwell_s: 3.0, positions_deg, ..Scenario::example() }.recording(9, "64.csv");
    let direct = calibrate(&rec, &Options::default()).unwrap();
    let replayed = calibrate_on_host(&rec, &Options::default()).unwrap();
    let (d, r) = (direct.channels.as_ref().unwrap(), replayed.channels.as_ref().unwrap());
    assert_eq!((d.dwells, r.dwells), (capacity, capacity));
    assert_eq!(replayed.positions.len(), capacity);
    for i in 0..sinscal::calib::general::PARAMETERS {
        if let (Some((dv, ds)), Some((rv, _))) = (d.estimate(i), r.estimate(i)) {
            assert!((dv - rv).abs() < 0.02 * ds, "{}", sinscal::calib::general::parameter_name(i));
        }
    }
    // One more position is refused with the limit named.
    let mut positions_deg = Scenario::example().positions_deg;
    positions_deg.extend((0..capacity - 5).map(|k| [0.0, 0.0, k as f64]));
    let rec = Scenario { dwell_s: 1.0, positions_deg, ..Scenario::example() }.recording(9, "65.csv");
    let e = calibrate_on_host(&rec, &Options::default()).unwrap_err().to_string();
    assert!(e.contains("more than 64"), "{e}");
}

#[test]
fn corrupted_frames_are_counted_and_the_dwell_survives_a_few() {
    let rec = example(20.0);
    let (mut file, _) = replay_file(&rec, &Options::angles()).unwrap();
    // Row 300 is in dwell 1 (after 200 settle rows): flip a byte (checksum error); row 310: repeat the
    // previous counter (stalled); row 320: set DIAG_STAT bit 1 (data path overrun) with a valid checksum.
    let at = frame_offset(&file, 300) + 1 + 6;
    file[at] ^= 0x40;
    let prev = frame_offset(&file, 309);
    let stalled = frame_offset(&file, 310);
    let copy: Vec<u8> = file[prev + 1..prev + 1 + BURST32_LEN].to_vec();
    file[stalled + 1..stalled + 1 + BURST32_LEN].copy_from_slice(&copy);
    let flagged = frame_offset(&file, 320) + 1;
    let mut burst = decode_burst::<()>(Model::Adis16505_2, &file[flagged..flagged + BURST32_LEN]).unwrap();
    burst.diag_stat = 0x0002;
    let mut bytes = [0u8; BURST32_LEN];
    encode_burst(Model::Adis16505_2, &burst, &mut bytes);
    file[flagged..flagged + BURST32_LEN].copy_from_slice(&bytes);
    // Row 330: every byte zero (the data line stuck low), which passes the byte-sum checksum.
    let dead = frame_offset(&file, 330) + 1;
    file[dead..dead + BURST32_LEN].fill(0);

    let outcome = run_replay(&file[..], |_| {}).unwrap();
    let s = outcome.sampling;
    assert_eq!((s.checksum_errors, s.stalled_counters, s.status_flags, s.dead_bus_frames), (1, 1, 1, 1));
    assert_eq!((s.bus_errors, s.faults()), (0, 4));
    assert_eq!(s.readings as usize, rec.rows.len() - 4);
    // Four faults are within the dwell's allowance: the sequence completes, with 4 fewer samples there.
    assert!(outcome.result.is_some());
    assert_eq!(outcome.positions[0].summary.samples, 2000 - 4);
    assert_eq!(outcome.positions[1].summary.samples, 2000);
    // The outcome file carries every counter, and decodes to the same outcome.
    let mut bytes = vec![0u8; sinscal::instrument::wire::outcome::MAX_BYTES];
    let n = outcome.encode(&mut bytes).unwrap();
    let decoded = sinscal::instrument::wire::outcome::Outcome::decode(&outcome.configuration, &bytes[..n]).unwrap();
    assert_eq!(decoded.sampling, s);
    assert_eq!(decoded, outcome);
}

#[test]
fn motion_and_a_wrong_position_abort_the_dwell_with_a_reason() {
    let rec = example(20.0);
    let (clean, _) = replay_file(&rec, &Options::angles()).unwrap();

    // A bump: 5 deg/s about x for one sample in the middle of dwell 2.
    let mut file = clean.clone();
    let k = 200 + 2000 + 200 + 1000;
    assert_eq!(rec.rows[k].pos, 2);
    let at = frame_offset(&file, k) + 1;
    let mut burst = decode_burst::<()>(Model::Adis16505_2, &file[at..at + BURST32_LEN]).unwrap();
    burst.gyro_lsb[0] = sinscal::sensor::adis::I16F16::from_num(5.0 * 40.0);
    let mut bytes = [0u8; BURST32_LEN];
    encode_burst(Model::Adis16505_2, &burst, &mut bytes);
    file[at..at + BURST32_LEN].copy_from_slice(&bytes);
    let mut events = Vec::new();
    let outcome = run_replay(&file[..], |e| events.push(*e)).unwrap();
    let abort = events.iter().find_map(|e| match e {
        Event::DwellAborted { index, reason, at_sample } => Some((*index, *reason, *at_sample)),
        _ => None,
    });
    assert_eq!(abort, Some((1, AbortReason::Rotation, 1001)));
    // The dwell was collected again from the samples after the bump, and the calibration completed.
    assert!(outcome.result.is_some());
    assert_eq!(outcome.positions[1].summary.samples, 999);

    // The schedule announces (0, 0, 0) where the data have z pointing east (roll 90): every sample of that
    // dwell contradicts the position; after three aborts the sequence fails and says why.
    let mut rec_wrong = rec.clone();
    for row in rec_wrong.rows.iter_mut().filter(|r| r.pos == 5) {
        row.roll_deg = 0.0;
    }
    let err = calibrate_on_host(&rec_wrong, &Options::angles()).unwrap_err().to_string();
    assert!(err.contains("position 5 (dwell 5) aborted: GravityContradictsPosition"), "{err}");
    let (file, _) = replay_file(&rec_wrong, &Options::angles()).unwrap();
    let outcome = run_replay(&file[..], |_| {}).unwrap();
    assert!(matches!(
        outcome.failure,
        Some(SequenceFailure::PositionAborted { index: 4, reason: AbortReason::GravityContradictsPosition })
    ));
}

#[test]
fn a_full_queue_is_counted_not_dropped_silently() {
    use heapless::spsc::Queue;
    use sinscal::run::sampling::{on_data_ready, QueueItem, SamplingStats, QUEUE_SLOTS};
    use sinscal::sensor::sample::ImuReading;
    use sinscal::sensor::source::{ClassifiedError, ImuSource, ReadFault};

    #[derive(Debug)]
    struct Never;
    impl ClassifiedError for Never {
        fn fault(&self) -> ReadFault {
            ReadFault::Bus
        }
    }
    struct Counter(u16);
    impl ImuSource for Counter {
        type Error = Never;
        fn read(&mut self) -> Result<ImuReading, Never> {
            self.0 += 1;
            Ok(ImuReading { counter: self.0, ..ImuReading::default() })
        }
    }
    let mut queue: Queue<QueueItem, QUEUE_SLOTS> = Queue::new();
    let (mut producer, mut consumer) = queue.split();
    let mut stats = SamplingStats::default();
    let mut imu = Counter(0);
    // The processing loop stalls for 20 samples (200 ms); the table signal changes every sample.
    for k in 0..20u8 {
        on_data_ready(&mut imu, &mut producer, &mut stats, k % 3);
    }
    assert_eq!((stats.events, stats.readings, stats.queue_full), (20, 20, 20 - (QUEUE_SLOTS as u32 - 1)));
    // What is in the queue is in order, the oldest first, each with the table signal of its own sample.
    let items: Vec<QueueItem> = std::iter::from_fn(|| consumer.dequeue()).collect();
    let counters: Vec<u16> = items.iter().map(|i| i.reading.unwrap().counter).collect();
    assert_eq!(counters, (1..QUEUE_SLOTS as u16).collect::<Vec<_>>());
    let tables: Vec<u8> = items.iter().map(|i| i.table).collect();
    assert_eq!(tables, (0..QUEUE_SLOTS as u8 - 1).map(|k| k % 3).collect::<Vec<_>>());
}

#[test]
fn sampling_counters_saturate_instead_of_wrapping() {
    use heapless::spsc::Queue;
    use sinscal::run::sampling::{on_data_ready, QueueItem, SamplingStats};
    // Every counter at its largest value (497 days of events at 100 Hz): more events, readings, a missed
    // sample, a dead-bus fault and a full queue leave them there; a wrapping counter would restart from 0.
    let max = u32::MAX;
    let all_max = SamplingStats {
        events: max,
        readings: max,
        queue_full: max,
        bus_errors: max,
        checksum_errors: max,
        stalled_counters: max,
        status_flags: max,
        dead_bus_frames: max,
        missed_samples: max,
        queue_high_water: max,
    };
    assert_eq!(all_max.faults(), max);
    let mut stats = all_max;
    // A queue of one item: the second and third enqueue find it full.
    let mut queue: Queue<QueueItem, 2> = Queue::new();
    let (mut producer, _consumer) = queue.split();
    let mut imu = Level { counter: 0, dead_bus_at: Some(3), missed: 1 };
    for _ in 0..3 {
        on_data_ready(&mut imu, &mut producer, &mut stats, 1);
    }
    assert_eq!(stats, all_max);
    // From zero the same events count normally.
    let mut stats = SamplingStats::default();
    let mut queue: Queue<QueueItem, 2> = Queue::new();
    let (mut producer, _consumer) = queue.split();
    let mut imu = Level { counter: 0, dead_bus_at: Some(3), missed: 1 };
    for _ in 0..3 {
        on_data_ready(&mut imu, &mut producer, &mut stats, 1);
    }
    let expected = SamplingStats {
        events: 3,
        readings: 2,
        queue_full: 2,
        dead_bus_frames: 1,
        missed_samples: 2,
        // The queue of one slot, full from the first sample on.
        queue_high_water: 1,
        ..SamplingStats::default()
    };
    assert_eq!(stats, expected);
}

/// A level IMU at rest (gravity on z, a little Earth rate) whose data counter advances, or a dead bus.
struct Level {
    counter: u16,
    dead_bus_at: Option<u16>,
    /// Samples reported missed before each reading.
    missed: u16,
}

impl sinscal::sensor::source::ImuSource for Level {
    type Error = sinscal::sensor::adis::AdisError<()>;
    fn read(&mut self) -> Result<sinscal::sensor::sample::ImuReading, Self::Error> {
        self.counter += 1;
        if self.dead_bus_at == Some(self.counter) {
            return Err(sinscal::sensor::adis::AdisError::DeadBus);
        }
        let sample = sinscal::sensor::sample::ImuSample {
            rate_b_radps: [0.0, 5.1e-5, 5.2e-5],
            force_b_mps2: [1e-3, -2e-3, 9.806],
        };
        Ok(sinscal::sensor::sample::ImuReading {
            sample,
            counter: self.counter,
            missed: self.missed,
            ..Default::default()
        })
    }
}

/// A one-position sequence as the replay runs it (no settling, dwells as long as the table says).
fn level_sequence() -> sinscal::run::sequence::CalibrationSequence {
    use sinscal::instrument::wire::codes::EstimatorCode;
    use sinscal::instrument::wire::configuration::{Configuration, Thresholds};
    let site = sinscal::nav::earth::Site::with_normal_gravity(45.0f32.to_radians(), 0.0);
    let schedule = [sinscal::nav::frames::Attitude::from_degrees(0.0, 0.0, 0.0)];
    let configuration = Configuration {
        estimator: EstimatorCode::Angles,
        schedule: heapless::Vec::from_slice(&schedule).unwrap(),
        labels: heapless::Vec::from_slice(&[1]).unwrap(),
        prefilter: sinscal::calib::dwell::Prefilter::None,
        dwell_value: sinscal::calib::align::DwellValue::Mean,
        max_passes: 1,
        estimate_reference_offset: false,
        ..Configuration::new(sinscal::sensor::adis::Model::Adis16505_2, site)
    };
    let settings = configuration.sequence_settings(Thresholds::REPLAY);
    sinscal::run::sequence::CalibrationSequence::new(&schedule, site, settings).unwrap()
}

#[test]
fn the_table_signal_is_the_one_latched_with_its_sample() {
    use heapless::spsc::Queue;
    use sinscal::run::sampling::{on_data_ready, process_next, QueueItem, SamplingStats, QUEUE_SLOTS};
    use sinscal::run::sequence::feed_sequence;
    // The processing loop falls behind by 14 samples: 12 taken in position 1, then 2 after the table left.
    // Processed later, when the table has long left, the dwell still holds exactly the 12 samples taken in
    // position; a loop that read the table when it dequeued would have collected none.
    let mut queue: Queue<QueueItem, QUEUE_SLOTS> = Queue::new();
    let (mut producer, mut consumer) = queue.split();
    let mut stats = SamplingStats::default();
    let mut imu = Level { counter: 0, dead_bus_at: Some(5), missed: 0 };
    for k in 0..14 {
        on_data_ready(&mut imu, &mut producer, &mut stats, if k < 12 { 1 } else { 0 });
    }
    assert_eq!((stats.readings, stats.dead_bus_frames, stats.faults()), (13, 1, 1));
    let mut sequence = level_sequence();
    let mut events = Vec::new();
    while let Some(e) = process_next(&mut consumer, |item| feed_sequence(&mut sequence, item)) {
        events.extend(e.into_iter().flatten());
    }
    assert_eq!(events[0], Event::DwellStarted { index: 0 });
    // 12 samples in position, one of them the dead-bus fault: 11 in the statistics.
    assert_eq!(events[1], Event::DwellCompleted { index: 0, samples: 11, faults: 1 });
    assert_eq!(sequence.completed()[0].summary.samples, 11);
}

#[test]
fn a_gpio_in_position_signal_feeds_whichever_position_is_next() {
    use sinscal::run::sampling::{QueueItem, TABLE_IN_POSITION};
    use sinscal::run::sequence::feed_sequence;
    use sinscal::sensor::source::{ClassifiedError, ImuSource};
    // TABLE_IN_POSITION (a board that only says "in position") counts as in position for the position the
    // sequence works on, whatever its number; 0 is moving; another position's number is not in position.
    let mut imu = Level { counter: 0, dead_bus_at: None, missed: 0 };
    let mut sequence = level_sequence();
    let mut item = |table: u8| QueueItem { reading: imu.read().map_err(|e| e.fault()), table };
    assert_eq!(feed_sequence(&mut sequence, &item(2)), [None, None]);
    assert_eq!(feed_sequence(&mut sequence, &item(0)), [None, None]);
    assert_eq!(feed_sequence(&mut sequence, &item(TABLE_IN_POSITION)), [Some(Event::DwellStarted { index: 0 }), None]);
    for _ in 0..19 {
        assert_eq!(feed_sequence(&mut sequence, &item(TABLE_IN_POSITION)), [None, None]);
    }
    assert_eq!(
        feed_sequence(&mut sequence, &item(0)),
        [Some(Event::DwellCompleted { index: 0, samples: 20, faults: 0 }), None]
    );
    assert_eq!(sequence.completed()[0].summary.samples, 20);
}

#[test]
fn unknown_headings_beyond_the_32nd_dwell_reach_the_sequence() {
    // SIMULATION: Table 1 six times over (36 dwells of 1 s); the headings of dwells 4 and 35 (labels) emptied.
    // The replay header holds one flag per dwell: the sequence must see exactly those two as unknown (a
    // 32-bit mask put the 35th dwell's flag on the 3rd, and overflowed in a debug build; found by cargo-fuzz).
    let positions: Vec<[f64; 3]> = (0..6).flat_map(|_| sinscal_host::model::synth::TABLE1_DEG).collect();
    let mut rec = Scenario { dwell_s: 1.0, positions_deg: positions, ..Scenario::example() }.recording(8, "e.csv");
    for row in rec.rows.iter_mut().filter(|r| r.pos == 4 || r.pos == 35) {
        row.heading_deg = None;
    }
    let (file, plan) = replay_file(&rec, &Options::default()).unwrap();
    assert_eq!(plan.dwells.len(), 36);
    let header = read_header(&mut &file[..]).unwrap();
    assert_eq!(header.configuration.unknown_headings, (1 << 3) | (1 << 34));
    // The firmware path solves the same session as the direct path: every heading estimate agrees.
    let direct = calibrate(&rec, &Options::default()).unwrap();
    let replayed = calibrate_on_host(&rec, &Options::default()).unwrap();
    let (d, r) = (direct.channels.unwrap(), replayed.channels.unwrap());
    assert_eq!(d.suspect, r.suspect);
    for (k, (a, b)) in direct.positions.iter().zip(&replayed.positions).enumerate() {
        assert_eq!(a.attitude.heading_deg.is_none(), b.attitude.heading_deg.is_none(), "dwell {k}");
    }
    // The two unknown headings are estimated (a standard error), the 34 others known, on both paths.
    for k in 0..36 {
        let estimated = k == 3 || k == 34;
        assert_eq!(d.heading_std_rad[k] > 0.0, estimated, "direct, dwell {k}");
        assert_eq!(r.heading_std_rad[k] > 0.0, estimated, "replayed, dwell {k}");
        assert!(
            (d.heading_rad[k] - r.heading_rad[k]).abs() < 1e-3,
            "dwell {k}: {} {}",
            d.heading_rad[k],
            r.heading_rad[k]
        );
    }
}
