//! The human summary of an analysis (what `sinscal analyze` prints; units stated).

use std::fmt::Write as _;

use super::{Analysis, Effect};

/// Human summary of an analysis (units stated).
pub fn summary(a: &Analysis) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "analysis of {} ({})", a.source, a.input);
    let _ = writeln!(
        s,
        "base model: constant biases + white noise, {} observations, ln L = {:.2}, BIC = {:.2}",
        a.base_model.observations, a.base_model.log_likelihood, a.base_model.bic
    );
    for (k, v) in &a.base_model.residual_rms {
        let _ = writeln!(s, "  residual RMS {k}: {v:.4e}");
    }
    let _ = writeln!(s, "criterion: {}", a.criterion);
    let _ = writeln!(
        s,
        "ranking: the column effects in the order chosen, each with its consequence (how many standard errors \
         leaving it out moves a bias); then the noise effects by BIC gain; uncertain time terms (pose order, \
         slow wander, halves, time constant at its grid's end) last"
    );
    if a.effects.is_empty() {
        let _ = writeln!(s, "verdict: none (the base model is adequate)");
    } else {
        let _ = writeln!(s, "verdict: {}", a.verdict);
        for e in &a.effects {
            effect_line(&mut s, e);
        }
    }
    for m in &a.misfits {
        let _ = writeln!(
            s,
            "  misfit: {} would need {:+.4e} +- {:.2e} {}, beyond the plausible {:.1e} (mostly at pos {}, {}): \
             the model misses something there",
            m.candidate, m.estimate, m.std_error, m.unit, m.limit, m.pos, m.channel
        );
    }
    for u in &a.unsupported {
        let _ = writeln!(s, "  unsupported: {}", u.text());
    }
    for c in &a.confounded {
        let _ = writeln!(s, "  {}", super::confounded_text(c));
    }
    for line in a.model_fit.iter().flat_map(|f| f.lines()) {
        let _ = writeln!(s, "{line}");
    }
    if let Some(w) = &a.windows {
        let _ = writeln!(s, "{}", w.text());
    }
    if let Some(x) = &a.settling {
        let tests: Vec<String> = x
            .passed
            .iter()
            .map(|t| {
                format!(
                    "{} {} segment {}: F {:.1} ({}, {}), p {:.1e}",
                    t.channel, t.end, t.segment, t.f, t.dof[0], t.dof[1], t.p_value
                )
            })
            .collect();
        let _ = writeln!(
            s,
            "settling after a move: the first {:.1} s and the last {:.1} s of {} dwells of {} tested left out ({})",
            x.start_s,
            x.end_s,
            x.dwells,
            x.tested_dwells,
            tests.join("; ")
        );
    }
    for c in &a.checks {
        let _ = writeln!(s, "check {}: {}: {}", c.check, if c.passed { "passed" } else { "FAILED" }, c.detail);
    }
    if !a.noise_model.is_empty() {
        let _ = writeln!(s, "noise (terms named from the Allan variance of the longest dwell):");
        for m in &a.noise_model {
            let _ = writeln!(s, "  {}", m.text());
        }
    }
    let disturbed: Vec<_> = a.diagnostics.iter().filter_map(|d| d.disturbances.as_ref().map(|x| (d, x))).collect();
    if !disturbed.is_empty() {
        let _ = writeln!(
            s,
            "disturbances (one-second blocks whose noise stands far above the channel's own level; the noise terms include them):"
        );
        for (d, x) in disturbed {
            let unit = super::CHANNELS.iter().position(|c| *c == d.channel).map_or("", |c| super::CHANNEL_UNITS[c]);
            let _ = writeln!(
                s,
                "  {}: {:.0} s ({} of {} blocks) in {} episodes; they add {:.3e} +- {:.2e} {unit} to its level of {:.3e} {unit} (p {:.1e})",
                d.channel, x.disturbed_s, x.blocks, x.tested, x.episodes, x.excess, x.std_error, x.quiet_rms, x.p_value
            );
        }
    }
    if !a.unobservable.is_empty() {
        let _ = writeln!(s, "unobservable with this data: {}", a.unobservable.join(", "));
    }
    s
}

/// One effect: estimate, BIC change, residuals before and after, extras and aliases.
fn effect_line(s: &mut String, e: &Effect) {
    let _ = write!(
        s,
        "  {:<20} {:<9} {:<4} estimate {:+.4e} +- {} {}  delta BIC {:.1}  residual RMS {:.3e} -> {:.3e} {} ({})",
        e.effect,
        e.sensor,
        e.axes,
        e.estimate,
        e.std_error_text(),
        e.unit,
        e.delta_bic,
        e.residual_rms_before,
        e.residual_rms_after,
        e.residual_unit,
        e.residual_of
    );
    let extras = e.extras();
    if !extras.is_empty() {
        let _ = write!(s, "  {extras}");
    }
    if e.at_grid_edge {
        let _ = write!(s, " (at the edge of its grid: not determined)");
    }
    if let Some(c) = &e.consequence {
        let _ = write!(s, "  moves {} by {:.1} standard errors", c.bias, c.in_std_errors);
    }
    if !e.aliases.is_empty() {
        let _ = write!(s, "  ({})", e.aliases_text());
    }
    if !e.rivals.is_empty() {
        let _ = write!(s, "  ({})", e.rivals_text());
    }
    let _ = writeln!(s);
}
