//! The checks of a calibration that fail loudly (docs/cli.md#checks): `physics` (gravity and the Earth
//! rate against the recording's labels and units, before the fit), `fit` (the model against the dwell noise),
//! `convergence` and `plausibility` (every estimate and standard error finite and within its term's plausible
//! magnitude), and `spikes` (the spike gate left out isolated samples only). Each is run on every calibration
//! and listed, passed or failed, in the JSON's `checks`; a failed one makes `calibrate` (and `apply`, reading
//! such a result) exit with status 3.

use serde::Serialize;
use serde_json::Value;
use sinscal::calib::dwell::{pool_mean_noise, DwellSummary};
use sinscal::calib::general::{implausible_parameter, parameter_name, Term, PARAMETERS, PLAUSIBLE_MAGNITUDE_SI};
use sinscal::nav::earth::Site;
use sinscal::nav::frames::Attitude;

use crate::calibration::{gyros_resolve_earth_rate, Calibration, Estimates};
use crate::io::import::gyro_units::{median_rest_rate_radps, MAX_REST_RATE_RADPS};
use crate::io::recording::shown;
use crate::io::recording::DwellAttitude;

/// The level below which a chi-square's p-value says the model misfits the data.
pub const MISFIT_LEVEL: f64 = 1e-3;

/// How many times smaller an alternative hypothesis's chi-square must be than the stated labels' for the
/// physics check to name it.
pub const ALTERNATIVE_FACTOR: f64 = 10.0;

/// Largest relative difference of a dwell's |f| from g the physics check accepts: the core's limit for any
/// accelerometer, raw ones included (an uncalibrated MEMS triad with biases of 0.1 g reads |f| 11 % from g).
pub const GRAVITY_TOLERANCE: f64 = sinscal::calib::limits::FORCE_MAGNITUDE_ERROR_MAX_RELATIVE as f64;

/// Floor of the standard error of a dwell's gyro mean, rad/s (0.001 deg/h): noise-free simulations still weigh.
const GYRO_MEAN_STD_FLOOR_RADPS: f64 = 4.848e-9;

/// Floor of the standard error of a dwell's accelerometer mean, m/s^2 (0.1 ug).
const ACCEL_MEAN_STD_FLOOR_MPS2: f64 = 9.80665e-7;

/// Degrees per radian, the factor of gyros in deg/s written as rad/s.
const DEG_PER_RAD: f64 = 57.29578;

/// One check: its name, whether it passed, and a one-line detail.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Check {
    /// `physics`, `fit`, `convergence`, `plausibility`, `spikes`, or for a device's record `stored_record`
    /// (an analysis: `fit`, `plausibility`).
    pub check: &'static str,
    /// Whether the result passed it.
    pub passed: bool,
    /// What it found, one line.
    pub detail: String,
}

impl Check {
    /// A check named `check`.
    pub fn new(check: &'static str, passed: bool, detail: impl Into<String>) -> Check {
        Check { check, passed, detail: detail.into() }
    }
}

/// Every check of a calibration, in the order they are listed (adding a check is one line here).
pub fn checks(c: &Calibration) -> Vec<Check> {
    let mut fit = fit(&c.estimates, noise_dof(c));
    if let Some(hint) = c.fit_hint.as_ref().filter(|_| !fit.passed) {
        fit.detail = format!("{hint}; {}", fit.detail);
    }
    let mut all = vec![physics(c), fit, convergence(c), plausibility(&c.estimates), spikes(c)];
    all.extend(c.record.as_ref().map(stored_record));
    all
}

/// Whether a device's record is its newest: a damaged newer record means the device compensates with an older
/// calibration than the last one stored.
pub fn stored_record(r: &crate::calibration::RecordIdentity) -> Check {
    match r.damaged_newer {
        None => Check::new("stored_record", true, format!("record {} is the newest stored", r.sequence)),
        Some(newer) => Check::new(
            "stored_record",
            false,
            format!(
                "the newest record ({newer}) is damaged (its CRC does not match); shown: the older record {},                  which the device compensates with",
                r.sequence
            ),
        ),
    }
}

/// The checks that failed, as the lines `calibrate` prints on stderr (`check failed: fit: ...`).
pub fn failed_lines<'a>(checks: impl IntoIterator<Item = &'a Check>) -> Vec<String> {
    checks.into_iter().filter(|c| !c.passed).map(|c| format!("check failed: {}: {}", c.check, c.detail)).collect()
}

/// The p-value of the fit's chi-square on its degrees of freedom, when the dwell noise it is weighted by is
/// itself estimated with `noise_dof` degrees of freedom: `chi-square / dof` is then F-distributed with (dof,
/// noise_dof) degrees of freedom, not chi-square / dof (with 12 noise degrees of freedom its 0.1 % point for 6
/// fit degrees of freedom is 8.4, not 3.7); infinite `noise_dof` is the chi-square test. `None` without
/// degrees of freedom.
pub fn fit_p_value(e: &Estimates, noise_dof: f64) -> Option<f64> {
    let dof = e.degrees_of_freedom as f64;
    (dof > 0.0).then(|| 1.0 - crate::stats::noise::f_cdf(e.chi_square / dof, dof, noise_dof))
}

/// The degrees of freedom of the dwell noise a calibration's fit is weighted by: the fewest of its channels'
/// pooled noise estimates (the accelerometers', and the gyros' where used; docs/method.md#honest-errors).
/// Taking the fewest makes the fit check lenient where one channel's noise is poorly known. With a noise file
/// (`--noise`) the noise is the file's model, taken as known: infinite (the chi-square test).
pub fn noise_dof(c: &Calibration) -> f64 {
    if c.noise.is_some() {
        return f64::INFINITY;
    }
    let noise = pool_mean_noise(c.positions.iter().map(|p| p.summary));
    let first = if c.has_gyro { 0 } else { 3 };
    noise[first..].iter().map(|m| m.dof as f64).filter(|d| *d > 0.0).fold(f64::INFINITY, f64::min)
}

/// `fit`: the estimator's chi-square against its degrees of freedom at the 0.1 % level.
pub fn fit(e: &Estimates, noise_dof: f64) -> Check {
    let Some(p_value) = fit_p_value(e, noise_dof) else {
        return Check::new("fit", true, "no degrees of freedom: nothing checks the fit");
    };
    let ratio = e.chi_square / e.degrees_of_freedom as f64;
    let noise =
        if noise_dof.is_finite() { format!(", the dwell noise estimated with {noise_dof:.0}") } else { String::new() };
    let what = format!(
        "chi-square {:.2} on {} degrees of freedom{noise}, p = {p_value:.3}",
        e.chi_square, e.degrees_of_freedom
    );
    if p_value < MISFIT_LEVEL {
        let detail = format!(
            "the residuals are {:.1} times what the dwell noise explains ({what}): the model misses something",
            ratio.sqrt()
        );
        Check::new("fit", false, detail)
    } else {
        Check::new("fit", true, what)
    }
}

/// Largest fraction of a dwell's samples the spike gate may leave out: beyond it they are not isolated
/// corrupt samples but a gate that does not suit the data (or data that are not at rest).
pub const SPIKE_FRACTION_MAX: f64 = 0.01;

/// `spikes`: how many samples the spike gate left out (docs/method.md#spikes); failed when a dwell lost more
/// than [`SPIKE_FRACTION_MAX`] of its samples.
pub fn spikes(c: &Calibration) -> Check {
    let total: u64 = c.positions.iter().map(|p| p.summary.spikes as u64).sum();
    let worst = c.positions.iter().max_by(|a, b| spike_fraction(a).total_cmp(&spike_fraction(b)));
    match worst {
        Some(p) if spike_fraction(p) > SPIKE_FRACTION_MAX => Check::new(
            "spikes",
            false,
            format!(
                "position {} lost {} of {} samples to the spike gate: not isolated spikes",
                p.pos,
                p.summary.spikes,
                p.summary.samples + p.summary.spikes
            ),
        ),
        _ if total == 0 => Check::new("spikes", true, "no sample beyond the spike gate"),
        _ => Check::new("spikes", true, format!("{total} isolated sample(s) beyond the spike gate, not used")),
    }
}

/// The fraction of a dwell's samples that the spike gate left out.
fn spike_fraction(p: &crate::calibration::PositionResult) -> f64 {
    let s = &p.summary;
    s.spikes as f64 / (s.samples as f64 + s.spikes as f64).max(1.0)
}

/// `convergence`: whether the solution's refinement converged.
pub fn convergence(c: &Calibration) -> Check {
    if c.converged {
        Check::new("convergence", true, format!("converged in {} passes", c.passes))
    } else {
        Check::new("convergence", false, format!("the solution did not converge in {} passes", c.passes))
    }
}

/// `plausibility`: every estimate and standard error finite and within its term's plausible magnitude
/// (`sinscal::calib::general::PLAUSIBLE_MAGNITUDE_SI`).
pub fn plausibility(e: &Estimates) -> Check {
    for (what, of) in [("", &e.value_si), ("the standard error of ", &e.std_si)] {
        let theta: [f32; PARAMETERS] = core::array::from_fn(|i| of[i].map_or(0.0, |x| x as f32));
        if let Some(p) = implausible_parameter(&theta) {
            let value = of[p].unwrap_or(f64::NAN);
            let limit = limit_of(p);
            let detail = format!(
                "{what}{} = {} (SI) is not finite or beyond the plausible {} of any instrument",
                parameter_name(p),
                shown(value),
                shown(limit as f64)
            );
            return Check::new("plausibility", false, detail);
        }
    }
    Check::new(
        "plausibility",
        true,
        "every estimate and standard error finite and within its term's plausible magnitude",
    )
}

/// The plausible magnitude of parameter `p`'s term, SI.
fn limit_of(p: usize) -> f32 {
    Term::ALL
        .iter()
        .zip(PLAUSIBLE_MAGNITUDE_SI)
        .find(|(t, _)| {
            let (first, count) = t.parameters();
            (first..first + count).contains(&p)
        })
        .map_or(f32::NAN, |(_, limit)| limit)
}

/// The JSON fields of each term's values and standard errors (docs/formats.md#calibration-json-version-2).
const TERM_FIELDS: [(Term, &str, &str); 8] = [
    (Term::GyroBias, "gyro_bias_radps", "gyro_bias_std_radps"),
    (Term::AccelBias, "accel_bias_mps2", "accel_bias_std_mps2"),
    (Term::AccelScaleFactor, "accel_scale_factor", "accel_scale_factor_std"),
    (Term::AccelMisalignment, "accel_misalignment", "accel_misalignment_std"),
    (Term::GyroScaleFactor, "gyro_scale_factor", "gyro_scale_factor_std"),
    (Term::GyroMisalignment, "gyro_misalignment", "gyro_misalignment_std"),
    (Term::GyroGSensitivity, "gyro_g_sensitivity_radps_per_mps2", "gyro_g_sensitivity_std_radps_per_mps2"),
    (Term::ReferenceOffset, "reference_offset_rad", "reference_offset_std_rad"),
];

/// What a calibration JSON says failed: each entry of its `checks` that did not pass, and the plausibility rule
/// of [`plausibility`] on its values and standard errors, as the lines `apply` prints on stderr. A JSON without
/// `checks` (written before them) is checked for plausibility only.
pub fn failed_in_json(v: &Value) -> Vec<String> {
    let mut lines = Vec::new();
    for entry in v["checks"].as_array().into_iter().flatten() {
        if entry["passed"].as_bool() == Some(false) {
            let name = entry["check"].as_str().unwrap_or("?");
            let detail = entry["detail"].as_str().unwrap_or("");
            lines.push(format!("check failed: {name}: {detail} (in the calibration)"));
        }
    }
    for (term, value_field, std_field) in TERM_FIELDS {
        let (first, _) = term.parameters();
        let limit = limit_of(first) as f64;
        for field in [value_field, std_field] {
            let mut numbers = Vec::new();
            numbers_of(&v[field], &mut numbers);
            if let Some(x) = numbers.iter().find(|x| !x.is_finite() || x.abs() > limit) {
                lines.push(format!(
                    "check failed: plausibility: {field} has {}, beyond the plausible {} of any instrument",
                    shown(*x),
                    shown(limit)
                ));
            }
        }
    }
    lines
}

/// Every number in a JSON value (arrays of arrays included); nulls are none.
fn numbers_of(v: &Value, out: &mut Vec<f64>) {
    match v {
        Value::Number(n) => out.push(n.as_f64().unwrap_or(f64::NAN)),
        Value::Array(items) => items.iter().for_each(|x| numbers_of(x, out)),
        _ => {}
    }
}

/// One sensor triad of the physics check.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Sensor {
    Gyro,
    Accel,
}

/// A way the recording's labels or units may be wrong, or the stated ones.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Hypothesis {
    /// The labels and units as stated.
    Stated,
    /// Every heading is half a turn off.
    HeadingsHalfTurn,
    /// The latitude's sign is wrong.
    LatitudeFlipped,
    /// The values are in a unit this many times smaller than the column's (deg/s written as rad/s).
    Unit(f64),
    /// Two axes are swapped.
    Swapped(usize, usize),
    /// One axis is negated.
    Negated(usize),
}

const AXES: [&str; 3] = ["x", "y", "z"];

impl Hypothesis {
    /// The alternatives of a sensor.
    fn alternatives(sensor: Sensor) -> Vec<Hypothesis> {
        let mut out = match sensor {
            Sensor::Gyro => {
                vec![Hypothesis::HeadingsHalfTurn, Hypothesis::LatitudeFlipped, Hypothesis::Unit(DEG_PER_RAD)]
            }
            Sensor::Accel => vec![Hypothesis::Unit(1.0 / 9.80665)],
        };
        out.extend([Hypothesis::Swapped(0, 1), Hypothesis::Swapped(1, 2), Hypothesis::Swapped(0, 2)]);
        out.extend((0..3).map(Hypothesis::Negated));
        out
    }

    /// What the check says when this hypothesis explains the data.
    fn hint(self, sensor: Sensor) -> String {
        let triad = match sensor {
            Sensor::Gyro => "gyro",
            Sensor::Accel => "accelerometer",
        };
        match self {
            Hypothesis::Stated => "the labels as stated".to_string(),
            Hypothesis::HeadingsHalfTurn => "headings half a turn off?".to_string(),
            Hypothesis::LatitudeFlipped => "latitude sign?".to_string(),
            Hypothesis::Unit(_) if sensor == Sensor::Gyro => "gyros in deg/s?".to_string(),
            Hypothesis::Unit(_) => "accelerometers in g, not m/s^2?".to_string(),
            Hypothesis::Swapped(i, j) => format!("{triad} axes {} and {} swapped?", AXES[i], AXES[j]),
            Hypothesis::Negated(i) => format!("{triad} axis {} negated?", AXES[i]),
        }
    }
}

/// A dwell as the physics check sees it: the reference attitude and the statistics.
pub type PhysicsDwell = (DwellAttitude, DwellSummary);

/// `physics` of a calibration's positions.
pub fn physics(c: &Calibration) -> Check {
    let dwells: Vec<PhysicsDwell> = c.positions.iter().map(|p| (p.attitude, p.summary)).collect();
    physics_of(&dwells, &c.site, c.has_gyro)
}

/// `physics` of a recording's dwells before any calibration (the dwells as `options`' prefilter collects
/// them, the site of its header); `None` when they cannot be collected or a dwell has no attitude (the reasons
/// a calibration gives instead).
pub fn physics_of_recording(rec: &impl crate::io::recording::RowSource, options: &super::Options) -> Option<Check> {
    let prefilter = super::prefilter_of(options, rec).ok()?;
    let dwells = super::collect_dwells(rec, &prefilter, sinscal::calib::general::MAX_DWELLS, None).ok()?;
    let source = rec.source();
    let dwells: Option<Vec<PhysicsDwell>> =
        dwells.into_iter().map(|(tally, summary)| tally.attitude(source).ok().map(|a| (a, summary))).collect();
    let (site, _) = super::site_of(rec.header());
    Some(physics_of(&dwells?, &site, rec.has_gyro()))
}

/// `physics`, before any fit: (a) each dwell's |f| against g; (b) the direction of gravity and of the Earth rate
/// against the labels: the misfit (chi-square of a constant bias per channel, weighted by each dwell mean's
/// noise) of the data as stated against that of each alternative (headings half a turn off, latitude sign, gyros
/// in deg/s, two axes swapped, an axis negated). It fails when the stated labels misfit at the 0.1 % level and
/// an alternative explains the data [`ALTERNATIVE_FACTOR`] times better. Gyros that do not resolve the Earth
/// rate, and dwells without a reference heading, are not checked against it.
pub fn physics_of(dwells: &[PhysicsDwell], site: &Site, has_gyro: bool) -> Check {
    if let Some(detail) = gravity_magnitude(dwells, site) {
        return Check::new("physics", false, detail);
    }
    let mut failed = Vec::new();
    let mut passed = Vec::new();
    let noise = pool_mean_noise(dwells.iter().map(|d| d.1)).map(|m| m.white_equivalent_var);
    let gyros_checked = has_gyro && gyros_resolve_earth_rate(&noise, dwells.iter().map(|d| d.1.samples));
    if let Some(detail) = has_gyro.then(|| rest_rate(dwells)).flatten() {
        failed.push(detail);
    }
    // Gyros in deg/s make them look noisy 57.3-fold too: checked whether or not they resolve the Earth rate.
    let one_pose = has_gyro && misfit(Sensor::Gyro, dwells, site, Hypothesis::Stated).is_none();
    if let Some(detail) = one_pose.then(|| gyros_in_degrees(dwells, site)).flatten() {
        failed.push(detail);
    }
    for sensor in [Sensor::Gyro, Sensor::Accel] {
        if sensor == Sensor::Gyro && !gyros_checked {
            if has_gyro {
                passed.push("the gyros were not checked against the Earth rate (they do not resolve it)".to_string());
            }
            continue;
        }
        match compare(sensor, dwells, site) {
            Verdict::Failed(detail) => failed.push(detail),
            Verdict::Passed(detail) => passed.push(detail),
        }
    }
    if failed.is_empty() {
        Check::new("physics", true, format!("gravity and the Earth rate agree with the labels: {}", passed.join("; ")))
    } else {
        Check::new("physics", false, failed.join("; "))
    }
}

/// Gyros that read more at rest than any gyro's bias: the median of the dwells' `|w|` beyond
/// [`MAX_REST_RATE_RADPS`] (0.2 rad/s, 11.5 deg/s), as a detail. It needs no resolution of the Earth rate:
/// a consumer gyro's 0.6 deg/s bias written in deg/s reads 0.6 "rad/s".
fn rest_rate(dwells: &[PhysicsDwell]) -> Option<String> {
    let median_radps = median_rest_rate_radps(dwells.iter().map(|(_, s)| s.rate_mean_b_radps.map(f64::from)))?;
    (median_radps > MAX_REST_RATE_RADPS).then(|| {
        format!(
            "gyros in deg/s? the gyros read {} rad/s at rest (the median over {} dwells), more than any gyro's \
             bias ({MAX_REST_RATE_RADPS} rad/s)",
            shown(median_radps),
            dwells.len()
        )
    })
}

/// The first dwell whose |f| is more than [`GRAVITY_TOLERANCE`] from g, as a detail.
fn gravity_magnitude(dwells: &[PhysicsDwell], site: &Site) -> Option<String> {
    let g_mps2 = site.gravity_mps2 as f64;
    dwells.iter().enumerate().find_map(|(k, (_, s))| {
        let f_mps2 = s.force_mean_b_mps2.iter().map(|x| (*x as f64).powi(2)).sum::<f64>().sqrt();
        ((f_mps2 / g_mps2 - 1.0).abs() > GRAVITY_TOLERANCE).then(|| {
            let hint = if (f_mps2 - 1.0).abs() < GRAVITY_TOLERANCE {
                "accelerometers in g, not m/s^2?"
            } else {
                "not at rest, or an accelerometer scale error?"
            };
            format!("{hint} dwell {}: |f| = {f_mps2:.4} m/s^2 where g = {g_mps2:.4} m/s^2", k + 1)
        })
    })
}

enum Verdict {
    Passed(String),
    Failed(String),
}

/// The stated labels of one sensor against its alternatives.
fn compare(sensor: Sensor, dwells: &[PhysicsDwell], site: &Site) -> Verdict {
    let (name, reference) = match sensor {
        Sensor::Gyro => ("gyros", "the Earth rate"),
        Sensor::Accel => ("accelerometers", "gravity"),
    };
    let Some((stated, dof)) = misfit(sensor, dwells, site, Hypothesis::Stated) else {
        return Verdict::Passed(format!("{name}: too few dwells to check"));
    };
    let p_value = 1.0 - crate::stats::noise::chi_square_cdf(stated, dof as f64);
    let best = Hypothesis::alternatives(sensor)
        .into_iter()
        .filter_map(|h| misfit(sensor, dwells, site, h).map(|(chi, _)| (h, chi)))
        .min_by(|a, b| a.1.total_cmp(&b.1));
    match best {
        Some((h, chi)) if p_value < MISFIT_LEVEL && chi * ALTERNATIVE_FACTOR < stated => Verdict::Failed(format!(
            "{} the {name} misfit {reference} as labelled (chi-square {stated:.3e} on {dof} degrees of \
             freedom), {chi:.3e} if so",
            h.hint(sensor)
        )),
        _ => Verdict::Passed(format!("{name} chi-square {stated:.1} on {dof} degrees of freedom")),
    }
}

/// Largest relative difference of a dwell's `|w|` from 57.3 times the Earth rate, and largest difference of its
/// angle from the vertical from the Earth rate's (90 deg - latitude), deg, that [`gyros_in_degrees`] takes for
/// gyros in deg/s.
const DEGREES_MAGNITUDE_TOLERANCE: f64 = 0.02;
const DEGREES_ANGLE_TOLERANCE_DEG: f64 = 5.0;

/// Gyros in deg/s written as rad/s, from dwells too few to compare hypotheses (one pose, where a constant bias
/// absorbs any constant rate): every dwell's mean rate is 57.3 times the Earth rate (within
/// [`DEGREES_MAGNITUDE_TOLERANCE`]) and at the Earth rate's angle from the vertical (within
/// [`DEGREES_ANGLE_TOLERANCE_DEG`]). A true rate does so only with a bias of 57 times the Earth rate (0.24 deg/s)
/// on the Earth rate's cone about the vertical, within 2 % and 5 deg.
fn gyros_in_degrees(dwells: &[PhysicsDwell], site: &Site) -> Option<String> {
    let earth_radps = sinscal::nav::earth::EARTH_RATE_RADPS as f64;
    let expected_deg = 90.0 - (site.latitude_rad as f64).to_degrees();
    let mut ratio_sum = 0.0;
    for (attitude, s) in dwells {
        let c_b_n = Attitude::from_degrees(attitude.pitch_deg as f32, attitude.roll_deg as f32, 0.0).c_b_n();
        let up_b = c_b_n.transpose().mul_vec([0.0, 0.0, 1.0]).map(f64::from);
        let w = s.rate_mean_b_radps.map(f64::from);
        let size = w.iter().map(|x| x * x).sum::<f64>().sqrt();
        let ratio = size / earth_radps / DEG_PER_RAD;
        let cos = (w[0] * up_b[0] + w[1] * up_b[1] + w[2] * up_b[2]) / size.max(f64::MIN_POSITIVE);
        let angle_deg = cos.clamp(-1.0, 1.0).acos().to_degrees();
        let degrees = (ratio - 1.0).abs() < DEGREES_MAGNITUDE_TOLERANCE
            && (angle_deg - expected_deg).abs() < DEGREES_ANGLE_TOLERANCE_DEG;
        if !degrees {
            return None;
        }
        ratio_sum += ratio;
    }
    (!dwells.is_empty()).then(|| {
        format!(
            "gyros in deg/s? the mean rate of every dwell is {:.3} x 57.3 times the Earth rate, at its angle from \
             the vertical",
            ratio_sum / dwells.len() as f64
        )
    })
}

/// Chi-square and degrees of freedom of a constant bias per channel fitted to the dwell means minus what the
/// reference predicts under a hypothesis; `None` with fewer than two dwells to use (gyros: with a heading).
fn misfit(sensor: Sensor, dwells: &[PhysicsDwell], site: &Site, h: Hypothesis) -> Option<(f64, u32)> {
    let mut sums = [[0.0f64; 3]; 3]; // per channel: sum w, sum w d, sum w d^2
    let mut used = 0u32;
    for (attitude, s) in dwells {
        let heading_deg = match (sensor, attitude.heading_deg) {
            (Sensor::Gyro, None) => continue,
            (_, heading) => heading.unwrap_or(0.0) + if h == Hypothesis::HeadingsHalfTurn { 180.0 } else { 0.0 },
        };
        let c_b_n =
            Attitude::from_degrees(attitude.pitch_deg as f32, attitude.roll_deg as f32, heading_deg as f32).c_b_n();
        let (reference_n, measured, first, floor) = match sensor {
            Sensor::Gyro => {
                let latitude_rad =
                    if h == Hypothesis::LatitudeFlipped { -site.latitude_rad } else { site.latitude_rad };
                let at = Site { latitude_rad, ..*site };
                (at.earth_rate_n_radps(), s.rate_mean_b_radps, 0, GYRO_MEAN_STD_FLOOR_RADPS)
            }
            Sensor::Accel => (site.force_at_rest_n_mps2(), s.force_mean_b_mps2, 3, ACCEL_MEAN_STD_FLOOR_MPS2),
        };
        let predicted = c_b_n.transpose().mul_vec(reference_n);
        let mut value: [f64; 3] = core::array::from_fn(|i| measured[i] as f64);
        let mut var: [f64; 3] = core::array::from_fn(|i| {
            let n = &s.mean_noise[first + i];
            (n.white_equivalent_var as f64 / s.samples.max(1) as f64).max(floor * floor)
        });
        match h {
            Hypothesis::Unit(per) => {
                value = value.map(|x| x / per);
                var = var.map(|x| x / (per * per));
            }
            Hypothesis::Swapped(i, j) => {
                value.swap(i, j);
                var.swap(i, j);
            }
            Hypothesis::Negated(i) => value[i] = -value[i],
            _ => {}
        }
        for i in 0..3 {
            let d = value[i] - predicted[i] as f64;
            let w = 1.0 / var[i];
            sums[i][0] += w;
            sums[i][1] += w * d;
            sums[i][2] += w * d * d;
        }
        used += 1;
    }
    (used >= 2).then(|| (sums.iter().map(|s| (s[2] - s[1] * s[1] / s[0]).max(0.0)).sum(), 3 * (used - 1)))
}
