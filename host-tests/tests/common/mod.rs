//! Helpers shared by the tests that read the measured data sets (`SINSCAL_DATA`).
#![allow(dead_code)] // each test file uses what it needs

use std::io::Write;
use std::path::{Path, PathBuf};

pub mod held_out;

/// The shared data directory, or `None` (with a message) when `SINSCAL_DATA` is not set.
pub fn data_dir() -> Option<PathBuf> {
    match std::env::var_os("SINSCAL_DATA") {
        // A relative path means relative to the repository root (as CI gives it), not to the package's
        // directory, where cargo runs the tests (host-tests/, or host-tests/lab/, whose tests share this module).
        Some(dir) => {
            let dir = PathBuf::from(dir);
            let root = Path::new(env!("CARGO_MANIFEST_DIR")).ancestors().find(|d| d.join("memory.x").is_file());
            Some(if dir.is_relative() { root.expect("the repository root above the package").join(dir) } else { dir })
        }
        None => {
            skipped("a real-data test", "SINSCAL_DATA is not set; set it to the shared data directory");
            None
        }
    }
}

/// The variable `.ci/run` sets: a test whose prerequisite (the shared data, QEMU, flip-link) is missing then fails
/// instead of reporting itself skipped, so that a CI run cannot pass by skipping.
pub const REQUIRE_ALL: &str = "SINSCAL_REQUIRE_ALL";

/// Whether missing prerequisites are failures (`SINSCAL_REQUIRE_ALL` set to anything but empty or 0).
pub fn prerequisites_required() -> bool {
    std::env::var(REQUIRE_ALL).is_ok_and(|v| !v.is_empty() && v != "0")
}

/// Reports `what` as skipped because of `why`; a failure instead where prerequisites are required (CI).
pub fn skipped(what: &str, why: &str) {
    report_skip(what, why, prerequisites_required(), &mut std::io::stderr());
}

/// The report of a skip on `out` (the stderr handle: written to it directly, not through eprintln!, so that the
/// test harness's output capture does not hide it and a plain `cargo test` run shows the skip); a panic naming
/// the missing prerequisite when `required`.
pub fn report_skip(what: &str, why: &str, required: bool, out: &mut dyn Write) {
    assert!(!required, "{what} cannot run: {why}; {REQUIRE_ALL} is set (as in CI), so a missing prerequisite fails");
    let _ = writeln!(out, "SKIPPED {what}: {why}");
}

/// A prerequisite that a machine may lack without fault (a device node, say): reported as skipped on the stderr
/// handle even in CI.
pub fn skipped_here(what: &str, why: &str) {
    report_skip(what, why, false, &mut std::io::stderr());
}

/// A file of the data directory; missing is a failure (SINSCAL_DATA is set).
pub fn data_file(dir: &Path, relative: &str) -> PathBuf {
    let path = dir.join(relative);
    assert!(path.is_file(), "SINSCAL_DATA is set but {} is missing", path.display());
    path
}

/// The imucal Ferraris session of the data directory, imported with its labels (latitude: the importer's default).
pub fn ferraris_session(dir: &Path) -> sinscal_host::io::recording::Recording {
    let csv = data_file(dir, "imucal-ferraris/example_ferraris_session.csv");
    let labels = data_file(dir, "imucal-ferraris/example_ferraris_session_list.json");
    sinscal_host::io::import::import_imucal(&csv, &labels, None).expect("import").recording
}

/// The imu_tk xsens session of the data directory, imported with the default static detection (attitudes
/// levelled from the accelerometers).
pub fn imutk_session(dir: &Path) -> sinscal_host::io::recording::Recording {
    let acc = data_file(dir, "imu-tk-xsens/xsens_acc.mat");
    let gyro = data_file(dir, "imu-tk-xsens/xsens_gyro.mat");
    let detection = sinscal_host::io::import::StaticDetection::default();
    sinscal_host::io::import::import_imutk(&acc, &gyro, None, &detection).expect("import").recording
}

/// The PSINS laser-gyro record of the data directory (one static pose, 1847 s at 100 Hz).
pub fn psins_session(dir: &Path) -> sinscal_host::io::recording::Recording {
    let imu = data_file(dir, "psins-lasergyro/lasergyro.imu");
    sinscal_host::io::import::import_psins(&imu, None).expect("import").recording
}

/// Whether qemu-system-arm runs here. Where prerequisites are required (CI) a missing QEMU is a failure; elsewhere
/// the caller's test is reported as skipped (`what` says what of it is skipped, e.g. " (--on qemu only)"; empty for
/// all of it).
pub fn qemu_available(what: &str) -> bool {
    let qemu = sinscal_host::calibration::qemu::QEMU;
    let found = std::process::Command::new(qemu).arg("--version").output().is_ok_and(|o| o.status.success());
    if !found {
        skipped(&format!("a QEMU test{what}"), &format!("{qemu} not found (run scripts/setup)"));
    }
    found
}

/// A row of a static pose: time, s; position (0 = moving); pitch and roll, deg; body rate, rad/s; specific
/// force, m/s^2; no heading, temperature or turn.
pub fn static_row(
    t_s: f64,
    pos: u32,
    attitude_deg: (f64, f64),
    rate_b_radps: [f64; 3],
    force_b_mps2: [f64; 3],
) -> sinscal_host::io::recording::Row {
    sinscal_host::io::recording::Row {
        t_s,
        pos,
        pitch_deg: attitude_deg.0,
        roll_deg: attitude_deg.1,
        heading_deg: None,
        rate_b_radps,
        force_b_mps2,
        temp_c: None,
        turn_axis: None,
        line: 0,
    }
}
