//! `sinscal align`: the attitude of the analytic coarse alignment of every dwell of a recording, with standard
//! errors, against the recording's reference attitude (docs/cli.md#align, JSON docs/formats.md#alignment-json).
//!
//! With gyros the attitude is the core's [`coarse_align`] of the dwell means (f32); its matrix is not exactly
//! orthogonal for noisy vectors, so the angles are read off the nearest rotation (the orthogonal polar factor,
//! whose first-order rotation is the misalignment of docs/conventions.md#misalignment). Without gyros pitch and
//! roll come from the direction of the mean specific force (f64) and the heading is not determined.
//!
//! Standard errors are first order in the errors of the dwell means, each the sample standard deviation over
//! sqrt(N) per channel (white noise; channels independent). The misalignment they cause is
//!     phi_e = -df_n / g,   phi_n = df_e / g,   phi_u = -dw_e / (W cos L) + tan L df_e / g
//! (docs/method.md#step-4-angles-and-biases with the errors in place of the biases; `df_n = C_b^n df_b`), and a
//! misalignment maps to the angles through `phi = J (d_pitch, d_roll, d_heading)` with the columns of `J`
//! `-Rz(-psi) e_x`, `-Rz(-psi) Rx(theta) e_y` and `e_z` (the derivative of `C_b^n = Rz(-psi) Rx(theta) Ry(gamma)`).
//! Without gyros the level angles' gradients with respect to the mean specific force are used directly.

use serde::Serialize;
use sinscal::calib::align::{coarse_align, AlignError};
use sinscal::nav::earth::{Site, EARTH_RATE_RADPS};

use crate::io::dwell_tally::{DwellTallies, DwellTally};
use crate::io::error::InputError;
use crate::io::recording::RowSource;

/// A 3x3 matrix, row-major, f64.
type M3 = [[f64; 3]; 3];

/// Fewest rows of a dwell that `align` uses (as the calibration: a sample standard deviation needs a few).
pub const MIN_DWELL_ROWS: usize = 10;

/// Within this many degrees of pitch +-90 roll and heading are not separate angles (gimbal lock).
pub const GIMBAL_LOCK_DEG: f64 = 0.1;

/// The alignment of one dwell (JSON `positions[]` of `sinscal-alignment/1`). Angles in degrees.
#[derive(Clone, Debug, Serialize)]
pub struct PositionAlignment {
    /// Position label.
    pub pos: u32,
    /// Rows of the dwell.
    pub samples: usize,
    /// Pitch of the alignment, deg.
    pub pitch_deg: f64,
    /// Roll, deg (null at pitch +-90).
    pub roll_deg: Option<f64>,
    /// Heading, deg clockwise from north (null without gyros, at pitch +-90, or when not determined).
    pub heading_deg: Option<f64>,
    /// Standard error of the pitch, deg.
    pub pitch_std_deg: f64,
    /// Standard error of the roll, deg.
    pub roll_std_deg: Option<f64>,
    /// Standard error of the heading, deg.
    pub heading_std_deg: Option<f64>,
    /// The recording's reference pitch, deg.
    pub reference_pitch_deg: f64,
    /// The recording's reference roll, deg.
    pub reference_roll_deg: f64,
    /// The recording's reference heading, deg (null if unknown).
    pub reference_heading_deg: Option<f64>,
    /// Alignment minus reference, deg.
    pub pitch_difference_deg: f64,
    /// Alignment minus reference, deg.
    pub roll_difference_deg: Option<f64>,
    /// Alignment minus reference, deg (null where either heading is unknown).
    pub heading_difference_deg: Option<f64>,
    /// Why an angle is null, if one is.
    pub note: Option<String>,
}

/// The result of `sinscal align` (JSON `sinscal-alignment/1`).
#[derive(Clone, Debug, Serialize)]
pub struct AlignmentReport {
    /// "sinscal-alignment/1".
    pub schema: &'static str,
    /// The recording.
    pub source: String,
    /// Latitude, deg.
    pub latitude_deg: f64,
    /// Gravity used, m/s^2.
    pub gravity_mps2: f64,
    /// "header" or "normal_gravity".
    pub gravity_source: &'static str,
    /// Whether the recording has gyros (false: pitch and roll from gravity only).
    pub gyro: bool,
    /// One entry per dwell, in order of first appearance.
    pub positions: Vec<PositionAlignment>,
    /// The sinscal version that wrote this.
    pub sinscal_version: &'static str,
}

/// Aligns every dwell of a recording, streaming its rows: per dwell only its tally and the running moments of
/// its six channels are kept (at most [`crate::io::dwell_tally::MAX_DWELLS_READ`] dwells), never its rows.
pub fn align(rec: &impl RowSource) -> Result<AlignmentReport, InputError> {
    let source = rec.source();
    let h = rec.header();
    let latitude_rad = h.latitude_deg.to_radians();
    let (site, gravity_source) = match h.gravity_mps2 {
        Some(g) => (Site { latitude_rad: latitude_rad as f32, gravity_mps2: g as f32 }, "header"),
        None => (Site::with_normal_gravity(latitude_rad as f32, h.height_m as f32), "normal_gravity"),
    };
    let mut tallies = DwellTallies::bounded();
    let mut moments: Vec<Moments> = Vec::new();
    rec.for_each_row(&mut |row| {
        if let Some(i) = tallies.push(row, source)? {
            if i == moments.len() {
                moments.push(Moments::default());
            }
            moments[i].push(row.force_b_mps2, row.rate_b_radps);
        }
        Ok(())
    })?;
    let dwells = tallies.at_least_one(source)?;
    let positions = dwells
        .iter()
        .zip(&moments)
        .map(|(d, m)| align_dwell(d, m, rec.has_gyro(), &site, source))
        .collect::<Result<Vec<_>, _>>()?;
    Ok(AlignmentReport {
        schema: "sinscal-alignment/1",
        source: source.to_string(),
        latitude_deg: h.latitude_deg,
        gravity_mps2: site.gravity_mps2 as f64,
        gravity_source,
        gyro: rec.has_gyro(),
        positions,
        sinscal_version: env!("CARGO_PKG_VERSION"),
    })
}

/// The running means and sums of squared deviations of a dwell's specific force and rate (Welford's update).
#[derive(Clone, Debug, Default)]
struct Moments {
    n: usize,
    force_b_mps2: Running3,
    rate_b_radps: Running3,
}

/// The running mean of a three-axis quantity and its sum of squared deviations per axis.
#[derive(Clone, Copy, Debug, Default)]
struct Running3 {
    mean: [f64; 3],
    m2: [f64; 3],
}

impl Running3 {
    /// Adds the `n`-th value.
    fn push(&mut self, v: [f64; 3], n: f64) {
        for i in 0..3 {
            let delta = v[i] - self.mean[i];
            self.mean[i] += delta / n;
            self.m2[i] += delta * (v[i] - self.mean[i]);
        }
    }

    /// Mean and variance of the mean (sample variance / N) of `n` values.
    fn mean_and_variance(&self, n: usize) -> ([f64; 3], [f64; 3]) {
        let n = n as f64;
        (self.mean, self.m2.map(|m2| m2 / (n - 1.0) / n))
    }
}

impl Moments {
    /// Adds one row's specific force and rate.
    fn push(&mut self, force_b_mps2: [f64; 3], rate_b_radps: [f64; 3]) {
        self.n += 1;
        self.force_b_mps2.push(force_b_mps2, self.n as f64);
        self.rate_b_radps.push(rate_b_radps, self.n as f64);
    }
}

/// Angles of one attitude and their covariance, radians: (pitch, roll, heading) with `None` for a heading
/// that is not determined.
struct Angles {
    pitch: f64,
    roll: f64,
    heading: Option<f64>,
    covariance: M3,
}

fn align_dwell(
    dwell: &DwellTally,
    moments: &Moments,
    has_gyro: bool,
    site: &Site,
    source: &str,
) -> Result<PositionAlignment, InputError> {
    let n = dwell.samples;
    if n < MIN_DWELL_ROWS {
        return Err(InputError::at(
            source,
            dwell.first_line,
            format!("dwell {}: {n} rows, align needs at least {MIN_DWELL_ROWS}", dwell.pos),
        ));
    }
    let reference = dwell.attitude(source)?;
    let (force, force_var) = moments.force_b_mps2.mean_and_variance(moments.n);
    // Readings that are not gravity (zeros, accelerometers in g) define no attitude: refused, not aligned.
    let norm = (force[0] * force[0] + force[1] * force[1] + force[2] * force[2]).sqrt();
    let limit = f64::from(sinscal::calib::limits::FORCE_MAGNITUDE_ERROR_MAX_RELATIVE);
    let g = f64::from(site.gravity_mps2);
    if norm.is_nan() || (norm / g - 1.0).abs() > limit {
        return Err(InputError::at(
            source,
            dwell.first_line,
            format!(
                "dwell {}: |f| is {} m/s^2, more than {} % from g ({}): these readings define no attitude \
                 (accelerometers in g, or not at rest?)",
                dwell.pos,
                crate::io::recording::shown(norm),
                crate::io::recording::shown(limit * 100.0),
                crate::io::recording::shown(g)
            ),
        ));
    }
    let mut note = None;
    let angles = if has_gyro {
        let (rate, rate_var) = moments.rate_b_radps.mean_and_variance(moments.n);
        match coarse_align(force.map(|x| x as f32), rate.map(|x| x as f32), site) {
            Ok(c) => gyro_angles(&c.0.map(|row| row.map(f64::from)), force_var, rate_var, site),
            Err(AlignError::Degenerate) => {
                note = Some("specific force and angular rate are parallel: heading not determined".to_string());
                level_angles(force, force_var)
            }
            Err(e) => return Err(InputError::at(source, dwell.first_line, format!("dwell {}: {e}", dwell.pos))),
        }
    } else {
        level_angles(force, force_var)
    };
    let locked = angles.pitch.cos() < GIMBAL_LOCK_DEG.to_radians().sin();
    if locked {
        note = Some(format!(
            "pitch within {GIMBAL_LOCK_DEG} deg of +-90: roll and heading are not separate angles (gimbal lock)"
        ));
    }
    let std = [0, 1, 2].map(|i| angles.covariance[i][i].sqrt().to_degrees());
    // The alignment in the Euler branch of the reference: (180 - pitch, roll + 180, heading + 180) is the same
    // attitude, used when the reference pitch is beyond +-90.
    let (mut pitch, mut roll, mut heading) =
        (angles.pitch.to_degrees(), angles.roll.to_degrees(), angles.heading.map(f64::to_degrees));
    if wrap180(reference.pitch_deg).abs() > 90.0 {
        (pitch, roll, heading) = (180.0 - pitch, roll + 180.0, heading.map(|h| h + 180.0));
    }
    let near = |angle: f64, reference: f64| reference + wrap180(angle - reference);
    let pitch = near(pitch, reference.pitch_deg);
    let roll = near(roll, reference.roll_deg);
    let heading = heading.map(|h| match reference.heading_deg {
        Some(r) => near(h, r),
        None => h.rem_euclid(360.0),
    });
    let (roll, heading) = if locked { (None, None) } else { (Some(roll), heading) };
    Ok(PositionAlignment {
        pos: dwell.pos,
        samples: n,
        pitch_deg: pitch,
        roll_deg: roll,
        heading_deg: heading,
        pitch_std_deg: std[0],
        roll_std_deg: roll.map(|_| std[1]),
        heading_std_deg: heading.map(|_| std[2]),
        reference_pitch_deg: reference.pitch_deg,
        reference_roll_deg: reference.roll_deg,
        reference_heading_deg: reference.heading_deg,
        pitch_difference_deg: pitch - reference.pitch_deg,
        roll_difference_deg: roll.map(|r| r - reference.roll_deg),
        heading_difference_deg: heading.zip(reference.heading_deg).map(|(h, r)| h - r),
        note,
    })
}

/// `x` wrapped into (-180, 180], degrees.
fn wrap180(x: f64) -> f64 {
    let w = (x + 180.0).rem_euclid(360.0) - 180.0;
    if w == -180.0 {
        180.0
    } else {
        w
    }
}

/// Pitch and roll from the direction of the mean specific force (`f_b = C_n^b [0, 0, g]`, so `f_b / |f_b| =
/// [-sin(roll) cos(pitch), sin(pitch), cos(roll) cos(pitch)]`, docs/conventions.md#attitude), with their
/// covariance from the gradients.
fn level_angles(f: [f64; 3], var: [f64; 3]) -> Angles {
    let [fx, fy, fz] = f;
    let h2 = fx * fx + fz * fz;
    let h = h2.sqrt();
    let f2 = h2 + fy * fy;
    let pitch = fy.atan2(h);
    let roll = (-fx).atan2(fz);
    let d_pitch = [-fy * fx / (h * f2), h / f2, -fy * fz / (h * f2)];
    let d_roll = [-fz / h2, 0.0, fx / h2];
    let cov = |a: [f64; 3], b: [f64; 3]| (0..3).map(|i| a[i] * b[i] * var[i]).sum::<f64>();
    let covariance = [
        [cov(d_pitch, d_pitch), cov(d_pitch, d_roll), 0.0],
        [cov(d_roll, d_pitch), cov(d_roll, d_roll), 0.0],
        [0.0, 0.0, 0.0],
    ];
    Angles { pitch, roll, heading: None, covariance }
}

/// The angles of the alignment matrix `c_hat` (its orthogonal polar factor) and their covariance.
fn gyro_angles(c_hat: &M3, force_var: [f64; 3], rate_var: [f64; 3], site: &Site) -> Angles {
    let r = polar(c_hat);
    let pitch = r[2][1].atan2(r[2][0].hypot(r[2][2]));
    let roll = (-r[2][0]).atan2(r[2][2]);
    let heading = r[0][1].atan2(r[1][1]);
    // phi = A_f df_b + A_w dw_b (first order, see the module's documentation).
    let g = site.gravity_mps2 as f64;
    let latitude = site.latitude_rad as f64;
    let omega_n = EARTH_RATE_RADPS as f64 * latitude.cos();
    let tan = latitude.tan();
    let (east, north) = (r[0], r[1]);
    let a_f: M3 = [north.map(|c| -c / g), east.map(|c| c / g), east.map(|c| tan * c / g)];
    let a_w: M3 = [[0.0; 3], [0.0; 3], east.map(|c| -c / omega_n)];
    // (d_pitch, d_roll, d_heading) = J^-1 phi.
    let (sp, cp) = pitch.sin_cos();
    let (sh, ch) = heading.sin_cos();
    let j: M3 = [[-ch, -sh * cp, 0.0], [sh, -ch * cp, 0.0], [0.0, -sp, 1.0]];
    let covariance = match inverse(&j) {
        Some(j_inv) => {
            let k_f = mul(&j_inv, &a_f);
            let k_w = mul(&j_inv, &a_w);
            let mut p = [[0.0; 3]; 3];
            for (a, b) in [(0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2)] {
                let v = (0..3).map(|k| k_f[a][k] * k_f[b][k] * force_var[k] + k_w[a][k] * k_w[b][k] * rate_var[k]);
                p[a][b] = v.sum();
                p[b][a] = p[a][b];
            }
            p
        }
        // At pitch +-90 (gimbal lock) only the pitch has a standard error: that of the level angle along it.
        None => level_angles(mul_t_vec(&r, [0.0, 0.0, g]), force_var).covariance,
    };
    Angles { pitch, roll, heading: Some(heading), covariance }
}

fn mul(a: &M3, b: &M3) -> M3 {
    [0, 1, 2].map(|i| [0, 1, 2].map(|j| (0..3).map(|k| a[i][k] * b[k][j]).sum()))
}

fn mul_t_vec(a: &M3, v: [f64; 3]) -> [f64; 3] {
    [0, 1, 2].map(|i| (0..3).map(|k| a[k][i] * v[k]).sum())
}

fn transpose(a: &M3) -> M3 {
    [0, 1, 2].map(|i| [0, 1, 2].map(|j| a[j][i]))
}

fn inverse(a: &M3) -> Option<M3> {
    let det = crate::io::calibration_model::det(a);
    if det.abs() < 1e-12 {
        return None;
    }
    let c = |i: usize, j: usize| {
        let (r0, r1) = ((i + 1) % 3, (i + 2) % 3);
        let (c0, c1) = ((j + 1) % 3, (j + 2) % 3);
        a[r0][c0] * a[r1][c1] - a[r0][c1] * a[r1][c0]
    };
    // inverse = adjugate / det, adjugate = transposed cofactors (the cyclic form carries the signs).
    Some([0, 1, 2].map(|i| [0, 1, 2].map(|j| c(j, i) / det)))
}

/// The orthogonal polar factor of `a` (the nearest rotation), by Newton's iteration `X <- (X + X^-T) / 2`.
fn polar(a: &M3) -> M3 {
    let mut x = *a;
    for _ in 0..50 {
        let Some(inv) = inverse(&x) else { break };
        let inv_t = transpose(&inv);
        let next = [0, 1, 2].map(|i| [0, 1, 2].map(|j| 0.5 * (x[i][j] + inv_t[i][j])));
        let change = (0..3).flat_map(|i| (0..3).map(move |j| (i, j))).map(|(i, j)| (next[i][j] - x[i][j]).abs());
        let change = change.fold(0.0, f64::max);
        x = next;
        if change < 1e-15 {
            break;
        }
    }
    x
}

/// The human summary: one row per dwell, units in the header.
pub fn summary(r: &AlignmentReport) -> String {
    use std::fmt::Write as _;
    let mut s = String::new();
    let _ = writeln!(
        s,
        "sinscal align: {} ({} dwells, latitude {} deg, g = {:.6} m/s^2 {})",
        r.source,
        r.positions.len(),
        r.latitude_deg,
        r.gravity_mps2,
        if r.gravity_source == "header" { "from the header" } else { "WGS-84 normal gravity" }
    );
    let _ = writeln!(
        s,
        "attitude of the analytic coarse alignment of each dwell's mean, +- one standard error (white noise assumed);\n\
         diff = alignment - reference{}",
        if r.gyro { "" } else { "; accelerometer-only: pitch and roll from gravity, no heading" }
    );
    let _ = writeln!(
        s,
        "\n {:>4} {:>7} | {:>22} {:>22} {:>22} | {:>10} {:>10} {:>10}",
        "pos", "samples", "pitch [deg]", "roll [deg]", "heading [deg]", "diff p [\"]", "diff r [\"]", "diff h [\"]"
    );
    let angle = |v: Option<f64>, sd: Option<f64>| match (v, sd) {
        (Some(v), Some(sd)) => format!("{v:+10.5} ± {sd:<9.5}"),
        _ => "-".to_string(),
    };
    let arcsec = |v: Option<f64>| v.map_or("-".to_string(), |v| format!("{:+.2}", v * 3600.0));
    let mut notes = Vec::new();
    for p in &r.positions {
        let _ = writeln!(
            s,
            " {:>4} {:>7} | {:>22} {:>22} {:>22} | {:>10} {:>10} {:>10}",
            p.pos,
            p.samples,
            angle(Some(p.pitch_deg), Some(p.pitch_std_deg)),
            angle(p.roll_deg, p.roll_std_deg),
            angle(p.heading_deg, p.heading_std_deg),
            arcsec(Some(p.pitch_difference_deg)),
            arcsec(p.roll_difference_deg),
            arcsec(p.heading_difference_deg)
        );
        if let Some(n) = &p.note {
            notes.push(format!("  dwell {}: {n}", p.pos));
        }
    }
    if !notes.is_empty() {
        let _ = writeln!(s, "\n{}", notes.join("\n"));
    }
    let _ = writeln!(
        s,
        "\nThe standard errors are those of the dwell means (sample std / sqrt(N), white noise); sensor biases are \
         not in them: an east gyro bias b shifts the heading by about b / (W cos L), an accelerometer bias b tilts \
         the level angles by about b / g."
    );
    s
}
