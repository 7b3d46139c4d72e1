//! Scatter plots of cost against error (`reyes sweep`), drawn with `plotters` as PNG or SVG:
//! panels with log-log axes, points styled by series, the Pareto front joined as a staircase
//! and ringed, one point highlighted with a red ring and a label, an optional dashed
//! reference line. Text is laid out with `ab_glyph` from a font compiled into the binary
//! (Ubuntu Light, from `epaint_default_fonts`, as the benchmark suite's plots), so no system
//! font or fontconfig is needed; the SVG names the font family and leaves drawing the text to
//! the viewer.

use plotters::coord::Shift;
use plotters::coord::ranged1d::{KeyPointHint, NoDefaultFormatting, Ranged, ValueFormatter};
use plotters::prelude::*;
use plotters::style::{FontStyle, register_font};
use std::ops::Range;
use std::path::{Path, PathBuf};
use std::sync::Once;

/// Marker shapes (one per pixel-sample setting in the sweep).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Shape {
    /// A disc.
    Circle,
    /// An axis-aligned square.
    Square,
    /// A triangle, point up.
    Triangle,
    /// A square turned 45 degrees.
    Diamond,
}

/// How a point is drawn.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Style {
    /// sRGB.
    pub colour: [u8; 3],
    /// Marker shape.
    pub shape: Shape,
    /// Outline only.
    pub hollow: bool,
}

/// One marker of a panel, in data coordinates.
#[derive(Clone, Debug, PartialEq)]
pub struct Point {
    /// Position on the (log) x axis.
    pub x: f64,
    /// Position on the (log) y axis.
    pub y: f64,
    /// Its marker.
    pub style: Style,
    /// On the Pareto front: ringed and joined.
    pub front: bool,
    /// Marked with a red ring and labelled (the default settings).
    pub highlight: Option<String>,
}

/// One chart. Points with a non-positive or non-finite coordinate are left out (log axes).
#[derive(Clone, Debug, PartialEq)]
pub struct Panel {
    /// Title above the chart.
    pub title: String,
    /// Label of the x axis.
    pub x_label: String,
    /// Label of the y axis.
    pub y_label: String,
    /// The markers.
    pub points: Vec<Point>,
    /// A dashed horizontal reference line and its label (e.g. the 0.5 px requirement).
    pub hline: Option<(f64, String)>,
}

/// A figure: `panels` in rows of `columns` under `title`, with `legend` at the bottom (a
/// marker style, or None for a plain line of text, and its text).
#[derive(Clone, Debug, PartialEq)]
pub struct Figure<'a> {
    /// Title above the panels.
    pub title: &'a str,
    /// The charts, row by row.
    pub panels: &'a [Panel],
    /// Panels per row.
    pub columns: usize,
    /// Legend lines: a marker style (or `None` for text alone) and its text.
    pub legend: &'a [(Option<Style>, String)],
}

/// Panel width in pixels.
pub const PANEL_W: u32 = 640;
/// Panel height in pixels.
pub const PANEL_H: u32 = 440;

/// Per panel, the pixel position of each of its points in the figure, in the order of its
/// points: `None` for a point left out.
pub type PointPositions = Vec<Vec<Option<(i32, i32)>>>;
const HEADER: u32 = 36;
const LEGEND_LINE: u32 = 18;

const FONT: &str = "sans-serif";
const DARK: RGBColor = RGBColor(70, 70, 70);
/// The highlight ring's colour, sRGB.
pub const RED: [u8; 3] = [220, 20, 20];

fn rgb(c: [u8; 3]) -> RGBColor {
    RGBColor(c[0], c[1], c[2])
}

/// Why a figure could not be drawn or written.
#[derive(Debug, thiserror::Error)]
pub enum PlotError {
    /// The plotting backend failed; its error as text (its type depends on the backend).
    #[error("plot: {0}")]
    Draw(String),
    /// The drawn bitmap does not have the figure's width x height pixels.
    #[error("plot buffer size")]
    BufferSize,
    /// The figure could not be encoded as PNG or its file written.
    #[error(transparent)]
    Output(#[from] reyes::Error),
    /// A figure for the file `path` that could not be drawn or encoded.
    #[error("{}: {source}", path.display())]
    For {
        /// The file the figure was for.
        path: PathBuf,
        /// What went wrong.
        source: Box<PlotError>,
    },
}

fn err(e: impl std::fmt::Display) -> PlotError {
    PlotError::Draw(e.to_string())
}

fn register_fonts() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        if register_font(FONT, FontStyle::Normal, epaint_default_fonts::UBUNTU_LIGHT).is_err() {
            panic!("the embedded font does not parse");
        }
    });
}

impl Figure<'_> {
    fn columns(&self) -> usize {
        self.columns.max(1)
    }

    fn rows(&self) -> u32 {
        self.panels.len().div_ceil(self.columns()).max(1) as u32
    }

    /// Width and height in pixels.
    pub fn size(&self) -> (u32, u32) {
        let legend_h = self.legend.len() as u32 * LEGEND_LINE + 12;
        (
            PANEL_W * self.columns() as u32,
            HEADER + self.rows() * PANEL_H + legend_h,
        )
    }

    /// The figure as PNG bytes, and each panel's drawn points' pixel positions (in the order
    /// of their points, `None` for points left out).
    pub fn png(&self) -> Result<(Vec<u8>, PointPositions), PlotError> {
        let (w, h) = self.size();
        let mut buf = vec![0u8; (w * h * 3) as usize];
        let positions = {
            let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
            self.draw(&root)?
        };
        let img = image::RgbImage::from_raw(w, h, buf).ok_or(PlotError::BufferSize)?;
        Ok((reyes::output::png(&img)?, positions))
    }

    /// The figure as SVG.
    pub fn svg(&self) -> Result<String, PlotError> {
        let mut text = String::new();
        {
            let root = SVGBackend::with_string(&mut text, self.size()).into_drawing_area();
            self.draw(&root)?;
        }
        Ok(text)
    }

    /// Writes the PNG to `path` (atomically).
    pub fn write_png(&self, path: &Path) -> Result<(), PlotError> {
        let (png, _) = self.png().map_err(|e| PlotError::For {
            path: path.to_path_buf(),
            source: Box::new(e),
        })?;
        Ok(reyes::output::write_atomic(path, &png)?)
    }

    /// Writes the SVG to `path` (atomically).
    pub fn write_svg(&self, path: &Path) -> Result<(), PlotError> {
        let svg = self.svg().map_err(|e| PlotError::For {
            path: path.to_path_buf(),
            source: Box::new(e),
        })?;
        Ok(reyes::output::write_atomic(path, svg.as_bytes())?)
    }

    fn draw<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, Shift>,
    ) -> Result<PointPositions, PlotError> {
        register_fonts();
        root.fill(&WHITE).map_err(err)?;
        let (header, rest) = root.split_vertically(HEADER);
        header
            .draw(&Text::new(
                self.title.to_string(),
                (10, 8),
                (FONT, 22).into_font().color(&BLACK),
            ))
            .map_err(err)?;
        let (grid, legend) = rest.split_vertically(self.rows() * PANEL_H);
        let cells = grid.split_evenly((self.rows() as usize, self.columns()));
        let mut positions = Vec::new();
        for (p, area) in self.panels.iter().zip(&cells) {
            positions.push(panel(area, p)?);
        }
        let mut y = 6;
        for (style, text) in self.legend {
            let x = match style {
                Some(s) => {
                    marker(&legend, (16, y + 8), s)?;
                    30
                }
                None => 10,
            };
            legend
                .draw(&Text::new(
                    text.clone(),
                    (x, y),
                    (FONT, 14).into_font().color(&BLACK),
                ))
                .map_err(err)?;
            y += LEGEND_LINE as i32;
        }
        root.present().map_err(err)?;
        Ok(positions)
    }
}

/// A log axis covering the positive finite `values` with a margin (at least 0.3 decades), in
/// log10 units, with its ticks (log10 of 1, 2, 5 x 10^k inside it; every 1..9 x 10^k where
/// those are fewer than three). Drawn on a linear coordinate of log10 values, so the ticks are
/// these round numbers.
fn log_axis(values: impl Iterator<Item = f64>) -> LogAxis {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in values.filter(|v| v.is_finite() && *v > 0.0) {
        lo = lo.min(v.log10());
        hi = hi.max(v.log10());
    }
    if !lo.is_finite() {
        (lo, hi) = (0.0, 1.0);
    }
    let mid = (lo + hi) / 2.0;
    let half = ((hi - lo) / 2.0).max(0.15) * 1.08;
    let range = mid - half..mid + half;
    let ticks = |mantissas: &[f64]| -> Vec<f64> {
        (range.start.floor() as i32..=range.end.ceil() as i32)
            .flat_map(|k| mantissas.iter().map(move |m| (m * 10f64.powi(k)).log10()))
            .filter(|t| range.contains(t))
            .collect()
    };
    let mut t = ticks(&[1.0, 2.0, 5.0]);
    if t.len() < 3 {
        t = ticks(&[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0]);
    }
    LogAxis { range, ticks: t }
}

/// A `plotters` coordinate of log10 values, linear in them, whose grid lines and labels are
/// [`log_axis`]'s round ticks, labelled with the values themselves.
#[derive(Clone, Debug)]
struct LogAxis {
    range: Range<f64>,
    ticks: Vec<f64>,
}

impl Ranged for LogAxis {
    type FormatOption = NoDefaultFormatting;
    type ValueType = f64;

    fn map(&self, v: &f64, limit: (i32, i32)) -> i32 {
        let t = (v - self.range.start) / (self.range.end - self.range.start);
        limit.0 + ((limit.1 - limit.0) as f64 * t).round() as i32
    }

    fn key_points<H: KeyPointHint>(&self, hint: H) -> Vec<f64> {
        // Grid lines and labels at the ticks; no light lines between them.
        if hint.weight().allow_light_points() {
            return Vec::new();
        }
        self.ticks.clone()
    }

    fn range(&self) -> Range<f64> {
        self.range.clone()
    }
}

impl ValueFormatter<f64> for LogAxis {
    fn format(v: &f64) -> String {
        label(10f64.powf(*v))
    }
}

/// A tick label: as many decimals as the value's decade needs, no more.
fn label(v: f64) -> String {
    let decimals = (-v.log10().floor()).max(0.0) as usize;
    format!("{v:.decimals$}")
}

/// The corners of a polygon marker of radius `r` px about (0, 0) (y down).
fn corners(shape: Shape, r: i32) -> Vec<(i32, i32)> {
    match shape {
        Shape::Square => vec![(-r, -r), (r, -r), (r, r), (-r, r)],
        Shape::Triangle => vec![(0, -r - 1), (r + 1, r), (-r - 1, r)],
        Shape::Diamond => vec![(0, -r - 1), (r + 1, 0), (0, r + 1), (-r - 1, 0)],
        Shape::Circle => Vec::new(),
    }
}

/// Draws a marker centred on `at`: filled in its colour with a dark edge, or (hollow) an
/// outline in its colour.
fn marker<DB: DrawingBackend, CT: CoordTranslate>(
    area: &DrawingArea<DB, CT>,
    at: CT::From,
    s: &Style,
) -> Result<(), PlotError> {
    let r = 5;
    let colour = rgb(s.colour);
    let result = match (s.shape, s.hollow) {
        (Shape::Circle, true) => {
            area.draw(&(EmptyElement::at(at) + Circle::new((0, 0), r, colour.stroke_width(2))))
        }
        (Shape::Circle, false) => area.draw(
            &(EmptyElement::at(at)
                + Circle::new((0, 0), r, colour.filled())
                + Circle::new((0, 0), r, DARK.stroke_width(1))),
        ),
        (shape, hollow) => {
            let c = corners(shape, r);
            let mut closed = c.clone();
            closed.push(c[0]);
            if hollow {
                area.draw(
                    &(EmptyElement::at(at) + PathElement::new(closed, colour.stroke_width(2))),
                )
            } else {
                area.draw(
                    &(EmptyElement::at(at)
                        + Polygon::new(c, colour.filled())
                        + PathElement::new(closed, DARK.stroke_width(1))),
                )
            }
        }
    };
    result.map_err(err)
}

fn drawable(q: &Point) -> bool {
    q.x.is_finite() && q.x > 0.0 && q.y.is_finite() && q.y > 0.0
}

/// Draws one panel; its points' pixel positions.
fn panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    p: &Panel,
) -> Result<Vec<Option<(i32, i32)>>, PlotError> {
    let x_axis = log_axis(p.points.iter().map(|q| q.x));
    let xs = x_axis.range.clone();
    let y_axis = log_axis(
        p.points
            .iter()
            .map(|q| q.y)
            .chain(p.hline.as_ref().map(|h| h.0)),
    );
    let at = |x: f64, y: f64| (x.log10(), y.log10());
    let mut chart = ChartBuilder::on(area)
        .caption(&p.title, (FONT, 16))
        .margin(10)
        .x_label_area_size(42)
        .y_label_area_size(66)
        .build_cartesian_2d(x_axis, y_axis)
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc(&p.x_label)
        .y_desc(&p.y_label)
        .light_line_style(WHITE)
        .label_style((FONT, 12))
        .axis_desc_style((FONT, 14))
        .draw()
        .map_err(err)?;
    if let Some((v, text)) = &p.hline {
        let red = rgb(RED);
        chart
            .draw_series(DashedLineSeries::new(
                [(xs.start, v.log10()), (xs.end, v.log10())],
                6,
                6,
                red.stroke_width(1),
            ))
            .map_err(err)?;
        let dx = -8 * text.len() as i32 - 4;
        chart
            .draw_series(std::iter::once(
                EmptyElement::at((xs.end, v.log10()))
                    + Text::new(text.clone(), (dx, -16), (FONT, 13).into_font().color(&red)),
            ))
            .map_err(err)?;
    }
    // The front as a staircase: from each point right to the next one's cost, then down.
    let mut front: Vec<&Point> = (p.points.iter())
        .filter(|q| drawable(q) && q.front)
        .collect();
    front.sort_by(|a, b| a.x.total_cmp(&b.x));
    let mut stairs = Vec::new();
    for (i, q) in front.iter().enumerate() {
        if i > 0 {
            stairs.push(at(q.x, front[i - 1].y));
        }
        stairs.push(at(q.x, q.y));
    }
    if stairs.len() > 1 {
        chart
            .draw_series(LineSeries::new(stairs, DARK.stroke_width(2)))
            .map_err(err)?;
    }
    let plot = chart.plotting_area();
    for q in p.points.iter().filter(|q| drawable(q)) {
        marker(plot, at(q.x, q.y), &q.style)?;
    }
    for q in p.points.iter().filter(|q| drawable(q)) {
        if q.front {
            plot.draw(
                &(EmptyElement::at(at(q.x, q.y)) + Circle::new((0, 0), 8, BLACK.stroke_width(1))),
            )
            .map_err(err)?;
        }
        if let Some(text) = &q.highlight {
            let red = rgb(RED);
            plot.draw(
                &(EmptyElement::at(at(q.x, q.y))
                    + Circle::new((0, 0), 11, red.stroke_width(2))
                    + Text::new(text.clone(), (14, -22), (FONT, 13).into_font().color(&red))),
            )
            .map_err(err)?;
        }
    }
    Ok(p.points
        .iter()
        .map(|q| drawable(q).then(|| chart.backend_coord(&at(q.x, q.y))))
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn style(colour: [u8; 3], shape: Shape) -> Style {
        Style {
            colour,
            shape,
            hollow: false,
        }
    }

    const BLUE: [u8; 3] = [10, 20, 200];
    const ORANGE: [u8; 3] = [230, 120, 10];

    fn panels() -> Vec<Panel> {
        let pt = |x, y, shape, front, highlight: Option<&str>| Point {
            x,
            y,
            style: style(if front { BLUE } else { ORANGE }, shape),
            front,
            highlight: highlight.map(String::from),
        };
        let a = Panel {
            title: "teapot: error against time".into(),
            x_label: "GPU ms".into(),
            y_label: "geom_err_max_px".into(),
            points: vec![
                pt(1.0, 0.1, Shape::Square, true, None),
                pt(10.0, 0.01, Shape::Diamond, true, Some("default")),
                pt(20.0, 0.2, Shape::Triangle, false, None),
                pt(-1.0, 0.2, Shape::Circle, false, None),
            ],
            hline: Some((0.5, "0.5 px".into())),
        };
        let mut b = a.clone();
        b.title = "second".into();
        b.hline = None;
        vec![a, b]
    }

    fn figure<'a>(panels: &'a [Panel], legend: &'a [(Option<Style>, String)]) -> Figure<'a> {
        Figure {
            title: "reyes sweep test",
            panels,
            columns: 2,
            legend,
        }
    }

    /// The PNG decodes at the figure's size; points are drawn in their colour where the log
    /// axes put them, the front's staircase joins the front, the default is ringed in red.
    #[test]
    fn png_points_front_and_highlight_are_drawn() {
        let panels = panels();
        let legend = vec![
            (Some(style(BLUE, Shape::Circle)), "megakernel".to_string()),
            (None, "plain text".to_string()),
        ];
        let f = figure(&panels, &legend);
        let (png, positions) = f.png().unwrap();
        let img = image::load_from_memory(&png).unwrap().to_rgb8();
        assert_eq!((img.width(), img.height()), f.size());
        assert_eq!(f.size().0, 2 * PANEL_W);
        let px = |(x, y): (i32, i32)| img.get_pixel(x as u32, y as u32).0;
        for (k, pos) in positions.iter().enumerate() {
            assert_eq!(pos.len(), 4);
            assert!(pos[3].is_none(), "x = -1 cannot be drawn on a log axis");
            let (a, b, c) = (pos[0].unwrap(), pos[1].unwrap(), pos[2].unwrap());
            // The second panel sits right of the first.
            assert!(a.0 >= k as i32 * PANEL_W as i32 && a.0 < (k as i32 + 1) * PANEL_W as i32);
            assert!(a.0 < b.0 && b.0 < c.0, "{a:?} {b:?} {c:?}");
            assert!(b.1 > a.1, "smaller error lower");
            assert_eq!(px(a), BLUE, "panel {k}: front point");
            assert_eq!(px(b), BLUE);
            assert_eq!(px(c), ORANGE);
            // The staircase: right from a at a's height, then down to b.
            let dark = |p: [u8; 3]| p.iter().all(|&v| v < 140);
            let mid = ((a.0 + b.0) / 2, a.1);
            assert!(
                (-1..=1).any(|d| dark(px((mid.0, mid.1 + d)))),
                "panel {k}: no staircase at {mid:?}"
            );
            let down = (b.0, (a.1 + b.1) / 2);
            assert!((-1..=1).any(|d| dark(px((down.0 + d, down.1)))));
            // The red ring about the default point, and none about the others.
            let reddish = |p: [u8; 3]| p[0] > 150 && p[1] < 90 && p[2] < 90;
            let ring = |q: (i32, i32)| {
                (-12..=12)
                    .flat_map(|dy| (-12..=12).map(move |dx| (dx, dy)))
                    .filter(|(dx, dy)| {
                        let d = ((dx * dx + dy * dy) as f64).sqrt().round() as i32;
                        (9..=13).contains(&d)
                    })
                    .filter(|&(dx, dy)| reddish(px((q.0 + dx, q.1 + dy))))
                    .count()
            };
            assert!(ring(b) > 20, "panel {k}: red ring {}", ring(b));
            assert_eq!(ring(c), 0);
        }
        // Dark text in the title band.
        assert!(
            (0..HEADER).any(|y| (0..200).any(|x| img.get_pixel(x, y).0.iter().all(|&v| v < 100)))
        );
    }

    #[test]
    fn svg_has_the_text_and_every_marker() {
        let panels = panels();
        let svg = figure(&panels, &[]).svg().unwrap();
        assert!(svg.starts_with("<svg"), "{}", &svg[..40]);
        assert!(svg.contains("reyes sweep test") && svg.contains("geom_err_max_px"));
        assert!(svg.contains("0.5 px") && svg.contains("default"));
        // Per panel: one square and one diamond and one triangle (polygons), rings as circles.
        assert!(svg.matches("<polygon").count() >= 6, "{svg}");
        assert!(svg.matches("<circle").count() >= 2 * 3, "{svg}");
    }

    #[test]
    fn tick_labels_and_axis_ranges() {
        assert_eq!(label(0.02), "0.02");
        assert_eq!(label(0.5), "0.5");
        assert_eq!(label(200.0), "200");
        assert_eq!(label(1.0), "1");
        let LogAxis { range: r, ticks: t } = log_axis([0.3, 30.0, f64::NAN, -1.0].into_iter());
        let (lo, hi) = (10f64.powf(r.start), 10f64.powf(r.end));
        assert!(lo < 0.3 && lo > 0.2 && hi > 30.0 && hi < 45.0, "{lo} {hi}");
        let t: Vec<String> = t.iter().map(|t| label(10f64.powf(*t))).collect();
        assert_eq!(t, ["0.5", "1", "2", "5", "10", "20"]);
        let LogAxis {
            range: one,
            ticks: t,
        } = log_axis([2.0, 3.5].into_iter());
        assert!(one.start < 2f64.log10() && one.end > 2f64.log10());
        assert!(one.end - one.start > 0.3);
        let t: Vec<String> = t.iter().map(|t| label(10f64.powf(*t))).collect();
        assert_eq!(t, ["2", "3"], "1..9 where 1, 2, 5 give fewer than three");
    }
}
