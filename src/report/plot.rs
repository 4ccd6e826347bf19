//! SVG line and scatter charts for reports (`plotters` with its SVG backend only).
//!
//! Text is written as SVG `<text>` elements and laid out with plotters' built-in size
//! estimate, so no system font (fontconfig, freetype) is needed to make a chart; the viewer
//! picks a sans-serif font when it renders the file.
//!
//! ```no_run
//! use vanefit::report::plot::{Chart, Series};
//! let chart = Chart::new("Speed", "time [s]", "speed [rpm]")
//!     .with(Series::line("simulated", vec![(0.0, 0.0), (1.0, 3000.0)]));
//! chart.write_svg(std::path::Path::new("speed.svg")).unwrap();
//! ```

use plotters::coord::ranged1d::{AsRangedCoord, Ranged, ValueFormatter};
use plotters::coord::Shift;
use plotters::prelude::*;
use std::fmt;
use std::path::Path;

/// How a series is drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Style {
    /// Points joined by straight lines.
    #[default]
    Line,
    /// Markers only (measured data).
    Points,
}

/// One named curve.
#[derive(Debug, Clone, PartialEq)]
pub struct Series {
    /// Legend entry; an empty name is left out of the legend.
    pub name: String,
    /// (x, y) in the chart's units. Non-finite points, and non-positive ones on a log axis,
    /// are skipped (a line is broken there).
    pub points: Vec<(f64, f64)>,
    /// Line or points, and colour.
    pub style: Style,
}

impl Series {
    /// A line through the points.
    pub fn line(name: &str, points: Vec<(f64, f64)>) -> Self {
        Self {
            name: name.to_string(),
            points,
            style: Style::Line,
        }
    }

    /// Markers at the points.
    pub fn points(name: &str, points: Vec<(f64, f64)>) -> Self {
        Self {
            name: name.to_string(),
            points,
            style: Style::Points,
        }
    }
}

/// Where the legend goes inside the plotting area.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Legend {
    #[default]
    /// Top right corner.
    UpperRight,
    /// Top left corner.
    UpperLeft,
    /// Bottom right corner.
    LowerRight,
    /// Bottom left corner.
    LowerLeft,
    /// No legend.
    Hidden,
}

/// A chart with one pair of axes.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Chart {
    /// Title above the chart.
    pub title: String,
    /// Label of the x axis, with its unit.
    pub x_label: String,
    /// Label of the y axis, with its unit.
    pub y_label: String,
    /// Logarithmic x axis.
    pub log_x: bool,
    /// Logarithmic y axis.
    pub log_y: bool,
    /// Axis ranges; `None` fits the data (with a small margin on linear axes).
    pub x_range: Option<(f64, f64)>,
    /// Fixed y range (None: from the data).
    pub y_range: Option<(f64, f64)>,
    /// Where the legend goes.
    pub legend: Legend,
    /// The curves.
    pub series: Vec<Series>,
}

/// Why a chart could not be drawn.
#[derive(Debug, Clone, PartialEq)]
pub struct PlotError(pub String);

impl fmt::Display for PlotError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "plot: {}", self.0)
    }
}

impl std::error::Error for PlotError {}

/// Size of one panel, pixels.
const PANEL_W: u32 = 640;
const PANEL_H: u32 = 420;

/// Line colours, in order (colour-blind-safe Tableau 10).
const COLOURS: [RGBColor; 8] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
];

impl Chart {
    /// An empty chart with its title and axis labels.
    pub fn new(title: &str, x_label: &str, y_label: &str) -> Self {
        Self {
            title: title.to_string(),
            x_label: x_label.to_string(),
            y_label: y_label.to_string(),
            ..Self::default()
        }
    }

    /// Adds a series (builder style).
    pub fn with(mut self, s: Series) -> Self {
        self.series.push(s);
        self
    }

    /// With a logarithmic x axis.
    pub fn log_x(mut self) -> Self {
        self.log_x = true;
        self
    }

    /// With a logarithmic y axis.
    pub fn log_y(mut self) -> Self {
        self.log_y = true;
        self
    }

    /// With the legend at `at`.
    pub fn legend(mut self, at: Legend) -> Self {
        self.legend = at;
        self
    }

    /// The chart as a standalone SVG document.
    pub fn to_svg(&self) -> Result<String, PlotError> {
        Figure::new(vec![self.clone()], 1).to_svg()
    }

    /// Writes the SVG atomically (`fsutil::write_atomic`).
    pub fn write_svg(&self, path: &Path) -> Result<(), PlotError> {
        write(path, &self.to_svg()?)
    }

    /// Points of every series that can be shown on this chart's axes.
    fn visible(&self, p: &(f64, f64)) -> bool {
        p.0.is_finite()
            && p.1.is_finite()
            && (!self.log_x || p.0 > 0.0)
            && (!self.log_y || p.1 > 0.0)
    }

    fn data_range(&self, axis: usize, log: bool, fixed: Option<(f64, f64)>) -> (f64, f64) {
        if let Some((lo, hi)) = fixed {
            return (lo, hi);
        }
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for s in &self.series {
            for p in s.points.iter().filter(|p| self.visible(p)) {
                let v = if axis == 0 { p.0 } else { p.1 };
                lo = lo.min(v);
                hi = hi.max(v);
            }
        }
        if !lo.is_finite() {
            return if log { (0.1, 10.0) } else { (0.0, 1.0) };
        }
        if log {
            if hi <= lo * 1.0001 {
                (lo / 2.0, hi * 2.0)
            } else {
                let pad = (hi / lo).powf(0.03);
                (lo / pad, hi * pad)
            }
        } else if hi - lo <= 1e-12 * lo.abs().max(hi.abs()).max(1e-300) {
            let d = lo.abs().max(1.0) * 0.1;
            (lo - d, hi + d)
        } else {
            let pad = 0.04 * (hi - lo);
            (lo - pad, hi + pad)
        }
    }
}

/// Several charts on a grid, filled row by row.
#[derive(Debug, Clone, PartialEq)]
pub struct Figure {
    /// The charts, row by row.
    pub panels: Vec<Chart>,
    /// Charts per row.
    pub columns: usize,
}

impl Figure {
    /// A figure of `panels` in rows of `columns`.
    pub fn new(panels: Vec<Chart>, columns: usize) -> Self {
        Self { panels, columns }
    }

    /// The figure as a standalone SVG document.
    pub fn to_svg(&self) -> Result<String, PlotError> {
        let cols = self.columns.max(1).min(self.panels.len().max(1));
        let rows = self.panels.len().div_ceil(cols).max(1);
        let mut buf = String::new();
        {
            let root =
                SVGBackend::with_string(&mut buf, (PANEL_W * cols as u32, PANEL_H * rows as u32))
                    .into_drawing_area();
            root.fill(&WHITE).map_err(err)?;
            let areas = root.split_evenly((rows, cols));
            for (chart, area) in self.panels.iter().zip(&areas) {
                draw_any(area, chart)?;
            }
            root.present().map_err(err)?;
        }
        Ok(buf)
    }

    /// Writes the SVG atomically (`fsutil::write_atomic`).
    pub fn write_svg(&self, path: &Path) -> Result<(), PlotError> {
        write(path, &self.to_svg()?)
    }
}

fn write(path: &Path, svg: &str) -> Result<(), PlotError> {
    crate::io::write_atomic(path, svg.as_bytes())
        .map_err(|e| PlotError(format!("{}: {e}", path.display())))
}

fn err<E: std::error::Error>(e: E) -> PlotError {
    PlotError(e.to_string())
}

/// Dispatches on the axis kinds (plotters types linear and log axes differently).
fn draw_any<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    chart: &Chart,
) -> Result<(), PlotError> {
    let (x0, x1) = chart.data_range(0, chart.log_x, chart.x_range);
    let (y0, y1) = chart.data_range(1, chart.log_y, chart.y_range);
    match (chart.log_x, chart.log_y) {
        (false, false) => draw(area, chart, x0..x1, y0..y1),
        (true, false) => draw(area, chart, (x0..x1).log_scale(), y0..y1),
        (false, true) => draw(area, chart, x0..x1, (y0..y1).log_scale()),
        (true, true) => draw(area, chart, (x0..x1).log_scale(), (y0..y1).log_scale()),
    }
}

/// A tick label: short, fixed point in the usual range, scientific otherwise.
fn tick(v: f64) -> String {
    let a = v.abs();
    if a == 0.0 {
        "0".into()
    } else if !(1e-3..1e5).contains(&a) {
        let s = format!("{v:.1e}");
        s.replace(".0e", "e")
    } else {
        let s = format!("{v:.4}");
        let s = s.trim_end_matches('0').trim_end_matches('.');
        s.to_string()
    }
}

fn draw<DB, X, Y>(area: &DrawingArea<DB, Shift>, chart: &Chart, x: X, y: Y) -> Result<(), PlotError>
where
    DB: DrawingBackend,
    X: AsRangedCoord<Value = f64>,
    Y: AsRangedCoord<Value = f64>,
    X::CoordDescType: Ranged<ValueType = f64> + ValueFormatter<f64>,
    Y::CoordDescType: Ranged<ValueType = f64> + ValueFormatter<f64>,
{
    let mut cc = ChartBuilder::on(area)
        .caption(&chart.title, ("sans-serif", 18))
        .margin(12)
        .x_label_area_size(44)
        .y_label_area_size(64)
        .build_cartesian_2d(x, y)
        .map_err(err)?;
    let fmt = |v: &f64| tick(*v);
    cc.configure_mesh()
        .x_desc(chart.x_label.as_str())
        .y_desc(chart.y_label.as_str())
        .x_label_formatter(&fmt)
        .y_label_formatter(&fmt)
        .axis_desc_style(("sans-serif", 15))
        .label_style(("sans-serif", 13))
        .light_line_style(RGBColor(238, 238, 238))
        .draw()
        .map_err(err)?;
    let mut named = false;
    for (k, s) in chart.series.iter().enumerate() {
        let colour = COLOURS[k % COLOURS.len()];
        // Split at points that cannot be shown, so that a line is broken there.
        let mut runs: Vec<Vec<(f64, f64)>> = vec![Vec::new()];
        for p in &s.points {
            if chart.visible(p) {
                runs.last_mut().expect("never empty").push(*p);
            } else if !runs.last().expect("never empty").is_empty() {
                runs.push(Vec::new());
            }
        }
        let mut first = true;
        for run in runs.into_iter().filter(|r| !r.is_empty()) {
            let anno = match s.style {
                Style::Line => cc
                    .draw_series(LineSeries::new(run, colour.stroke_width(2)))
                    .map_err(err)?,
                Style::Points => cc
                    .draw_series(run.into_iter().map(|p| Circle::new(p, 3, colour.filled())))
                    .map_err(err)?,
            };
            if first && !s.name.is_empty() {
                named = true;
                let anno = anno.label(s.name.as_str());
                match s.style {
                    Style::Line => anno.legend(move |(lx, ly)| {
                        PathElement::new(vec![(lx, ly), (lx + 18, ly)], colour.stroke_width(2))
                    }),
                    Style::Points => {
                        anno.legend(move |(lx, ly)| Circle::new((lx + 9, ly), 3, colour.filled()))
                    }
                };
            }
            first = false;
        }
    }
    let pos = match chart.legend {
        Legend::UpperRight => SeriesLabelPosition::UpperRight,
        Legend::UpperLeft => SeriesLabelPosition::UpperLeft,
        Legend::LowerRight => SeriesLabelPosition::LowerRight,
        Legend::LowerLeft => SeriesLabelPosition::LowerLeft,
        Legend::Hidden => return Ok(()),
    };
    if named {
        cc.configure_series_labels()
            .position(pos)
            .background_style(WHITE.mix(0.85))
            .border_style(RGBColor(160, 160, 160))
            .label_font(("sans-serif", 13))
            .draw()
            .map_err(err)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sine(n: usize) -> Vec<(f64, f64)> {
        (0..n)
            .map(|k| {
                let x = k as f64 / n as f64 * 6.0;
                (x, x.sin())
            })
            .collect()
    }

    #[test]
    fn chart_is_svg_with_series_names_and_labels() {
        let chart = Chart::new("Speed & <torque>", "time [s]", "speed [rpm]")
            .with(Series::line("simulated", sine(50)))
            .with(Series::points("measured", sine(10)));
        let svg = chart.to_svg().unwrap();
        assert!(svg.trim_start().starts_with("<svg"), "{}", &svg[..60]);
        assert!(svg.trim_end().ends_with("</svg>"));
        for text in ["simulated", "measured", "time [s]", "speed [rpm]"] {
            assert!(svg.contains(text), "missing {text}");
        }
        // Special characters are escaped, not written raw into the XML.
        assert!(svg.contains("&lt;torque&gt;"));
        assert!(svg.contains("<polyline"), "no line drawn");
        assert!(svg.contains("<circle"), "no markers drawn");
    }

    #[test]
    fn log_axes_skip_non_positive_points_and_multi_panel_has_every_title() {
        let bode = Chart::new("Bode magnitude", "f [Hz]", "|G|")
            .log_x()
            .log_y()
            .with(Series::line(
                "G",
                vec![
                    (0.0, 1.0),
                    (0.1, 1.0),
                    (1.0, 0.5),
                    (10.0, 0.05),
                    (100.0, -1.0),
                ],
            ));
        let phase = Chart::new("Bode phase", "f [Hz]", "phase [deg]")
            .log_x()
            .with(Series::line("G", vec![(0.1, -5.0), (10.0, -150.0)]));
        let fig = Figure::new(vec![bode, phase, Chart::new("empty", "x", "y")], 2);
        let svg = fig.to_svg().unwrap();
        for t in ["Bode magnitude", "Bode phase", "empty"] {
            assert!(svg.contains(t), "missing {t}");
        }
        assert!(svg.contains("width=\"1280\"") && svg.contains("height=\"840\""));
        assert!(!svg.contains("NaN") && !svg.contains("inf"));
    }

    #[test]
    fn write_svg_replaces_the_file() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("c.svg");
        std::fs::write(&path, "old").unwrap();
        Chart::new("t", "x", "y")
            .with(Series::line("a", sine(5)))
            .write_svg(&path)
            .unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        assert!(text.starts_with("<svg") && text.contains("<text"), "{text}");
    }

    #[test]
    fn ticks_are_short() {
        assert_eq!(tick(0.0), "0");
        assert_eq!(tick(2500.0), "2500");
        assert_eq!(tick(0.25), "0.25");
        assert_eq!(tick(1e-8), "1e-8");
        assert_eq!(tick(-3.5e6), "-3.5e6");
    }
}
