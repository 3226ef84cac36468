//! The [`Analysis`] assembled from a front end's selection and findings: the effects chosen as public
//! [`Effect`]s, ranked, the base model, the verdict, the criterion in words and the residuals of the
//! report's figure.

use std::collections::BTreeMap;

use crate::model::catalogue::EffectKind;

use super::sample_tests::{FASTEST_RESOLVED, SLOWEST_RESOLVED};
use super::selection::{ApartFromAliases, Problem, Selection, HALVES, POSE_ORDER};
use super::windows::NOT_STATIONARY;
use super::{Analysis, BaseModel, ChannelDiagnostics, Confounded, Consequence, Effect, FigureData, Misfit, ALPHA};

/// The input kinds (the `input` field).
pub(super) const RECORDING: &str = "recording";
/// See [`RECORDING`].
pub(super) const ANGLES: &str = "angles";

/// What a front end hands over besides the problem and its selection.
pub(super) struct Findings {
    /// Every effect found (the selection's and the sample tests'), in any order.
    pub effects: Vec<Effect>,
    /// RMS residual of the base model per channel or angle group.
    pub residual_rms: BTreeMap<String, f64>,
    /// RMS residual of the block means per channel (recordings).
    pub block_residual_rms: BTreeMap<String, f64>,
    /// Candidates tested in all (the Bonferroni `m`).
    pub m: f64,
    /// Per-channel diagnostics (recordings).
    pub diagnostics: Vec<ChannelDiagnostics>,
    /// The noise model named per channel (recordings; [`super::noise_terms::noise_models`] of `figures`).
    pub noise_model: Vec<super::noise_terms::NoiseModel>,
    /// Figure data.
    pub figures: FigureData,
    /// The verdict on the final model (recordings).
    pub model_fit: Option<super::ModelFit>,
    /// The final model across the thirds of every dwell (recordings).
    pub windows: Option<super::WindowCheck>,
}

/// The effects the selection chose, in the order it chose them.
pub(super) fn effects_of(problem: &Problem, selection: &Selection) -> Vec<Effect> {
    (0..selection.chosen.len()).map(|i| effect_of(problem, selection, i)).collect()
}

/// The `index`-th chosen candidate as an [`Effect`], with the final fit's estimate.
fn effect_of(problem: &Problem, selection: &Selection, index: usize) -> Effect {
    let c = &selection.chosen[index];
    let cand = &problem.candidates[c.candidate];
    let j = problem.base.len() + index;
    let units: Vec<&str> = cand.groups.iter().map(|&g| problem.group_units[g]).collect();
    let mut effect = Effect {
        effect: cand.effect.name().to_string(),
        sensor: cand.sensor.name().to_string(),
        axes: cand.axes.clone(),
        pos: cand.pos,
        pair_pos: cand.pair_pos,
        estimate: selection.final_fit.beta[j],
        std_error: std_error_of(problem, selection, index),
        unit: cand.unit().to_string(),
        delta_bic: c.delta_bic,
        residual_rms_before: c.rms_before,
        residual_rms_after: c.rms_after,
        residual_unit: units.first().copied().unwrap_or("").to_string(),
        residual_of: problem.residual_of.to_string(),
        tau_s: cand.variants[c.variant].0,
        settled_after_s: None,
        frequency_hz: None,
        frequency_spread_hz: None,
        likelihood_ratio: c.lr,
        parameters: cand.parameters(),
        p_value: c.p_value,
        aliases: selection.aliases[index].clone(),
        rivals: rivals(problem, selection, index),
        std_error_with_aliases: None,
        consequence: consequence(problem, selection, index),
        at_grid_edge: cand.variants.len() > 1 && (c.variant == 0 || c.variant + 1 == cand.variants.len()),
        uncertain: false,
    };
    effect.std_error_with_aliases = match selection.apart_from_aliases.get(index) {
        None | Some(ApartFromAliases::NoAliases) => None,
        // A standard error beyond the plausible limit of the term says no more than "not determined".
        Some(ApartFromAliases::Inflated(factor)) if cand.limit.is_none_or(|l| effect.std_error * factor <= l) => {
            Some(Some(effect.std_error * factor))
        }
        Some(ApartFromAliases::Inflated(_) | ApartFromAliases::NotDetermined) => Some(None),
    };
    effect
}

/// The standard error of the `index`-th chosen candidate: the fit's assumes independent block means;
/// correlated ones widen it, and so does a bias that wanders (the larger of the two).
pub(super) fn std_error_of(problem: &Problem, selection: &Selection, index: usize) -> f64 {
    let j = problem.base.len() + index;
    let groups = &problem.candidates[selection.chosen[index].candidate].groups;
    (selection.final_fit.std_error(j) * groups.iter().map(|&g| selection.inflation[g]).fold(1.0, f64::max).sqrt())
        .max(selection.wander_std_errors.get(j).copied().unwrap_or(0.0))
}

/// What leaving chosen effect `index` out of the final model does to the biases: refitting without it moves
/// bias `k` by `-C_kj / C_jj * theta_j` (`C` the final fit's covariance, `j` the effect), exactly, with every
/// other effect kept; in units of the bias's standard error in the final fit. The bias it moves most.
fn consequence(problem: &Problem, selection: &Selection, index: usize) -> Option<Consequence> {
    let fit = &selection.final_fit;
    let j = problem.base.len() + index;
    let c = &fit.covariance;
    if c[j][j].is_nan() || c[j][j] <= 0.0 {
        return None;
    }
    let theta = fit.beta[j];
    let delta = |k: usize| -c[k][j] / c[j][j] * theta;
    let z = |k: usize| delta(k).abs() / c[k][k].max(f64::MIN_POSITIVE).sqrt();
    let biases = (0..problem.base.len()).filter(|&k| problem.base_names[k].contains("_bias_"));
    let worst = biases.max_by(|&p, &q| z(p).total_cmp(&z(q)))?;
    Some(Consequence { bias: problem.base_names[worst].clone(), bias_error: delta(worst), in_std_errors: z(worst) })
}

/// The set-aside candidates as public records.
fn misfits_and_confounded(problem: &Problem, selection: &Selection) -> (Vec<Misfit>, Vec<Confounded>) {
    let misfits = selection
        .misfits
        .iter()
        .map(|m| {
            let cand = &problem.candidates[m.candidate];
            Misfit {
                candidate: cand.name(),
                estimate: m.estimate,
                std_error: m.std_error,
                limit: m.limit,
                unit: cand.unit().to_string(),
                pos: m.pos,
                channel: problem.group_names.get(m.group).cloned().unwrap_or_default(),
            }
        })
        .collect();
    let confounded = selection
        .confounded
        .iter()
        .map(|c| Confounded {
            candidate: problem.candidates[c.candidate].name(),
            likelihood_ratio: c.lr,
            likelihood_ratio_within_poses: c.lr_within,
            estimate: c.estimate,
            estimate_within_poses: c.estimate_within,
            std_error_within_poses: c.std_error_within,
            unit: problem.candidates[c.candidate].unit().to_string(),
            contradicted: c.contradicted,
        })
        .collect();
    (misfits, confounded)
}

/// The rivals of chosen effect `index` that are neither among its aliases nor in the final model.
fn rivals(problem: &Problem, selection: &Selection, index: usize) -> Vec<String> {
    let in_model: Vec<String> = selection.chosen.iter().map(|c| problem.candidates[c.candidate].name()).collect();
    selection.rivals[index]
        .iter()
        .filter(|r| !selection.aliases[index].contains(r) && !in_model.contains(r))
        .cloned()
        .collect()
}

/// Effects ranked: the column effects (what a calibration must model) in the order the forward selection
/// chose them; then the noise effects, which move no estimate, by their BIC gain; the uncertain time terms
/// (confounded with pose order, a random walk of the bias or the session's halves, or a time constant at its
/// grid's end) and the noise terms that differ between the thirds of the dwells or whose time constant is an
/// end of what the samples resolve after all of them. Each column effect carries its consequence; the ranking does
/// not sort by it (a small partial alias of a strong effect can move a bias more than the effect itself:
/// docs/analysis.md#verdict).
fn rank(effects: &mut [Effect]) {
    for e in effects.iter_mut() {
        e.uncertain = is_uncertain(e);
    }
    let class = |e: &Effect| {
        if e.uncertain {
            2
        } else if e.consequence.is_none() {
            1
        } else {
            0
        }
    };
    // Stable: the column effects stay in the order the forward selection chose them (each the best against
    // the model before it); the noise effects by BIC gain.
    effects.sort_by(|a, b| {
        class(a).cmp(&class(b)).then_with(|| {
            if class(a) == 1 {
                a.delta_bic.total_cmp(&b.delta_bic)
            } else {
                std::cmp::Ordering::Equal
            }
        })
    });
}

/// An effect the analysis cannot stand behind: an alias of pose order, the session's halves, the bias's
/// wander, the thirds of the dwells, a slower term bending the dwells or the noise's colour at the sample
/// scale, or a column effect whose time constant is an end of its grid (not determined either).
fn is_uncertain(e: &Effect) -> bool {
    let alias = |a: &String| {
        a == POSE_ORDER
            || a == HALVES
            || a == super::wander::WANDER
            || a == NOT_STATIONARY
            || a == SLOWEST_RESOLVED
            || a == FASTEST_RESOLVED
    };
    e.aliases.iter().any(alias) || (e.at_grid_edge && e.consequence.is_some())
}

/// The verdict: the first ranked effect, except a quantisation whose error (step / sqrt(12)) is below half
/// the noise it sits in, which is reported but never the verdict.
fn verdict(effects: &[Effect]) -> String {
    let below_noise = |e: &Effect| {
        e.effect == EffectKind::Quantization.name() && e.estimate / 12f64.sqrt() < 0.5 * e.residual_rms_before
    };
    effects.iter().find(|e| !below_noise(e)).map_or("none".to_string(), |e| e.effect.clone())
}

/// Per observation group: (position, base residual, final residual) of each observation.
pub(super) fn residuals_by_group(problem: &Problem, selection: &Selection) -> Vec<Vec<(u32, f64, f64)>> {
    let mut out = vec![Vec::new(); problem.obs.groups];
    for i in 0..problem.obs.y.len() {
        out[problem.obs.group[i]].push((
            problem.obs_pos[i],
            selection.base_fit.residual[i],
            selection.final_fit.residual[i],
        ));
    }
    out
}

/// The analysis of `source` (`input` = [`RECORDING`] or [`ANGLES`]).
pub(super) fn assemble(
    problem: Problem,
    selection: Selection,
    mut findings: Findings,
    input: &str,
    source: &str,
) -> Analysis {
    rank(&mut findings.effects);
    let verdict = verdict(&findings.effects);
    let (misfits, confounded) = misfits_and_confounded(&problem, &selection);
    let mut unobservable = problem.unobservable.clone();
    if input == ANGLES {
        // The per-channel time and noise effects (no single sensor in the catalogue) need samples, and the
        // accelerometers' nonlinearity their forces (the alignment equations are linear in the sensor terms).
        let not_in_angles =
            EffectKind::ALL.into_iter().filter(|e| e.sensor().is_none() || *e == EffectKind::AccelNonlinearity);
        unobservable.extend(not_in_angles.map(|e| format!("{e}: angles only")));
    }
    let m = findings.m;
    let mut analysis = Analysis {
        schema: "sinscal-analysis/1".into(),
        source: source.into(),
        input: input.into(),
        base_model: base_model(&problem, &selection, findings.residual_rms, findings.block_residual_rms),
        effects: findings.effects,
        unobservable,
        misfits,
        confounded,
        unsupported: selection
            .unsupported
            .iter()
            .map(|u| {
                let c = &problem.candidates[u.candidate];
                super::UnsupportedEffect {
                    candidate: c.name(),
                    estimate: u.estimate,
                    std_error: u.std_error,
                    unit: c.unit().to_string(),
                }
            })
            .collect(),
        verdict,
        criterion: format!(
            "forward selection; an effect is added when its likelihood-ratio p-value is below alpha/m = {:.3e} \
             (alpha = {ALPHA}, Bonferroni over m = {} candidates) and its delta BIC is negative",
            ALPHA / m,
            m as usize
        ),
        alpha: ALPHA,
        candidates_tested: m as usize,
        cut_short: selection
            .cut_short
            .map(|(ci, lr)| super::CutShort { candidate: problem.candidates[ci].name(), likelihood_ratio: lr }),
        tested: selection.tested,
        diagnostics: findings.diagnostics,
        noise_model: findings.noise_model,
        model_fit: findings.model_fit,
        windows: findings.windows,
        settling: None,
        checks: Vec::new(),
        figures: findings.figures,
    };
    analysis.checks = super::checks::checks(&analysis);
    analysis
}

/// The base model's likelihood, BIC (biases and one variance per group) and biases.
fn base_model(
    problem: &Problem,
    selection: &Selection,
    residual_rms: BTreeMap<String, f64>,
    block_residual_rms: BTreeMap<String, f64>,
) -> BaseModel {
    let nobs = problem.obs.y.len();
    let k = problem.base.len() as f64;
    let ll = selection.base_fit.log_likelihood;
    let biases =
        problem.base_names.iter().enumerate().map(|(j, name)| (name.clone(), selection.base_fit.beta[j])).collect();
    BaseModel {
        name: "bias-only".into(),
        residual_rms,
        block_residual_rms,
        log_likelihood: ll,
        bic: -2.0 * ll + (k + problem.obs.groups as f64) * (nobs as f64).ln(),
        observations: nobs,
        biases,
    }
}
