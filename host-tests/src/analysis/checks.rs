//! The checks of an analysis that fail loudly (docs/cli.md#checks), as a calibration's do: `fit` (the final
//! model's block means against each channel's noise model, recordings: [`super::model_fit`]),
//! `plausibility` (no candidate the data want needs a value no instrument has: `misfits`) and `selection`
//! (the forward selection was not stopped by its most effects with a candidate still passing). All are listed,
//! passed or failed, in the JSON's `checks`, after a recording's `physics` check (calibrate's own, added by
//! [`super::recording::analyze_recording`]); a failed one makes `analyze` exit with status 3.

use crate::calibration::checks::{Check, MISFIT_LEVEL};

use super::{Analysis, ModelFit, MAX_EFFECTS};

/// Every check of an analysis, in the order they are listed.
pub(super) fn checks(a: &Analysis) -> Vec<Check> {
    let mut all: Vec<Check> = a.model_fit.iter().map(fit).collect();
    all.push(plausibility(a));
    all.push(selection(a));
    all
}

/// The forward selection ended because no candidate passed, not because it reached its most effects.
fn selection(a: &Analysis) -> Check {
    match &a.cut_short {
        None => Check::new("selection", true, "the forward selection ended with no candidate passing the criterion"),
        Some(c) => Check::new(
            "selection",
            false,
            format!(
                "the forward selection stopped at its most effects ({MAX_EFFECTS}) while {} still passed the \
                 criterion (likelihood ratio {:.1}): the final model is incomplete",
                c.candidate, c.likelihood_ratio
            ),
        ),
    }
}

/// The final model against the noise model: every channel's chi-square within the 0.1 % level, over the
/// channels (Bonferroni).
fn fit(f: &ModelFit) -> Check {
    let level = MISFIT_LEVEL / f.groups.len().max(1) as f64;
    let worst = f.groups.iter().min_by(|a, b| a.p_value.total_cmp(&b.p_value));
    let Some(g) = worst else { return Check::new("fit", true, "no channel to fit") };
    let shown = format!(
        "{}: chi2/dof {:.2} (p {:.1e}; between the dwells {:.2}, within {:.2})",
        g.channel,
        g.chi_square / g.dof,
        g.p_value,
        g.chi_square_between_dwells / g.dof_between_dwells,
        g.chi_square_within_dwells / g.dof_within_dwells
    );
    if g.p_value >= level {
        return Check::new("fit", true, format!("the final model explains every channel; the least: {shown}"));
    }
    let beyond: Vec<&str> = f.groups.iter().filter(|g| g.p_value < level).map(|g| g.channel.as_str()).collect();
    let dwell = f.dwells.first().map_or(String::new(), |d| format!("; the worst dwell: {}", d.text()));
    Check::new(
        "fit",
        false,
        format!(
            "the final model leaves {} beyond its noise model at the 0.1 % level (the worst, {shown}){dwell}: \
             something the catalogue does not hold, or a wrong label",
            beyond.join(", ")
        ),
    )
}

/// No candidate needs an impossible value.
fn plausibility(a: &Analysis) -> Check {
    match a.misfits.first() {
        None => Check::new("plausibility", true, "no candidate needs an implausible value"),
        Some(m) => Check::new(
            "plausibility",
            false,
            format!(
                "{} misfit(s): {} needs {:.3e} +- {:.2e} {} (plausible up to {:.1e}), most at pos {} {}",
                a.misfits.len(),
                m.candidate,
                m.estimate,
                m.std_error,
                m.unit,
                m.limit,
                m.pos,
                m.channel
            ),
        ),
    }
}
