//! Measured data: the gyro matrix that `calibrate --model full` gives from the rotations of the imucal Ferraris
//! session and of the imu_tk session, beside the data authors' references, and each calibration checked on the
//! session's rests: the gravity direction carried by the compensated gyros across every motion between two rests
//! (docs/method.md#held-out-moves), and |f| - g of the rests without a label. The study calls the product; so
//! do these tests.

mod common;

use sinscal_host::calibration::{calibrate, checks::checks, Options};
use sinscal_host::study::ferraris_turns;
use sinscal_host::study::rests::rms;
use sinscal_host::study::rotations::{ferraris_rotations, imutk_rotations, RotationFit, RotationStudy};

/// imucal 2.6.0's Ferraris gyro matrix `K_g R_g` on this session at 102.4 Hz (rows = gyro axes).
const IMUCAL_T_G: [[f64; 3]; 3] =
    [[1.027903, -0.000467, -0.006591], [-0.000218, 0.982424, -0.002735], [0.009698, 0.007628, 0.998234]];

fn print(study: &RotationStudy) {
    println!("reference: {}", study.reference_name);
    for f in &study.fits {
        println!(
            "fit on {}: `{}` ({} rotations, {} passes, chi-square {:.1} on {}, hand moves' error {:.3} deg, checks {})",
            f.name,
            f.command,
            f.rotations,
            f.passes,
            f.chi_square,
            f.degrees_of_freedom,
            f.move_error_deg,
            if f.checks_passed { "passed" } else { "FAILED" }
        );
        for i in 0..3 {
            println!(
                "  {:+.5} ± {:.5}  {:+.5} ± {:.5}  {:+.5} ± {:.5}",
                f.t_g[i][0], f.t_g_std[i][0], f.t_g[i][1], f.t_g_std[i][1], f.t_g[i][2], f.t_g_std[i][2]
            );
        }
        for t in &f.transitions {
            println!(
                "  {} ({}): turned {:.1} deg, gravity carried: raw {:.3} deg, calibrated {:.3} deg",
                t.label,
                if t.used_in_fit { "in the fit" } else { "held out" },
                t.angle_deg,
                t.raw_error_deg,
                t.calibrated_error_deg
            );
        }
        for r in &f.rests {
            println!(
                "  {} ({} samples): |f| - g raw {:+.4}, calibrated {:+.4} m/s^2",
                r.label, r.samples, r.raw_error_mps2, r.calibrated_error_mps2
            );
        }
    }
}

/// RMS of the raw and the calibrated gravity errors of the transitions `pick` selects, and their number.
fn carried(f: &RotationFit, pick: impl Fn(&sinscal_host::study::rests::Transition) -> bool) -> (usize, f64, f64) {
    let chosen: Vec<_> = f.transitions.iter().filter(|t| pick(t)).collect();
    (chosen.len(), rms(chosen.iter().map(|t| t.raw_error_deg)), rms(chosen.iter().map(|t| t.calibrated_error_deg)))
}

/// REAL DATA, the acceptance: `sinscal calibrate --model full` with default options on the imported
/// Ferraris session passes every check; every entry of T_g within 2 of its standard errors of imucal's; the 9
/// motions between rests that are not the labelled turns, gravity carried by the calibrated gyros: RMS <= 0.80
/// deg; the 7 rests without a label: RMS |f| - g <= 0.0050 m/s^2. Fitted on the turns alone, the 9 motions it
/// did not see are better than raw.
#[test]
fn ferraris_calibrate_full_against_imucal_and_the_rests() {
    let Some(dir) = common::data_dir() else { return };
    let labels = dir.join("imucal-ferraris/example_ferraris_session_list.json");
    let rec = common::ferraris_session(&dir);
    let turns = ferraris_turns(&rec, &labels).expect("turns");
    let study = ferraris_rotations(&rec, &turns).expect("rotations");
    print(&study);
    assert!(study.refused.is_empty(), "{:?}", study.refused);
    let all = &study.fits[0];
    assert_eq!(all.command, "sinscal calibrate --model full");
    assert!(all.checks_passed, "calibrate --model full passes every check (exit status 0)");
    for (i, row) in IMUCAL_T_G.iter().enumerate() {
        for (j, reference) in row.iter().enumerate() {
            let z = (all.t_g[i][j] - reference) / all.t_g_std[i][j];
            println!("  T_g[{i}][{j}] {:+.6} against imucal's {reference:+.6}: {z:+.2} standard errors", all.t_g[i][j]);
            assert!(z.abs() < 2.0, "T_g[{i}][{j}]: {z:.2} standard errors from imucal's");
        }
    }
    assert_eq!(all.transitions.len(), 12, "13 rests: 6 faces and 7 without a label");
    let (n, raw, calibrated) = carried(all, |t| !t.turn);
    println!("REAL DATA Ferraris, calibrate --model full: the {n} motions that are not turns, RMS raw {raw:.3} deg, calibrated {calibrated:.3} deg");
    assert_eq!(n, 9);
    assert!(calibrated <= 0.80, "{calibrated} deg");
    assert_eq!(all.rests.len(), 7);
    let force = rms(all.rests.iter().map(|r| r.calibrated_error_mps2));
    println!("REAL DATA Ferraris: the 7 rests without a label, RMS |f| - g {force:.4} m/s^2");
    assert!(force <= 0.0050, "{force} m/s^2");
    // The turns alone: the 9 other motions, which that fit never saw, better than raw.
    let turns_only = &study.fits[1];
    let (n, raw, calibrated) = carried(turns_only, |t| !t.used_in_fit);
    println!("fitted on the turns: {n} motions held out, RMS raw {raw:.3} deg, calibrated {calibrated:.3} deg");
    assert_eq!(n, 9);
    assert!(calibrated < 0.25 * raw, "{calibrated} vs {raw}");
}

/// REAL DATA, the acceptance: calibrate's own gyro terms (`--model full`, the 2nd, 4th, ... moves held
/// out) carry gravity across the 18 held-out moves to RMS <= 0.60 deg, and calibrate's own report of those moves
/// (their residuals against its attitudes) agrees with the independent check within 20 %; the fit on every move
/// gives the factory misalignments within 0.02.
#[test]
fn imutk_calibrate_full_on_held_out_moves() {
    let Some(dir) = common::data_dir() else { return };
    let rec = common::imutk_session(&dir);
    let study = imutk_rotations(&rec).expect("rotations");
    print(&study);
    assert!(study.refused.is_empty(), "{:?}", study.refused);
    let all = &study.fits[0];
    for i in 0..3 {
        for j in 0..3 {
            let d = (all.t_g[i][j] - study.reference_t_g[i][j]).abs();
            assert!(d < 0.02, "T_g[{i}][{j}]: {} vs factory {}", all.t_g[i][j], study.reference_t_g[i][j]);
        }
    }
    let half = &study.fits[1];
    assert!(half.checks_passed);
    let (n, raw, calibrated) = carried(half, |t| !t.used_in_fit);
    println!(
        "REAL DATA imu_tk: {n} moves held out, gravity carried: RMS raw {raw:.3} deg, calibrated {calibrated:.3} deg"
    );
    assert_eq!(n, 18);
    assert!(calibrated <= 0.60, "{calibrated} deg");
    // The same moves as calibrate reports them.
    let mask = half.command.rsplit(' ').next().expect("the list");
    let held: u64 = mask.split(',').map(|k| 1u64 << (k.parse::<u32>().expect("a number") - 1)).fold(0, |a, b| a | b);
    let options = Options { model: sinscal::calib::general::Model::FULL, hold_out_moves: held, ..Options::default() };
    let cal = calibrate(&rec, &options).expect("calibrate");
    assert!(checks(&cal).iter().all(|c| c.passed));
    let own: Vec<f64> = cal
        .moves
        .iter()
        .filter(|m| m.held_out)
        .map(|m| m.residual_rad.iter().map(|x| x * x).sum::<f64>().sqrt().to_degrees())
        .collect();
    let own_rms = rms(own.iter().copied());
    println!("calibrate's own report of the {} held-out moves: RMS {own_rms:.3} deg", own.len());
    assert_eq!(own.len(), 18);
    assert!((own_rms / calibrated - 1.0).abs() < 0.2, "{own_rms} vs {calibrated}");
}

/// REAL DATA: with exact labels (pose tolerance 0) the Ferraris hand moves' error is not named (they are a
/// turntable's moves then) and the fit check fails, as a turntable's misfit moves must.
#[test]
fn ferraris_moves_with_exact_labels_fail_the_fit_check() {
    let Some(dir) = common::data_dir() else { return };
    let rec = common::ferraris_session(&dir);
    let model = sinscal_host::calibration::estimates::parse_model(
        "biases,accel_scale_factor,gyro_scale_factor,gyro_misalignment",
    )
    .expect("model");
    let exact = Options { model, pose_tolerance_deg: Some(0.0), ..Default::default() };
    let cal = calibrate(&rec, &exact).expect("calibrate");
    assert_eq!(cal.move_error_rad, 0.0);
    let fit = checks(&cal).into_iter().find(|c| c.check == "fit").expect("fit");
    assert!(!fit.passed, "misfit moves with exact labels fail the fit check");
}
