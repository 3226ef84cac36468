//! The static sensor-error model, written once (docs/conventions.md#sensor-model):
//!
//! ```text
//! w_meas = T_g w + b_g + G f        f_meas = T_a f + b_a        T = I + S + M
//! ```
//!
//! with `S` diagonal (scale factors), `M` off-diagonal (misalignments: row i, column j is axis i's
//! sensitivity along j) and `G` the gyro g-sensitivity. [`Triad`] is one triad's static terms and what it
//! measures; [`Term`] is one proportional parameter of the model (a scale factor, a misalignment or a
//! g-sensitivity) with the column it adds to a linear fit: the measurement's derivative by the parameter.
//! The simulator measures through [`Triad`]; the analysis fits the columns of [`Term`].

use crate::model::catalogue::{EffectKind, Sensor};
use crate::model::synth::M3;

/// One triad's static error terms: `meas = gain own + bias + cross other`, where `own` is the true
/// quantity the triad senses (rate for gyros, specific force for accelerometers) and `other` is the other
/// triad's (specific force for the gyros' g-sensitivity; unused, zero, for accelerometers).
#[derive(Clone, Debug, PartialEq)]
pub struct Triad {
    /// `b`, in the unit of the measurement.
    pub bias: [f64; 3],
    /// `T = I + S + M`, dimensionless.
    pub gain: M3,
    /// `G`, measurement unit per unit of `other`.
    pub cross: M3,
}

impl Triad {
    /// The triad with biases `bias`, scale factors `scale_factor` (the diagonal of `S`), misalignments
    /// `misalignment` (its diagonal is ignored: scale factors live in `scale_factor`) and cross-coupling
    /// `cross`.
    pub fn new(bias: [f64; 3], scale_factor: [f64; 3], misalignment: &M3, cross: M3) -> Triad {
        let mut gain = *misalignment;
        for i in 0..3 {
            gain[i][i] = 1.0 + scale_factor[i];
        }
        Triad { bias, gain, cross }
    }

    /// Axis `i` of the measurement: `b_i + sum_j (T_ij own_j + G_ij other_j)`, summed in that order.
    pub fn measure_axis(&self, i: usize, own: [f64; 3], other: [f64; 3]) -> f64 {
        let mut y = self.bias[i];
        for j in 0..3 {
            y += self.gain[i][j] * own[j] + self.cross[i][j] * other[j];
        }
        y
    }

    /// The measurement of all three axes.
    pub fn measure(&self, own: [f64; 3], other: [f64; 3]) -> [f64; 3] {
        [0, 1, 2].map(|i| self.measure_axis(i, own, other))
    }
}

/// One proportional parameter of the model: an entry of the catalogue (a scale factor, a misalignment or a
/// gyro g-sensitivity) at output axis `axis`, which sees `parameter * source[along]`, where `source` is the true
/// body rate (the gyros' scale factors and misalignments) or the true specific force (accelerometer terms and
/// the gyros' g-sensitivity).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Term {
    /// The catalogue entry: one of [`Term::EFFECTS`].
    pub effect: EffectKind,
    /// The output axis, 0..2.
    pub axis: usize,
    /// The axis of the source quantity, 0..2 (equal to `axis` for a scale factor).
    pub along: usize,
}

impl Term {
    /// The catalogue entries that are proportional terms of the sensor model, in the order of [`Term::all`].
    pub const EFFECTS: [EffectKind; 5] = [
        EffectKind::AccelScaleFactor,
        EffectKind::AccelMisalignment,
        EffectKind::GyroScaleFactor,
        EffectKind::GyroMisalignment,
        EffectKind::GyroGSensitivity,
    ];

    /// Every proportional term: the accelerometer scale factors and misalignments, and, with `gyros`, the
    /// gyro scale factors, misalignments and g-sensitivity, in that order (axis by axis, `along` inner).
    pub fn all(gyros: bool) -> Vec<Term> {
        let effects = if gyros { &Term::EFFECTS[..] } else { &Term::EFFECTS[..2] };
        let mut terms = Vec::new();
        for &effect in effects {
            for (axis, along) in (0..3).flat_map(|i| (0..3).map(move |j| (i, j))) {
                let present = match effect {
                    EffectKind::AccelScaleFactor | EffectKind::GyroScaleFactor => along == axis,
                    EffectKind::GyroGSensitivity => true,
                    _ => along != axis,
                };
                if present {
                    terms.push(Term { effect, axis, along });
                }
            }
        }
        terms
    }

    /// The triad whose output the term enters.
    pub fn sensor(&self) -> Sensor {
        self.effect.sensor().unwrap_or(Sensor::Accel)
    }

    /// The output channel the term enters: gyros 0..2, accelerometers 3..5.
    pub fn channel(&self) -> usize {
        match self.sensor() {
            Sensor::Gyro => self.axis,
            _ => 3 + self.axis,
        }
    }

    /// Whether the source quantity is the specific force (else the rate).
    pub fn from_force(&self) -> bool {
        self.sensor() != Sensor::Gyro || self.effect == EffectKind::GyroGSensitivity
    }

    /// The output error per unit parameter at true body rate `rate_b_radps` and specific force
    /// `force_b_mps2`: the term's column in a linear fit.
    pub fn per_unit(&self, rate_b_radps: [f64; 3], force_b_mps2: [f64; 3]) -> f64 {
        if self.from_force() {
            force_b_mps2[self.along]
        } else {
            rate_b_radps[self.along]
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One catalogue: every term the analysis tests is a parameter of the calibration estimator
    /// (`sinscal calibrate --model`) of the same name, whose output error in the core's sensor model is the
    /// term's column, sign included.
    #[test]
    fn analysis_terms_are_the_calibration_estimators_parameters() {
        use sinscal::calib::general::{g_sensitivity_radps_per_mps2, parameter_name, sensor_matrix, PARAMETERS};
        let (rate, force) = ([0.3f32, -1.2, 2.5], [-4.0f32, 1.5, 9.0]);
        let axes = ["x", "y", "z"];
        for term in Term::all(true) {
            let name = match term.effect {
                EffectKind::AccelScaleFactor | EffectKind::GyroScaleFactor => {
                    format!("{}_{}", term.effect, axes[term.axis])
                }
                _ => format!("{}_{}{}", term.effect, axes[term.axis], axes[term.along]),
            };
            let index = (0..PARAMETERS).find(|&i| parameter_name(i) == name).unwrap_or_else(|| panic!("{name}"));
            let mut theta = [0.0f32; PARAMETERS];
            theta[index] = 1.0;
            // The core's output error: (T - I) source for the scale and misalignment terms (accelerometer
            // T from index 6 and 9, gyro from 15 and 18), G f for the g-sensitivity.
            let error: [f32; 3] = match term.effect {
                EffectKind::GyroGSensitivity => g_sensitivity_radps_per_mps2(&theta).mul_vec(force),
                EffectKind::AccelScaleFactor | EffectKind::AccelMisalignment => {
                    let t = sensor_matrix(&theta, 6, 9).mul_vec(force);
                    std::array::from_fn(|i| t[i] - force[i])
                }
                _ => {
                    let t = sensor_matrix(&theta, 15, 18).mul_vec(rate);
                    std::array::from_fn(|i| t[i] - rate[i])
                }
            };
            let column = term.per_unit(rate.map(f64::from), force.map(f64::from));
            for (i, e) in error.iter().enumerate() {
                let want = if i == term.axis { column } else { 0.0 };
                assert!((*e as f64 - want).abs() < 1e-6, "{name}: axis {i}: core {e}, analysis {want}");
            }
        }
    }

    /// The columns of the terms are the derivatives of the triads' measurements, with the gain and cross
    /// matrices written out independently of [`Term`].
    #[test]
    fn term_columns_are_the_derivatives_of_the_measurement() {
        let (rate, force) = ([0.3, -1.2, 2.5], [-4.0, 1.5, 9.0]);
        for term in Term::all(true) {
            let h = 1e-3;
            let mut m = [[0.0; 3]; 3];
            let (mut scale, mut cross) = ([0.0; 3], [[0.0; 3]; 3]);
            match term.effect {
                EffectKind::AccelScaleFactor | EffectKind::GyroScaleFactor => scale[term.axis] = h,
                EffectKind::GyroGSensitivity => cross[term.axis][term.along] = h,
                _ => m[term.axis][term.along] = h,
            }
            let triad = Triad::new([0.0; 3], scale, &m, cross);
            let (own, other) = if term.sensor() == Sensor::Gyro { (rate, force) } else { (force, [0.0; 3]) };
            let base = Triad::new([0.0; 3], [0.0; 3], &[[0.0; 3]; 3], [[0.0; 3]; 3]).measure(own, other);
            let moved = triad.measure(own, other);
            for i in 0..3 {
                let expected = if i == term.axis { term.per_unit(rate, force) * h } else { 0.0 };
                assert!((moved[i] - base[i] - expected).abs() < 1e-12, "{term:?} axis {i}");
            }
        }
        assert_eq!(Term::all(false).len(), 9);
        assert_eq!(Term::all(true).len(), 9 + 9 + 9);
    }

    #[test]
    fn measurement_is_gain_times_truth_plus_bias_plus_cross() {
        let mut m = [[0.0; 3]; 3];
        m[0][1] = 2e-3; // x senses 0.002 of y
        let mut g = [[0.0; 3]; 3];
        g[2][2] = 1e-4;
        let t = Triad::new([0.1, -0.2, 0.3], [1e-3, 0.0, -2e-3], &m, g);
        let y = t.measure([1.0, 2.0, 3.0], [0.0, 0.0, 10.0]);
        assert!((y[0] - (0.1 + 1.001 * 1.0 + 0.002 * 2.0)).abs() < 1e-15);
        assert!((y[1] - (-0.2 + 2.0)).abs() < 1e-15);
        assert!((y[2] - (0.3 + 0.998 * 3.0 + 1e-4 * 10.0)).abs() < 1e-15);
    }
}
