//! Figures (PNG, plotters).

use std::path::Path;
use std::sync::OnceLock;

use ab_glyph::{point, Font, FontRef, PxScale, ScaleFont};
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters_backend::text_anchor::{HPos, VPos};
use plotters_backend::{BackendColor, BackendCoord, BackendTextStyle, DrawingErrorKind};

use crate::io::ARCSEC_PER_RAD;
use crate::navigation::check::NavReport;

/// The figures' font: DejaVu Sans, bundled by the `dejavu` crate (the font's licence ships there), so that no
/// font library of the system (fontconfig, FreeType: C libraries) is needed. Its line height (the `hhea`
/// ascender less the descender) is set to 1.24 em, the ratio of text size to em of plotters' font-kit path:
/// ab_glyph scales a font by that height, so that plotters' own estimates (a legend's box) and [`Png`]'s text
/// both set text of size `s` at one em = s / 1.24 pixels, as the figures had it.
fn font_bytes() -> &'static [u8] {
    static BYTES: OnceLock<&'static [u8]> = OnceLock::new();
    BYTES.get_or_init(|| {
        let mut font = dejavu::sans::regular().to_vec();
        let be16 = |b: &[u8], at: usize| b.get(at..at + 2).map(|v| u16::from_be_bytes([v[0], v[1]]));
        let table = |b: &[u8], tag: &[u8; 4]| {
            (0..usize::from(be16(b, 4)?)).map(|i| 12 + 16 * i).find_map(|r| {
                let o = b.get(r + 8..r + 12)?;
                (b.get(r..r + 4)? == tag).then(|| u32::from_be_bytes([o[0], o[1], o[2], o[3]]) as usize)
            })
        };
        let units_per_em = table(&font, b"head").and_then(|head| be16(&font, head + 18));
        let hhea = table(&font, b"hhea");
        let descender = hhea.and_then(|h| be16(&font, h + 6)).map(|d| d as i16);
        if let (Some(upem), Some(hhea), Some(descender)) = (units_per_em, hhea, descender) {
            let ascender = (1.24 * f64::from(upem)).round() as i16 + descender;
            font[hhea + 4..hhea + 6].copy_from_slice(&ascender.to_be_bytes());
        }
        Box::leak(font.into_boxed_slice())
    })
}

/// The figures' font, read.
fn font() -> &'static FontRef<'static> {
    static FONT: OnceLock<FontRef<'static>> = OnceLock::new();
    FONT.get_or_init(|| FontRef::try_from_slice(font_bytes()).expect("DejaVu Sans is a font ab_glyph reads"))
}

/// Registers the figures' font with plotters (its `ab_glyph` text path) as `sans-serif`, the family every
/// figure names: plotters sizes a legend's box with it. The text itself is drawn by [`Png`].
fn register_font() -> anyhow::Result<()> {
    static REGISTERED: OnceLock<bool> = OnceLock::new();
    let ok = *REGISTERED
        .get_or_init(|| plotters::style::register_font("sans-serif", FontStyle::Normal, font_bytes()).is_ok());
    anyhow::ensure!(ok, "the figures' font (DejaVu Sans) could not be read");
    Ok(())
}

/// A PNG figure: plotters' bitmap backend, with text drawn by ab_glyph (pure Rust) from [`font`]. Text of size
/// `s` pixels is set at one em = s / 1.24 pixels, its box s / 1.24 high with the baseline 0.76 em below the top
/// (the metrics of plotters' font-kit path, so that the figures keep their layout), each glyph placed at its
/// own side bearing and sub-pixel position.
pub(crate) struct Png<'a>(BitMapBackend<'a>);

impl Png<'_> {
    /// The scale (ab_glyph's pixel height: ascent - descent) that makes one em `size / 1.24` pixels.
    fn scale(size: f64) -> PxScale {
        let f = font();
        let em = (size / 1.24) as f32;
        PxScale::from(em * f.height_unscaled() / f.units_per_em().unwrap_or(2048.0))
    }

    /// The advance width of `text` in pixels.
    fn width(text: &str, scale: PxScale) -> f32 {
        let f = font().as_scaled(scale);
        let mut prev = None;
        let mut x = 0.0;
        for c in text.chars() {
            let id = f.glyph_id(c);
            if let Some(p) = prev {
                x += f.kern(p, id);
            }
            x += f.h_advance(id);
            prev = Some(id);
        }
        x
    }
}

impl DrawingBackend for Png<'_> {
    type ErrorType = <BitMapBackend<'static> as DrawingBackend>::ErrorType;

    fn get_size(&self) -> (u32, u32) {
        self.0.get_size()
    }
    fn ensure_prepared(&mut self) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        self.0.ensure_prepared()
    }
    fn present(&mut self) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        self.0.present()
    }
    fn draw_pixel(
        &mut self,
        point: BackendCoord,
        color: BackendColor,
    ) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        self.0.draw_pixel(point, color)
    }
    fn draw_line<S: plotters_backend::BackendStyle>(
        &mut self,
        from: BackendCoord,
        to: BackendCoord,
        style: &S,
    ) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        self.0.draw_line(from, to, style)
    }
    fn draw_rect<S: plotters_backend::BackendStyle>(
        &mut self,
        upper_left: BackendCoord,
        bottom_right: BackendCoord,
        style: &S,
        fill: bool,
    ) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        self.0.draw_rect(upper_left, bottom_right, style, fill)
    }
    fn draw_path<S: plotters_backend::BackendStyle, I: IntoIterator<Item = BackendCoord>>(
        &mut self,
        path: I,
        style: &S,
    ) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        self.0.draw_path(path, style)
    }
    fn draw_circle<S: plotters_backend::BackendStyle>(
        &mut self,
        center: BackendCoord,
        radius: u32,
        style: &S,
        fill: bool,
    ) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        self.0.draw_circle(center, radius, style, fill)
    }
    fn fill_polygon<S: plotters_backend::BackendStyle, I: IntoIterator<Item = BackendCoord>>(
        &mut self,
        vert: I,
        style: &S,
    ) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        self.0.fill_polygon(vert, style)
    }
    fn blit_bitmap(
        &mut self,
        pos: BackendCoord,
        size: (u32, u32),
        src: &[u8],
    ) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        self.0.blit_bitmap(pos, size, src)
    }

    fn estimate_text_size<S: BackendTextStyle>(
        &self,
        text: &str,
        style: &S,
    ) -> Result<(u32, u32), DrawingErrorKind<Self::ErrorType>> {
        let size = style.size();
        Ok((Self::width(text, Self::scale(size)) as u32, (size / 1.24) as u32))
    }

    fn draw_text<S: BackendTextStyle>(
        &mut self,
        text: &str,
        style: &S,
        pos: BackendCoord,
    ) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        let color = style.color();
        if color.alpha == 0.0 {
            return Ok(());
        }
        let size = style.size();
        let scale = Self::scale(size);
        let (width, height) = (Self::width(text, scale) as i32, (size / 1.24) as i32);
        let anchor = style.anchor();
        let dx = match anchor.h_pos {
            HPos::Left => 0,
            HPos::Right => -width,
            HPos::Center => -width / 2,
        };
        let dy = match anchor.v_pos {
            VPos::Top => 0,
            VPos::Center => -height / 2,
            VPos::Bottom => -height,
        };
        let transform = style.transform();
        let (w, h) = self.get_size();
        let baseline = (0.76 * size / 1.24) as f32;
        let f = font().as_scaled(scale);
        let mut result = Ok(());
        let mut x = 0.0;
        let mut prev = None;
        for c in text.chars() {
            let id = f.glyph_id(c);
            if let Some(p) = prev {
                x += f.kern(p, id);
            }
            prev = Some(id);
            if let Some(outline) = font().outline_glyph(id.with_scale_and_position(scale, point(x, baseline))) {
                let min = outline.px_bounds().min;
                outline.draw(|gx, gy, coverage| {
                    let (tx, ty) = transform.transform(min.x as i32 + gx as i32 + dx, min.y as i32 + gy as i32 + dy);
                    let (px, py) = (pos.0 + tx, pos.1 + ty);
                    if coverage > 0.0 && px >= 0 && py >= 0 && px < w as i32 && py < h as i32 && result.is_ok() {
                        result = self.0.draw_pixel((px, py), color.mix(f64::from(coverage)));
                    }
                });
            }
            x += f.h_advance(id);
        }
        result
    }
}

/// A new figure: a white PNG of `size` pixels at `path`. Every figure starts here.
pub(crate) fn figure(path: &Path, size: (u32, u32)) -> anyhow::Result<DrawingArea<Png<'_>, Shift>> {
    register_font()?;
    let root = Png(BitMapBackend::new(path, size)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| anyhow::anyhow!("plot {}: {e}", path.display()))?;
    Ok(root)
}

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
    let root = figure(path, (1200, 900))?;
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
