//! `reyes sweep`: speed against error over the quality settings. For each scene, each dicing
//! setting (target micropolygon size, or Patney & Owens' fixed bound), each pixel-sample count
//! and each strategy: GPU time (warm-up, then `--runs` timed frames, median ± MAD) and the
//! metrics of `reyes measure`. Writes `sweep.csv`, `sweep.md`, `sweep.png` and `sweep.svg` (GPU ms against
//! the geometric error and against FLIP, Pareto fronts and the default settings marked).
//!
//! Work that does not depend on a setting is done once: the reference render per scene, the
//! geometry metrics per dicing setting (they do not depend on samples or strategy), and the
//! image metrics per image (the strategies give bit-identical images; if they did not, each
//! image would be measured on its own).
//!
//! On a terminal a progress bar counts the settings (one step per scene, dicing, samples and
//! strategy) and another the rows of each scene's reference render (`reyes_cli::progress`).

use crate::cli::SweepCmd;
use crate::error::CliError;
use crate::measure::timed_frames;
use crate::setup::{self, load_scene};
use reyes::frame::{FrameData, RenderOptions};
use reyes::gpu_render::GpuRenderer;
use reyes::image::FrameImage;
use reyes::stages::C_MICROPOLYGONS;
use reyes_accuracy::exact_image::render_reference;
use reyes_accuracy::geometry::{GeometryStats, geometry};
use reyes_accuracy::image_error::{ImageError, composite_srgb8, srgb8_errors};
use reyes_accuracy::measure::pinhole_count;
use reyes_accuracy::pareto::pareto_front;
use reyes_accuracy::plot::{Figure, Panel, Point, Shape, Style};
use scheduler::StrategyKind;
use scheduler::stats::median_and_mad;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// How grids are diced: adaptively to a micropolygon size, or split to a fixed screen bound
/// and diced 16x16.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Dicing {
    MpSize(f32),
    BoundPx(f32),
}

impl Dicing {
    fn label(&self) -> String {
        match self {
            Dicing::MpSize(s) => format!("mp {s} px"),
            Dicing::BoundPx(b) => format!("bound {b} px"),
        }
    }
}

struct Config {
    scenes: Vec<String>,
    out: PathBuf,
    width: u32,
    height: u32,
    runs: u32,
    ref_samples: u32,
    dicings: Vec<Dicing>,
    samples: Vec<(u32, u32)>,
    strategies: Vec<StrategyKind>,
}

impl Config {
    /// The sweep's settings from its command line.
    fn new(a: SweepCmd) -> Config {
        let mut dicings: Vec<Dicing> = a.mp_sizes.into_iter().map(Dicing::MpSize).collect();
        dicings.extend(a.bound_px.0.into_iter().map(Dicing::BoundPx));
        Config {
            scenes: a.scenes.into_iter().filter(|s| !s.is_empty()).collect(),
            out: a.out,
            width: a.width,
            height: a.height,
            runs: a.runs,
            ref_samples: a.ref_samples,
            dicings,
            samples: a.samples,
            strategies: a.strategies,
        }
    }
}

/// `teapot` (built in), `killeroo` (the shared scene) or a path.
fn scene_path(name: &str) -> Option<PathBuf> {
    match name {
        "teapot" => None,
        "killeroo" => Some(reyes::shared_data_dir().join("rib/killeroo.rib")),
        p => Some(PathBuf::from(p)),
    }
}

/// One measured setting.
struct Row {
    scene: String,
    strategy: &'static str,
    dicing: Dicing,
    samples: (u32, u32),
    /// Median and MAD (None where the adapter has no timestamps).
    gpu_ms: Option<(f64, f64)>,
    wall_ms: (f64, f64),
    geom: GeometryStats,
    micropolygons: u64,
    mp_per_px: f64,
    img: ImageError,
    pinholes: usize,
    default: bool,
    front_geom: bool,
    front_flip: bool,
}

impl Row {
    /// The cost axis: GPU time, or wall time where there is none.
    fn cost(&self) -> f64 {
        self.gpu_ms.map_or(self.wall_ms.0, |g| g.0)
    }
}

/// Runs the subcommand.
pub fn main(a: SweepCmd) -> Result<(), CliError> {
    let c = Config::new(a);
    std::fs::create_dir_all(&c.out).map_err(|source| CliError::CreateFolder {
        path: c.out.clone(),
        source,
    })?;
    let gpu = setup::open_gpu()?;
    let adapter = gpu.adapter_name();
    let renderers: Vec<(StrategyKind, GpuRenderer)> = c
        .strategies
        .iter()
        .map(|&k| Ok((k, setup::renderer(&gpu, k)?)))
        .collect::<Result<_, CliError>>()?;
    let start = std::time::Instant::now();
    let mut rows = Vec::new();
    let defaults = RenderOptions::default();
    // Settings per scene; a scene whose own sample count is not in --samples adds its own.
    let per_samples = (c.dicings.len() * c.strategies.len()) as u64;
    let settings = reyes_cli::progress::bar(
        c.scenes.len() as u64 * c.samples.len() as u64 * per_samples,
        "settings",
    );
    for name in &c.scenes {
        let (scene, short) = load_scene(scene_path(name).as_deref())?;
        let short = if name == "killeroo" {
            "killeroo".into()
        } else {
            short
        };
        let (w, h) = (c.width, c.height);
        settings.set_message(format!("settings ({short})"));
        let ref_rows =
            reyes_cli::progress::bar(h as u64, &format!("{short}: reference pixel rows"));
        let reference = render_reference(&scene, w, h, c.ref_samples, &|n| ref_rows.inc(n));
        ref_rows.finish_and_clear();
        let mut images: Vec<Vec<u8>> = Vec::new();
        let first_row = rows.len();
        reyes_cli::progress::note(format!(
            "{short}: reference {w}x{h}, {n}x{n} samples/pixel, {:.1} s",
            reference.cpu_ms / 1e3,
            n = c.ref_samples
        ));
        // The scene's own sample count is the default: sweep it even if not asked.
        let mut sample_set = c.samples.clone();
        if !sample_set.contains(&scene.pixel_samples) {
            sample_set.push(scene.pixel_samples);
            settings.inc_length(per_samples);
        }
        for &dicing in &c.dicings {
            let options = |spp| RenderOptions {
                width: Some(w),
                height: Some(h),
                pixel_samples: Some(spp),
                mp_size: match dicing {
                    Dicing::MpSize(s) => s,
                    Dicing::BoundPx(_) => defaults.mp_size,
                },
                bound_px: match dicing {
                    Dicing::BoundPx(b) => Some(b),
                    Dicing::MpSize(_) => None,
                },
                ..RenderOptions::default()
            };
            let geom = geometry(&scene, &FrameData::new(&scene, &options((1, 1)))?);
            for &spp in &sample_set {
                let data = FrameData::new(&scene, &options(spp))?;
                // This setting's distinct images (the strategies' are normally identical).
                let mut seen: Vec<(FrameImage, usize, usize)> = Vec::new();
                for (kind, renderer) in &renderers {
                    let (frame, gpu_ms, wall_ms) = timed_frames(&gpu, renderer, &data, c.runs)?;
                    let gpu_ms: Option<Vec<f64>> = gpu_ms.into_iter().collect();
                    let (image, pinholes) = match seen.iter().find(|m| m.0 == frame.image) {
                        Some(m) => (m.1, m.2),
                        None => {
                            let p = pinhole_count(&frame.image, &reference);
                            images.push(composite_srgb8(&frame.image));
                            seen.push((frame.image.clone(), images.len() - 1, p));
                            (images.len() - 1, p)
                        }
                    };
                    let micropolygons = frame.counters[C_MICROPOLYGONS];
                    let row = Row {
                        scene: short.clone(),
                        strategy: kind.name(),
                        dicing,
                        samples: spp,
                        gpu_ms: gpu_ms.map(|v| median_and_mad(&v)),
                        wall_ms: median_and_mad(&wall_ms),
                        geom: geom.clone(),
                        micropolygons,
                        mp_per_px: micropolygons as f64
                            / frame.image.covered_pixels().max(1) as f64,
                        img: ImageError {
                            psnr_db: f64::NAN,
                            flip_mean: f64::NAN,
                        },
                        pinholes,
                        default: dicing == Dicing::MpSize(defaults.mp_size)
                            && spp == scene.pixel_samples
                            && *kind == StrategyKind::Megakernel,
                        front_geom: false,
                        front_flip: false,
                    };
                    reyes_cli::progress::note(format!(
                        "{short} {} {} {}x{}: {:.3} ms, geom max {:.3} px, pinholes {}, {} workgroups",
                        row.strategy,
                        dicing.label(),
                        spp.0,
                        spp.1,
                        row.cost(),
                        row.geom.err_max_px,
                        row.pinholes,
                        frame.run.workgroups
                    ));
                    rows.push((row, image));
                    settings.inc(1);
                }
            }
        }
        // Image metrics of the scene's distinct images, all cores at once.
        let errors = srgb8_errors(&composite_srgb8(&reference.image), &images, w, h);
        for (row, image) in &mut rows[first_row..] {
            row.img = errors[*image];
        }
        reyes_cli::progress::note(format!(
            "{short}: image metrics of {} distinct images done",
            images.len()
        ));
    }
    settings.finish_and_clear();
    let mut rows: Vec<Row> = rows.into_iter().map(|r| r.0).collect();
    mark_fronts(&mut rows);
    let elapsed = start.elapsed().as_secs_f64();
    let command = std::env::args().collect::<Vec<_>>().join(" ");
    write(&c.out.join("sweep.csv"), &csv(&rows))?;
    write(
        &c.out.join("sweep.md"),
        &markdown(&rows, &c, &adapter, &command, elapsed),
    )?;
    plots(&c.out, &rows, &c, &adapter)?;
    eprintln!(
        "wrote {}/sweep.{{csv,md,png,svg}} ({} settings, {elapsed:.0} s)",
        c.out.display(),
        rows.len()
    );
    Ok(())
}

fn write(path: &Path, text: &str) -> Result<(), CliError> {
    Ok(reyes::output::write_atomic(path, text.as_bytes())?)
}

/// Pareto fronts per scene: cost against geometric error and against FLIP.
fn mark_fronts(rows: &mut [Row]) {
    let scenes: Vec<String> = rows.iter().map(|r| r.scene.clone()).collect();
    for s in &scenes {
        let idx: Vec<usize> = (0..rows.len()).filter(|&i| &rows[i].scene == s).collect();
        let geom = pareto_front(
            &idx.iter()
                .map(|&i| (rows[i].cost(), rows[i].geom.err_max_px))
                .collect::<Vec<_>>(),
        );
        let flip = pareto_front(
            &idx.iter()
                .map(|&i| (rows[i].cost(), rows[i].img.flip_mean))
                .collect::<Vec<_>>(),
        );
        for (k, &i) in idx.iter().enumerate() {
            rows[i].front_geom = geom[k];
            rows[i].front_flip = flip[k];
        }
    }
}

pub const CSV_COLUMNS: &str = "scene,strategy,mode,mp_size_px,bound_px,pixel_samples,gpu_ms,gpu_ms_mad,wall_ms,wall_ms_mad,geom_err_max_px,geom_err_p99_px,mp_edge_max_px,mp_area_mean_px,micropolygons,micropolygons_per_covered_pixel,psnr_db,flip_mean,pinholes,default,pareto_geom,pareto_flip";

fn csv(rows: &[Row]) -> String {
    let mut s = String::from(CSV_COLUMNS);
    s.push('\n');
    for r in rows {
        let (mode, mp, bound) = match r.dicing {
            Dicing::MpSize(m) => ("adaptive", m.to_string(), String::new()),
            Dicing::BoundPx(b) => ("fixed_bound", String::new(), b.to_string()),
        };
        let opt = |v: Option<f64>| v.map_or(String::new(), |v| format!("{v:.4}"));
        let psnr = if r.img.psnr_db.is_finite() {
            format!("{:.3}", r.img.psnr_db)
        } else {
            "inf".into()
        };
        writeln!(
            s,
            "{},{},{mode},{mp},{bound},{}x{},{},{},{:.4},{:.4},{:.5},{:.5},{:.4},{:.4},{},{:.3},{psnr},{:.5},{},{},{},{}",
            r.scene,
            r.strategy,
            r.samples.0,
            r.samples.1,
            opt(r.gpu_ms.map(|g| g.0)),
            opt(r.gpu_ms.map(|g| g.1)),
            r.wall_ms.0,
            r.wall_ms.1,
            r.geom.err_max_px,
            r.geom.err_p99_px,
            r.geom.edge_max_px,
            r.geom.area_mean_px,
            r.micropolygons,
            r.mp_per_px,
            r.img.flip_mean,
            r.pinholes,
            r.default,
            r.front_geom,
            r.front_flip,
        )
        .unwrap();
    }
    s
}

fn markdown(rows: &[Row], c: &Config, adapter: &str, command: &str, elapsed: f64) -> String {
    let mut s = String::new();
    let timed = if rows.iter().all(|r| r.gpu_ms.is_some()) {
        "GPU ms"
    } else {
        "wall ms (no GPU timestamps)"
    };
    writeln!(
        s,
        "Adapter: {adapter}. Image {}x{}. Each setting: a warm-up frame, 0.5 s of full GPU load (clocks), one more frame, then {} timed frames; \
         time is the median ± MAD of {timed} (scheduler run plus resolve). Reference: \
         {n}x{n} samples per pixel on the exact surfaces. Sweep took {elapsed:.0} s.\n\n\
         Command: `{command}`\n\n\
         Columns: `geom max`/`p99`: screen distance (px) between drawn micropolygons and the exact \
         surface; `edge max`, `area`: micropolygon size (px, px²); `mp/px`: micropolygons per \
         covered pixel; PSNR (dB, 8-bit sRGB over black) and FLIP mean against the reference; \
         `front`: on the Pareto front of time against geometric error (G) or FLIP (F); \
         **bold**: the default settings.\n",
        c.width,
        c.height,
        c.runs,
        n = c.ref_samples,
    )
    .unwrap();
    let mut scenes: Vec<&str> = rows.iter().map(|r| r.scene.as_str()).collect();
    scenes.dedup();
    for scene in scenes {
        writeln!(s, "\n### {scene}\n").unwrap();
        s += "| strategy | dicing | samples | time ms | geom max px | geom p99 px | edge max px | area px² | mp/px | PSNR dB | FLIP | pinholes | front |\n";
        s += "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |\n";
        for r in rows.iter().filter(|r| r.scene == scene) {
            let (t, mad) = r.gpu_ms.unwrap_or(r.wall_ms);
            let front = match (r.front_geom, r.front_flip) {
                (true, true) => "G F",
                (true, false) => "G",
                (false, true) => "F",
                _ => "",
            };
            let psnr = if r.img.psnr_db.is_finite() {
                format!("{:.2}", r.img.psnr_db)
            } else {
                "inf".into()
            };
            let cells = [
                r.strategy.to_string(),
                r.dicing.label(),
                format!("{}x{}", r.samples.0, r.samples.1),
                format!("{t:.3} ± {mad:.3}"),
                format!("{:.3}", r.geom.err_max_px),
                format!("{:.3}", r.geom.err_p99_px),
                format!("{:.2}", r.geom.edge_max_px),
                format!("{:.3}", r.geom.area_mean_px),
                format!("{:.2}", r.mp_per_px),
                psnr,
                format!("{:.4}", r.img.flip_mean),
                r.pinholes.to_string(),
                front.to_string(),
            ];
            let cells: Vec<String> = if r.default {
                cells.into_iter().map(|c| format!("**{c}**")).collect()
            } else {
                cells.into()
            };
            writeln!(s, "| {} |", cells.join(" | ")).unwrap();
        }
    }
    s
}

const BLUE: [u8; 3] = [31, 119, 180];
const ORANGE: [u8; 3] = [230, 120, 10];

fn style(r: &Row) -> Style {
    Style {
        colour: if r.strategy == StrategyKind::Megakernel.name() {
            BLUE
        } else {
            ORANGE
        },
        shape: match r.samples {
            (1, 1) => Shape::Circle,
            (2, 2) => Shape::Square,
            (4, 4) => Shape::Triangle,
            _ => Shape::Diamond,
        },
        hollow: matches!(r.dicing, Dicing::BoundPx(_)),
    }
}

/// Writes `sweep.png` and `sweep.svg` into `dir`.
fn plots(dir: &Path, rows: &[Row], c: &Config, adapter: &str) -> Result<(), CliError> {
    let timed = if rows.iter().all(|r| r.gpu_ms.is_some()) {
        "GPU ms (median)"
    } else {
        "wall ms (median; no GPU timestamps)"
    };
    let mut scenes: Vec<&str> = rows.iter().map(|r| r.scene.as_str()).collect();
    scenes.dedup();
    let mut panels = Vec::new();
    for scene in scenes {
        let rs: Vec<&Row> = rows.iter().filter(|r| r.scene == scene).collect();
        let point = |r: &&Row, y: f64, front: bool| Point {
            x: r.cost(),
            y,
            style: style(r),
            front,
            highlight: r.default.then(|| "default".to_string()),
        };
        panels.push(Panel {
            title: format!("{scene}: max geometric error against time"),
            x_label: timed.into(),
            y_label: "geom_err_max_px".into(),
            points: rs
                .iter()
                .map(|r| point(r, r.geom.err_max_px, r.front_geom))
                .collect(),
            hline: Some((0.5, "0.5 px".into())),
        });
        panels.push(Panel {
            title: format!("{scene}: FLIP mean against time"),
            x_label: timed.into(),
            y_label: "flip_mean".into(),
            points: rs
                .iter()
                .map(|r| point(r, r.img.flip_mean, r.front_flip))
                .collect(),
            hline: None,
        });
    }
    let s = |colour, shape, hollow| {
        Some(Style {
            colour,
            shape,
            hollow,
        })
    };
    let legend = vec![
        (s(BLUE, Shape::Square, false), "megakernel".to_string()),
        (s(ORANGE, Shape::Square, false), "multipass".to_string()),
        (s(BLUE, Shape::Circle, false), "1x1 samples".to_string()),
        (s(BLUE, Shape::Square, false), "2x2 samples".to_string()),
        (s(BLUE, Shape::Triangle, false), "4x4 samples".to_string()),
        (s(BLUE, Shape::Diamond, false), "other samples".to_string()),
        (
            s(BLUE, Shape::Circle, true),
            "hollow: fixed bound (split to the bound, dice 16x16); filled: adaptive mp size"
                .to_string(),
        ),
        (
            None,
            "black rings and staircase: Pareto front; red ring: default settings".to_string(),
        ),
    ];
    let title = format!("reyes sweep, {}x{}, {adapter}", c.width, c.height);
    let figure = Figure {
        title: &title,
        panels: &panels,
        columns: 2,
        legend: &legend,
    };
    figure.write_png(&dir.join("sweep.png"))?;
    figure.write_svg(&dir.join("sweep.svg"))?;
    Ok(())
}
