//! The recording front end: observations, candidates, selection, sample tests, result (the steps of the
//! module's flow, in order).

use std::collections::BTreeMap;

use crate::calibration::attitude_knowledge;
use crate::calibration::checks::physics_of_recording;
use crate::io::error::InputError;
use crate::io::recording::RowSource;
use crate::model::catalogue::{EffectKind, Sensor};
use crate::stats::linfit::Observations;
use sinscal::calib::general::AttitudeKnowledge;

use super::candidates::RecordingColumns;
use super::model_fit::{model_fit, FitResiduals, NoiseWarmupOf};
use super::noise_terms::noise_models;
use super::observations::{BlockObs, Blocks, Session};
use super::result::{assemble, effects_of, residuals_by_group, Findings, RECORDING};
use super::sample_tests::{measure_samples, sample_tests, test_samples, SampleFindings, Warmup};
use super::selection::{final_columns, select, select_without, BlockOf, Problem, Selection, Unsupported};
use super::settling::settle;
use super::wander::{mark_wander, unsupported, wander_std_errors, widen_tested};
use super::windows::window_check;
use super::{Analysis, ChannelDiagnostics, Effect, CHANNELS, CHANNEL_UNITS};

/// Analyses a recording: in one pass over its rows, of which the dwells' columns are kept
/// (docs/analysis.md#speed-and-memory). Its dwells are also held against gravity and the Earth rate as
/// `calibrate` holds them, in a second pass beside the first: the `physics` check leads the analysis's checks
/// (none when the dwells have no labelled attitude to hold them against).
pub fn analyze_recording(recording: &(impl RowSource + Sync)) -> Result<Analysis, InputError> {
    let levelled = attitude_knowledge(recording.header()) == AttitudeKnowledge::Unknown;
    // The check reads the rows again, beside the analysis's own pass. The 1-kHz hour: 19.0 s without the
    // check, 26.2 s with it after the analysis, 21.4 s with it beside.
    let (analysis, physics) = std::thread::scope(|scope| {
        let physics = scope.spawn(|| physics_of_recording(recording, &Default::default()));
        let analysis = Session::read(recording).and_then(|s| analyze_session(s, levelled, recording.source()));
        (analysis, physics.join().unwrap_or_else(|e| std::panic::resume_unwind(e)))
    });
    let mut analysis = analysis?;
    analysis.checks.splice(0..0, physics);
    Ok(analysis)
}

/// Most selections run again without the effects a selection admitted that their own standard errors cannot
/// tell from zero ([`unsupported`]); what the last one admits is kept.
const MAX_RESELECTIONS: usize = 3;

/// The analysis of a session read from `source`; `levelled`: its attitudes were levelled from its own
/// accelerometers.
fn analyze_session(mut session: Session, levelled: bool, source: &str) -> Result<Analysis, InputError> {
    let settling = settle(&mut session);
    let accel_bias_mps2 = if levelled { relevel(&mut session) } else { [0.0; 3] };
    let session = &session;
    let blocks = Blocks::cut(session);
    check_column_memory(session, &blocks, source)?;
    // The sample statistics are measured while the block observations are fitted (docs/analysis.md#speed-and-memory).
    let (mut problem, selection, measures) = std::thread::scope(|scope| {
        let measuring = scope.spawn(|| measure_samples(session));
        let mut problem = problem(session, &blocks, levelled.then_some(accel_bias_mps2));
        let selection = select(&mut problem, sample_tests(session));
        let measures = measuring.join().unwrap_or_else(|e| std::panic::resume_unwind(e));
        (problem, selection, measures)
    });
    let mut selection = selection.map_err(|e| InputError::file(source, e))?;
    let m = (selection.observable + sample_tests(session)) as f64;
    let SampleFindings { effects: sample_effects, diagnostics, mut figures } =
        test_samples(session, &measures, m, &chosen_warmups(&problem, &selection));
    let noise_model = noise_models(&figures);
    // Each selection's unsupported effects are left out of the next, until none is left (at most
    // `MAX_RESELECTIONS` more selections).
    let mut all_unsupported: Vec<Unsupported> = Vec::new();
    for round in 0..=MAX_RESELECTIONS {
        mark_wander(&problem, &mut selection, &noise_model, m);
        selection.wander_std_errors = wander_std_errors(&problem, &selection, &noise_model);
        let unsupported = if round < MAX_RESELECTIONS { unsupported(&problem, &selection, m) } else { Vec::new() };
        if unsupported.is_empty() {
            break;
        }
        all_unsupported.extend(unsupported);
        let excluded: Vec<usize> = all_unsupported.iter().map(|u| u.candidate).collect();
        selection =
            select_without(&mut problem, sample_tests(session), &excluded).map_err(|e| InputError::file(source, e))?;
    }
    selection.unsupported = all_unsupported;
    widen_tested(&problem, &mut selection, &noise_model);
    let windows = window_check(&problem, &selection, &noise_model);
    let mut effects = effects_of(&problem, &selection);
    let widened_by = windows.as_ref().map_or(1.0, |w| w.widened_by);
    for e in &mut effects {
        e.std_error *= widened_by;
        if let Some(Some(s)) = e.std_error_with_aliases.as_mut() {
            *s *= widened_by;
        }
    }
    effects.extend(sample_effects);
    let (residual_rms, block_residual_rms) = residual_rms(&problem, &selection, &diagnostics);
    figures.residual_names = problem.group_names.clone();
    figures.residuals = residuals_by_group(&problem, &selection);
    let model_fit = model_fit(&fit_residuals(&problem, &selection), &noise_model, &noise_warmups(&effects, session));
    let findings = Findings {
        effects,
        residual_rms,
        block_residual_rms,
        m,
        diagnostics,
        noise_model,
        figures,
        model_fit,
        windows,
    };
    let mut analysis = assemble(problem, selection, findings, RECORDING, source);
    analysis.settling = settling;
    for (k, axis) in ["x", "y", "z"].iter().enumerate() {
        if let Some(b) = analysis.base_model.biases.get_mut(&format!("accel_bias_{axis}")) {
            *b += accel_bias_mps2[k];
        }
    }
    Ok(analysis)
}

/// The warm-ups of `selection`, per channel of the six.
fn chosen_warmups(problem: &Problem, selection: &Selection) -> [Vec<Warmup>; 6] {
    let mut out: [Vec<Warmup>; 6] = Default::default();
    for (j, c) in selection.chosen.iter().enumerate() {
        let candidate = &problem.candidates[c.candidate];
        let (EffectKind::BiasWarmup, Some(tau)) = (candidate.effect, candidate.variants[c.variant].0) else {
            continue;
        };
        let Some(axis) = ["x", "y", "z"].iter().position(|a| *a == candidate.axes) else { continue };
        let channel = if candidate.sensor == Sensor::Gyro { axis } else { 3 + axis };
        out[channel].push(Warmup { amplitude: selection.final_fit.beta[problem.base.len() + j], tau_s: tau });
    }
    out
}

/// The final model's block-mean residuals with what the verdict on the model needs
/// ([`super::model_fit`]): each block's place, and the parameters acting on each group (a column counted in
/// every group where it has an entry).
fn fit_residuals<'p>(problem: &'p Problem, selection: &'p Selection) -> FitResiduals<'p> {
    let groups = problem.obs.groups;
    let mut parameters = vec![0; groups];
    for column in final_columns(problem, selection) {
        let mut on = vec![false; groups];
        for (v, &g) in column.iter().zip(&problem.obs.group) {
            on[g] |= *v != 0.0;
        }
        for (p, on) in parameters.iter_mut().zip(on) {
            *p += usize::from(on);
        }
    }
    FitResiduals {
        residual: &selection.final_fit.residual,
        group: &problem.obs.group,
        block: problem.obs_block.as_deref().unwrap_or_default(),
        pos: &problem.obs_pos,
        group_names: &problem.group_names,
        group_units: &problem.group_units,
        parameters,
    }
}

/// Levels every dwell again from its accelerometer mean less the accelerometer biases, and returns the
/// biases: the fit along gravity is linear in the biases only near them (a bias of 1 m/s^2 across gravity
/// changes `|f|` by 0.05 m/s^2), so the biases are found by Gauss-Newton on the base model, four passes.
fn relevel(session: &mut Session) -> [f64; 3] {
    let means: Vec<[f64; 3]> = session
        .dwells
        .iter()
        .map(|d| std::array::from_fn(|c| d.y[3 + c].iter().sum::<f64>() / d.y[3 + c].len().max(1) as f64))
        .collect();
    let mut bias = [0.0; 3];
    for _ in 0..4 {
        for (d, m) in session.dwells.iter_mut().zip(&means) {
            let v = [m[0] - bias[0], m[1] - bias[1], m[2] - bias[2]];
            let n = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt().max(f64::MIN_POSITIVE);
            let pitch_deg = (v[1] / n).clamp(-1.0, 1.0).asin().to_degrees();
            let roll_deg = (-v[0]).atan2(v[2]).to_degrees();
            d.c_tilt = crate::model::synth::c_b_n(pitch_deg, roll_deg, 0.0);
        }
        let blocks = Blocks::cut(session);
        let p = problem_with(session, &blocks, Some(bias), false);
        let base: Vec<&[f64]> = p.base.iter().map(|c| c.as_slice()).collect();
        let Some(fit) = crate::stats::linfit::fit(&p.obs, &base) else { break };
        for (j, name) in p.base_names.iter().enumerate() {
            if let Some(k) = ["accel_bias_x", "accel_bias_y", "accel_bias_z"].iter().position(|b| b == name) {
                bias[k] += fit.beta[j];
            }
        }
    }
    bias
}

/// Refuses, before any candidate column is built, a session whose columns would pass the limit
/// ([`super::check_column_memory`]).
fn check_column_memory(session: &Session, blocks: &Blocks, source: &str) -> Result<(), InputError> {
    let dwells = session.dwells.len() as u64;
    let observations = blocks.y.len() as u64;
    let largest_channel = (0..6).map(|c| blocks.group.iter().filter(|&&g| g == c).count()).max().unwrap_or(0) as u64;
    // On one channel's observations: the sensor terms (at most 30) and per channel a drift, a temperature term
    // and a warm-up per time constant of the grid. On all: the reference offsets and the position errors (each
    // on its own dwell's blocks, three axes).
    let per_channel = 30 + 6 * (2 + super::candidates::TAU_GRID_POINTS as u64);
    let entries = per_channel * largest_channel + 3 * observations + 3 * observations;
    super::check_column_memory(&format!("{dwells} dwells"), blocks.y.len(), entries, source)
}

/// The block means, the base model's bias columns and the catalogue's candidates. With attitudes levelled
/// from the recording's own accelerometers (`levelled`: the accelerometer biases they were levelled with),
/// the accelerometer rows become one row per block: the force along the gravity direction
/// ([`along_gravity`]).
fn problem(session: &Session, blocks: &Blocks, levelled: Option<[f64; 3]>) -> Problem {
    problem_with(session, blocks, levelled, true)
}

/// [`problem`], with the catalogue's candidates only when `with_candidates` (the levelling passes need the
/// base model alone).
fn problem_with(session: &Session, blocks: &Blocks, levelled: Option<[f64; 3]>, with_candidates: bool) -> Problem {
    let mut unobservable = Vec::new();
    let (base, base_names) = blocks.base_columns(&mut unobservable);
    let candidates =
        if with_candidates { RecordingColumns::new(session, blocks).candidates(&mut unobservable) } else { Vec::new() };
    let problem = Problem {
        obs: Observations { y: blocks.y.clone(), group: blocks.group.clone(), groups: 6, sigma: None },
        base,
        base_names,
        group_names: CHANNELS.iter().map(|s| s.to_string()).collect(),
        group_units: CHANNEL_UNITS.to_vec(),
        obs_pos: blocks.obs_pos.clone(),
        obs_pose: Some(poses(session, blocks)),
        obs_block: Some(block_places(session, blocks)),
        candidates,
        unobservable,
        residual_of: "block means",
    };
    match levelled {
        Some(bias) => along_gravity(problem, session, blocks, bias),
        None => problem,
    }
}

/// Name of the accelerometer group once projected on gravity.
pub(super) const ALONG_GRAVITY: &str = "f_along_gravity_mps2";

/// A recording whose attitudes were levelled from its own accelerometers predicts gravity along the
/// measured direction: the accelerometer residuals across it carry the levelling, not the sensor. Each
/// block's three accelerometer rows (residual and every column) are replaced by their component along the
/// dwell's gravity direction `u` (`sum_c u_c row_c`, group 3, named [`ALONG_GRAVITY`]): what `|f| = g`
/// tests, free of every dwell's level. The residual is taken about the accelerometer biases `bias` the
/// dwells were levelled with (`u . (mean - bias) - g`), so the base model's biases are corrections to them.
/// Gyro rows stay.
fn along_gravity(mut p: Problem, session: &Session, blocks: &Blocks, bias: [f64; 3]) -> Problem {
    use std::collections::BTreeMap;
    let mut triads: BTreeMap<(usize, usize), [Option<usize>; 3]> = BTreeMap::new();
    let mut keep: Vec<usize> = Vec::new();
    for (i, b) in blocks.list.iter().enumerate() {
        if b.channel < 3 {
            keep.push(i);
        } else {
            triads.entry((b.dwell, b.range.0)).or_default()[b.channel - 3] = Some(i);
        }
    }
    let rows: Vec<(usize, [usize; 3])> =
        triads.into_iter().filter_map(|((dwell, _), t)| Some((dwell, [t[0]?, t[1]?, t[2]?]))).collect();
    let up = |dwell: usize| {
        let c = &session.dwells[dwell].c_tilt;
        [c[2][0], c[2][1], c[2][2]]
    };
    let project = |v: &[f64]| -> Vec<f64> {
        let mut out: Vec<f64> = keep.iter().map(|&i| v[i]).collect();
        out.extend(rows.iter().map(|(d, r)| (0..3).map(|c| up(*d)[c] * v[r[c]]).sum::<f64>()));
        out
    };
    let project_idx = |v: &[usize], accel: usize| -> Vec<usize> {
        let mut out: Vec<usize> = keep.iter().map(|&i| v[i]).collect();
        out.extend(rows.iter().map(|(_, r)| if accel == usize::MAX { v[r[0]] } else { accel }));
        out
    };
    p.obs.y = project(&p.obs.y);
    for (k, (d, _)) in rows.iter().enumerate() {
        p.obs.y[keep.len() + k] -= (0..3).map(|c| up(*d)[c] * bias[c]).sum::<f64>();
    }
    p.obs.group = project_idx(&p.obs.group, 3);
    p.obs_pose = p.obs_pose.as_ref().map(|poses| project_idx(poses, usize::MAX));
    p.obs_block = p.obs_block.as_ref().map(|b| {
        let mut out: Vec<BlockOf> = keep.iter().map(|&i| b[i]).collect();
        out.extend(rows.iter().map(|(_, r)| b[r[0]]));
        out
    });
    let pos: Vec<usize> = p.obs_pos.iter().map(|&x| x as usize).collect();
    p.obs_pos = project_idx(&pos, usize::MAX).into_iter().map(|x| x as u32).collect();
    p.base = p.base.iter().map(|c| project(c)).collect();
    // A level error of a pose moves gravity across the measured direction, which the levelling took: no
    // trace along it.
    if p.candidates.iter().any(|c| c.effect == EffectKind::PositionError) {
        p.candidates.retain(|c| c.effect != EffectKind::PositionError);
        p.unobservable
            .push(format!("{}: the attitudes are levelled from the accelerometers", EffectKind::PositionError));
    }
    for cand in p.candidates.iter_mut() {
        for (_, col) in cand.variants.iter_mut() {
            *col = col.map_dense(project);
        }
        for g in cand.groups.iter_mut().filter(|g| **g >= 3) {
            *g = 3;
        }
        cand.groups.dedup();
    }
    p.group_names[3] = ALONG_GRAVITY.into();
    p.unobservable
        .push("accelerometer terms across gravity: the attitudes are levelled from the accelerometers".into());
    p
}

/// The noise warm-ups among `effects` (docs/analysis.md#noise-warm-up), as the model fit adds them to the
/// block means' noise.
fn noise_warmups(effects: &[Effect], session: &Session) -> Vec<NoiseWarmupOf> {
    effects
        .iter()
        .filter(|e| e.effect == EffectKind::NoiseWarmup.name())
        .filter_map(|e| {
            Some(NoiseWarmupOf {
                channel: CHANNELS[e.channel()?],
                excess: e.estimate,
                settled_at_s: session.t0 + e.settled_after_s?,
                rate_hz: session.rate_hz,
            })
        })
        .collect()
}

/// Where and when each block of `blocks` lies: its dwell, its length and its middle time.
fn block_places(session: &Session, blocks: &Blocks) -> Vec<BlockOf> {
    let place = |b: &BlockObs| {
        let t = &session.dwells[b.dwell].t;
        let duration_s = (b.range.1 - b.range.0) as f64 / session.rate_hz;
        BlockOf { dwell: b.dwell, duration_s, t_mid_s: 0.5 * (t[b.range.0] + t[b.range.1 - 1]) }
    };
    blocks.list.iter().map(place).collect()
}

/// The pose of every observation: dwells whose reference attitudes agree (to 1e-9) share a pose.
fn poses(session: &Session, blocks: &Blocks) -> Vec<usize> {
    let mut attitudes: Vec<[[f64; 3]; 3]> = Vec::new();
    let pose_of_dwell: Vec<usize> = session
        .dwells
        .iter()
        .map(|d| {
            let c = d.c_b_n.unwrap_or(d.c_tilt);
            let same = |a: &[[f64; 3]; 3]| (0..9).all(|k| (a[k / 3][k % 3] - c[k / 3][k % 3]).abs() < 1e-9);
            attitudes.iter().position(same).unwrap_or_else(|| {
                attitudes.push(c);
                attitudes.len() - 1
            })
        })
        .collect();
    blocks.list.iter().map(|b| pose_of_dwell[b.dwell]).collect()
}

/// Per channel present: the RMS residual of the samples after the base model, and of its block means.
fn residual_rms(
    problem: &Problem,
    selection: &Selection,
    diagnostics: &[ChannelDiagnostics],
) -> (BTreeMap<String, f64>, BTreeMap<String, f64>) {
    let mut residual_rms = BTreeMap::new();
    let mut block_rms = BTreeMap::new();
    for c in (0..6).filter(|c| problem.obs.group.contains(c)) {
        // Samples minus the base model: the dwell's deviation from the fitted bias (block level) plus the
        // detrended part (diagnostics; along gravity, the accelerometers' mean square).
        let block = selection.base_fit.rms[c];
        let name = problem.group_names[c].clone();
        let of = |c: usize| diagnostics.iter().find(|d| d.channel == CHANNELS[c]).map_or(f64::NAN, |d| d.detrended_rms);
        let detrended_sq =
            if name == ALONG_GRAVITY { (3..6).map(|c| of(c) * of(c)).sum::<f64>() / 3.0 } else { of(c) * of(c) };
        block_rms.insert(name.clone(), block);
        residual_rms.insert(name, (detrended_sq + block * block).sqrt());
    }
    (residual_rms, block_rms)
}
