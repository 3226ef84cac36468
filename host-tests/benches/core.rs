//! Host benchmarks of the core's hot paths (criterion): the per-sample dwell update (six channels, with
//! and without the HMM/KF prefilter), one alignment, and one six-position solution. Instruction counts
//! on the Cortex-M4F come from the firmware's QEMU benchmark, not from here.

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion};
use sinscal::calib::align::{position_angles, DwellValue};
use sinscal::calib::angles::{BiasSolver, SolverSettings, TABLE1_POSITIONS_DEG};
use sinscal::calib::dwell::{DwellCollector, Prefilter};
use sinscal::nav::earth::Site;
use sinscal::nav::frames::Attitude;
use sinscal::sensor::sample::ImuSample;

fn sample(k: u32) -> ImuSample {
    let wobble = (k % 17) as f32 * 1e-7;
    ImuSample { rate_b_radps: [1e-6 + wobble, 5.1e-5, 5.2e-5 - wobble], force_b_mps2: [1e-3, -2e-3 + wobble, 9.806] }
}

fn benches(c: &mut Criterion) {
    for (name, prefilter) in
        [("dwell update, no prefilter", Prefilter::None), ("dwell update, hmmkf", Prefilter::paper())]
    {
        let mut collector = DwellCollector::new(&prefilter).unwrap();
        let mut k = 0u32;
        c.bench_function(name, |b| {
            b.iter(|| {
                k = k.wrapping_add(1);
                collector.update(black_box(&sample(k))).unwrap();
            })
        });
    }

    let site = Site::with_normal_gravity(45.7796f32.to_radians(), 0.0);
    let mut collector = DwellCollector::new(&Prefilter::paper()).unwrap();
    let mut summaries = Vec::new();
    for p in TABLE1_POSITIONS_DEG {
        let c_b_n = Attitude::from_degrees(p[0], p[1], p[2]).c_b_n();
        collector.reset();
        for k in 0..200 {
            let mut s = sample(k);
            s.rate_b_radps = c_b_n.transpose().mul_vec(site.earth_rate_n_radps());
            s.force_b_mps2 = c_b_n.transpose().mul_vec(site.force_at_rest_n_mps2());
            s.force_b_mps2[0] += (k % 7) as f32 * 1e-4;
            collector.update(&s).unwrap();
        }
        summaries.push((c_b_n, collector.summary().unwrap()));
    }
    c.bench_function("alignment of one position", |b| {
        b.iter(|| position_angles(black_box(&summaries[2].1), DwellValue::Mean, &summaries[2].0, &site).unwrap())
    });
    let angles: Vec<_> =
        summaries.iter().map(|(c, s)| (*c, position_angles(s, DwellValue::Mean, c, &site).unwrap())).collect();
    c.bench_function("six-position solution", |b| {
        b.iter(|| {
            let mut solver = BiasSolver::new(site, SolverSettings::default());
            for (c, a) in &angles {
                solver.add(c, a.phi_n_rad, &a.covariance_rad2).unwrap();
            }
            black_box(solver.solve().unwrap())
        })
    });
}

criterion_group!(core, benches);
criterion_main!(core);
