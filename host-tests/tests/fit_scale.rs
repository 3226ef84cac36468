//! The fit scale (docs/method.md#fit-scale): a channel whose dwell means scatter more than their own noise says gets
//! its terms' standard errors scaled by its sqrt(chi-square / degrees of freedom); the other channels' are not
//! touched. SIMULATION: the built-in example, then the same with a slow accelerometer x wander added dwell by dwell.

use sinscal_host::calibration::{calibrate, Options};
use sinscal_host::model::synth::Scenario;

#[test]
fn slow_noise_of_one_sensor_scales_that_sensors_errors_only() {
    let rec = Scenario { dwell_s: 60.0, ..Scenario::example() }.recording(7, "example.csv");
    let clean = calibrate(&rec, &Options::default()).unwrap();
    // White noise, and the example's turntable offset (3 and -2 arcsec of tilt, not in the default model: about
    // one dwell-mean standard error on the horizontal accelerometers): a channel's scale, if any, stays small.
    assert!(clean.estimates.std_scale.iter().all(|s| (1.0..2.5).contains(s)), "{:?}", clean.estimates.std_scale);
    // A wander of accelerometer x, constant within a dwell and different between dwells (+-20 times a dwell
    // mean's standard error): invisible within the dwells, plain in the fit.
    let sigma_mean = clean.estimates.std_si[3].unwrap();
    let mut wandering = rec.clone();
    for row in wandering.rows.iter_mut().filter(|r| r.pos > 0) {
        row.force_b_mps2[0] += 20.0 * sigma_mean * if row.pos % 2 == 0 { 1.0 } else { -1.0 } * (row.pos as f64 / 3.0);
    }
    let scaled = calibrate(&wandering, &Options::default()).unwrap();
    let (s, c) = (scaled.estimates.std_scale, clean.estimates.std_scale);
    println!("fit scale per channel: clean {c:?}, with the wander {s:?}");
    // Only accelerometer x's scale moves: the gyros' and the other accelerometers' stay.
    for ch in [0, 1, 2, 4, 5] {
        assert_eq!(s[ch], c[ch], "channel {ch}: {s:?} vs {c:?}");
    }
    assert!(s[3] > 5.0, "accelerometer x scale {}", s[3]);
    // Accelerometer x's bias error grows by that factor; the gyro and the other accelerometer biases' not at all.
    let ratio = |i: usize| scaled.estimates.std_si[i].unwrap() / clean.estimates.std_si[i].unwrap();
    for i in [0, 1, 2, 4, 5] {
        assert!((ratio(i) - 1.0).abs() < 1e-3, "parameter {i}: std ratio {}", ratio(i));
    }
    let want = s[3] / c[3];
    assert!((ratio(3) / want - 1.0).abs() < 0.05, "accel x std ratio {} vs scale {want}", ratio(3));
}
