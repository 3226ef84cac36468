//! On-target tests: core checks run on the Cortex-M4F in QEMU (f32 hardware float, libm, no std), and the
//! board's SPI port giving up on a stalled bus.
//! Writes one line per check (`ok NAME VALUE` or `FAILED NAME VALUE`) and a closing `N passed, N failed`
//! line to the file named by the first semihosting argument; the exit status is the number of failures.
//! The record store's check keeps its flash image in a scratch file beside it (that name plus `.flash`),
//! removed at the end.
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(not(target_os = "none"))]
fn main() {}

#[cfg(target_os = "none")]
mod firmware {
    use core::fmt::Write as _;

    use cortex_m as _;
    use cortex_m_rt::entry;
    use sinscal::board::exit;
    use sinscal::calib::angles::{calibrate_positions, CalibrationSettings, PositionInput, TABLE1_POSITIONS_DEG};
    use sinscal::calib::dwell::{DwellCollector, Prefilter};
    use sinscal::calib::prefilter::{HmmKf, PrefilterSettings};
    use sinscal::math::accumulate::DwellStats;
    use sinscal::nav::earth::Site;
    use sinscal::nav::frames::Attitude;
    use sinscal::sensor::sample::ImuSample;

    struct Report {
        text: heapless::String<3072>,
        passed: u32,
        failed: u32,
    }

    impl Report {
        fn check(&mut self, name: &str, ok: bool, value: f32) {
            let verdict = self.tally(ok);
            let _ = writeln!(self.text, "{verdict} {name} {value:e}");
        }

        /// A check whose value is a 32-bit pattern, printed in hex.
        fn check_hex(&mut self, name: &str, ok: bool, value: u32) {
            let verdict = self.tally(ok);
            let _ = writeln!(self.text, "{verdict} {name} {value:#010x}");
        }

        fn tally(&mut self, ok: bool) -> &'static str {
            if ok {
                self.passed += 1;
                "ok"
            } else {
                self.failed += 1;
                "FAILED"
            }
        }
    }

    const DEG_PER_HOUR: f32 = core::f32::consts::PI / 180.0 / 3600.0;
    const MICRO_G: f32 = 9.80665e-6;

    fn exact_six_position(report: &mut Report) {
        // Exact samples computed on the target with the core's own frames: the biases must come back with
        // their signs, to the first-order accuracy and, refined, to f32 precision.
        let site = Site::with_normal_gravity(45.7796f32.to_radians(), 0.0);
        let eps = [0.05 * DEG_PER_HOUR, -0.05 * DEG_PER_HOUR, 0.05 * DEG_PER_HOUR];
        let nabla = [-100.0 * MICRO_G, 100.0 * MICRO_G, 100.0 * MICRO_G];
        let mut inputs: heapless::Vec<PositionInput, 6> = heapless::Vec::new();
        let Ok(mut collector) = DwellCollector::new(&Prefilter::paper()) else {
            report.check("collector", false, 0.0);
            return;
        };
        for p in TABLE1_POSITIONS_DEG {
            let c = Attitude::from_degrees(p[0], p[1], p[2]).c_b_n();
            let ct = c.transpose();
            let w = ct.mul_vec(site.earth_rate_n_radps());
            let f = ct.mul_vec(site.force_at_rest_n_mps2());
            let sample = ImuSample {
                rate_b_radps: [w[0] + eps[0], w[1] + eps[1], w[2] + eps[2]],
                force_b_mps2: [f[0] + nabla[0], f[1] + nabla[1], f[2] + nabla[2]],
            };
            collector.reset();
            for _ in 0..600 {
                let _ = collector.update(&sample);
            }
            let Ok(summary) = collector.summary() else { return };
            let _ = inputs.push(PositionInput { c_b_n: c, summary });
        }
        for (passes, gyro_tol, accel_tol, name) in [(1, 1e-3, 3.0, "first_order"), (6, 1e-5, 0.05, "refined")] {
            let settings = CalibrationSettings { max_passes: passes, ..CalibrationSettings::default() };
            let Ok(r) = calibrate_positions(&inputs, &site, &settings) else {
                report.check(name, false, 0.0);
                return;
            };
            let mut worst_g: f32 = 0.0;
            let mut worst_a: f32 = 0.0;
            let mut signs = true;
            for i in 0..3 {
                let g = r.solution.gyro_bias_b_radps[i].map_or(f32::NAN, |e| e.value);
                let a = r.solution.accel_bias_b_mps2[i].map_or(f32::NAN, |e| e.value);
                signs &= g.signum() == eps[i].signum() && a.signum() == nabla[i].signum();
                worst_g = worst_g.max((g - eps[i]).abs() / DEG_PER_HOUR);
                worst_a = worst_a.max((a - nabla[i]).abs() / MICRO_G);
            }
            let mut label: heapless::String<48> = heapless::String::new();
            let _ = write!(label, "six_position_{name}_signs");
            report.check(&label, signs, 0.0);
            label.clear();
            let _ = write!(label, "six_position_{name}_gyro_error_deg_per_h");
            report.check(&label, worst_g < gyro_tol, worst_g);
            label.clear();
            let _ = write!(label, "six_position_{name}_accel_error_ug");
            report.check(&label, worst_a < accel_tol, worst_a);
        }
    }

    fn prefilter(report: &mut Report) {
        let Ok(mut f) = HmmKf::new(&PrefilterSettings::paper_gyro()) else {
            report.check("prefilter_gain", false, 0.0);
            return;
        };
        let c = 7.292_115e-5f32;
        let exact = (0..5000).all(|_| f.update(c) == c);
        report.check("prefilter_passes_constant_bit_exactly", exact, c);
        let (dc, _) = f.impulse_response_sums();
        report.check("prefilter_dc_gain_one", (dc - 1.0).abs() < 1e-4, dc);
        // The gain bits, for the host test to compare with x86.
        report.check("prefilter_gain_k00_bits", true, f.gain()[0][0]);
    }

    fn accumulator(report: &mut Report) {
        // 72,000 samples of 9.80665 + a +-1e-3 square wave: mean 9.80665 exactly (in f32 terms), variance 1e-6.
        let mut s = DwellStats::new();
        for k in 0..72_000u32 {
            s.add(9.806_65 + if k % 2 == 0 { 1e-3 } else { -1e-3 });
        }
        let mean = s.mean().unwrap_or(0.0);
        let var = s.variance().unwrap_or(0.0);
        report.check("accumulator_mean_m_s2", (mean - 9.806_65).abs() <= 1e-6, mean);
        report.check("accumulator_variance_rel_error", ((var - 1e-6) / 1e-6).abs() < 1e-3, var);
    }

    fn general_estimator(report: &mut Report) {
        // The exact 24-pose session with every static term, solved on the target: the truth comes back, and the
        // bits of every parameter are printed for the host test to compare with x86.
        use sinscal::calib::general::{ChannelEstimator, ChannelSettings, Model};
        let mut est = ChannelEstimator::new(
            sinscal::rig::exact::site(),
            ChannelSettings { model: Model::FULL, ..ChannelSettings::default() },
        );
        for d in sinscal::rig::exact::session() {
            if est.add(d).is_err() {
                report.check("channels_add", false, 0.0);
                return;
            }
        }
        let Ok(sol) = est.solve() else {
            report.check("channels_solve", false, 0.0);
            return;
        };
        let truth = sinscal::rig::exact::truth();
        let mut worst = 0.0f32;
        for (i, t) in truth.iter().enumerate() {
            worst = worst.max((sol.parameters_si[i] - t).abs() / sinscal::rig::exact::physical_scale(i));
        }
        report.check("channels_full_model_worst_error_of_scale", worst < 1e-6 && sol.unobservable == 0, worst);
        report.check("channels_parameter_bits_hash", true, sinscal::rig::exact::bits_hash(&sol.parameters_si));
        report.check("channels_chi_square_bits", true, sol.chi_square);
    }

    /// The payload byte `i` of test record `seed`.
    fn record_byte(i: usize, seed: usize) -> u8 {
        (i.wrapping_mul(131).wrapping_add(seed * 7919) >> 2) as u8
    }

    fn record_store(report: &mut Report) {
        // The calibration record through RecordStore<HostFileFlash>: two stores into a missing flash file, then
        // the file opened again (a "power cycle") and the newest record read back.
        use sinscal::instrument::store::RecordStore;
        use sinscal::rig::semihost::{arg_path, HostFileFlash};
        let Some(path) = arg_path(1).and_then(|p| p.with_suffix(".flash")) else {
            report.check("record_store_scratch_path", false, 0.0);
            return;
        };
        let _ = semihosting::fs::remove_file(path.as_c_str());
        let slot_bytes = HostFileFlash::SECTOR_BYTES as u32;
        let Ok(mut store) = RecordStore::new(HostFileFlash::open(path), slot_bytes) else {
            report.check("record_store_layout", false, 0.0);
            return;
        };
        report.check("record_store_missing_file_reads_empty", matches!(store.newest(), Ok(None)), 0.0);
        let max = store.max_payload();
        let mut stored = [None, None];
        for (k, len) in [10_240, max].into_iter().enumerate() {
            stored[k] = store
                .store(len, |offset, chunk| {
                    chunk.iter_mut().enumerate().for_each(|(i, b)| *b = record_byte(offset + i, k));
                    Ok(())
                })
                .ok();
        }
        let erases = stored.iter().flatten().map(|r| r.erases).sum::<u32>();
        let alternate = matches!(stored, [Some(a), Some(b)] if (a.slot, b.slot, b.sequence) == (0, 1, 2));
        report.check("record_store_two_stores_two_erases", alternate && erases == 2, erases as f32);
        // Power cycle: the file opened again by a new store.
        let path = store.release().into_path();
        let Ok(mut store) = RecordStore::new(HostFileFlash::open(path), slot_bytes) else { return };
        let Ok(Some(info)) = store.newest() else {
            report.check("record_store_reopened_finds_the_record", false, 0.0);
            return;
        };
        let mut chunk = [0u8; 256];
        let mut mismatches = 0u32;
        for offset in (0..info.len).step_by(chunk.len()) {
            let n = chunk.len().min(info.len - offset);
            if store.read(&info, offset, &mut chunk[..n]).is_err() {
                mismatches += 1;
            }
            mismatches +=
                chunk[..n].iter().enumerate().filter(|(i, &b)| b != record_byte(offset + i, 1)).count() as u32;
        }
        let same = (info.sequence, info.len) == (2, max) && mismatches == 0;
        report.check("record_store_reopened_record_bit_identical", same, mismatches as f32);
        let path = store.release().into_path();
        report.check("record_store_scratch_removed", semihosting::fs::remove_file(path.as_c_str()).is_ok(), 0.0);
    }

    fn host_file_flash(report: &mut Report) {
        // The flash file's NOR semantics: a short file reads as erased past its end and is extended with 0xFF, a
        // write ANDs, an erase sets 0xFF.
        use embedded_storage::nor_flash::{NorFlash, ReadNorFlash};
        use sinscal::rig::semihost::{arg_path, write_file, HostFileFlash};
        let Some(path) = arg_path(1).and_then(|p| p.with_suffix(".flash")) else { return };
        let written = write_file(&path, &[0x00; 6]);
        let mut flash = HostFileFlash::open(path);
        let mut bytes = [0u8; 8];
        let short = flash.read(4, &mut bytes).is_ok() && bytes == [0, 0, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF];
        let mut tail = [0u8; 4];
        let anded = flash.write(8, &[0xF0; 4]).is_ok()
            && flash.write(8, &[0x3C; 4]).is_ok()
            && flash.read(8, &mut bytes).is_ok()
            && bytes == [0x30, 0x30, 0x30, 0x30, 0xFF, 0xFF, 0xFF, 0xFF]
            && flash.read(HostFileFlash::CAPACITY_BYTES as u32 - 4, &mut tail).is_ok()
            && tail == [0xFF; 4];
        let erased = flash.erase(0, HostFileFlash::SECTOR_BYTES as u32).is_ok()
            && flash.read(0, &mut bytes).is_ok()
            && bytes == [0xFF; 8];
        let refused = flash.write(2, &[0; 4]).is_err() && flash.erase(0, 100).is_err();
        report.check("host_file_flash_nor_semantics", written && short && anded && erased && refused, 0.0);
        let _ = semihosting::fs::remove_file(flash.into_path().as_c_str());
    }

    fn move_integration(report: &mut Report) {
        // A move's rotation from 1000 rate samples that turn and change (the host computes the same sequence and
        // compares the bits: host-tests/tests/qemu.rs).
        let mut m = sinscal::nav::strapdown::MoveIntegrator::new(0.01);
        for k in 0..1000 {
            let k = k as f32;
            m.push([0.3 - 0.0006 * k, 0.1 + 0.0004 * k, -0.2 + 0.0001 * k * k * 0.001]);
        }
        let q = m.rotation().0;
        for (i, c) in q.iter().enumerate() {
            let name = ["move_rotation_w_bits", "move_rotation_x_bits", "move_rotation_y_bits", "move_rotation_z_bits"];
            report.check(name[i], c.is_finite(), *c);
        }
    }

    fn move_sums(report: &mut Report) {
        // A move integrated with the rates compensated by a prior with every gyro term, and its sensitivity sums
        // (sinscal::rig::exact::turning_move): the compensated rotation must be the true one, every gyro term
        // observed; the host recomputes the finished move and compares its bits (host-tests/tests/qemu.rs).
        use sinscal::calib::moves::MOVE_COLUMNS;
        use sinscal::rig::exact::{move_bits_hash, turning_move, MOVE_DT_S, MOVE_SAMPLES};
        let Ok((m, truth)) = turning_move() else {
            report.check("move_sums_prior", false, 0.0);
            return;
        };
        let error_rad = sinscal::math::linalg::norm(m.rotation.conjugate().mul(&truth).to_rotation_vector());
        report.check("move_sums_rotation_error_rad", error_rad < 2e-6, error_rad);
        let finite = m.rotation.0.iter().chain(m.jacobian.iter().flatten()).all(|x| x.is_finite())
            && m.covariance_rad2.is_finite();
        let observed = (0..MOVE_COLUMNS).all(|c| (0..3).any(|a| m.jacobian[a][c] != 0.0));
        report.check("move_sums_jacobian_finite_every_column_observed", finite && observed, 0.0);
        let duration_s = MOVE_SAMPLES as f32 * MOVE_DT_S;
        report.check("move_sums_duration_bits", (m.duration_s - duration_s).abs() < 1e-3, m.duration_s);
        report.check_hex("move_sums_bits_fnv", true, move_bits_hash(&m));
        for (c, name) in m.rotation.0.iter().zip(["w", "x", "y", "z"]) {
            let mut label: heapless::String<32> = heapless::String::new();
            let _ = write!(label, "move_sums_rotation_{name}_bits");
            report.check(&label, true, *c);
        }
        report.check("move_sums_jacobian_0_0_bits", true, m.jacobian[0][0]);
        report.check("move_sums_jacobian_2_20_bits", true, m.jacobian[2][MOVE_COLUMNS - 1]);
        report.check("move_sums_covariance_0_1_bits", true, m.covariance_rad2.0[0][1]);
    }

    fn watchdog(report: &mut Report) {
        // The board's watchdog: present, counting down from its load value, and fed back to it.
        use sinscal::board::watchdog;
        report.check("watchdog_present", watchdog::present(), 0.0);
        // QEMU counts the watchdog in host time, and a loaded host can stall the guest between two reads (a fixed
        // delay of 134 us once lost to a stall between the feed and its read-back): wait until half the period
        // has gone, so that only a stall of half a period (50 ms) could hide the feed.
        const PERIOD_US: u32 = 100_000;
        const HALF_TICKS: u32 = sinscal::board::mps2_an386::CLOCK_HZ / 1_000_000 * PERIOD_US / 2;
        watchdog::start(PERIOD_US);
        let first = watchdog::value();
        let mut later = first;
        let mut polls = 0u32;
        while later > HALF_TICKS && polls < 50_000_000 {
            later = watchdog::value();
            polls += 1;
        }
        watchdog::feed();
        let fed = watchdog::value();
        watchdog::stop();
        let fed_back = first > later && later <= HALF_TICKS && fed > HALF_TICKS;
        report.check("watchdog_counts_down_and_is_fed", fed_back, fed.wrapping_sub(later) as f32);
        // Not fed for more than a period: its interrupt, the NMI, fires (the handler stops the watchdog).
        WATCHDOG_NMI.store(false, core::sync::atomic::Ordering::SeqCst);
        watchdog::start(1_000);
        // QEMU counts the watchdog in host time: wait until its count has gone round at least once.
        let mut polls = 0u32;
        let mut last = watchdog::value();
        while !WATCHDOG_NMI.load(core::sync::atomic::Ordering::SeqCst) && polls < 50_000_000 {
            let now = watchdog::value();
            if now > last {
                polls = polls.max(49_000_000);
            }
            last = now;
            polls += 1;
        }
        let fired = WATCHDOG_NMI.load(core::sync::atomic::Ordering::SeqCst);
        watchdog::stop();
        report.check("watchdog_unfed_raises_the_nmi", fired, 0.0);
    }

    static WATCHDOG_NMI: core::sync::atomic::AtomicBool = core::sync::atomic::AtomicBool::new(false);

    #[cortex_m_rt::exception]
    unsafe fn NonMaskableInt() {
        sinscal::board::watchdog::stop();
        WATCHDOG_NMI.store(true, core::sync::atomic::Ordering::SeqCst);
    }

    fn bounded_spi(report: &mut Report) {
        // The PL022 with its port disabled never moves a byte: the transfer must give up with a timeout (not
        // hang), and the port must work again once enabled. (The chip select's release is not visible here:
        // QEMU's MPS2 leaves the GPIO block unimplemented.)
        use embedded_hal::spi::SpiDevice;
        use sinscal::board::mps2_an386::{Pl022, SpiError};
        let mut spi = Pl022::init();
        spi.disable();
        let mut word = [0u8; 2];
        let stalled = spi.transaction(&mut [embedded_hal::spi::Operation::Read(&mut word)]);
        report.check("spi_stalled_port_times_out", stalled == Err(SpiError::Timeout), 0.0);
        spi.enable();
        report.check("spi_port_works_again_when_enabled", spi.read(&mut word).is_ok(), 0.0);
    }

    #[entry]
    fn main() -> ! {
        let mut report = Report { text: heapless::String::new(), passed: 0, failed: 0 };
        exact_six_position(&mut report);
        prefilter(&mut report);
        accumulator(&mut report);
        general_estimator(&mut report);
        host_file_flash(&mut report);
        record_store(&mut report);
        bounded_spi(&mut report);
        watchdog(&mut report);
        move_integration(&mut report);
        move_sums(&mut report);
        let _ = writeln!(report.text, "{} passed, {} failed", report.passed, report.failed);
        if let Some(path) = sinscal::rig::semihost::arg_path(1) {
            sinscal::rig::semihost::write_file(&path, report.text.as_bytes());
        }
        exit(report.failed as i32)
    }
}
