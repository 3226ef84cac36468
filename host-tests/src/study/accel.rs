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
    let rows: Vec<Vec<f64>> = ups.iter().map(|u| vec![1.0, g * u[0], g * u[1], g * u[2]]).collect();
    let mut model = AccelModel { bias_mps2: [0.0; 3], matrix: IDENTITY };
    for i in 0..3 {
        let y: Vec<f64> = means.iter().map(|m| m[i]).collect();
        let x = least_squares_normal(&rows, &y)?;
        model.bias_mps2[i] = x[0];
        model.matrix[i] = [x[1], x[2], x[3]];
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
    let t_of = |p: &[f64]| -> M3 { [[p[3], 0.0, 0.0], [p[4], p[5], 0.0], [p[6], p[7], p[8]]] };
    let residuals = |p: &[f64]| -> Vec<f64> {
        let t = t_of(p);
        means.iter().map(|m| norm(mul_vec(&t, sub(*m, [p[0], p[1], p[2]]))) - g).collect()
    };
    if means.len() < 9 {
        return None;
    }
    let p = gauss_newton(vec![0.0, 0.0, 0.0, 1.0, 0.0, 1.0, 0.0, 0.0, 1.0], &residuals);
    Some(AccelModel { bias_mps2: [p[0], p[1], p[2]], matrix: inverse3(&t_of(&p))? })
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

/// The gain on poses not used for the fit: |f calibrated| - g (m/s^2) of each held-out pose under the base and
/// the extended model, with the rule in words. Labelled: leave one pose out (every pose is then marked held
/// out); unlabelled: fit on the even poses, evaluate on the odd ones.
pub(crate) fn held_out_norms(
    kind: PoseKind,
    poses: &mut [Pose],
    means: &[[f64; 3]],
    ups: &[[f64; 3]],
    g: f64,
    source: &str,
) -> Result<(&'static str, Vec<f64>, Vec<f64>), InputError> {
    match kind {
        PoseKind::Labelled => {
            let (rb, re) = leave_one_out(means, ups, g);
            for p in poses.iter_mut() {
                p.held_out = true;
            }
            Ok(("leave one pose out (each pose predicted by the fit on the other five)", rb, re))
        }
        PoseKind::Unlabelled => {
            let fit: Vec<[f64; 3]> = poses.iter().zip(means).filter(|(p, _)| !p.held_out).map(|(_, m)| *m).collect();
            let b = base_unlabelled(&fit, g);
            let e = extended_unlabelled(&fit, g)
                .ok_or_else(|| InputError::file(source, "fewer than 9 even poses: cannot fit 9 parameters"))?;
            let test = poses.iter().zip(means).filter(|(p, _)| p.held_out).map(|(_, m)| *m);
            let rb = test.clone().map(|m| norm(b.calibrate(m)) - g).collect();
            let re = test.map(|m| norm(e.calibrate(m)) - g).collect();
            Ok(("odd poses (models fitted on the even poses)", rb, re))
        }
    }
}

/// Labelled poses, each predicted by the base and the extended fit on the others: |f calibrated| - g, m/s^2
/// (the extended one only where the other poses determine it).
fn leave_one_out(means: &[[f64; 3]], ups: &[[f64; 3]], g: f64) -> (Vec<f64>, Vec<f64>) {
    let (mut rb, mut re) = (Vec::new(), Vec::new());
    for k in 0..means.len() {
        let keep: Vec<usize> = (0..means.len()).filter(|&j| j != k).collect();
        let m: Vec<[f64; 3]> = keep.iter().map(|&j| means[j]).collect();
        let u: Vec<[f64; 3]> = keep.iter().map(|&j| ups[j]).collect();
        let b = base_labelled(&m, &u, g);
        rb.push(norm(b.calibrate(means[k])) - g);
        if let Some(e) = extended_labelled(&m, &u, g) {
            re.push(norm(e.calibrate(means[k])) - g);
        }
    }
    (rb, re)
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
