//! SIMULATION: the noise-analysis module (`sinscal_host::stats::noise`) on seeded synthetic noise of known
//! parameters: Allan deviation and noise-term identification (white noise, rate random walk, first-order
//! Gauss-Markov, angle quantization), Welch PSD (white level, Parseval, a sinusoid), the FFT against a
//! direct DFT, the Ljung-Box test and the chi-square distribution, and quantization detection.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal, StandardNormal};
use sinscal_host::stats::noise::*;

/// `n` samples of white Gaussian noise of standard deviation `sigma`.
fn white(seed: u64, n: usize, sigma: f64) -> Vec<f64> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let d = Normal::new(0.0, sigma).unwrap();
    (0..n).map(|_| d.sample(&mut rng)).collect()
}

/// Least-squares slope of log(adev) against log(tau) over the points with tau in [lo, hi] s.
fn log_log_slope(points: &[AllanPoint], lo: f64, hi: f64) -> f64 {
    let xy: Vec<(f64, f64)> =
        points.iter().filter(|p| p.tau_s >= lo && p.tau_s <= hi).map(|p| (p.tau_s.ln(), p.adev.ln())).collect();
    let n = xy.len() as f64;
    let (mx, my) = (xy.iter().map(|p| p.0).sum::<f64>() / n, xy.iter().map(|p| p.1).sum::<f64>() / n);
    let sxy: f64 = xy.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let sxx: f64 = xy.iter().map(|p| (p.0 - mx) * (p.0 - mx)).sum();
    sxy / sxx
}

fn rel(a: f64, b: f64) -> f64 {
    a / b - 1.0
}

// ---------------------------------------------------------------------------------------------------
// Allan deviation and noise terms
// ---------------------------------------------------------------------------------------------------

#[test]
fn white_noise_allan_deviation_is_sigma_over_sqrt_rate_tau_and_fit_recovers_n() {
    let (fs, sigma, n) = (100.0, 0.02, 200_000);
    let y = white(1, n, sigma);
    let n_true = sigma / f64::sqrt(fs); // u/sqrt(Hz)
    let pts = overlapping_allan_deviation(&y, fs, &[1, 10, 100, 1000, 10_000]);
    assert_eq!(pts.len(), 5);
    for p in &pts {
        let expected = sigma / (fs * p.tau_s).sqrt();
        let z = rel(p.adev, expected) / p.rel_uncertainty;
        println!(
            "white: m {:>6} tau {:>7.2} s  adev {:.4e} expected {:.4e}  error {:+.2}% = {:+.2} stated sigma",
            p.cluster_size,
            p.tau_s,
            p.adev,
            expected,
            100.0 * rel(p.adev, expected),
            z
        );
        assert_eq!(p.terms, n + 1 - 2 * p.cluster_size);
        assert!(z.abs() <= 2.0, "m = {}: {z} stated sigma", p.cluster_size);
    }

    // Calibration of the stated uncertainty over 20 more records: RMS of (error / stated sigma) per m.
    let ms = [1, 10, 100, 1000, 10_000];
    let mut sum_z2 = [0.0; 5];
    let records = 20;
    for seed in 0..records {
        let yy = white(100 + seed, n, sigma);
        for (i, p) in overlapping_allan_deviation(&yy, fs, &ms).iter().enumerate() {
            let z = rel(p.adev, sigma / (fs * p.tau_s).sqrt()) / p.rel_uncertainty;
            sum_z2[i] += z * z;
        }
    }
    for (m, s2) in ms.iter().zip(sum_z2) {
        let rms_z = (s2 / records as f64).sqrt();
        println!("white: m {m:>6}: RMS error / stated sigma over {records} records = {rms_z:.2}");
        // About 1.22 is expected at m = 1 (see AllanPoint::rel_uncertainty), less above.
        assert!(rms_z < 1.5, "m = {m}: {rms_z}");
    }

    let curve = overlapping_allan_deviation(&y, fs, &log_spaced_clusters(n, 10));
    let fit = fit_noise_terms(&curve).unwrap();
    println!("white: fit {:?}, weighted RMS residual {:.3}", fit.terms, fit.weighted_rms_residual);
    println!("white: classic {:?}", fit.classic);
    println!(
        "white: N fit {:.5e} vs true {:.5e} ({:+.2}%), classic {:+.2}%",
        fit.terms.random_walk_n,
        n_true,
        100.0 * rel(fit.terms.random_walk_n, n_true),
        100.0 * rel(fit.classic.random_walk_n.unwrap(), n_true)
    );
    assert!(rel(fit.terms.random_walk_n, n_true).abs() < 0.05);
    assert!(rel(fit.classic.random_walk_n.unwrap(), n_true).abs() < 0.05);
    // The other terms are negligible at every tau of the record.
    for p in &curve {
        let t = fit.terms;
        let others = NoiseTerms { random_walk_n: 0.0, ..t };
        assert!(others.allan_variance(p.tau_s) < 0.25 * t.allan_variance(p.tau_s), "tau {}", p.tau_s);
    }
}

#[test]
fn rate_random_walk_has_slope_plus_half_and_fit_recovers_k() {
    // y_k = sum of white steps of standard deviation s: K = s * sqrt(fs) (u/sqrt(s)).
    let (fs, s, n) = (100.0, 1e-4, 200_000);
    let k_true = s * f64::sqrt(fs);
    for seed in [2, 3, 4] {
        let steps = white(seed, n, s);
        let y: Vec<f64> = steps
            .iter()
            .scan(0.0, |acc, w| {
                *acc += w;
                Some(*acc)
            })
            .collect();
        let curve = overlapping_allan_deviation(&y, fs, &log_spaced_clusters(n, 10));
        let slope = log_log_slope(&curve, 0.1, 100.0);
        let fit = fit_noise_terms(&curve).unwrap();
        let k_classic = fit.classic.rate_random_walk_k.unwrap();
        println!(
            "random walk seed {seed}: slope {slope:.3}; K fit {:.4e} ({:+.1}%), classic {:.4e} ({:+.1}%), \
             true {k_true:.4e}; fit {:?}",
            fit.terms.rate_random_walk_k,
            100.0 * rel(fit.terms.rate_random_walk_k, k_true),
            k_classic,
            100.0 * rel(k_classic, k_true),
            fit.terms
        );
        assert!((slope - 0.5).abs() < 0.05, "slope {slope}");
        assert!(rel(fit.terms.rate_random_walk_k, k_true).abs() < 0.15);
        assert!(rel(k_classic, k_true).abs() < 0.15);
    }
}

#[test]
fn gauss_markov_allan_curve_peaks_near_1_89_correlation_times() {
    // x_k = a x_{k-1} + w_k, a = exp(-dt/T), stationary standard deviation sigma_gm.
    let (fs, t_corr, sigma_gm, n): (f64, f64, f64, usize) = (100.0, 0.2, 1.0, 200_000);
    let a = (-1.0 / (fs * t_corr)).exp();
    let w = white(5, n, sigma_gm * (1.0 - a * a).sqrt());
    let mut x = Vec::with_capacity(n);
    let mut state = Normal::new(0.0, sigma_gm).unwrap().sample(&mut ChaCha8Rng::seed_from_u64(6));
    for wk in w {
        state = a * state + wk;
        x.push(state);
    }
    // Dense cluster sizes around the expected peak (1.89 T = 37.8 samples).
    let clusters: Vec<usize> = (10..=120).collect();
    let curve = overlapping_allan_deviation(&x, fs, &clusters);
    let imax = (0..curve.len()).max_by(|&i, &j| curve[i].adev.total_cmp(&curve[j].adev)).unwrap();
    // Parabola in (ln tau, ln adev) through the points within a factor 1.5 of the argmax in tau.
    let t0 = curve[imax].tau_s;
    let sel: Vec<(f64, f64)> = curve
        .iter()
        .filter(|p| p.tau_s >= t0 / 1.5 && p.tau_s <= t0 * 1.5)
        .map(|p| ((p.tau_s / t0).ln(), p.adev.ln()))
        .collect();
    let (c0, c1, c2) = quadratic_fit(&sel);
    let u_peak = -c1 / (2.0 * c2);
    let tau_peak = t0 * u_peak.exp();
    let adev_peak = (c0 + c1 * u_peak + c2 * u_peak * u_peak).exp();
    println!(
        "Gauss-Markov: peak at tau {tau_peak:.4} s = {:.3} T (expected 1.89 T), argmax {:.3} T; adev {adev_peak:.4} = \
         {:.4} sigma_gm (expected 0.62)",
        tau_peak / t_corr,
        t0 / t_corr,
        adev_peak / sigma_gm
    );
    assert!(rel(tau_peak, 1.89 * t_corr).abs() < 0.15);
    assert!(rel(adev_peak, 0.62 * sigma_gm).abs() < 0.15);
    assert!(rel(t0, 1.89 * t_corr).abs() < 0.15);
}

/// Least squares y = c0 + c1 x + c2 x^2 (normal equations, Cramer's rule).
fn quadratic_fit(xy: &[(f64, f64)]) -> (f64, f64, f64) {
    let mut s = [0.0; 5];
    let mut t = [0.0; 3];
    for &(x, y) in xy {
        for (k, sk) in s.iter_mut().enumerate() {
            *sk += x.powi(k as i32);
        }
        for (k, tk) in t.iter_mut().enumerate() {
            *tk += y * x.powi(k as i32);
        }
    }
    let m = [[s[0], s[1], s[2]], [s[1], s[2], s[3]], [s[2], s[3], s[4]]];
    let det3 = |m: &[[f64; 3]; 3]| {
        m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
    };
    let d = det3(&m);
    let solve = |col: usize| {
        let mut mc = m;
        for r in 0..3 {
            mc[r][col] = t[r];
        }
        det3(&mc) / d
    };
    (solve(0), solve(1), solve(2))
}

#[test]
fn angle_quantization_gives_the_minus_one_slope_term_q_over_sqrt_12() {
    // Model tested (IEEE Std 952-1997 Annex C, angle quantization): the sensor integrates its
    // rate and outputs the accumulated angle rounded to a step q (rad); the rate samples are the
    // differences of that output times fs. The true rate is a constant w0 (the angle is a slow ramp,
    // 0.12 q per sample) plus white noise whose angle increments have a standard deviation of 0.5 q per
    // sample: enough to make the rounding errors independent and uniform (the characteristic function of
    // the increment at 2 pi / q is exp(-2 pi^2 0.25) = 0.007), so Q = q / sqrt(12) and
    // N = 0.5 q fs / sqrt(fs).
    let (fs, q, n) = (100.0, 1e-3, 200_000);
    let dt = 1.0 / fs;
    let w0 = 0.0123; // rad/s
    let sigma_rate = 0.5 * q / dt; // rad/s per sample
    let w = white(7, n + 1, sigma_rate);
    let mut theta = 0.0;
    let mut counts = Vec::with_capacity(n + 1);
    for wk in &w {
        theta += (w0 + wk) * dt;
        counts.push((theta / q).round());
    }
    let y: Vec<f64> = counts.windows(2).map(|c| (c[1] - c[0]) * q / dt).collect();
    let q_true = q / 12f64.sqrt();
    let n_true = sigma_rate / fs.sqrt();
    let curve = overlapping_allan_deviation(&y, fs, &log_spaced_clusters(n, 10));
    let fit = fit_noise_terms(&curve).unwrap();
    println!(
        "quantization: Q fit {:.4e} vs q/sqrt(12) {q_true:.4e} ({:+.1}%); N fit {:.4e} vs {n_true:.4e} ({:+.1}%); \
         fit {:?}",
        fit.terms.quantization_q,
        100.0 * rel(fit.terms.quantization_q, q_true),
        fit.terms.random_walk_n,
        100.0 * rel(fit.terms.random_walk_n, n_true),
        fit.terms
    );
    assert!(rel(fit.terms.quantization_q, q_true).abs() < 0.20);
    assert!(rel(fit.terms.random_walk_n, n_true).abs() < 0.05);
    // The rate output is quantized to q / dt.
    let det = detect_quantization(&y).unwrap();
    println!("quantization: detected {det:?}");
    assert!(det.quantized);
    assert!(rel(det.step, q / dt).abs() < 1e-9);
}

#[test]
fn noise_terms_model_and_edge_cases() {
    let t = NoiseTerms {
        quantization_q: 1e-5,
        random_walk_n: 1e-4,
        bias_instability_b: 2e-5,
        rate_random_walk_k: 1e-6,
        ramp_r: 1e-8,
    };
    // Pure terms at their characteristic read-off points.
    let only_n = NoiseTerms { random_walk_n: 1e-4, ..Default::default() };
    assert!((only_n.allan_deviation(1.0) - 1e-4).abs() < 1e-18);
    let only_k = NoiseTerms { rate_random_walk_k: 1e-6, ..Default::default() };
    assert!((only_k.allan_deviation(3.0) - 1e-6).abs() < 1e-20);
    let only_b = NoiseTerms { bias_instability_b: 2e-5, ..Default::default() };
    assert!((only_b.allan_deviation(123.0) / 2e-5 - 0.6643).abs() < 1e-4);
    assert!((bias_instability_factor() - 0.664_282_4).abs() < 1e-6);

    // A noiseless model curve is fitted back exactly.
    let pts: Vec<AllanPoint> = (0..50)
        .map(|i| {
            let tau = 10f64.powf(-2.0 + i as f64 / 8.0);
            AllanPoint {
                cluster_size: i + 1,
                tau_s: tau,
                adev: t.allan_deviation(tau),
                terms: 100,
                rel_uncertainty: 0.05,
            }
        })
        .collect();
    let fit = fit_noise_terms(&pts).unwrap();
    for (a, b) in fit.terms.as_array().iter().zip(t.as_array()) {
        assert!(rel(*a, b).abs() < 1e-6, "{a} vs {b}");
    }
    assert!(fit.weighted_rms_residual < 1e-6);

    // Classic read-offs on a noiseless curve with well-separated N, B and K regions. (The floor read-off
    // is biased high by the N and K terms at the minimum: by sqrt(1 + (2 N K / sqrt(3)) / (0.441 B^2)),
    // 1.3% here, 12% with K = 1e-9.)
    let sep =
        NoiseTerms { random_walk_n: 1e-4, bias_instability_b: 1e-6, rate_random_walk_k: 1e-10, ..Default::default() };
    let pts: Vec<AllanPoint> = (0..=104)
        .map(|i| {
            let tau = 10f64.powf(-2.0 + i as f64 / 8.0);
            AllanPoint {
                cluster_size: i + 1,
                tau_s: tau,
                adev: sep.allan_deviation(tau),
                terms: 100,
                rel_uncertainty: 0.05,
            }
        })
        .collect();
    let c = classic_read_offs(&pts);
    println!("classic read-offs on a model curve (N 1e-4, B 1e-6, K 1e-10): {c:?}");
    assert!(rel(c.random_walk_n.unwrap(), 1e-4).abs() < 0.05);
    assert!(rel(c.bias_instability_b.unwrap(), 1e-6).abs() < 0.05);
    assert!(rel(c.rate_random_walk_k.unwrap(), 1e-10).abs() < 0.05);

    // Short, empty or bad input: no panic.
    assert!(overlapping_allan_deviation(&[], 100.0, &[1]).is_empty());
    assert!(overlapping_allan_deviation(&[1.0], 100.0, &[1]).is_empty());
    assert!(overlapping_allan_deviation(&[1.0, 2.0], 0.0, &[1]).is_empty());
    assert!(overlapping_allan_deviation(&[1.0, f64::NAN, 2.0], 10.0, &[1]).is_empty());
    let two = overlapping_allan_deviation(&[1.0, 2.0, 3.0, 4.0], 10.0, &[0, 1, 2, 3]);
    assert_eq!(two.iter().map(|p| p.cluster_size).collect::<Vec<_>>(), vec![1, 2]);
    assert!(log_spaced_clusters(0, 10).is_empty());
    assert!(log_spaced_clusters(2, 10).is_empty());
    assert!(log_spaced_clusters(100, 0).is_empty());
    assert_eq!(log_spaced_clusters(3, 10), vec![1]);
    let c = log_spaced_clusters(200_000, 10);
    assert_eq!((c[0], *c.last().unwrap()), (1, 99_999));
    assert!(c.windows(2).all(|w| w[0] < w[1]));
    println!("log_spaced_clusters(200000, 10): {} sizes", c.len());
    assert!(fit_noise_terms(&[]).is_err());
    assert_eq!(classic_read_offs(&[]), ClassicReadOffs::default());
}

// ---------------------------------------------------------------------------------------------------
// FFT and PSD
// ---------------------------------------------------------------------------------------------------

#[test]
fn fft_matches_a_direct_dft() {
    let mut rng = ChaCha8Rng::seed_from_u64(8);
    for n in [1usize, 2, 4, 8, 64, 256] {
        let x: Vec<(f64, f64)> =
            (0..n).map(|_| (rng.sample::<f64, _>(StandardNormal), rng.sample::<f64, _>(StandardNormal))).collect();
        let (mut re, mut im): (Vec<f64>, Vec<f64>) = x.iter().copied().unzip();
        fft_in_place(&mut re, &mut im).unwrap();
        let mut max_err = 0.0f64;
        for k in 0..n {
            let (mut sr, mut si) = (0.0, 0.0);
            for (j, &(xr, xi)) in x.iter().enumerate() {
                let (s, c) = (-2.0 * std::f64::consts::PI * ((k * j) % n) as f64 / n as f64).sin_cos();
                sr += xr * c - xi * s;
                si += xr * s + xi * c;
            }
            max_err = max_err.max((re[k] - sr).hypot(im[k] - si));
        }
        println!("FFT n = {n}: max |FFT - DFT| = {max_err:.2e}");
        assert!(max_err < 1e-12 * (n as f64).max(1.0), "n = {n}: {max_err}");
    }
    assert!(fft_in_place(&mut [0.0; 6], &mut [0.0; 6]).is_err());
    assert!(fft_in_place(&mut [0.0; 4], &mut [0.0; 2]).is_err());
    assert!(fft_in_place(&mut [], &mut []).is_err());
}

#[test]
fn welch_psd_of_white_noise_is_flat_at_two_sigma_squared_over_rate_and_integrates_to_the_variance() {
    let (fs, sigma, n, l) = (200.0, 0.5, 200_000, 256);
    let y = white(9, n, sigma);
    let psd = welch_psd(&y, fs, l).unwrap();
    assert_eq!(psd.frequencies_hz.len(), l / 2 + 1);
    assert_eq!(psd.density.len(), l / 2 + 1);
    assert_eq!(psd.frequencies_hz[l / 2], fs / 2.0);
    let level = 2.0 * sigma * sigma / fs;
    let mut worst = 0.0f64;
    for k in 2..l / 2 {
        worst = worst.max(rel(psd.density[k], level).abs());
    }
    // The documented edge bins: bin 1 at 5/6 of the level (mean removal through the window), Nyquist at
    // half (not doubled).
    let (bin1, nyquist) = (psd.density[1] / level, psd.density[l / 2] / level);
    println!("Welch white: bin 1 at {bin1:.3} of the level (expected 0.833), Nyquist at {nyquist:.3} (expected 0.5)");
    assert!(rel(bin1, 5.0 / 6.0).abs() < 0.10);
    assert!(rel(nyquist, 0.5).abs() < 0.15);
    let mean = y.iter().sum::<f64>() / n as f64;
    let var = y.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / (n - 1) as f64;
    let integral: f64 = psd.density.iter().sum::<f64>() * psd.resolution_hz;
    println!(
        "Welch white: {} segments, worst bin {:.2}% from 2 sigma^2/fs; Parseval integral / variance = {:.4}",
        psd.segments,
        100.0 * worst,
        integral / var
    );
    assert!(worst < 0.10);
    assert!(rel(integral, var).abs() < 0.03);

    assert!(welch_psd(&y, fs, 100).is_err());
    assert!(welch_psd(&y, fs, 1).is_err());
    assert!(welch_psd(&y[..100], fs, 128).is_err());
    assert!(welch_psd(&[], fs, 128).is_err());
    assert!(welch_psd(&y, f64::NAN, 128).is_err());
}

#[test]
fn welch_psd_of_a_sinusoid_peaks_at_its_frequency_with_half_amplitude_squared() {
    let (fs, n, l, amp, f0) = (200.0, 100_000, 1024, 0.3, 23.37);
    let noise = white(10, n, 0.01);
    let y: Vec<f64> = noise
        .iter()
        .enumerate()
        .map(|(i, w)| amp * (2.0 * std::f64::consts::PI * f0 * i as f64 / fs + 0.4).sin() + w)
        .collect();
    let psd = welch_psd(&y, fs, l).unwrap();
    let kmax = (0..psd.density.len()).max_by(|&i, &j| psd.density[i].total_cmp(&psd.density[j])).unwrap();
    let f_peak = psd.frequencies_hz[kmax];
    let df = psd.resolution_hz;
    let power = psd.band_power(f_peak - 4.0 * df, f_peak + 4.0 * df);
    println!(
        "Welch sinusoid: peak at {f_peak:.3} Hz (f0 {f0} Hz, bin {df:.4} Hz); power over 9 bins {power:.5} \
         vs A^2/2 {:.5} ({:+.2}%)",
        amp * amp / 2.0,
        100.0 * rel(power, amp * amp / 2.0)
    );
    assert!((f_peak - f0).abs() <= 0.5 * df + 1e-12);
    assert!(rel(power, amp * amp / 2.0).abs() < 0.02);
}

// ---------------------------------------------------------------------------------------------------
// Whiteness
// ---------------------------------------------------------------------------------------------------

#[test]
fn chi_square_and_incomplete_gamma_match_known_values() {
    // Table values (5% critical points) and their exact quantiles.
    assert!((chi_square_cdf(3.84, 1.0) - 0.95).abs() < 1e-3);
    assert!((chi_square_cdf(18.31, 10.0) - 0.95).abs() < 1e-3);
    assert!((chi_square_cdf(3.841_458_820_694_124, 1.0) - 0.95).abs() < 1e-12);
    assert!((chi_square_cdf(18.307_038_053_275_146, 10.0) - 0.95).abs() < 1e-12);
    assert!((chi_square_cdf(31.410_432_844_230_925, 20.0) - 0.95).abs() < 1e-12);
    assert!((chi_square_cdf(6.634_896_601_021_213, 1.0) - 0.99).abs() < 1e-12);
    // P(1, x) = 1 - exp(-x); P(1/2, x) = erf(sqrt(x)); erf(1) = 0.8427007929497149.
    for x in [0.01, 0.5, 1.0, 2.0, 5.0, 30.0] {
        assert!((regularized_gamma_p(1.0, x) - (1.0 - (-x).exp())).abs() < 1e-14, "x {x}");
        assert!((regularized_gamma_q(1.0, x) - (-x).exp()).abs() < 1e-14 * (-x).exp().max(1e-300), "x {x}");
    }
    assert!((regularized_gamma_p(0.5, 1.0) - 0.842_700_792_949_714_9).abs() < 1e-14);
    assert!((ln_gamma(0.5) - std::f64::consts::PI.sqrt().ln()).abs() < 1e-14);
    assert!((ln_gamma(10.0) - 362_880f64.ln()).abs() < 1e-13);
    assert!((ln_gamma(0.1) - 2.252_712_651_734_206).abs() < 1e-13);
    // Far tail: Q(10, 100) = e^-100 sum_{k<10} 100^k / k! (integer a), without cancellation.
    let mut tail = 0.0;
    let mut term = 1.0;
    for k in 0..10 {
        if k > 0 {
            term *= 100.0 / k as f64;
        }
        tail += term;
    }
    tail *= (-100.0f64).exp();
    assert!(rel(regularized_gamma_q(10.0, 100.0), tail).abs() < 1e-10);
    assert!(regularized_gamma_p(-1.0, 1.0).is_nan());
    assert!(regularized_gamma_p(1.0, -1.0).is_nan());
    assert_eq!(chi_square_cdf(-1.0, 3.0), 0.0);
    assert!(chi_square_cdf(1.0, 0.0).is_nan());
}

#[test]
fn ljung_box_accepts_white_noise_at_its_level_and_rejects_ar1() {
    let (n, h) = (1000, 20);
    let seeds = 200;
    let mut rejected = 0;
    let mut p_sum = 0.0;
    for seed in 0..seeds {
        let lb = ljung_box(&white(1000 + seed, n, 1.0), h).unwrap();
        assert_eq!((lb.lags, lb.degrees_of_freedom, lb.autocorrelation.len()), (h, h, h));
        p_sum += lb.p_value;
        if lb.p_value < 0.05 {
            rejected += 1;
        }
    }
    let rate = rejected as f64 / seeds as f64;
    println!(
        "Ljung-Box white: rejected at 5% in {rejected}/{seeds} = {:.1}%, mean p {:.3}",
        100.0 * rate,
        p_sum / 200.0
    );
    assert!((0.01..=0.12).contains(&rate));
    assert!(p_sum / seeds as f64 > 0.35);

    for seed in 0..5 {
        let w = white(2000 + seed, n, 1.0);
        let mut x = Vec::with_capacity(n);
        let mut s = 0.0;
        for wk in w {
            s = 0.5 * s + wk;
            x.push(s);
        }
        let lb = ljung_box(&x, h).unwrap();
        println!(
            "Ljung-Box AR(1) rho 0.5 seed {seed}: Q {:.1}, p {:.3e}, r1 {:.3}",
            lb.q_statistic, lb.p_value, lb.autocorrelation[0]
        );
        assert!(lb.p_value < 1e-10);
        assert!((lb.autocorrelation[0] - 0.5).abs() < 0.1);
    }

    assert!(ljung_box(&[], 5).is_err());
    assert!(ljung_box(&[1.0, 2.0, 3.0], 5).is_err());
    assert!(ljung_box(&[1.0; 50], 5).is_err());
    assert!(ljung_box(&white(1, 50, 1.0), 0).is_err());
    assert!(ljung_box(&white(1, 50, 1.0), usize::MAX).is_err());
}

// ---------------------------------------------------------------------------------------------------
// Quantization detection
// ---------------------------------------------------------------------------------------------------

#[test]
fn quantization_step_is_detected_on_quantized_noise_and_not_on_continuous_noise() {
    let q = 0.0125;
    let offset = 3.3;
    let g = white(11, 20_000, 5.0 * q);
    let quantized: Vec<f64> = g.iter().map(|v| offset + q * (v / q).round()).collect();
    let det = detect_quantization(&quantized).unwrap();
    println!("quantized noise (q = {q}): {det:?}");
    assert!(det.quantized);
    assert!(rel(det.step, q).abs() < 1e-9);
    assert!(det.fraction_on_grid > 0.999);
    assert!((det.rounding_noise_std() - q / 12f64.sqrt()).abs() < 1e-9 * q);

    let cont = detect_quantization(&g).unwrap();
    println!("continuous noise: {cont:?}");
    assert!(!cont.quantized);

    // Levels {0, 2q, 5q}: differences are 2q, 3q and 5q, never q; their common divisor is q.
    let mut rng = ChaCha8Rng::seed_from_u64(12);
    let levels = [0.0, 2.0 * q, 5.0 * q];
    let coarse: Vec<f64> = (0..5000).map(|_| levels[rng.random_range(0..3)]).collect();
    let det = detect_quantization(&coarse).unwrap();
    println!("levels 0, 2q, 5q: {det:?}");
    assert!(det.quantized);
    assert!(rel(det.step, q).abs() < 1e-9);

    assert!(detect_quantization(&[]).is_err());
    assert!(detect_quantization(&[1.0; 100]).is_err());
    assert!(detect_quantization(&[1.0, f64::NAN, 2.0]).is_err());
}
