//! Benchmark of the recording reader against counting the file's lines (criterion), the measure of the speed
//! goal "calibrate at most 15 times the time of `wc -l` on the same cached file" (docs/formats.md#speed-and-memory):
//! the clean Table 1 scenario at 1 kHz with 60-s dwells (363,100 rows, SIMULATION, seed 1) written to a
//! scratch file once, then (1) its lines counted by `wc -l` (and by a plain loop over 1-MB blocks), (2) every
//! row read and parsed (`RecordingFile::for_each_row`, the reader alone) and (3) the whole
//! calibration (`calibration::calibrate`, default options). The ratios (2)/(1) and (3)/(1) are the figures.

use std::hint::black_box;
use std::io::Read as _;
use std::path::Path;
use std::time::Duration;

use criterion::{criterion_group, criterion_main, Criterion};
use sinscal_host::calibration::{calibrate, Options};
use sinscal_host::io::recording::{RecordingFile, RowSource};
use sinscal_host::model::simulator::{simulate, ScenarioFile};

/// Newlines of the file at `path`, read in 1-MB blocks.
fn count_lines(path: &Path) -> usize {
    let mut file = std::fs::File::open(path).unwrap();
    let mut buffer = vec![0u8; 1 << 20];
    let mut lines = 0;
    loop {
        let n = file.read(&mut buffer).unwrap();
        if n == 0 {
            return lines;
        }
        lines += buffer[..n].iter().filter(|&&b| b == b'\n').count();
    }
}

fn benches(c: &mut Criterion) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/table1-clean.toml");
    let mut scenario = ScenarioFile::read(&path).unwrap_or_else(|e| panic!("{e}"));
    scenario.schedule.rate_hz = 1000.0;
    let recording = simulate(&scenario, 1, "table1-clean.toml at 1 kHz");
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("session.csv");
    recording.write(&file).unwrap();
    drop(recording);
    let rows = count_lines(&file);
    let mut group = c.benchmark_group(format!("reader ({rows} lines)"));
    group.sample_size(10).warm_up_time(Duration::from_secs(2)).measurement_time(Duration::from_secs(20));
    // `wc -l` itself (its process start included, about a millisecond), and a plain Rust count for comparison.
    group.bench_function("wc -l", |b| {
        b.iter(|| std::process::Command::new("wc").arg("-l").arg(black_box(&file)).output().unwrap())
    });
    group.bench_function("count newlines (plain loop)", |b| b.iter(|| count_lines(black_box(&file))));
    group.bench_function("read and parse every row", |b| {
        b.iter(|| {
            let rec = RecordingFile::open(&file).unwrap();
            let mut n = 0usize;
            rec.for_each_row(&mut |row| {
                n += black_box(row).line & 1;
                Ok(())
            })
            .unwrap();
            n
        })
    });
    group.bench_function("calibrate (default options)", |b| {
        b.iter(|| calibrate(&RecordingFile::open(&file).unwrap(), &Options::default()).unwrap())
    });
    group.finish();
}

criterion_group!(reader, benches);
criterion_main!(reader);
