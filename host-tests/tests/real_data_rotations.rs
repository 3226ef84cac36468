//! Measured data: the gyro matrix from the rotations of the imucal Ferraris session and of the imu_tk session,
//! beside the data authors' references, with rotations held out of each fit (docs/method.md#moves).

mod common;

use sinscal_host::io::import::{import_imucal, import_imutk, StaticDetection};
use sinscal_host::study::ferraris_turns;
use sinscal_host::study::rotations::{ferraris_rotations, imutk_rotations, RotationStudy};

fn print(study: &RotationStudy) {
    println!("reference: {}", study.reference_name);
    for row in &study.reference_t_g {
        println!("  {:+.5} {:+.5} {:+.5}", row[0], row[1], row[2]);
    }
    for f in &study.fits {
        println!(
            "fit: {} ({} rotations, {} passes, chi-square {:.1} on {})",
            f.name, f.rotations, f.passes, f.chi_square, f.degrees_of_freedom
        );
        for i in 0..3 {
            println!(
                "  {:+.5} ± {:.5}  {:+.5} ± {:.5}  {:+.5} ± {:.5}",
                f.t_g[i][0], f.t_g_std[i][0], f.t_g[i][1], f.t_g_std[i][1], f.t_g[i][2], f.t_g_std[i][2]
            );
        }
        println!("  bias deg/s: {:?}", f.gyro_bias_radps.map(|(v, e)| (v.to_degrees(), e.to_degrees())));
        for h in &f.held_out {
            println!(
                "  held out {}: angle {:.1} deg, raw error {:.3} deg, calibrated {:.3} deg ({} components)",
                h.label, h.angle_deg, h.raw_error_deg, h.calibrated_error_deg, h.components
            );
        }
    }
}

#[test]
fn ferraris_gyro_matrix_from_the_turns_and_the_hand_moves() {
    let Some(dir) = common::data_dir() else { return };
    let csv = dir.join("imucal-ferraris/example_ferraris_session.csv");
    let labels = dir.join("imucal-ferraris/example_ferraris_session_list.json");
    let rec = import_imucal(&csv, &labels, None).expect("import").recording;
    let turns = ferraris_turns(&rec, &labels).expect("turns");
    let study = ferraris_rotations(&rec, &turns).expect("rotations");
    print(&study);
    assert_eq!(study.fits.len() + study.refused.len(), 3);
    // The turns alone: imucal's formulas, entry by entry, within three standard errors (the same data, the same
    // observation: the integral of the rate over each turn).
    let turns_fit = study.fits.iter().find(|f| f.name == "the three labelled turns").expect("the turns' fit");
    for i in 0..3 {
        for j in 0..3 {
            let d = (turns_fit.t_g[i][j] - study.reference_t_g[i][j]).abs();
            assert!(d < 3.0 * turns_fit.t_g_std[i][j], "T_g[{i}][{j}]: {d} vs ± {}", turns_fit.t_g_std[i][j]);
        }
    }
    // Its calibration on the five hand moves it never saw: better than the raw gyros.
    let rms = |f: &dyn Fn(&sinscal_host::study::rotations::HeldOut) -> f64| {
        (turns_fit.held_out.iter().map(|h| f(h).powi(2)).sum::<f64>() / turns_fit.held_out.len() as f64).sqrt()
    };
    let (raw, calibrated) = (rms(&|h| h.raw_error_deg), rms(&|h| h.calibrated_error_deg));
    println!("held-out hand moves: RMS raw {raw:.3} deg, calibrated {calibrated:.3} deg");
    assert_eq!(turns_fit.held_out.len(), 5);
    assert!(calibrated < raw, "{calibrated} vs {raw}");
}

#[test]
fn imutk_gyro_matrix_from_the_hand_moves() {
    let Some(dir) = common::data_dir() else { return };
    let rec = import_imutk(
        &dir.join("imu-tk-xsens/xsens_acc.mat"),
        &dir.join("imu-tk-xsens/xsens_gyro.mat"),
        None,
        &StaticDetection::default(),
    )
    .expect("import")
    .recording;
    let study = imutk_rotations(&rec).expect("rotations");
    print(&study);
    assert!(study.refused.is_empty(), "{:?}", study.refused);
    // Every entry within 0.02 of the factory calibration's (its gains are the importer's, so its diagonal is 1).
    let all = &study.fits[0];
    for i in 0..3 {
        for j in 0..3 {
            let d = (all.t_g[i][j] - study.reference_t_g[i][j]).abs();
            assert!(d < 0.02, "T_g[{i}][{j}]: {} vs factory {}", all.t_g[i][j], study.reference_t_g[i][j]);
        }
    }
    // Fitted on every other move, checked on the others: ten times better than the raw gyros.
    let half = &study.fits[1];
    let rms = |f: &dyn Fn(&sinscal_host::study::rotations::HeldOut) -> f64| {
        (half.held_out.iter().map(|h| f(h).powi(2)).sum::<f64>() / half.held_out.len() as f64).sqrt()
    };
    let (raw, calibrated) = (rms(&|h| h.raw_error_deg), rms(&|h| h.calibrated_error_deg));
    println!("held-out moves: {} , RMS raw {raw:.3} deg, calibrated {calibrated:.3} deg", half.held_out.len());
    assert!(half.held_out.len() >= 10);
    assert!(calibrated < 0.1 * raw, "{calibrated} vs {raw}");
}

/// REAL DATA: `calibrate` itself on the imported Ferraris session with the gyro terms: its three labelled turns
/// and five hand moves are observations; the hand moves misfit white rate noise, so their error is named from
/// their residuals (between 0.3 and 3 deg per axis) and the fit passes its checks; `T_g` within 2 of its
/// standard errors of imucal's `K_g R_g` (the reference values). With exact labels (pose tolerance 0)
/// no error is named and the fit check fails, as a turntable's misfit moves must.
#[test]
fn calibrate_uses_the_ferraris_turns_and_names_the_hand_moves_error() {
    let Some(dir) = common::data_dir() else { return };
    let rec = common::ferraris_session(&dir);
    let model = sinscal_host::calibration::estimates::parse_model(
        "biases,accel_scale_factor,gyro_scale_factor,gyro_misalignment",
    )
    .expect("model");
    let options = sinscal_host::calibration::Options { model, ..Default::default() };
    let cal = sinscal_host::calibration::calibrate(&rec, &options).expect("calibrate");
    let turns = cal.moves.iter().filter(|m| m.turn.is_some()).count();
    assert_eq!((turns, cal.moves.len()), (3, 8), "three turns and five hand moves");
    let error_deg = cal.move_error_rad.to_degrees();
    println!("REAL DATA imucal Ferraris: hand moves' error {error_deg:.3} deg per axis");
    assert!((0.3..3.0).contains(&error_deg), "{error_deg}");
    let checks = sinscal_host::calibration::checks::checks(&cal);
    assert!(checks.iter().all(|c| c.passed), "{checks:?}");
    let imucal = [[1.027903, -0.000467, -0.006591], [-0.000218, 0.982424, -0.002735], [0.009698, 0.007628, 0.998234]];
    let s = cal.channels.as_ref().expect("general estimator");
    for (i, row) in imucal.iter().enumerate() {
        for (j, reference) in row.iter().enumerate() {
            let p = if i == j { 15 + i } else { 18 + sinscal::calib::general::misalignment_index(i, j) };
            let (v, e) = s.estimate(p).expect("estimated");
            let value = v as f64 + if i == j { 1.0 } else { 0.0 };
            let z = (value - reference) / e as f64;
            println!("  T_g[{i}][{j}] {value:+.5} +- {e:.5} against {reference:+.6}: {z:+.2} standard errors");
            assert!(z.abs() < 2.0, "T_g[{i}][{j}]: {z:.2} standard errors from imucal's");
        }
    }
    let exact = sinscal_host::calibration::Options { pose_tolerance_deg: Some(0.0), ..options };
    let cal = sinscal_host::calibration::calibrate(&rec, &exact).expect("calibrate");
    assert_eq!(cal.move_error_rad, 0.0);
    let fit = sinscal_host::calibration::checks::checks(&cal).into_iter().find(|c| c.check == "fit").expect("fit");
    assert!(!fit.passed, "misfit moves with exact labels fail the fit check");
}
