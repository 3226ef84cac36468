//! The sensor model's prediction of a dwell's means and its derivatives by the parameters and the attitude,
//! and the dwell's whitened rows.

use crate::calib::general::estimator::{ChannelDwell, ChannelEstimator};
use crate::calib::general::terms::{misalignment_index, Model, Term, PARAMETERS};
use crate::math::linalg::{cross, rotation, Mat3};
use crate::nav::earth::{Site, EARTH_RATE_RADPS};

/// The prediction of one dwell and its derivatives: rows 0-2 gyro x, y, z, rows 3-5 accelerometer x, y, z;
/// `d_attitude[row][m]`: by a rotation of the dwell's attitude about navigation axis m (e, n, u; u is the
/// heading), `C' = R(-phi) C`.
pub(super) struct Linearised {
    pub(super) pred: [f32; 6],
    pub(super) jac: [[f32; PARAMETERS]; 6],
    pub(super) d_attitude: [[f32; 3]; 6],
    /// Variance each gyro's mean gains from a horizontal Earth rate of unknown direction, (rad/s)^2 (0 when the
    /// whole Earth rate is predicted).
    pub(super) horizontal_var_radps2: [f32; 3],
}

/// `T = I + S + M` of one sensor from the parameters: scale factors from index `scale_first`, misalignments
/// (order xy, xz, yx, yz, zx, zy) from `misalignment_first`.
pub fn sensor_matrix(theta: &[f32; PARAMETERS], scale_first: usize, misalignment_first: usize) -> Mat3 {
    let mut t = Mat3::IDENTITY;
    for i in 0..3 {
        t.0[i][i] += theta[scale_first + i];
        for j in 0..3 {
            if i != j {
                t.0[i][j] += theta[misalignment_first + misalignment_index(i, j)];
            }
        }
    }
    t
}

/// The gyro g-sensitivity `G` from the parameters, (rad/s)/(m/s^2), row i = gyro i.
pub fn g_sensitivity_radps_per_mps2(theta: &[f32; PARAMETERS]) -> Mat3 {
    Mat3([[theta[24], theta[25], theta[26]], [theta[27], theta[28], theta[29]], [theta[30], theta[31], theta[32]]])
}

/// Prediction and Jacobian of one dwell at the parameters `theta` and the attitude `c_ref` (`C_b^n`).
/// Without `earth_rate` (the heading not given and not resolved by the gyros) the gyros are predicted with the
/// Earth rate's vertical part `W sin L up` alone, which no heading changes; its horizontal part `W cos L`, of
/// unknown direction, is noise: over a uniform heading its covariance in the body is `(W cos L)^2 / 2 (I - up
/// up^T)`, of which each gyro's variance is kept (`horizontal_var_radps2`).
pub(super) fn linearise(
    theta: &[f32; PARAMETERS],
    c_ref: &Mat3,
    site: &Site,
    model: Model,
    earth_rate: bool,
) -> Linearised {
    let c_ref = *c_ref;
    let offset = [theta[33], theta[34], theta[35]];
    let c_true = if model.contains(Term::ReferenceOffset) {
        rotation([-offset[0], -offset[1], -offset[2]]).mul(&c_ref)
    } else {
        c_ref
    };
    let f_n = site.force_at_rest_n_mps2();
    let w_full = site.earth_rate_n_radps();
    let w_n = if earth_rate { w_full } else { [0.0, 0.0, w_full[2]] };
    let ct = c_true.transpose();
    let up_b = ct.mul_vec([0.0, 0.0, 1.0]);
    let horizontal = if earth_rate { 0.0 } else { 0.5 * w_full[1] * w_full[1] };
    let f_b = ct.mul_vec(f_n);
    let w_b = ct.mul_vec(w_n);
    let t_a = sensor_matrix(theta, 6, 9);
    let t_g = sensor_matrix(theta, 15, 18);
    let g_mat =
        Mat3([[theta[24], theta[25], theta[26]], [theta[27], theta[28], theta[29]], [theta[30], theta[31], theta[32]]]);
    let fa = t_a.mul_vec(f_b);
    let wg = t_g.mul_vec(w_b);
    let gf = g_mat.mul_vec(f_b);
    let mut out = Linearised {
        pred: [0.0; 6],
        jac: [[0.0; PARAMETERS]; 6],
        d_attitude: [[0.0; 3]; 6],
        horizontal_var_radps2: [0, 1, 2].map(|i| horizontal * (1.0 - up_b[i] * up_b[i]).max(0.0)),
    };
    for i in 0..3 {
        out.pred[i] = wg[i] + theta[i] + gf[i];
        out.pred[3 + i] = fa[i] + theta[3 + i];
        let (g, a) = (i, 3 + i);
        out.jac[g][i] = 1.0;
        out.jac[a][3 + i] = 1.0;
        out.jac[a][6 + i] = f_b[i];
        out.jac[g][15 + i] = w_b[i];
        for j in 0..3 {
            if i != j {
                out.jac[a][9 + misalignment_index(i, j)] = f_b[j];
                out.jac[g][18 + misalignment_index(i, j)] = w_b[j];
            }
            out.jac[g][24 + 3 * i + j] = f_b[j];
        }
    }
    // Reference offset: d(C_true^T v)/d(delta_m) = C_true^T (e_m x v) to first order.
    let axes = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    for (m, e) in axes.iter().enumerate() {
        let dfb = ct.mul_vec(cross(*e, f_n));
        let dwb = ct.mul_vec(cross(*e, w_n));
        let (da, dg, dgf) = (t_a.mul_vec(dfb), t_g.mul_vec(dwb), g_mat.mul_vec(dfb));
        for i in 0..3 {
            out.jac[i][33 + m] = dg[i] + dgf[i];
            out.jac[3 + i][33 + m] = da[i];
        }
    }
    // Attitude (tilt about e and n, heading about u): d(C_true^T v)/d(phi_m) = C_ref^T (e_m x (C_ref v_b)) with
    // v_b = C_true^T v (exact); the heading psi is phi_u.
    for (m, e) in axes.iter().enumerate() {
        let dfb = c_ref.transpose().mul_vec(cross(*e, c_ref.mul_vec(f_b)));
        let dwb = c_ref.transpose().mul_vec(cross(*e, c_ref.mul_vec(w_b)));
        let (da, dg, dgf) = (t_a.mul_vec(dfb), t_g.mul_vec(dwb), g_mat.mul_vec(dfb));
        for i in 0..3 {
            out.d_attitude[i][m] = dg[i] + dgf[i];
            out.d_attitude[3 + i][m] = da[i];
        }
    }
    out
}

/// Whitened rows of one dwell: channel rows (`rows` of them), their right-hand sides and the columns of its
/// nuisance attitude angles (e, n, u; zero for the angles that are not nuisances).
pub(super) struct DwellRows {
    pub(super) a: [[f32; PARAMETERS]; DWELL_ROWS],
    pub(super) y: [f32; DWELL_ROWS],
    pub(super) h: [[f32; 3]; DWELL_ROWS],
    pub(super) rows: usize,
}

/// Rows of one dwell at most: six channels and the priors of its three attitude angles.
pub(super) const DWELL_ROWS: usize = 9;

impl ChannelEstimator {
    /// Prediction and Jacobian of one dwell (the whole Earth rate when the gyros resolve it, else its vertical
    /// part).
    pub(super) fn linearise(&self, theta: &[f32; PARAMETERS], c_ref: &Mat3, model: Model) -> Linearised {
        linearise(theta, c_ref, &self.site, model, self.settings.earth_rate_resolved)
    }

    /// Whitened rows of dwell `d` for the model's columns `cols` (`n` of them), scaled by `scale`, with the
    /// columns of the nuisance angles `nuisance`.
    #[allow(clippy::too_many_arguments, reason = "one call site; a struct would only rename the arguments")]
    pub(super) fn rows(
        &self,
        d: &ChannelDwell,
        lin: &Linearised,
        cols: &[usize; PARAMETERS],
        n: usize,
        scale: &[f32; PARAMETERS],
        structural: bool,
        nuisance: [bool; 3],
    ) -> DwellRows {
        let mut out =
            DwellRows { a: [[0.0; PARAMETERS]; DWELL_ROWS], y: [0.0; DWELL_ROWS], h: [[0.0; 3]; DWELL_ROWS], rows: 0 };
        let first = if self.settings.use_gyro { 0 } else { 3 };
        let g = self.site.gravity_mps2;
        for ch in first..6 {
            let (measured, var) = d.channel(ch);
            let var = if ch < 3 { var + lin.horizontal_var_radps2[ch] } else { var };
            let weight = if structural {
                if ch < 3 {
                    1.0 / EARTH_RATE_RADPS
                } else {
                    1.0 / g
                }
            } else {
                1.0 / libm::sqrtf(var)
            };
            let r = out.rows;
            for (c, &p) in cols.iter().enumerate().take(n) {
                let mut x = lin.jac[ch][p] * weight;
                if structural && x.abs() < 1e-6 {
                    x = 0.0;
                }
                out.a[r][c] = x * scale[c];
            }
            out.y[r] = (measured - lin.pred[ch]) * weight;
            for m in 0..3 {
                let mut h = if nuisance[m] { lin.d_attitude[ch][m] * weight } else { 0.0 };
                if structural && h.abs() < 1e-6 {
                    h = 0.0;
                }
                out.h[r][m] = h;
            }
            out.rows += 1;
        }
        out
    }
}
