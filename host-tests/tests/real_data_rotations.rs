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
}
