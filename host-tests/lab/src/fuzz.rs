//! Every reader of sinscal as a fuzz target (docs/formats.md#bad-input): bytes in, the input accepted (with
//! finite values) or refused with a reason; anything else (a panic, a non-finite value accepted, the file
//! reader disagreeing with the text reader) is a failure. The stable mutation harness
//! (`host-tests/lab/tests/fuzz_readers.rs`) and the cargo-fuzz targets (`host-tests/fuzz/`) run these same
//! functions, from the same seeds.

use sinscal::rig::replay::{run_replay, ReplayError};
use sinscal::sensor::adis::{decode_burst, encode_burst, AdisError, Burst, Model, I16F16};

use sinscal_host::analysis::AnglesFile;
use sinscal_host::calibration::firmware_path::replay_file;
use sinscal_host::calibration::Options;
use sinscal_host::io::calibration_model::CalibrationModel;
use sinscal_host::io::recording::Recording;
use sinscal_host::io::ScratchFile;
use sinscal_host::model::simulator::ScenarioFile;
use sinscal_host::model::synth::Scenario;

/// A reader under test: bytes in, `Ok(true)` accepted (with finite values), `Ok(false)` refused.
pub type Reader = fn(&[u8]) -> Result<bool, String>;

fn text(bytes: &[u8]) -> Option<&str> {
    std::str::from_utf8(bytes).ok()
}

/// The recording text reader (`Recording::parse`).
pub fn read_recording(bytes: &[u8]) -> Result<bool, String> {
    let Some(t) = text(bytes) else { return Ok(false) };
    match Recording::parse(t, "fuzz.csv") {
        Err(_) => Ok(false),
        Ok(r) => {
            let finite = r.rows.iter().all(|row| {
                row.t_s.is_finite()
                    && row.rate_b_radps.iter().chain(&row.force_b_mps2).all(|v| v.is_finite())
                    && [row.pitch_deg, row.roll_deg].iter().all(|v| v.is_finite())
            });
            if finite {
                Ok(true)
            } else {
                Err("a recording with a non-finite value was accepted".into())
            }
        }
    }
}

/// The file reader (chunks parsed on the available cores) against the text reader: what the file reader
/// accepts, the text reader accepts with the same rows (the file reader also refuses a last line without an
/// end of line, which the text reader cannot see).
pub fn read_recording_file(bytes: &[u8]) -> Result<bool, String> {
    let file = ScratchFile::new("fuzz.csv");
    std::fs::write(file.path(), bytes).map_err(|e| e.to_string())?;
    let from_file = Recording::read(file.path());
    let from_text = text(bytes).map(|t| Recording::parse(t, "fuzz.csv"));
    match (from_file, from_text) {
        (Err(_), _) => Ok(false),
        (Ok(f), Some(Ok(t))) if f.rows == t.rows && f.header == t.header => read_recording(bytes),
        (Ok(_), _) => Err("the file reader accepted what the text reader refuses or reads otherwise".into()),
    }
}

/// The angles file reader.
pub fn read_angles(bytes: &[u8]) -> Result<bool, String> {
    let Some(t) = text(bytes) else { return Ok(false) };
    match AnglesFile::parse(t, "fuzz.angles") {
        Err(_) => Ok(false),
        Ok(a) => {
            let finite =
                a.rows.iter().all(|r| r.phi_rad.iter().chain(r.phi_std_rad.iter().flatten()).all(|v| v.is_finite()));
            if finite {
                Ok(true)
            } else {
                Err("an angles file with a non-finite value was accepted".into())
            }
        }
    }
}

/// The scenario reader (with its checks: finite numbers, bounded sizes).
pub fn read_scenario(bytes: &[u8]) -> Result<bool, String> {
    let Some(t) = text(bytes) else { return Ok(false) };
    Ok(ScenarioFile::parse(t, "fuzz.toml").is_ok())
}

/// The calibration JSON reader (`apply`, `navigate`).
pub fn read_calibration(bytes: &[u8]) -> Result<bool, String> {
    let Some(t) = text(bytes) else { return Ok(false) };
    match CalibrationModel::parse(t, "fuzz.json") {
        Err(_) => Ok(false),
        Ok(m) => {
            let values = m.gyro_bias_radps.iter().chain(&m.accel_bias_mps2).chain(m.accel_t.iter().flatten());
            if values.chain(m.gyro_t.iter().flatten()).all(|v| v.is_finite()) {
                Ok(true)
            } else {
                Err("a calibration with a non-finite value was accepted".into())
            }
        }
    }
}

/// The replay file through the firmware path (header, frames, the calibration sequence).
pub fn read_replay(bytes: &[u8]) -> Result<bool, String> {
    let outcome: Result<_, ReplayError> = run_replay(bytes, |_| {});
    Ok(outcome.is_ok())
}

/// The ADIS16505-2 burst decoder.
pub fn read_burst(bytes: &[u8]) -> Result<bool, String> {
    let decoded: Result<Burst, AdisError<()>> = decode_burst(Model::Adis16505_2, bytes);
    Ok(decoded.is_ok())
}

/// The MAT-file reader (`io::import::mat::read_mat`): what it accepts is at least one matrix whose value count is
/// its rows times its columns, every value finite.
pub fn read_mat(bytes: &[u8]) -> Result<bool, String> {
    match sinscal_host::io::import::mat::read_mat(bytes, "fuzz.mat") {
        Err(_) => Ok(false),
        Ok(matrices) if matrices.is_empty() => Err("a MAT-file without a matrix was accepted".into()),
        Ok(matrices) => {
            for m in &matrices {
                if m.rows.checked_mul(m.cols) != Some(m.data.len()) {
                    return Err(format!(
                        "'{}': {}x{} with {} values was accepted",
                        m.name,
                        m.rows,
                        m.cols,
                        m.data.len()
                    ));
                }
                if !m.data.iter().all(|v| v.is_finite()) {
                    return Err(format!("'{}': a non-finite value was accepted", m.name));
                }
            }
            Ok(true)
        }
    }
}

/// The layout file of `sinscal import columns` (`io::import::Layout::parse`): what it accepts names three
/// different fields per sensor, finite non-zero scales and a body-from-sensor matrix that is a rotation.
pub fn read_layout(bytes: &[u8]) -> Result<bool, String> {
    let Some(t) = text(bytes) else { return Ok(false) };
    match sinscal_host::io::import::Layout::parse(t, "fuzz.toml") {
        Err(_) => Ok(false),
        Ok(layout) => {
            let m = layout.axes;
            let det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
                - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
                + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
            let scales_ok = [&layout.gyro, &layout.accel].iter().all(|c| {
                c.scale.iter().chain(&c.counts_per_unit).all(|s| s.is_finite() && *s != 0.0)
                    && c.fields[0] != c.fields[1]
                    && c.fields[1] != c.fields[2]
                    && c.fields[0] != c.fields[2]
            });
            if det != 1.0 {
                Err(format!("an axis mapping of determinant {det} was accepted"))
            } else if !scales_ok {
                Err("a zero or non-finite scale, or a field used twice, was accepted".into())
            } else {
                Ok(true)
            }
        }
    }
}

/// The labels file of `sinscal import columns` (`io::import::parse_labels`): what it accepts are finite ranges
/// that do not overlap, with pitch in [-90, 90].
pub fn read_labels(bytes: &[u8]) -> Result<bool, String> {
    let Some(t) = text(bytes) else { return Ok(false) };
    match sinscal_host::io::import::parse_labels(t, "fuzz.csv") {
        Err(_) => Ok(false),
        Ok(labels) => {
            for (i, a) in labels.iter().enumerate() {
                if !(a.start_s.is_finite() && a.end_s.is_finite() && a.start_s < a.end_s) {
                    return Err(format!("range [{}, {}) was accepted", a.start_s, a.end_s));
                }
                if !(-90.0..=90.0).contains(&a.pitch_deg) || !a.roll_deg.is_finite() {
                    return Err(format!("pitch {} roll {} was accepted", a.pitch_deg, a.roll_deg));
                }
                if labels[i + 1..].iter().any(|b| b.start_s < a.end_s && a.start_s < b.end_s) {
                    return Err("overlapping ranges were accepted".into());
                }
            }
            Ok(true)
        }
    }
}

/// The valid inputs the fuzzing starts from, per target: its name, its reader and a valid input that sinscal
/// writes itself.
pub fn seeds() -> Vec<(&'static str, Reader, Vec<u8>)> {
    let scenario = Scenario { dwell_s: 1.0, ..Scenario::example() };
    let rec = scenario.recording(1, "seed.csv");
    let cal = sinscal_host::calibration::calibrate(&rec, &Options::default()).expect("the seed calibrates");
    let cal_json = serde_json::to_string_pretty(&sinscal_host::calibration::result::CalibrationJson::new(&cal))
        .expect("the calibration serialises");
    let angles = "# sinscal-angles: 1\n# latitude_deg: 45.7796\n\
                  pos,pitch_deg,roll_deg,heading_deg,phi_e_rad,phi_n_rad,phi_u_rad,phi_e_std_rad,phi_n_std_rad,phi_u_std_rad\n\
                  1,0,0,0,1e-5,-2e-5,3e-4,1e-6,1e-6,1e-5\n2,0,0,180,2e-5,1e-5,-3e-4,1e-6,1e-6,1e-5\n\
                  3,0,0,90,1e-5,1e-5,2e-4,1e-6,1e-6,1e-5\n4,0,0,270,-1e-5,2e-5,1e-4,1e-6,1e-6,1e-5\n\
                  5,0,90,0,3e-5,-1e-5,3e-4,1e-6,1e-6,1e-5\n6,0,270,0,1e-5,1e-5,-2e-4,1e-6,1e-6,1e-5\n";
    let scenario_toml = include_str!("../../scenarios/all-effects.toml").to_string();
    let (replay, _) = replay_file(&rec, &Options::default()).expect("the seed replays");
    let mut burst = vec![0u8; Model::Adis16505_2.burst_len()];
    let lsb = |x: f64| I16F16::from_num(x);
    let b = Burst {
        diag_stat: 0,
        gyro_lsb: [lsb(100.5), lsb(-200.25), lsb(300.0)],
        accel_lsb: [lsb(10.0), lsb(20.0), lsb(3000.0)],
        temp_raw: 25,
        data_counter: 7,
    };
    encode_burst(Model::Adis16505_2, &b, &mut burst);
    // Small MAT-files: little-endian and uncompressed (a 1x1 with a small-element name, a 3x2), and
    // big-endian with compressed elements (MATLAB's default -v7 layout).
    use sinscal_host::io::import::mat::{write_mat, ByteOrder};
    let values = [0.25, -1.5, 3.0, 1e-3, 9.81, -0.0];
    let matrices: [sinscal_host::io::import::mat::NamedMatrix<'_>; 2] =
        [("t", 1, 1, &[2.5]), ("acc_counts", 3, 2, &values)];
    let mat = write_mat(&matrices, ByteOrder::Little, false).expect("the seed MAT-file is written");
    let mat_compressed = write_mat(&matrices, ByteOrder::Big, true).expect("the seed MAT-file is written");
    // And a version 7.3 file (HDF5 behind MATLAB's user block), its datasets compressed as MATLAB writes them.
    let mat_v73 = sinscal_host::io::import::mat::write_mat_v73(&matrices, true).expect("the seed MAT-file is written");
    vec![
        ("recording", read_recording as Reader, rec.to_csv().into_bytes()),
        ("recording-file", read_recording_file as Reader, rec.to_csv().into_bytes()),
        ("angles", read_angles as Reader, angles.as_bytes().to_vec()),
        ("scenario", read_scenario as Reader, scenario_toml.into_bytes()),
        ("calibration", read_calibration as Reader, cal_json.into_bytes()),
        ("replay", read_replay as Reader, replay),
        ("burst", read_burst as Reader, burst),
        ("mat", read_mat as Reader, mat),
        ("mat-compressed", read_mat as Reader, mat_compressed),
        ("layout", read_layout as Reader, include_str!("../../layouts/imutk.toml").as_bytes().to_vec()),
        (
            "labels",
            read_labels as Reader,
            b"pos,start_s,end_s,pitch_deg,roll_deg,heading_deg\n1,0,4.5,0,-90,?\n2,5,9,90,0,12.5\n".to_vec(),
        ),
        ("mat-v73", read_mat as Reader, mat_v73),
    ]
}
