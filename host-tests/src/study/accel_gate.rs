//! The held-out gate of the multi-pose studies' extended accelerometer model: each of its scale factors and
//! misalignments stays only if the poses held out of the fit need it. Backward elimination: the term whose
//! removal raises the held-out chi^2 least is dropped while that rise is not significant (the rule of the noise
//! model's gate, [`super::noise_extension::significant`]); the terms left are the extended model
//! (docs/cli.md#held-out-gate-of-the-pose-model).

use super::accel::{held_out_of, ExtendedFit};
use super::multi_pose::PoseKind;
use super::noise_extension::{significant, TermGate};
use super::{norm, AccelModel};

/// The extended model's terms: labelled poses, the 9 entries of A (row-major: `A_ij` is output axis i's
/// sensitivity to force along j); unlabelled poses, the 6 of T's lower triangle (T = A^-1: 00, 10, 11, 20, 21,
/// 22). A diagonal entry is a scale factor (fixed at 1 when dropped), another a misalignment (fixed at 0).
pub(crate) fn term_names(kind: PoseKind) -> Vec<String> {
    let entries: Vec<(usize, usize)> = match kind {
        PoseKind::Labelled => (0..3).flat_map(|i| (0..3).map(move |j| (i, j))).collect(),
        PoseKind::Unlabelled => vec![(0, 0), (1, 0), (1, 1), (2, 0), (2, 1), (2, 2)],
    };
    let axis = |k: usize| ["x", "y", "z"][k];
    entries
        .into_iter()
        .map(
            |(i, j)| {
                if i == j {
                    format!("scale factor {}", axis(i))
                } else {
                    format!("misalignment {}{}", axis(i), axis(j))
                }
            },
        )
        .collect()
}

/// The gate's outcome: the verdict on every term (in the order they were decided), the terms kept (a mask over
/// [`term_names`]) and the extended model of those terms, fitted on all poses.
pub(crate) struct AccelGate {
    pub verdicts: Vec<TermGate>,
    pub free: Vec<bool>,
    pub model: AccelModel,
}

/// The held-out chi^2 of the extended model with the terms `free`: the held-out poses' |f calibrated| - g over
/// each one's white-noise standard deviation (`noise_std_mps2` per sample and axis, the pose's samples), squared
/// and summed. `None` when the poses do not determine that model.
fn chi2(fit: &ExtendedFit<'_>, free: &[bool], noise_std_mps2: [f64; 3]) -> Option<f64> {
    let residuals = held_out_of(fit, free)?;
    let mut chi2 = 0.0;
    for (k, r) in residuals {
        let m = fit.means[k];
        let n = fit.samples[k].max(1) as f64;
        let nm = norm(m).max(f64::MIN_POSITIVE);
        let var = (0..3).map(|i| (m[i] / nm * noise_std_mps2[i]).powi(2)).sum::<f64>() / n;
        chi2 += r * r / var.max(f64::MIN_POSITIVE);
    }
    Some(chi2)
}

/// Backward elimination over the extended model's terms on the held-out poses of `fit` (see the module).
pub(crate) fn gate(fit: &ExtendedFit<'_>, noise_std_mps2: [f64; 3]) -> Option<AccelGate> {
    let names = term_names(fit.kind);
    let mut free = vec![true; names.len()];
    let mut verdicts = Vec::new();
    loop {
        let with = chi2(fit, &free, noise_std_mps2)?;
        // Each free term's held-out chi^2 without it (`None`: the poses cannot determine the model without it,
        // which keeps it).
        let without: Vec<(usize, Option<f64>)> = (0..free.len())
            .filter(|&j| free[j])
            .map(|j| {
                let mut less = free.clone();
                less[j] = false;
                (j, chi2(fit, &less, noise_std_mps2))
            })
            .collect();
        let weakest = without.iter().filter_map(|&(j, c)| c.map(|c| (j, c))).min_by(|a, b| a.1.total_cmp(&b.1));
        let Some((j, without_j)) = weakest.filter(|&(_, c)| !significant(with, c)) else {
            // Every term left is needed: each one's own rise, with the rest kept.
            for (j, c) in without {
                verdicts.push(verdict(&names[j], true, with, c.unwrap_or(f64::INFINITY)));
            }
            break;
        };
        free[j] = false;
        verdicts.push(verdict(&names[j], false, with, without_j));
    }
    let model = fit.fit(&free)?;
    Some(AccelGate { verdicts, free, model })
}

/// The verdict on term `name`: held-out chi^2 `with` it and `without` it.
fn verdict(name: &str, kept: bool, with: f64, without: f64) -> TermGate {
    let rise = without - with;
    TermGate {
        term: name.to_string(),
        kept,
        chi2_with: with,
        chi2_without: without,
        reason: if kept {
            format!("without it the held-out chi^2 rises by {rise:.1} (from {with:.1}): significant")
        } else {
            format!("without it the held-out chi^2 changes by {rise:+.1} (from {with:.1}): not significant")
        },
    }
}
