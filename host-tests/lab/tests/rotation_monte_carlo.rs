//! SIMULATION: the general estimator with the turntable's moves (`sinscal calibrate --model full`) on a
//! 14-position schedule with a tactical MEMS IMU and white noise only, against the Cramer-Rao bound of the dwell
//! means and the moves' rotations computed independently of the core (`sinscal_lab::rotation_mc`).
//!
//! The acceptance, for every gyro scale factor and misalignment: RMS of error / reported standard error in
//! [0.8, 1.2] and RMS error / bound at most 1.05, over 2000 runs (the issue asks for at least 200; at 200 an
//! RMS scatters by 5 %, as much as the band, so the efficient estimator itself misses it on some parameter in
//! about one run of the campaign in six):
//! `cargo test --release -p sinscal-lab --test rotation_monte_carlo -- --ignored --nocapture` (more runs with
//! `SINSCAL_MC_RUNS`). The table also gives, per parameter, the RMS error of the efficient reference estimator on
//! the same runs (the generalised least squares linearised at the truth, whose covariance is the bound):
//! "GLS/CRB" is the scatter of the runs themselves (an RMS over n runs scatters by 1 / sqrt(2 n) relative, 5 % at
//! 200), and "RMS/GLS" the estimator's RMS error over the reference's, RMS error / bound with that scatter divided
//! out.

use std::time::Instant;

use sinscal::calib::general::parameter_name;
use sinscal_host::model::simulator::simulate;
use sinscal_host::model::synth::{mul, rotation_vector, transpose};
use sinscal_lab::bound::{channel_noises, cramer_rao, design, dwell_mean_covariance, dwell_spans, Session};
use sinscal_lab::rotation_mc::{
    core_jacobian_agreement, figures, gyro_parameters, integrate, move_covariance_rad2, moves_of, reference_errors,
    run_all, scenario, setup, table, truth_si, without_noise, Setup,
};

/// The gyro scale factors (15-17) and misalignments (18-23): the terms the moves are for.
fn moved_terms() -> std::ops::Range<usize> {
    15..24
}

fn print_setup(setup: &Setup) {
    let noise = channel_noises(&setup.scenario);
    println!(
        "SIMULATION: 14 positions, dwells {} s, moves {} s, {} Hz; white noise only: gyro {:.3e} rad/s, accel {:.3e} \
         m/s^2 per sample; {} moves; {} determined parameters",
        setup.scenario.schedule.dwell_s,
        setup.scenario.schedule.move_s,
        setup.scenario.schedule.rate_hz,
        noise[0].white_sample_std_si,
        noise[3].white_sample_std_si,
        setup.bound.moves.len(),
        setup.parameters.len()
    );
}

/// The dwell part of the bound is the existing bound of the dwell means (`bound::cramer_rao`) when the dwells
/// alone determine the parameters, and every move's integrated rotation noise has the covariance the bound
/// gives it (whitened squared error of 3 on average).
fn check_bound_machinery(setup: &Setup) {
    let s = &setup.scenario;
    let quiet = simulate(&without_noise(s), 0, "quiet");
    let session = Session {
        latitude_rad: s.site.latitude_deg.to_radians(),
        gravity_mps2: s.gravity_mps2(),
        positions_deg: s.schedule.positions_deg.clone(),
    };
    let spans = dwell_spans(&quiet).unwrap();
    let covariance = channel_noises(s).map(|n| dwell_mean_covariance(&n, &spans, 1.0 / s.schedule.rate_hz));
    let dwell_only = setup.bound.dwell_only_std_si.as_ref().expect("14 positions determine every term from dwells");
    let existing = cramer_rao(&design(&session, &setup.truth_si), &covariance, &setup.parameters).unwrap().std_si();
    for (i, &p) in setup.parameters.iter().enumerate() {
        assert!(
            (dwell_only[i] / existing[i] - 1.0).abs() < 1e-6,
            "{}: {} vs {}",
            parameter_name(p),
            dwell_only[i],
            existing[i]
        );
        assert!(setup.bound.std_si()[i] > 0.0 && setup.bound.std_si()[i] <= dwell_only[i] * (1.0 + 1e-9));
    }
    // The moves are what determine the gyro scale factors and misalignments: at least 5 times better than the
    // dwells alone (which see them through the Earth rate only).
    for p in moved_terms() {
        let i = setup.parameters.iter().position(|&q| q == p).unwrap();
        let gain = dwell_only[i] / setup.bound.std_si()[i];
        println!(
            "{}: bound {:.3e}, dwells alone {:.3e} ({gain:.0} times)",
            parameter_name(p),
            setup.bound.std_si()[i],
            dwell_only[i]
        );
        assert!(gain > 5.0, "{}: the moves improve the bound only {gain:.2} times", parameter_name(p));
    }
    // The moves' rotation noise: integrated at the truth, noisy against noise-free, whitened by the bound's
    // covariance; 3 per move on average (chi-square of 3 degrees of freedom).
    let var = channel_noises(s).map(|n| n.white_sample_std_si.powi(2));
    let quiet_moves = moves_of(&quiet);
    let (mut sum, mut count) = (0.0, 0usize);
    for seed in 0..8 {
        let noisy = moves_of(&simulate(s, 1000 + seed, "noisy"));
        for (m, q) in noisy.iter().zip(&quiet_moves) {
            let e = rotation_vector(&mul(
                &integrate(&m.samples, &setup.truth_si),
                &transpose(&integrate(&q.samples, &setup.truth_si)),
            ));
            let cov = move_covariance_rad2(&q.samples, &setup.truth_si, [var[0], var[1], var[2]]);
            let inv =
                sinscal_host::stats::solve::solve_spd(&cov.iter().map(|r| r.to_vec()).collect::<Vec<_>>(), &[0.0; 3])
                    .unwrap()
                    .1;
            sum += (0..3).map(|a| (0..3).map(|b| e[a] * inv[a][b] * e[b]).sum::<f64>()).sum::<f64>();
            count += 1;
        }
    }
    let mean = sum / count as f64;
    println!(
        "moves' rotation noise against its covariance: whitened squared error {mean:.3} on average over {count} \
         moves (3 expected)"
    );
    // The mean of `count` chi-squares of 3 has the standard deviation sqrt(6 / count); four of them.
    assert!((mean - 3.0).abs() < 4.0 * (6.0 / count as f64).sqrt(), "{mean}");
}

/// The reference estimator (generalised least squares linearised at the truth) on noise-free sessions: zero
/// error at the truth, and a known change of the gyro terms comes back with its sign through the dwells and the
/// moves (the moves' Jacobians enter with the opposite sign of the dwells' design).
fn check_reference_estimator(setup: &Setup) {
    let quiet = without_noise(&setup.scenario);
    let at_truth = reference_errors(&setup.bound, &setup.truth_si, &simulate(&quiet, 0, "quiet"));
    let mut changed = quiet.clone();
    let delta = [(17, 1e-4), (18, -1e-4), (23, 5e-5), (15, -5e-5)];
    for (p, d) in delta {
        match p {
            15..=17 => changed.gyro.scale_factor[p - 15] += d,
            18 => changed.gyro.misalignment[0][1] += d,
            _ => changed.gyro.misalignment[2][1] += d,
        }
    }
    assert!((truth_si(&changed)[23] - setup.truth_si[23] - 5e-5).abs() < 1e-15, "misalignment zy is parameter 23");
    let moved = reference_errors(&setup.bound, &setup.truth_si, &simulate(&changed, 0, "changed"));
    let bound = setup.bound.std_si();
    for (i, &p) in setup.parameters.iter().enumerate() {
        let expected = delta.iter().find(|(q, _)| *q == p).map_or(0.0, |(_, d)| *d);
        assert!(at_truth[i].abs() < 1e-3 * bound[i], "{} at the truth: {:e}", parameter_name(p), at_truth[i]);
        assert!(
            (moved[i] - expected).abs() < 1e-2 * bound[i],
            "{}: {:e} for {expected:e}",
            parameter_name(p),
            moved[i]
        );
    }
}

/// The core's Jacobian of every simulated move (f32, `MoveSums`, its prior at the truth) against the finite
/// differences of the bound (both with the compensated force in the g-sensitivity): per column its difference over the column's largest component (columns of at least a tenth
/// of their kind's largest) and over the kind's largest component (all columns). Returns the worst of both.
fn check_core_jacobian(setup: &Setup) -> (f64, f64) {
    let quiet = simulate(&without_noise(&setup.scenario), 0, "quiet");
    let moves = moves_of(&quiet);
    // The core's move columns are the gyro parameters the finite differences cover.
    assert_eq!(sinscal::calib::moves::MOVE_PARAMETERS.to_vec(), gyro_parameters());
    let (mut own, mut kind) = (0.0f64, 0.0f64);
    for m in &moves {
        let (columns, angle) = core_jacobian_agreement(&m.samples, &setup.truth_si);
        let big = columns.iter().filter(|c| c.column_scale_rad_per_si >= 0.1 * c.kind_scale_rad_per_si);
        let worst_own = big.map(|c| c.difference_rad_per_si / c.column_scale_rad_per_si).fold(0.0, f64::max);
        let worst = columns
            .iter()
            .max_by(|a, b| {
                (a.difference_rad_per_si / a.kind_scale_rad_per_si)
                    .total_cmp(&(b.difference_rad_per_si / b.kind_scale_rad_per_si))
            })
            .unwrap();
        println!(
            "move {:>2} -> {:>2}: rotations {angle:.1e} rad apart; Jacobian relative difference: largest columns \
             {worst_own:.1e}, all columns {:.1e} of their kind's largest ({})",
            m.from + 1,
            m.to + 1,
            worst.difference_rad_per_si / worst.kind_scale_rad_per_si,
            parameter_name(worst.parameter)
        );
        own = own.max(worst_own);
        kind = kind.max(worst.difference_rad_per_si / worst.kind_scale_rad_per_si);
    }
    (own, kind)
}

#[test]
fn bound_machinery_and_a_short_monte_carlo() {
    let start = Instant::now();
    let setup = setup(scenario());
    print_setup(&setup);
    assert_eq!(setup.truth_si, truth_si(&setup.scenario));
    check_bound_machinery(&setup);
    check_reference_estimator(&setup);
    let (own, kind) = check_core_jacobian(&setup);
    println!("core Jacobian against the finite differences: {own:.1e} of a column, {kind:.1e} of its kind's largest");
    assert!(own < 2e-4 && kind < 2e-4, "{own} {kind}");
    let outcomes = run_all(&setup, 12, 1);
    let failed: Vec<&String> = outcomes.iter().filter_map(|o| o.as_ref().err()).collect();
    assert!(failed.is_empty(), "{failed:?}");
    let f = figures(&setup, &outcomes);
    println!("{}", table(&f));
    for x in &f {
        assert_eq!(x.runs, 12, "{} undetermined in some runs", parameter_name(x.parameter));
        assert!(x.rms_z < 2.0, "{}: RMS z {}", parameter_name(x.parameter), x.rms_z);
    }
    println!("wall time {:.1} s", start.elapsed().as_secs_f64());
}

/// Runs of the acceptance: 2000, or `SINSCAL_MC_RUNS` (at least 200).
fn runs() -> usize {
    std::env::var("SINSCAL_MC_RUNS").ok().and_then(|v| v.parse().ok()).filter(|&n| n >= 200).unwrap_or(2000)
}

#[test]
#[ignore = "2000 runs: cargo test --release -p sinscal-lab --test rotation_monte_carlo -- --ignored --nocapture"]
fn gyro_scale_factors_and_misalignments_from_the_moves_meet_the_acceptance() {
    let runs = runs();
    let start = Instant::now();
    let setup = setup(scenario());
    print_setup(&setup);
    let outcomes = run_all(&setup, runs, 1);
    let failed: Vec<&String> = outcomes.iter().filter_map(|o| o.as_ref().err()).collect();
    let f = figures(&setup, &outcomes);
    let passes: Vec<u32> = outcomes.iter().filter_map(|o| o.as_ref().ok().map(|r| r.move_passes)).collect();
    let scaled =
        outcomes.iter().filter_map(|o| o.as_ref().ok()).filter(|r| r.std_scale[..3].iter().any(|s| *s != 1.0)).count();
    println!(
        "{runs} runs, seeds 1 to {runs}; {} failed; move passes {} to {}; gyro fit scale above 1 in {scaled} runs",
        failed.len(),
        passes.iter().min().unwrap_or(&0),
        passes.iter().max().unwrap_or(&0)
    );
    println!("{}", table(&f));
    println!("wall time {:.1} s", start.elapsed().as_secs_f64());
    assert!(failed.is_empty(), "{failed:?}");
    let mut misses = Vec::new();
    for x in f.iter().filter(|x| moved_terms().contains(&x.parameter)) {
        if x.runs != runs || !(0.8..=1.2).contains(&x.rms_z) || x.rms_over_bound() > 1.05 {
            misses.push(format!(
                "{}: RMS z {:.3}, RMS / CRB {:.3}, {} runs",
                parameter_name(x.parameter),
                x.rms_z,
                x.rms_over_bound(),
                x.runs
            ));
        }
    }
    assert!(misses.is_empty(), "acceptance missed:\n{}", misses.join("\n"));
}
