//! The declared gyro unit of a described layout against the data (docs/data.md#described-layouts): at rest a gyro
//! reads the Earth rate plus its bias. Two checks on the static dwells of an imported recording:
//!
//! - **Magnitude.** No gyro's bias reaches [`MAX_REST_RATE_RADPS`]: a median dwell rate beyond it is a unit, an
//!   increment or a field of the wrong sensor (the accelerometer's 9.8 read as rad/s).
//! - **Scale.** The Earth rate's vertical part needs no heading: the mean rate of dwell k along its up direction
//!   `u_k` (the direction of its mean specific force) is `s W sin L + b . u_k`, with a constant bias `b` and `s`
//!   = 1 for a right unit. Fitted by weighted least squares over the dwells (each weighted by its mean's
//!   variance along `u_k`), `s` is checked wherever the dwells determine it to [`MAX_SCALE_STD`]: a scale off by
//!   more than [`SCALE_SIGMAS`] standard errors and within [`ALTERNATIVE_TOLERANCE`] of a unit mistake's factor
//!   (1/57.3 for rad/s declared as deg/s, the sample interval for increments declared as rates, ...) is refused,
//!   naming the mistake.
//!   Gyros too noisy to resolve the Earth rate (consumer MEMS, short dwells) are not checked, and the import says
//!   so.

use crate::io::error::InputError;
use crate::io::recording::{shown, Row};

/// The largest rate a gyro at rest may read, rad/s (11.5 deg/s): beyond any gyro's bias.
pub const MAX_REST_RATE_RADPS: f64 = 0.2;
/// The largest standard error of the fitted Earth-rate scale for which the scale is checked.
pub const MAX_SCALE_STD: f64 = 0.1;
/// Standard errors by which the fitted scale must miss 1 to be refused.
pub const SCALE_SIGMAS: f64 = 5.0;
/// Degrees per radian: the factor of a deg/s and rad/s mix-up.
const DEG_PER_RAD: f64 = 180.0 / std::f64::consts::PI;
/// How near (relative) the fitted scale must be to a unit mistake's factor for the mistake to be named.
pub const ALTERNATIVE_TOLERANCE: f64 = 0.25;

/// One static dwell: its rows, mean rate and force (body axes), and the rate's sample variance per axis.
struct RestDwell {
    rows: usize,
    rate_b_radps: [f64; 3],
    force_b_mps2: [f64; 3],
    rate_var_radps2: [f64; 3],
}

/// A dwell's rows, and its sums of rate, force and squared rate.
type Sums = (usize, [f64; 3], [f64; 3], [f64; 3]);

/// The dwells (rows with a non-zero `pos`, grouped by label) of `rows`.
fn rest_dwells(rows: &[Row]) -> Vec<RestDwell> {
    let mut order: Vec<u32> = Vec::new();
    let mut sums: std::collections::HashMap<u32, Sums> = Default::default();
    for r in rows.iter().filter(|r| r.pos != 0) {
        let e = sums.entry(r.pos).or_insert_with(|| {
            order.push(r.pos);
            (0, [0.0; 3], [0.0; 3], [0.0; 3])
        });
        e.0 += 1;
        for i in 0..3 {
            e.1[i] += r.rate_b_radps[i];
            e.2[i] += r.force_b_mps2[i];
            e.3[i] += r.rate_b_radps[i] * r.rate_b_radps[i];
        }
    }
    order
        .iter()
        .map(|p| {
            let (n, rate, force, square) = sums[p];
            let m = n as f64;
            let mean = rate.map(|s| s / m);
            let rate_var = [0, 1, 2].map(|i| ((square[i] / m - mean[i] * mean[i]) * m / (m - 1.0).max(1.0)).max(0.0));
            RestDwell { rows: n, rate_b_radps: mean, force_b_mps2: force.map(|s| s / m), rate_var_radps2: rate_var }
        })
        .collect()
}

/// The median over dwells of the magnitude of each dwell's mean rate `rates_b_radps` (body axes), rad/s;
/// `None` without a dwell. Beyond [`MAX_REST_RATE_RADPS`] the gyros read more at rest than any gyro's bias.
pub fn median_rest_rate_radps(rates_b_radps: impl Iterator<Item = [f64; 3]>) -> Option<f64> {
    let mut rates: Vec<f64> = rates_b_radps.map(|v| v[0].hypot(v[1]).hypot(v[2])).collect();
    rates.sort_by(f64::total_cmp);
    rates.get(rates.len() / 2).copied()
}

/// What the check found: `None` when the gyros do not resolve the Earth rate (not checked), else the fitted
/// scale and its standard error.
pub type ScaleFound = Option<(f64, f64)>;

/// Checks the gyros of `rows` (positions assigned) against the Earth rate at `latitude_deg`; `rate_hz` and
/// `increments` name the likely mistakes. Refuses with the reason; otherwise the scale found, if checked.
pub fn check_gyro_units(
    rows: &[Row],
    latitude_deg: f64,
    rate_hz: f64,
    increments: bool,
    source: &str,
) -> Result<ScaleFound, InputError> {
    let dwells = rest_dwells(rows);
    if dwells.is_empty() {
        return Ok(None);
    }
    let norm = |v: [f64; 3]| v[0].hypot(v[1]).hypot(v[2]);
    let Some(median) = median_rest_rate_radps(dwells.iter().map(|d| d.rate_b_radps)) else { return Ok(None) };
    if median > MAX_REST_RATE_RADPS {
        let forces: Vec<f64> = dwells.iter().map(|d| norm(d.force_b_mps2)).collect();
        let like_force = dwells.iter().zip(&forces).all(|(d, f)| (norm(d.rate_b_radps) / f - 1.0).abs() < 0.05);
        let hint = if like_force {
            "the gyro fields read what the accelerometer fields read: fields of the wrong sensor?".to_string()
        } else {
            let mut hints = vec!["deg/s declared as rad/s?"];
            if !increments {
                hints.push("or not at rest?");
            } else {
                hints.push("or rates declared as increments (set increments = false)?");
            }
            hints.join(" ")
        };
        return Err(InputError::file(
            source,
            format!(
                "the gyros read {} rad/s at rest (the median over {} dwells), more than any gyro's bias ({} rad/s): {hint}",
                shown(median),
                dwells.len(),
                MAX_REST_RATE_RADPS
            ),
        ));
    }
    let Some((s, std)) = earth_rate_scale(&dwells, latitude_deg) else { return Ok(None) };
    if std > MAX_SCALE_STD {
        return Ok(None);
    }
    if (s - 1.0).abs() <= SCALE_SIGMAS * std {
        return Ok(Some((s, std)));
    }
    let increment_mistake = if increments {
        (rate_hz, "rates declared as increments (set increments = false)?")
    } else {
        (1.0 / rate_hz, "increments declared as rates (set increments = true)?")
    };
    let alternatives = [
        (1.0 / DEG_PER_RAD, "rad/s declared as deg/s (or a scale 57.3 times too small)?"),
        (DEG_PER_RAD, "deg/s declared as rad/s?"),
        (1.0 / 3600.0, "deg/s declared as deg/h?"),
        (3600.0, "deg/h declared as deg/s?"),
        increment_mistake,
        (-1.0, "the latitude's sign, or the gyros' axes, reversed?"),
    ];
    // Refused only when a mistake explains the scale (within [`ALTERNATIVE_TOLERANCE`] of its factor): a scale
    // off for another reason (quantised noise-free counts, a sensor model beyond bias and scale) is not a unit.
    let Some(&(_, nearest)) = alternatives.iter().find(|a| (s / a.0 - 1.0).abs() <= ALTERNATIVE_TOLERANCE) else {
        return Ok(Some((s, std)));
    };
    Err(InputError::file(
        source,
        format!(
            "the gyros see {} +- {} times the Earth rate's vertical part (over {} dwells; 1 for a right unit): \
             {nearest}",
            shown(s),
            shown(std),
            dwells.len()
        ),
    ))
}

/// The fitted scale of the Earth rate's vertical part and its standard error: unknowns `s` and the bias `b`,
/// one equation per dwell (`r_k . u_k = s W sin L + b . u_k`). `None` with fewer than five dwells or a
/// singular system.
fn earth_rate_scale(dwells: &[RestDwell], latitude_deg: f64) -> Option<(f64, f64)> {
    if dwells.len() < 5 {
        return None;
    }
    let w_up_radps = sinscal::nav::earth::EARTH_RATE_RADPS as f64 * latitude_deg.to_radians().sin();
    let mut a = [[0.0f64; 4]; 4];
    let mut y = [0.0f64; 4];
    for d in dwells {
        let f = d.force_b_mps2[0].hypot(d.force_b_mps2[1]).hypot(d.force_b_mps2[2]);
        if f == 0.0 || d.rows < 2 {
            continue;
        }
        let u = d.force_b_mps2.map(|v| v / f);
        let var = (0..3).map(|i| u[i] * u[i] * d.rate_var_radps2[i]).sum::<f64>() / d.rows as f64;
        let weight = 1.0 / var.max(1e-30);
        let row = [w_up_radps, u[0], u[1], u[2]];
        let obs = (0..3).map(|i| d.rate_b_radps[i] * u[i]).sum::<f64>();
        for i in 0..4 {
            y[i] += weight * row[i] * obs;
            for j in 0..4 {
                a[i][j] += weight * row[i] * row[j];
            }
        }
    }
    let inverse = invert4(a)?;
    let s = (0..4).map(|j| inverse[0][j] * y[j]).sum::<f64>();
    let std = inverse[0][0].max(0.0).sqrt();
    (s.is_finite() && std.is_finite()).then_some((s, std))
}

/// The inverse of a symmetric 4x4 matrix by Gauss-Jordan elimination with partial pivoting; `None` if singular.
fn invert4(mut a: [[f64; 4]; 4]) -> Option<[[f64; 4]; 4]> {
    let mut inv = [[0.0; 4]; 4];
    for (i, row) in inv.iter_mut().enumerate() {
        row[i] = 1.0;
    }
    let scale = a.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
    for col in 0..4 {
        let pivot = (col..4).max_by(|&p, &q| a[p][col].abs().total_cmp(&a[q][col].abs()))?;
        if a[pivot][col].abs() <= 1e-12 * scale {
            return None;
        }
        a.swap(col, pivot);
        inv.swap(col, pivot);
        let p = a[col][col];
        for j in 0..4 {
            a[col][j] /= p;
            inv[col][j] /= p;
        }
        for r in 0..4 {
            if r != col {
                let factor = a[r][col];
                for j in 0..4 {
                    a[r][j] -= factor * a[col][j];
                    inv[r][j] -= factor * inv[col][j];
                }
            }
        }
    }
    Some(inv)
}
