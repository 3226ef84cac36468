//! imu_tk: the fitted accelerometer against the Xsens factory calibration, both brought into one gauge (the
//! lower-triangular factor L of K = L Q: the rotation Q is not observable from |f| = g).

use super::{norm, AccelModel, FactoryComparison, IDENTITY};
use crate::io::import::IMUTK_ACCEL_GAIN_COUNTS_PER_MPS2;
use crate::model::synth::M3;
use crate::stats::solve::inverse3;

/// The lower-triangular L (positive diagonal) of a = L Q, Q orthogonal (an LQ decomposition by Gram-Schmidt on
/// the rows of `a`, first row first).
pub fn lower_triangular_form(a: &M3) -> M3 {
    // Rows of a = L Q: q_0 = a_0 / |a_0|, q_1 from a_1 less its q_0 part, q_2 likewise.
    let mut q: Vec<[f64; 3]> = Vec::new();
    let mut l = [[0.0; 3]; 3];
    for i in 0..3 {
        let mut v = a[i];
        for (j, qj) in q.iter().enumerate() {
            let d: f64 = (0..3).map(|k| a[i][k] * qj[k]).sum();
            l[i][j] = d;
            for k in 0..3 {
                v[k] -= d * qj[k];
            }
        }
        let nv = norm(v);
        l[i][i] = nv;
        q.push(v.map(|x| x / nv));
    }
    l
}

/// The imu_tk comparison: our model in the importer's units is f_imp = A f + b with f_imp = (counts - 32768) /
/// nominal gain, so counts = diag(nominal gain) A f + (32768 + nominal gain * b); the factory model is counts =
/// diag(gain) M f + offset. Both are brought into the lower-triangular gauge (K = L Q).
pub(crate) fn factory_comparison(model: &AccelModel) -> FactoryComparison {
    let nominal = IMUTK_ACCEL_GAIN_COUNTS_PER_MPS2;
    let k_fit: M3 = [0, 1, 2].map(|i| [0, 1, 2].map(|j| nominal[i] * model.matrix[i][j]));
    let l_fit = lower_triangular_form(&k_fit);
    let m_factory: M3 = [[1.0, 0.0, -0.01], [0.01, 1.0, 0.01], [0.02, 0.01, 1.0]];
    let gain_factory = [415.0, 413.0, 415.0];
    let k_factory = |m: &M3| -> M3 { [0, 1, 2].map(|i| [0, 1, 2].map(|j| gain_factory[i] * m[i][j])) };
    let l_f = lower_triangular_form(&k_factory(&m_factory));
    let l_fi = lower_triangular_form(&k_factory(&inverse3(&m_factory).unwrap_or(IDENTITY)));
    let mis = |l: &M3| [l[1][0] / l[1][1], l[2][0] / l[2][2], l[2][1] / l[2][2]];
    FactoryComparison {
        fitted_gain_counts_per_mps2: [l_fit[0][0], l_fit[1][1], l_fit[2][2]],
        factory_gain_counts_per_mps2: [l_f[0][0], l_f[1][1], l_f[2][2]],
        fitted_misalignment: mis(&l_fit),
        factory_misalignment: mis(&l_f),
        factory_misalignment_inverse: mis(&l_fi),
        fitted_offset_counts: [0, 1, 2].map(|i| 32768.0 + nominal[i] * model.bias_mps2[i]),
    }
}
