//! The Ferraris session's held-out check (docs/method.md#on-measured-data): static intervals among the rows no
//! label names, and |f| - g on them under an accelerometer model `f_meas = T_a f + b_a`.

use sinscal_host::calibration::Calibration;
use sinscal_host::io::recording::Recording;
use sinscal_host::model::synth::{mul_vec, M3};
use sinscal_host::stats::solve::inverse3;

/// One held-out interval: its rows and its mean specific force, m/s^2.
pub struct Interval {
    /// First row and one past the last.
    pub rows: std::ops::Range<usize>,
    /// Mean accelerometer output, body, m/s^2.
    pub mean_force_b_mps2: [f64; 3],
}

/// The rests among the unlabelled rows, as the study finds them (`sinscal_host::study::rests::find_rests`: still
/// periods of at least 2 s holding neither a label nor a turn).
pub fn unlabelled_static_intervals(rec: &Recording) -> Vec<Interval> {
    sinscal_host::study::rests::find_rests(rec, true)
        .into_iter()
        .filter(|r| r.pos == 0)
        .map(|r| {
            let rows = &rec.rows[r.rows.clone()];
            let n = rows.len() as f64;
            let mean_force_b_mps2 = [0, 1, 2].map(|i| rows.iter().map(|x| x.force_b_mps2[i]).sum::<f64>() / n);
            Interval { rows: r.rows, mean_force_b_mps2 }
        })
        .collect()
}

/// The accelerometer model of a calibration: `T_a` (identity plus the scale factors and misalignments; absent or
/// undetermined terms add nothing) and `b_a`, m/s^2.
pub fn accelerometer_model(cal: &Calibration) -> (M3, [f64; 3]) {
    let v = |i: usize| cal.estimates.value_si[i].unwrap_or(0.0);
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
    (t, [v(3), v(4), v(5)])
}

/// `|T_a^-1 (f - b_a)| - g` of one mean force `f`, m/s^2.
pub fn calibrated_norm_error_mps2(t_a: &M3, b_a: [f64; 3], g_mps2: f64, f: [f64; 3]) -> f64 {
    let t_inv = inverse3(t_a).expect("T_a invertible");
    let c = mul_vec(&t_inv, [f[0] - b_a[0], f[1] - b_a[1], f[2] - b_a[2]]);
    (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]).sqrt() - g_mps2
}

/// RMS over the intervals of `|T_a^-1 (f - b_a)| - g`, m/s^2.
pub fn held_out_rms_mps2(t_a: &M3, b_a: [f64; 3], g_mps2: f64, intervals: &[Interval]) -> f64 {
    let sq: f64 =
        intervals.iter().map(|i| calibrated_norm_error_mps2(t_a, b_a, g_mps2, i.mean_force_b_mps2).powi(2)).sum();
    (sq / intervals.len() as f64).sqrt()
}
