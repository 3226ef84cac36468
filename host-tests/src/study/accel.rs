//! The accelerometer pose models of the multi-pose studies, f_meas = A f + b: the BASE model (bias only,
//! A = I) and the EXTENDED model (bias, scale factors, misalignments), fitted with the labelled up axes
//! (Ferraris) or from |f| = g alone (imu_tk); their gain on held-out poses; and the per-pose norms of the data
//! and of the base and extended SIMULATIONs.

use rand_chacha::ChaCha8Rng;

use super::multi_pose::PoseKind;
use super::{norm, sub, AccelModel, Pose, IDENTITY};
use crate::io::error::InputError;
use crate::model::simulator::{normal, rng};
use crate::model::synth::{mul_vec, M3};
use crate::stats::solve::{gauss_newton, inverse3, least_squares_normal};

/// Bias-only fit with labelled up directions: b = mean over poses of (m_k - g u_k), m/s^2.
pub(crate) fn base_labelled(means: &[[f64; 3]], ups: &[[f64; 3]], g: f64) -> AccelModel {
    let mut b = [0.0; 3];
    for (m, u) in means.iter().zip(ups) {
        for i in 0..3 {
            b[i] += (m[i] - g * u[i]) / means.len() as f64;
        }
    }
    AccelModel { bias_mps2: b, matrix: IDENTITY }
}

/// Ferraris fit: per output axis m_k,i = b_i + g sum_j A_ij u_k,j by least squares (needs 4 poses spanning
/// the three axes).
pub(crate) fn extended_labelled(means: &[[f64; 3]], ups: &[[f64; 3]], g: f64) -> Option<AccelModel> {
    labelled_with(means, ups, g, &[true; 9])
}

/// [`extended_labelled`] with only the entries of A that `free` marks (row-major) fitted; the others fixed at
/// the identity's (1 on the diagonal, 0 off it).
fn labelled_with(means: &[[f64; 3]], ups: &[[f64; 3]], g: f64, free: &[bool]) -> Option<AccelModel> {
    let mut model = AccelModel { bias_mps2: [0.0; 3], matrix: IDENTITY };
    for i in 0..3 {
        let cols: Vec<usize> = (0..3).filter(|&j| free[3 * i + j]).collect();
        let rows: Vec<Vec<f64>> =
            ups.iter().map(|u| std::iter::once(1.0).chain(cols.iter().map(|&j| g * u[j])).collect()).collect();
        let fixed = |u: &[f64; 3]| (0..3).filter(|&j| !free[3 * i + j]).map(|j| IDENTITY[i][j] * g * u[j]).sum::<f64>();
        let y: Vec<f64> = means.iter().zip(ups).map(|(m, u)| m[i] - fixed(u)).collect();
        let x = least_squares_normal(&rows, &y)?;
        model.bias_mps2[i] = x[0];
        for (c, &j) in cols.iter().enumerate() {
            model.matrix[i][j] = x[1 + c];
        }
    }
    Some(model)
}

/// Bias-only fit by Gauss-Newton on |m_k - b| = g.
pub(crate) fn base_unlabelled(means: &[[f64; 3]], g: f64) -> AccelModel {
    let p =
        gauss_newton(vec![0.0; 3], &|p: &[f64]| means.iter().map(|m| norm(sub(*m, [p[0], p[1], p[2]])) - g).collect());
    AccelModel { bias_mps2: [p[0], p[1], p[2]], matrix: IDENTITY }
}

/// imu_tk-style fit by Gauss-Newton on |T (m_k - b)| = g with T lower-triangular (6 parameters: 3 scale, 3
/// misalignments; the rotation of the body frame is not observable from |f| and is fixed by the triangular
/// form: body x = accelerometer x, body y in the accelerometers' x-y plane). A = T^-1 (lower-triangular too).
pub(crate) fn extended_unlabelled(means: &[[f64; 3]], g: f64) -> Option<AccelModel> {
    unlabelled_with(means, g, &[true; 6])
}

/// [`extended_unlabelled`] with only the entries of T's lower triangle that `free` marks (00, 10, 11, 20, 21,
/// 22) fitted; the others fixed at the identity's.
fn unlabelled_with(means: &[[f64; 3]], g: f64, free: &[bool]) -> Option<AccelModel> {
    const START: [f64; 9] = [0.0, 0.0, 0.0, 1.0, 0.0, 1.0, 0.0, 0.0, 1.0];
    let t_of = |p: &[f64]| -> M3 { [[p[3], 0.0, 0.0], [p[4], p[5], 0.0], [p[6], p[7], p[8]]] };
    // The full parameters (bias, T's six entries) from the fitted ones (bias, the free entries).
    let expand = |q: &[f64]| -> Vec<f64> {
        let mut p = START.to_vec();
        p[..3].copy_from_slice(&q[..3]);
        let mut k = 3;
        for (t, &f) in free.iter().enumerate() {
            if f {
                p[3 + t] = q[k];
                k += 1;
            }
        }
        p
    };
    let residuals = |q: &[f64]| -> Vec<f64> {
        let p = expand(q);
        let t = t_of(&p);
        means.iter().map(|m| norm(mul_vec(&t, sub(*m, [p[0], p[1], p[2]]))) - g).collect()
    };
    if means.len() < 9 {
        return None;
    }
    let start: Vec<f64> =
        START[..3].iter().chain(free.iter().zip(&START[3..]).filter(|(f, _)| **f).map(|(_, v)| v)).copied().collect();
    let p = expand(&gauss_newton(start, &residuals));
    Some(AccelModel { bias_mps2: [p[0], p[1], p[2]], matrix: inverse3(&t_of(&p))? })
}

/// What the held-out comparisons fit and hold out: the poses' mean forces, labelled up axes and samples, and
/// which poses are held out (unlabelled poses: the odd ones; labelled poses: each in turn).
pub(crate) struct ExtendedFit<'a> {
    pub kind: PoseKind,
    /// Mean specific force of each pose, body axes, m/s^2.
    pub means: &'a [[f64; 3]],
    /// Labelled up direction of each pose, body axes (unit vectors; unused for unlabelled poses).
    pub ups: &'a [[f64; 3]],
    /// Samples of each pose.
    pub samples: Vec<usize>,
    /// Unlabelled poses: whether each is held out of the fit.
    pub held_out: Vec<bool>,
    /// Gravity, m/s^2.
    pub g: f64,
}

impl ExtendedFit<'_> {
    /// The extended model with the terms `free` fitted on the poses `keep` marks.
    fn fit_on(&self, free: &[bool], keep: &dyn Fn(usize) -> bool) -> Option<AccelModel> {
        self.model_on(
            &|means, ups| match self.kind {
                PoseKind::Labelled => labelled_with(means, ups, self.g, free),
                PoseKind::Unlabelled => unlabelled_with(means, self.g, free),
            },
            keep,
        )
    }

    /// `model` fitted on the poses `keep` marks (their means and up axes).
    fn model_on(&self, model: &Fitter<'_>, keep: &dyn Fn(usize) -> bool) -> Option<AccelModel> {
        let pick = |v: &[[f64; 3]]| -> Vec<[f64; 3]> { (0..v.len()).filter(|&k| keep(k)).map(|k| v[k]).collect() };
        model(&pick(self.means), &pick(self.ups))
    }

    /// The extended model with the terms `free`, fitted on all poses.
    pub fn fit(&self, free: &[bool]) -> Option<AccelModel> {
        self.fit_on(free, &|_| true)
    }

    /// |f calibrated| - g (m/s^2) of each held-out pose (its index beside) under `model` fitted without it:
    /// labelled poses, each left out in turn; unlabelled, the odd poses under the fit on the even ones. `None`
    /// when a fit is not determined.
    fn held_out(&self, model: &Fitter<'_>) -> Option<Vec<(usize, f64)>> {
        let residual = |m: &AccelModel, k: usize| norm(m.calibrate(self.means[k])) - self.g;
        match self.kind {
            PoseKind::Labelled => {
                (0..self.means.len()).map(|k| self.model_on(model, &|j| j != k).map(|m| (k, residual(&m, k)))).collect()
            }
            PoseKind::Unlabelled => {
                let m = self.model_on(model, &|j| !self.held_out[j])?;
                Some((0..self.means.len()).filter(|&k| self.held_out[k]).map(|k| (k, residual(&m, k))).collect())
            }
        }
    }
}

/// A model fitted on poses' mean forces and up axes.
type Fitter<'f> = dyn Fn(&[[f64; 3]], &[[f64; 3]]) -> Option<AccelModel> + 'f;

/// The held-out poses' |f calibrated| - g (m/s^2) under the extended model with the terms `free`
/// ([`ExtendedFit::held_out`]).
pub(crate) fn held_out_of(fit: &ExtendedFit<'_>, free: &[bool]) -> Option<Vec<(usize, f64)>> {
    fit.held_out(&|means, ups| match fit.kind {
        PoseKind::Labelled => labelled_with(means, ups, fit.g, free),
        PoseKind::Unlabelled => unlabelled_with(means, fit.g, free),
    })
}

/// The base and extended models fitted on all poses (`means`, m/s^2; `ups`, the labelled up axes), and the
/// method in words. Errors name `source` when the poses cannot determine the extended model.
pub(crate) fn fit_models(
    kind: PoseKind,
    means: &[[f64; 3]],
    ups: &[[f64; 3]],
    g: f64,
    source: &str,
) -> Result<(AccelModel, AccelModel, &'static str), InputError> {
    Ok(match kind {
        PoseKind::Labelled => (
            base_labelled(means, ups, g),
            extended_labelled(means, ups, g)
                .ok_or_else(|| InputError::file(source, "the labelled poses do not span the three axes"))?,
            "labelled orientations (Ferraris): m = A g u + b per pose, u the labelled up axis",
        ),
        PoseKind::Unlabelled => (
            base_unlabelled(means, g),
            extended_unlabelled(means, g)
                .ok_or_else(|| InputError::file(source, "fewer than 9 static poses: cannot fit 9 parameters"))?,
            "|f| = g over static poses (orientations unknown): |T (m - b)| = g, T lower-triangular, A = T^-1",
        ),
    })
}

/// The base model's gain on poses not used for the fit ([`ExtendedFit::held_out`]): |f calibrated| - g
/// (m/s^2) of each held-out pose, with the rule in words. Labelled poses are then all marked held out.
pub(crate) fn held_out_base(fit: &ExtendedFit<'_>, poses: &mut [Pose]) -> (&'static str, Vec<f64>) {
    let base = fit.held_out(&|means, ups| {
        Some(match fit.kind {
            PoseKind::Labelled => base_labelled(means, ups, fit.g),
            PoseKind::Unlabelled => base_unlabelled(means, fit.g),
        })
    });
    let residuals = base.unwrap_or_default().into_iter().map(|(_, r)| r).collect();
    match fit.kind {
        PoseKind::Labelled => {
            for p in poses.iter_mut() {
                p.held_out = true;
            }
            ("leave one pose out (each pose predicted by the fit on the other five)", residuals)
        }
        PoseKind::Unlabelled => ("odd poses (models fitted on the even poses)", residuals),
    }
}

/// Fills the per-pose norms: |mean f - b| - g of the data, of the base SIMULATION (stream 77) and of the
/// extended SIMULATION (stream 78) of each pose mean (same samples, same directions; b the base bias), of the
/// data calibrated by the extended model, and the white-noise std of the norm (`noise_std`: the accelerometer
/// white-noise std per sample, m/s^2).
pub(crate) fn simulate_pose_norms(
    poses: &mut [Pose],
    base: &AccelModel,
    extended: &AccelModel,
    g: f64,
    noise_std: [f64; 3],
    seed: u64,
) {
    let mut r = rng(seed, 77);
    let mut r_ext = rng(seed, 78);
    for p in poses.iter_mut() {
        let m = p.mean_force_mps2;
        let n = p.samples as f64;
        let dir = p.up_b.unwrap_or_else(|| unit(extended.calibrate(m)));
        let base_dir = p.up_b.unwrap_or_else(|| unit(sub(m, base.bias_mps2)));
        let base_sim = simulated_mean(base_dir.map(|x| g * x), base, noise_std, n, &mut r);
        let ext_sim = simulated_mean(mul_vec(&extended.matrix, dir.map(|x| g * x)), extended, noise_std, n, &mut r_ext);
        p.norm_minus_g_data_mps2 = norm(sub(m, base.bias_mps2)) - g;
        p.norm_minus_g_base_sim_mps2 = norm(sub(base_sim, base.bias_mps2)) - g;
        p.norm_minus_g_extended_sim_mps2 = norm(sub(ext_sim, base.bias_mps2)) - g;
        p.norm_minus_g_extended_mps2 = norm(extended.calibrate(m)) - g;
        let u = sub(m, base.bias_mps2);
        let nu = norm(u);
        p.norm_noise_std_mps2 = ((0..3).map(|i| (u[i] / nu * noise_std[i]).powi(2)).sum::<f64>() / n).sqrt();
    }
}

/// `v / |v|`.
fn unit(v: [f64; 3]) -> [f64; 3] {
    let nv = norm(v);
    v.map(|x| x / nv)
}

/// A SIMULATION of the mean of `n` samples: the sensed force `f` (A f already applied) plus the model's bias
/// plus white noise of std `noise_std` / sqrt n per axis (three normals from `r`, x first).
fn simulated_mean(f: [f64; 3], model: &AccelModel, noise_std: [f64; 3], n: f64, r: &mut ChaCha8Rng) -> [f64; 3] {
    [0, 1, 2].map(|i| f[i] + model.bias_mps2[i] + noise_std[i] / n.sqrt() * normal(r))
}
