//! PNG figures: a grid of x–y panels, each with labelled line series. Text is drawn with the
//! DejaVu Sans font embedded in the binary, so figures look the same on every host.

use std::path::Path;
use std::sync::Once;

use plotters::prelude::*;

use crate::io::file::FileError;

/// One curve of a panel.
pub struct Series {
    pub label: String,
    pub points: Vec<(f64, f64)>,
    /// Index into the palette.
    pub color: usize,
    /// Dots instead of a line (for measured data).
    pub dots: bool,
}

/// One chart.
pub struct Panel {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    pub series: Vec<Series>,
    /// Same scale on both axes (for a path in the plane).
    pub equal_axes: bool,
}

/// A shaded band between two curves on the same abscissae (an uncertainty band).
pub struct Band {
    pub label: String,
    /// (x, lower, upper) per point.
    pub points: Vec<(f64, f64, f64)>,
    /// Index into the palette.
    pub color: usize,
}

const PALETTE: [RGBColor; 6] = [
    RGBColor(214, 39, 40),
    RGBColor(31, 119, 180),
    RGBColor(44, 160, 44),
    RGBColor(100, 100, 100),
    RGBColor(148, 103, 189),
    RGBColor(255, 127, 14),
];

pub(crate) fn register_font() {
    static FONT: Once = Once::new();
    FONT.call_once(|| {
        // the embedded font is valid TrueType; a failure here would only lose the text
        let _ = plotters::style::register_font(
            "sans-serif",
            FontStyle::Normal,
            dejavu::sans::regular(),
        );
    });
}

fn bounds(panel: &Panel, bands: &[Band]) -> ((f64, f64), (f64, f64)) {
    let (mut x0, mut x1, mut y0, mut y1) = (
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    );
    let band_points = bands
        .iter()
        .flat_map(|b| b.points.iter().flat_map(|&(x, lo, hi)| [(x, lo), (x, hi)]));
    for (x, y) in panel
        .series
        .iter()
        .flat_map(|s| s.points.iter().copied())
        .chain(band_points)
    {
        if x.is_finite() && y.is_finite() {
            (x0, x1, y0, y1) = (x0.min(x), x1.max(x), y0.min(y), y1.max(y));
        }
    }
    if !x0.is_finite() {
        return ((0.0, 1.0), (0.0, 1.0));
    }
    let pad = |a: f64, b: f64| {
        let m = ((b - a) * 0.05).max(1e-12 * a.abs().max(1.0));
        (a - m, b + m)
    };
    let (mut xr, mut yr) = (pad(x0, x1), pad(y0, y1));
    if panel.equal_axes {
        let half = 0.5 * (xr.1 - xr.0).max(yr.1 - yr.0);
        let (cx, cy) = (0.5 * (xr.0 + xr.1), 0.5 * (yr.0 + yr.1));
        xr = (cx - half, cx + half);
        yr = (cy - half, cy + half);
    }
    (xr, yr)
}

/// Draws `panels` in a grid of `columns` columns into the PNG `path` of `width × height` pixels.
pub fn draw(
    path: &Path,
    panels: &[Panel],
    columns: usize,
    size: (u32, u32),
) -> Result<(), FileError> {
    draw_with_bands(path, panels, &[], columns, size)
}

/// [`draw`] with shaded bands under the curves: `bands[i]` belongs to `panels[i]` (missing
/// entries: none).
pub fn draw_with_bands(
    path: &Path,
    panels: &[Panel],
    bands: &[Vec<Band>],
    columns: usize,
    (width, height): (u32, u32),
) -> Result<(), FileError> {
    to_png(path, (width, height), |root| {
        let rows = panels.len().div_ceil(columns);
        let areas = root.split_evenly((rows, columns));
        for (k, (panel, area)) in panels.iter().zip(areas.iter()).enumerate() {
            let panel_bands = bands.get(k).map_or(&[][..], |b| b.as_slice());
            let ((x0, x1), (y0, y1)) = bounds(panel, panel_bands);
            let mut chart = ChartBuilder::on(area)
                .caption(&panel.title, ("sans-serif", 20))
                .margin(12)
                .x_label_area_size(42)
                .y_label_area_size(70)
                .build_cartesian_2d(x0..x1, y0..y1)
                .map_err(|e| e.to_string())?;
            chart
                .configure_mesh()
                .x_desc(panel.x_label.as_str())
                .y_desc(panel.y_label.as_str())
                .label_style(("sans-serif", 14))
                .axis_desc_style(("sans-serif", 16))
                .light_line_style(RGBColor(235, 235, 235))
                .draw()
                .map_err(|e| e.to_string())?;
            for b in panel_bands {
                let color = PALETTE[b.color % PALETTE.len()];
                let finite = |&&(x, lo, hi): &&(f64, f64, f64)| {
                    x.is_finite() && lo.is_finite() && hi.is_finite()
                };
                let outline: Vec<(f64, f64)> = b
                    .points
                    .iter()
                    .filter(finite)
                    .map(|&(x, _, hi)| (x, hi))
                    .chain(
                        b.points
                            .iter()
                            .rev()
                            .filter(finite)
                            .map(|&(x, lo, _)| (x, lo)),
                    )
                    .collect();
                chart
                    .draw_series(std::iter::once(Polygon::new(
                        outline,
                        color.mix(0.25).filled(),
                    )))
                    .map_err(|e| e.to_string())?
                    .label(b.label.as_str())
                    .legend(move |(x, y)| {
                        Rectangle::new([(x, y - 5), (x + 18, y + 5)], color.mix(0.25).filled())
                    });
            }
            for s in &panel.series {
                let color = PALETTE[s.color % PALETTE.len()];
                let pts = s
                    .points
                    .iter()
                    .copied()
                    .filter(|(x, y)| x.is_finite() && y.is_finite());
                let drawn = if s.dots {
                    chart.draw_series(pts.map(|p| Circle::new(p, 1, color.filled())))
                } else {
                    chart.draw_series(LineSeries::new(pts, color.stroke_width(2)))
                }
                .map_err(|e| e.to_string())?;
                drawn.label(s.label.as_str()).legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 18, y)], color.stroke_width(3))
                });
            }
            legend(&mut chart, 14)?;
        }
        Ok(())
    })
}

/// Draws into the PNG `path` of `size` pixels on a white ground through `draw`, by way of a
/// temporary file beside it: a failed drawing leaves no figure, a finished one replaces the old
/// one whole.
pub(crate) fn to_png(
    path: &Path,
    size: (u32, u32),
    draw: impl FnOnce(&DrawingArea<BitMapBackend, plotters::coord::Shift>) -> Result<(), String>,
) -> Result<(), FileError> {
    register_font();
    let fail = |e: String| FileError::new(path, format!("cannot draw the figure: {e}"));
    let tmp = path.with_extension("tmp.png");
    let drawn = (|| {
        let root = BitMapBackend::new(&tmp, size).into_drawing_area();
        root.fill(&WHITE).map_err(|e| e.to_string())?;
        draw(&root)?;
        root.present().map_err(|e| e.to_string())
    })();
    if let Err(e) = drawn.and_then(|()| std::fs::rename(&tmp, path).map_err(|e| e.to_string())) {
        let _ = std::fs::remove_file(&tmp);
        return Err(fail(e));
    }
    Ok(())
}

/// The series' legend box in the upper right corner, its text of `font_size` pixels.
pub(crate) fn legend<'a, DB: DrawingBackend + 'a, CT: CoordTranslate>(
    chart: &mut ChartContext<'a, DB, CT>,
    font_size: u32,
) -> Result<(), String>
where
    DB::ErrorType: 'static,
{
    chart
        .configure_series_labels()
        .label_font(("sans-serif", font_size))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()
        .map_err(|e| e.to_string())
}
