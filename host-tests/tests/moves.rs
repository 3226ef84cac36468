//! SIMULATION: the moves between dwells as observations of the gyro terms (docs/method.md#moves), through the
//! recording format and `calibrate`. Exact data (no noise) with every gyro term of both signs are recovered to
//! 1e-5 of each parameter's scale (1 for scale factors and misalignments, the Earth rate for biases, the Earth
//! rate per g for the g-sensitivity); with unknown headings (each move without its part about up) as well; and
//! with the scenario's noise the moves make the gyro scale factors and misalignments hundreds of times more
//! precise than the static dwells alone.

mod common;

use std::path::Path;

use sinscal::calib::general::{parameter_name, Model, PARAMETERS};
use sinscal_host::calibration::{calibrate, Calibration, Options};
use sinscal_host::io::recording::Recording;
use sinscal_host::model::simulator::{simulate, ScenarioFile};

const EARTH_RATE_RADPS: f64 = 7.292115e-5;
const G_MPS2: f64 = 9.80665;

fn scenario() -> ScenarioFile {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/rotations.toml");
    ScenarioFile::read(&path).expect("scenario")
}

/// The scenario without noise, every error term times `sign`.
fn exact(sign: f64) -> ScenarioFile {
    let mut s = scenario();
    s.gyro.angle_random_walk_rad_per_sqrt_s = 0.0;
    s.accel.velocity_random_walk_mps_per_sqrt_s = 0.0;
    let flip3 = |v: [f64; 3]| v.map(|x| sign * x);
    s.gyro.bias_radps = flip3(s.gyro.bias_radps);
    s.gyro.scale_factor = flip3(s.gyro.scale_factor);
    s.gyro.misalignment = s.gyro.misalignment.map(flip3);
    s.gyro.g_sensitivity_radps_per_mps2 = s.gyro.g_sensitivity_radps_per_mps2.map(flip3);
    s.accel.bias_mps2 = flip3(s.accel.bias_mps2);
    s.accel.scale_factor = flip3(s.accel.scale_factor);
    s.accel.misalignment = s.accel.misalignment.map(flip3);
    s
}

/// The true parameters of a scenario in the estimator's order.
fn truth(s: &ScenarioFile) -> [f64; PARAMETERS] {
    let mut t = [0.0; PARAMETERS];
    let off = |m: &[[f64; 3]; 3], k: usize| {
        let (i, j) = [(0, 1), (0, 2), (1, 0), (1, 2), (2, 0), (2, 1)][k];
        m[i][j]
    };
    for i in 0..3 {
        t[i] = s.gyro.bias_radps[i];
        t[3 + i] = s.accel.bias_mps2[i];
        t[6 + i] = s.accel.scale_factor[i];
        t[15 + i] = s.gyro.scale_factor[i];
        for j in 0..3 {
            t[24 + 3 * i + j] = s.gyro.g_sensitivity_radps_per_mps2[i][j];
        }
    }
    for k in 0..6 {
        t[9 + k] = off(&s.accel.misalignment, k);
        t[18 + k] = off(&s.gyro.misalignment, k);
    }
    t
}

fn scale_of(index: usize) -> f64 {
    match index {
        0..=2 => EARTH_RATE_RADPS,
        3..=5 => G_MPS2,
        24..=32 => EARTH_RATE_RADPS / G_MPS2,
        _ => 1.0,
    }
}

fn run(recording: &Recording, use_moves: bool) -> Calibration {
    let text = recording.to_csv();
    let rec = Recording::parse(&text, "moves.csv").expect("parse");
    calibrate(&rec, &Options { model: Model::FULL, use_moves, ..Options::default() }).expect("calibrate")
}

/// Every parameter of the full model within `tol` of its scale; returns the worst relative error.
fn assert_recovered(cal: &Calibration, t: &[f64; PARAMETERS], tol: f64) -> f64 {
    let s = cal.channels.as_ref().expect("general estimator");
    let mut worst = 0.0f64;
    for (i, truth) in t.iter().enumerate().take(33) {
        let (value, _) = s.estimate(i).unwrap_or_else(|| panic!("{} is not determined", parameter_name(i)));
        let err = (value as f64 - truth).abs() / scale_of(i);
        if truth.abs() / scale_of(i) > 10.0 * tol {
            assert_eq!((value as f64).signum(), truth.signum(), "{}: sign", parameter_name(i));
        }
        assert!(err < tol, "{}: {value} vs {truth} (error {err:.2e} of its scale)", parameter_name(i));
        worst = worst.max(err);
    }
    worst
}

#[test]
fn exact_moves_recover_every_gyro_term_of_both_signs() {
    for sign in [1.0, -1.0] {
        let s = exact(sign);
        let cal = run(&simulate(&s, 1, "exact"), true);
        assert_eq!(cal.moves.len(), 13, "a move between each two of the 14 positions");
        assert!(cal.move_passes >= 2, "integrated again with the estimate");
        for m in &cal.moves {
            let error_rad = m.residual_rad.iter().map(|x| x * x).sum::<f64>().sqrt();
            assert!(error_rad < 1e-5, "move at line {}: {error_rad} rad left", m.first_line);
        }
        let worst = assert_recovered(&cal, &truth(&s), 1e-5);
        println!("sign {sign:+}: worst error {worst:.2e} of the scale, {} passes with the moves", cal.move_passes);
    }
}

#[test]
fn exact_moves_with_unknown_headings_recover_every_gyro_term() {
    // The headings blanked: each move is compared without its part about up (two components).
    let mut rec = simulate(&exact(1.0), 2, "exact, headings unknown");
    for row in &mut rec.rows {
        row.heading_deg = None;
    }
    let cal = run(&rec, true);
    assert_eq!(cal.moves.len(), 13);
    let t = truth(&exact(1.0));
    let s = cal.channels.as_ref().unwrap();
    let mut worst = 0.0f64;
    for i in [15, 16, 17, 18, 19, 20, 21, 22, 23] {
        let (value, _) = s.estimate(i).unwrap_or_else(|| panic!("{} is not determined", parameter_name(i)));
        let err = (value as f64 - t[i]).abs();
        assert!(err < 1e-5, "{}: {value} vs {}", parameter_name(i), t[i]);
        worst = worst.max(err);
    }
    println!("headings unknown: worst gyro scale factor or misalignment error {worst:.2e}");
}

#[test]
fn the_moves_determine_the_gyro_matrix_the_dwells_cannot() {
    // The scenario's noise (0.15 deg/sqrt(h)): through the Earth rate alone the static dwells leave the gyro scale
    // factors and misalignments at the 1e-1 level; the moves bring them to 1e-4.
    let rec = simulate(&scenario(), 3, "rotations");
    let with = run(&rec, true);
    let without = run(&rec, false);
    let (a, b) = (with.channels.as_ref().unwrap(), without.channels.as_ref().unwrap());
    let t = truth(&scenario());
    for i in 15..24 {
        let (value, std_with) = a.estimate(i).unwrap();
        let std_without = b.estimate(i).map_or(f32::INFINITY, |e| e.1);
        println!(
            "{:<24} {:+.6} ± {:.6} (truth {:+.6}); without the moves ± {:.4}",
            parameter_name(i),
            value,
            std_with,
            t[i],
            std_without
        );
        assert!(std_with < 1e-4, "{}: ± {std_with}", parameter_name(i));
        assert!(std_without > 100.0 * std_with, "{}: {std_without} vs {std_with}", parameter_name(i));
        assert!(((value as f64) - t[i]).abs() < 4.0 * std_with as f64, "{}: {value} vs {}", parameter_name(i), t[i]);
    }
}

#[test]
fn the_firmware_path_integrates_the_moves_too() {
    // The sequence integrates each move once, with no prior (docs/method.md#moves): on the scenario's noise its
    // gyro scale factors and misalignments are the direct path's within a fifth of their standard errors, and in
    // QEMU the Cortex-M4F gives the same JSON as x86.
    let rec = simulate(&scenario(), 3, "rotations");
    let options = Options { model: Model::FULL, ..Options::default() };
    let direct = run(&rec, true);
    let firmware = sinscal_host::calibration::firmware_path::calibrate_on_host(&rec, &options).expect("--on host");
    let (a, b) = (direct.channels.as_ref().unwrap(), firmware.channels.as_ref().unwrap());
    for i in 15..24 {
        let ((x, sx), (y, sy)) = (a.estimate(i).unwrap(), b.estimate(i).unwrap());
        println!("{:<24} direct {x:+.6} ± {sx:.6}, firmware path {y:+.6} ± {sy:.6}", parameter_name(i));
        assert!(sy < 1e-4, "{}: ± {sy}: the firmware path did not use the moves", parameter_name(i));
        assert!((x - y).abs() < 0.2 * sx, "{}: {x} vs {y}", parameter_name(i));
    }
    if common::qemu_available(" (the moves in QEMU)") {
        let qemu = sinscal_host::calibration::qemu::calibrate_on_qemu(&rec, &options).expect("--on qemu");
        let json = |c: &Calibration| {
            let mut v = serde_json::to_value(sinscal_host::calibration::result::CalibrationJson::new(c)).unwrap();
            v.as_object_mut().unwrap().remove("on");
            v
        };
        assert_eq!(json(&qemu), json(&firmware), "--on qemu and --on host differ");
        let sf = qemu.channels.as_ref().and_then(|s| s.estimate(15)).expect("gyro scale factor x");
        println!("--on qemu: the same JSON as --on host (gyro scale factor x {:+.6} ± {:.6})", sf.0, sf.1);
    }
}

#[test]
fn the_firmware_path_refuses_moves_at_another_rate_than_the_imus() {
    // At 50 Hz the ADIS's 10 ms interval would halve every move's angle: refused with the reason; without the
    // terms that use the moves the same recording goes through.
    let mut s = scenario();
    s.schedule.rate_hz = 50.0;
    s.schedule.positions_deg.truncate(4);
    let rec = simulate(&s, 4, "rotations at 50 Hz");
    let full = Options { model: Model::FULL, ..Options::default() };
    let err = sinscal_host::calibration::firmware_path::calibrate_on_host(&rec, &full).expect_err("refused");
    let text = err.to_string();
    assert!(text.contains("100 Hz") && text.contains("50 Hz"), "{text}");
    sinscal_host::calibration::firmware_path::calibrate_on_host(&rec, &Options::default()).expect("default model");
}

#[test]
fn a_move_to_a_dwell_that_was_not_added_is_refused_not_a_panic() {
    let mut s = scenario();
    s.schedule.positions_deg.truncate(3);
    let rec = simulate(&s, 5, "three positions");
    let session =
        sinscal_host::calibration::channel_session(&rec, &Options { model: Model::FULL, ..Options::default() }, false)
            .expect("session");
    let sums = sinscal::calib::moves::MoveSums::new(&[0.0; PARAMETERS]).expect("prior");
    let mut m = sums.finish(0, 1, [1e-6; 3]);
    m.duration_s = 1.0;
    m.to = 99;
    for result in [session.estimator.solve_with(&[m]), session.estimator.solve_excluding_with(1, &[m])] {
        assert!(matches!(result, Err(sinscal::calib::general::ChannelError::BadMove { index: 0 })), "{result:?}");
    }
}

/// A labelled turn after the last dwell (as a Ferraris session ends with its turns): the scenario's positions
/// and four more, level at headings 0, 120, 240 and 0 (a full turn about the body z axis in three moves); the
/// last three dwells' rows made `pos = 0`, and the rows from the level dwell to the last labelled `turn = z`.
/// Exact data: the turn is an observation beside the 14 moves, its error after the fit within the horizontal
/// Earth rate it leaves out, every parameter recovered; the same rows without the label are a run after the
/// last dwell, not used.
#[test]
fn a_labelled_turn_after_the_last_dwell_is_an_observation() {
    let mut s = exact(1.0);
    let level = s.schedule.positions_deg.len() as u32 + 1;
    s.schedule.positions_deg.extend([[0.0, 0.0, 0.0], [0.0, 0.0, 120.0], [0.0, 0.0, 240.0], [0.0, 0.0, 0.0]]);
    let mut rec = simulate(&s, 3, "exact, a labelled turn at the end");
    let first = rec.rows.iter().rposition(|r| r.pos == level).expect("the level dwell") + 1;
    let end = rec.rows.iter().position(|r| r.pos == level + 3).expect("the last dwell");
    for row in &mut rec.rows {
        if row.pos > level {
            row.pos = 0;
        }
    }
    let unlabelled = run(&rec, true);
    for row in &mut rec.rows[first..end] {
        row.turn_axis = Some(2);
    }
    let text = rec.to_csv();
    assert!(text.lines().any(|l| l.ends_with(",z")), "the turn column is written");
    let cal = run(&rec, true);
    assert_eq!(unlabelled.moves.len(), 14, "without the label the rows after the last dwell are not a move");
    assert_eq!(cal.moves.len(), 15, "the 14 moves and the turn");
    let turn = cal.moves.iter().find(|m| m.turn == Some("z")).expect("the turn about z is used");
    // A full turn, and the Earth rate about up over the minute it lasts.
    assert!((turn.angle_deg - 360.0).abs() < 0.5, "a full turn: {} deg", turn.angle_deg);
    // A turn's reference is the Earth's rotation about up; the horizontal part turns with the body and is its
    // noise (docs/method.md#moves): over the two stops of this turn it does not average out.
    let error_rad = turn.residual_rad.iter().map(|x| x * x).sum::<f64>().sqrt();
    assert!(error_rad < EARTH_RATE_RADPS * turn.duration_s, "the turn: {error_rad} rad left");
    let worst = assert_recovered(&cal, &truth(&s), 1e-5);
    println!("a labelled turn after the last dwell: worst error {worst:.2e} of the scale");
    // The device's sequence solves when the table leaves its last position: the firmware path refuses a turn
    // after it, with the reason, rather than calibrate without it.
    let full = Options { model: Model::FULL, ..Options::default() };
    let err = sinscal_host::calibration::firmware_path::calibrate_on_host(&rec, &full).expect_err("refused");
    assert!(err.to_string().contains("after the last dwell"), "{err}");
}

/// Table moves, hand moves and a labelled turn between two dwells, exact data: the scenario's positions and four
/// more, level at headings 0, 120, 240 and 0 (a full turn about body z in three moves, the two dwells inside it
/// made `pos = 0` and its rows labelled `turn = z`); positions 9 to 13 without their headings (hand-placed: each
/// move to or from them is compared without its part about up). The direct path uses the 14 moves and the turn
/// and recovers every gyro scale factor and misalignment to 1e-6 and every parameter to 1e-5 of its scale; the
/// firmware path integrates the turn too (once, with no prior), and in QEMU the Cortex-M4F gives the same JSON
/// as x86.
#[test]
fn table_moves_hand_moves_and_a_turn_between_dwells() {
    let mut s = exact(1.0);
    let level = s.schedule.positions_deg.len() as u32 + 1;
    s.schedule.positions_deg.extend([[0.0, 0.0, 0.0], [0.0, 0.0, 120.0], [0.0, 0.0, 240.0], [0.0, 0.0, 0.0]]);
    let mut rec = simulate(&s, 5, "exact, a labelled turn between two dwells");
    let first = rec.rows.iter().rposition(|r| r.pos == level).expect("the level dwell") + 1;
    let end = rec.rows.iter().position(|r| r.pos == level + 3).expect("the dwell after the turn");
    for row in &mut rec.rows {
        if row.pos == level + 1 || row.pos == level + 2 {
            row.pos = 0;
        }
        if (9..=13).contains(&row.pos) {
            row.heading_deg = None;
        }
    }
    for row in &mut rec.rows[first..end] {
        row.turn_axis = Some(2);
    }
    let rec = Recording::parse(&rec.to_csv(), "turn-between.csv").expect("parse");
    let options = Options { model: Model::FULL, ..Options::default() };
    let direct = calibrate(&rec, &options).expect("calibrate");
    let turns = direct.moves.iter().filter(|m| m.turn.is_some()).count();
    assert_eq!((direct.moves.len(), turns), (15, 1), "14 moves and the turn (the run holding it is no move)");
    let t = truth(&s);
    let worst = assert_recovered(&direct, &t, 1e-5);
    let gyro_matrix_error = |cal: &Calibration| {
        let s = cal.channels.as_ref().expect("general estimator");
        (15..24).map(|i| (s.estimate(i).expect("determined").0 as f64 - t[i]).abs()).fold(0.0f64, f64::max)
    };
    let worst_gyro = gyro_matrix_error(&direct);
    println!("direct path: every parameter within {worst:.2e} of its scale, the gyro matrix within {worst_gyro:.2e}");
    assert!(worst_gyro < 1e-6, "{worst_gyro}");
    let firmware = sinscal_host::calibration::firmware_path::calibrate_on_host(&rec, &options).expect("--on host");
    let worst_firmware = gyro_matrix_error(&firmware);
    println!("firmware path (one pass, no prior): the gyro matrix within {worst_firmware:.2e}");
    assert!(worst_firmware < 1e-4, "{worst_firmware}");
    // Without the turn's label the firmware path's answer is another (its rows a move, not a turn).
    let mut unlabelled = rec.clone();
    for row in &mut unlabelled.rows {
        row.turn_axis = None;
    }
    let without =
        sinscal_host::calibration::firmware_path::calibrate_on_host(&unlabelled, &options).expect("--on host");
    assert_ne!(gyro_matrix_error(&without), worst_firmware, "the firmware path used the turn");
    if common::qemu_available(" (the turn in QEMU)") {
        let qemu = sinscal_host::calibration::qemu::calibrate_on_qemu(&rec, &options).expect("--on qemu");
        let json = |c: &Calibration| {
            let mut v = serde_json::to_value(sinscal_host::calibration::result::CalibrationJson::new(c)).unwrap();
            v.as_object_mut().unwrap().remove("on");
            v
        };
        assert_eq!(json(&qemu), json(&firmware), "--on qemu and --on host differ");
        println!("--on qemu: the same JSON as --on host");
    }
}
