//! The fit scale (docs/method.md#fit-scale): a sensor whose dwell means scatter more than their own noise says gets
//! its standard errors scaled by its channels' sqrt(chi-square / degrees of freedom); the other sensor's are not
//! touched. SIMULATION: the built-in example, then the same with a slow accelerometer x wander added dwell by dwell.

use sinscal_host::calibration::{calibrate, Options};
use sinscal_host::model::synth::Scenario;

#[test]
fn slow_noise_of_one_sensor_scales_that_sensors_errors_only() {
    let rec = Scenario { dwell_s: 60.0, ..Scenario::example() }.recording(7, "example.csv");
    let clean = calibrate(&rec, &Options::default()).unwrap();
    // White noise: each sensor's chi-square is about its degrees of freedom; a scale, if any, stays small.
    assert!(clean.estimates.std_scale.iter().all(|s| (1.0..2.0).contains(s)), "{:?}", clean.estimates.std_scale);
    // A wander of accelerometer x, constant within a dwell and different between dwells (+-20 times a dwell
    // mean's standard error): invisible within the dwells, plain in the fit.
    let sigma_mean = clean.estimates.std_si[3].unwrap();
    let mut wandering = rec.clone();
    for row in wandering.rows.iter_mut().filter(|r| r.pos > 0) {
        row.force_b_mps2[0] += 20.0 * sigma_mean * if row.pos % 2 == 0 { 1.0 } else { -1.0 } * (row.pos as f64 / 3.0);
    }
    let scaled = calibrate(&wandering, &Options::default()).unwrap();
    let [gyro, accel] = scaled.estimates.std_scale;
    println!("std_scale: clean {:?}, with the wander gyro {gyro:.3}, accel {accel:.3}", clean.estimates.std_scale);
    assert_eq!(gyro, clean.estimates.std_scale[0], "the gyros' scale does not move");
    assert!(accel > 5.0, "accelerometer scale {accel}");
    // The accelerometer errors grow by that factor, the gyro errors not at all.
    let ratio = |i: usize| scaled.estimates.std_si[i].unwrap() / clean.estimates.std_si[i].unwrap();
    assert!((ratio(0) - 1.0).abs() < 1e-3, "gyro x std ratio {}", ratio(0));
    let want = accel / clean.estimates.std_scale[1];
    assert!((ratio(3) / want - 1.0).abs() < 0.05, "accel x std ratio {} vs scale {want}", ratio(3));
}
