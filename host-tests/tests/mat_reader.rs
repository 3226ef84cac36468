//! The MAT-file reader (`sinscal_host::io::import::mat`) on the shared data sets in the directory named by the
//! environment variable `SINSCAL_DATA` (skipped with a message when it is not set). The format itself (round
//! trips, byte orders, compressed elements, storage types, refusals) is tested in the module's unit tests.

mod common;

use std::path::{Path, PathBuf};

use common::{data_dir, data_file};
use sinscal_host::io::import::mat::read_mat;

/// Every file under `dir`, recursively.
fn files(dir: &Path, out: &mut Vec<PathBuf>) {
    let mut entries: Vec<PathBuf> = std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().path()).collect();
    entries.sort();
    for p in entries {
        if p.is_dir() {
            files(&p, out);
        } else {
            out.push(p);
        }
    }
}

/// imu_tk's `xsens_acc.mat` and `xsens_gyro.mat` are text (columns of numbers, as MATLAB's `save -ascii`
/// writes) despite their name: the reader says so, with the first line, and points at `sinscal import imutk`.
#[test]
fn imutk_mat_files_are_text_and_refused_as_such() {
    let Some(dir) = data_dir() else { return };
    for name in ["imu-tk-xsens/xsens_acc.mat", "imu-tk-xsens/xsens_gyro.mat"] {
        let path = data_file(&dir, name);
        let bytes = std::fs::read(&path).unwrap();
        let e = read_mat(&bytes, name).expect_err("a text file is not a MAT-file").to_string();
        println!("{e}");
        assert!(e.starts_with(&format!("{name}: text, not a MAT-file (its first line: '   2.9840000e-02")), "{e}");
        assert!(e.contains("sinscal import imutk"), "{e}");
    }
}

/// Every file of the data directory: a file with a MAT-file header (level 5 or 7.3) must read (at least one
/// finite matrix); every other one must be refused. Prints what each file is.
#[test]
fn every_shared_data_file_is_read_or_refused_as_what_it_is() {
    let Some(dir) = data_dir() else { return };
    let mut all = Vec::new();
    files(&dir, &mut all);
    assert!(all.len() >= 3, "SINSCAL_DATA is set but holds {} files", all.len());
    let mut mat_files = 0;
    let is_mat = |b: &[u8]| b.starts_with(b"MATLAB 5.0 MAT-file") || b.starts_with(b"MATLAB 7.3 MAT-file");
    for path in &all {
        let bytes = std::fs::read(path).unwrap();
        let name = path.strip_prefix(&dir).unwrap().display().to_string();
        match read_mat(&bytes, &name) {
            Ok(matrices) => {
                assert!(is_mat(&bytes), "{name} read without a MAT-file header");
                mat_files += 1;
                for m in matrices {
                    println!("{name}: '{}' {}x{}", m.name, m.rows, m.cols);
                }
            }
            Err(e) => {
                assert!(!is_mat(&bytes), "a MAT-file refused: {e}");
                println!("{e}");
            }
        }
    }
    println!("{} files, {mat_files} MAT-files", all.len());
}
