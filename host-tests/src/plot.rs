//! Figures (PNG, plotters).

use std::path::Path;

use plotters::prelude::*;

use crate::io::ARCSEC_PER_RAD;
use crate::navigation::check::NavReport;

fn run_color(name: &str, index: usize) -> RGBColor {
    if name == "uncompensated" {
        RGBColor(200, 30, 30)
    } else if name == "true errors removed" {
        RGBColor(30, 150, 60)
    } else if index == 1 {
        RGBColor(30, 70, 200)
    } else {
        RGBColor(230, 140, 0)
    }
}

/// The navigation check as a figure: horizontal position error (log scale) and heading error over time,
/// one line per run.
pub fn navigation_plot(report: &NavReport, path: &Path) -> anyhow::Result<()> {
    let err = |e: &dyn std::fmt::Display| anyhow::anyhow!("plot {}: {e}", path.display());
    let root = BitMapBackend::new(path, (1200, 900)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| err(&e))?;
    let (upper, lower) = root.split_vertically(470);
    let hours = report.hours.max(1e-6);
    let floor = 1e-3;
    let pos_max = report
        .histories
        .iter()
        .flat_map(|(_, h)| h.iter().map(|e| e.horizontal_position_m()))
        .fold(floor * 10.0, f64::max)
        * 1.5;
    let title = format!(
        "Static navigation, {:.2} h at lat {:.4} deg, attitude ({}, {}, {}) deg{}",
        report.hours,
        report.latitude_deg,
        report.attitude_deg[0],
        report.attitude_deg[1],
        report.attitude_deg[2],
        if report.simulated { " (SIMULATION)" } else { "" }
    );
    let mut chart = ChartBuilder::on(&upper)
        .caption(title, ("sans-serif", 22))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(80)
        .build_cartesian_2d(0f64..hours, (floor..pos_max).log_scale())
        .map_err(|e| err(&e))?;
    chart.configure_mesh().x_desc("time [h]").y_desc("horizontal position error [m]").draw().map_err(|e| err(&e))?;
    for (i, (name, history)) in report.histories.iter().enumerate() {
        let color = run_color(name, i);
        chart
            .draw_series(LineSeries::new(
                history.iter().map(|e| (e.t_s / 3600.0, e.horizontal_position_m().max(floor))),
                color.stroke_width(2),
            ))
            .map_err(|e| err(&e))?
            .label(name.clone())
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 24, y)], color.stroke_width(3)));
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::LowerRight)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()
        .map_err(|e| err(&e))?;

    let heading: Vec<(String, Vec<(f64, f64)>)> = report
        .histories
        .iter()
        .map(|(n, h)| (n.clone(), h.iter().map(|e| (e.t_s / 3600.0, e.attitude_n_rad[2] * ARCSEC_PER_RAD)).collect()))
        .collect();
    let hmax = heading.iter().flat_map(|(_, p)| p.iter().map(|(_, y)| y.abs())).fold(1.0, f64::max) * 1.1;
    let mut chart = ChartBuilder::on(&lower)
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(80)
        .build_cartesian_2d(0f64..hours, -hmax..hmax)
        .map_err(|e| err(&e))?;
    chart.configure_mesh().x_desc("time [h]").y_desc("heading error phi_u [arcsec]").draw().map_err(|e| err(&e))?;
    for (i, (name, points)) in heading.into_iter().enumerate() {
        chart.draw_series(LineSeries::new(points, run_color(&name, i).stroke_width(2))).map_err(|e| err(&e))?;
    }
    root.present().map_err(|e| err(&e))?;
    Ok(())
}

/// Tick values for a log axis over `lo..hi` (both > 0): the powers of ten inside, with 2 and 5 times them
/// when the range spans less than two decades.
pub(crate) fn log_ticks(lo: f64, hi: f64) -> Vec<f64> {
    let (a, b) = (lo.log10().floor() as i32, hi.log10().ceil() as i32);
    let mantissas: &[f64] = if hi / lo < 100.0 { &[1.0, 2.0, 5.0] } else { &[1.0] };
    (a..=b)
        .flat_map(|e| mantissas.iter().map(move |m| m * 10f64.powi(e)))
        .filter(|v| *v >= lo * (1.0 - 1e-9) && *v <= hi * (1.0 + 1e-9))
        .collect()
}

/// A tick label that reads as written: `0.01`, `2`, `500`, `1e-5`, `2e5` (no rounding noise).
pub(crate) fn tick_label(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return "0".into();
    }
    let mut e = v.abs().log10().floor() as i32;
    let mut m = (v / 10f64.powi(e) * 1000.0).round() / 1000.0;
    if m.abs() >= 10.0 {
        m /= 10.0;
        e += 1;
    }
    if (-3..=4).contains(&e) {
        let decimals = (-e).max(0) as usize + if (m - m.round()).abs() > 1e-9 { 1 } else { 0 };
        format!("{:.decimals$}", m * 10f64.powi(e))
    } else if (m - 1.0).abs() < 1e-9 {
        format!("1e{e}")
    } else {
        format!("{m}e{e}")
    }
}

/// The unit a channel's values are shown in, and the SI value of one of it: deg/h for rates (`_radps`), ug
/// (mg above 10,000 ug) for specific force (`_mps2`), arcsec for angles (`_rad`).
pub(crate) fn display_unit(channel: &str, max_abs_si: f64) -> (&'static str, f64) {
    use crate::model::synth::{DEG_PER_HOUR, MICRO_G};
    if channel.ends_with("_radps") {
        ("deg/h", DEG_PER_HOUR)
    } else if channel.ends_with("_mps2") {
        if max_abs_si > 1e4 * MICRO_G {
            ("mg", 1e3 * MICRO_G)
        } else {
            ("ug", MICRO_G)
        }
    } else if channel.ends_with("_rad") {
        ("arcsec", 1.0 / ARCSEC_PER_RAD)
    } else {
        ("SI", 1.0)
    }
}

/// The channel name without its unit suffix (`gx_radps` -> `gx`, `phi_u_rad` -> `phi_u`).
pub(crate) fn short_name(channel: &str) -> &str {
    channel.rsplit_once('_').map_or(channel, |(a, _)| a)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tick_labels_read_as_written() {
        assert_eq!(tick_label(1e-5), "1e-5");
        assert_eq!(tick_label(9.999999999999999e-5), "1e-4");
        assert_eq!(tick_label(0.01), "0.01");
        assert_eq!(tick_label(0.002), "0.002");
        assert_eq!(tick_label(500.0), "500");
        assert_eq!(tick_label(2e5), "2e5");
        assert_eq!(log_ticks(0.003, 0.2), vec![0.005, 0.01, 0.02, 0.05, 0.1, 0.2]);
        assert_eq!(log_ticks(1e-6, 1e-2).len(), 5);
    }
}
