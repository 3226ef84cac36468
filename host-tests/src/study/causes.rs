//! Naming the cause: each test of a study whose number leaves what white noise and the base model explain gives
//! a [`Cause`] with that number in words; the causes are ranked by how far the number is from the base model.

use super::{unit_of, Cause, ChannelNoise, PoseStudy, Study, Sway, CHANNELS, CORRELATED_RATIO, POSE_SPREAD_RATIO};
use crate::io::ARCSEC_PER_RAD;
use crate::model::synth::MICRO_G;

/// A cause with its strength (how many times what the base model explains; the ranking key).
type Ranked = (f64, Cause);

/// Names the causes the numbers of a study show, strongest first.
pub fn name_causes(s: &Study) -> Vec<Cause> {
    let mut causes: Vec<Ranked> = Vec::new();
    if let Some(p) = &s.poses {
        causes.extend(accel_pose_cause(p));
        causes.extend(gyro_pose_cause(p));
        causes.extend(turn_causes(p));
    }
    causes.extend(s.sway.iter().filter_map(sway_cause));
    for ch in &s.noise {
        causes.extend(faster_than_white_cause(ch));
        causes.extend(correlated_noise_cause(ch));
    }
    causes.sort_by(|a, b| b.0.total_cmp(&a.0));
    causes.into_iter().map(|c| c.1).collect()
}

/// The accelerometer pose norms scatter more than [`POSE_SPREAD_RATIO`] times white noise: scale factors and
/// misalignments when the extended model cuts the held-out RMS by more than 2, else an unexplained pose error.
fn accel_pose_cause(p: &PoseStudy) -> Option<Ranked> {
    let ratio = Some(p.norm_rms_data_mps2 / p.norm_rms_noise_mps2).filter(|r| *r > POSE_SPREAD_RATIO)?;
    let gain = p.held_out_norm_rms_base_mps2 / p.held_out_norm_rms_extended_mps2;
    let sf = p.extended_accel.scale_factors();
    let a = &p.extended_accel.matrix;
    let name = if gain > 2.0 {
        "accel scale factors and misalignments".to_string()
    } else {
        "accel pose-dependent error not explained by scale factors and misalignments".to_string()
    };
    let evidence = format!(
        "|mean f - b| - g over the poses: RMS {:.4} m/s^2 = {:.0} x the {:.2e} m/s^2 that white noise \
         gives (bias-only base model); fitted scale factors {:+.4} {:+.4} {:+.4}, misalignments \
         A_yx {:+.4} A_zx {:+.4} A_zy {:+.4} (dimensionless); held-out RMS {:.4} -> {:.4} m/s^2 \
         ({:.0} x smaller)",
        p.norm_rms_data_mps2,
        ratio,
        p.norm_rms_noise_mps2,
        sf[0],
        sf[1],
        sf[2],
        a[1][0],
        a[2][0],
        a[2][1],
        p.held_out_norm_rms_base_mps2,
        p.held_out_norm_rms_extended_mps2,
        gain
    );
    Some((ratio, Cause { name, channels: "ax ay az".to_string(), evidence }))
}

/// The gyro pose means scatter more than [`POSE_SPREAD_RATIO`] times white noise: named after the per-pose
/// model that beats a constant bias on the held-out poses by more than 20 %, if one does.
fn gyro_pose_cause(p: &PoseStudy) -> Option<Ranked> {
    let gratio = Some(p.gyro_spread_rms_radps / p.gyro_spread_noise_radps).filter(|r| *r > POSE_SPREAD_RATIO)?;
    let (name, detail) = gyro_model_verdict(&p.gyro_models_held_out_radps);
    let evidence = format!(
        "per-pose gyro means scatter by {:.4} deg/s RMS, {:.1} x the {:.4} deg/s white noise gives{detail}",
        p.gyro_spread_rms_radps.to_degrees(),
        gratio,
        p.gyro_spread_noise_radps.to_degrees()
    );
    Some((gratio, Cause { name, channels: "gx gy gz".to_string(), evidence }))
}

/// The name of the gyro pose cause and the held-out numbers behind it, from the held-out RMS of each per-pose
/// model (rad/s).
fn gyro_model_verdict(models: &[(&'static str, f64)]) -> (String, String) {
    let constant = models.iter().find(|m| m.0 == "constant bias").map(|m| m.1);
    let best = models.iter().min_by(|a, b| a.1.total_cmp(&b.1));
    match (constant, best) {
        (Some(c), Some(b)) if b.0 != "constant bias" && b.1 < 0.8 * c => (
            format!("gyro {}", b.0.trim_start_matches("bias + ")),
            format!(
                "; on the odd poses the {} model leaves {:.4} deg/s RMS against {:.4} deg/s for a constant \
                 bias",
                b.0,
                b.1.to_degrees(),
                c.to_degrees()
            ),
        ),
        (Some(c), Some(_)) => (
            "gyro bias varying from pose to pose (not drift, not g-sensitivity)".to_string(),
            format!(
                "; neither drift nor g-sensitivity beats a constant bias on the odd poses ({:.4} deg/s RMS)",
                c.to_degrees()
            ),
        ),
        _ => ("gyro bias varying from pose to pose".to_string(), String::new()),
    }
}

/// A labelled full turn whose integrated angle is more than 0.5 % off 360 deg: a gyro scale factor.
fn turn_causes(p: &PoseStudy) -> Vec<Ranked> {
    p.turns
        .iter()
        .filter(|t| t.scale_factor.abs() > 0.005)
        .map(|t| {
            let evidence = format!(
                "{}: the gyro integrates {:.1} deg ({:.1} deg raw) over a labelled full turn: scale \
                 factor {:+.4} (if the turn is exactly 360 deg)",
                t.label,
                t.angle_rad.to_degrees(),
                t.raw_angle_rad.to_degrees(),
                t.scale_factor
            );
            let cause =
                Cause { name: "gyro scale factor".to_string(), channels: CHANNELS[t.axis].to_string(), evidence };
            (t.scale_factor.abs() * 100.0, cause)
        })
        .collect()
}

/// A sway pair correlated above 0.5: the vehicle sways (real tilt motion).
fn sway_cause(sw: &Sway) -> Option<Ranked> {
    let correlation = Some(sw.correlation).filter(|c| *c > 0.5)?;
    let evidence = format!(
        "high-passed 1-s means: correlation {:.3}, slope {:.2} m/s^2/rad (g = tilt), accel RMS {:.0} \
         ug, tilt RMS {:.1} arcsec",
        sw.correlation,
        sw.slope_mps2_per_rad,
        sw.accel_rms_mps2 / MICRO_G,
        sw.tilt_rms_rad * ARCSEC_PER_RAD
    );
    let cause = Cause { name: "vehicle sway (real tilt motion)".to_string(), channels: sw.pair.to_string(), evidence };
    Some((10.0 * correlation, cause))
}

/// The data's ADEV at the long tau below 1 / [`CORRELATED_RATIO`] of the white SIMULATION's: the per-sample
/// scatter averages faster than white noise.
fn faster_than_white_cause(ch: &ChannelNoise) -> Option<Ranked> {
    Some(ch.ratio_at_long_tau).filter(|r| *r < 1.0 / CORRELATED_RATIO)?;
    let (u, uname) = unit_of(ch.channel);
    let (data, sim) = ch.adev_at_long_tau();
    let evidence = format!(
        "ADEV at tau {:.1} s: data {:.4} {uname}, white-noise SIMULATION {:.4} {uname} ({:.2} x): the \
         per-sample scatter does not average like white noise",
        ch.long_tau_s,
        data / u,
        sim / u,
        ch.ratio_at_long_tau
    );
    let name = "sample-to-sample noise not white (averages faster: quantisation / vibration)".to_string();
    Some((1.0 / ch.ratio_at_long_tau, Cause { name, channels: ch.channel.to_string(), evidence }))
}

/// The data's ADEV at the long tau above [`CORRELATED_RATIO`] times the white SIMULATION's: correlated noise,
/// named after the extension's dominant term, with the extension's held-out gain when there is one.
fn correlated_noise_cause(ch: &ChannelNoise) -> Option<Ranked> {
    Some(ch.ratio_at_long_tau).filter(|r| *r > CORRELATED_RATIO)?;
    let (u, uname) = unit_of(ch.channel);
    let term = ch.extended.as_ref().map_or("correlated noise", |e| e.dominant_term);
    let name = match term {
        "white" | "quantization" => "correlated noise".to_string(),
        other => format!("correlated noise ({other})"),
    };
    let gain = ch.extended.as_ref().map_or(String::new(), |e| {
        format!(
            "; held-out RMS log10(ADEV sim/data) {:.3} (base) -> {:.3} (extended)",
            e.held_out_rms_log10_base, e.held_out_rms_log10_extended
        )
    });
    let (data, sim) = ch.adev_at_long_tau();
    let evidence = format!(
        "ADEV at tau {:.1} s: data {:.4} {uname}, white-noise SIMULATION {:.4} {uname} ({:.1} x){gain}",
        ch.long_tau_s,
        data / u,
        sim / u,
        ch.ratio_at_long_tau
    );
    Some((ch.ratio_at_long_tau, Cause { name, channels: ch.channel.to_string(), evidence }))
}
