//! Scatter plots of cost against error as a PNG: panels with log-log axes, points styled by
//! series, the Pareto front joined as a staircase and ringed, one point highlighted. Drawn
//! with the `image` crate and the public-domain 8x8 bitmap font of `font8x8`, so it needs no
//! system fonts (nothing to install on a GPU box or in CI).

use image::{Rgb, RgbImage};
use std::path::Path;

/// Marker shapes (one per pixel-sample setting in the sweep).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Shape {
    Circle,
    Square,
    Triangle,
    Diamond,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Style {
    pub colour: [u8; 3],
    pub shape: Shape,
    /// Outline only.
    pub hollow: bool,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Point {
    pub x: f64,
    pub y: f64,
    pub style: Style,
    /// On the Pareto front: ringed and joined.
    pub front: bool,
    /// Marked with a red ring and labelled (the default settings).
    pub highlight: Option<String>,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Panel {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    pub points: Vec<Point>,
    /// A dashed horizontal reference line and its label (e.g. the 0.5 px requirement).
    pub hline: Option<(f64, String)>,
}

const PANEL_W: u32 = 640;
const PANEL_H: u32 = 440;
const LEFT: i32 = 74;
const RIGHT: i32 = 18;
const TOP: i32 = 30;
const BOTTOM: i32 = 46;
const HEADER: u32 = 28;
const LEGEND_LINE: u32 = 14;

const WHITE: [u8; 3] = [255, 255, 255];
const BLACK: [u8; 3] = [0, 0, 0];
const GREY: [u8; 3] = [200, 200, 200];
const DARK: [u8; 3] = [70, 70, 70];
const RED: [u8; 3] = [220, 20, 20];

/// Draws `panels` in rows of `columns` under `title`, with `legend` (a style, or None for a
/// plain line of text, and its text) at the bottom, and writes a PNG.
pub fn write_png(
    path: &Path,
    title: &str,
    panels: &[Panel],
    columns: usize,
    legend: &[(Option<Style>, String)],
) -> Result<(), String> {
    let png = crate::output::png(&draw(title, panels, columns, legend))
        .map_err(|e| format!("{}: {e}", path.display()))?;
    crate::output::write_atomic(path, &png)
}

pub fn draw(
    title: &str,
    panels: &[Panel],
    columns: usize,
    legend: &[(Option<Style>, String)],
) -> RgbImage {
    let columns = columns.max(1);
    let rows = panels.len().div_ceil(columns).max(1) as u32;
    let legend_h = legend.len() as u32 * LEGEND_LINE + 10;
    let mut c = Canvas(RgbImage::from_pixel(
        PANEL_W * columns as u32,
        HEADER + rows * PANEL_H + legend_h,
        Rgb(WHITE),
    ));
    c.text(10, 8, title, BLACK, 2);
    for (k, p) in panels.iter().enumerate() {
        let x0 = (k % columns) as i32 * PANEL_W as i32;
        let y0 = HEADER as i32 + (k / columns) as i32 * PANEL_H as i32;
        c.panel(x0, y0, p);
    }
    let mut y = (HEADER + rows * PANEL_H + 4) as i32;
    for (style, text) in legend {
        let tx = match style {
            Some(s) => {
                c.marker(16, y + 4, s);
                28
            }
            None => 10,
        };
        c.text(tx, y, text, BLACK, 1);
        y += LEGEND_LINE as i32;
    }
    c.0
}

/// A log10 axis from `lo` to `hi` (in log10 units) mapped to pixels `a..b`.
#[derive(Clone, Copy)]
struct Axis {
    lo: f64,
    hi: f64,
    a: f64,
    b: f64,
}

impl Axis {
    /// Covers the positive finite `values` with a margin; at least 0.3 decades.
    fn fit(values: impl Iterator<Item = f64>, a: f64, b: f64) -> Axis {
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
        Axis {
            lo: mid - half,
            hi: mid + half,
            a,
            b,
        }
    }

    fn px(&self, v: f64) -> f64 {
        self.a + (v.log10() - self.lo) / (self.hi - self.lo) * (self.b - self.a)
    }

    /// Tick values 1, 2, 5 x 10^k inside the axis.
    fn ticks(&self) -> Vec<f64> {
        let mut t = Vec::new();
        for k in self.lo.floor() as i32..=self.hi.ceil() as i32 {
            for m in [1.0, 2.0, 5.0] {
                let v = m * 10f64.powi(k);
                if (self.lo..=self.hi).contains(&v.log10()) {
                    t.push(v);
                }
            }
        }
        t
    }
}

/// A tick label: as many decimals as the value's decade needs, no more.
fn label(v: f64) -> String {
    let decimals = (-v.log10().floor()).max(0.0) as usize;
    format!("{v:.decimals$}")
}

struct Canvas(RgbImage);

impl Canvas {
    fn put(&mut self, x: i32, y: i32, c: [u8; 3]) {
        if x >= 0 && y >= 0 && (x as u32) < self.0.width() && (y as u32) < self.0.height() {
            self.0.put_pixel(x as u32, y as u32, Rgb(c));
        }
    }

    fn rect(&mut self, x0: i32, y0: i32, x1: i32, y1: i32, c: [u8; 3]) {
        for y in y0..=y1 {
            for x in x0..=x1 {
                self.put(x, y, c);
            }
        }
    }

    /// A line `width` px thick; `dash` > 0 draws dash-long pieces with equal gaps.
    fn line(
        &mut self,
        (x0, y0): (f64, f64),
        (x1, y1): (f64, f64),
        c: [u8; 3],
        width: i32,
        dash: f64,
    ) {
        let len = (x1 - x0).hypot(y1 - y0);
        let steps = len.ceil().max(1.0) as usize;
        for k in 0..=steps {
            let t = k as f64 / steps as f64;
            if dash > 0.0 && (t * len / dash) as u64 % 2 == 1 {
                continue;
            }
            let (x, y) = (
                (x0 + (x1 - x0) * t).round() as i32,
                (y0 + (y1 - y0) * t).round() as i32,
            );
            let lo = -(width - 1) / 2;
            self.rect(x + lo, y + lo, x + lo + width - 1, y + lo + width - 1, c);
        }
    }

    fn ring(&mut self, cx: i32, cy: i32, r: f64, c: [u8; 3], width: f64) {
        let ri = r.ceil() as i32 + 1;
        for dy in -ri..=ri {
            for dx in -ri..=ri {
                let d = ((dx * dx + dy * dy) as f64).sqrt();
                if (d - r).abs() <= width / 2.0 {
                    self.put(cx + dx, cy + dy, c);
                }
            }
        }
    }

    fn marker(&mut self, cx: i32, cy: i32, s: &Style) {
        let r = 4i32;
        let inside = |dx: i32, dy: i32, r: i32| match s.shape {
            Shape::Circle => dx * dx + dy * dy <= r * r,
            Shape::Square => dx.abs() <= r - 1 && dy.abs() <= r - 1,
            Shape::Diamond => dx.abs() + dy.abs() <= r,
            // Apex up, base at dy = r - 1.
            Shape::Triangle => dy <= r - 1 && 2 * dx.abs() <= dy + r + 1,
        };
        for dy in -r - 1..=r + 1 {
            for dx in -r - 1..=r + 1 {
                if !inside(dx, dy, r + 1) {
                    continue;
                }
                let edge = !inside(dx, dy, r - 1);
                match (s.hollow, edge) {
                    (true, true) => self.put(cx + dx, cy + dy, s.colour),
                    (true, false) => {}
                    (false, true) => self.put(cx + dx, cy + dy, DARK),
                    (false, false) => self.put(cx + dx, cy + dy, s.colour),
                }
            }
        }
    }

    /// 8x8 glyphs scaled by `scale`; bit k of a glyph row is column k.
    fn text(&mut self, x: i32, y: i32, s: &str, c: [u8; 3], scale: i32) {
        for (i, ch) in s.chars().enumerate() {
            let glyph = glyph(ch);
            for (row, bits) in glyph.iter().enumerate() {
                for col in 0..8 {
                    if bits >> col & 1 == 1 {
                        let (px, py) = (x + (i as i32 * 8 + col) * scale, y + row as i32 * scale);
                        self.rect(px, py, px + scale - 1, py + scale - 1, c);
                    }
                }
            }
        }
    }

    /// Text rotated a quarter turn anticlockwise (reads bottom to top), ending at y.
    fn text_up(&mut self, x: i32, y: i32, s: &str, c: [u8; 3]) {
        for (i, ch) in s.chars().enumerate() {
            let glyph = glyph(ch);
            for (row, bits) in glyph.iter().enumerate() {
                for col in 0..8 {
                    if bits >> col & 1 == 1 {
                        self.put(x + row as i32, y - (i as i32 * 8 + col), c);
                    }
                }
            }
        }
    }

    fn panel(&mut self, x0: i32, y0: i32, p: &Panel) {
        let (l, r) = (x0 + LEFT, x0 + PANEL_W as i32 - RIGHT);
        let (t, b) = (y0 + TOP, y0 + PANEL_H as i32 - BOTTOM);
        let xs = Axis::fit(p.points.iter().map(|q| q.x), l as f64, r as f64);
        let ys = Axis::fit(
            p.points
                .iter()
                .map(|q| q.y)
                .chain(p.hline.as_ref().map(|h| h.0)),
            b as f64,
            t as f64,
        );
        self.text(x0 + 8, y0 + 10, &p.title, BLACK, 1);
        for v in xs.ticks() {
            let x = xs.px(v).round() as i32;
            self.line((x as f64, t as f64), (x as f64, b as f64), GREY, 1, 0.0);
            let s = label(v);
            self.text(x - 4 * s.len() as i32, b + 6, &s, BLACK, 1);
        }
        for v in ys.ticks() {
            let y = ys.px(v).round() as i32;
            self.line((l as f64, y as f64), (r as f64, y as f64), GREY, 1, 0.0);
            let s = label(v);
            self.text(l - 6 - 8 * s.len() as i32, y - 4, &s, BLACK, 1);
        }
        self.line((l as f64, b as f64), (r as f64, b as f64), BLACK, 1, 0.0);
        self.line((l as f64, t as f64), (l as f64, b as f64), BLACK, 1, 0.0);
        let xl = &p.x_label;
        self.text((l + r) / 2 - 4 * xl.len() as i32, b + 22, xl, BLACK, 1);
        let yl = &p.y_label;
        self.text_up(x0 + 6, (t + b) / 2 + 4 * yl.len() as i32, yl, BLACK);
        if let Some((v, text)) = &p.hline {
            let y = ys.px(*v);
            self.line((l as f64, y), (r as f64, y), RED, 1, 6.0);
            self.text(r - 8 * text.len() as i32 - 2, y as i32 - 11, text, RED, 1);
        }
        let drawable = |q: &&Point| q.x.is_finite() && q.x > 0.0 && q.y.is_finite() && q.y > 0.0;
        let pos = |q: &Point| (xs.px(q.x), ys.px(q.y));
        // The front as a staircase: from each point right to the next one's cost, then down.
        let mut front: Vec<&Point> = p
            .points
            .iter()
            .filter(drawable)
            .filter(|q| q.front)
            .collect();
        front.sort_by(|a, b| a.x.total_cmp(&b.x));
        for w in front.windows(2) {
            let (a, c) = (pos(w[0]), pos(w[1]));
            self.line(a, (c.0, a.1), DARK, 2, 0.0);
            self.line((c.0, a.1), c, DARK, 2, 0.0);
        }
        for q in p.points.iter().filter(drawable) {
            let (x, y) = pos(q);
            self.marker(x.round() as i32, y.round() as i32, &q.style);
        }
        for q in p.points.iter().filter(drawable) {
            let (x, y) = pos(q);
            let (x, y) = (x.round() as i32, y.round() as i32);
            if q.front {
                self.ring(x, y, 7.5, BLACK, 1.5);
            }
            if let Some(text) = &q.highlight {
                self.ring(x, y, 11.0, RED, 2.5);
                self.text(x + 14, y - 14, text, RED, 1);
            }
        }
    }
}

/// The 8x8 bitmap of `ch` (`?` outside ASCII).
fn glyph(ch: char) -> [u8; 8] {
    font8x8::legacy::BASIC_LEGACY
        .get(ch as usize)
        .copied()
        .unwrap_or(font8x8::legacy::BASIC_LEGACY[b'?' as usize])
}

#[cfg(test)]
mod tests {
    use super::*;

    fn style(colour: [u8; 3]) -> Style {
        Style {
            colour,
            shape: Shape::Square,
            hollow: false,
        }
    }

    /// Points land where the log axes say, in their colour, with the highlight ring in red.
    #[test]
    fn points_are_drawn_where_the_axes_put_them() {
        let blue = [10, 20, 200];
        let pts = vec![
            Point {
                x: 1.0,
                y: 0.1,
                style: style(blue),
                front: true,
                highlight: None,
            },
            Point {
                x: 10.0,
                y: 0.01,
                style: style(blue),
                front: true,
                highlight: Some("default".into()),
            },
        ];
        let panel = Panel {
            title: "t".into(),
            x_label: "GPU ms".into(),
            y_label: "error".into(),
            points: pts,
            hline: None,
        };
        let img = draw("title", &[panel], 1, &[(None, "legend".into())]);
        assert_eq!(img.width(), PANEL_W);
        let xs = Axis::fit(
            [1.0, 10.0].into_iter(),
            LEFT as f64,
            (PANEL_W as i32 - RIGHT) as f64,
        );
        let top = HEADER as i32;
        let ys = Axis::fit(
            [0.1, 0.01].into_iter(),
            (top + PANEL_H as i32 - BOTTOM) as f64,
            (top + TOP) as f64,
        );
        for (x, y) in [(1.0, 0.1), (10.0, 0.01)] {
            let (px, py) = (xs.px(x).round() as u32, ys.px(y).round() as u32);
            assert_eq!(img.get_pixel(px, py).0, blue, "point ({x}, {y})");
        }
        // The red ring around the highlighted point.
        let (px, py) = (xs.px(10.0).round() as u32, ys.px(0.01).round() as u32);
        assert_eq!(img.get_pixel(px + 11, py).0, RED);
        assert_ne!(img.get_pixel(px + 11, py + 30).0, RED);
    }

    #[test]
    fn tick_labels_and_axis_ranges() {
        assert_eq!(label(0.02), "0.02");
        assert_eq!(label(0.5), "0.5");
        assert_eq!(label(200.0), "200");
        assert_eq!(label(1.0), "1");
        let a = Axis::fit([0.3, 30.0].into_iter(), 0.0, 100.0);
        assert!(a.px(0.3) > 0.0 && a.px(30.0) < 100.0);
        assert_eq!(a.ticks(), vec![0.5, 1.0, 2.0, 5.0, 10.0, 20.0]);
    }
}
