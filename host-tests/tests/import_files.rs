//! `sinscal import columns` of several files (docs/data.md#several-files): in sequence, as sessions on their own
//! time bases, side by side; accelerometer-only layouts; time stamps with a nominal rate.
//!
//! - Each arrangement imports to the recording, value for value, that the same data merged by hand into one file
//!   give through a layout of one file: two binary files of one pose each (in sequence, positions by file), two
//!   text files whose times overlap (sessions), four MAT-files of one variable each (side by side,
//!   accelerometer-only velocity increments), jittered time stamps with a nominal rate.
//! - Every new refusal names the file and the line (or record): files side by side of different lengths, a
//!   nominal rate that the time stamps contradict, files that overlap in time without sessions, a position that
//!   spans two sessions.
//! - An accelerometer-only recording imported from MAT-files runs through `calibrate`, `analyze` and `apply`, and
//!   calibrate finds the simulated accelerometer errors.

use std::path::{Path, PathBuf};

use assert_cmd::Command;
use sinscal_host::io::import::mat::write_mat_v5;
use sinscal_host::io::import::{import_columns, parse_labels, ColumnsImport, Imported, Layout, Positions};
use sinscal_host::io::recording::Recording;
use sinscal_host::model::synth::Scenario;

/// A short simulated session: six positions of 4 s at 100 Hz with 2 s moves, every bias and noise of the example.
fn session() -> Recording {
    Scenario { dwell_s: 4.0, ..Scenario::example() }.recording(5, "session.csv")
}

fn write(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, bytes).unwrap();
    p
}

fn sinscal() -> Command {
    Command::cargo_bin("sinscal").unwrap()
}

/// Imports `inputs` through the layout text with the labels text (library path).
fn import(inputs: &[&Path], layout_text: &str, labels: &str) -> Result<Imported, String> {
    let layout = Layout::parse(layout_text, "layout.toml").map_err(|e| e.to_string())?;
    let positions = Positions::Labels(parse_labels(labels, "labels.csv").map_err(|e| e.to_string())?);
    let import = ColumnsImport {
        layout: &layout,
        layout_source: "layout.toml",
        positions,
        labels_source: Some("labels.csv"),
        latitude_deg: None,
    };
    import_columns(inputs, &import).map_err(|e| e.to_string())
}

/// The two recordings hold the same rows, value for value (time, position, attitude, every channel), and the same
/// columns; `what` names the case.
fn assert_identical(got: &Recording, want: &Recording, what: &str) {
    assert_eq!(got.rows.len(), want.rows.len(), "{what}: rows");
    assert_eq!(got.has_gyro, want.has_gyro, "{what}: gyro columns");
    for (k, (g, w)) in got.rows.iter().zip(&want.rows).enumerate() {
        let key = |r: &sinscal_host::io::recording::Row| {
            (r.t_s, r.pos, r.pitch_deg, r.roll_deg, r.heading_deg, r.rate_b_radps, r.force_b_mps2)
        };
        assert_eq!(key(g), key(w), "{what}: row {k}");
    }
    let positions = got.dwells().len();
    println!("{what}: {} rows in {positions} positions identical to the import of the merged file", got.rows.len());
}

const SITE: &str = "[site]\nlatitude_deg = 45.7796\n";

/// The session's samples as binary f64 records of six fields (gyro, accel: no time field).
fn binary_records(rows: &[sinscal_host::io::recording::Row]) -> Vec<u8> {
    let mut out = Vec::new();
    for r in rows {
        for v in r.rate_b_radps.iter().chain(&r.force_b_mps2) {
            out.extend(v.to_le_bytes());
        }
    }
    out
}

#[test]
fn two_binary_files_of_one_pose_each_equal_the_concatenated_file() {
    // A ring-laser IMU writes one raw binary file per pose: here dwells 1 and 2 of the session, at a constant
    // 100 Hz (no time field), read in sequence, each file one position (--file-position).
    let rec = session();
    let dwells = rec.dwells();
    let (a, b) = (&dwells[0], &dwells[1]);
    let rows_a: Vec<_> = a.rows.iter().map(|r| (*r).clone()).collect();
    let rows_b: Vec<_> = b.rows.iter().map(|r| (*r).clone()).collect();
    let dir = tempfile::tempdir().unwrap();
    let file_a = write(dir.path(), "pose-a.bin", &binary_records(&rows_a));
    let file_b = write(dir.path(), "pose-b.bin", &binary_records(&rows_b));
    let merged = write(dir.path(), "merged.bin", &[binary_records(&rows_a), binary_records(&rows_b)].concat());
    let one = format!(
        "format = \"binary\"\n[binary]\ntype = \"f64\"\nendian = \"little\"\nfields = 6\n[time]\nrate_hz = 100\n\
         [gyro]\nfields = [0, 1, 2]\nunit = \"rad/s\"\n[accel]\nfields = [3, 4, 5]\nunit = \"m/s^2\"\n{SITE}"
    );
    let two = format!("{one}[files]\narrange = \"sequence\"\n");
    let one_path = write(dir.path(), "one.toml", one.as_bytes());
    let two_path = write(dir.path(), "two.toml", two.as_bytes());
    let attitude = |r: &sinscal_host::io::recording::Row| {
        let h = r.heading_deg.map_or("?".to_string(), |h| format!("{h:?}"));
        format!("{:?},{:?},{h}", r.pitch_deg, r.roll_deg)
    };
    let (pose_a, pose_b) = (attitude(&rows_a[0]), attitude(&rows_b[0]));
    let out_two = dir.path().join("two.csv");
    let file_flags = ["--file-position", &pose_a, "--file-position", &pose_b];
    let run = import_cli(&[&file_a, &file_b], &two_path, &file_flags, &out_two);
    assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
    let stdout = String::from_utf8_lossy(&run.stdout);
    assert!(stdout.contains("2 files in sequence on one time base") && stdout.contains("2 position(s)"), "{stdout}");
    // By hand: the files concatenated, the positions by time (file a's records are 0 .. n_a / 100 s).
    let split_s = rows_a.len() as f64 / 100.0;
    let out_one = dir.path().join("one.csv");
    let (range_a, range_b) = (format!("0,{split_s:?},{pose_a}"), format!("{split_s:?},1e9,{pose_b}"));
    let run = import_cli(&[&merged], &one_path, &["--position", &range_a, "--position", &range_b], &out_one);
    assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
    let (got, want) = (Recording::read(&out_two).unwrap(), Recording::read(&out_one).unwrap());
    assert_identical(&got, &want, "two binary files in sequence");
    assert_eq!(got.dwells().len(), 2);
    assert_eq!(got.rows[rows_a.len()].pos, 2, "the second file's first record is position 2");
    assert_eq!(got.rows[rows_a.len()].force_b_mps2, rows_b[0].force_b_mps2);
    // One flag per file: two flags for one file is a usage error.
    let run = import_cli(&[&file_a], &two_path, &file_flags, &out_two);
    assert_eq!(run.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&run.stderr).contains("one per input file (2 flags for 1 files)"));
}

/// `sinscal import columns INPUTS --layout LAYOUT FLAGS --out OUT`.
fn import_cli(inputs: &[&Path], layout: &Path, flags: &[&str], out: &Path) -> std::process::Output {
    let mut cmd = sinscal();
    cmd.args(["import", "columns"]).args(inputs).arg("--layout").arg(layout).args(flags).arg("--out").arg(out);
    cmd.output().unwrap()
}

/// The rows as text lines `t wx wy wz fx fy fz` with the times of `time_s`.
fn text_lines(rows: &[sinscal_host::io::recording::Row], time_s: &dyn Fn(f64) -> f64) -> String {
    let mut text = String::new();
    for r in rows {
        let (w, f) = (r.rate_b_radps, r.force_b_mps2);
        let t = time_s(r.t_s);
        text += &format!("{t:?} {:?} {:?} {:?} {:?} {:?} {:?}\n", w[0], w[1], w[2], f[0], f[1], f[2]);
    }
    text
}

/// The labels of the dwells whose rows are in `rows`, with their times through `time_s` and a `file` cell.
fn labels_of(rows: &[sinscal_host::io::recording::Row], time_s: &dyn Fn(f64) -> f64, file: &str) -> String {
    let mut out = String::new();
    let dt_s = 0.01;
    let mut k = 0;
    while k < rows.len() {
        let end = k + rows[k..].iter().take_while(|r| r.pos == rows[k].pos).count();
        let (a, b) = (&rows[k], &rows[end - 1]);
        if a.pos != 0 {
            let heading = a.heading_deg.map_or("?".to_string(), |h| format!("{h:?}"));
            let (start, stop) = (time_s(a.t_s) - dt_s / 2.0, time_s(b.t_s) + dt_s / 2.0);
            out += &format!("{},{file}{start:?},{stop:?},{:?},{:?},{heading}\n", a.pos, a.pitch_deg, a.roll_deg);
        }
        k = end;
    }
    out
}

#[test]
fn two_text_files_whose_times_overlap_are_sessions_equal_to_the_hand_shifted_file() {
    // A MEMS IMU writes one text file per half of the schedule, both stamped with GPS times of week that cover
    // the same span: each file is a session on its own time base.
    let rec = session();
    let split = rec.rows.iter().position(|r| r.pos == 4).unwrap();
    let (rows_a, rows_b) = rec.rows.split_at(split);
    let week_s = 345_600.0;
    let t_b0 = rows_b[0].t_s;
    let own_a = |t: f64| t + week_s;
    let own_b = |t: f64| t - t_b0 + week_s + 3.0;
    let dir = tempfile::tempdir().unwrap();
    let file_a = write(dir.path(), "a.txt", text_lines(rows_a, &own_a).as_bytes());
    let file_b = write(dir.path(), "b.txt", text_lines(rows_b, &own_b).as_bytes());
    // By hand: session b shifted to start 1 s after the last record of a, as the documented shift does.
    let parsed = |t: f64| format!("{t:?}").parse::<f64>().unwrap();
    let last_a = parsed(own_a(rows_a[rows_a.len() - 1].t_s));
    let shift_s = last_a + 1.0 - parsed(own_b(t_b0));
    let merged_b = |t: f64| parsed(own_b(t)) + shift_s;
    let merged_text = text_lines(rows_a, &own_a) + &text_lines(rows_b, &merged_b);
    let merged = write(dir.path(), "merged.txt", merged_text.as_bytes());
    let one = format!(
        "format = \"text\"\n[time]\nfield = 0\n[gyro]\nfields = [1, 2, 3]\nunit = \"rad/s\"\n\
         [accel]\nfields = [4, 5, 6]\nunit = \"m/s^2\"\n{SITE}"
    );
    let sessions = format!("{one}[files]\narrange = \"sessions\"\n");
    // The sessions' labels in each file's own times; the merged file's in its times.
    let file_labels = format!(
        "pos,file,start_s,end_s,pitch_deg,roll_deg,heading_deg\n{}{}",
        labels_of(rows_a, &own_a, "1,"),
        labels_of(rows_b, &own_b, "2,")
    );
    let merged_labels = format!(
        "pos,start_s,end_s,pitch_deg,roll_deg,heading_deg\n{}{}",
        labels_of(rows_a, &own_a, ""),
        labels_of(rows_b, &merged_b, "")
    );
    let got = import(&[&file_a, &file_b], &sessions, &file_labels).unwrap();
    let want = import(&[&merged], &one, &merged_labels).unwrap();
    assert_identical(&got.recording, &want.recording, "two overlapping text files as sessions");
    assert_eq!(got.recording.dwells().len(), 6);
    let shift_text = format!("times shifted by {shift_s} s");
    let comment = got.recording.header.comments.iter().find(|c| c.starts_with("sessions: ")).unwrap();
    assert!(comment.contains(&shift_text) && comment.contains("a.txt (records 1 to"), "{comment}");
    assert!(got.summary.contains(&shift_text), "{}", got.summary);
    // The same files on one time base overlap: refused at the second file's first line.
    let sequence = format!("{one}[files]\narrange = \"sequence\"\n");
    let err = import(&[&file_a, &file_b], &sequence, &file_labels).unwrap_err();
    assert!(
        err.contains("b.txt:1: time 345603 s is not after the last record of ") && err.contains("a.txt ("),
        "{err}"
    );
    assert!(err.contains("the files overlap in time") && err.contains("arrange = \"sessions\""), "{err}");
    // A position reaching across the gap between the sessions is refused at its line.
    let across = format!("start_s,end_s,pitch_deg,roll_deg\n{:?},{:?},0,0\n", last_a - 0.5, merged_b(rows_b[10].t_s));
    let err = import(&[&file_a, &file_b], &sessions, &across).unwrap_err();
    assert!(err.contains("labels.csv:2:") && err.contains("holds records of"), "{err}");
    assert!(err.contains("a.txt and") && err.contains("b.txt: a position lies within one session"), "{err}");
}

/// Six static poses (z up, z down, x up, x down, y up, y down) of `samples` each at 200 Hz, one after another:
/// the pitch and roll of each, and the specific force `T (g u) + b + noise` of an accelerometer with scale factors
/// `1 + scale`, bias `bias_mps2` and white noise of `noise_mps2` per sample (u: the up direction in the body).
struct SixPoses {
    attitudes_deg: [(f64, f64); 6],
    t_s: Vec<f64>,
    force_b_mps2: Vec<[f64; 3]>,
}

const G_MPS2: f64 = 9.80665;

fn six_poses(samples: usize, scale: [f64; 3], bias_mps2: [f64; 3], noise_mps2: f64) -> SixPoses {
    let attitudes_deg = [(0.0, 0.0), (0.0, 180.0), (0.0, -90.0), (0.0, 90.0), (90.0, 0.0), (-90.0, 0.0)];
    let mut t_s = Vec::new();
    let mut force_b_mps2 = Vec::new();
    let mut noise = Gaussian(952);
    for (p, (pitch_deg, roll_deg)) in attitudes_deg.iter().enumerate() {
        let (theta, gamma) = (f64::to_radians(*pitch_deg), f64::to_radians(*roll_deg));
        let up = [-gamma.sin() * theta.cos(), theta.sin(), gamma.cos() * theta.cos()];
        for k in 0..samples {
            t_s.push(1000.0 + ((p * samples + k) as f64) * 0.005);
            let f = [0, 1, 2].map(|i| (1.0 + scale[i]) * G_MPS2 * up[i] + bias_mps2[i]);
            force_b_mps2.push(f.map(|v| v + noise_mps2 * noise.next()));
        }
    }
    SixPoses { attitudes_deg, t_s, force_b_mps2 }
}

/// Standard normal numbers (splitmix64 and Box-Muller), reproducible from the seed.
struct Gaussian(u64);

impl Gaussian {
    fn uniform(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }

    fn next(&mut self) -> f64 {
        let (u, v) = (1.0 - self.uniform(), self.uniform());
        (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
    }
}

/// The four MAT-files of one variable each of an accelerometer-only logger: `t` (a row vector), `X`, `Y`, `Z`
/// (velocity increments per 5 ms, columns), and the same data merged by hand into one matrix `imu` of four columns.
fn four_mat_files(dir: &Path, poses: &SixPoses, z_rows: usize) -> (Vec<PathBuf>, PathBuf) {
    let n = poses.t_s.len();
    let axis = |i: usize| -> Vec<f64> { poses.force_b_mps2.iter().map(|f| f[i] * 0.005).collect() };
    let (x, y, z) = (axis(0), axis(1), axis(2));
    let files = vec![
        write(dir, "t.mat", &write_mat_v5(&[("t", 1, n, &poses.t_s)]).unwrap()),
        write(dir, "X.mat", &write_mat_v5(&[("X", n, 1, &x)]).unwrap()),
        write(dir, "Y.mat", &write_mat_v5(&[("Y", n, 1, &y)]).unwrap()),
        write(dir, "Z.mat", &write_mat_v5(&[("Z", z_rows, 1, &z[..z_rows])]).unwrap()),
    ];
    let merged: Vec<f64> = [poses.t_s.clone(), x, y, z].concat();
    (files, write(dir, "merged.mat", &write_mat_v5(&[("imu", n, 4, &merged)]).unwrap()))
}

/// The layout of the four one-variable files (side by side) and of the merged matrix.
fn accel_only_layouts() -> (String, String) {
    let one = format!(
        "format = \"mat\"\n[time]\nfield = 0\nunit = \"s\"\nrate_hz = 200\n\
         [accel]\nfields = [1, 2, 3]\nunit = \"m/s\"\nincrements = true\n{SITE}gravity_mps2 = {G_MPS2:?}\n"
    );
    (format!("{one}[files]\narrange = \"side-by-side\"\n"), one)
}

/// `--position` flags (or labels lines) of the six poses, 0.25 s in from each end of each pose.
fn pose_ranges(poses: &SixPoses, samples: usize) -> Vec<String> {
    (0..6)
        .map(|p| {
            let (start, end) = (poses.t_s[p * samples] + 0.25, poses.t_s[(p + 1) * samples - 1] - 0.25);
            let (pitch, roll) = poses.attitudes_deg[p];
            format!("{start:?},{end:?},{pitch:?},{roll:?},?")
        })
        .collect()
}

#[test]
fn four_mat_files_of_one_variable_equal_the_merged_matrix_without_gyro_columns() {
    let samples = 400;
    let poses = six_poses(samples, [0.0; 3], [0.002, -0.001, 0.003], 0.0);
    let dir = tempfile::tempdir().unwrap();
    let (files, merged) = four_mat_files(dir.path(), &poses, poses.t_s.len());
    let (four, one) = accel_only_layouts();
    let labels = format!("start_s,end_s,pitch_deg,roll_deg,heading_deg\n{}\n", pose_ranges(&poses, samples).join("\n"));
    let inputs: Vec<&Path> = files.iter().map(|p| p.as_path()).collect();
    let got = import(&inputs, &four, &labels).unwrap();
    let want = import(&[&merged], &one, &labels).unwrap();
    assert_identical(&got.recording, &want.recording, "four MAT-files of one variable");
    assert!(!got.recording.has_gyro, "accelerometer-only: no gyro columns");
    assert_eq!(got.recording.dwells().len(), 6);
    // Increments per 5 ms divided by the nominal 5 ms: the force, to rounding.
    let (row, truth) = (&got.recording.rows[samples + 100], poses.force_b_mps2[samples + 100]);
    for i in 0..3 {
        assert!((row.force_b_mps2[i] - truth[i]).abs() < 1e-12, "{:?} vs {truth:?}", row.force_b_mps2);
    }
    let csv = got.recording.to_csv();
    let columns = csv.lines().find(|l| l.starts_with("t_s")).unwrap();
    assert_eq!(columns, "t_s,pos,pitch_deg,roll_deg,heading_deg,ax_mps2,ay_mps2,az_mps2");
    assert!(got.summary.contains("no gyro in the layout: an accelerometer-only recording"), "{}", got.summary);
}

#[test]
fn every_new_refusal_names_the_file_and_the_line() {
    let dir = tempfile::tempdir().unwrap();
    // Files side by side of different lengths: Z one row short, refused at its last record.
    let samples = 100;
    let poses = six_poses(samples, [0.0; 3], [0.0; 3], 0.0);
    let n = poses.t_s.len();
    let (files, _) = four_mat_files(dir.path(), &poses, n - 1);
    let (four, _) = accel_only_layouts();
    let labels = format!("start_s,end_s,pitch_deg,roll_deg\n{:?},{:?},0,0\n", poses.t_s[0], poses.t_s[10]);
    let inputs: Vec<&Path> = files.iter().map(|p| p.as_path()).collect();
    let err = import(&inputs, &four, &labels).unwrap_err();
    let z = files[3].display().to_string();
    assert!(err.starts_with(&format!("{z}:{}: the file ends after {} records", n - 1, n - 1)), "{err}");
    assert!(err.contains(&format!("t.mat has {n}: files side by side hold as many records")), "{err}");
    // A nominal rate the time stamps contradict: refused at the layout's rate_hz line.
    let (_, one) = accel_only_layouts();
    let rate_line = one.lines().position(|l| l.starts_with("rate_hz")).unwrap() + 1;
    let (files, merged) = four_mat_files(dir.path(), &poses, n);
    drop(files);
    let err = import(&[&merged], &one.replace("rate_hz = 200", "rate_hz = 190"), &labels).unwrap_err();
    assert!(err.starts_with(&format!("layout.toml:{rate_line}: [time] rate_hz 190 disagrees with the time stamps")));
    assert!(err.contains("the median time step is 0.005 s (200 Hz)") && err.contains("more than 1 % apart"), "{err}");
    // Gyro-only data make no recording (its accelerometers are required): the layout says so.
    let gyro_only = one.replace("[accel]", "[gyro]").replace("m/s\"", "rad\"");
    let err = Layout::parse(&gyro_only, "gyro.toml").unwrap_err().to_string();
    assert!(err.starts_with("gyro.toml: no [accel] table: a recording holds the accelerometers"), "{err}");
    // Text files that overlap in time without sessions: refused at the second file's first record.
    let text = "0 0 0 0 0 0 9.8\n0.01 0 0 0 0 0 9.8\n0.02 0 0 0 0 0 9.8\n";
    let a = write(dir.path(), "a.txt", text.as_bytes());
    let b = write(dir.path(), "b.txt", format!("# header\n{text}").as_bytes());
    let layout = format!(
        "format = \"text\"\n[text]\ncomment = \"#\"\n[time]\nfield = 0\n[gyro]\nfields = [1, 2, 3]\nunit = \"rad/s\"\n\
         [accel]\nfields = [4, 5, 6]\nunit = \"m/s^2\"\n[files]\narrange = \"sequence\"\n{SITE}"
    );
    let err = import(&[&a, &b], &layout, "start_s,end_s,pitch_deg,roll_deg\n0,0.015,0,0\n").unwrap_err();
    let b = b.display().to_string();
    assert!(err.starts_with(&format!("{b}:2: time 0 s is not after the last record of")), "{err}");
}

#[test]
fn jittered_time_stamps_with_a_nominal_rate_are_kept_checked_and_measured() {
    // A navigation-grade record at a nominal 100 Hz whose time stamps run at 100.04 Hz with jitter: the stamps are
    // kept, the rate is the nominal one, the jitter is measured.
    let rec = session();
    let jitter_s = |k: usize| 1e-3 * ((k as f64) * 1.7).sin();
    let stamped = |k: usize| (k as f64) / 100.04 + jitter_s(k);
    let dir = tempfile::tempdir().unwrap();
    let mut text = String::new();
    for (k, r) in rec.rows.iter().enumerate() {
        let (w, f) = (r.rate_b_radps, r.force_b_mps2);
        text += &format!("{:?} {:?} {:?} {:?} {:?} {:?} {:?}\n", stamped(k), w[0], w[1], w[2], f[0], f[1], f[2]);
    }
    let input = write(dir.path(), "jitter.txt", text.as_bytes());
    let measured = format!(
        "format = \"text\"\n[time]\nfield = 0\nunit = \"s\"\n[gyro]\nfields = [1, 2, 3]\nunit = \"rad/s\"\n\
         [accel]\nfields = [4, 5, 6]\nunit = \"m/s^2\"\n{SITE}"
    );
    let nominal = measured.replace("unit = \"s\"\n", "unit = \"s\"\nrate_hz = 100\n");
    let mut labels = "start_s,end_s,pitch_deg,roll_deg,heading_deg\n".to_string();
    let index_of = |t: f64| (t * 100.0).round() as usize;
    for d in rec.dwells() {
        let (a, b) = (index_of(d.rows[0].t_s), index_of(d.rows[d.rows.len() - 1].t_s));
        let h = d.rows[0].heading_deg.map_or("?".to_string(), |h| format!("{h:?}"));
        let (p, r) = (d.rows[0].pitch_deg, d.rows[0].roll_deg);
        labels += &format!("{:?},{:?},{p:?},{r:?},{h}\n", stamped(a) - 0.005, stamped(b) + 0.005);
    }
    let got = import(&[&input], &nominal, &labels).unwrap();
    // By hand: the same file without the nominal rate gives the same rows, at the measured rate.
    let want = import(&[&input], &measured, &labels).unwrap();
    assert_identical(&got.recording, &want.recording, "jittered time stamps with a nominal rate");
    assert_eq!(got.recording.header.rate_hz, Some(100.0));
    let measured_hz = want.recording.header.rate_hz.unwrap();
    assert!((measured_hz - 100.04).abs() < 1.0, "without rate_hz the rate is measured: {measured_hz} Hz");
    for (k, row) in got.recording.rows.iter().enumerate() {
        assert_eq!(row.t_s, stamped(k), "row {k}: the time stamp kept");
    }
    let comment = got.recording.header.comments.iter().find(|c| c.starts_with("time_stamps: ")).unwrap();
    println!("{comment}");
    assert!(comment.contains("nominal rate 100 Hz checked against them"), "{comment}");
    // The jitter: the steps' spread (sin at 1.7 rad per step: about 1.4e-3 s) and the largest deviation from 10 ms.
    let field = |after: &str| -> f64 {
        let rest = &comment[comment.find(after).unwrap() + after.len()..];
        rest.split_whitespace().next().unwrap().parse().unwrap()
    };
    assert!((field("measured ") - 100.04).abs() < 0.01, "{comment}");
    assert!((1.0e-3..2.0e-3).contains(&field("step standard deviation ")), "{comment}");
    let largest_s = field("largest |step - 1/rate_hz| ");
    assert!((1.4e-3..2.01e-3).contains(&largest_s), "{comment}");
    // The written recording passes its own rate check.
    let out = dir.path().join("out.csv");
    got.recording.write(&out).unwrap();
    assert_eq!(Recording::read(&out).unwrap().rows.len(), rec.rows.len());
}

#[test]
fn an_accelerometer_only_import_from_mat_files_runs_through_calibrate_analyze_and_apply() {
    // Truth: scale factors of +300, -200, +100 ppm, biases of 2, -1, 3 mm/s^2 (204, -102, 306 ug), white noise of
    // 20 ug per sample (a navigation-grade accelerometer). Its dwell means are nearly as precise as f32 holds
    // them: before the core's convergence allowed for its own rounding, calibrate exited 3 here ("did not
    // converge in 12 passes") with the right estimates.
    let (scale, bias_mps2) = ([300e-6, -200e-6, 100e-6], [0.002, -0.001, 0.003]);
    let samples = 2000;
    let noise_mps2 = 20.0 * 9.80665e-6;
    let poses = six_poses(samples, scale, bias_mps2, noise_mps2);
    let dir = tempfile::tempdir().unwrap();
    let (files, _) = four_mat_files(dir.path(), &poses, poses.t_s.len());
    let (four, _) = accel_only_layouts();
    let layout = write(dir.path(), "four.toml", four.as_bytes());
    let recording = dir.path().join("accel.csv");
    let ranges = pose_ranges(&poses, samples);
    let flags: Vec<&str> = ranges.iter().flat_map(|p| ["--position", p.as_str()]).collect();
    let inputs: Vec<&Path> = files.iter().map(|p| p.as_path()).collect();
    let run = import_cli(&inputs, &layout, &flags, &recording);
    assert_eq!(run.status.code(), Some(0), "{}", String::from_utf8_lossy(&run.stderr));
    let calibration = dir.path().join("calibration.json");
    let model = "accel_bias,accel_scale_factor";
    let run = sinscal().arg("calibrate").arg(&recording).args(["--model", model, "--json"]).arg(&calibration).output();
    let run = run.unwrap();
    println!("calibrate: {}\n{}", run.status, String::from_utf8_lossy(&run.stdout));
    assert_eq!(run.status.code(), Some(0), "{}", String::from_utf8_lossy(&run.stderr));
    let json: serde_json::Value = serde_json::from_slice(&std::fs::read(&calibration).unwrap()).unwrap();
    for i in 0..3 {
        let b = json["accel_bias_mps2"][i].as_f64().unwrap();
        let s = json["accel_scale_factor"][i].as_f64().unwrap();
        println!("axis {i}: bias {b:e} m/s^2 (truth {:e}), scale factor {s:e} (truth {:e})", bias_mps2[i], scale[i]);
        let (b_std, s_std) =
            (json["accel_bias_std_mps2"][i].as_f64().unwrap(), json["accel_scale_factor_std"][i].as_f64().unwrap());
        println!("  standard errors {b_std:e} m/s^2, {s_std:e}");
        // Within 5 standard errors, and those as small as the noise makes them (1900 samples in each of 6 poses).
        assert!((b - bias_mps2[i]).abs() < 5.0 * b_std && b_std < 5e-5, "accel bias {i}: {b} +- {b_std}");
        assert!((s - scale[i]).abs() < 5.0 * s_std && s_std < 1e-5, "accel scale factor {i}: {s} +- {s_std}");
    }
    assert!(json["gyro_bias_radps"].is_null() || json["gyro_bias_radps"][0].is_null(), "{}", json["gyro_bias_radps"]);
    let run = sinscal().arg("analyze").arg(&recording).output().unwrap();
    let analysis = String::from_utf8_lossy(&run.stdout);
    println!("analyze: {}\n{analysis}", run.status);
    assert_eq!(run.status.code(), Some(0), "{}", String::from_utf8_lossy(&run.stderr));
    assert!(analysis.contains("verdict: accel_scale_factor"), "the simulated scale factors are the effect found");
    let compensated = dir.path().join("compensated.csv");
    let mut apply = sinscal();
    apply.arg("apply").arg(&recording).arg("--calibration").arg(&calibration).arg("--out").arg(&compensated);
    let run = apply.output().unwrap();
    println!("apply: {}\n{}", run.status, String::from_utf8_lossy(&run.stdout));
    assert_eq!(run.status.code(), Some(0), "{}", String::from_utf8_lossy(&run.stderr));
    // Compensated: gravity along each pose's up direction, the errors removed.
    let back = Recording::read(&compensated).unwrap();
    assert!(!back.has_gyro);
    for p in 0..6 {
        let (theta, gamma) = (poses.attitudes_deg[p].0.to_radians(), poses.attitudes_deg[p].1.to_radians());
        let up = [-gamma.sin() * theta.cos(), theta.sin(), gamma.cos() * theta.cos()];
        let row = &back.rows[p * samples + samples / 2];
        for i in 0..3 {
            let error_mps2 = (row.force_b_mps2[i] - G_MPS2 * up[i]).abs();
            assert!(error_mps2 < 6.0 * noise_mps2, "pose {p}: {:?}", row.force_b_mps2);
        }
    }
}

#[test]
fn static_intervals_end_where_a_file_ends() {
    // Two files of one accelerometer-only logger at 10 Hz, in sequence on one time base (the second continues
    // the first's record count), both at rest in the same pose: the specific force does not show where one file
    // ends, the detection's interval does end there (each file a pose of its own).
    let mut noise = Gaussian(7);
    let mut file = |samples: usize| -> String {
        let mut text = String::new();
        for _ in 0..samples {
            let f = [0.0, 0.0, G_MPS2].map(|v| v + 1e-4 * noise.next());
            text += &format!("{:?} {:?} {:?}\n", f[0], f[1], f[2]);
        }
        text
    };
    let dir = tempfile::tempdir().unwrap();
    let a = write(dir.path(), "a.txt", file(600).as_bytes());
    let b = write(dir.path(), "b.txt", file(400).as_bytes());
    let layout_text = format!(
        "format = \"text\"\n[time]\nrate_hz = 10\n[accel]\nfields = [0, 1, 2]\nunit = \"m/s^2\"\n\
         [files]\narrange = \"sequence\"\n{SITE}"
    );
    let layout = Layout::parse(&layout_text, "layout.toml").unwrap();
    let import = ColumnsImport {
        layout: &layout,
        layout_source: "layout.toml",
        positions: Positions::Detect(sinscal_host::io::import::StaticDetection::default()),
        labels_source: None,
        latitude_deg: None,
    };
    let got = import_columns(&[&a, &b], &import).unwrap().recording;
    println!("{}", got.header.comments.join("\n"));
    let dwells = got.dwells();
    assert_eq!(dwells.len(), 2, "one interval per file");
    assert_eq!(dwells[0].rows.last().unwrap().t_s, 59.9, "the first ends with file a's last record");
    assert_eq!(dwells[1].rows[0].t_s, 60.0, "the second starts with file b's first record");
    assert!(dwells.iter().all(|d| d.rows.len() > 350), "each file's rest, but the window's half at the far ends");
}
