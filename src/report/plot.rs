//! SVG line and scatter charts for reports (`plotters` with its SVG backend only).
//!
//! Text is written as SVG `<text>` elements and laid out with plotters' built-in size
//! estimate, so no system font (fontconfig, freetype) is needed to make a chart; the viewer
//! picks a sans-serif font when it renders the file.
//!
//! Legends sit outside the plotting area, to its right or below it, so that they never hide
//! data; the figure grows to hold them. A logarithmic axis is labelled at every power of ten
//! (every second or third one when it spans more than `MAX_LOG_LABELS` decades), with light
//! grid lines at the multiples 2–9 between; an axis is widened to whole decades, so that
//! both ends carry a label, where that adds at most half the data's span, and an axis with
//! fewer than two powers of ten inside is labelled at 1, 2 and 5 times them as well.
//!
//! ```no_run
//! use vanefit::report::plot::{Chart, Series};
//! let chart = Chart::new("Speed", "time [s]", "speed [rpm]")
//!     .with(Series::line("simulated", vec![(0.0, 0.0), (1.0, 3000.0)]));
//! chart.write_svg(std::path::Path::new("speed.svg")).unwrap();
//! ```

use plotters::coord::combinators::{LogCoord, WithKeyPoints};
use plotters::coord::ranged1d::{AsRangedCoord, Ranged, ValueFormatter};
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use std::path::Path;

/// How a series is drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Style {
    /// Points joined by straight lines.
    #[default]
    Line,
    /// Markers only (measured data).
    Points,
    /// A cross at each point, larger than [`Style::Points`] (a fitted value where there is
    /// a single point to compare, so no line to draw).
    Marker,
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

    /// Crosses at the points ([`Style::Marker`]).
    pub(crate) fn marker(name: &str, points: Vec<(f64, f64)>) -> Self {
        Self {
            name: name.to_string(),
            points,
            style: Style::Marker,
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

/// Where the legend goes: always outside the plotting area, so that it covers no data.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Legend {
    #[default]
    /// To the right of the plotting area, top-aligned with it; the panel widens to hold it.
    Right,
    /// Below the x-axis title, entries side by side (wrapped into rows); the panel grows
    /// taller to hold it.
    Below,
    /// No legend.
    Hidden,
    /// As [`Legend::Right`] (kept for callers written when legends sat inside the plot).
    UpperRight,
    /// As [`Legend::Right`] (kept for callers written when legends sat inside the plot).
    UpperLeft,
    /// As [`Legend::Right`] (kept for callers written when legends sat inside the plot).
    LowerRight,
    /// As [`Legend::Right`] (kept for callers written when legends sat inside the plot).
    LowerLeft,
}

impl Legend {
    /// Whether the legend goes below the plot (else, unless hidden, to its right).
    fn below(self) -> bool {
        self == Legend::Below
    }
}

/// A chart with one pair of axes.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Chart {
    /// Title above the chart.
    pub(crate) title: String,
    /// Label of the x axis, with its unit.
    pub(crate) x_label: String,
    /// Label of the y axis, with its unit.
    pub(crate) y_label: String,
    /// Logarithmic x axis.
    pub(crate) log_x: bool,
    /// Logarithmic y axis.
    pub(crate) log_y: bool,
    /// Axis ranges; `None` fits the data (with a small margin on linear axes).
    pub(crate) x_range: Option<(f64, f64)>,
    /// Fixed y range (None: from the data).
    pub(crate) y_range: Option<(f64, f64)>,
    /// Where the legend goes.
    pub(crate) legend: Legend,
    /// The curves.
    pub(crate) series: Vec<Series>,
    /// Names of the categories at x = 1, 2, … (a fleet's motors), written as the x tick
    /// labels instead of numbers; empty for a numeric x axis.
    pub(crate) x_names: Vec<String>,
    /// The index into [`COLOURS`] of each series, set by a [`Figure`] so that a series
    /// keeps one colour in every panel; empty (or short): the series' position.
    pub(crate) colours: Vec<usize>,
}

/// Why a chart could not be drawn.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum PlotError {
    /// The drawing backend failed (plotters' message: its errors borrow the backend).
    #[error("plot: {0}")]
    Draw(String),
    /// The SVG file could not be written.
    #[error("plot: {}: {source}", path.display())]
    Write {
        /// The file.
        path: std::path::PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// A model to draw does not simulate.
    #[error("plot: {0}")]
    Sim(#[from] crate::sim::experiment::SimError),
    /// A channel to draw is not in its recording.
    #[error("plot: {0}")]
    Data(#[from] crate::data::DataError),
    /// A channel to draw is not in its recording.
    #[error("plot: {0}")]
    MissingColumn(#[from] crate::sim::recording::MissingColumn),
}

/// Size of one panel's chart (title, axes and plotting area), pixels; a legend adds to it.
const PANEL_W: u32 = 640;
const PANEL_H: u32 = 420;

/// Legend text size as given to plotters (the SVG gets 13/1.24 ≈ 10.5 px, as tick labels).
const LEGEND_FONT: u32 = 13;
/// Width of one legend character, pixels: a generous average for a sans-serif font at
/// 10.5 px (≈ 0.6 em), so that the box holds its text in the usual viewers.
const LEGEND_CHAR_W: f64 = 6.2;
/// Half the width of a [`Style::Marker`] cross, pixels.
const MARKER_SIZE: i32 = 6;
/// Height of one legend row, pixels.
const LEGEND_ROW_H: i32 = 18;
/// Length of a legend's line sample, pixels.
const LEGEND_GLYPH_W: i32 = 18;
/// Padding inside the legend box, pixels.
const LEGEND_PAD: i32 = 6;
/// Space between a legend glyph and its text, and after an entry in a row, pixels.
const LEGEND_SPACE: i32 = 6;
/// Widest row of a legend below the chart, pixels.
const LEGEND_BELOW_W: i32 = PANEL_W as i32 - 100;

/// The most decades a logarithmic axis labels one by one; beyond, every second (third, ...)
/// power of ten is labelled and the others get grid lines.
const MAX_LOG_LABELS: usize = 12;

/// Line colours, in order (colour-blind-safe Tableau 10), for every chart.
pub(crate) const COLOURS: [RGBColor; 8] = [
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
    pub(crate) fn log_x(mut self) -> Self {
        self.log_x = true;
        self
    }

    /// With a logarithmic y axis.
    pub(crate) fn log_y(mut self) -> Self {
        self.log_y = true;
        self
    }

    /// With the legend at `at`.
    pub(crate) fn legend(mut self, at: Legend) -> Self {
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
            } else if let Some(range) = whole_decades(lo, hi) {
                range
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

/// One legend entry: a named series that has something to show.
struct Entry<'a> {
    name: &'a str,
    style: Style,
    colour: RGBColor,
}

impl Chart {
    /// The legend's entries (none when it is hidden).
    fn legend_entries(&self) -> Vec<Entry<'_>> {
        if self.legend == Legend::Hidden {
            return Vec::new();
        }
        self.series
            .iter()
            .enumerate()
            .filter(|(_, s)| !s.name.is_empty() && s.points.iter().any(|p| self.visible(p)))
            .map(|(k, s)| Entry {
                name: &s.name,
                style: s.style,
                colour: self.colour(k),
            })
            .collect()
    }

    /// The colour of the `k`-th series.
    fn colour(&self, k: usize) -> RGBColor {
        COLOURS[self.colours.get(k).copied().unwrap_or(k) % COLOURS.len()]
    }

    /// The room (width, height) the legend takes beside or below the chart, pixels.
    fn legend_extent(&self) -> (u32, u32) {
        let entries = self.legend_entries();
        if entries.is_empty() {
            return (0, 0);
        }
        if self.legend.below() {
            let ((_, h), _) = legend_layout(&entries, Some(LEGEND_BELOW_W));
            (0, (h + 2 + LEGEND_PAD) as u32)
        } else {
            let ((w, _), _) = legend_layout(&entries, None);
            (w as u32 + 12, 0)
        }
    }
}

/// Estimated width of a legend text, pixels.
fn text_width(text: &str) -> i32 {
    (LEGEND_CHAR_W * text.chars().count() as f64).ceil() as i32
}

/// Width of one legend entry (glyph, space, text), pixels.
fn entry_width(e: &Entry) -> i32 {
    LEGEND_GLYPH_W + LEGEND_SPACE + text_width(e.name)
}

/// The legend box's (width, height) and each entry's anchor (left end of its glyph, centre
/// line of its row) relative to the box: one column, or rows no wider than `max_w`.
type LegendLayout = ((i32, i32), Vec<(i32, i32)>);

fn legend_layout(entries: &[Entry], max_w: Option<i32>) -> LegendLayout {
    let row_centre = |row: i32| LEGEND_PAD + row * LEGEND_ROW_H + LEGEND_ROW_H / 2;
    let Some(max_w) = max_w else {
        let w = entries.iter().map(entry_width).max().unwrap_or(0) + 2 * LEGEND_PAD;
        let anchors = (0..entries.len() as i32)
            .map(|i| (LEGEND_PAD, row_centre(i)))
            .collect();
        return (
            (w, 2 * LEGEND_PAD + entries.len() as i32 * LEGEND_ROW_H),
            anchors,
        );
    };
    let (mut x, mut row, mut w) = (LEGEND_PAD, 0, 0);
    let mut anchors = Vec::with_capacity(entries.len());
    for e in entries {
        let ew = entry_width(e);
        if x > LEGEND_PAD && x + ew + LEGEND_PAD > max_w {
            row += 1;
            x = LEGEND_PAD;
        }
        anchors.push((x, row_centre(row)));
        w = w.max(x + ew + LEGEND_PAD);
        x += ew + 3 * LEGEND_SPACE;
    }
    ((w, 2 * LEGEND_PAD + (row + 1) * LEGEND_ROW_H), anchors)
}

/// A pixel rectangle \[x0, y0, x1, y1\], absolute in the SVG.
type PixelRect = [i32; 4];

/// Where a panel's plotting area (the data rectangle) and its legend box were drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct PanelGeometry {
    plot: PixelRect,
    legend: Option<PixelRect>,
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

    /// The figure as a standalone SVG document. Every cell of the grid is a chart of
    /// `PANEL_W` × `PANEL_H` pixels; a column is widened by the widest legend beside its
    /// charts, a row made taller by the tallest legend below them.
    pub fn to_svg(&self) -> Result<String, PlotError> {
        self.render().map(|(svg, _)| svg)
    }

    /// The panels with one colour per series name throughout the figure: a name takes the
    /// colour it had in the first panel that showed it; a name not seen before keeps its
    /// position's colour unless a series seen before holds that colour in the same panel,
    /// and then takes the first colour neither used in the panel nor held by another name
    /// (else the first free in the panel). (A single chart, or panels whose names do not
    /// recur at other positions, keep their positions' colours.)
    fn shared_colours(&self) -> Vec<Chart> {
        let mut known: Vec<(String, usize)> = Vec::new();
        let mut panels = self.panels.clone();
        for chart in &mut panels {
            let seen = |name: &str, known: &[(String, usize)]| {
                known
                    .iter()
                    .find(|(n, _)| !n.is_empty() && n == name)
                    .map(|(_, c)| *c)
            };
            let fixed: Vec<Option<usize>> =
                chart.series.iter().map(|s| seen(&s.name, &known)).collect();
            let mut taken: Vec<usize> = fixed.iter().flatten().copied().collect();
            let mut colours = Vec::with_capacity(fixed.len());
            for (k, (s, c)) in chart.series.iter().zip(&fixed).enumerate() {
                let c = c.unwrap_or_else(|| {
                    let c = if taken.contains(&(k % COLOURS.len())) {
                        let owned = |c: &usize| known.iter().any(|(_, o)| o == c);
                        let free = |c: &usize| !taken.contains(c);
                        (0..COLOURS.len())
                            .find(|c| free(c) && !owned(c))
                            .or_else(|| (0..COLOURS.len()).find(free))
                            .unwrap_or(k % COLOURS.len())
                    } else {
                        k % COLOURS.len()
                    };
                    taken.push(c);
                    if !s.name.is_empty() {
                        known.push((s.name.clone(), c));
                    }
                    c
                });
                colours.push(c);
            }
            chart.colours = colours;
        }
        panels
    }

    /// The SVG and, per panel, where its plotting area and legend ended up.
    fn render(&self) -> Result<(String, Vec<PanelGeometry>), PlotError> {
        let panels = self.shared_colours();
        let cols = self.columns.max(1).min(self.panels.len().max(1));
        let rows = self.panels.len().div_ceil(cols).max(1);
        let (mut widths, mut heights) = (vec![PANEL_W; cols], vec![PANEL_H; rows]);
        for (i, chart) in self.panels.iter().enumerate() {
            let (w, h) = chart.legend_extent();
            widths[i % cols] = widths[i % cols].max(PANEL_W + w);
            heights[i / cols] = heights[i / cols].max(PANEL_H + h);
        }
        let offset = |sizes: &[u32], k: usize| sizes[..k].iter().sum::<u32>();
        let mut geometry = Vec::with_capacity(self.panels.len());
        let mut buf = String::new();
        {
            let size = (widths.iter().sum::<u32>(), heights.iter().sum::<u32>());
            let root = SVGBackend::with_string(&mut buf, size).into_drawing_area();
            root.fill(&WHITE).map_err(err)?;
            for (i, chart) in panels.iter().enumerate() {
                let (c, r) = (i % cols, i / cols);
                let cell = root.clone().shrink(
                    (offset(&widths, c), offset(&heights, r)),
                    (widths[c], heights[r]),
                );
                geometry.push(draw_panel(&cell, chart)?);
            }
            root.present().map_err(err)?;
        }
        Ok((buf, geometry))
    }

    /// Writes the SVG atomically (`fsutil::write_atomic`).
    pub fn write_svg(&self, path: &Path) -> Result<(), PlotError> {
        write(path, &self.to_svg()?)
    }
}

fn write(path: &Path, svg: &str) -> Result<(), PlotError> {
    crate::io::write_atomic(path, svg.as_bytes()).map_err(|source| PlotError::Write {
        path: path.to_path_buf(),
        source,
    })
}

fn err<E: std::error::Error>(e: E) -> PlotError {
    PlotError::Draw(e.to_string())
}

/// Draws a chart and its legend in one cell of a figure: the chart in the cell's top-left
/// `PANEL_W` × `PANEL_H` pixels, the legend outside its plotting area.
fn draw_panel<DB: DrawingBackend>(
    cell: &DrawingArea<DB, Shift>,
    chart: &Chart,
) -> Result<PanelGeometry, PlotError> {
    let area = cell.clone().shrink((0, 0), (PANEL_W, PANEL_H));
    let plot = draw_any(&area, chart)?;
    let entries = chart.legend_entries();
    if entries.is_empty() {
        return Ok(PanelGeometry { plot, legend: None });
    }
    let (bx, by) = cell.get_base_pixel();
    let (origin, max_w) = if chart.legend.below() {
        ((plot[0] - bx, PANEL_H as i32 + 2), Some(LEGEND_BELOW_W))
    } else {
        ((PANEL_W as i32, plot[1] - by), None)
    };
    let (size, anchors) = legend_layout(&entries, max_w);
    draw_legend(cell, origin, size, &entries, &anchors)?;
    let legend = [
        bx + origin.0,
        by + origin.1,
        bx + origin.0 + size.0,
        by + origin.1 + size.1,
    ];
    Ok(PanelGeometry {
        plot,
        legend: Some(legend),
    })
}

/// Draws a legend box at `(x0, y0)` of `cell` (cell pixels) with its entries at `anchors`.
fn draw_legend<DB: DrawingBackend>(
    cell: &DrawingArea<DB, Shift>,
    (x0, y0): (i32, i32),
    (w, h): (i32, i32),
    entries: &[Entry],
    anchors: &[(i32, i32)],
) -> Result<(), PlotError> {
    let corners = [(x0, y0), (x0 + w, y0 + h)];
    cell.draw(&Rectangle::new(corners, WHITE.filled()))
        .map_err(err)?;
    cell.draw(&Rectangle::new(
        corners,
        RGBColor(160, 160, 160).stroke_width(1),
    ))
    .map_err(err)?;
    let font = ("sans-serif", LEGEND_FONT)
        .into_font()
        .color(&BLACK)
        .pos(Pos::new(HPos::Left, VPos::Center));
    for (e, (dx, dy)) in entries.iter().zip(anchors) {
        let (x, y) = (x0 + dx, y0 + dy);
        match e.style {
            Style::Line => cell.draw(&PathElement::new(
                vec![(x, y), (x + LEGEND_GLYPH_W, y)],
                e.colour.stroke_width(2),
            )),
            Style::Points => cell.draw(&Circle::new(
                (x + LEGEND_GLYPH_W / 2, y),
                3,
                e.colour.filled(),
            )),
            Style::Marker => cell.draw(&Cross::new(
                (x + LEGEND_GLYPH_W / 2, y),
                MARKER_SIZE,
                e.colour.stroke_width(2),
            )),
        }
        .map_err(err)?;
        let text_x = x + LEGEND_GLYPH_W + LEGEND_SPACE;
        cell.draw(&Text::new(e.name, (text_x, y), font.clone()))
            .map_err(err)?;
    }
    Ok(())
}

/// Dispatches on the axis kinds (plotters types linear and log axes differently); returns
/// the plotting area's pixels.
fn draw_any<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    chart: &Chart,
) -> Result<PixelRect, PlotError> {
    let (x0, x1) = chart.data_range(0, chart.log_x, chart.x_range);
    let (y0, y1) = chart.data_range(1, chart.log_y, chart.y_range);
    let spans = [
        (!chart.log_x).then_some((x0, x1)),
        (!chart.log_y).then_some((y0, y1)),
    ];
    match (chart.log_x, chart.log_y) {
        (false, false) => draw(area, chart, x0..x1, y0..y1, spans),
        (true, false) => draw(area, chart, log_axis(x0, x1), y0..y1, spans),
        (false, true) => draw(area, chart, x0..x1, log_axis(y0, y1), spans),
        (true, true) => draw(area, chart, log_axis(x0, x1), log_axis(y0, y1), spans),
    }
}

/// A logarithmic axis from `lo` to `hi` with the labels and grid lines of [`log_ticks`].
fn log_axis(lo: f64, hi: f64) -> WithKeyPoints<LogCoord<f64>> {
    let (major, minor) = log_ticks(lo, hi);
    (lo..hi)
        .log_scale()
        .with_key_points(major)
        .with_light_points(minor)
}

/// The data range `lo..hi` widened to whole decades, with 2% of the span to spare so that
/// the end labels' data are not drawn on the frame; `None` when that would take more than
/// 1.5 times the data's own span (a short range keeps its data filling the axis).
fn whole_decades(lo: f64, hi: f64) -> Option<(f64, f64)> {
    let span = (hi / lo).log10();
    let a = (lo.log10() + 1e-9).floor();
    let b = (hi.log10() - 1e-9).ceil();
    if b - a > 1.5 * span {
        return None;
    }
    let pad = 0.02 * (b - a);
    Some((10f64.powf(a - pad), 10f64.powf(b + pad)))
}

/// 10^d as the nearest double (as the literal `1e{d}` reads).
fn power_of_ten(d: i32) -> f64 {
    format!("1e{d}").parse().expect("a number")
}

/// Labelled ticks and light grid lines of a logarithmic axis from `lo` to `hi` (> 0): a
/// label at every power of ten inside (every second, third, ... when there are more than
/// [`MAX_LOG_LABELS`]) and grid lines at the multiples 1–9 of each decade that carry no
/// label. An axis with fewer than two powers of ten inside is labelled at 1, 2 and 5 times
/// them (or every multiple, or its ends).
fn log_ticks(lo: f64, hi: f64) -> (Vec<f64>, Vec<f64>) {
    let inside = |v: &f64| *v >= lo * (1.0 - 1e-12) && *v <= hi * (1.0 + 1e-12);
    let (first, last) = (lo.log10().floor() as i32, hi.log10().ceil() as i32);
    let multiples = |ms: &[u32]| -> Vec<f64> {
        (first..=last)
            .flat_map(|d| ms.iter().map(move |m| f64::from(*m) * power_of_ten(d)))
            .filter(inside)
            .collect()
    };
    let decades: Vec<i32> = (first..=last)
        .filter(|d| inside(&power_of_ten(*d)))
        .collect();
    let all = multiples(&[1, 2, 3, 4, 5, 6, 7, 8, 9]);
    let major = if decades.len() >= 2 {
        let step = decades.len().div_ceil(MAX_LOG_LABELS) as i32;
        decades
            .iter()
            .filter(|d| d.rem_euclid(step) == 0)
            .map(|d| power_of_ten(*d))
            .collect()
    } else {
        let one_two_five = multiples(&[1, 2, 5]);
        if one_two_five.len() >= 2 {
            one_two_five
        } else if all.len() >= 2 {
            all.clone()
        } else {
            vec![lo, hi]
        }
    };
    let minor = all
        .into_iter()
        .filter(|v| !major.iter().any(|m| (m - v).abs() <= 1e-9 * m))
        .collect();
    (major, minor)
}

/// A tick label on a linear axis spanning `lo..hi`: as many significant digits as tell
/// neighbouring ticks apart (about a tenth of the span), so that a narrow span far from zero
/// (a conductance known to 0.1 %) is not labelled with one number repeated.
fn tick_in(v: f64, lo: f64, hi: f64) -> String {
    // Ticks fall at most a twentieth of the span apart.
    let step = (hi - lo).abs() / 20.0;
    let m = lo.abs().max(hi.abs());
    if !(step > 0.0 && m > 0.0 && step.is_finite() && m.is_finite()) || v == 0.0 {
        return tick(v);
    }
    // A tick at zero computed as a difference of rounded numbers (−2.2e-16) is zero.
    if v.abs() < step * 1e-6 {
        return "0".into();
    }
    let step_exp = step.log10().floor() as i32;
    if !(1e-3..1e5).contains(&m) {
        // One precision for every tick of the axis, trailing zeros kept.
        let prec = (m.log10().floor() as i32 - step_exp).clamp(1, 9) as usize;
        format!("{v:.prec$e}")
    } else {
        let decimals = (-step_exp).clamp(0, 10) as usize;
        let s = format!("{v:.decimals$}");
        if s.contains('.') {
            s.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            s
        }
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

/// Draws the title, axes and series of a chart on `area`; returns the plotting area's pixels.
fn draw<DB, X, Y>(
    area: &DrawingArea<DB, Shift>,
    chart: &Chart,
    x: X,
    y: Y,
    spans: [Option<(f64, f64)>; 2],
) -> Result<PixelRect, PlotError>
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
    let label = |axis: usize| {
        move |v: &f64| match spans[axis] {
            Some((lo, hi)) => tick_in(*v, lo, hi),
            None => tick(*v),
        }
    };
    let (numeric_x, fy) = (label(0), label(1));
    let fx = |v: &f64| {
        if chart.x_names.is_empty() {
            numeric_x(v)
        } else {
            category_label(&chart.x_names, *v)
        }
    };
    cc.configure_mesh()
        .x_labels(x_label_count(chart, spans[0]))
        .x_desc(chart.x_label.as_str())
        .y_desc(chart.y_label.as_str())
        .x_label_formatter(&fx)
        .y_label_formatter(&fy)
        .axis_desc_style(("sans-serif", 15))
        .label_style(("sans-serif", 13))
        .light_line_style(RGBColor(238, 238, 238))
        .draw()
        .map_err(err)?;
    for (k, s) in chart.series.iter().enumerate() {
        let colour = chart.colour(k);
        for run in visible_runs(chart, s) {
            draw_run(&mut cc, s.style, run, colour)?;
        }
    }
    let (xs, ys) = cc.plotting_area().get_pixel_range();
    Ok([xs.start, ys.start, xs.end, ys.end])
}

/// The label of named categories at the integers 1..=n: their names there, nothing
/// between.
fn category_label(names: &[String], v: f64) -> String {
    let k = v.round();
    match names.get((k as usize).wrapping_sub(1)) {
        Some(name) if (v - k).abs() < 1e-9 && k >= 1.0 => name.clone(),
        _ => String::new(),
    }
}

/// How many labels the x axis asks for: one per named category, else fewer of the long
/// scientific labels of a linear axis spanning `span`, so that they do not touch.
fn x_label_count(chart: &Chart, span: Option<(f64, f64)>) -> usize {
    let scientific = span.is_some_and(|(lo, hi)| !(1e-3..1e5).contains(&lo.abs().max(hi.abs())));
    if !chart.x_names.is_empty() {
        chart.x_names.len()
    } else if scientific {
        6
    } else {
        10
    }
}

/// The series' points split at points the chart cannot show, so that a line is broken
/// there; each run is non-empty.
fn visible_runs(chart: &Chart, s: &Series) -> Vec<Vec<(f64, f64)>> {
    let mut runs: Vec<Vec<(f64, f64)>> = vec![Vec::new()];
    for p in &s.points {
        if chart.visible(p) {
            runs.last_mut().expect("never empty").push(*p);
        } else if !runs.last().expect("never empty").is_empty() {
            runs.push(Vec::new());
        }
    }
    runs.into_iter().filter(|r| !r.is_empty()).collect()
}

/// Draws one run of a series' points in its style and colour.
fn draw_run<DB, CT>(
    cc: &mut ChartContext<'_, DB, CT>,
    style: Style,
    run: Vec<(f64, f64)>,
    colour: RGBColor,
) -> Result<(), PlotError>
where
    DB: DrawingBackend,
    CT: CoordTranslate<From = (f64, f64)>,
{
    match style {
        Style::Line => cc
            .draw_series(LineSeries::new(run, colour.stroke_width(2)))
            .map_err(err)?,
        Style::Points => cc
            .draw_series(run.into_iter().map(|p| Circle::new(p, 3, colour.filled())))
            .map_err(err)?,
        Style::Marker => cc
            .draw_series(
                run.into_iter()
                    .map(|p| Cross::new(p, MARKER_SIZE, colour.stroke_width(2))),
            )
            .map_err(err)?,
    };
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A series keeps one colour in every panel of a figure (design.svg: "designed" and
    /// the paper's gains in the open-loop panels and in the step, where the set-point comes
    /// first), and the colours that the SVG draws are those.
    #[test]
    fn a_series_keeps_its_colour_across_panels() {
        let line = |n: &str| Series::line(n, vec![(1.0, 1.0), (2.0, 2.0)]);
        let panel = |names: &[&str]| {
            names
                .iter()
                .fold(Chart::new("p", "x", "y"), |c, n| c.with(line(n)))
        };
        let figure = Figure::new(
            vec![
                panel(&["designed", "paper", "1"]),
                panel(&["designed", "paper"]),
                panel(&["set-point", "designed", "paper"]),
                panel(&["other", "more"]),
            ],
            2,
        );
        let colours: Vec<Vec<usize>> = figure
            .shared_colours()
            .iter()
            .map(|c| c.colours.clone())
            .collect();
        // designed 0 and paper 1 throughout; the set-point takes a colour no other name
        // holds (not the "1" line's 2); panels of new names keep their positions' colours.
        assert_eq!(
            colours,
            [vec![0, 1, 2], vec![0, 1], vec![3, 0, 1], vec![0, 1]]
        );
        let svg = figure.to_svg().unwrap();
        let hex = |c: RGBColor| format!("#{:02X}{:02X}{:02X}", c.0, c.1, c.2);
        assert!(
            svg.contains(&hex(COLOURS[3])),
            "the set-point's colour is drawn"
        );
        // A lone chart: the positions' colours, as before.
        let lone = Figure::new(vec![panel(&["a", "b", "c"])], 1).shared_colours();
        assert_eq!(lone[0].colours, [0, 1, 2]);
    }

    /// Named categories (a fleet's motors) label the x axis by name, not by number.
    #[test]
    fn named_categories_label_the_x_axis() {
        let mut chart = Chart::new("c_in1", "motor (dataset)", "%").with(Series::points(
            "estimate",
            vec![(1.0, 0.1), (2.0, -0.1), (3.0, 0.0)],
        ));
        chart.x_range = Some((0.5, 3.5));
        chart.x_names = vec!["ar034-a".into(), "ar034-b".into(), "ar034-c".into()];
        let svg = chart.to_svg().unwrap();
        let texts: Vec<&str> = svg.lines().map(str::trim).collect();
        for name in &chart.x_names {
            assert!(texts.contains(&name.as_str()), "{name} missing");
        }
        for number in ["0.5", "1", "1.5", "2", "3"] {
            assert!(!texts.contains(&number), "{number} on the x axis");
        }
    }

    fn sine(n: usize) -> Vec<(f64, f64)> {
        (0..n)
            .map(|k| {
                let x = k as f64 / n as f64 * 6.0;
                (x, x.sin())
            })
            .collect()
    }

    #[test]
    fn linear_ticks_tell_neighbours_apart() {
        // A conductance known to 0.1 %: ticks 1e-12 apart on 6.75e-9.
        let (lo, hi) = (6.745e-9, 6.77e-9);
        let labels: Vec<String> = (0..=5)
            .map(|k| tick_in(lo + k as f64 * 5e-12, lo, hi))
            .collect();
        let mut unique = labels.clone();
        unique.dedup();
        assert_eq!(unique.len(), labels.len(), "{labels:?}");
        assert_eq!(tick_in(6.75e-9, lo, hi), "6.750e-9");
        // The usual range keeps short labels.
        assert_eq!(tick_in(250.0, 0.0, 1000.0), "250");
        assert_eq!(tick_in(0.25, 0.0, 1.0), "0.25");
        assert_eq!(tick_in(0.0, -1.0, 1.0), "0");
        assert_eq!(tick_in(-2.2e-16, -1.0, 1.0), "0");
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
        // Two columns of charts widened by the legend beside them; no legend below.
        let width: u32 = attr(&svg, "svg", "width") as u32;
        assert!(width > 2 * PANEL_W && width % 2 == 0, "{width}");
        assert!(svg.contains("height=\"840\""));
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

    /// The value of attribute `name` of the first `<tag ...>` element.
    fn attr(svg: &str, tag: &str, name: &str) -> f64 {
        let el = svg.split(&format!("<{tag} ")).nth(1).expect("element");
        attribute(el, name).expect("attribute")
    }

    fn attribute(element: &str, name: &str) -> Option<f64> {
        let key = format!(" {name}=\"");
        let rest = &format!(" {element}")[..];
        let i = rest.find(&key)? + key.len();
        rest[i..].split('"').next()?.parse().ok()
    }

    /// Every `<text>` element: x, y, text-anchor and content.
    fn texts(svg: &str) -> Vec<(f64, f64, String, String)> {
        svg.split("<text ")
            .skip(1)
            .map(|t| {
                let anchor = t
                    .split("text-anchor=\"")
                    .nth(1)
                    .and_then(|r| r.split('"').next())
                    .unwrap_or("start")
                    .to_string();
                let body = &t[t.find('>').unwrap() + 1..t.find("</text>").unwrap()];
                let x = attribute(t, "x").unwrap();
                let y = attribute(t, "y").unwrap();
                (x, y, anchor, body.trim().to_string())
            })
            .collect()
    }

    /// The numbers written as x-axis tick labels (centred under their tick).
    fn x_tick_labels(svg: &str) -> Vec<(f64, f64)> {
        texts(svg)
            .into_iter()
            .filter(|t| t.2 == "middle")
            .filter_map(|t| t.3.parse::<f64>().ok().map(|v| (t.0, v)))
            .collect()
    }

    /// The legend is drawn to the right of the data: every legend text lies right of the
    /// last x-axis tick label (the data span the whole axis), its box clear of the plotting
    /// area and inside the (widened) SVG; below the chart, the box lies under the area.
    #[test]
    fn legend_lies_outside_the_data_rectangle() {
        let full = (0..=60)
            .map(|k| (k as f64 / 10.0, (k as f64 / 10.0).sin()))
            .collect::<Vec<_>>();
        let chart = Chart::new("legend", "x", "y")
            .with(Series::line("simulated", full.clone()))
            .with(Series::points("measured", full));
        let svg = chart.to_svg().unwrap();
        let last_tick = x_tick_labels(&svg)
            .iter()
            .map(|t| t.0)
            .fold(f64::MIN, f64::max);
        for name in ["simulated", "measured"] {
            let t = texts(&svg).into_iter().find(|t| t.3 == name).unwrap();
            assert!(
                t.0 > last_tick,
                "{name} at x {} inside the data (last tick {last_tick})",
                t.0
            );
        }
        for (at, width_grows) in [(Legend::Right, true), (Legend::Below, false)] {
            let fig = Figure::new(vec![chart.clone().legend(at)], 1);
            let (svg, geometry) = fig.render().unwrap();
            let [px0, py0, px1, py1] = geometry[0].plot;
            let [lx0, ly0, lx1, ly1] = geometry[0].legend.unwrap();
            assert!(
                lx0 >= px1 || ly0 >= py1,
                "{at:?}: legend {:?} overlaps plot {:?}",
                geometry[0].legend,
                geometry[0].plot
            );
            assert!(lx1 > lx0 && ly1 > ly0 && px0 < px1 && py0 < py1);
            let (w, h) = (attr(&svg, "svg", "width"), attr(&svg, "svg", "height"));
            assert!(
                f64::from(lx1) <= w && f64::from(ly1) <= h,
                "{at:?}: legend outside {w}x{h}"
            );
            assert_eq!(w > f64::from(PANEL_W), width_grows, "{at:?}");
            assert_eq!(h > f64::from(PANEL_H), !width_grows, "{at:?}");
            // The box is drawn where the geometry says, and holds its widest text.
            assert!(
                svg.contains(&format!("<rect x=\"{lx0}\" y=\"{ly0}\"")),
                "{at:?}"
            );
            assert!(lx1 - lx0 > text_width("simulated") + LEGEND_GLYPH_W);
        }
        let hidden = Figure::new(vec![chart.legend(Legend::Hidden)], 1)
            .render()
            .unwrap();
        assert_eq!(hidden.1[0].legend, None);
        assert!(hidden.0.contains("width=\"640\""));
    }

    /// A conductance axis over about three decades (the outlet-throttle study's) is
    /// labelled at each power of ten from 1e-9 to 1e-6, and at nothing else.
    #[test]
    fn log_axis_is_labelled_at_every_decade() {
        let data: Vec<(f64, f64)> = (0..=40)
            .map(|k| (2e-9 * 400f64.powf(k as f64 / 40.0), k as f64))
            .collect();
        let charts = [
            Chart::new("c", "C [m3/(s*Pa)]", "speed").log_x(),
            Chart {
                x_range: Some((1e-9, 1e-6)),
                ..Chart::new("c", "C [m3/(s*Pa)]", "speed").log_x()
            },
        ];
        for chart in charts {
            let svg = chart
                .with(Series::line("s", data.clone()))
                .to_svg()
                .unwrap();
            let labels: Vec<f64> = x_tick_labels(&svg).iter().map(|t| t.1).collect();
            assert!(labels.len() >= 3, "{labels:?}");
            for v in &labels {
                let d = v.log10();
                assert!(
                    (d - d.round()).abs() < 1e-9,
                    "label {v} is not a power of ten"
                );
            }
            for d in [-9, -8, -7, -6] {
                assert!(
                    labels.contains(&power_of_ten(d)),
                    "1e{d} missing: {labels:?}"
                );
            }
        }
    }

    #[test]
    fn log_ticks_label_decades_and_grid_the_multiples() {
        let (major, minor) = log_ticks(1e-9, 1e-6);
        assert_eq!(major, [1e-9, 1e-8, 1e-7, 1e-6]);
        assert_eq!(minor.len(), 3 * 8);
        assert!(minor.iter().any(|v| (v / 2e-9 - 1.0).abs() < 1e-12));
        // Many decades: every second one labelled, the others still grid lines.
        let (major, minor) = log_ticks(1e-12, 1e10);
        assert!(
            major.len() >= 6 && major.len() <= MAX_LOG_LABELS,
            "{major:?}"
        );
        assert!(minor.iter().any(|v| (v / 1e-11 - 1.0).abs() < 1e-12));
        // Less than a decade: 1, 2 and 5 times a power of ten.
        assert_eq!(log_ticks(1.5e-9, 6e-9).0, [2e-9, 5e-9]);
        assert_eq!(log_ticks(2.1, 2.9).0, [2.1, 2.9]);
        // Data over a few decades fill whole decades ...
        let (lo, hi) = whole_decades(2e-9, 8e-7).unwrap();
        assert!(
            lo < 1e-9 && lo > 0.8e-9 && hi > 1e-6 && hi < 1.2e-6,
            "{lo} {hi}"
        );
        // ... unless that would leave much of the axis empty.
        assert_eq!(whole_decades(1.5e-9, 3e-8), None);
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
