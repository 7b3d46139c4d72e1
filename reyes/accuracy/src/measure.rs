//! One frame's cost and accuracy as the JSON object `reyes measure` prints ([`MeasureReport`]):
//! the settings and times from `stats::frame_stats`, and the metrics of this module's siblings.

use super::exact_image::ReferenceImage;
use super::geometry::GeometryStats;
use super::image_error::ImageError;
use reyes::image::FrameImage;
use reyes::reference::pinholes;
use reyes::stats::FrameStats;
use serde::{Deserialize, Serialize};

/// Pixels that the exact surfaces cover completely, together with their eight neighbours
/// (`Coverage::interior` of the reference), but the render leaves partly empty. Computed for
/// any scene: on a closed surface these are the pinholes (background inside the silhouette);
/// elsewhere they are equally wrong, whatever the cause (cracks, or a silhouette pulled in by
/// more than a pixel).
pub fn pinhole_count(image: &FrameImage, reference: &ReferenceImage) -> usize {
    let alpha: Vec<f32> = image.rgba.iter().map(|p| p[3]).collect();
    pinholes(&alpha, &reference.coverage)
}

/// The metrics of one render, with where they came from.
pub struct Measurement<'a> {
    /// The scene's short name (file stem, or `teapot`).
    pub scene: &'a str,
    /// `stats::frame_stats` of the render (settings, counts, times).
    pub stats: &'a FrameStats,
    /// Geometric accuracy of the micropolygons.
    pub geometry: &'a GeometryStats,
    /// Image error against the reference.
    pub image: &'a ImageError,
    /// Pinholes ([`pinhole_count`]).
    pub pinholes: usize,
    /// Covered area of the render: the sum of its alpha, in square pixels.
    pub coverage_px: f64,
    /// The reference render.
    pub reference: &'a ReferenceImage,
    /// Timed GPU frames behind `gpu_ms` and `wall_ms`.
    pub runs: u32,
    /// Host time of the metrics themselves.
    pub metrics_cpu_ms: MetricsCpuMs,
}

/// What `reyes measure --json` prints: one frame's settings, cost and accuracy. Keys, units and
/// meanings are tabled in docs/reyes.md (*Statistics*).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MeasureReport {
    /// The scene's short name (file stem, or `teapot`).
    pub scene: String,
    /// The render's settings.
    pub settings: Settings,
    /// Median GPU ms (scheduler run plus resolve) over the timed frames; null without
    /// timestamp queries.
    pub gpu_ms: Option<f64>,
    /// Median host ms over the timed frames.
    pub wall_ms: f64,
    /// Largest screen distance (px) between a drawn point and the exact surface.
    pub geom_err_max_px: f64,
    /// 99th percentile over micropolygons of each one's largest distance (px).
    pub geom_err_p99_px: f64,
    /// Longest micropolygon side on screen (px).
    pub mp_edge_max_px: f64,
    /// Mean micropolygon area on screen (px²).
    pub mp_area_mean_px: f64,
    /// Micropolygons the GPU drew.
    pub micropolygons: u64,
    /// Micropolygons the geometric metrics measured (the CPU twin's drawn ones).
    pub micropolygons_measured: u64,
    /// `micropolygons / ` the pixels with any coverage.
    pub micropolygons_per_covered_pixel: f64,
    /// PSNR (dB) of the 8-bit sRGB image over black against the reference; null when equal
    /// byte for byte (infinite).
    pub psnr_db: Option<f64>,
    /// Mean FLIP against the reference (0: identical, 1: most different).
    pub flip_mean: f64,
    /// Pixels the exact surfaces cover with their neighbours that the render leaves partly
    /// empty ([`pinhole_count`]).
    pub pinholes: usize,
    /// Covered area of the render: the sum of its alpha (px²).
    pub coverage_px: f64,
    /// Covered area of the exact surfaces (px²).
    pub reference_coverage_px: f64,
    /// The reference render's settings and cost.
    pub reference: ReferenceInfo,
    /// Timed GPU frames.
    pub runs: u32,
    /// Host ms of each metric.
    pub metrics_cpu_ms: MetricsCpuMs,
}

/// The render's settings (as in `FrameStats`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Settings {
    /// The scheduling strategy (`megakernel`, `multipass`, `multipass-host`).
    pub strategy: String,
    /// The GPU adapter's name.
    pub adapter: String,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Samples per pixel, [x, y].
    pub pixel_samples: [u32; 2],
    /// Target micropolygon edge (px).
    pub mp_size_px: f64,
    /// Fixed-bound dicing's bound (px); null for adaptive dicing.
    pub bound_px: Option<f64>,
    /// Micropolygon rasterization, `bbox` or `nearest` (as in `FrameStats`).
    #[serde(default = "reyes::stats::default_raster")]
    pub raster: String,
}

/// The f64 reference render on the exact surfaces.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ReferenceInfo {
    /// Samples per pixel, [x, y].
    pub samples_per_pixel: [u32; 2],
    /// Samples that hit a surface.
    pub covered_samples: u64,
    /// Samples whose ray-patch intersection did not converge.
    pub unconverged_samples: u64,
    /// Host ms of the reference render.
    pub cpu_ms: f64,
}

/// Host ms of each metric.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct MetricsCpuMs {
    /// The reference render ([`crate::exact_image::render_reference`]).
    pub reference: f64,
    /// The geometric metrics ([`crate::geometry`]).
    pub geometry: f64,
    /// PSNR and FLIP ([`crate::image_error::image_error`]).
    pub image_error: f64,
}

impl Measurement<'_> {
    /// The report.
    pub fn report(&self) -> MeasureReport {
        let s = self.stats;
        let g = self.geometry;
        let r = self.reference;
        let n = r.samples_per_axis;
        MeasureReport {
            scene: self.scene.to_string(),
            settings: Settings {
                strategy: s.strategy.clone(),
                adapter: s.adapter.clone(),
                width: s.width,
                height: s.height,
                pixel_samples: s.pixel_samples,
                mp_size_px: s.mp_size_px,
                bound_px: s.bound_px,
                raster: s.raster.clone(),
            },
            gpu_ms: s.gpu_ms,
            wall_ms: s.wall_ms,
            geom_err_max_px: g.err_max_px,
            geom_err_p99_px: g.err_p99_px,
            mp_edge_max_px: g.edge_max_px,
            mp_area_mean_px: g.area_mean_px,
            micropolygons: s.micropolygons,
            micropolygons_measured: g.micropolygons,
            micropolygons_per_covered_pixel: s.micropolygons_per_covered_pixel,
            psnr_db: self.image.psnr_db.is_finite().then_some(self.image.psnr_db),
            flip_mean: self.image.flip_mean,
            pinholes: self.pinholes,
            coverage_px: self.coverage_px,
            reference_coverage_px: r.coverage.area(),
            reference: ReferenceInfo {
                samples_per_pixel: [n, n],
                covered_samples: r.covered_samples,
                unconverged_samples: r.unconverged_samples,
                cpu_ms: r.cpu_ms,
            },
            runs: self.runs,
            metrics_cpu_ms: self.metrics_cpu_ms,
        }
    }
}
