//! One view of a calibration's parameters, whichever estimator made them: the core's parameter layout
//! (docs/formats.md#calibration-json-version-2), values and standard errors in SI units, the full covariance of
//! the determined parameters, and which parameters the schedule cannot determine.

use sinscal::calib::angles::{BiasSolution, Parameter};
use sinscal::calib::general::{
    parameter_name, AttitudeKnowledge, ChannelEstimator, ChannelSolution, Model, Term, PARAMETERS,
};

/// Which estimator made a calibration.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Method {
    /// The paper's: alignment angles per position (docs/method.md#step-5-schedule-and-solution).
    Angles,
    /// The general estimator: every channel of every dwell (docs/method.md#general-estimator).
    Channels,
}

impl Method {
    /// The name on the command line and in the JSON.
    pub fn name(self) -> &'static str {
        match self {
            Method::Angles => "angles",
            Method::Channels => "channels",
        }
    }
}

/// Parameters of a calibration in the core's layout.
#[derive(Clone, Debug, PartialEq)]
pub struct Estimates {
    /// The estimator.
    pub method: Method,
    /// The terms estimated.
    pub model: Model,
    /// Value of each parameter, SI; `None` when not in the model or not determined.
    pub value_si: [Option<f64>; PARAMETERS],
    /// Standard error of each parameter, SI; `None` likewise.
    pub std_si: [Option<f64>; PARAMETERS],
    /// Parameters in the model that the schedule cannot determine.
    pub unobservable: Vec<usize>,
    /// The determined parameters, in layout order.
    pub determined: Vec<usize>,
    /// Their covariance, SI, in the order of `determined`.
    pub covariance_si: Vec<Vec<f64>>,
    /// Sum of squared whitened residuals and its degrees of freedom.
    pub chi_square: f64,
    /// Degrees of freedom.
    pub degrees_of_freedom: u32,
    /// The factors the standard errors (and the covariance's square root) carry beyond the dwell noise, one per
    /// channel (gyro x, y, z, accelerometer x, y, z): `S = sqrt(chi_square / degrees_of_freedom)` of that
    /// channel's residuals when their chi-square is beyond its 95 % point, else 1 (docs/method.md#fit-scale). A
    /// parameter carries its channel's (a term's row axis: axis i's bias, scale factor, misalignments and
    /// g-sensitivities), the reference offset the largest. The angle method's are 1.
    pub std_scale: [f64; 6],
}

impl Estimates {
    /// From the general estimator's solution.
    pub fn from_channels(s: &ChannelSolution) -> Estimates {
        let mut e = Estimates::empty(Method::Channels, s.model, s.chi_square as f64, s.degrees_of_freedom);
        for i in 0..PARAMETERS {
            if let Some((v, sd)) = s.estimate(i) {
                e.value_si[i] = Some(v as f64);
                e.std_si[i] = Some(sd as f64);
                e.determined.push(i);
            } else if s.unobservable & (1 << i) != 0 {
                e.unobservable.push(i);
            }
        }
        e.covariance_si = e
            .determined
            .iter()
            .map(|&i| e.determined.iter().map(|&j| s.covariance_si[i][j] as f64).collect())
            .collect();
        e
    }

    /// From the general estimator's solution of `estimator`'s dwells (those not in `excluded`), with the fit
    /// scale of each sensor (docs/method.md#fit-scale).
    pub fn from_session(estimator: &ChannelEstimator, s: &ChannelSolution, excluded: u64) -> Estimates {
        let mut e = Estimates::from_channels(s);
        let use_gyro = estimator.settings().use_gyro;
        // Per channel: chi-square, rows, and what the parameters and nuisances take of them (fractions where a
        // parameter or a nuisance angle is shared: an estimated heading by the three gyros, a tilt by the three
        // accelerometers, the reference offset by every channel).
        let (mut chi, mut rows, mut taken) = ([0.0f64; 6], [0.0f64; 6], [0.0f64; 6]);
        let prior_tilt = estimator.settings().pose_tolerance_rad > 0.0 && s.attitude == AttitudeKnowledge::Reference;
        for (k, d) in estimator.dwells().iter().enumerate().take(s.dwells) {
            if k < 64 && excluded & (1 << k) != 0 {
                continue;
            }
            for i in 0..3 {
                if use_gyro {
                    chi[i] += (s.residual_rate_b_radps[k][i] as f64).powi(2) / d.rate_mean_var_b_radps2[i] as f64;
                    rows[i] += 1.0;
                    // An estimated heading (a free one: a prior row pays for its own) is the gyros' to determine.
                    if s.heading_std_rad[k] > 0.0 && d.heading_rad.is_none() {
                        taken[i] += 1.0 / 3.0;
                    }
                }
                chi[3 + i] += (s.residual_force_b_mps2[k][i] as f64).powi(2) / d.force_mean_var_b_mps2sq[i] as f64;
                rows[3 + i] += 1.0;
                // An estimated tilt is the accelerometers' (a tilt known to a tolerance pays with its prior row).
                if s.attitude == AttitudeKnowledge::Unknown && !prior_tilt {
                    taken[3 + i] += 2.0 / 3.0;
                }
            }
        }
        // The moves are gyro rows too.
        for k in 0..s.moves.min(s.move_rows.len()) {
            if s.move_rows[k] > 0 && s.move_statistic[k] >= 0.0 {
                for i in 0..3 {
                    chi[i] += s.move_statistic[k] as f64 / 3.0;
                    rows[i] += f64::from(s.move_rows[k]) / 3.0;
                }
            }
        }
        // The completion's parameters (docs/method.md#observability) take their freedom too.
        let completion = (0..PARAMETERS).filter(|&i| s.completion & (1 << i) != 0);
        for i in e.determined.iter().copied().chain(completion) {
            match channel_of(i) {
                Some(ch) => taken[ch] += 1.0,
                None => {
                    let first = if use_gyro { 0 } else { 3 };
                    for t in taken.iter_mut().skip(first) {
                        *t += 1.0 / (6 - first) as f64;
                    }
                }
            }
        }
        e.std_scale = core::array::from_fn(|g| {
            let dof = rows[g] - taken[g];
            if dof < 0.5 || !chi[g].is_finite() {
                return 1.0;
            }
            // Only a chi-square beyond its 95 % point says the sensor's dwell means scatter more than their noise:
            // below it, a ratio above 1 is the noise's own fluctuation and scaling by it would overstate errors.
            let p_value = 1.0 - crate::stats::noise::chi_square_cdf(chi[g], dof);
            if p_value < FIT_SCALE_LEVEL {
                (chi[g] / dof).sqrt()
            } else {
                1.0
            }
        });
        e.apply_scale();
        e
    }

    /// Multiplies the covariance by the scales (entry `(i, j)` by `S(i) S(j)`) and takes each standard error as
    /// the square root of its entry, in f32 as the core's values are: every number written stays an f32.
    fn apply_scale(&mut self) {
        if self.std_scale == [1.0; 6] {
            return;
        }
        let largest = self.std_scale.iter().fold(1.0f64, |m, s| m.max(*s));
        let scale: Vec<f64> =
            self.determined.iter().map(|&i| channel_of(i).map_or(largest, |ch| self.std_scale[ch])).collect();
        for (a, row) in self.covariance_si.iter_mut().enumerate() {
            for (b, c) in row.iter_mut().enumerate() {
                *c = (*c as f32 * (scale[a] * scale[b]) as f32) as f64;
            }
        }
        for (k, &i) in self.determined.iter().enumerate() {
            self.std_si[i] = Some((self.covariance_si[k][k] as f32).max(0.0).sqrt() as f64);
        }
    }

    /// From the angle method's solution: gyro and accelerometer biases, and the reference offset when it was
    /// estimated.
    pub fn from_angles(s: &BiasSolution) -> Estimates {
        let mut model = Model::BIASES;
        if s.reference_offset_estimated {
            model = model.with(Term::ReferenceOffset);
        }
        let mut e = Estimates::empty(Method::Angles, model, s.chi_square as f64, s.degrees_of_freedom);
        // The angle solver's order (gyro 0-2, accelerometer 3-5, offset 6-8) in the core's layout.
        let offset_first = Term::ReferenceOffset.parameters().0;
        let layout = |k: usize| if k < 6 { k } else { offset_first + (k - 6) };
        let mut solver_index = Vec::new();
        for (k, p) in Parameter::ALL.iter().enumerate() {
            let i = layout(k);
            match s.get(*p) {
                Some(est) => {
                    e.value_si[i] = Some(est.value as f64);
                    e.std_si[i] = Some(est.std_error as f64);
                    e.determined.push(i);
                    solver_index.push(k);
                }
                None if s.is_unobservable(*p) => e.unobservable.push(i),
                None => {}
            }
        }
        e.covariance_si = solver_index
            .iter()
            .map(|&a| solver_index.iter().map(|&b| s.covariance_si[a][b] as f64).collect())
            .collect();
        e
    }

    fn empty(method: Method, model: Model, chi_square: f64, degrees_of_freedom: u32) -> Estimates {
        Estimates {
            method,
            model,
            value_si: [None; PARAMETERS],
            std_si: [None; PARAMETERS],
            unobservable: Vec::new(),
            determined: Vec::new(),
            covariance_si: Vec::new(),
            chi_square,
            degrees_of_freedom,
            std_scale: [1.0; 6],
        }
    }

    /// Names of the unobservable parameters.
    pub fn unobservable_names(&self) -> Vec<&'static str> {
        self.unobservable.iter().map(|&i| parameter_name(i)).collect()
    }

    /// Names of the determined parameters.
    pub fn determined_names(&self) -> Vec<&'static str> {
        self.determined.iter().map(|&i| parameter_name(i)).collect()
    }

    /// The model's term names.
    pub fn model_names(&self) -> Vec<&'static str> {
        Term::ALL.iter().filter(|t| self.model.contains(**t)).map(|t| t.name()).collect()
    }
}

/// The significance level below which a sensor's chi-square scales its terms' errors (docs/method.md#fit-scale).
pub const FIT_SCALE_LEVEL: f64 = 0.05;

/// 0 for a gyro term's parameter, 1 for the accelerometers' and the reference offset's (seen through the tilt).
/// The channel (gyro x, y, z, accelerometer x, y, z) whose residuals a parameter answers to: the row axis of its
/// term (axis i's bias, scale factor, misalignments, g-sensitivities); `None` for the reference offset, which
/// every channel sees.
fn channel_of(index: usize) -> Option<usize> {
    Term::ALL.iter().find_map(|t| {
        let (first, count) = t.parameters();
        if !(first..first + count).contains(&index) {
            return None;
        }
        let k = index - first;
        let axis = match t.info().axes {
            sinscal::calib::general::Axes::Body => k,
            sinscal::calib::general::Axes::OffDiagonal => k / 2,
            sinscal::calib::general::Axes::Matrix => k / 3,
            sinscal::calib::general::Axes::Navigation => return None,
        };
        Some(if t.is_gyro() { axis } else { 3 + axis })
    })
}

/// Parses `--model`: `biases`, `full`, or a comma list of term names. `position_error` is analyze's.
pub fn parse_model(text: &str) -> Result<Model, String> {
    match text.trim() {
        "biases" => return Ok(Model::BIASES),
        "full" => return Ok(Model::FULL),
        _ => {}
    }
    let mut model = Model::EMPTY;
    for name in text.split(',').map(str::trim) {
        if name == "biases" || name == "full" {
            let preset = if name == "biases" { Model::BIASES } else { Model::FULL };
            model = Term::ALL.iter().filter(|t| preset.contains(**t)).fold(model, |m, t| m.with(*t));
            continue;
        }
        if name == "position_error" {
            return Err("position_error: per-position attitude errors are found by `sinscal analyze`; calibrate \
                        estimates the constant reference_offset"
                .to_string());
        }
        let term = Term::ALL.iter().find(|t| t.name() == name).ok_or_else(|| {
            let known: Vec<&str> = Term::ALL.iter().map(|t| t.name()).collect();
            format!("unknown model term '{name}' (known: {}, or the presets biases, full)", known.join(", "))
        })?;
        if model.contains(*term) {
            return Err(format!("model term '{name}' is given twice"));
        }
        model = model.with(*term);
    }
    Ok(model)
}
