//! The recording front end: observations, candidates, selection, sample tests, result (the steps of the
//! module's flow, in order).

use std::collections::BTreeMap;

use crate::io::error::InputError;
use crate::io::recording::Recording;
use crate::stats::linfit::Observations;

use super::candidates::RecordingColumns;
use super::observations::{Blocks, Session};
use super::result::{assemble, effects_of, residuals_by_group, Findings, RECORDING};
use super::sample_tests::{measure_samples, test_samples, SampleFindings, SAMPLE_TESTS};
use super::selection::{select, Problem, Selection};
use super::{Analysis, ChannelDiagnostics, CHANNELS, CHANNEL_UNITS};

/// Analyses a recording.
pub fn analyze_recording(recording: &Recording) -> Result<Analysis, InputError> {
    recording.require_gyro("analyze")?;
    analyze_session(&Session::read(recording)?, &recording.source)
}

/// Analyses a recording that is not needed afterwards: its rows are dropped once the dwells are read, so
/// that the rows and the analysis' working data are not held at once (docs/analysis.md#speed-and-memory).
pub(super) fn analyze_recording_owned(recording: Recording) -> Result<Analysis, InputError> {
    recording.require_gyro("analyze")?;
    let session = Session::read(&recording)?;
    let source = recording.source.clone();
    drop(recording);
    analyze_session(&session, &source)
}

/// The analysis of a session read from `source`.
fn analyze_session(session: &Session, source: &str) -> Result<Analysis, InputError> {
    // The sample statistics are measured while the block observations are fitted (docs/analysis.md#speed-and-memory).
    let (blocks, problem, selection, measures) = std::thread::scope(|scope| {
        let measuring = scope.spawn(|| measure_samples(session));
        let blocks = Blocks::cut(session);
        let mut problem = problem(session, &blocks);
        let selection = select(&mut problem, SAMPLE_TESTS);
        let measures = measuring.join().unwrap_or_else(|e| std::panic::resume_unwind(e));
        (blocks, problem, selection, measures)
    });
    let selection = selection.map_err(|e| InputError::file(source, e))?;
    let m = (selection.observable + SAMPLE_TESTS) as f64;
    let mut effects = effects_of(&problem, &selection);
    let SampleFindings { effects: sample_effects, diagnostics, mut figures } = test_samples(session, &measures, m);
    effects.extend(sample_effects);
    let (residual_rms, block_residual_rms) = residual_rms(&blocks, &selection, &diagnostics);
    figures.residual_names = CHANNELS.iter().map(|s| s.to_string()).collect();
    figures.residuals = residuals_by_group(&problem, &selection);
    let findings = Findings { effects, residual_rms, block_residual_rms, m, diagnostics, figures };
    Ok(assemble(problem, selection, findings, RECORDING, source))
}

/// The block means, the base model's bias columns and the catalogue's candidates.
fn problem(session: &Session, blocks: &Blocks) -> Problem {
    let mut unobservable = Vec::new();
    let (base, base_names) = blocks.base_columns(&mut unobservable);
    let candidates = RecordingColumns::new(session, blocks).candidates(&mut unobservable);
    Problem {
        obs: Observations { y: blocks.y.clone(), group: blocks.group.clone(), groups: 6, sigma: None },
        base,
        base_names,
        group_names: CHANNELS.iter().map(|s| s.to_string()).collect(),
        group_units: CHANNEL_UNITS.to_vec(),
        obs_pos: blocks.obs_pos.clone(),
        candidates,
        unobservable,
        residual_of: "block means",
    }
}

/// Per channel present: the RMS residual of the samples after the base model, and of its block means.
fn residual_rms(
    blocks: &Blocks,
    selection: &Selection,
    diagnostics: &[ChannelDiagnostics],
) -> (BTreeMap<String, f64>, BTreeMap<String, f64>) {
    let mut residual_rms = BTreeMap::new();
    let mut block_rms = BTreeMap::new();
    for c in (0..6).filter(|&c| blocks.present[c]) {
        // Samples minus the base model: the dwell's deviation from the fitted bias (block level) plus the
        // detrended part (diagnostics).
        let block = selection.base_fit.rms[c];
        block_rms.insert(CHANNELS[c].to_string(), block);
        let detrended_rms = diagnostics[c].detrended_rms;
        residual_rms.insert(CHANNELS[c].to_string(), (detrended_rms * detrended_rms + block * block).sqrt());
    }
    (residual_rms, block_rms)
}
