//! The firmware in QEMU (mps2-an386, Cortex-M4F) against the same replay path on x86: byte-identical
//! outcomes (every f32 bit), and identical `sinscal calibrate --on host|qemu` JSON. Needs qemu-system-arm
//! and the thumbv7em target (scripts/setup installs both); in CI (`SINSCAL_REQUIRE_ALL` set by .ci/run) a missing QEMU is a failure,
//! elsewhere the test reports itself as skipped.

mod common;

use sinscal_host::io::noise_file::NoiseTerms;

use sinscal::calib::session::{session_estimator, SessionDwell};
use sinscal::instrument::wire::outcome::{Outcome, MAX_BYTES as MAX_OUTCOME_BYTES};
use sinscal::rig::replay::{read_header, run_replay};
use sinscal::run::sequence::{Estimator, SequenceSolution};
use sinscal_host::calibration::firmware_path::{calibrate_on_host, replay_file};
use sinscal_host::calibration::qemu::{
    calibrate_on_qemu, firmware_binary, firmware_elf, run_firmware, run_with_output,
};
use sinscal_host::calibration::result::CalibrationJson;
use sinscal_host::calibration::Options;
use sinscal_host::model::synth::Scenario;

fn json_without_on(c: &sinscal_host::calibration::Calibration) -> serde_json::Value {
    let mut v = serde_json::to_value(CalibrationJson::new(c)).unwrap();
    v.as_object_mut().unwrap().remove("on");
    v
}

#[test]
fn firmware_in_qemu_and_the_host_replay_agree_to_the_bit() {
    if !common::qemu_available("") {
        return;
    }
    let elf = firmware_elf().expect("firmware builds");
    let rec = Scenario { dwell_s: 30.0, ..Scenario::example() }.recording(11, "example.csv");
    let mut unknown_headings = rec.clone();
    for row in unknown_headings.rows.iter_mut().filter(|r| r.pos == 2 || r.pos == 5) {
        row.heading_deg = None;
    }
    let full = Options { model: sinscal::calib::general::Model::FULL, ..Options::default() };
    // A spike of 1.7 deg/s (inside the sequence's rest limit) in dwell 1, and the labels known to half a degree:
    // the gate and the pose priors run on the target as on x86.
    let mut spiked = rec.clone();
    assert_eq!(spiked.rows[1500].pos, 1);
    spiked.rows[1500].rate_b_radps[0] += 0.029_67;
    let tolerant = Options { pose_tolerance_deg: Some(0.5), ..Options::default() };
    // A noise model with every term (the exponentials of Gauss-Markov and sway on either side of their series), so that
    // the dwell variances computed on the target are those of x86.
    let terms = |scale: f32| sinscal::calib::noise_model::ChannelNoiseTerms {
        quantisation_u_s: 1e-3 * scale,
        white_u_sqrt_s: 1e-2 * scale,
        instability_u: 1e-3 * scale,
        gauss_markov_u: 3e-3 * scale,
        gauss_markov_time_s: if scale < 1e-3 { 10.0 } else { 100.0 },
        random_walk_u_per_sqrt_s: 1e-5 * scale,
        ramp_u_per_s: 1e-7 * scale,
        sway_u_s: 1e-3 * scale,
        sway_time_s: if scale < 1e-3 { 10.0 } else { 100.0 },
    };
    let channels = [1e-5f32, 1e-5, 1e-5, 0.1, 0.1, 0.1].map(|s| Some(terms(s)));
    let noisy = Options { noise: Some(NoiseTerms { channels, from_recording: false }), ..Options::default() };
    for (rec, options) in [
        (&rec, Options::angles()),
        (
            &rec,
            Options { prefilter: sinscal_host::calibration::PrefilterKind::None, max_passes: 1, ..Options::angles() },
        ),
        (&rec, Options::default()),
        (&rec, full),
        (&unknown_headings, Options::default()),
        (&spiked, tolerant),
        (&rec, noisy),
    ] {
        let (mut file, _) = replay_file(rec, &options).unwrap();
        // Also a corrupted frame (a gyro byte of row 1000, inside dwell 1), so the fault path runs on both.
        let header_len = sinscal::rig::replay::replay_header_bytes(6);
        let record = 1 + sinscal::sensor::adis::BURST32_LEN;
        assert_eq!(rec.rows[1000].pos, 1);
        file[header_len + 1000 * record + 1 + 4] ^= 0x01;
        let host = run_replay(&file[..], |_| {}).unwrap();
        let mut bytes = vec![0u8; MAX_OUTCOME_BYTES];
        let n = host.encode(&mut bytes).unwrap();
        let (target, log) = run_firmware(&elf, &file).expect("firmware runs");
        assert_eq!(target, bytes[..n].to_vec(), "outcome bytes differ; firmware log:\n{log}");
        assert!(host.result.is_some());
        assert_eq!(host.sampling.faults(), 1);
        let spikes: u32 = host.positions.iter().map(|p| p.summary.spikes).sum();
        assert_eq!(spikes, u32::from(std::ptr::eq(rec, &spiked)), "spikes counted");
        // The general estimator solved on the Cortex-M4F is the host core's solution of the firmware's own
        // dwell statistics, to the bit.
        let header = read_header(&mut &file[..]).unwrap();
        let decoded = Outcome::decode(&header.configuration, &target).unwrap();
        if let (Some(SequenceSolution::Channels(on_target)), Estimator::Channels(settings)) =
            (&decoded.result, header.configuration.sequence_estimator())
        {
            // Each dwell's first sample: the device counts every frame, so the row of the dwell's first row.
            let labels = &header.configuration.labels;
            let first = |k: usize| rec.rows.iter().position(|r| r.pos == u32::from(labels[k])).map(|i| i as u32);
            let dwells = decoded.positions.iter().enumerate().zip(&header.configuration.schedule).map(|((k, p), a)| {
                SessionDwell {
                    attitude: *a,
                    heading_known: header.configuration.unknown_headings & (1 << k) == 0,
                    summary: &p.summary,
                    first_sample: first(k),
                }
            });
            let on_x86 = session_estimator(dwells, header.configuration.site, settings, options.dwell_value)
                .unwrap()
                .solve()
                .unwrap();
            let bits = |c: &sinscal::calib::general::ChannelSolution| {
                let mut b = c.parameters_si.map(f32::to_bits).to_vec();
                b.extend(c.covariance_si.iter().flatten().map(|x| x.to_bits()));
                b.extend(c.heading_rad[..c.dwells].iter().map(|x| x.to_bits()));
                b.push(c.chi_square.to_bits());
                b
            };
            assert_eq!(bits(on_target), bits(&on_x86), "the estimator in QEMU differs from x86");
            assert_eq!((on_target.observable, on_target.suspect), (on_x86.observable, on_x86.suspect));
        }
    }
    for (rec, options) in [(&rec, Options::angles()), (&rec, Options::default()), (&spiked, tolerant), (&rec, noisy)] {
        let on_host = calibrate_on_host(rec, &options).unwrap();
        let on_qemu = calibrate_on_qemu(rec, &options).unwrap();
        assert_eq!(on_qemu.on, "qemu");
        assert_eq!(json_without_on(&on_host), json_without_on(&on_qemu));
    }
}

#[test]
fn on_target_tests_pass_in_qemu() {
    if !common::qemu_available("") {
        return;
    }
    let elf = firmware_binary("sinscal-selftest").expect("firmware builds");
    let (code, report) = run_with_output(&elf, false).expect("QEMU runs");
    println!("on-target tests (Cortex-M4F in QEMU):\n{report}");
    assert_eq!(code, 0, "{report}");
    assert!(report.lines().any(|l| l.ends_with(" passed, 0 failed")), "{report}");
    // The calibration record stored through the host-file flash, read back after the file was opened again.
    for check in [
        "host_file_flash_nor_semantics",
        "record_store_two_stores_two_erases",
        "record_store_reopened_record_bit_identical",
    ] {
        assert!(report.lines().any(|l| l.starts_with(&format!("ok {check} "))), "{check} missing\n{report}");
    }
    // The PL022 with its port stalled gives up with a timeout, and works again once enabled.
    for check in ["spi_stalled_port_times_out", "spi_port_works_again_when_enabled"] {
        assert!(report.contains(&format!("ok {check}")), "{check}\n{report}");
    }
    // The steady prefilter gain computed on the target is the x86 one, bit for bit.
    let k = sinscal::calib::prefilter::HmmKf::new(&sinscal::calib::prefilter::PrefilterSettings::paper_gyro())
        .unwrap()
        .gain()[0][0];
    assert!(report.contains(&format!("ok prefilter_gain_k00_bits {k:e}")), "host K00 = {k:e}\n{report}");
    // A move's rotation integrated on the target: the host's bits.
    let mut m = sinscal::nav::strapdown::MoveIntegrator::new(0.01);
    for k in 0..1000 {
        let k = k as f32;
        m.push([0.3 - 0.0006 * k, 0.1 + 0.0004 * k, -0.2 + 0.0001 * k * k * 0.001]);
    }
    for (c, name) in m.rotation().0.iter().zip(["w", "x", "y", "z"]) {
        let line = format!("ok move_rotation_{name}_bits {c:e}");
        assert!(report.contains(&line), "host: {line}\n{report}");
    }
    // A move integrated with MoveSums on the target, compensated by a prior with every gyro term: the host's
    // finished move, bit for bit (a hash of every f32 of it, and a few of them on their own).
    use sinscal::calib::moves::MOVE_COLUMNS;
    let (mv, _) = sinscal::rig::exact::turning_move().unwrap();
    for check in ["move_sums_rotation_error_rad", "move_sums_jacobian_finite_every_column_observed"] {
        assert!(report.lines().any(|l| l.starts_with(&format!("ok {check} "))), "{check} missing\n{report}");
    }
    let mut lines = vec![format!("ok move_sums_bits_fnv {:#010x}", sinscal::rig::exact::move_bits_hash(&mv))];
    for (c, name) in mv.rotation.0.iter().zip(["w", "x", "y", "z"]) {
        lines.push(format!("ok move_sums_rotation_{name}_bits {c:e}"));
    }
    lines.push(format!("ok move_sums_duration_bits {:e}", mv.duration_s));
    lines.push(format!("ok move_sums_jacobian_0_0_bits {:e}", mv.jacobian[0][0]));
    lines.push(format!("ok move_sums_jacobian_2_20_bits {:e}", mv.jacobian[2][MOVE_COLUMNS - 1]));
    lines.push(format!("ok move_sums_covariance_0_1_bits {:e}", mv.covariance_rad2.0[0][1]));
    for line in lines {
        assert!(report.lines().any(|l| l == line), "host: {line}\n{report}");
    }
    // The general estimator on the exact session, solved on x86 by the same core: the same bits as on the target.
    use sinscal::calib::general::{ChannelEstimator, ChannelSettings, Model};
    let mut est = ChannelEstimator::new(
        sinscal::rig::exact::site(),
        ChannelSettings { model: Model::FULL, ..ChannelSettings::default() },
    );
    for d in sinscal::rig::exact::session() {
        est.add(d).unwrap();
    }
    let sol = est.solve().unwrap();
    let hash = sinscal::rig::exact::bits_hash(&sol.parameters_si);
    assert!(report.contains(&format!("ok channels_parameter_bits_hash {hash:e}")), "host hash {hash:e}\n{report}");
    let chi = sol.chi_square;
    assert!(report.contains(&format!("ok channels_chi_square_bits {chi:e}")), "host chi-square {chi:e}\n{report}");
}
