//! The suite's plots (`plotters`): per workload one PNG with three panels against the problem
//! size (work items of the CPU reference), log axes: median wall ms, median GPU ms, and items
//! per second of wall time, one line per strategy, named in one legend under the title. Text
//! is drawn with `ab_glyph` from a font compiled into the binary (Ubuntu Light, from
//! `epaint_default_fonts`), so no system font or fontconfig is needed; pixels go into a buffer
//! that the `image` crate encodes.

use crate::error::Error;
use crate::files::write_file;
use crate::record::RunRecord;
use crate::summary::{Cell, cells, plot_file_name};
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use plotters::style::{FontStyle, register_font};
use std::path::{Path, PathBuf};
use std::sync::Once;

const WIDTH: u32 = 1500;
const HEIGHT: u32 = 550;
/// The legend's row under the title.
const LEGEND_HEIGHT: u32 = 30;
const FONT: &str = "sans-serif";

/// Strategy colours, in the order strategies first appear.
const PALETTE: [RGBColor; 8] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
];

fn register() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        if register_font(FONT, FontStyle::Normal, epaint_default_fonts::UBUNTU_LIGHT).is_err() {
            panic!("the embedded font does not parse");
        }
    });
}

/// One panel: a value per cell, or none where the cell has no such value.
struct Panel {
    title: &'static str,
    y_label: &'static str,
    value: fn(&Cell) -> Option<f64>,
}

const PANELS: [Panel; 3] = [
    Panel {
        title: "wall time",
        y_label: "ms (median)",
        value: |c| c.wall.map(|w| w.0),
    },
    Panel {
        title: "GPU time (timestamps)",
        y_label: "ms (median)",
        value: |c| c.gpu.map(|g| g.0),
    },
    Panel {
        title: "throughput",
        y_label: "items/s (wall)",
        value: |c| c.wall.map(|w| c.items as f64 / w.0 * 1e3),
    },
];

/// A tick label: at most 3 significant digits with an SI suffix (`250`, `1.5k`, `20M`).
fn si(v: f64) -> String {
    let (scaled, suffix) = [(1e12, "T"), (1e9, "G"), (1e6, "M"), (1e3, "k")]
        .into_iter()
        .find(|(s, _)| v.abs() >= *s)
        .map_or((v, ""), |(s, n)| (v / s, n));
    let decimals = if scaled.abs() >= 100.0 {
        0
    } else if scaled.abs() >= 10.0 {
        1
    } else {
        3
    };
    let digits = format!("{scaled:.decimals$}");
    let digits = if digits.contains('.') {
        digits.trim_end_matches('0').trim_end_matches('.')
    } else {
        &digits
    };
    format!("{digits}{suffix}")
}

/// A log axis range around `v` (a decade's margin for a single value).
fn log_range(v: impl Iterator<Item = f64>) -> std::ops::Range<f64> {
    let (lo, hi) = v
        .filter(|x| *x > 0.0 && x.is_finite())
        .fold((f64::MAX, f64::MIN), |(a, b), x| (a.min(x), b.max(x)));
    if lo > hi {
        return 0.1..10.0;
    }
    lo / 1.5..hi * 1.5
}

/// Tick values for a log axis over `r`: the powers of ten in it where it spans more than three
/// decades; 1, 2 and 5 times them where it spans fewer; every multiple 1..9 where that still
/// gives fewer than three ticks (plotters' own key points leave a range inside one decade
/// without a label).
fn log_ticks(r: &std::ops::Range<f64>) -> Vec<f64> {
    let (first, last) = (r.start.log10().floor() as i32, r.end.log10().ceil() as i32);
    let pick = |multiples: &[f64]| -> Vec<f64> {
        (first..=last)
            .flat_map(|d| multiples.iter().map(move |m| m * 10f64.powi(d)))
            .filter(|v| r.contains(v))
            .collect()
    };
    let decades = (r.end / r.start).log10();
    let ticks = pick(if decades > 3.0 {
        &[1.0]
    } else {
        &[1.0, 2.0, 5.0]
    });
    if ticks.len() >= 3 {
        ticks
    } else {
        pick(&[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0])
    }
}

/// Draws one workload's plot into an RGB buffer of `WIDTH` x `HEIGHT`.
fn draw(workload: &str, cs: &[Cell], buf: &mut [u8]) -> Result<(), Error> {
    register();
    let err = |e: &dyn std::fmt::Display| Error::Plot {
        workload: workload.to_string(),
        message: e.to_string(),
    };
    let root = BitMapBackend::with_buffer(buf, (WIDTH, HEIGHT)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| err(&e))?;
    let root = root.titled(workload, (FONT, 22)).map_err(|e| err(&e))?;
    let mut strategies: Vec<&str> = Vec::new();
    for c in cs {
        if !strategies.contains(&c.strategy.as_str()) {
            strategies.push(&c.strategy);
        }
    }
    // One legend for the three panels, in a row of its own under the title, where it covers
    // no line (one in each panel hid points).
    let (legend, root) = root.split_vertically(LEGEND_HEIGHT);
    let (mut at, y) = (90, LEGEND_HEIGHT as i32 / 2);
    let style = TextStyle::from((FONT, 14).into_font()).pos(Pos::new(HPos::Left, VPos::Center));
    for (i, name) in strategies.iter().enumerate() {
        let colour = PALETTE[i % PALETTE.len()];
        legend
            .draw(&PathElement::new(
                vec![(at, y), (at + 24, y)],
                colour.stroke_width(3),
            ))
            .map_err(|e| err(&e))?;
        legend
            .draw(&Text::new(name.to_string(), (at + 30, y), style.clone()))
            .map_err(|e| err(&e))?;
        at += 40 + 8 * name.len() as i32;
    }
    let x_range = log_range(cs.iter().map(|c| c.problem_items as f64));
    for (area, panel) in root.split_evenly((1, PANELS.len())).iter().zip(&PANELS) {
        let y_range = log_range(cs.iter().filter(|c| c.ok()).filter_map(panel.value));
        let mut chart = ChartBuilder::on(area)
            .caption(panel.title, (FONT, 18))
            .margin(12)
            .x_label_area_size(44)
            .y_label_area_size(70)
            .build_cartesian_2d(
                (x_range.clone().log_scale()).with_key_points(log_ticks(&x_range)),
                (y_range.clone().log_scale()).with_key_points(log_ticks(&y_range)),
            )
            .map_err(|e| err(&e))?;
        chart
            .configure_mesh()
            .x_desc("work items (CPU reference)")
            .y_desc(panel.y_label)
            .x_label_formatter(&|v| si(*v))
            .y_label_formatter(&|v| si(*v))
            .light_line_style(WHITE)
            .label_style((FONT, 13))
            .axis_desc_style((FONT, 15))
            .draw()
            .map_err(|e| err(&e))?;
        for (i, name) in strategies.iter().enumerate() {
            let colour = PALETTE[i % PALETTE.len()];
            let points: Vec<(f64, f64)> = cs
                .iter()
                .filter(|c| c.strategy == *name && c.ok())
                .filter_map(|c| (panel.value)(c).map(|y| (c.problem_items as f64, y)))
                .filter(|p| p.0 > 0.0 && p.1 > 0.0)
                .collect();
            if points.is_empty() {
                continue;
            }
            chart
                .draw_series(LineSeries::new(points.clone(), colour.stroke_width(2)))
                .map_err(|e| err(&e))?;
            chart
                .draw_series(points.iter().map(|&p| Circle::new(p, 4, colour.filled())))
                .map_err(|e| err(&e))?;
        }
    }
    root.present().map_err(|e| err(&e))?;
    Ok(())
}

/// Encodes an RGB buffer as PNG.
fn png(buf: Vec<u8>) -> Result<Vec<u8>, Error> {
    let img = image::RgbImage::from_raw(WIDTH, HEIGHT, buf).ok_or(Error::PlotBufferSize)?;
    let mut bytes = Vec::new();
    img.write_to(
        &mut std::io::Cursor::new(&mut bytes),
        image::ImageFormat::Png,
    )?;
    Ok(bytes)
}

/// Writes one plot per workload into `dir`; their paths.
pub fn write_plots(dir: &Path, records: &[RunRecord]) -> Result<Vec<PathBuf>, Error> {
    let mut out = Vec::new();
    for (workload, cs) in cells(records) {
        let mut buf = vec![0u8; (WIDTH * HEIGHT * 3) as usize];
        draw(&workload, &cs, &mut buf)?;
        out.push(write_file(dir, &plot_file_name(&workload), &png(buf)?)?);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tick_labels_are_short() {
        assert_eq!(si(250.0), "250");
        assert_eq!(si(1500.0), "1.5k");
        assert_eq!(si(20e6), "20M");
        assert_eq!(si(0.05), "0.05");
        assert_eq!(si(12.5), "12.5");
        assert_eq!(si(131_072.0), "131k");
    }

    /// Every axis gets at least three labelled ticks, inside its range, fewer than a dozen.
    #[test]
    fn log_axes_have_a_few_ticks_whatever_their_span() {
        for r in [
            24.0..65.0,
            0.8..3.0,
            1.0e3..1.0e7,
            0.05..0.2,
            131_000.0..8.4e6,
        ] {
            let t = log_ticks(&r);
            assert!((3..12).contains(&t.len()), "{r:?}: {t:?}");
            assert!(t.iter().all(|v| r.contains(v)), "{r:?}: {t:?}");
            assert!(t.windows(2).all(|w| w[0] < w[1]), "{r:?}: {t:?}");
        }
        assert_eq!(log_ticks(&(24.0..65.0)), vec![30.0, 40.0, 50.0, 60.0]);
        assert_eq!(log_ticks(&(1.0e3..1.0e7)), vec![1e3, 1e4, 1e5, 1e6]);
    }

    #[test]
    fn a_plot_has_text_and_lines() {
        let rec = |strategy: &str, items: u64, wall: f64| RunRecord {
            workload: "w".into(),
            strategy: strategy.into(),
            policy: None,
            size: format!("{items}"),
            params: String::new(),
            item_layout: None,
            enqueue: None,
            workgroup_size: None,
            adapter: String::new(),
            run: 0,
            items,
            problem_items: items,
            verified: true,
            error: None,
            gpu_ms: Some(wall / 2.0),
            wall_ms: Some(wall),
            items_per_s: None,
            items_per_s_wall: None,
            gteps: None,
            executed: vec![],
            rounds: 0,
            launches: 0,
            batches: 0,
            local_items: 0,
            local_queues: None,
            local_workgroup_bytes: None,
            guided_claims: None,
            queue_order: None,
            indirect_validation: None,
            round_dispatch: None,
            max_workgroups: None,
            spin_wait_us: 0,
            idle_polls: 0,
            abandoned: 0,
            flags_cleared: None,
            queue_growths: 0,
            partial_rounds: 0,
            parked_items: 0,
            peak_occupancy: vec![],
            queue_bytes: 0,
            workgroups: 0,
            probed_workgroups: None,
            turn_anatomy: Vec::new(),
        };
        let records = vec![
            rec("a", 1000, 1.0),
            rec("a", 100_000, 10.0),
            rec("b", 1000, 3.0),
            rec("b", 100_000, 5.0),
        ];
        let cs = &cells(&records)[0].1;
        let mut buf = vec![0u8; (WIDTH * HEIGHT * 3) as usize];
        draw("w", cs, &mut buf).unwrap();
        let px = |x: u32, y: u32| {
            let i = ((y * WIDTH + x) * 3) as usize;
            [buf[i], buf[i + 1], buf[i + 2]]
        };
        let all: Vec<[u8; 3]> = (0..HEIGHT)
            .flat_map(|y| (0..WIDTH).map(move |x| (x, y)))
            .map(|(x, y)| px(x, y))
            .collect();
        // Both strategies' colours are drawn, and dark text (titles, labels) is there.
        for c in [PALETTE[0], PALETTE[1]] {
            assert!(all.contains(&[c.0, c.1, c.2]), "colour {c:?} missing");
        }
        let dark = all.iter().filter(|p| p.iter().all(|&v| v < 60)).count();
        assert!(dark > 2000, "{dark} dark pixels: no text or axes?");
        // The title's row band has dark (glyph) pixels.
        assert!((0..30).any(|y| (0..WIDTH).any(|x| px(x, y).iter().all(|&v| v < 100))));
        assert!(!png(buf).unwrap().is_empty());
    }
}
