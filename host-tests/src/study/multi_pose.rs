//! The multi-pose studies (the imucal Ferraris session, the imu_tk Xsens session): the static poses, the six
//! channels' noise (pooled white std, Allan deviation on the longest pose), the accelerometer models and the
//! gyro pose means against the base model and its SIMULATION, the extensions and their gain on held-out poses,
//! the Ferraris turns and the imu_tk factory comparison.

use super::accel::{fit_models, held_out_base, held_out_of, simulate_pose_norms, ExtendedFit};
use super::accel_gate::{gate, term_names};
use super::causes::name_causes;
use super::factory::factory_comparison;
use super::gyro::{gyro_models, gyro_spread, integrate_turns};
use super::noise::{channel_noise, white_std};
use super::{channel_value, rms, ChannelNoise, LabelledTurn, Pose, PoseStudy, Study, CHANNELS};
use crate::io::error::InputError;
use crate::io::import::{position_stats, FERRARIS_POSES};
use crate::io::recording::{Dwell, Recording};

/// How the poses' orientations are known.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PoseKind {
    /// Each pose has a known up axis, from its recorded pitch and roll (imucal labels, a turntable); the turns
    /// are labelled too.
    Labelled,
    /// No labels: only |f| = g is known (imu_tk).
    Unlabelled,
}

/// Study of a multi-pose recording: the six channels' noise on the longest pose, the per-pose accelerometer
/// norms and gyro means against the base model and its SIMULATION, the extended accelerometer model and its gain
/// on held-out poses, the gyro per-pose models; `turns` are the Ferraris turns as (label, axis, sample range).
pub fn study_multi_pose(
    rec: &Recording,
    kind: PoseKind,
    gravity_mps2: f64,
    dataset: &str,
    sources: Vec<String>,
    seed: u64,
    turns: &[LabelledTurn],
) -> Result<Study, InputError> {
    let g = gravity_mps2;
    let rate_hz = rec.header.rate_hz.unwrap_or(100.0);
    let dwells = rec.dwells();
    if dwells.len() < 6 {
        return Err(InputError::file(&rec.source, format!("{} static poses: a study needs at least 6", dwells.len())));
    }
    let (noise, sigma) = pose_noise(&dwells, rate_hz, seed);
    let mut poses = static_poses(rec, kind, dataset);
    let means: Vec<[f64; 3]> = poses.iter().map(|p| p.mean_force_mps2).collect();
    let ups: Vec<[f64; 3]> = poses.iter().map(|p| p.up_b.unwrap_or([0.0, 0.0, 1.0])).collect();
    let (base, extended, method) = fit_models(kind, &means, &ups, g, &rec.source)?;
    let fit = ExtendedFit {
        kind,
        means: &means,
        ups: &ups,
        samples: poses.iter().map(|p| p.samples).collect(),
        held_out: poses.iter().map(|p| p.held_out).collect(),
        g,
    };
    // The held-out gate keeps the terms of the extended model that the held-out poses need.
    let accel_gate = gate(&fit, [sigma[3], sigma[4], sigma[5]]);
    let free = accel_gate.as_ref().map_or_else(|| vec![true; term_names(kind).len()], |a| a.free.clone());
    let ext_res: Vec<f64> = held_out_of(&fit, &free)
        .ok_or_else(|| InputError::file(&rec.source, "the poses held out leave too few to fit the extended model"))?
        .into_iter()
        .map(|(_, r)| r)
        .collect();
    let (accel_term_gate, extended) = accel_gate.map_or((Vec::new(), extended), |a| (a.verdicts, a.model));
    let (held_out_rule, base_res) = held_out_base(&fit, &mut poses);
    simulate_pose_norms(&mut poses, &base, &extended, g, [sigma[3], sigma[4], sigma[5]], seed);
    let (spread, spread_noise) = gyro_spread(&poses, [sigma[0], sigma[1], sigma[2]]);
    let (gyro_models_held_out_radps, gyro_g_sensitivity) =
        if kind == PoseKind::Unlabelled { gyro_models(&poses) } else { (Vec::new(), None) };
    let labelled_turns = turns;
    let turns = integrate_turns(rec, &poses, turns);
    let factory = (dataset == "imutk").then(|| factory_comparison(&extended));
    let rotations = match dataset {
        "ferraris" => Some(super::rotations::ferraris_rotations(rec, labelled_turns)?),
        "imutk" => Some(super::rotations::imutk_rotations(rec)?),
        _ => None,
    };
    let pose_study = PoseStudy {
        gravity_mps2: g,
        method,
        norm_rms_data_mps2: rms(poses.iter().map(|p| p.norm_minus_g_data_mps2)),
        norm_rms_noise_mps2: rms(poses.iter().map(|p| p.norm_noise_std_mps2)),
        held_out_norm_rms_base_mps2: rms(base_res),
        held_out_norm_rms_extended_mps2: rms(ext_res),
        held_out_rule,
        gyro_spread_rms_radps: spread,
        gyro_spread_noise_radps: spread_noise,
        gyro_models_held_out_radps,
        gyro_g_sensitivity,
        turns,
        factory,
        rotations,
        poses,
        base_accel: base,
        extended_accel: extended,
        accel_term_gate,
    };
    let mut study = Study {
        dataset: dataset.to_string(),
        sources,
        seed,
        rate_hz,
        noise,
        sway: Vec::new(),
        poses: Some(pose_study),
        causes: Vec::new(),
    };
    study.causes = name_causes(&study);
    Ok(study)
}

/// The six channels' noise of a multi-pose record: the white std pooled over the static poses (returned beside,
/// SI) and the Allan deviation of the longest pose against its base SIMULATION (no extension: poses are short).
fn pose_noise(dwells: &[Dwell<'_>], rate_hz: f64, seed: u64) -> (Vec<ChannelNoise>, [f64; 6]) {
    let seg = |d: &Dwell<'_>, c: usize| -> Vec<f64> { d.rows.iter().map(|r| channel_value(r, c)).collect() };
    let longest = dwells.iter().max_by_key(|d| d.rows.len()).expect("non-empty");
    let mut noise = Vec::new();
    let mut sigma = [0.0; 6];
    for c in 0..6 {
        let segs: Vec<Vec<f64>> = dwells.iter().map(|d| seg(d, c)).collect();
        let refs: Vec<&[f64]> = segs.iter().map(|s| s.as_slice()).collect();
        sigma[c] = white_std(&refs);
        let mut ch = channel_noise(CHANNELS[c], &seg(longest, c), rate_hz, seed, c as u64 * 1000);
        ch.extended = None;
        ch.white_std = sigma[c];
        noise.push(ch);
    }
    (noise, sigma)
}

/// The static poses of `rec` with their means, named (the Ferraris labels for the `ferraris` data set) and, when
/// labelled, given the up axes of their recorded pitch and roll; the norms are filled in later; the odd poses
/// (1, 3, ... in record order) are marked held out.
fn static_poses(rec: &Recording, kind: PoseKind, dataset: &str) -> Vec<Pose> {
    position_stats(rec)
        .iter()
        .enumerate()
        .map(|(k, s)| Pose {
            pos: s.pos,
            name: match kind {
                PoseKind::Labelled if dataset == "ferraris" => FERRARIS_POSES
                    .iter()
                    .find(|p| p.pos == s.pos)
                    .map_or(format!("pose {}", s.pos), |p| p.label.to_string()),
                _ => format!("pose {}", s.pos),
            },
            samples: s.samples,
            t_mid_s: 0.5 * (s.first_t_s + s.last_t_s),
            mean_rate_radps: s.mean_rate_b_radps,
            mean_force_mps2: s.mean_force_b_mps2,
            up_b: if kind == PoseKind::Labelled { Some(labelled_up(s.pitch_deg, s.roll_deg)) } else { None },
            norm_minus_g_data_mps2: 0.0,
            norm_minus_g_base_sim_mps2: 0.0,
            norm_minus_g_extended_sim_mps2: 0.0,
            norm_minus_g_extended_mps2: 0.0,
            norm_noise_std_mps2: 0.0,
            held_out: k % 2 == 1,
        })
        .collect()
}

/// The up direction in the body of a pose of labelled pitch and roll, deg (exact zeros kept).
fn labelled_up(pitch_deg: f64, roll_deg: f64) -> [f64; 3] {
    let (st, ct) = pitch_deg.to_radians().sin_cos();
    let (sg, cg) = roll_deg.to_radians().sin_cos();
    [-sg * ct, st, cg * ct].map(|v: f64| if v.abs() < 1e-12 { 0.0 } else { v })
}
