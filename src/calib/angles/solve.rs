//! The bias solution of docs/method.md (steps 4 and 5): weighted least squares over any set of positions.
//!
//! Per position, with `C = C_b^n` of the reference, `nabla_n = C nabla_b`, `eps_n = C eps_b`, and the
//! optional constant reference offset `phi0` (turntable base not level or not pointing north):
//!     phi_e = -nabla_n / g                                      + phi0_e
//!     phi_n =  nabla_e / g                                      + phi0_n
//!     phi_u = -eps_e / (W cos L) + (nabla_e / g) tan L           + phi0_u
//! Stacking all positions gives `y = A theta + noise` with the block-diagonal angle covariance of
//! [`crate::calib::align::angle_covariance_rad2`]. The solver whitens each block, forms the normal equations
//! in scaled units (gyro biases in units of `W cos L`, accelerometer biases in units of `g`, so every
//! column is of order one), equilibrates them, and decomposes them with the Jacobi eigenvalue method.
//! Directions with eigenvalues below [`SolverSettings::rank_tolerance`] of the largest are the
//! schedule's blind spots: every parameter with a share in them is reported unobservable and is not
//! guessed; the others come from the pseudo-inverse, which gives them uniquely, with their standard
//! errors from the same matrix.

use crate::math::linalg::{Mat3, Vec3};
use crate::nav::earth::Site;

/// Most positions one solution takes: the general estimator's capacity, so that a session either estimator
/// takes fits the calibration sequence (the imu_tk session has 37 poses).
pub const MAX_POSITIONS: usize = crate::calib::general::MAX_DWELLS;
/// Parameters: gyro bias x, y, z; accelerometer bias x, y, z; reference offset e, n, u.
pub const MAX_PARAMETERS: usize = 9;

/// One unknown of the bias solution.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Parameter {
    /// Gyro bias along body axis 0, 1, 2 (x, y, z), rad/s.
    GyroBias(usize),
    /// Accelerometer bias along body axis 0, 1, 2, m/s^2.
    AccelBias(usize),
    /// Reference offset about navigation axis 0, 1, 2 (e, n, u), rad.
    ReferenceOffset(usize),
}

impl Parameter {
    /// All parameters in solution order.
    pub const ALL: [Parameter; MAX_PARAMETERS] = [
        Parameter::GyroBias(0),
        Parameter::GyroBias(1),
        Parameter::GyroBias(2),
        Parameter::AccelBias(0),
        Parameter::AccelBias(1),
        Parameter::AccelBias(2),
        Parameter::ReferenceOffset(0),
        Parameter::ReferenceOffset(1),
        Parameter::ReferenceOffset(2),
    ];

    /// The name used in reports (docs/formats.md#calibration-json, `unobservable`): `gyro_bias_x`, `accel_bias_z`,
    /// `reference_offset_e`, ...
    pub fn name(&self) -> &'static str {
        const GYRO: [&str; 3] = ["gyro_bias_x", "gyro_bias_y", "gyro_bias_z"];
        const ACCEL: [&str; 3] = ["accel_bias_x", "accel_bias_y", "accel_bias_z"];
        const OFFSET: [&str; 3] = ["reference_offset_e", "reference_offset_n", "reference_offset_u"];
        match *self {
            Parameter::GyroBias(i) => GYRO[i],
            Parameter::AccelBias(i) => ACCEL[i],
            Parameter::ReferenceOffset(i) => OFFSET[i],
        }
    }
}

/// Settings of the solver.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SolverSettings {
    /// Estimate the constant reference offset `phi0` (true by default: the paper removes it by pair
    /// differences, and with it the solution does not depend on the turntable's base alignment).
    pub estimate_reference_offset: bool,
    /// A floor added to every angle's standard deviation, rad: the resolution of an f32 attitude
    /// computation (2^-23 = 1.2e-7 rad). Keeps the weights finite for noise-free data.
    pub angle_floor_std_rad: f32,
    /// Eigenvalues of the equilibrated normal matrix below this fraction of the largest are blind spots.
    pub rank_tolerance: f32,
}

impl Default for SolverSettings {
    fn default() -> SolverSettings {
        SolverSettings { estimate_reference_offset: true, angle_floor_std_rad: 1.2e-7, rank_tolerance: 1e-5 }
    }
}

/// Why a solution cannot be computed.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum SolveError {
    /// More than [`MAX_POSITIONS`] positions were added.
    TooManyPositions,
    /// No position was added.
    NoPositions,
    /// An angle or covariance is NaN or infinite, or a covariance is not positive definite.
    BadInput,
}

impl core::fmt::Display for SolveError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            SolveError::TooManyPositions => write!(f, "more than {MAX_POSITIONS} positions"),
            SolveError::NoPositions => f.write_str("no positions to solve"),
            SolveError::BadInput => f.write_str("angles or covariance not finite or not positive definite"),
        }
    }
}

impl core::error::Error for SolveError {}

/// An estimate and its standard error, in the unit of the parameter.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Estimate {
    /// The estimate.
    pub value: f32,
    /// Its standard error (one sigma).
    pub std_error: f32,
}

/// The solution. `None` marks a parameter the schedule cannot determine (or, for the reference offset,
/// one that was not estimated: see [`BiasSolution::reference_offset_estimated`]).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct BiasSolution {
    /// Gyro bias, body frame, rad/s.
    pub gyro_bias_b_radps: [Option<Estimate>; 3],
    /// Accelerometer bias, body frame, m/s^2.
    pub accel_bias_b_mps2: [Option<Estimate>; 3],
    /// Constant reference offset `phi0`, navigation frame (e, n, u), rad.
    pub reference_offset_n_rad: [Option<Estimate>; 3],
    /// Whether `phi0` was a parameter.
    pub reference_offset_estimated: bool,
    /// Positions used.
    pub positions: usize,
    /// Residual `phi - A theta` per position (first `positions` entries), rad.
    pub residual_n_rad: [Vec3; MAX_POSITIONS],
    /// Weighted residual sum of squares `sum r^T Sigma^-1 r` (chi-square with `degrees_of_freedom`
    /// degrees of freedom when the bias-only model and the white-noise covariance are right).
    pub chi_square: f32,
    /// Observations minus the rank of the problem.
    pub degrees_of_freedom: u32,
    /// Covariance of all parameters, SI units, in the order of [`Parameter::ALL`] (zero rows and columns
    /// for unobservable or absent parameters).
    pub covariance_si: [[f32; MAX_PARAMETERS]; MAX_PARAMETERS],
}

impl BiasSolution {
    /// The estimate of one parameter.
    pub fn get(&self, p: Parameter) -> Option<Estimate> {
        match p {
            Parameter::GyroBias(i) => self.gyro_bias_b_radps[i],
            Parameter::AccelBias(i) => self.accel_bias_b_mps2[i],
            Parameter::ReferenceOffset(i) => self.reference_offset_n_rad[i],
        }
    }

    /// Whether a parameter was a parameter of this solution and could not be determined.
    pub fn is_unobservable(&self, p: Parameter) -> bool {
        let estimated = !matches!(p, Parameter::ReferenceOffset(_)) || self.reference_offset_estimated;
        estimated && self.get(p).is_none()
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
struct PositionRecord {
    c_b_n: Mat3,
    phi_n_rad: Vec3,
    covariance_rad2: Mat3,
}

/// Collects positions and solves for the biases.
#[derive(Clone, Debug)]
pub struct BiasSolver {
    site: Site,
    settings: SolverSettings,
    records: [PositionRecord; MAX_POSITIONS],
    len: usize,
}

/// The three rows (`phi_e`, `phi_n`, `phi_u`) of the design matrix of one position, in SI units:
/// derivatives of the angles (rad) with respect to [`Parameter::ALL`] (rad/s, m/s^2, rad).
pub fn design_rows_si(c_b_n: &Mat3, site: &Site) -> [[f32; MAX_PARAMETERS]; 3] {
    let scaled = design_rows_scaled(c_b_n, site);
    let scale = parameter_scale(site);
    let mut rows = [[0.0; MAX_PARAMETERS]; 3];
    for (r, row) in rows.iter_mut().enumerate() {
        for (j, cell) in row.iter_mut().enumerate() {
            *cell = scaled[r][j] / scale[j];
        }
    }
    rows
}

/// The size of one scaled unit of each parameter in SI: `W cos L` for gyro biases, `g` for
/// accelerometer biases, 1 rad for the offset.
fn parameter_scale(site: &Site) -> [f32; MAX_PARAMETERS] {
    let (omega, g) = (site.earth_rate_north_radps(), site.gravity_mps2);
    [omega, omega, omega, g, g, g, 1.0, 1.0, 1.0]
}

/// Design rows for the scaled parameters (all entries of order one).
fn design_rows_scaled(c_b_n: &Mat3, site: &Site) -> [[f32; MAX_PARAMETERS]; 3] {
    let c = &c_b_n.0;
    let tan = site.tan_latitude();
    let mut rows = [[0.0; MAX_PARAMETERS]; 3];
    for j in 0..3 {
        rows[0][3 + j] = -c[1][j]; // phi_e = -nabla_n / g
        rows[1][3 + j] = c[0][j]; // phi_n = nabla_e / g
        rows[2][j] = -c[0][j]; // phi_u = -eps_e / (W cos L) ...
        rows[2][3 + j] = tan * c[0][j]; // ... + tan L nabla_e / g
        rows[j][6 + j] = 1.0; // + phi0
    }
    rows
}

/// Cholesky factor `L` (lower) of a symmetric positive definite 3x3 matrix.
fn cholesky3(m: &Mat3) -> Option<Mat3> {
    let a = &m.0;
    let mut l = [[0.0f32; 3]; 3];
    for i in 0..3 {
        for j in 0..=i {
            let s: f32 = a[i][j] - (0..j).map(|k| l[i][k] * l[j][k]).sum::<f32>();
            if i == j {
                if s <= 0.0 || !s.is_finite() {
                    return None;
                }
                l[i][i] = libm::sqrtf(s);
            } else {
                l[i][j] = s / l[j][j];
            }
        }
    }
    Some(Mat3(l))
}

/// Solves `L x = b` for lower-triangular `L`.
fn forward_substitute(l: &Mat3, b: Vec3) -> Vec3 {
    let l = &l.0;
    let x0 = b[0] / l[0][0];
    let x1 = (b[1] - l[1][0] * x0) / l[1][1];
    let x2 = (b[2] - l[2][0] * x0 - l[2][1] * x1) / l[2][2];
    [x0, x1, x2]
}

/// Eigen-decomposition of the leading `n x n` block of a symmetric matrix by cyclic Jacobi rotations.
/// On return `a` holds the eigenvalues on its diagonal and the columns of `v` the eigenvectors.
fn jacobi_eigen(
    a: &mut [[f32; MAX_PARAMETERS]; MAX_PARAMETERS],
    v: &mut [[f32; MAX_PARAMETERS]; MAX_PARAMETERS],
    n: usize,
) {
    for (i, row) in v.iter_mut().enumerate() {
        for (j, cell) in row.iter_mut().enumerate() {
            *cell = if i == j { 1.0 } else { 0.0 };
        }
    }
    for _sweep in 0..60 {
        let mut off = 0.0f32;
        let mut diag = 0.0f32;
        for i in 0..n {
            diag += a[i][i] * a[i][i];
            for j in (i + 1)..n {
                off += a[i][j] * a[i][j];
            }
        }
        if off <= 1e-14 * diag || off == 0.0 {
            return;
        }
        for p in 0..n {
            for q in (p + 1)..n {
                let apq = a[p][q];
                if apq == 0.0 {
                    continue;
                }
                let theta = (a[q][q] - a[p][p]) / (2.0 * apq);
                let t = if theta.abs() > 1e15 {
                    0.5 / theta
                } else {
                    let sign = if theta >= 0.0 { 1.0 } else { -1.0 };
                    sign / (theta.abs() + libm::sqrtf(theta * theta + 1.0))
                };
                let c = 1.0 / libm::sqrtf(t * t + 1.0);
                let s = t * c;
                for row in a.iter_mut().take(n) {
                    let (kp, kq) = (row[p], row[q]);
                    row[p] = c * kp - s * kq;
                    row[q] = s * kp + c * kq;
                }
                for k in 0..n {
                    let (pk, qk) = (a[p][k], a[q][k]);
                    a[p][k] = c * pk - s * qk;
                    a[q][k] = s * pk + c * qk;
                }
                for row in v.iter_mut().take(n) {
                    let (kp, kq) = (row[p], row[q]);
                    row[p] = c * kp - s * kq;
                    row[q] = s * kp + c * kq;
                }
            }
        }
    }
}

impl BiasSolver {
    /// An empty solver for a site.
    pub fn new(site: Site, settings: SolverSettings) -> BiasSolver {
        let empty = PositionRecord { c_b_n: Mat3::IDENTITY, phi_n_rad: [0.0; 3], covariance_rad2: Mat3::IDENTITY };
        BiasSolver { site, settings, records: [empty; MAX_POSITIONS], len: 0 }
    }

    /// Positions added so far.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether no position was added.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Removes all positions.
    pub fn clear(&mut self) {
        self.len = 0;
    }

    /// Adds one position: its reference attitude, misalignment angles (rad) and their covariance (rad^2).
    pub fn add(&mut self, c_b_n: &Mat3, phi_n_rad: Vec3, covariance_rad2: &Mat3) -> Result<(), SolveError> {
        if self.len == MAX_POSITIONS {
            return Err(SolveError::TooManyPositions);
        }
        if !(phi_n_rad.iter().all(|x| x.is_finite()) && covariance_rad2.is_finite() && c_b_n.is_finite()) {
            return Err(SolveError::BadInput);
        }
        self.records[self.len] = PositionRecord { c_b_n: *c_b_n, phi_n_rad, covariance_rad2: *covariance_rad2 };
        self.len += 1;
        Ok(())
    }

    /// Solves the weighted least-squares problem over the positions added: the whitened normal equations,
    /// their equilibrated eigen-decomposition (rank and blind spots), the estimates with their
    /// covariance, and the residuals with their chi-square.
    pub fn solve(&self) -> Result<BiasSolution, SolveError> {
        if self.len == 0 {
            return Err(SolveError::NoPositions);
        }
        let params = if self.settings.estimate_reference_offset { MAX_PARAMETERS } else { 6 };
        let system = self.normal_equations(params)?;
        // Observability from the unweighted design: the schedule's property, never the noise's.
        let structure = self.pseudo_inverse(&system.structural, params, None);
        let inverse = self.pseudo_inverse(&system.normal, params, Some(&structure.observable));
        let (theta_scaled, covariance_si) = self.parameters(&system, &inverse, params);
        let mut estimates = [None; MAX_PARAMETERS];
        for i in 0..params {
            if inverse.observable[i] {
                let std_error = libm::sqrtf(covariance_si[i][i].max(0.0));
                estimates[i] = Some(Estimate { value: theta_scaled[i] * inverse.scale[i], std_error });
            }
        }
        let (residual_n_rad, chi_square) = self.residuals(&system, &theta_scaled, params);
        let pick = |offset: usize| [estimates[offset], estimates[offset + 1], estimates[offset + 2]];
        Ok(BiasSolution {
            gyro_bias_b_radps: pick(0),
            accel_bias_b_mps2: pick(3),
            reference_offset_n_rad: pick(6),
            reference_offset_estimated: self.settings.estimate_reference_offset,
            positions: self.len,
            residual_n_rad,
            chi_square,
            degrees_of_freedom: (3 * self.len).saturating_sub(inverse.rank) as u32,
            covariance_si,
        })
    }

    /// An angle covariance with the floor of [`SolverSettings::angle_floor_std_rad`] on its diagonal.
    fn with_floor(&self, m: &Mat3) -> Mat3 {
        let floor = self.settings.angle_floor_std_rad * self.settings.angle_floor_std_rad;
        let mut m = *m;
        for i in 0..3 {
            m.0[i][i] += floor;
        }
        m
    }

    /// Normal equations in scaled units, `N = sum A_w^T A_w`, `b = sum A_w^T y_w`, with every position's
    /// rows and angles whitened by the Cholesky factor of its angle covariance (kept for the residuals).
    fn normal_equations(&self, params: usize) -> Result<NormalEquations, SolveError> {
        let records = &self.records[..self.len];
        // Common scale of the angle variances, so the whitened numbers are of order one.
        let var_ref = records
            .iter()
            .map(|r| (0..3).map(|i| self.with_floor(&r.covariance_rad2).0[i][i]).sum::<f32>())
            .sum::<f32>()
            / (3 * self.len) as f32;
        if !(var_ref > 0.0 && var_ref.is_finite()) {
            return Err(SolveError::BadInput);
        }
        let mut system = NormalEquations {
            normal: [[0.0f32; MAX_PARAMETERS]; MAX_PARAMETERS],
            structural: [[0.0f32; MAX_PARAMETERS]; MAX_PARAMETERS],
            rhs: [0.0f32; MAX_PARAMETERS],
            factors: [Mat3::IDENTITY; MAX_POSITIONS],
            var_ref,
        };
        for (k, r) in records.iter().enumerate() {
            let cov = self.with_floor(&r.covariance_rad2);
            let cov = Mat3(cov.0.map(|row| row.map(|x| x / var_ref)));
            let l = cholesky3(&cov).ok_or(SolveError::BadInput)?;
            system.factors[k] = l;
            let rows = design_rows_scaled(&r.c_b_n, &self.site);
            for i in 0..params {
                for j in 0..params {
                    system.structural[i][j] += (0..3).map(|m| rows[m][i] * rows[m][j]).sum::<f32>();
                }
            }
            let mut white = [[0.0f32; MAX_PARAMETERS]; 3];
            for j in 0..params {
                let col = forward_substitute(&l, [rows[0][j], rows[1][j], rows[2][j]]);
                for i in 0..3 {
                    white[i][j] = col[i];
                }
            }
            let y = forward_substitute(&l, r.phi_n_rad);
            for i in 0..params {
                system.rhs[i] += (0..3).map(|m| white[m][i] * y[m]).sum::<f32>();
                for j in 0..params {
                    system.normal[i][j] += (0..3).map(|m| white[m][i] * white[m][j]).sum::<f32>();
                }
            }
        }
        Ok(system)
    }

    /// The pseudo-inverse of the equilibrated normal matrix, its rank and the observable parameters.
    ///
    /// Equilibration gives a unit diagonal. In scaled units every parameter moves the angles by the same
    /// amount per unit, so a parameter whose diagonal is far below the largest hardly enters the data (a
    /// position that is a few arcsec off an axis, a reference corrected by a small offset): it is a blind
    /// spot, excluded before equilibration would blow its column up to full size.
    ///
    /// With `allowed` (the structurally observable parameters), the others are excluded instead, and every
    /// eigen-direction of the equilibrated weighted matrix above f32 resolution is kept: a parameter the
    /// schedule determines is estimated however imprecisely.
    fn pseudo_inverse(
        &self,
        normal: &[[f32; MAX_PARAMETERS]; MAX_PARAMETERS],
        params: usize,
        allowed: Option<&[bool; MAX_PARAMETERS]>,
    ) -> PseudoInverse {
        let largest = (0..params).map(|i| normal[i][i]).fold(0.0f32, f32::max);
        let mut d = [0.0f32; MAX_PARAMETERS];
        for i in 0..params {
            let take = match allowed {
                Some(allowed) => allowed[i] && normal[i][i] > 0.0,
                None => normal[i][i] > self.settings.rank_tolerance * largest,
            };
            if take {
                d[i] = libm::sqrtf(normal[i][i]);
            }
        }
        let mut a = [[0.0f32; MAX_PARAMETERS]; MAX_PARAMETERS];
        for i in 0..params {
            for j in 0..params {
                if d[i] > 0.0 && d[j] > 0.0 {
                    a[i][j] = normal[i][j] / (d[i] * d[j]);
                }
            }
        }
        let mut v = [[0.0f32; MAX_PARAMETERS]; MAX_PARAMETERS];
        jacobi_eigen(&mut a, &mut v, params);
        let lambda_max = (0..params).map(|i| a[i][i]).fold(0.0f32, f32::max);
        let tolerance = if allowed.is_some() { 1e-7 } else { self.settings.rank_tolerance };
        let kept = |k: usize| a[k][k] > tolerance * lambda_max;
        let rank = (0..params).filter(|&k| kept(k)).count();
        let mut observable = [false; MAX_PARAMETERS];
        for i in 0..params {
            let blind_share: f32 = (0..params).filter(|&k| !kept(k)).map(|k| v[i][k] * v[i][k]).sum();
            observable[i] = d[i] > 0.0 && blind_share < 0.01;
        }
        let mut pinv = [[0.0f32; MAX_PARAMETERS]; MAX_PARAMETERS];
        for k in (0..params).filter(|&k| kept(k)) {
            for i in 0..params {
                for j in 0..params {
                    pinv[i][j] += v[i][k] * v[j][k] / a[k][k];
                }
            }
        }
        PseudoInverse { pinv, d, observable, rank, scale: parameter_scale(&self.site) }
    }

    /// The parameters in scaled units and their covariance in SI units (zero for unobservable ones).
    fn parameters(
        &self,
        system: &NormalEquations,
        inverse: &PseudoInverse,
        params: usize,
    ) -> ([f32; MAX_PARAMETERS], [[f32; MAX_PARAMETERS]; MAX_PARAMETERS]) {
        let PseudoInverse { pinv, d, observable, scale, .. } = inverse;
        let mut theta_scaled = [0.0f32; MAX_PARAMETERS];
        let mut covariance_si = [[0.0f32; MAX_PARAMETERS]; MAX_PARAMETERS];
        for i in 0..params {
            if d[i] == 0.0 {
                continue;
            }
            theta_scaled[i] =
                (0..params).filter(|&j| d[j] > 0.0).map(|j| pinv[i][j] * system.rhs[j] / d[j]).sum::<f32>() / d[i];
        }
        for i in 0..params {
            for j in 0..params {
                if observable[i] && observable[j] {
                    covariance_si[i][j] = pinv[i][j] / (d[i] * d[j]) * system.var_ref * scale[i] * scale[j];
                }
            }
        }
        (theta_scaled, covariance_si)
    }

    /// Residuals in rad per position and the weighted residual sum of squares.
    fn residuals(
        &self,
        system: &NormalEquations,
        theta_scaled: &[f32; MAX_PARAMETERS],
        params: usize,
    ) -> ([[f32; 3]; MAX_POSITIONS], f32) {
        let mut residual_n_rad = [[0.0f32; 3]; MAX_POSITIONS];
        let mut chi_square = 0.0f32;
        for (k, r) in self.records[..self.len].iter().enumerate() {
            let rows = design_rows_scaled(&r.c_b_n, &self.site);
            let mut res = r.phi_n_rad;
            for (i, out) in res.iter_mut().enumerate() {
                *out -= (0..params).map(|j| rows[i][j] * theta_scaled[j]).sum::<f32>();
            }
            residual_n_rad[k] = res;
            let w = forward_substitute(&system.factors[k], res);
            chi_square += (w[0] * w[0] + w[1] * w[1] + w[2] * w[2]) / system.var_ref;
        }
        (residual_n_rad, chi_square)
    }
}

/// The whitened normal equations of [`BiasSolver::solve`], in scaled units.
struct NormalEquations {
    normal: [[f32; MAX_PARAMETERS]; MAX_PARAMETERS],
    /// The same design unweighted (scaled units): what the schedule can see, whatever the noise.
    structural: [[f32; MAX_PARAMETERS]; MAX_PARAMETERS],
    rhs: [f32; MAX_PARAMETERS],
    /// Cholesky factor of each position's scaled angle covariance.
    factors: [Mat3; MAX_POSITIONS],
    /// The common scale of the angle variances, rad^2.
    var_ref: f32,
}

/// The equilibrated pseudo-inverse of the normal matrix and what it says about the parameters.
struct PseudoInverse {
    pinv: [[f32; MAX_PARAMETERS]; MAX_PARAMETERS],
    /// Equilibration: square roots of the normal matrix's diagonal (0 for a blind spot).
    d: [f32; MAX_PARAMETERS],
    observable: [bool; MAX_PARAMETERS],
    rank: usize,
    /// Physical size of each parameter (scaled to SI).
    scale: [f32; MAX_PARAMETERS],
}

/// Table 1 of the paper: turntable (pitch, roll, heading) in degrees, in table order t1..t6.
pub const TABLE1_POSITIONS_DEG: [[f32; 3]; 6] =
    [[0.0, 0.0, 0.0], [0.0, 0.0, 180.0], [0.0, 0.0, 90.0], [0.0, 0.0, 270.0], [0.0, 90.0, 0.0], [0.0, 270.0, 0.0]];

/// The paper's pair formulas (docs/method.md#step-5-schedule-and-solution, consistent signs) for the six Table 1 positions in table
/// order: returns `(gyro_bias_b_radps, accel_bias_b_mps2)`. For axis i with pair (t_a, t_b):
///     nabla_i = g (phi_n(t_a) - phi_n(t_b)) / 2
///     eps_i   = Omega_n (phi_u(t_b) - phi_u(t_a)) / 2 + Omega_n tan L (phi_n(t_a) - phi_n(t_b)) / 2
/// The least-squares solution generalises this; on angles that follow the linear model exactly the two
/// agree (a test shows it).
pub fn table1_pair_solution(phi_n_rad: &[Vec3; 6], site: &Site) -> (Vec3, Vec3) {
    let omega = site.earth_rate_north_radps();
    let (g, tan) = (site.gravity_mps2, site.tan_latitude());
    let mut eps = [0.0; 3];
    let mut nabla = [0.0; 3];
    for axis in 0..3 {
        let (ta, tb) = (phi_n_rad[2 * axis], phi_n_rad[2 * axis + 1]);
        let dn = 0.5 * (ta[1] - tb[1]);
        nabla[axis] = g * dn;
        eps[axis] = omega * 0.5 * (tb[2] - ta[2]) + omega * tan * dn;
    }
    (eps, nabla)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::nav::frames::Attitude;

    fn site() -> Site {
        Site { latitude_rad: 45.7796f32.to_radians(), gravity_mps2: 9.8063 }
    }

    fn angles_from_model(c: &Mat3, theta_si: &[f32; 9], s: &Site) -> Vec3 {
        let rows = design_rows_si(c, s);
        [0, 1, 2].map(|i| (0..9).map(|j| rows[i][j] * theta_si[j]).sum())
    }

    #[test]
    fn least_squares_agrees_with_pair_formulas_on_model_angles() {
        let s = site();
        let omega = s.earth_rate_north_radps();
        let truth = [0.3 * omega, -0.2 * omega, 0.1 * omega, 1e-3, -2e-3, 1.5e-3, 2e-5, -1e-5, 3e-4];
        let mut solver = BiasSolver::new(s, SolverSettings::default());
        let mut phis = [[0.0; 3]; 6];
        let cov = Mat3([[1e-10, 0.0, 0.0], [0.0, 1e-10, 0.0], [0.0, 0.0, 1e-8]]);
        for (k, p) in TABLE1_POSITIONS_DEG.iter().enumerate() {
            let c = Attitude::from_degrees(p[0], p[1], p[2]).c_b_n();
            phis[k] = angles_from_model(&c, &truth, &s);
            solver.add(&c, phis[k], &cov).unwrap();
        }
        let sol = solver.solve().unwrap();
        let (eps, nabla) = table1_pair_solution(&phis, &s);
        for i in 0..3 {
            let ls_eps = sol.gyro_bias_b_radps[i].unwrap().value;
            let ls_nabla = sol.accel_bias_b_mps2[i].unwrap().value;
            // Agreement to f32 solve precision: 1e-4 relative (the values differ by about 1e-5).
            assert!((ls_eps - eps[i]).abs() < 1e-4 * eps[i].abs(), "eps {i}: {ls_eps} vs pair {}", eps[i]);
            assert!((ls_eps - truth[i]).abs() < 1e-4 * truth[i].abs());
            assert!((ls_nabla - nabla[i]).abs() < 1e-4 * nabla[i].abs(), "nabla {i}: {ls_nabla} vs pair {}", nabla[i]);
            assert!((ls_nabla - truth[3 + i]).abs() < 1e-4 * truth[3 + i].abs());
            let offset = sol.reference_offset_n_rad[i].unwrap().value;
            assert!((offset - truth[6 + i]).abs() < 1e-4 * truth[6 + i].abs(), "phi0 {i}: {offset}");
        }
        assert!(sol.chi_square < 1e-3, "chi2 {}", sol.chi_square);
        assert_eq!(sol.degrees_of_freedom, 18 - 9);
    }

    #[test]
    fn blind_spots_are_reported_not_guessed() {
        let s = site();
        let cov = Mat3([[1e-10, 0.0, 0.0], [0.0, 1e-10, 0.0], [0.0, 0.0, 1e-8]]);
        // Only the first Table 1 pair: x east and west. eps_z never enters; eps_y enters only through
        // eps_e, which it never is; nabla_z is always vertical.
        let mut solver = BiasSolver::new(s, SolverSettings::default());
        let truth = [1e-7, 0.0, 0.0, 1e-3, 2e-3, 0.0, 1e-5, 2e-5, 1e-4];
        for p in &TABLE1_POSITIONS_DEG[..2] {
            let c = Attitude::from_degrees(p[0], p[1], p[2]).c_b_n();
            solver.add(&c, angles_from_model(&c, &truth, &s), &cov).unwrap();
        }
        let sol = solver.solve().unwrap();
        let unobservable: Vec<&str> =
            Parameter::ALL.iter().filter(|p| sol.is_unobservable(**p)).map(|p| p.name()).collect();
        assert_eq!(unobservable, ["gyro_bias_y", "gyro_bias_z", "accel_bias_z"]);
        assert!((sol.gyro_bias_b_radps[0].unwrap().value - 1e-7).abs() < 1e-11);
        assert!((sol.accel_bias_b_mps2[1].unwrap().value - 2e-3).abs() < 1e-8);

        // One position with the offset: bias and offset are confounded in every angle.
        let mut solver = BiasSolver::new(s, SolverSettings::default());
        let c = Attitude::from_degrees(0.0, 0.0, 0.0).c_b_n();
        solver.add(&c, [1e-4, 2e-4, 3e-3], &cov).unwrap();
        let sol = solver.solve().unwrap();
        for p in Parameter::ALL {
            assert!(sol.is_unobservable(p), "{} should be unobservable", p.name());
        }
        // Without the offset, that one position determines nabla_x, nabla_y and eps_x.
        let mut solver = BiasSolver::new(s, SolverSettings { estimate_reference_offset: false, ..Default::default() });
        solver.add(&c, [1e-4, 2e-4, 3e-3], &cov).unwrap();
        let sol = solver.solve().unwrap();
        let observable: Vec<&str> =
            Parameter::ALL.iter().filter(|p| sol.get(**p).is_some()).map(|p| p.name()).collect();
        assert_eq!(observable, ["gyro_bias_x", "accel_bias_x", "accel_bias_y"]);
        assert!(!sol.is_unobservable(Parameter::ReferenceOffset(0)));
    }

    #[test]
    fn errors() {
        let s = site();
        let solver = BiasSolver::new(s, SolverSettings::default());
        assert_eq!(solver.solve(), Err(SolveError::NoPositions));
        let mut solver = BiasSolver::new(s, SolverSettings::default());
        let c = Mat3::IDENTITY;
        assert_eq!(solver.add(&c, [f32::NAN, 0.0, 0.0], &c), Err(SolveError::BadInput));
        for _ in 0..MAX_POSITIONS {
            solver.add(&c, [0.0; 3], &c).unwrap();
        }
        assert_eq!(solver.add(&c, [0.0; 3], &c), Err(SolveError::TooManyPositions));
    }
}
