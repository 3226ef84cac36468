//! The report directory of `sinscal analyze --report DIR`: `summary.md` and figures (PNG, plotters).

use std::fmt::Write as _;
use std::path::Path;

use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use plotters::coord::combinators::LogCoord;
use plotters::coord::combinators::{BindKeyPoints, WithKeyPoints};

use crate::analysis::noise_terms::{sig, FitPoint, NoiseModel, Term};
use crate::analysis::sample_colour::SampleColour;
use crate::analysis::{Analysis, CHANNELS};
use crate::model::catalogue::EffectKind;
use crate::plot::{display_unit, figure, log_ticks, short_name, tick_label, Png};
use crate::stats::noise::{log_spaced_clusters, overlapping_allan_deviation, welch_psd};

fn err(path: &Path, e: &dyn std::fmt::Display) -> anyhow::Error {
    anyhow::anyhow!("plot {}: {e}", path.display())
}

/// Writes `summary.md`, `residuals.png` and, for recordings, `allan.png`, `psd.png` and `noise_level.png`
/// into `dir`.
pub fn write_report(a: &Analysis, dir: &Path) -> anyhow::Result<Vec<String>> {
    std::fs::create_dir_all(dir).map_err(|e| anyhow::anyhow!("{}: {e}", dir.display()))?;
    let mut files = vec!["summary.md".to_string(), "residuals.png".to_string()];
    residuals_plot(a, &dir.join("residuals.png"))?;
    if !a.noise_model.is_empty() {
        allan_plot(a, &dir.join("allan.png"))?;
        psd_plot(a, &dir.join("psd.png"))?;
        noise_level_plot(a, &dir.join("noise_level.png"))?;
        files.push("allan.png".into());
        files.push("psd.png".into());
        files.push("noise_level.png".into());
    }
    let mut md = String::new();
    base_model_md(&mut md, a);
    effects_md(&mut md, a);
    model_fit_md(&mut md, a);
    diagnostics_md(&mut md, a);
    noise_md(&mut md, a);
    figures_md(&mut md, a, files.len() > 2);
    std::fs::write(dir.join("summary.md"), md).map_err(|e| anyhow::anyhow!("{}: {e}", dir.display()))?;
    Ok(files)
}

/// `summary.md`: the title, the verdict, the criterion and the base model.
fn base_model_md(md: &mut String, a: &Analysis) {
    let _ = writeln!(md, "# sinscal analysis of `{}`\n", a.source);
    let _ = writeln!(md, "Input: {}. Schema `{}`.\n", a.input, a.schema);
    let _ = writeln!(md, "## Verdict: {}\n", a.verdict);
    let _ = writeln!(md, "Criterion: {}.\n", a.criterion);
    let _ = writeln!(md, "## Base model (constant biases, white noise)\n");
    let _ = writeln!(
        md,
        "{} observations, log-likelihood {:.2}, BIC {:.2}.\n",
        a.base_model.observations, a.base_model.log_likelihood, a.base_model.bic
    );
    let _ = writeln!(md, "| quantity | value (SI) |\n|---|---|");
    for (k, v) in &a.base_model.biases {
        let _ = writeln!(md, "| {k} | {v:.6e} |");
    }
    for (k, v) in &a.base_model.residual_rms {
        let _ = writeln!(md, "| residual RMS {k} | {v:.4e} |");
    }
}

/// `summary.md`: the effects found, ranked (docs/analysis.md#verdict), then the misfits and the time terms confounded
/// with pose order.
fn effects_md(md: &mut String, a: &Analysis) {
    let _ = writeln!(md, "\n## Effects found (column effects in the order chosen, then noise effects)\n");
    if a.effects.is_empty() {
        let _ = writeln!(md, "None: no candidate passes the criterion.\n");
    } else {
        let _ = writeln!(
            md,
            "| effect | sensor | axes | estimate | std error | unit | moves (in standard errors) | delta BIC | residual RMS before -> after | extra | aliases, rivals |\n|---|---|---|---|---|---|---|---|---|---|---|"
        );
    }
    for e in &a.effects {
        let moves = e.consequence.as_ref().map_or("-".to_string(), |c| format!("{} by {:.1}", c.bias, c.in_std_errors));
        let extras = if e.at_grid_edge { format!("{} (tau at its grid edge)", e.extras()) } else { e.extras() };
        let _ = writeln!(
            md,
            "| {} | {} | {} | {:+.4e} | {} | {} | {} | {:.1} | {:.3e} -> {:.3e} {} ({}) | {} | {} |",
            e.effect,
            e.sensor,
            e.axes,
            e.estimate,
            e.std_error_text(),
            e.unit,
            moves,
            e.delta_bic,
            e.residual_rms_before,
            e.residual_rms_after,
            e.residual_unit,
            e.residual_of,
            extras,
            [e.aliases_text(), e.rivals_text()]
                .iter()
                .filter(|t| !t.is_empty())
                .cloned()
                .collect::<Vec<_>>()
                .join("; ")
        );
    }
    if !a.misfits.is_empty() {
        let _ = writeln!(md, "\n## Misfits: effects the data want at impossible values\n");
        let _ = writeln!(
            md,
            "| candidate | would need | std error | plausible limit | unit | mostly at |\n|---|---|---|---|---|---|"
        );
        for m in &a.misfits {
            let _ = writeln!(
                md,
                "| {} | {:+.4e} | {:.2e} | {:.1e} | {} | pos {}, {} |",
                m.candidate, m.estimate, m.std_error, m.limit, m.unit, m.pos, m.channel
            );
        }
    }
    if !a.unsupported.is_empty() {
        let _ =
            writeln!(md, "\n## Admitted, but not an effect: within the criterion of zero by its own standard error\n");
        for u in &a.unsupported {
            let _ = writeln!(md, "- {}", u.text());
        }
    }
    if !a.confounded.is_empty() {
        let _ = writeln!(md, "\n## Time terms confounded with pose order\n");
        for c in &a.confounded {
            let _ = writeln!(md, "- {}", super::confounded_text(c));
        }
    }
}

/// `summary.md`: the verdict on the final model (docs/analysis.md#model-fit) and its standard errors across
/// the thirds of every dwell (docs/analysis.md#windows).
fn model_fit_md(md: &mut String, a: &Analysis) {
    let Some(fit) = &a.model_fit else { return };
    let _ = writeln!(md, "\n## Model fit: {}\n", fit.verdict);
    let _ = writeln!(
        md,
        "The final model's block-mean residuals against each channel's named noise at the block's length \
         (chi-square per degree of freedom; between the dwells: what wanders from dwell to dwell; within: \
         seconds to a dwell's length).\n"
    );
    let _ = writeln!(
        md,
        "| channel | residual RMS | noise RMS | chi2/dof | p | between dwells | within dwells | |\n|---|---|---|---|---|---|---|---|"
    );
    for g in &fit.groups {
        let _ = writeln!(
            md,
            "| {} | {:.3e} {u} | {:.3e} {u} | {:.2} | {:.1e} | {:.2} | {:.2} | {} |",
            g.channel,
            g.residual_rms,
            g.noise_rms,
            g.chi_square / g.dof,
            g.p_value,
            g.chi_square_between_dwells / g.dof_between_dwells,
            g.chi_square_within_dwells / g.dof_within_dwells,
            if g.explained { "" } else { "unexplained" },
            u = g.unit
        );
    }
    if !fit.dwells.is_empty() {
        let _ = writeln!(md);
    }
    for d in &fit.dwells {
        let _ = writeln!(md, "- {}", d.text());
    }
    if let Some(w) = &a.windows {
        let _ = writeln!(md, "\n{}.", w.text());
    }
}

/// `summary.md`: the per-channel diagnostics (recordings), and what settling after a move left out.
fn diagnostics_md(md: &mut String, a: &Analysis) {
    if let Some(x) = &a.settling {
        let _ = writeln!(
            md,
            "\n## Settling after a move\n\nThe first {:.1} s and the last {:.1} s of {} dwells (of {} tested) were left out \
             (docs/analysis.md#settling-after-a-move):\n\n| channel | end | segment | F | dof | p |\n|---|---|---|---|---|---|",
            x.start_s, x.end_s, x.dwells, x.tested_dwells
        );
        for t in &x.passed {
            let _ = writeln!(
                md,
                "| {} | {} | {} | {:.2} | {}, {} | {:.1e} |",
                t.channel, t.end, t.segment, t.f, t.dof[0], t.dof[1], t.p_value
            );
        }
    }
    if a.diagnostics.is_empty() {
        return;
    }
    let _ = writeln!(md, "\n## Diagnostics per channel\n");
    let _ = writeln!(
        md,
        "| channel | detrended RMS | Ljung-Box p (20 lags, longest dwell) | largest within-dwell trend (z) | quantisation step | print step (file's digits) | disturbed seconds (episodes) |\n|---|---|---|---|---|---|---|"
    );
    for d in &a.diagnostics {
        let _ = writeln!(
            md,
            "| {} | {:.4e} | {:.3} | {:.1} | {} | {} | {} |",
            d.channel,
            d.detrended_rms,
            d.whiteness_p_value,
            d.max_trend_z,
            d.quantization_step.map_or("-".to_string(), |q| format!("{q:.4e}")),
            d.print_step.map_or("-".to_string(), |q| format!("{q:.0e}")),
            d.disturbances.as_ref().map_or("-".to_string(), |x| format!("{:.0} ({})", x.disturbed_s, x.episodes))
        );
    }
}

/// `summary.md`: the noise model named per channel (docs/analysis.md#noise-model).
fn noise_md(md: &mut String, a: &Analysis) {
    if a.noise_model.is_empty() {
        return;
    }
    let _ = writeln!(md, "\n## Noise\n");
    let _ = writeln!(
        md,
        "Terms named from the Allan variance of the longest dwell (value +- standard error), against white noise alone; lag-1 correlation of the sample differences.\n"
    );
    for m in &a.noise_model {
        let _ = writeln!(md, "- {}", m.text());
    }
}

/// `summary.md`: what this data cannot see, and the figures (`noise_figures`: the Allan and PSD plots too).
fn figures_md(md: &mut String, a: &Analysis, noise_figures: bool) {
    let _ = writeln!(
        md,
        "\n## Unobservable with this data\n\n{}\n",
        if a.unobservable.is_empty() { "-".to_string() } else { a.unobservable.join(", ") }
    );
    let _ = writeln!(md, "## Figures\n");
    let _ = writeln!(md, "- `residuals.png`: residual of every observation (block means, or angles) by position, for the base model (grey) and the final model (colour).");
    if noise_figures {
        let _ = writeln!(md, "- `allan.png`: overlapping Allan deviation of the longest dwell (mean and trend removed): the octave points fitted with 1-sigma bars and a dense curve, white noise alone (red), the named terms (blue) and each term (dashed).");
        let _ = writeln!(md, "- `psd.png`: Welch power spectral density (Hann, 1024-sample segments) of the same samples, with the base model's white level.");
        let _ = writeln!(md, "- `noise_level.png`: the standard deviation of every one-second block of the dwells (mean removed) against the time since the record's first row, with the time a noise warm-up settles where one is named.");
    }
    let _ = writeln!(md, "\n![residuals](residuals.png)");
    if noise_figures {
        let _ = writeln!(md, "\n![allan](allan.png)\n\n![psd](psd.png)\n\n![noise level](noise_level.png)");
    }
}

type Area<'a> = DrawingArea<Png<'a>, plotters::coord::Shift>;

/// Colours: base model, final / named model, white only, and one per noise term (model order).
const GREY: RGBColor = RGBColor(150, 150, 150);
const BLUE: RGBColor = RGBColor(30, 70, 200);
const RED: RGBColor = RGBColor(200, 30, 30);
const TERM_COLOURS: [RGBColor; Term::ALL.len()] = [
    RGBColor(140, 40, 160),
    RGBColor(230, 120, 0),
    RGBColor(30, 140, 60),
    RGBColor(0, 150, 160),
    RGBColor(150, 90, 40),
    RGBColor(220, 40, 150),
    RGBColor(40, 70, 200),
];

fn legend_line(c: RGBColor, width: u32) -> impl Fn((i32, i32)) -> PathElement<(i32, i32)> {
    move |(x, y)| PathElement::new(vec![(x, y), (x + 24, y)], c.stroke_width(width))
}

/// Runs of equal position labels in observation order: (label, first index, one past the last).
fn position_spans(points: &[(u32, f64, f64)]) -> Vec<(u32, usize, usize)> {
    let mut spans: Vec<(u32, usize, usize)> = Vec::new();
    for (i, p) in points.iter().enumerate() {
        match spans.last_mut() {
            Some(s) if s.0 == p.0 => s.2 = i + 1,
            _ => spans.push((p.0, i, i + 1)),
        }
    }
    spans
}

/// `residuals.png`: one panel per observation group that has observations, residuals in time order with the
/// positions as alternating bands.
fn residuals_plot(a: &Analysis, path: &Path) -> anyhow::Result<()> {
    let groups: Vec<usize> = (0..a.figures.residuals.len()).filter(|&g| !a.figures.residuals[g].is_empty()).collect();
    let rows = groups.len().max(1);
    let root = figure(path, (1400, 50 + 250 * rows as u32))?;
    let root = root
        .titled(
            &format!("Residuals of the observations ({}) by position: base model and final model", residual_kind(a)),
            ("sans-serif", 22),
        )
        .map_err(|e| err(path, &e))?;
    for (area, &g) in root.split_evenly((rows, 1)).iter().zip(&groups) {
        let name = a.figures.residual_names.get(g).cloned().unwrap_or_default();
        residual_panel(area, &name, &a.figures.residuals[g]).map_err(|e| err(path, &e))?;
    }
    root.present().map_err(|e| err(path, &e))?;
    Ok(())
}

fn residual_kind(a: &Analysis) -> &'static str {
    if a.input == "angles" {
        "angles"
    } else {
        "block means"
    }
}

fn residual_panel(area: &Area, name: &str, points: &[(u32, f64, f64)]) -> anyhow::Result<()> {
    let e = |e: &dyn std::fmt::Display| anyhow::anyhow!("{e}");
    let max_si = points.iter().flat_map(|p| [p.1.abs(), p.2.abs()]).fold(0.0, f64::max);
    let (unit, per) = display_unit(name, max_si);
    let ymax = (max_si / per).max(1e-12) * 1.15;
    let spans = position_spans(points);
    let step = spans.len().div_ceil(30).max(1);
    let n = points.len() as f64;
    let rms = |f: &dyn Fn(&(u32, f64, f64)) -> f64| (points.iter().map(|p| f(p).powi(2)).sum::<f64>() / n).sqrt() / per;
    let mut chart = ChartBuilder::on(area)
        .margin(10)
        .x_label_area_size(38)
        .y_label_area_size(90)
        .build_cartesian_2d(-0.5f64..n - 0.5, -ymax..ymax)
        .map_err(|x| e(&x))?;
    chart
        .configure_mesh()
        .disable_x_mesh()
        .x_labels(0)
        .y_label_formatter(&|v| tick_label(*v))
        .x_desc("position (observations in time order; the label of each position at its foot)")
        .y_desc(format!("{} residual [{unit}]", short_name(name)))
        .draw()
        .map_err(|x| e(&x))?;
    let band = RGBColor(225, 232, 245).filled();
    chart
        .draw_series(
            spans
                .iter()
                .enumerate()
                .filter(|(k, _)| k % 2 == 1)
                .map(|(_, s)| Rectangle::new([(s.1 as f64 - 0.5, -ymax), (s.2 as f64 - 0.5, ymax)], band)),
        )
        .map_err(|x| e(&x))?;
    chart.draw_series(LineSeries::new([(-0.5, 0.0), (n - 0.5, 0.0)], BLACK.stroke_width(1))).map_err(|x| e(&x))?;
    let font = ("sans-serif", 13).into_font().color(&BLACK).pos(Pos::new(HPos::Center, VPos::Bottom));
    chart
        .draw_series(
            spans
                .iter()
                .step_by(step)
                .map(|s| Text::new(s.0.to_string(), ((s.1 + s.2) as f64 / 2.0 - 0.5, -ymax * 0.97), font.clone())),
        )
        .map_err(|x| e(&x))?;
    let size = if points.len() > 400 { 2 } else { 3 };
    chart
        .draw_series(points.iter().enumerate().map(|(i, p)| Circle::new((i as f64, p.1 / per), size, GREY.filled())))
        .map_err(|x| e(&x))?
        .label(format!("base model (biases only), RMS {} {unit}", sig(rms(&|p| p.1))))
        .legend(|(x, y)| Circle::new((x + 10, y), 4, GREY.filled()));
    chart
        .draw_series(points.iter().enumerate().map(|(i, p)| Circle::new((i as f64, p.2 / per), size, BLUE.filled())))
        .map_err(|x| e(&x))?
        .label(format!("final model (with the effects found), RMS {} {unit}", sig(rms(&|p| p.2))))
        .legend(|(x, y)| Circle::new((x + 10, y), 4, BLUE.filled()));
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font(("sans-serif", 14))
        .draw()
        .map_err(|x| e(&x))?;
    Ok(())
}

/// The panels of the noise figures: (area, channel index) with gyros in the left column and accelerometers in
/// the right, only the channels that have a noise model; the layout adapts to what is there.
fn channel_panels<'a>(a: &Analysis, root: &Area<'a>) -> Vec<(Area<'a>, usize)> {
    let channels: Vec<usize> =
        a.noise_model.iter().filter_map(|m| CHANNELS.iter().position(|c| *c == m.channel)).collect();
    let gyros: Vec<usize> = channels.iter().copied().filter(|&c| c < 3).collect();
    let accels: Vec<usize> = channels.iter().copied().filter(|&c| c >= 3).collect();
    let columns: Vec<&Vec<usize>> = [&gyros, &accels].into_iter().filter(|c| !c.is_empty()).collect();
    let rows = columns.iter().map(|c| c.len()).max().unwrap_or(1);
    let areas = root.split_evenly((rows, columns.len().max(1)));
    let mut out = Vec::new();
    for (col, list) in columns.iter().enumerate() {
        for (row, &c) in list.iter().enumerate() {
            if let Some(area) = areas.get(row * columns.len() + col) {
                out.push((area.clone(), c));
            }
        }
    }
    out
}

/// Size of the noise figures for the channels shown.
fn noise_figure_size(a: &Analysis) -> (u32, u32) {
    let gyros = a.noise_model.iter().filter(|m| m.channel.starts_with('g')).count();
    let accels = a.noise_model.len() - gyros;
    let columns = (gyros > 0) as u32 + (accels > 0) as u32;
    (if columns > 1 { 1500 } else { 900 }, 60 + 400 * gyros.max(accels).max(1) as u32)
}

fn allan_plot(a: &Analysis, path: &Path) -> anyhow::Result<()> {
    let root = figure(path, noise_figure_size(a))?;
    let n = a.noise_model.first().map_or(0, |m| m.samples);
    let title = format!(
        "Overlapping Allan deviation of the longest dwell ({n} samples at {} Hz, mean and trend removed)",
        sig(a.figures.rate_hz)
    );
    let root = root.titled(&title, ("sans-serif", 22)).map_err(|e| err(path, &e))?;
    for (area, c) in channel_panels(a, &root) {
        let Some(model) = a.noise_model.iter().find(|m| m.channel == CHANNELS[c]) else { continue };
        let samples = a.figures.longest_dwell.get(c).map_or(&[][..], |s| s.as_slice());
        allan_panel(&area, model, samples, a.figures.rate_hz).map_err(|e| err(path, &e))?;
    }
    root.present().map_err(|e| err(path, &e))?;
    Ok(())
}

/// One channel's Allan deviation: the data (a dense curve and the octave points fitted, with 1-sigma bars), white
/// noise alone, the named terms' model and each term dashed.
fn allan_panel(area: &Area, model: &NoiseModel, samples: &[f64], rate_hz: f64) -> anyhow::Result<()> {
    let e = |e: &dyn std::fmt::Display| anyhow::anyhow!("{e}");
    let fit = &model.fit_points;
    let dense: Vec<(f64, f64)> = overlapping_allan_deviation(samples, rate_hz, &log_spaced_clusters(samples.len(), 10))
        .into_iter()
        .filter(|p| p.adev > 0.0 && p.adev.is_finite())
        .map(|p| (p.tau_s, p.adev))
        .collect();
    let (unit, per) = display_unit(&model.channel, 0.0);
    let (t0, t1) = (fit[0].tau_s * 0.8, dense.last().map_or(fit[fit.len() - 1].tau_s, |p| p.0) * 1.25);
    let data_lo = fit.iter().map(|p| (p.adev - p.adev_std).max(p.adev * 0.2)).chain(dense.iter().map(|p| p.1));
    let data_hi = fit.iter().map(|p| p.adev + p.adev_std).chain(dense.iter().map(|p| p.1));
    let mut lo = data_lo.fold(f64::INFINITY, f64::min) / per * 0.6;
    let mut hi = data_hi.fold(0.0, f64::max) / per * 1.6;
    if hi / lo < 10.0 {
        let mid = (hi * lo).sqrt();
        (lo, hi) = (mid / 3.2, mid * 3.2);
    }
    let axes = LogAxes {
        x: (t0, t1),
        y: (lo, hi),
        x_desc: "averaging time tau [s]".into(),
        y_desc: format!("Allan deviation [{unit}]"),
    };
    let mut chart = log_log_chart(area, &panel_caption(model), &axes)?;
    let taus: Vec<f64> = (0..=120).map(|i| t0 * (t1 / t0).powf(i as f64 / 120.0)).collect();
    let clip = |v: f64| (v / per >= lo && v / per <= hi).then_some(v / per);
    for term in &model.terms {
        let colour = TERM_COLOURS[term.term as usize];
        let pts: Vec<(f64, f64)> =
            taus.iter().filter_map(|&t| clip(term.allan_variance(t).sqrt()).map(|v| (t, v))).collect();
        chart
            .draw_series(DashedLineSeries::new(pts, 6, 4, colour.stroke_width(1)))
            .map_err(|x| e(&x))?
            .label(format!("  {}", term.text()))
            .legend(legend_line(colour, 1));
    }
    let white = &model.white_only;
    chart
        .draw_series(LineSeries::new(
            taus.iter().filter_map(|&t| clip(white.allan_variance(t).sqrt()).map(|v| (t, v))),
            RED.stroke_width(2),
        ))
        .map_err(|x| e(&x))?
        .label(format!("white only: N = {} {}", sig(white.value), white.unit))
        .legend(legend_line(RED, 2));
    chart
        .draw_series(LineSeries::new(
            taus.iter().filter_map(|&t| clip(model.allan_deviation(t)).map(|v| (t, v))),
            BLUE.stroke_width(3),
        ))
        .map_err(|x| e(&x))?
        .label(format!("named terms: {}", model.named))
        .legend(legend_line(BLUE, 3));
    allan_data(&mut chart, &dense, fit, per).map_err(|x| e(&x))?;
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::LowerLeft)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font(("sans-serif", 13))
        .draw()
        .map_err(|x| e(&x))?;
    Ok(())
}

type LogChart<'a, 'b> =
    ChartContext<'a, Png<'b>, Cartesian2d<WithKeyPoints<LogCoord<f64>>, WithKeyPoints<LogCoord<f64>>>>;

/// The ranges and descriptions of a log-log panel.
struct LogAxes {
    /// x range (both positive).
    x: (f64, f64),
    /// y range (both positive).
    y: (f64, f64),
    x_desc: String,
    y_desc: String,
}

/// A log-log panel of `area` with its caption, ticks at the decades (labels readable: `tick_label`) and axis
/// descriptions.
fn log_log_chart<'a, 'b>(area: &'a Area<'b>, caption: &str, axes: &LogAxes) -> anyhow::Result<LogChart<'a, 'b>> {
    let e = |e: &dyn std::fmt::Display| anyhow::anyhow!("{e}");
    let ((x0, x1), (y0, y1)) = (axes.x, axes.y);
    let mut chart = ChartBuilder::on(area)
        .caption(caption, ("sans-serif", 17))
        .margin(10)
        .x_label_area_size(40)
        .y_label_area_size(80)
        .build_cartesian_2d(
            (x0..x1).log_scale().with_key_points(log_ticks(x0, x1)),
            (y0..y1).log_scale().with_key_points(log_ticks(y0, y1)),
        )
        .map_err(|x| e(&x))?;
    chart
        .configure_mesh()
        .x_label_formatter(&|v| tick_label(*v))
        .y_label_formatter(&|v| tick_label(*v))
        .x_desc(axes.x_desc.as_str())
        .y_desc(axes.y_desc.as_str())
        .draw()
        .map_err(|x| e(&x))?;
    Ok(chart)
}

/// The measured Allan deviation: the dense curve (thin) and the fitted octave points with 1-sigma bars.
fn allan_data(chart: &mut LogChart, dense: &[(f64, f64)], fit: &[FitPoint], per: f64) -> anyhow::Result<()> {
    let e = |e: &dyn std::fmt::Display| anyhow::anyhow!("{e}");
    chart
        .draw_series(LineSeries::new(dense.iter().map(|p| (p.0, p.1 / per)), BLACK.mix(0.6).stroke_width(1)))
        .map_err(|x| e(&x))?;
    chart
        .draw_series(fit.iter().map(|p| {
            let lo = (p.adev - p.adev_std).max(p.adev * 0.05) / per;
            ErrorBar::new_vertical(p.tau_s, lo, p.adev / per, (p.adev + p.adev_std) / per, BLACK.stroke_width(1), 8)
        }))
        .map_err(|x| e(&x))?;
    chart
        .draw_series(fit.iter().map(|p| Circle::new((p.tau_s, p.adev / per), 4, BLACK.filled())))
        .map_err(|x| e(&x))?
        .label("data: octave points fitted, 1-sigma bars")
        .legend(|(x, y)| Circle::new((x + 12, y), 4, BLACK.filled()));
    Ok(())
}

fn panel_caption(model: &NoiseModel) -> String {
    let verdict = if model.better_than_white_only {
        "named terms fit better than white only"
    } else {
        "named terms not better than white only"
    };
    let lag1 = model.lag1_difference_autocorrelation.map_or(String::new(), |r| format!(", lag-1 diff. corr. {r:+.2}"));
    format!("{}: {verdict}{lag1}", short_name(&model.channel))
}

fn psd_plot(a: &Analysis, path: &Path) -> anyhow::Result<()> {
    let root = figure(path, noise_figure_size(a))?;
    let title = "One-sided power spectral density of the longest dwell (Welch, Hann, 1024-sample segments)";
    let root = root.titled(title, ("sans-serif", 22)).map_err(|e| err(path, &e))?;
    for (area, c) in channel_panels(a, &root) {
        let Some(samples) = a.figures.longest_dwell.get(c) else { continue };
        psd_panel(&area, a, c, samples).map_err(|e| err(path, &e))?;
    }
    root.present().map_err(|e| err(path, &e))?;
    Ok(())
}

/// `noise_level.png`: per channel, each one-second block's standard deviation against time (log scale), and
/// where a noise warm-up is named, the time it settles and the levels before and after.
fn noise_level_plot(a: &Analysis, path: &Path) -> anyhow::Result<()> {
    let root = figure(path, noise_figure_size(a))?;
    let title = "Noise level: the standard deviation of each one-second block of the dwells, against time";
    let root = root.titled(title, ("sans-serif", 22)).map_err(|e| err(path, &e))?;
    for (area, c) in channel_panels(a, &root) {
        let Some(levels) = a.figures.noise_level.get(c).filter(|l| l.len() > 1) else { continue };
        noise_level_panel(&area, a, c, levels).map_err(|e| err(path, &e))?;
    }
    root.present().map_err(|e| err(path, &e))?;
    Ok(())
}

fn noise_level_panel(area: &Area, a: &Analysis, c: usize, levels: &[(f64, f64)]) -> anyhow::Result<()> {
    let e = |e: &dyn std::fmt::Display| anyhow::anyhow!("{e}");
    let (unit, per) = display_unit(CHANNELS[c], 0.0);
    let points: Vec<(f64, f64)> = levels.iter().filter(|p| p.1 > 0.0).map(|&(t, s)| (t, s / per)).collect();
    let (Some(first), Some(last)) = (points.first(), points.last()) else { return Ok(()) };
    let (t0, t1) = (first.0.min(0.0), last.0.max(first.0 + 1.0));
    let lo = points.iter().map(|p| p.1).fold(f64::INFINITY, f64::min) * 0.8;
    let hi = points.iter().map(|p| p.1).fold(0.0, f64::max) * 1.25;
    let mut chart = ChartBuilder::on(area)
        .caption(short_name(CHANNELS[c]), ("sans-serif", 17))
        .margin(10)
        .x_label_area_size(40)
        .y_label_area_size(80)
        .build_cartesian_2d(t0..t1, (lo..hi).log_scale().with_key_points(log_ticks(lo, hi)))
        .map_err(|x| e(&x))?;
    chart
        .configure_mesh()
        .light_line_style(TRANSPARENT)
        .x_label_formatter(&|v| format!("{v:.0}"))
        .y_label_formatter(&|v| tick_label(*v))
        .x_desc("time since the first row [s]")
        .y_desc(format!("block standard deviation [{unit}]"))
        .draw()
        .map_err(|x| e(&x))?;
    let disturbed = a.diagnostics.iter().find(|d| d.channel == CHANNELS[c]).and_then(|d| d.disturbances.as_ref());
    if let Some(x) = disturbed {
        let shade = RGBColor(230, 140, 0).mix(0.35).filled();
        chart
            .draw_series(x.episodes_s.iter().map(|&[from, to]| Rectangle::new([(from, lo), (to, hi)], shade)))
            .map_err(|x| e(&x))?
            .label(format!("disturbed: {:.0} s in {} episodes", x.disturbed_s, x.episodes))
            .legend(move |(x, y)| Rectangle::new([(x + 6, y - 5), (x + 18, y + 5)], shade));
    }
    chart
        .draw_series(points.iter().map(|&p| Circle::new(p, 1, BLACK.mix(0.5).filled())))
        .map_err(|x| e(&x))?
        .label("one-second blocks")
        .legend(|(x, y)| Circle::new((x + 12, y), 3, BLACK.filled()));
    let warmup = a.effects.iter().find(|w| w.effect == EffectKind::NoiseWarmup.name() && w.channel() == Some(c));
    if let Some((w, settled)) = warmup.and_then(|w| w.settled_after_s.map(|s| (w, s))) {
        let after = w.residual_rms_after / per;
        let before = (after * after + (w.estimate / per).powi(2)).sqrt();
        chart
            .draw_series(LineSeries::new([(settled, lo), (settled, hi)], BLUE.stroke_width(2)))
            .map_err(|x| e(&x))?
            .label(format!("noise warm-up: settled after {settled:.1} s"))
            .legend(legend_line(BLUE, 2));
        chart
            .draw_series(LineSeries::new(
                [(t0, before), (settled, before), (settled, after), (t1, after)],
                RED.stroke_width(2),
            ))
            .map_err(|x| e(&x))?
            .label(format!("RMS level: {} before, {} after", sig(before), sig(after)))
            .legend(legend_line(RED, 2));
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .position(SeriesLabelPosition::UpperRight)
        .draw()
        .map_err(|x| e(&x))?;
    Ok(())
}

fn psd_panel(area: &Area, a: &Analysis, c: usize, samples: &[f64]) -> anyhow::Result<()> {
    let e = |e: &dyn std::fmt::Display| anyhow::anyhow!("{e}");
    let rate = a.figures.rate_hz;
    let seg = 1024.min(samples.len().next_power_of_two() / 2).max(2);
    let Ok(psd) = welch_psd(samples, rate, seg) else { return Ok(()) };
    let (unit, per) = display_unit(CHANNELS[c], 0.0);
    let per2 = per * per;
    let pts: Vec<(f64, f64)> = psd
        .frequencies_hz
        .iter()
        .zip(&psd.density)
        .skip(2)
        .filter(|(_, d)| **d > 0.0)
        .map(|(f, d)| (*f, *d / per2))
        .collect();
    if pts.len() < 2 {
        return Ok(());
    }
    let white = 2.0 * a.figures.base_sigma[c].powi(2) / rate / per2;
    let lo = pts.iter().map(|p| p.1).fold(f64::INFINITY, f64::min).min(white) * 0.5;
    let hi = pts.iter().map(|p| p.1).fold(0.0, f64::max).max(white) * 2.0;
    let (f0, f1) = (pts[0].0, pts[pts.len() - 1].0);
    let axes =
        LogAxes { x: (f0, f1), y: (lo, hi), x_desc: "frequency [Hz]".into(), y_desc: format!("PSD [({unit})^2/Hz]") };
    let mut chart = log_log_chart(area, short_name(CHANNELS[c]), &axes)?;
    chart
        .draw_series(LineSeries::new(pts.iter().copied(), BLACK.stroke_width(1)))
        .map_err(|x| e(&x))?
        .label("data")
        .legend(legend_line(BLACK, 1));
    let n_white = (white * per2 * rate / 2.0).sqrt() / rate.sqrt();
    let (n_unit, n_per) = crate::analysis::noise_terms::Term::White.unit_human(c < 3);
    chart
        .draw_series(LineSeries::new([(f0, white), (f1, white)], RED.stroke_width(2)))
        .map_err(|x| e(&x))?
        .label(format!("white level of the base model (N = {} {n_unit})", sig(n_white / n_per)))
        .legend(legend_line(RED, 2));
    if let Some(theta) =
        a.diagnostics.iter().find(|d| d.channel == CHANNELS[c]).map(|d| d.sample_colour_ma).filter(|t| *t != [0.0, 0.0])
    {
        // The moving average of white noise with the base model's variance.
        let colour = SampleColour { theta };
        let shape = |f: f64| white * colour.relative_density(f, rate);
        let curve: Vec<(f64, f64)> =
            (0..=200).map(|i| f0 * (f1 / f0).powf(i as f64 / 200.0)).map(|f| (f, shape(f))).collect();
        chart
            .draw_series(LineSeries::new(curve, MAGENTA.stroke_width(2)))
            .map_err(|x| e(&x))?
            .label(format!(
                "the sensor's filter (moving average {:.2}, {:.2}), removed before the correlated-noise test",
                theta[0], theta[1]
            ))
            .legend(legend_line(MAGENTA, 2));
    }
    for &(amp, f) in &a.figures.vibration[c] {
        chart
            .draw_series(LineSeries::new([(f, lo), (f, hi)], BLUE.stroke_width(2)))
            .map_err(|x| e(&x))?
            .label(format!("vibration found: {} Hz, {} {unit} seen", sig(f), sig(amp / per)))
            .legend(legend_line(BLUE, 2));
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::LowerLeft)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font(("sans-serif", 13))
        .draw()
        .map_err(|x| e(&x))?;
    Ok(())
}
