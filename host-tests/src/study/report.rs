//! The report of `sinscal study` (docs/cli.md#study): the human summary (Markdown, one function per section),
//! the machine-readable JSON (schema [`SCHEMA`]) and the PNG figures (Allan deviation panels, per-pose norms and
//! gyro means). Every simulated number is labelled SIMULATION.

use std::fmt::Write as _;
use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;
use serde_json::{json, Map, Value};

use crate::io::ARCSEC_PER_RAD;
use crate::model::synth::MICRO_G;
use crate::plot::{figure, Png};
use crate::stats::noise::NoiseTerms;
use crate::study::noise_extension::{ExtraTerm, TermGate, GATE_MIN_DELTA_CHI2, GATE_MIN_RELATIVE_RISE};
use crate::study::rests::rms;
use crate::study::rotations::{RotationFit, RotationStudy};
use crate::study::{
    unit_of, ChannelNoise, Curve, FactoryComparison, NoiseExtension, Pose, PoseStudy, Study, CHANNELS, SCHEMA,
};

/// Writes the report of a study into `report_dir` (created if needed): the figures, `summary.md` (also printed
/// to stdout, unless the JSON goes there) and, with `json_path`, the JSON ('-' = stdout).
pub fn write_report(study: &Study, report_dir: &Path, json_path: Option<&Path>) -> anyhow::Result<()> {
    std::fs::create_dir_all(report_dir).map_err(|e| anyhow::anyhow!("cannot create {}: {e}", report_dir.display()))?;
    eprintln!("study {}: figures", study.dataset);
    let figures = write_figures(study, report_dir)?;
    let text = summary_markdown(study, &figures);
    let md = report_dir.join("summary.md");
    std::fs::write(&md, &text).map_err(|e| anyhow::anyhow!("cannot write {}: {e}", md.display()))?;
    let to_stdout = json_path == Some(Path::new("-"));
    if !to_stdout {
        crate::io::out(&format!("{text}\nreport: {}\n", md.display()))?;
    }
    if let Some(path) = json_path {
        let mut out = serde_json::to_string_pretty(&study_json(study, &figures))?;
        out.push('\n');
        if to_stdout {
            crate::io::out(&out)?;
        } else {
            std::fs::write(path, out).map_err(|e| anyhow::anyhow!("cannot write {}: {e}", path.display()))?;
        }
    }
    Ok(())
}

// ---------------------------------------------------------------------------------------------------------------
// Summary (Markdown)

/// `[x, y, z]` of `v / scale` with `prec` decimals.
fn fmt3(v: [f64; 3], scale: f64, prec: usize) -> String {
    format!("[{:.p$}, {:.p$}, {:.p$}]", v[0] / scale, v[1] / scale, v[2] / scale, p = prec)
}

/// The human summary (Markdown; also printed to stdout). `figures` are the PNG file names to link.
pub fn summary_markdown(s: &Study, figures: &[String]) -> String {
    let mut o = String::new();
    header_section(&mut o, s);
    base_model_section(&mut o, s);
    noise_disagreement_section(&mut o, s);
    if let Some(p) = &s.poses {
        pose_disagreement(&mut o, p);
    }
    cause_section(&mut o, s);
    extended_noise_section(&mut o, s);
    if let Some(p) = &s.poses {
        extended_pose_models(&mut o, p);
    }
    gain_section(&mut o, s);
    if let Some(p) = &s.poses {
        factory_section(&mut o, p);
        if let Some(r) = &p.rotations {
            rotations_section(&mut o, r);
        }
    }
    figures_section(&mut o, figures);
    o
}

/// Title, the data read, the seed.
fn header_section(o: &mut String, s: &Study) {
    let _ = writeln!(o, "# sinscal study: {}\n", s.dataset);
    let _ = writeln!(o, "Measured data: {} ({} Hz).", s.sources.join(", "), s.rate_hz);
    let _ = writeln!(
        o,
        "Every SIMULATION below is seeded (seed {}) and uses the data's own sample times and poses; it is not \
         measured data.\n",
        s.seed
    );
}

/// 1. The base model: white noise per channel; for the pose sets, the pose means of a bias-only sensor.
fn base_model_section(o: &mut String, s: &Study) {
    let _ = writeln!(o, "## 1. Base model\n");
    let _ = writeln!(
        o,
        "Each static pose: a constant mean per channel plus white noise. White-noise standard deviation per sample = \
         overlapping Allan deviation at one sample = RMS of first differences / sqrt 2, pooled over the static poses:"
    );
    for ch in &s.noise {
        let (u, name) = if ch.channel.starts_with('g') { (1f64.to_radians(), "deg/s") } else { (1.0, "m/s^2") };
        let _ = writeln!(o, "- {}: {:.4e} {name} per sample", ch.channel, ch.white_std / u);
    }
    if let Some(p) = &s.poses {
        let _ = writeln!(
            o,
            "\nPose means of the base model: accelerometer = g ({:.5} m/s^2) along the pose's up direction + one bias \
             (bias-only sensor, {}), gyro = one constant bias. Base accelerometer bias {} m/s^2.",
            p.gravity_mps2,
            if p.method.starts_with("labelled") { "labelled up axes" } else { "direction from the data, |f| = g" },
            fmt3(p.base_accel.bias_mps2, 1.0, 4)
        );
    }
}

/// 2.-3. The Allan deviation of the data against the base SIMULATION per channel, and the sway tests.
fn noise_disagreement_section(o: &mut String, s: &Study) {
    let _ = writeln!(o, "\n## 2.-3. Data against the base SIMULATION\n");
    let _ = writeln!(
        o,
        "Allan deviation ({}): ratio data / base SIMULATION at the longest tau with at least 9 clusters, and RMS over \
         tau of log10(ADEV SIMULATION / ADEV data):",
        if s.poses.is_some() { "longest static pose" } else { "whole record" }
    );
    let _ = writeln!(o, "\n| channel | tau [s] | data ADEV | base SIM ADEV | ratio | RMS log10 | quantisation step |");
    let _ = writeln!(o, "|---|---|---|---|---|---|---|");
    for ch in &s.noise {
        let (u, name) = unit_of(ch.channel);
        let (data, sim) = ch.adev_at_long_tau();
        let q = ch.quantization_step.map_or("-".to_string(), |q| format!("{:.4} {name}", q / u));
        let _ = writeln!(
            o,
            "| {} | {:.2} | {:.4} {name} | {:.4} {name} | {:.2} | {:.3} | {q} |",
            ch.channel,
            ch.long_tau_s,
            data / u,
            sim / u,
            ch.ratio_at_long_tau,
            ch.rms_log10_base
        );
    }
    for sw in &s.sway {
        let _ = writeln!(
            o,
            "\nSway test {}: high-passed (61 s) 1-s means, correlation {:.3}, slope {:.2} m/s^2 per rad (a real tilt \
             gives g), accelerometer RMS {:.0} ug, tilt RMS {:.2} arcsec.",
            sw.pair,
            sw.correlation,
            sw.slope_mps2_per_rad,
            sw.accel_rms_mps2 / MICRO_G,
            sw.tilt_rms_rad * ARCSEC_PER_RAD
        );
    }
}

/// 2.-3. for the pose sets: per pose |mean f - b| - g of the data and the SIMULATIONs, the gyro pose means, the
/// turns.
fn pose_disagreement(o: &mut String, p: &PoseStudy) {
    let _ = writeln!(
        o,
        "\nPer-pose |mean f - b| - g [m/s^2] (b = base bias): data, base SIMULATION, extended SIMULATION; white \
         noise std of the norm:"
    );
    let _ = writeln!(o, "\n| pose | samples | data | base SIM | extended SIM | noise std | extended-calibrated data |");
    let _ = writeln!(o, "|---|---|---|---|---|---|---|");
    for q in &p.poses {
        let _ = writeln!(
            o,
            "| {} | {} | {:+.4} | {:+.4} | {:+.4} | {:.1e} | {:+.4} |",
            q.name,
            q.samples,
            q.norm_minus_g_data_mps2,
            q.norm_minus_g_base_sim_mps2,
            q.norm_minus_g_extended_sim_mps2,
            q.norm_noise_std_mps2,
            q.norm_minus_g_extended_mps2
        );
    }
    let _ = writeln!(
        o,
        "\nRMS over poses: data {:.4} m/s^2 against {:.2e} m/s^2 of white noise ({:.0} x).",
        p.norm_rms_data_mps2,
        p.norm_rms_noise_mps2,
        p.norm_rms_data_mps2 / p.norm_rms_noise_mps2
    );
    let _ = writeln!(
        o,
        "Gyro per-pose means: RMS scatter {:.5} deg/s against {:.5} deg/s from white noise ({:.1} x).",
        p.gyro_spread_rms_radps.to_degrees(),
        p.gyro_spread_noise_radps.to_degrees(),
        p.gyro_spread_rms_radps / p.gyro_spread_noise_radps
    );
    for t in &p.turns {
        let _ = writeln!(
            o,
            "Turn {} ({:.2} s): gyro {} integrates {:.1} deg raw, {:.1} deg with the static bias removed.",
            t.label,
            t.duration_s,
            CHANNELS[t.axis],
            t.raw_angle_rad.to_degrees(),
            t.angle_rad.to_degrees()
        );
    }
}

/// 4. The causes, strongest first.
fn cause_section(o: &mut String, s: &Study) {
    let _ = writeln!(o, "\n## 4. Cause\n");
    if s.causes.is_empty() {
        let _ = writeln!(o, "None: the base model agrees with the data within the noise.");
    }
    for c in &s.causes {
        let _ = writeln!(o, "- **{}** ({}): {}", c.name, c.channels, c.evidence);
    }
}

/// 5. The extended noise model per channel (single-pose records) and its generator.
fn extended_noise_section(o: &mut String, s: &Study) {
    let _ = writeln!(o, "\n## 5. Extended model\n");
    for ch in &s.noise {
        if let Some(e) = &ch.extended {
            let t = &e.terms_all;
            let (gyro, (u, name)) = (ch.channel.starts_with('g'), unit_of(ch.channel));
            let _ = writeln!(
                o,
                "- {} IEEE 952 terms (whole record; SI): Q {:.3e} {}, N {:.3e} {}, B {:.3e} {} ({:.4} {name}), K {:.3e} \
                 {}, R {:.3e} {}; dominant at long tau: {}",
                ch.channel,
                t.quantization_q,
                if gyro { "rad" } else { "m/s" },
                t.random_walk_n,
                if gyro { "rad/sqrt(s)" } else { "m/s/sqrt(s)" },
                t.bias_instability_b,
                if gyro { "rad/s" } else { "m/s^2" },
                t.bias_instability_b / u,
                t.rate_random_walk_k,
                if gyro { "rad/s/sqrt(s)" } else { "m/s^2/sqrt(s)" },
                t.ramp_r,
                if gyro { "rad/s^2" } else { "m/s^3" },
                e.dominant_term
            );
            if let Some(x) = &e.extra_all {
                let _ = writeln!(o, "  plus {}", x.describe(if gyro { "rad/s" } else { "m/s^2" }));
            }
            gate_lines(o, e);
        }
    }
    if s.noise.iter().any(|c| c.extended.is_some()) {
        let _ = writeln!(
            o,
            "\nGenerator: quantisation as differenced white angle noise, white noise, bias instability as a sum of \
             Gauss-Markov processes (two per decade), rate random walk, ramp, and the band-limited term (Gauss-Markov \
             or sinusoid with random phase) where it lowers the weighted Allan residual by more than 20 %. Held-out \
             gate: the model is fitted on the first half; a term (other than white) stays only when refitting the \
             first half without it raises the second half's chi^2 = sum of (ln(ADEV data / ADEV model) / relative \
             uncertainty)^2 by at least max({GATE_MIN_DELTA_CHI2}, {:.0} % of the chi^2 with it); the weakest \
             term leaves first, one at a time. The kept terms are refitted on the whole record.",
            100.0 * GATE_MIN_RELATIVE_RISE
        );
    }
}

/// The held-out gate's verdicts of one channel: the kept terms, then the dropped ones with why.
fn gate_lines(o: &mut String, e: &NoiseExtension) {
    verdict_lines(o, &e.gate, " (besides white)");
}

/// Verdicts of a held-out gate: the kept terms (`besides`: what is kept without a verdict), the dropped ones,
/// then each with why.
fn verdict_lines(o: &mut String, gate: &[TermGate], besides: &str) {
    let names = |kept: bool| -> Vec<&str> { gate.iter().filter(|g| g.kept == kept).map(|g| g.term.as_str()).collect() };
    let (kept, dropped) = (names(true), names(false));
    let list = |v: &[&str]| if v.is_empty() { "none".to_string() } else { v.join(", ") };
    let _ = writeln!(o, "  held-out gate: kept {}{besides}; dropped {}", list(&kept), list(&dropped));
    for g in gate {
        let _ = writeln!(o, "  - {} {}: {}", if g.kept { "kept" } else { "dropped" }, g.term, g.reason);
    }
}

/// 5. for the pose sets: the extended accelerometer model, the gyro g-sensitivity, the turns' scale factors.
fn extended_pose_models(o: &mut String, p: &PoseStudy) {
    let a = &p.extended_accel.matrix;
    let _ = writeln!(o, "Accelerometer, {}, fitted on all poses:", p.method);
    let _ = writeln!(o, "- bias {} m/s^2", fmt3(p.extended_accel.bias_mps2, 1.0, 4));
    let _ = writeln!(o, "- scale factors {} (dimensionless)", fmt3(p.extended_accel.scale_factors(), 1.0, 5));
    let _ = writeln!(
        o,
        "- A (f_meas = A f + b, dimensionless): [[{:.5}, {:+.5}, {:+.5}], [{:+.5}, {:.5}, {:+.5}], [{:+.5}, {:+.5}, \
         {:.5}]]",
        a[0][0], a[0][1], a[0][2], a[1][0], a[1][1], a[1][2], a[2][0], a[2][1], a[2][2]
    );
    if let Some(gs) = &p.gyro_g_sensitivity {
        let _ = writeln!(
            o,
            "- gyro g-sensitivity (fitted on all poses), (deg/s)/(m/s^2): [{}, {}, {}]",
            fmt3(gs[0], 1f64.to_radians(), 5),
            fmt3(gs[1], 1f64.to_radians(), 5),
            fmt3(gs[2], 1f64.to_radians(), 5)
        );
    }
    for t in &p.turns {
        let _ = writeln!(
            o,
            "- gyro scale factor {} from {}: {:+.4} (dimensionless)",
            CHANNELS[t.axis], t.label, t.scale_factor
        );
    }
}

/// 6. The gain of the extensions on data not used for the fit.
fn gain_section(o: &mut String, s: &Study) {
    let _ = writeln!(o, "\n## 6. Gain on data not used for the fit\n");
    for ch in &s.noise {
        if let Some(e) = &ch.extended {
            let _ = writeln!(
                o,
                "- {}: second half, RMS log10(ADEV SIMULATION / ADEV data): base {:.3}, extended {:.3}; chi^2 of the \
                 model's ADEV over {} Allan points: base {:.1}, extended {:.1} (dimensionless)",
                ch.channel,
                e.held_out_rms_log10_base,
                e.held_out_rms_log10_extended,
                e.held_out_points,
                e.held_out_chi2_base,
                e.held_out_chi2_extended
            );
        }
    }
    if let Some(p) = &s.poses {
        let _ = writeln!(
            o,
            "- accelerometer, {}: RMS(|f calibrated| - g) base {:.4} m/s^2, extended {:.4} m/s^2 ({:.1} x smaller)",
            p.held_out_rule,
            p.held_out_norm_rms_base_mps2,
            p.held_out_norm_rms_extended_mps2,
            p.held_out_norm_rms_base_mps2 / p.held_out_norm_rms_extended_mps2
        );
        verdict_lines(o, &p.accel_term_gate, " (besides the biases)");
        for (name, v) in &p.gyro_models_held_out_radps {
            let _ = writeln!(o, "- gyro per-pose means, odd poses, {name}: RMS residual {:.5} deg/s", v.to_degrees());
        }
        if !p.turns.is_empty() {
            let _ = writeln!(
                o,
                "- gyro scale factors: one turn per axis, so no turn is held out of a fit of the turns; the hand \
                 moves between the poses are (section 8)."
            );
        }
    }
}

/// 7. imu_tk: the fitted accelerometer against the factory calibration (when there is one).
fn factory_section(o: &mut String, p: &PoseStudy) {
    let Some(f) = &p.factory else { return };
    let _ = writeln!(o, "\n## 7. imu_tk: fitted against the factory calibration\n");
    let _ = writeln!(
        o,
        "Both in the lower-triangular gauge K = L Q (counts = K f + offset; the rotation Q is not observable \
         from |f| = g), g = {} m/s^2. The importer's nominal gains [415, 413, 415] counts/(m/s^2) are undone: \
         counts = diag(nominal) A f + 32768 + nominal b.",
        p.gravity_mps2
    );
    let _ = writeln!(o, "\n| quantity | fitted | factory (diag(gain) M) | factory (diag(gain) M^-1) |");
    let _ = writeln!(o, "|---|---|---|---|");
    let _ = writeln!(
        o,
        "| gain x, y, z [counts/(m/s^2)] | {} | {} | |",
        fmt3(f.fitted_gain_counts_per_mps2, 1.0, 2),
        fmt3(f.factory_gain_counts_per_mps2, 1.0, 2)
    );
    let _ = writeln!(
        o,
        "| misalignment L10/L11, L20/L22, L21/L22 | {} | {} | {} |",
        fmt3(f.fitted_misalignment, 1.0, 4),
        fmt3(f.factory_misalignment, 1.0, 4),
        fmt3(f.factory_misalignment_inverse, 1.0, 4)
    );
    let _ = writeln!(o, "| offset [counts] | {} | not given | |", fmt3(f.fitted_offset_counts, 1.0, 1));
}

/// 8. The gyro matrix from the rotations beside the reference, and each calibration's checks on the rests.
fn rotations_section(o: &mut String, r: &RotationStudy) {
    let _ = writeln!(o, "\n## 8. Gyro matrix from the rotations (docs/method.md#moves)\n");
    let _ = writeln!(
        o,
        "Each fit is `sinscal calibrate --model full` itself (the study has no fit of its own), with some moves \
         held out where named: T_g = I + S + M, row i = gyro i, ± its standard error. Reference: {}. Each \
         calibration is checked on the session's rests (docs/method.md#held-out-moves): the gravity direction \
         carried by the compensated gyros across every motion between two rests, against the one measured after \
         it, and |f| - g of the rests without a label.",
        r.reference_name
    );
    for f in &r.fits {
        fit_section(o, r, f);
    }
    for (name, why) in &r.refused {
        let _ = writeln!(o, "\n**Fitted on {name}: refused** ({why}).");
    }
}

/// One fit of section 8: its matrix beside the reference, its transitions and rests.
fn fit_section(o: &mut String, r: &RotationStudy, f: &RotationFit) {
    let cell = |v: f64, e: Option<f64>| match e {
        Some(e) => format!("{v:+.5} ± {e:.5}"),
        None => format!("{v:+.5}"),
    };
    let _ = writeln!(
        o,
        "\n**Fitted on {}**: `{}` ({} moves and turns, {} passes; chi-square {:.1} on {} degrees of freedom; hand \
         moves' error {:.3} deg; checks {})\n",
        f.name,
        f.command,
        f.rotations,
        f.passes,
        f.chi_square,
        f.degrees_of_freedom,
        f.move_error_deg,
        if f.checks_passed { "all passed" } else { "FAILED" }
    );
    let _ = writeln!(o, "| T_g | x | y | z | reference x | y | z |\n|---|---|---|---|---|---|---|");
    for i in 0..3 {
        let _ = writeln!(
            o,
            "| {} | {} | {} | {} | {} | {} | {} |",
            ["x", "y", "z"][i],
            cell(f.t_g[i][0], Some(f.t_g_std[i][0])),
            cell(f.t_g[i][1], Some(f.t_g_std[i][1])),
            cell(f.t_g[i][2], Some(f.t_g_std[i][2])),
            cell(r.reference_t_g[i][0], None),
            cell(r.reference_t_g[i][1], None),
            cell(r.reference_t_g[i][2], None)
        );
    }
    let _ = writeln!(o, "\nLargest difference from the reference: {:.1} standard errors.", worst_z(r, f));
    if !f.transitions.is_empty() {
        let _ = writeln!(
            o,
            "\n| motion between two rests | in the fit | turned [deg] | gravity carried: error raw [deg] | calibrated [deg] |\n|---|---|---|---|---|"
        );
        for t in &f.transitions {
            let _ = writeln!(
                o,
                "| {} | {} | {:.1} | {:.3} | {:.3} |",
                t.label,
                if t.used_in_fit { "yes" } else { "held out" },
                t.angle_deg,
                t.raw_error_deg,
                t.calibrated_error_deg
            );
        }
        let held = |pick: &dyn Fn(&crate::study::rests::Transition) -> bool| {
            let chosen: Vec<_> = f.transitions.iter().filter(|t| pick(t)).collect();
            (
                chosen.len(),
                rms(chosen.iter().map(|t| t.raw_error_deg)),
                rms(chosen.iter().map(|t| t.calibrated_error_deg)),
            )
        };
        let (n, raw, cal) = held(&|t| !t.used_in_fit);
        if n > 0 {
            let _ = writeln!(
                o,
                "\nRMS over the {n} motions the fit did not use: raw {raw:.3} deg, calibrated {cal:.3} deg."
            );
        }
        let (n, raw, cal) = held(&|t| !t.turn);
        let _ = writeln!(
            o,
            "RMS over the {n} motions that are not labelled turns: raw {raw:.3} deg, calibrated {cal:.3} deg."
        );
    }
    if !f.rests.is_empty() {
        let _ = writeln!(
            o,
            "\n| rest without a label | samples | \\|f\\| - g raw [m/s^2] | calibrated [m/s^2] |\n|---|---|---|---|"
        );
        for rest in &f.rests {
            let _ = writeln!(
                o,
                "| {} | {} | {:+.4} | {:+.4} |",
                rest.label, rest.samples, rest.raw_error_mps2, rest.calibrated_error_mps2
            );
        }
        let _ = writeln!(
            o,
            "\nRMS |f| - g over the {} rests without a label: raw {:.4} m/s^2, calibrated {:.4} m/s^2.",
            f.rests.len(),
            rms(f.rests.iter().map(|r| r.raw_error_mps2)),
            rms(f.rests.iter().map(|r| r.calibrated_error_mps2))
        );
    }
}

/// The largest difference of a fit's T_g from the reference, in its standard errors.
pub fn worst_z(r: &RotationStudy, f: &RotationFit) -> f64 {
    (0..9)
        .map(|k| (k / 3, k % 3))
        .map(|(i, j)| ((f.t_g[i][j] - r.reference_t_g[i][j]) / f.t_g_std[i][j].max(1e-12)).abs())
        .fold(0.0f64, f64::max)
}

/// The rotation part of the study JSON.
fn rotations_json(r: &RotationStudy) -> Value {
    json!({
        "reference": r.reference_name,
        "reference_t_g": r.reference_t_g,
        "fits": r.fits.iter().map(|f| json!({
            "fitted_on": f.name,
            "command": f.command,
            "rotations": f.rotations,
            "t_g": f.t_g,
            "t_g_std": f.t_g_std,
            "gyro_bias_radps": f.gyro_bias_radps.map(|b| b.0),
            "gyro_bias_std_radps": f.gyro_bias_radps.map(|b| b.1),
            "chi_square": f.chi_square,
            "degrees_of_freedom": f.degrees_of_freedom,
            "passes": f.passes,
            "move_error_deg": f.move_error_deg,
            "checks_passed": f.checks_passed,
            "transitions": f.transitions.iter().map(|t| json!({
                "motion": t.label,
                "turn": t.turn,
                "used_in_fit": t.used_in_fit,
                "angle_deg": t.angle_deg,
                "raw_error_deg": t.raw_error_deg,
                "calibrated_error_deg": t.calibrated_error_deg,
            })).collect::<Vec<_>>(),
            "rests": f.rests.iter().map(|x| json!({
                "rest": x.label,
                "samples": x.samples,
                "raw_error_mps2": x.raw_error_mps2,
                "calibrated_error_mps2": x.calibrated_error_mps2,
            })).collect::<Vec<_>>(),
        })).collect::<Vec<_>>(),
        "refused": r.refused.iter().map(|(n, w)| json!({"fitted_on": n, "reason": w})).collect::<Vec<_>>(),
    })
}

/// The links to the figures.
fn figures_section(o: &mut String, figures: &[String]) {
    if !figures.is_empty() {
        let _ = writeln!(o, "\n## Figures\n");
        for f in figures {
            let _ = writeln!(o, "- [{f}]({f})");
        }
    }
}

// ---------------------------------------------------------------------------------------------------------------
// JSON

/// The unit in a channel's JSON keys: `radps` for the gyros, `mps2` for the accelerometers.
fn json_unit(channel: &str) -> &'static str {
    if channel.starts_with('g') {
        "radps"
    } else {
        "mps2"
    }
}

/// An Allan deviation curve: `tau_s` and `adev_<unit>`.
fn curve_json(c: &Curve, unit: &str) -> Value {
    let mut m = Map::new();
    m.insert("tau_s".into(), json!(c.tau_s));
    m.insert(format!("adev_{unit}"), json!(c.adev));
    Value::Object(m)
}

/// The IEEE 952 terms with unit-named keys (rad or m/s based).
fn terms_json(t: &NoiseTerms, gyro: bool) -> Value {
    if gyro {
        json!({"quantization_q_rad": t.quantization_q, "random_walk_n_rad_per_sqrt_s": t.random_walk_n,
               "bias_instability_b_radps": t.bias_instability_b, "rate_random_walk_k_radps_per_sqrt_s": t.rate_random_walk_k,
               "ramp_r_radps2": t.ramp_r})
    } else {
        json!({"quantization_q_mps": t.quantization_q, "random_walk_n_mps_per_sqrt_s": t.random_walk_n,
               "bias_instability_b_mps2": t.bias_instability_b, "rate_random_walk_k_mps2_per_sqrt_s": t.rate_random_walk_k,
               "ramp_r_mps3": t.ramp_r})
    }
}

/// The machine-readable study (schema [`SCHEMA`], SI units, unit-named keys).
pub fn study_json(s: &Study, figures: &[String]) -> Value {
    let mut disagreement = noise_disagreement_json(s);
    let mut extended = Map::new();
    let mut gain = Map::new();
    for ch in &s.noise {
        if let Some(e) = &ch.extended {
            noise_extension_json(ch.channel, e, &mut extended, &mut gain);
        }
    }
    if let Some(p) = &s.poses {
        disagreement.extend(pose_disagreement_json(p));
        pose_extension_json(p, &mut extended, &mut gain);
    }
    json!({
        "schema": SCHEMA,
        "dataset": s.dataset,
        "sources": s.sources,
        "seed": s.seed,
        "rate_hz": s.rate_hz,
        "base": base_json(s),
        "disagreement": disagreement,
        "cause": s.causes.iter().map(|c| json!({"name": c.name, "channels": c.channels, "evidence": c.evidence})).collect::<Vec<_>>(),
        "extended": Value::Object(extended),
        "gain": Value::Object(gain),
        "rotations": s.poses.as_ref().and_then(|p| p.rotations.as_ref()).map(rotations_json),
        "figures": figures,
    })
}

/// The base model: its description, the white std per channel, gravity and the base accelerometer bias.
fn base_json(s: &Study) -> Value {
    let mut base = Map::new();
    base.insert("model".into(), json!("per static pose: constant mean per channel + white noise (std = ADEV at one sample = RMS first difference / sqrt 2)"));
    base.insert("simulation".into(), json!(format!("SIMULATION, seed {}", s.seed)));
    for ch in &s.noise {
        base.insert(format!("{}_white_std_{}", ch.channel, json_unit(ch.channel)), json!(ch.white_std));
    }
    if let Some(p) = &s.poses {
        base.insert("gravity_mps2".into(), json!(p.gravity_mps2));
        base.insert("accel_bias_mps2".into(), json!(p.base_accel.bias_mps2));
    }
    Value::Object(base)
}

/// The disagreement of the noise: per channel the Allan deviation of the data and of the base SIMULATION; the
/// sway tests.
fn noise_disagreement_json(s: &Study) -> Vec<Value> {
    let mut disagreement = Vec::new();
    for ch in &s.noise {
        let u = json_unit(ch.channel);
        let mut m = Map::new();
        m.insert("what".into(), json!("allan_deviation"));
        m.insert("channel".into(), json!(ch.channel));
        m.insert("long_tau_s".into(), json!(ch.long_tau_s));
        m.insert("ratio_data_over_base_sim_at_long_tau".into(), json!(ch.ratio_at_long_tau));
        m.insert("rms_log10_base_sim_over_data".into(), json!(ch.rms_log10_base));
        m.insert("data".into(), curve_json(&ch.data, u));
        m.insert("base_sim".into(), curve_json(&ch.base_sim, u));
        if let Some(q) = ch.quantization_step {
            m.insert(format!("quantization_step_{u}"), json!(q));
        }
        disagreement.push(Value::Object(m));
    }
    for sw in &s.sway {
        disagreement.push(json!({"what": "sway", "pair": sw.pair, "correlation": sw.correlation,
            "slope_mps2_per_rad": sw.slope_mps2_per_rad, "accel_rms_mps2": sw.accel_rms_mps2, "tilt_rms_rad": sw.tilt_rms_rad}));
    }
    disagreement
}

/// One channel's noise extension: its terms, dominant term and band-limited terms into `extended`, its
/// held-out gain into `gain`.
fn noise_extension_json(
    channel: &str,
    e: &NoiseExtension,
    extended: &mut Map<String, Value>,
    gain: &mut Map<String, Value>,
) {
    let g = channel.starts_with('g');
    extended.insert(format!("{channel}_noise_terms"), terms_json(&e.terms_all, g));
    extended.insert(format!("{channel}_noise_terms_first_half"), terms_json(&e.terms_first_half, g));
    extended.insert(format!("{channel}_dominant_term"), json!(e.dominant_term));
    let u = json_unit(channel);
    for (key, x) in [("", e.extra_all), ("_first_half", e.extra_first_half)] {
        extended.insert(format!("{channel}_extra_term{key}"), extra_term_json(x, u));
    }
    extended.insert(format!("{channel}_term_gate"), gate_json(&e.gate));
    gain.insert(
        format!("{channel}_held_out_rms_log10_adev"),
        json!({"rule": "fit on the first half, evaluate on the second", "base": e.held_out_rms_log10_base,
               "extended": e.held_out_rms_log10_extended}),
    );
    gain.insert(
        format!("{channel}_held_out_chi2"),
        json!({"rule": "fit on the first half, evaluate on the second", "points": e.held_out_points,
               "base": e.held_out_chi2_base, "extended": e.held_out_chi2_extended,
               "gate": {"min_rise": GATE_MIN_DELTA_CHI2, "min_relative_rise": GATE_MIN_RELATIVE_RISE}}),
    );
}

/// A band-limited term of the extended noise model (`null` when there is none); `u` the unit in the keys.
fn extra_term_json(x: Option<ExtraTerm>, u: &str) -> Value {
    match x {
        Some(ExtraTerm::GaussMarkov { sigma, tc_s }) => {
            json!({"gauss_markov": {format!("sigma_{u}"): sigma, "tc_s": tc_s}})
        }
        Some(ExtraTerm::Sine { amplitude, frequency_hz }) => {
            json!({"sine": {format!("amplitude_{u}"): amplitude, "frequency_hz": frequency_hz}})
        }
        None => Value::Null,
    }
}

/// The disagreement of the pose sets: per pose |mean f - b| - g, the gyro pose means, the turns.
fn pose_disagreement_json(p: &PoseStudy) -> Vec<Value> {
    let mut disagreement = Vec::new();
    disagreement.push(json!({"what": "pose_norm_minus_g", "method": p.method,
        "poses": p.poses.iter().map(|q| json!({"pos": q.pos, "name": q.name, "samples": q.samples,
            "mean_force_mps2": q.mean_force_mps2, "mean_rate_radps": q.mean_rate_radps,
            "data_mps2": q.norm_minus_g_data_mps2, "base_sim_mps2": q.norm_minus_g_base_sim_mps2,
            "extended_sim_mps2": q.norm_minus_g_extended_sim_mps2, "noise_std_mps2": q.norm_noise_std_mps2,
            "extended_calibrated_mps2": q.norm_minus_g_extended_mps2})).collect::<Vec<_>>(),
        "rms_data_mps2": p.norm_rms_data_mps2, "rms_white_noise_mps2": p.norm_rms_noise_mps2}));
    disagreement.push(json!({"what": "gyro_pose_means", "rms_scatter_radps": p.gyro_spread_rms_radps,
        "rms_white_noise_radps": p.gyro_spread_noise_radps}));
    for t in &p.turns {
        disagreement
            .push(json!({"what": "turn", "label": t.label, "axis": CHANNELS[t.axis], "duration_s": t.duration_s,
            "raw_angle_rad": t.raw_angle_rad, "bias_removed_angle_rad": t.angle_rad}));
    }
    disagreement
}

/// A held-out gate's verdicts as JSON.
fn gate_json(gate: &[TermGate]) -> Value {
    gate.iter()
        .map(|g| {
            json!({"term": g.term, "kept": g.kept, "held_out_chi2_with": g.chi2_with,
                   "held_out_chi2_without": g.chi2_without, "reason": g.reason})
        })
        .collect()
}

/// The pose sets' extensions (accelerometer model, gyro g-sensitivity and scale factors, factory comparison)
/// into `extended`, their held-out gains into `gain`.
fn pose_extension_json(p: &PoseStudy, extended: &mut Map<String, Value>, gain: &mut Map<String, Value>) {
    extended.insert(
        "accel".into(),
        json!({"method": p.method, "bias_mps2": p.extended_accel.bias_mps2,
        "scale_factors": p.extended_accel.scale_factors(), "matrix_a": p.extended_accel.matrix,
        "term_gate": gate_json(&p.accel_term_gate)}),
    );
    if let Some(gs) = &p.gyro_g_sensitivity {
        extended.insert("gyro_g_sensitivity_radps_per_mps2".into(), json!(gs));
    }
    if !p.turns.is_empty() {
        extended.insert(
            "gyro_scale_factors".into(),
            Value::Object(p.turns.iter().map(|t| (CHANNELS[t.axis].to_string(), json!(t.scale_factor))).collect()),
        );
    }
    gain.insert(
        "accel_held_out_norm_rms_mps2".into(),
        json!({"rule": p.held_out_rule,
        "base": p.held_out_norm_rms_base_mps2, "extended": p.held_out_norm_rms_extended_mps2}),
    );
    if !p.gyro_models_held_out_radps.is_empty() {
        gain.insert(
            "gyro_pose_means_held_out_rms_radps".into(),
            Value::Object(p.gyro_models_held_out_radps.iter().map(|(n, v)| (n.to_string(), json!(v))).collect()),
        );
    }
    if let Some(f) = &p.factory {
        extended.insert("factory_comparison".into(), factory_json(p.gravity_mps2, f));
    }
}

/// imu_tk: the fitted accelerometer against the factory calibration, in the lower-triangular gauge.
fn factory_json(gravity_mps2: f64, f: &FactoryComparison) -> Value {
    json!({
    "gauge": "lower-triangular L of K = L Q, counts = K f + offset",
    "gravity_mps2": gravity_mps2,
    "fitted_gain_counts_per_mps2": f.fitted_gain_counts_per_mps2,
    "factory_gain_counts_per_mps2": f.factory_gain_counts_per_mps2,
    "fitted_misalignment": f.fitted_misalignment,
    "factory_misalignment": f.factory_misalignment,
    "factory_misalignment_inverse_convention": f.factory_misalignment_inverse,
    "fitted_offset_counts": f.fitted_offset_counts})
}

// ---------------------------------------------------------------------------------------------------------------
// Figures

/// A named, coloured line or point series (x, y).
type Series = (String, RGBColor, Vec<(f64, f64)>);

/// One log-log panel: its title, its y label and its series.
type Panel = (String, String, Vec<Series>);

/// A plotting error, naming the figure.
fn plot_err(path: &Path, e: impl std::fmt::Display) -> anyhow::Error {
    anyhow::anyhow!("plot {}: {e}", path.display())
}

/// The figures' colours: data, base SIMULATION, extended SIMULATION, extended calibration, second half.
const BLACKISH: RGBColor = RGBColor(20, 20, 20);
const BLUE_: RGBColor = RGBColor(30, 80, 210);
const RED_: RGBColor = RGBColor(210, 40, 30);
const GREEN_: RGBColor = RGBColor(30, 150, 60);
const GREY_: RGBColor = RGBColor(140, 140, 140);

/// Writes the study's figures into `dir`; returns their file names.
pub fn write_figures(s: &Study, dir: &Path) -> anyhow::Result<Vec<String>> {
    let mut names = Vec::new();
    let panels: Vec<Panel> = s.noise.iter().map(allan_panel).collect();
    let what = if s.poses.is_some() { "longest static pose" } else { "whole record" };
    loglog_panels(
        &dir.join("allan.png"),
        &format!("{}: overlapping Allan deviation, data vs SIMULATION ({what})", s.dataset),
        &panels,
    )?;
    names.push("allan.png".to_string());
    if let Some(p) = &s.poses {
        pose_norm_figure(&s.dataset, p, dir)?;
        names.push("pose_norm.png".to_string());
        gyro_pose_means_figure(&s.dataset, p, dir)?;
        names.push("gyro_pose_means.png".to_string());
    }
    Ok(names)
}

/// The Allan deviation panel of one channel: data and base SIMULATION; with an extension, the second half and
/// its extended SIMULATION.
fn allan_panel(ch: &ChannelNoise) -> Panel {
    let scaled =
        |c: &Curve, u: f64| -> Vec<(f64, f64)> { c.tau_s.iter().zip(&c.adev).map(|(t, a)| (*t, a / u)).collect() };
    let (u, name) = unit_of(ch.channel);
    let mut series = vec![
        ("data".to_string(), BLACKISH, scaled(&ch.data, u)),
        ("base SIMULATION (white)".to_string(), BLUE_, scaled(&ch.base_sim, u)),
    ];
    if let Some(e) = &ch.extended {
        series.push(("data, 2nd half".to_string(), GREY_, scaled(&e.held_out_data, u)));
        series.push(("extended SIMULATION, 2nd half".to_string(), RED_, scaled(&e.held_out_extended_sim, u)));
    }
    (
        format!("{}: ratio {:.1} at {:.0} s", ch.channel, ch.ratio_at_long_tau, ch.long_tau_s),
        format!("ADEV [{name}]"),
        series,
    )
}

/// `f` of each pose against its index (1, 2, ... in record order).
fn per_pose(p: &PoseStudy, f: &dyn Fn(&Pose) -> f64) -> Vec<(f64, f64)> {
    p.poses.iter().enumerate().map(|(k, q)| (k as f64 + 1.0, f(q))).collect()
}

/// `pose_norm.png`: |mean f - b| - g per pose, data, SIMULATIONs, extended calibration.
fn pose_norm_figure(dataset: &str, p: &PoseStudy, dir: &Path) -> anyhow::Result<()> {
    pose_plot(
        &dir.join("pose_norm.png"),
        &format!("{dataset}: |mean f - b| - g per pose (b: base bias)"),
        "|f| - g [m/s^2]",
        &[
            ("data".to_string(), BLACKISH, per_pose(p, &|q| q.norm_minus_g_data_mps2)),
            ("base SIMULATION".to_string(), BLUE_, per_pose(p, &|q| q.norm_minus_g_base_sim_mps2)),
            ("extended SIMULATION".to_string(), RED_, per_pose(p, &|q| q.norm_minus_g_extended_sim_mps2)),
            ("data, extended calibration".to_string(), GREEN_, per_pose(p, &|q| q.norm_minus_g_extended_mps2)),
        ],
    )
}

/// `gyro_pose_means.png`: the gyro pose means less their mean, deg/s.
fn gyro_pose_means_figure(dataset: &str, p: &PoseStudy, dir: &Path) -> anyhow::Result<()> {
    let n = p.poses.len() as f64;
    let colors = [RED_, GREEN_, BLUE_];
    let series: Vec<Series> = (0..3)
        .map(|i| {
            let m = p.poses.iter().map(|q| q.mean_rate_radps[i]).sum::<f64>() / n;
            let points = per_pose(p, &|q| (q.mean_rate_radps[i] - m).to_degrees());
            (format!("{} data - mean", CHANNELS[i]), colors[i], points)
        })
        .collect();
    pose_plot(
        &dir.join("gyro_pose_means.png"),
        &format!(
            "{}: gyro pose means less their mean (white noise gives {:.4} deg/s RMS)",
            dataset,
            p.gyro_spread_noise_radps.to_degrees()
        ),
        "deg/s",
        &series,
    )
}

/// Log-log panels (2 x 3).
fn loglog_panels(path: &Path, title: &str, panels: &[Panel]) -> anyhow::Result<()> {
    let root = figure(path, (1500, 900))?;
    let root = root.titled(title, ("sans-serif", 24)).map_err(|e| plot_err(path, e))?;
    let areas = root.split_evenly((2, 3));
    for (area, panel) in areas.iter().zip(panels) {
        loglog_panel(path, area, panel)?;
    }
    root.present().map_err(|e| plot_err(path, e))?;
    Ok(())
}

/// One log-log panel into `area` (nothing when its positive points do not span a range).
fn loglog_panel(path: &Path, area: &DrawingArea<Png<'_>, Shift>, panel: &Panel) -> anyhow::Result<()> {
    let (name, ylabel, series) = panel;
    let pts = series.iter().flat_map(|s| s.2.iter()).filter(|p| p.0 > 0.0 && p.1 > 0.0);
    let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for p in pts {
        x0 = x0.min(p.0);
        x1 = x1.max(p.0);
        y0 = y0.min(p.1);
        y1 = y1.max(p.1);
    }
    if !(x0 < x1 && y0 < y1) {
        return Ok(());
    }
    let mut chart = ChartBuilder::on(area)
        .caption(name, ("sans-serif", 18))
        .margin(8)
        .x_label_area_size(35)
        .y_label_area_size(70)
        .build_cartesian_2d((x0 / 1.2..x1 * 1.2).log_scale(), (y0 / 1.5..y1 * 1.5).log_scale())
        .map_err(|e| plot_err(path, e))?;
    chart.configure_mesh().x_desc("tau [s]").y_desc(ylabel.as_str()).draw().map_err(|e| plot_err(path, e))?;
    for (label, color, data) in series {
        let c = *color;
        chart
            .draw_series(LineSeries::new(data.iter().copied().filter(|p| p.1 > 0.0), c.stroke_width(2)))
            .map_err(|e| plot_err(path, e))?
            .label(label.clone())
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(3)));
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .label_font(("sans-serif", 12))
        .draw()
        .map_err(|e| plot_err(path, e))?;
    Ok(())
}

/// Points per pose index (linear axes), one panel.
fn pose_plot(path: &Path, title: &str, ylabel: &str, series: &[Series]) -> anyhow::Result<()> {
    let root = figure(path, (1200, 700))?;
    let all: Vec<(f64, f64)> = series.iter().flat_map(|s| s.2.iter().copied()).collect();
    let xmax = all.iter().map(|p| p.0).fold(1.0, f64::max) + 1.0;
    let ymax = all.iter().map(|p| p.1.abs()).fold(1e-9, f64::max) * 1.15;
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 22))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(80)
        .build_cartesian_2d(0f64..xmax, -ymax..ymax)
        .map_err(|e| plot_err(path, e))?;
    chart.configure_mesh().x_desc("pose (order in the record)").y_desc(ylabel).draw().map_err(|e| plot_err(path, e))?;
    for (label, color, data) in series {
        let c = *color;
        chart
            .draw_series(data.iter().map(|p| Circle::new(*p, 5, c.filled())))
            .map_err(|e| plot_err(path, e))?
            .label(label.clone())
            .legend(move |(x, y)| Circle::new((x + 10, y), 5, c.filled()));
        chart.draw_series(LineSeries::new(data.iter().copied(), c.mix(0.4))).map_err(|e| plot_err(path, e))?;
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()
        .map_err(|e| plot_err(path, e))?;
    root.present().map_err(|e| plot_err(path, e))?;
    Ok(())
}
