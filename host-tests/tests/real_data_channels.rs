//! The general estimator on measured data (`SINSCAL_DATA`): the imucal Ferraris session, judged on static
//! intervals that no fit used.
//!
//! The session's six labelled poses are hand-placed, headings unknown, gyros MEMS. Between and around them the
//! sensor also rests in places the labels do not name. Those intervals are the held-out check: with the
//! accelerometer calibration applied (f = T_a^-1 (f_meas - b_a)), |f| must equal g there.

mod common;

use sinscal::calib::channels::{Model, Term};
use sinscal_host::calibration::{calibrate, site_of, Calibration, Options, PrefilterKind};
use sinscal_host::io::import::import_imucal;
use sinscal_host::io::recording::Recording;
use sinscal_host::model::synth::{mul_vec, M3};
use sinscal_host::stats::solve::inverse3;

/// Static intervals among the unlabelled rows: windows of 1 s where every accelerometer axis varies by less
/// than 0.05 m/s^2 (standard deviation) and the gyros read below 0.05 rad/s, merged; the mean specific force of
/// each interval of at least 2 s.
fn unlabelled_static_means(rec: &Recording, rate_hz: f64) -> Vec<[f64; 3]> {
    let window = rate_hz.round() as usize;
    let mut flags = vec![false; rec.rows.len()];
    let mut start = 0;
    while start + window <= rec.rows.len() {
        let rows = &rec.rows[start..start + window];
        let unlabelled = rows.iter().all(|r| r.pos == 0);
        let mut ok = unlabelled;
        for axis in 0..3 {
            let m = rows.iter().map(|r| r.force_b_mps2[axis]).sum::<f64>() / window as f64;
            let v = rows.iter().map(|r| (r.force_b_mps2[axis] - m).powi(2)).sum::<f64>() / window as f64;
            ok &= v.sqrt() < 0.05;
            ok &= rows.iter().all(|r| r.rate_b_radps[axis].abs() < 0.05);
        }
        if ok {
            flags[start..start + window].iter_mut().for_each(|f| *f = true);
        }
        start += window / 4;
    }
    let mut means = Vec::new();
    let mut k = 0;
    while k < flags.len() {
        if !flags[k] {
            k += 1;
            continue;
        }
        let begin = k;
        while k < flags.len() && flags[k] {
            k += 1;
        }
        if k - begin >= 2 * window {
            let rows = &rec.rows[begin..k];
            let n = rows.len() as f64;
            means.push([0, 1, 2].map(|i| rows.iter().map(|r| r.force_b_mps2[i]).sum::<f64>() / n));
        }
    }
    means
}

/// RMS over the intervals of |T_a^-1 (f - b_a)| - g, with the terms of a calibration (absent or undetermined
/// terms: identity and zero).
fn held_out_rms(cal: &Calibration, means: &[[f64; 3]]) -> f64 {
    let e = &cal.estimates;
    let v = |i: usize| e.value_si[i].unwrap_or(0.0);
    let mut t: M3 = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    let mut k = 9;
    for (i, row) in t.iter_mut().enumerate() {
        row[i] += v(6 + i);
        for (j, cell) in row.iter_mut().enumerate() {
            if i != j {
                *cell += v(k);
                k += 1;
            }
        }
    }
    let t_inv = inverse3(&t).expect("T_a invertible");
    let g = cal.site.gravity_mps2 as f64;
    let sq: f64 = means
        .iter()
        .map(|m| {
            let f = mul_vec(&t_inv, [m[0] - v(3), m[1] - v(4), m[2] - v(5)]);
            let d = (f[0] * f[0] + f[1] * f[1] + f[2] * f[2]).sqrt() - g;
            d * d
        })
        .sum();
    (sq / means.len() as f64).sqrt()
}

#[test]
fn ferraris_held_out_static_intervals() {
    let Some(dir) = common::data_dir() else { return };
    let csv = common::data_file(&dir, "imucal-ferraris/example_ferraris_session.csv");
    let labels = common::data_file(&dir, "imucal-ferraris/example_ferraris_session_list.json");
    let rec = import_imucal(&csv, &labels, None).expect("import").recording;
    let means = unlabelled_static_means(&rec, 102.4);
    println!("Ferraris session: {} unlabelled static intervals (held out)", means.len());
    assert!(means.len() >= 5, "the session rests between its turns: {} intervals found", means.len());
    // The gravity every calibration below uses: WGS-84 normal gravity at the session's latitude.
    let g = site_of(&rec.header).0.gravity_mps2 as f64;
    let raw = (means.iter().map(|m| ((m[0] * m[0] + m[1] * m[1] + m[2] * m[2]).sqrt() - g).powi(2)).sum::<f64>()
        / means.len() as f64)
        .sqrt();
    println!("{:<60} RMS |f| - g on the held-out intervals", "model");
    println!("{:<60} {raw:.4} m/s^2", "none (raw data)");
    let models = [
        ("biases (default without scale factors)", Model::BIASES),
        ("biases, accel_scale_factor (the default)", Model::BIASES.with(Term::AccelScaleFactor)),
        (
            "biases, accel_scale_factor, accel_misalignment",
            Model::BIASES.with(Term::AccelScaleFactor).with(Term::AccelMisalignment),
        ),
    ];
    let mut rms = Vec::new();
    for (name, model) in models {
        for prefilter in [PrefilterKind::HmmKf, PrefilterKind::None] {
            let cal = calibrate(&rec, &Options { model, prefilter, ..Options::default() }).expect("calibrate");
            let r = held_out_rms(&cal, &means);
            println!("{name:<50} {:<9} {r:.4} m/s^2", format!("{prefilter:?}"));
            rms.push(r);
        }
    }
    // What the data show: this MEMS needs its scale factors (the default model), which bring the held-out
    // |f| - g down 40-fold from the raw data and 9-fold from biases alone. The misalignments do not change |f|
    // on these faces. The residual 0.015 m/s^2 is the difference between the labelled poses and later rests on
    // the same faces (docs/method.md#on-measured-data), not a fit error: the Ferraris
    // formulas (unweighted pair differences) give 0.014 on these poses.
    assert!(rms[2] < raw / 30.0, "scale factors: {:.4} vs raw {raw:.4}", rms[2]);
    assert!(rms[2] < rms[0] / 5.0, "scale factors: {:.4} vs biases only {:.4}", rms[2], rms[0]);
}
