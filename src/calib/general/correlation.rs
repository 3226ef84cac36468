//! The covariance that the correlation between dwells adds (docs/method.md#noise-model): with a noise model
//! and every used dwell's window in its session, the estimate's covariance is the sandwich of the weighted
//! least squares under the model's covariance of the dwell means, not only the inverse of its information.
//!
//! The estimate moves by `g_ki = P b_ki` for an error of one SI unit in channel `i` of dwell `k`'s mean
//! (`P` the covariance of the weighted fit, `b_ki` the dwell's rows after its nuisances are eliminated, applied
//! to that unit error whitened). The weighted fit's covariance assumes independent dwells of the variances they
//! were weighted by, `P = P (sum_ki b_ki b_ki^T v_ki + priors + moves) P`; under the model the dwell part is
//! `sum_i sum_kl b_ki b_li^T C_i(k, l)` instead, so the covariance gains
//!
//! `P [sum_i (sum_kl b_ki b_li^T C_i(k, l) - sum_k b_ki b_ki^T v_ki)] P`,
//!
//! `C_i(k, l)` the model's [`crate::calib::noise_model::NoiseModel::repeat_covariance`]. It is 0 when the dwells were weighted by the
//! model's own variances and the model has white noise only. Cost: two nested passes over the dwells per
//! channel (no storage per dwell): for six dwells a few hundred dwell rows, for 64 about 25,000.

use crate::calib::general::estimator::{ChannelEstimator, Pass, State};
use crate::calib::general::nuisance::eliminate_nuisances;
use crate::calib::general::terms::PARAMETERS;

impl ChannelEstimator {
    /// The covariance the model's correlation between the used dwells adds, in the pass's equilibrated
    /// parameters; `None` without a noise model or without every used dwell's window.
    pub(super) fn correlation_term(
        &self,
        state: &State<'_>,
        pass: &Pass,
        used: &impl Fn(usize) -> bool,
    ) -> Option<[[f32; PARAMETERS]; PARAMETERS]> {
        let model = self.settings.noise.as_ref()?;
        let used_dwells = || self.dwells.iter().enumerate().filter(|(k, _)| used(*k));
        let mut start = u32::MAX;
        let mut end = 0u32;
        for (_, d) in used_dwells() {
            let w = d.window?;
            start = start.min(w.first_sample);
            end = end.max(w.first_sample.saturating_add(w.samples));
        }
        let span = end.checked_sub(start)?;
        let n = state.n;
        let first = if self.settings.use_gyro { 0 } else { 3 };
        // S = sum_i (sum_kl b_ki b_li^T C_i(k, l) - sum_k b_ki b_ki^T v_ki).
        let mut s = [[0.0f32; PARAMETERS]; PARAMETERS];
        for ch in first..6 {
            for (l, dl) in used_dwells() {
                let b_l = self.unit_error_rows(state, pass, l, ch);
                let mut c = [0.0f32; PARAMETERS];
                for (k, dk) in used_dwells() {
                    let (wk, wl) = (dk.window?, dl.window?);
                    let mut cov = model.repeat_covariance(ch, wk, wl, span);
                    if k == l {
                        cov -= dl.channel(ch).1;
                    }
                    if cov == 0.0 {
                        continue;
                    }
                    let b_k = if k == l { b_l } else { self.unit_error_rows(state, pass, k, ch) };
                    for (x, b) in c.iter_mut().zip(b_k.iter()).take(n) {
                        *x += b * cov;
                    }
                }
                for i in 0..n {
                    for j in 0..n {
                        s[i][j] += c[i] * b_l[j];
                    }
                }
            }
        }
        Some(sandwich(&pass.cov_scaled, &s, n))
    }

    /// `b_k,ch`: dwell `k`'s rows, nuisances eliminated, applied to an error of one SI unit in its channel `ch`
    /// (whitened: 1 / its standard deviation in that channel's row, 0 in the others and the priors').
    fn unit_error_rows(&self, state: &State<'_>, pass: &Pass, k: usize, ch: usize) -> [f32; PARAMETERS] {
        let d = &self.dwells[k];
        let lin = self.linearise(state.theta, &state.attitude[k], state.model);
        let nuisance = self.nuisances(d);
        let mut rows = self.rows(d, &lin, state.cols, state.n, &pass.scale, false, nuisance);
        self.add_prior_rows(d, &state.attitude[k], &mut rows);
        let first = if self.settings.use_gyro { 0 } else { 3 };
        let row = ch - first;
        let inverse_std = 1.0 / libm::sqrtf(d.channel(ch).1);
        for (r, y) in rows.y.iter_mut().enumerate().take(rows.rows) {
            *y = if r == row { inverse_std } else { 0.0 };
        }
        let skip = eliminate_nuisances(&mut rows, state.n);
        let mut b = [0.0f32; PARAMETERS];
        for r in skip..rows.rows {
            for (x, a) in b.iter_mut().zip(rows.a[r].iter()).take(state.n) {
                *x += a * rows.y[r];
            }
        }
        b
    }
}

/// `P S P` of the first `n` rows and columns (`P` symmetric).
fn sandwich(
    p: &[[f32; PARAMETERS]; PARAMETERS],
    s: &[[f32; PARAMETERS]; PARAMETERS],
    n: usize,
) -> [[f32; PARAMETERS]; PARAMETERS] {
    let mut ps = [[0.0f32; PARAMETERS]; PARAMETERS];
    for i in 0..n {
        for j in 0..n {
            ps[i][j] = (0..n).map(|m| p[i][m] * s[m][j]).sum();
        }
    }
    let mut out = [[0.0f32; PARAMETERS]; PARAMETERS];
    for i in 0..n {
        for j in 0..n {
            out[i][j] = (0..n).map(|m| ps[i][m] * p[m][j]).sum();
        }
    }
    out
}
