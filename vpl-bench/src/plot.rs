//! Line charts as PNG files (plotters, with an embedded DejaVu Sans Mono so
//! the text needs no system fonts).

use plotters::prelude::*;
use std::path::Path;
use std::sync::Once;

/// DejaVu Sans Mono (Bitstream Vera licence: `assets/DejaVuSansMono-LICENSE.txt`).
static FONT: &[u8] = include_bytes!("../assets/DejaVuSansMono.ttf");
static REGISTER: Once = Once::new();

/// Errors of the plots.
#[derive(Debug, thiserror::Error)]
pub enum PlotError {
    /// Plotters could not draw.
    #[error("plot {0}: {1}")]
    Draw(String, String),
    /// Nothing to plot.
    #[error("plot {0}: no points")]
    Empty(String),
    /// The file could not be written.
    #[error(transparent)]
    Core(#[from] vpl_core::CoreError),
}

/// One line of a chart.
#[derive(Clone, Debug, PartialEq)]
pub struct Series {
    /// Legend entry (empty: none).
    pub label: String,
    /// Points (x, y), drawn in order.
    pub points: Vec<(f64, f64)>,
    /// Colour (RGB).
    pub color: (u8, u8, u8),
    /// Thicker line (the reference).
    pub bold: bool,
    /// Mark each point.
    pub markers: bool,
}

/// A line chart.
#[derive(Clone, Debug, PartialEq)]
pub struct Chart<'a> {
    /// Title above the plot.
    pub title: &'a str,
    /// Label of the x axis.
    pub x_label: &'a str,
    /// Label of the y axis.
    pub y_label: &'a str,
    /// Logarithmic axes (x, y).
    pub log: (bool, bool),
    /// Size in pixels.
    pub size: (u32, u32),
}

/// Colours of the methods in every chart: ground truth black, the rest
/// distinct and colour-blind-safe (Okabe–Ito).
pub fn method_color(name: &str) -> (u8, u8, u8) {
    match name {
        "truth" | "reference" => (0, 0, 0),
        "ir" => (230, 159, 0),
        "rr" => (86, 180, 233),
        "mir" | "mir-resample" => (0, 158, 115),
        "tcas" => (204, 121, 167),
        "smc" => (213, 94, 0),
        "smc-knn" => (0, 114, 178),
        _ => (120, 120, 120),
    }
}

fn range(v: impl Iterator<Item = f64>, log: bool) -> Option<(f64, f64)> {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for x in v.filter(|x| x.is_finite() && (!log || *x > 0.0)) {
        lo = lo.min(x);
        hi = hi.max(x);
    }
    if !lo.is_finite() {
        return None;
    }
    if log {
        Some((lo / 1.2, hi * 1.2))
    } else {
        let pad = ((hi - lo) * 0.05).max(1e-9);
        Some((lo - pad, hi + pad))
    }
}

/// A short axis label: no trailing ".0", three significant digits.
fn tick(v: f64) -> String {
    if v == 0.0 {
        return "0".into();
    }
    let a = v.abs();
    if !(1e-3..1e5).contains(&a) {
        format!("{v:.1e}")
    } else if a >= 100.0 {
        format!("{v:.0}")
    } else {
        let s = format!("{v:.3}");
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    }
}

/// Draws `series` into `path` (PNG, written atomically).
pub fn line_chart(path: &Path, chart: &Chart, series: &[Series]) -> Result<(), PlotError> {
    let png = line_chart_png(&path.display().to_string(), chart, series)?;
    vpl_core::image::write_atomic(path, &png)?;
    Ok(())
}

/// The PNG file of [`line_chart`], in memory (`name` names it in errors).
pub fn line_chart_png(name: &str, chart: &Chart, series: &[Series]) -> Result<Vec<u8>, PlotError> {
    REGISTER.call_once(|| {
        // The font is part of the binary; failing to parse it is a build defect.
        let _ = plotters::style::register_font("sans-serif", FontStyle::Normal, FONT);
    });
    let name = name.to_string();
    let draw = |e: &dyn std::fmt::Display| PlotError::Draw(name.clone(), e.to_string());
    let (log_x, log_y) = chart.log;
    let (x0, x1) = range(series.iter().flat_map(|s| s.points.iter().map(|p| p.0)), log_x).ok_or_else(|| PlotError::Empty(name.clone()))?;
    let (y0, y1) = range(series.iter().flat_map(|s| s.points.iter().map(|p| p.1)), log_y).ok_or_else(|| PlotError::Empty(name.clone()))?;
    let (w, h) = chart.size;
    let mut buf = vec![0u8; w as usize * h as usize * 3];
    {
        let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| draw(&e))?;
        let mut b = ChartBuilder::on(&root);
        b.caption(chart.title, ("sans-serif", 18)).margin(12).x_label_area_size(40).y_label_area_size(70);
        macro_rules! body {
            ($c:expr) => {{
                let mut c = $c.map_err(|e| draw(&e))?;
                c.configure_mesh()
                    .x_desc(chart.x_label)
                    .y_desc(chart.y_label)
                    .label_style(("sans-serif", 13))
                    .x_label_formatter(&|v| tick(*v))
                    .y_label_formatter(&|v| tick(*v))
                    .draw()
                    .map_err(|e| draw(&e))?;
                for s in series {
                    let col = RGBColor(s.color.0, s.color.1, s.color.2);
                    let style = col.stroke_width(if s.bold { 3 } else { 2 });
                    let pts: Vec<(f64, f64)> =
                        s.points.iter().copied().filter(|p| (!log_x || p.0 > 0.0) && (!log_y || p.1 > 0.0)).collect();
                    let drawn = c.draw_series(LineSeries::new(pts.clone(), style)).map_err(|e| draw(&e))?;
                    // A series without a label (another run of a method already named) stays out of the legend.
                    if !s.label.is_empty() {
                        // The legend's line as the series draws it: as wide, with a marker if its points have them.
                        let (width, marker) = (if s.bold { 3 } else { 2 }, if s.markers { 4 } else { 0 });
                        drawn.label(s.label.clone()).legend(move |(x, y)| {
                            EmptyElement::at((x, y))
                                + PathElement::new(vec![(0, 0), (20, 0)], col.stroke_width(width))
                                + Circle::new((10, 0), marker, col.filled())
                        });
                    }
                    if s.markers {
                        c.draw_series(pts.iter().map(|&p| Circle::new(p, 4, col.filled()))).map_err(|e| draw(&e))?;
                    }
                }
                c.configure_series_labels()
                    .label_font(("sans-serif", 13))
                    .background_style(WHITE.mix(0.85))
                    .border_style(BLACK)
                    .position(SeriesLabelPosition::UpperRight)
                    .draw()
                    .map_err(|e| draw(&e))?;
            }};
        }
        match (log_x, log_y) {
            (false, false) => body!(b.build_cartesian_2d(x0..x1, y0..y1)),
            (true, false) => body!(b.build_cartesian_2d((x0..x1).log_scale(), y0..y1)),
            (false, true) => body!(b.build_cartesian_2d(x0..x1, (y0..y1).log_scale())),
            (true, true) => body!(b.build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale())),
        }
        root.present().map_err(|e| draw(&e))?;
    }
    vpl_scene_io::encode_png_rgb8(w, h, &buf).map_err(|e| PlotError::Draw(name, e))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn draws_a_chart_with_text_and_refuses_an_empty_one() {
        let dir = std::env::temp_dir().join(format!("vpl-plot-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("c.png");
        let s =
            Series { label: "a".into(), points: vec![(1.0, 2.0), (2.0, 3.0), (4.0, 1.0)], color: (200, 0, 0), bold: false, markers: true };
        let c = Chart { title: "t", x_label: "x", y_label: "y", log: (true, true), size: (320, 240) };
        line_chart(&p, &c, std::slice::from_ref(&s)).unwrap();
        let bytes = std::fs::read(&p).unwrap();
        assert_eq!(&bytes[1..4], b"PNG");
        // Some pixels are the series' colour: the line was drawn.
        let dec = png::Decoder::new(std::io::Cursor::new(bytes));
        let mut r = dec.read_info().unwrap();
        let mut img = vec![0; r.output_buffer_size().unwrap()];
        r.next_frame(&mut img).unwrap();
        assert!(img.chunks(3).any(|p| p == [200, 0, 0]));
        let empty = Series { points: vec![], ..s };
        assert!(matches!(line_chart(&p, &c, &[empty]), Err(PlotError::Empty(_))));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
