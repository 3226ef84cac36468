//! The quickest real check, an x-up / x-down pair with unknown headings, cut from measured data (`SINSCAL_DATA`):
//! the imucal Ferraris session's poses x_p (body x up) and x_a (body x down), a consumer MEMS IMU.
//!
//! From the pair the general estimator must give what the pair's closed form gives: the x accelerometer's bias
//! `(f_up + f_down) / 2` and scale factor `(f_up - f_down) / (2 g) - 1`, and the x gyro's bias
//! `(w_up + w_down) / 2` (the Earth rate's `+-W sin L` cancels). The x gyro's scale factor rests on `+-W sin L`
//! (11 deg/h here): it is determined by the schedule, and on this consumer gyro, imprecise, which its standard
//! error must say.

mod common;

use sinscal::calib::general::{parameter_name, Model, Term};
use sinscal_host::calibration::{calibrate, site_of, Options, PrefilterKind};
use sinscal_host::io::recording::Recording;

/// Mean of channel `f` over the rows of dwell `pos`.
fn mean(rec: &Recording, pos: u32, f: impl Fn(&sinscal_host::io::recording::Row) -> f64) -> f64 {
    let rows: Vec<_> = rec.rows.iter().filter(|r| r.pos == pos).collect();
    rows.iter().map(|r| f(r)).sum::<f64>() / rows.len() as f64
}

#[test]
fn ferraris_x_up_x_down_pair_with_unknown_headings() {
    let Some(dir) = common::data_dir() else { return };
    let session = common::ferraris_session(&dir);
    // x_p is pos 1 (roll -90: body x up), x_a pos 2 (roll 90: body x down); the headings are left unknown.
    let mut pair = session.clone();
    pair.rows.retain(|r| r.pos == 1 || r.pos == 2);
    pair.rows.iter_mut().for_each(|r| r.heading_deg = None);
    let model = Model::BIASES.with(Term::AccelScaleFactor).with(Term::GyroScaleFactor);
    // The closed form takes the labels as exact attitudes (tolerance 0, not the importer's 1 deg).
    let options =
        Options { model, prefilter: PrefilterKind::None, pose_tolerance_deg: Some(0.0), ..Options::default() };
    let cal = calibrate(&pair, &options).expect("the pair calibrates");
    let e = &cal.estimates;
    let g = site_of(&pair.header).0.gravity_mps2 as f64;
    let (f_up, f_down) = (mean(&pair, 1, |r| r.force_b_mps2[0]), mean(&pair, 2, |r| r.force_b_mps2[0]));
    let (w_up, w_down) = (mean(&pair, 1, |r| r.rate_b_radps[0]), mean(&pair, 2, |r| r.rate_b_radps[0]));
    let closed = [(3, (f_up + f_down) / 2.0), (6, (f_up - f_down) / (2.0 * g) - 1.0), (0, (w_up + w_down) / 2.0)];
    println!("Ferraris x-up / x-down pair, headings unknown ({} rows)", pair.rows.len());
    println!("{:<24} {:>14} {:>12} {:>14}", "parameter", "estimate", "std", "closed form");
    for (i, want) in closed {
        let (value, std) = (e.value_si[i].expect("determined"), e.std_si[i].expect("determined"));
        println!("{:<24} {value:>14.6e} {std:>12.3e} {want:>14.6e}", parameter_name(i));
        // The closed form is the estimator's solution for the x channel of the pair; they differ by the f32
        // rounding of the dwell means only (2^-23 of g is 1.2e-6 m/s^2).
        let tolerance = 1e-5 * want.abs().max(if i == 0 { 1e-3 } else { 1.0 });
        assert!((value - want).abs() < tolerance, "{}: {value:e} vs {want:e}", parameter_name(i));
    }
    // The x gyro's scale factor: determined by the schedule (the input is +-W sin L, above 5 % of full scale),
    // and imprecise here: the standard error exceeds 10 %, and the estimate is within 3 of them of zero.
    let (sf, sf_std) = (e.value_si[15].expect("determined"), e.std_si[15].expect("determined"));
    println!("{:<24} {sf:>14.3e} {sf_std:>12.3e} (from +-W sin L on a MEMS gyro)", parameter_name(15));
    assert!(sf_std > 0.1 && sf.abs() < 3.0 * sf_std, "gyro x scale factor {sf} +- {sf_std}");
    // A consumer accelerometer's scale factor is within a per cent.
    let sf_x = e.value_si[6].expect("determined");
    assert!(sf_x.abs() < 0.01, "accelerometer x scale factor {sf_x}");
}
