//! Firmware benchmark: instructions per 100 Hz sample of the whole per-sample path, in QEMU.
//!
//! Run with `-icount shift=0` (one instruction per virtual nanosecond): SysTick, clocked by the 25 MHz core
//! clock of mps2-an386, then advances once per 40 instructions, deterministically. The path measured is
//! what the firmware does for every sample: the data-ready handler (burst read through the SPI device,
//! checksum, decode, counter and status checks, conversion to SI, enqueue) and the processing loop
//! (queue hand-over by reference, `feed_sequence` with the latched table signal, the calibration sequence's
//! checks, the HMM/KF bank and the dwell accumulators); on their own, the compensation of a sample with a stored
//! calibration (docs/compensation.md), a move's rotation (docs/method.md#a-moves-rotation-from-the-gyro-rates)
//! and a move's rotation with its sensitivity sums (`MoveSums`, src/calib/moves.rs). The SPI device is the
//! replay device serving a fixed frame, so the bus itself costs nothing here; on hardware the burst's 32 bytes
//! at 1 MHz add 256 us of SPI time, not instructions.
//! The result is written as text to the file named by the first semihosting argument.
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(not(target_os = "none"))]
fn main() {}

#[cfg(target_os = "none")]
mod firmware {
    use core::fmt::Write as _;

    use cortex_m::peripheral::syst::SystClkSource;
    use cortex_m::peripheral::SYST;
    use cortex_m_rt::entry;
    use heapless::spsc::Queue;
    use sinscal::board::exit;
    use sinscal::calib::compensation::Compensation;
    use sinscal::calib::dwell::Prefilter;
    use sinscal::instrument::wire::codes::EstimatorCode;
    use sinscal::instrument::wire::configuration::{Configuration, DeviceConfiguration, Thresholds};
    use sinscal::nav::earth::Site;
    use sinscal::nav::frames::Attitude;
    use sinscal::rig::replay::{NoDelay, ReplayDevice};
    use sinscal::run::sampling::{
        on_data_ready, process_next, QueueItem, SamplingStats, QUEUE_SLOTS, TABLE_IN_POSITION,
    };
    use sinscal::run::sequence::{feed_sequence, CalibrationSequence, Estimator};
    use sinscal::sensor::adis::{encode_burst, Adis, Burst, Model, BURST32_LEN, I16F16};
    use sinscal::sensor::sample::ImuSample;

    /// Instructions per SysTick tick under -icount shift=0 with the 25 MHz core clock.
    const INSTRUCTIONS_PER_TICK: u32 = 40;
    const SAMPLES: u32 = 2000;

    fn ticks_between(start: u32, end: u32) -> u32 {
        // SysTick counts down, 24 bits.
        start.wrapping_sub(end) & 0x00FF_FFFF
    }

    /// The six positions of Table 1 at 45.7796 N with the general estimator's default terms, one pass of the
    /// angle method, and `prefilter`.
    fn table1_configuration(estimator: EstimatorCode, prefilter: Prefilter) -> Configuration {
        let site = Site { latitude_rad: 45.7796f32.to_radians(), gravity_mps2: 9.8063 };
        let mut c = Configuration {
            estimator,
            terms: sinscal::calib::session::DEFAULT_MODEL,
            prefilter,
            dwell_value: sinscal::calib::align::DwellValue::Mean,
            max_passes: 1,
            estimate_reference_offset: true,
            ..Configuration::new(Model::Adis16505_2, site)
        };
        for (k, p) in sinscal::calib::angles::TABLE1_POSITIONS_DEG.iter().enumerate() {
            let _ = c.schedule.push(Attitude::from_degrees(p[0], p[1], p[2]));
            let _ = c.labels.push(k as u16 + 1);
        }
        c
    }

    /// The settings of the measured sequences (the per-sample path does not depend on the solve's).
    fn single_pass(prefilter: Prefilter) -> sinscal::run::sequence::SequenceSettings {
        table1_configuration(EstimatorCode::Angles, prefilter).sequence_settings(Thresholds::REPLAY)
    }

    fn measure(prefilter: Prefilter) -> (u32, u32, u32) {
        let model = Model::Adis16505_2;
        let mut imu = Adis::new(ReplayDevice::new(model), model);
        let _ = imu.init(&mut NoDelay);
        let site = Site::with_normal_gravity(45.7796f32.to_radians(), 0.0);
        let settings = single_pass(prefilter);
        let schedule = [Attitude::from_degrees(0.0, 0.0, 0.0)];
        let Ok(mut sequence) = CalibrationSequence::new(&schedule, site, settings) else { return (0, 0, 0) };
        let mut queue: Queue<QueueItem, QUEUE_SLOTS> = Queue::new();
        let (mut producer, mut consumer) = queue.split();
        let mut stats = SamplingStats::default();
        let lsb_w = model.radps_per_lsb() / 65536.0;
        let lsb_f = model.accel_mps2_per_lsb() / 65536.0;
        let mut frame = [0u8; BURST32_LEN];
        let mut burst = Burst {
            diag_stat: 0,
            gyro_lsb: [
                I16F16::from_bits((1e-6 / lsb_w) as i32),
                I16F16::from_bits((5.1e-5 / lsb_w) as i32),
                I16F16::from_bits((5.2e-5 / lsb_w) as i32),
            ],
            accel_lsb: [
                I16F16::from_bits((1e-3 / lsb_f) as i32),
                I16F16::from_bits((-2e-3 / lsb_f) as i32),
                I16F16::from_bits((9.806 / lsb_f) as i32),
            ],
            temp_raw: 250,
            data_counter: 0,
        };
        let syst = unsafe { &*SYST::PTR };
        let (mut isr, mut processing) = (0u32, 0u32);
        for k in 0..SAMPLES {
            // Prepare the next frame (the sensor's work, not timed).
            burst.data_counter = k as u16;
            burst.gyro_lsb[0] = I16F16::from_bits(burst.gyro_lsb[0].to_bits() ^ (k as i32 & 7));
            encode_burst(model, &burst, &mut frame);
            imu.spi_mut().load_frame(&frame);
            let t0 = syst.cvr.read();
            on_data_ready(&mut imu, &mut producer, &mut stats, TABLE_IN_POSITION);
            let t1 = syst.cvr.read();
            let _ = process_next(&mut consumer, |item| feed_sequence(&mut sequence, item));
            let t2 = syst.cvr.read();
            isr += ticks_between(t0, t1);
            processing += ticks_between(t1, t2);
        }
        // The queue hand-over on its own: one item enqueued (not timed), then taken by reference.
        let mut handover = 0u32;
        for _ in 0..SAMPLES {
            let reading = Ok(sinscal::sensor::sample::ImuReading::default());
            let _ = producer.enqueue(QueueItem { reading, table: TABLE_IN_POSITION });
            let t0 = syst.cvr.read();
            let _ = process_next(&mut consumer, |item| core::hint::black_box(item).reading.is_ok());
            let t1 = syst.cvr.read();
            handover += ticks_between(t0, t1);
        }
        let per = |ticks: u32| ticks * INSTRUCTIONS_PER_TICK / SAMPLES;
        HANDOVER.store(per(handover), core::sync::atomic::Ordering::Relaxed);
        (per(isr), per(processing), stats.readings)
    }

    /// Bytes of stack below the current stack pointer that `f` writes (stack painting: fill 8 KiB below SP
    /// with a pattern, run `f`, find the lowest word that changed).
    #[inline(never)]
    fn stack_used(f: &mut dyn FnMut()) -> u32 {
        stack_used_within(2048, f)
    }

    /// [`stack_used`] with a painted depth of `depth_words` words.
    #[inline(never)]
    fn stack_used_within(depth_words: usize, f: &mut dyn FnMut()) -> u32 {
        const PAINT: u32 = 0xDEAD_BEEF;
        let sp = cortex_m::register::msp::read() as usize;
        // Paint up to just below the current stack pointer: everything `f` and its callees push is below.
        let top = (sp - 8) & !3;
        let bottom = top - 4 * depth_words;
        for a in (bottom..top).step_by(4) {
            unsafe { core::ptr::write_volatile(a as *mut u32, PAINT) };
        }
        f();
        let lowest = (bottom..top).step_by(4).find(|&a| unsafe { core::ptr::read_volatile(a as *const u32) } != PAINT);
        lowest.map_or(0, |a| (sp - a) as u32)
    }

    /// Stack of one data-ready handler call and of one processing step.
    fn stack_depths() -> (u32, u32) {
        let model = Model::Adis16505_2;
        let mut imu = Adis::new(ReplayDevice::new(model), model);
        let _ = imu.init(&mut NoDelay);
        let site = Site::with_normal_gravity(45.7796f32.to_radians(), 0.0);
        let settings = single_pass(Prefilter::paper());
        let schedule = [Attitude::from_degrees(0.0, 0.0, 0.0)];
        let Ok(mut sequence) = CalibrationSequence::new(&schedule, site, settings) else { return (0, 0) };
        let mut queue: Queue<QueueItem, QUEUE_SLOTS> = Queue::new();
        let (mut producer, mut consumer) = queue.split();
        let mut stats = SamplingStats::default();
        let mut frame = [0u8; BURST32_LEN];
        let burst = Burst {
            diag_stat: 0,
            gyro_lsb: [I16F16::from_bits(1000); 3],
            accel_lsb: [I16F16::from_bits(0), I16F16::from_bits(0), I16F16::from_bits(263_700_000)],
            temp_raw: 250,
            data_counter: 0,
        };
        encode_burst(model, &burst, &mut frame);
        imu.spi_mut().load_frame(&frame);
        let isr = stack_used(&mut || on_data_ready(&mut imu, &mut producer, &mut stats, TABLE_IN_POSITION));
        let processing = stack_used(&mut || {
            let _ = process_next(&mut consumer, |item| feed_sequence(&mut sequence, item));
        });
        (isr, processing)
    }

    /// A configure body: the general estimator with its default terms, the paper's prefilter (a = 1), the six
    /// positions of Table 1 at 45.7796 N, and thresholds of 1,000-sample dwells without settling.
    fn configuration(out: &mut [u8]) -> usize {
        let prefilter = Prefilter::HmmKf {
            gyro: sinscal::calib::prefilter::PrefilterSettings::paper_gyro().with_a(1.0),
            accel: sinscal::calib::prefilter::PrefilterSettings::paper_accel().with_a(1.0),
        };
        let mut c = table1_configuration(EstimatorCode::General, prefilter);
        c.max_passes = 6;
        let thresholds = Thresholds { settle_samples: 0, dwell_samples: u32::MAX, min_dwell_samples: 1000 };
        let mut w = sinscal::instrument::wire::Writer::new(out);
        DeviceConfiguration { configuration: c, thresholds }.encode(&mut w);
        w.written().unwrap_or(0)
    }

    /// One request as the firmware's main loop handles it: its frame received byte by byte, the device's reply
    /// framed into a buffer of the longest frame. Its own frame (not inlined), so that its stack is measured.
    #[inline(never)]
    fn ask(
        device: &mut sinscal::instrument::device::Device<sinscal::rig::semihost::HostFileFlash>,
        k: u8,
        b: &[u8],
    ) -> usize {
        use sinscal::instrument::link::{encode_frame, FrameReceiver, MAX_WIRE_BYTES};
        let stats = SamplingStats::default();
        let mut request = [0u8; MAX_WIRE_BYTES];
        let mut reply = [0u8; MAX_WIRE_BYTES];
        let len = encode_frame(k, 1, b, &mut request).unwrap_or(0);
        let mut rx = FrameReceiver::new();
        let mut sent = 0;
        for &byte in &request[..len] {
            if let Some(f) = rx.push(byte) {
                sent = device.on_frame(f, &stats, &mut reply).0;
            }
        }
        core::hint::black_box(&reply);
        sent
    }

    /// The link's requests on a device whose flash is a scratch host file: the stack of a status request, of a
    /// configure and of a start (which builds the calibration sequence), and the instructions of a status request
    /// (frame checked, reply built and framed). The device itself is in this function's frame, as in `main`'s.
    fn link_costs() -> (u32, u32, u32, u32) {
        use sinscal::instrument::device::Device;
        use sinscal::instrument::message::kind;
        use sinscal::instrument::store::RecordStore;
        use sinscal::rig::semihost::{arg_path, HostFileFlash};
        let Some(path) = arg_path(1).and_then(|p| p.with_suffix(".flash")) else { return (0, 0, 0, 0) };
        let Ok(store) = RecordStore::new(HostFileFlash::open(path), HostFileFlash::SECTOR_BYTES as u32) else {
            return (0, 0, 0, 0);
        };
        let mut device = Device::new(Model::Adis16505_2, store);
        let mut body = [0u8; 512];
        let n = configuration(&mut body);
        // Painted 128 KiB deep: a request's handlers share one frame unless the compiler keeps them apart.
        let status = stack_used_within(32 * 1024, &mut || {
            ask(&mut device, kind::STATUS, &[]);
        });
        let configure = stack_used_within(32 * 1024, &mut || {
            ask(&mut device, kind::CONFIGURE, &body[..n]);
        });
        let start = stack_used_within(32 * 1024, &mut || {
            ask(&mut device, kind::START, &[]);
        });
        let syst = unsafe { &*SYST::PTR };
        let t0 = syst.cvr.read();
        for _ in 0..20 {
            core::hint::black_box(ask(&mut device, kind::STATUS, &[]));
        }
        let t1 = syst.cvr.read();
        let _ = semihosting::fs::remove_file(device.into_store().release().into_path().as_c_str());
        (status, configure, start, ticks_between(t0, t1) * INSTRUCTIONS_PER_TICK / 20)
    }

    static HANDOVER: core::sync::atomic::AtomicU32 = core::sync::atomic::AtomicU32::new(0);

    /// A compensation with every term non-zero (docs/compensation.md); its cost does not depend on the values.
    fn compensation() -> Compensation {
        let mut theta = [0.0f32; sinscal::calib::general::PARAMETERS];
        for (i, x) in theta.iter_mut().enumerate().take(33) {
            // 1e-4 to 8e-4 of both signs: biases, scale factors, misalignments, g-sensitivity.
            *x = if i % 2 == 0 { 1e-4 } else { -2e-4 } * (1 + i % 4) as f32;
        }
        Compensation::from_parameters(&theta).unwrap_or_else(|_| exit(5))
    }

    /// The compensation of a sample (`Compensation::apply`, every term): `SAMPLES` calls in one timed loop, the
    /// sample read and the result written each time as the per-sample path would, so the tick's 40-instruction
    /// quantum is spread over all of them (a span of its own per call would be quantised like the parts above).
    /// Includes the loop's counter and branch and the `black_box` pointer spills (6 instructions per call).
    fn compensation_loop() -> u32 {
        let comp = compensation();
        let sample = ImuSample { rate_b_radps: [0.01, -0.02, 0.03], force_b_mps2: [0.1, -0.2, 9.8] };
        let syst = unsafe { &*SYST::PTR };
        let t0 = syst.cvr.read();
        for _ in 0..SAMPLES {
            core::hint::black_box(core::hint::black_box(&comp).apply(core::hint::black_box(&sample)));
        }
        let t1 = syst.cvr.read();
        ticks_between(t0, t1) * INSTRUCTIONS_PER_TICK / SAMPLES
    }

    /// The rotation update of a move (`MoveIntegrator::push`: the increment, and every second sample the
    /// coning-corrected quaternion update), `SAMPLES` calls in one timed loop, per call.
    fn move_integration_loop() -> u32 {
        let mut m = sinscal::nav::strapdown::MoveIntegrator::new(0.01);
        let rate = [0.17f32, -0.05, 0.3];
        let syst = unsafe { &*SYST::PTR };
        let t0 = syst.cvr.read();
        for _ in 0..SAMPLES {
            core::hint::black_box(&mut m).push(core::hint::black_box(rate));
        }
        let t1 = syst.cvr.read();
        core::hint::black_box(m.rotation());
        ticks_between(t0, t1) * INSTRUCTIONS_PER_TICK / SAMPLES
    }

    /// A move's rotation and sensitivity sums (`MoveSums::push`: the compensation with the prior's `b_g`, `G` and
    /// `T_g^-1`, the increment, the attitude at mid-sample, the sums for every gyro term and the noise, and every
    /// second sample the coning-corrected update and its matrix), `SAMPLES` calls in one timed loop, per call.
    fn move_sums_loop() -> u32 {
        let Ok(mut m) = sinscal::calib::moves::MoveSums::new(&sinscal::rig::exact::move_prior()) else { exit(6) };
        let rate = [0.17f32, -0.05, 0.3];
        let force = [0.4f32, -0.2, 9.7];
        let syst = unsafe { &*SYST::PTR };
        let t0 = syst.cvr.read();
        for _ in 0..SAMPLES {
            core::hint::black_box(&mut m).push(
                core::hint::black_box(rate),
                core::hint::black_box(force),
                core::hint::black_box(0.01),
            );
        }
        let t1 = syst.cvr.read();
        core::hint::black_box(m.rotation());
        ticks_between(t0, t1) * INSTRUCTIONS_PER_TICK / SAMPLES
    }

    /// The parts on their own: the bus transfer (replay device), the driver's decode (checksum, decode,
    /// counter and status checks, conversion to SI: everything after the bus), and the collector update
    /// (prefilter bank and accumulators) without and with the HMM/KF.
    fn parts() -> (u32, u32, u32, u32) {
        use embedded_hal::spi::{Operation, SpiDevice};
        let model = Model::Adis16505_2;
        let mut imu = Adis::new(ReplayDevice::new(model), model);
        let _ = imu.init(&mut NoDelay);
        let mut frame = [0u8; BURST32_LEN];
        let mut burst = Burst {
            diag_stat: 0,
            gyro_lsb: [I16F16::from_bits(1000); 3],
            accel_lsb: [I16F16::from_bits(263_000_000), I16F16::from_bits(1000), I16F16::from_bits(-1000)],
            temp_raw: 250,
            data_counter: 1,
        };
        let syst = unsafe { &*SYST::PTR };
        let (mut t_bus, mut t_decode, mut t_collect_none, mut t_collect_kf) = (0, 0, 0, 0);
        let mut none = sinscal::calib::dwell::DwellCollector::new(&Prefilter::None).unwrap_or_else(|_| exit(3));
        let mut kf = sinscal::calib::dwell::DwellCollector::new(&Prefilter::paper()).unwrap_or_else(|_| exit(3));
        for k in 0..SAMPLES {
            // A new frame each sample (the counter advances), prepared outside the timed spans.
            burst.data_counter = k as u16;
            burst.gyro_lsb[0] = I16F16::from_bits(1000 ^ (k as i32 & 7));
            encode_burst(model, &burst, &mut frame);
            imu.spi_mut().load_frame(&frame);
            let mut buf = [0u8; BURST32_LEN];
            let t0 = syst.cvr.read();
            let bus = core::hint::black_box(imu.spi_mut())
                .transaction(&mut [Operation::Write(&sinscal::sensor::adis::BURST_COMMAND), Operation::Read(&mut buf)]);
            let t1 = syst.cvr.read();
            let reading = imu.decode_reading(core::hint::black_box(&buf));
            let t2 = syst.cvr.read();
            let sample = match (bus, reading) {
                (Ok(()), Ok(r)) => core::hint::black_box(r.sample),
                _ => exit(4),
            };
            let t3 = syst.cvr.read();
            let _ = core::hint::black_box(&mut none).update(&sample);
            let t4 = syst.cvr.read();
            let _ = core::hint::black_box(&mut kf).update(&sample);
            let t5 = syst.cvr.read();
            t_bus += ticks_between(t0, t1);
            t_decode += ticks_between(t1, t2);
            t_collect_none += ticks_between(t3, t4);
            t_collect_kf += ticks_between(t4, t5);
        }
        let per = |ticks: u32| ticks * INSTRUCTIONS_PER_TICK / SAMPLES;
        (per(t_bus), per(t_decode), per(t_collect_none), per(t_collect_kf))
    }

    /// Instructions of the longest processing step of a whole calibration sequence through the general
    /// estimator with `model`: the step that completes the last dwell and solves (the main loop spends them in
    /// one turn, so a board's watchdog must allow them; docs/board.md). The six positions of Table 1 at
    /// 45.7796 N, `SOLVE_DWELL_SAMPLES` samples each of the exact specific force and Earth rate with a small
    /// deterministic dither (the solve's cost does not depend on the values), 20 samples of "moving" between
    /// dwells (no rotation: with the full model the moves are measured and left out as gross misfits).
    fn solve_cost(
        model: sinscal::calib::general::Model,
        noise: Option<sinscal::calib::noise_model::NoiseModel>,
    ) -> u32 {
        const SOLVE_DWELL_SAMPLES: u32 = 300;
        let site = Site::with_normal_gravity(45.7796f32.to_radians(), 0.0);
        let mut schedule = [Attitude::from_degrees(0.0, 0.0, 0.0); 6];
        for (a, p) in schedule.iter_mut().zip(sinscal::calib::angles::TABLE1_POSITIONS_DEG.iter()) {
            *a = Attitude::from_degrees(p[0], p[1], p[2]);
        }
        let channels = sinscal::calib::general::ChannelSettings { model, noise, ..Default::default() };
        let settings = sinscal::run::sequence::SequenceSettings {
            settle_samples: 0,
            dwell_samples: SOLVE_DWELL_SAMPLES,
            estimator: Estimator::Channels(channels),
            ..Default::default()
        };
        let Ok(mut sequence) = CalibrationSequence::new(&schedule, site, settings) else { exit(6) };
        let syst = unsafe { &*SYST::PTR };
        let (mut longest, mut dither, mut counter) = (0u32, 12345u32, 0u16);
        for (k, attitude) in schedule.iter().enumerate() {
            let c_n_b = attitude.c_b_n().transpose();
            let force = c_n_b.mul_vec(site.force_at_rest_n_mps2());
            let rate = c_n_b.mul_vec(site.earth_rate_n_radps());
            for i in 0..SOLVE_DWELL_SAMPLES + 20 {
                dither = dither.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
                let e = ((dither >> 8) as f32 / 16_777_216.0 - 0.5) * 2e-3;
                let sample = ImuSample {
                    rate_b_radps: [rate[0] + e * 1e-3, rate[1] - e * 1e-3, rate[2] + e * 1e-3],
                    force_b_mps2: [force[0] + e, force[1] - e, force[2] + e],
                };
                counter = counter.wrapping_add(1);
                let reading = sinscal::sensor::sample::ImuReading { sample, counter, missed: 0, temperature_c: 25.0 };
                let table = if i < SOLVE_DWELL_SAMPLES { k as u8 + 1 } else { 0 };
                let item = QueueItem { reading: Ok(reading), table };
                let t0 = syst.cvr.read();
                let events = feed_sequence(&mut sequence, core::hint::black_box(&item));
                let t1 = syst.cvr.read();
                longest = longest.max(ticks_between(t0, t1));
                if events.iter().flatten().any(|e| matches!(e, sinscal::run::sequence::Event::Failed(_))) {
                    exit(7)
                }
            }
        }
        if sequence.result().is_none() {
            exit(8)
        }
        longest * INSTRUCTIONS_PER_TICK
    }

    #[entry]
    fn main() -> ! {
        let mut p = cortex_m::Peripherals::take().unwrap_or_else(|| exit(2));
        p.SYST.set_clock_source(SystClkSource::Core);
        p.SYST.set_reload(0x00FF_FFFF);
        p.SYST.clear_current();
        p.SYST.enable_counter();
        // The timing overhead itself (two register reads).
        let syst = unsafe { &*SYST::PTR };
        let t0 = syst.cvr.read();
        let t1 = syst.cvr.read();
        let overhead = ticks_between(t0, t1) * INSTRUCTIONS_PER_TICK;
        let (isr_none, proc_none, n_none) = measure(Prefilter::None);
        let (isr_kf, proc_kf, n_kf) = measure(Prefilter::paper());
        let (bus, decode, collect_none, collect_kf) = parts();
        let compensate = compensation_loop();
        let move_update = move_integration_loop();
        let move_sums = move_sums_loop();
        let (stack_isr, stack_processing) = stack_depths();
        let (stack_status, stack_configure, stack_start, status_instructions) = link_costs();
        let solve_default = solve_cost(sinscal::calib::session::DEFAULT_MODEL, None);
        let solve_full = solve_cost(sinscal::calib::general::Model::FULL, None);
        // A noise model with every term: the dwells' correlation adds its sandwich to the solving step.
        let terms = |s: f32| sinscal::calib::noise_model::ChannelNoiseTerms {
            quantisation_u_s: 1e-3 * s,
            white_u_sqrt_s: 1e-2 * s,
            instability_u: 1e-3 * s,
            gauss_markov_u: 3e-3 * s,
            gauss_markov_time_s: 30.0,
            random_walk_u_per_sqrt_s: 1e-5 * s,
            ramp_u_per_s: 0.0,
            sway_u_s: 1e-3 * s,
            sway_time_s: 5.0,
        };
        let noise = sinscal::calib::noise_model::NoiseModel {
            sample_interval_s: 0.01,
            channels: [1e-5f32, 1e-5, 1e-5, 0.1, 0.1, 0.1].map(terms),
        };
        let solve_noise = solve_cost(sinscal::calib::session::DEFAULT_MODEL, Some(noise));
        let mut text: heapless::String<1536> = heapless::String::new();
        let _ = write!(
            text,
            "stack_bytes_link_status {stack_status}\nstack_bytes_link_configure {stack_configure}\n\
             stack_bytes_link_start {stack_start}\nlink_status_request_instructions {status_instructions}\n\
             device_bytes {}\n",
            core::mem::size_of::<sinscal::instrument::device::Device<sinscal::rig::semihost::HostFileFlash>>()
        );
        let _ = write!(
            text,
            "solve_step_instructions_default_model {solve_default}\nsolve_step_instructions_full_model {solve_full}\n\
             solve_step_instructions_noise_model {solve_noise}\n"
        );
        let _ = writeln!(text, "part_queue_handover {}", HANDOVER.load(core::sync::atomic::Ordering::Relaxed));
        let _ = write!(
            text,
            "stack_bytes_data_ready_handler {stack_isr}\nstack_bytes_processing_step {stack_processing}\n"
        );
        let _ = write!(text, "part_bus_transfer_replay {bus}\npart_driver_decode {decode}\npart_collector_none {collect_none}\npart_collector_hmmkf {collect_kf}\npart_compensation {compensate}\npart_move_integration {move_update}\npart_move_sums {move_sums}\n");
        let _ = write!(
            text,
            "samples {SAMPLES} {n_none} {n_kf}\ntimer_overhead_instructions {overhead}\n\
             isr_instructions_per_sample {isr_none}\nprocessing_instructions_per_sample_none {proc_none}\n\
             processing_instructions_per_sample_hmmkf {proc_kf}\nisr_instructions_per_sample_hmmkf_run {isr_kf}\n"
        );
        let args_ok = sinscal::rig::semihost::arg_path(1)
            .is_some_and(|p| sinscal::rig::semihost::write_file(&p, text.as_bytes()));
        exit(if args_ok { 0 } else { 1 })
    }
}
