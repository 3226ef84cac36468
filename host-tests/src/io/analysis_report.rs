//! The report directory of `sinscal analyze --report DIR`: `summary.md` and figures (PNG, plotters).

use std::fmt::Write as _;
use std::path::Path;

use plotters::prelude::*;

use crate::analysis::{Analysis, CHANNELS};
use crate::stats::noise::{gauss_markov_allan_variance, log_spaced_clusters, overlapping_allan_deviation, welch_psd};

fn err(path: &Path, e: &dyn std::fmt::Display) -> anyhow::Error {
    anyhow::anyhow!("plot {}: {e}", path.display())
}

/// Writes `summary.md`, `residuals.png` and, for recordings, `allan.png` and `psd.png` into `dir`.
pub fn write_report(a: &Analysis, dir: &Path) -> anyhow::Result<Vec<String>> {
    std::fs::create_dir_all(dir).map_err(|e| anyhow::anyhow!("{}: {e}", dir.display()))?;
    let mut files = vec!["summary.md".to_string(), "residuals.png".to_string()];
    residuals_plot(a, &dir.join("residuals.png"))?;
    if !a.figures.longest_dwell.is_empty() {
        allan_plot(a, &dir.join("allan.png"))?;
        psd_plot(a, &dir.join("psd.png"))?;
        files.push("allan.png".into());
        files.push("psd.png".into());
    }
    let mut md = String::new();
    base_model_md(&mut md, a);
    effects_md(&mut md, a);
    diagnostics_md(&mut md, a);
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

/// `summary.md`: the effects found, strongest first.
fn effects_md(md: &mut String, a: &Analysis) {
    let _ = writeln!(md, "\n## Effects found (strongest first)\n");
    if a.effects.is_empty() {
        let _ = writeln!(md, "None: no candidate passes the criterion.\n");
        return;
    }
    let _ = writeln!(
        md,
        "| effect | sensor | axes | estimate | std error | unit | delta BIC | residual RMS before -> after | extra | aliases |\n|---|---|---|---|---|---|---|---|---|---|"
    );
    for e in &a.effects {
        let _ = writeln!(
            md,
            "| {} | {} | {} | {:+.4e} | {:.2e} | {} | {:.1} | {:.3e} -> {:.3e} {} ({}) | {} | {} |",
            e.effect,
            e.sensor,
            e.axes,
            e.estimate,
            e.std_error,
            e.unit,
            e.delta_bic,
            e.residual_rms_before,
            e.residual_rms_after,
            e.residual_unit,
            e.residual_of,
            e.extras(),
            e.aliases.join(", ")
        );
    }
}

/// `summary.md`: the per-channel diagnostics (recordings).
fn diagnostics_md(md: &mut String, a: &Analysis) {
    if a.diagnostics.is_empty() {
        return;
    }
    let _ = writeln!(md, "\n## Diagnostics per channel\n");
    let _ = writeln!(
        md,
        "| channel | detrended RMS | Ljung-Box p (20 lags, longest dwell) | largest within-dwell trend (z) | quantisation step |\n|---|---|---|---|---|"
    );
    for d in &a.diagnostics {
        let _ = writeln!(
            md,
            "| {} | {:.4e} | {:.3} | {:.1} | {} |",
            d.channel,
            d.detrended_rms,
            d.whiteness_p_value,
            d.max_trend_z,
            d.quantization_step.map_or("-".to_string(), |q| format!("{q:.4e}"))
        );
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
        let _ = writeln!(md, "- `allan.png`: overlapping Allan deviation of the longest dwell (each dwell's mean and trend removed), data against the base model's white noise and the model with the noise effects found.");
        let _ = writeln!(md, "- `psd.png`: Welch power spectral density (Hann, 1024-sample segments) of the same samples, with the base model's white level.");
    }
    let _ = writeln!(md, "\n![residuals](residuals.png)");
    if noise_figures {
        let _ = writeln!(md, "\n![allan](allan.png)\n\n![psd](psd.png)");
    }
}

fn residuals_plot(a: &Analysis, path: &Path) -> anyhow::Result<()> {
    let groups = a.figures.residuals.len().max(1);
    let root = BitMapBackend::new(path, (1200, 260 * groups as u32)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| err(path, &e))?;
    let areas = root.split_evenly((groups, 1));
    for (g, area) in areas.iter().enumerate() {
        let Some(points) = a.figures.residuals.get(g) else { continue };
        if points.is_empty() {
            continue;
        }
        let name = a.figures.residual_names.get(g).cloned().unwrap_or_default();
        let max_pos = points.iter().map(|p| p.0).max().unwrap_or(1) as f64;
        let ymax = points.iter().flat_map(|p| [p.1.abs(), p.2.abs()]).fold(1e-30, f64::max) * 1.1;
        let mut chart = ChartBuilder::on(area)
            .caption(format!("residual {name} by position: base (grey), final (blue)"), ("sans-serif", 16))
            .margin(8)
            .x_label_area_size(30)
            .y_label_area_size(80)
            .build_cartesian_2d(0.5f64..max_pos + 0.5, -ymax..ymax)
            .map_err(|e| err(path, &e))?;
        chart.configure_mesh().x_desc("position").y_desc(name.as_str()).draw().map_err(|e| err(path, &e))?;
        let n = points.len().max(1) as f64;
        let jitter = |i: usize| -0.3 + 0.6 * (i as f64 / n * 37.0).fract();
        chart
            .draw_series(
                points.iter().enumerate().map(|(i, p)| {
                    Circle::new((p.0 as f64 + jitter(i) - 0.05, p.1), 2, RGBColor(150, 150, 150).filled())
                }),
            )
            .map_err(|e| err(path, &e))?;
        chart
            .draw_series(
                points
                    .iter()
                    .enumerate()
                    .map(|(i, p)| Circle::new((p.0 as f64 + jitter(i) + 0.05, p.2), 2, RGBColor(30, 70, 200).filled())),
            )
            .map_err(|e| err(path, &e))?;
    }
    root.present().map_err(|e| err(path, &e))?;
    Ok(())
}

fn allan_plot(a: &Analysis, path: &Path) -> anyhow::Result<()> {
    let root = BitMapBackend::new(path, (1200, 900)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| err(path, &e))?;
    let areas = root.split_evenly((3, 2));
    let rate = a.figures.rate_hz;
    let dt = 1.0 / rate;
    for (c, area) in areas.iter().enumerate() {
        // Column-major: gyros left, accelerometers right.
        let channel = (c % 2) * 3 + c / 2;
        let Some(samples) = a.figures.longest_dwell.get(channel) else { continue };
        let clusters = log_spaced_clusters(samples.len(), 8);
        let points = overlapping_allan_deviation(samples, rate, &clusters);
        let points: Vec<_> = points.into_iter().filter(|p| p.adev > 0.0 && p.adev.is_finite()).collect();
        if points.is_empty() {
            continue;
        }
        let sigma = a.figures.base_sigma[channel];
        let base = |tau: f64| sigma * (dt / tau).sqrt();
        let extended = |tau: f64| {
            let mut white = sigma * sigma;
            let mut avar = 0.0;
            if let Some((s, t)) = a.figures.correlated[channel] {
                white = (white - s * s).max(0.0);
                avar += gauss_markov_allan_variance(s, t, tau);
            }
            if let Some((amp, f)) = a.figures.vibration[channel] {
                white = (white - 0.5 * amp * amp).max(0.0);
                let x = std::f64::consts::PI * f * tau;
                avar += amp * amp * x.sin().powi(4) / (x * x);
            }
            (avar + white * dt / tau).sqrt()
        };
        let (t0, t1) = (points[0].tau_s, points[points.len() - 1].tau_s);
        let lo = points.iter().map(|p| p.adev).fold(f64::INFINITY, f64::min).min(base(t1)) * 0.5;
        let hi = points.iter().map(|p| p.adev).fold(0.0, f64::max).max(base(t0)) * 2.0;
        let mut chart = ChartBuilder::on(area)
            .caption(format!("Allan deviation {}", CHANNELS[channel]), ("sans-serif", 16))
            .margin(8)
            .x_label_area_size(30)
            .y_label_area_size(70)
            .build_cartesian_2d((t0..t1).log_scale(), (lo..hi).log_scale())
            .map_err(|e| err(path, &e))?;
        chart.configure_mesh().x_desc("tau [s]").draw().map_err(|e| err(path, &e))?;
        chart
            .draw_series(LineSeries::new(points.iter().map(|p| (p.tau_s, p.adev)), BLACK.stroke_width(2)))
            .map_err(|e| err(path, &e))?
            .label("data")
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLACK.stroke_width(2)));
        chart
            .draw_series(LineSeries::new(
                points.iter().map(|p| (p.tau_s, base(p.tau_s))),
                RGBColor(200, 30, 30).stroke_width(2),
            ))
            .map_err(|e| err(path, &e))?
            .label("base model (white)")
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], RGBColor(200, 30, 30).stroke_width(2)));
        chart
            .draw_series(LineSeries::new(
                points.iter().map(|p| (p.tau_s, extended(p.tau_s))),
                RGBColor(30, 70, 200).stroke_width(2),
            ))
            .map_err(|e| err(path, &e))?
            .label("with noise effects found")
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], RGBColor(30, 70, 200).stroke_width(2)));
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::LowerLeft)
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .draw()
            .map_err(|e| err(path, &e))?;
    }
    root.present().map_err(|e| err(path, &e))?;
    Ok(())
}

fn psd_plot(a: &Analysis, path: &Path) -> anyhow::Result<()> {
    let root = BitMapBackend::new(path, (1200, 900)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| err(path, &e))?;
    let areas = root.split_evenly((3, 2));
    let rate = a.figures.rate_hz;
    for (c, area) in areas.iter().enumerate() {
        let channel = (c % 2) * 3 + c / 2;
        let Some(samples) = a.figures.longest_dwell.get(channel) else { continue };
        let seg = 1024.min(samples.len().next_power_of_two() / 2).max(2);
        let Ok(psd) = welch_psd(samples, rate, seg) else { continue };
        let pts: Vec<(f64, f64)> = psd
            .frequencies_hz
            .iter()
            .zip(&psd.density)
            .skip(1)
            .filter(|(_, d)| **d > 0.0)
            .map(|(f, d)| (*f, *d))
            .collect();
        if pts.is_empty() {
            continue;
        }
        let white = 2.0 * a.figures.base_sigma[channel].powi(2) / rate;
        let lo = pts.iter().map(|p| p.1).fold(f64::INFINITY, f64::min).min(white) * 0.5;
        let hi = pts.iter().map(|p| p.1).fold(0.0, f64::max).max(white) * 2.0;
        let (f0, f1) = (pts[0].0, pts[pts.len() - 1].0);
        let mut chart = ChartBuilder::on(area)
            .caption(format!("PSD {} (one-sided, unit^2/Hz)", CHANNELS[channel]), ("sans-serif", 16))
            .margin(8)
            .x_label_area_size(30)
            .y_label_area_size(70)
            .build_cartesian_2d((f0..f1).log_scale(), (lo..hi).log_scale())
            .map_err(|e| err(path, &e))?;
        chart.configure_mesh().x_desc("frequency [Hz]").draw().map_err(|e| err(path, &e))?;
        chart.draw_series(LineSeries::new(pts.iter().copied(), BLACK)).map_err(|e| err(path, &e))?;
        chart
            .draw_series(LineSeries::new([(f0, white), (f1, white)], RGBColor(200, 30, 30).stroke_width(2)))
            .map_err(|e| err(path, &e))?;
        if let Some((_, f)) = a.figures.vibration[channel] {
            chart
                .draw_series(LineSeries::new([(f, lo), (f, hi)], RGBColor(30, 70, 200).stroke_width(1)))
                .map_err(|e| err(path, &e))?;
        }
    }
    root.present().map_err(|e| err(path, &e))?;
    Ok(())
}
