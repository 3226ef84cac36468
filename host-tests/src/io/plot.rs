//! Figures (PNG, plotters).

use std::path::Path;

use plotters::prelude::*;

use crate::io::calibration_result::ARCSEC_PER_RAD;
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
