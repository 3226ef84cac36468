//! Benchmark of `sinscal analyze` on a recording (criterion): the scenario of the speed measurement
//! (host-tests/scenarios/mems-1khz-hour.toml, six positions at 1 kHz) with 60 s dwells instead of 600 s,
//! simulated in memory (360,000 rows), analysed from the parsed recording (docs/analysis.md#speed-and-memory).

use std::hint::black_box;
use std::path::Path;
use std::time::Duration;

use criterion::{criterion_group, criterion_main, Criterion};
use sinscal_host::analysis::analyze_recording;
use sinscal_host::model::simulator::{simulate, ScenarioFile};

fn benches(c: &mut Criterion) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/mems-1khz-hour.toml");
    let mut scenario = ScenarioFile::read(&path).unwrap_or_else(|e| panic!("{e}"));
    scenario.schedule.dwell_s = 60.0;
    let recording = simulate(&scenario, 7, "mems-1khz-hour.toml with 60 s dwells");
    let mut group = c.benchmark_group("analyze");
    group.sample_size(10).warm_up_time(Duration::from_secs(2)).measurement_time(Duration::from_secs(30));
    group.bench_function("6 x 60 s at 1 kHz (360,000 rows)", |b| {
        b.iter(|| analyze_recording(black_box(&recording)).unwrap_or_else(|e| panic!("{e}")))
    });
    group.finish();
}

criterion_group!(analyze, benches);
criterion_main!(analyze);
