//! One frame's cost and accuracy as the JSON object `reyes measure` prints: the settings and
//! times from `stats::frame_stats`, and the metrics of this module's siblings.

use super::exact_image::ReferenceImage;
use super::geometry::GeometryStats;
use super::image_error::ImageError;
use crate::image::FrameImage;
use crate::reference::pinholes;
use serde_json::{Value, json};

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
    pub scene: &'a str,
    /// `stats::frame_stats` of the render (settings, counts, times).
    pub stats: &'a Value,
    pub geometry: &'a GeometryStats,
    pub image: &'a ImageError,
    pub pinholes: usize,
    /// Covered area of the render: the sum of its alpha, in square pixels.
    pub coverage_px: f64,
    pub reference: &'a ReferenceImage,
}

impl Measurement<'_> {
    /// The JSON object. `psnr_db` is null when the render equals the reference byte for byte
    /// (infinite PSNR).
    pub fn json(&self) -> Value {
        let s = self.stats;
        let g = self.geometry;
        let r = self.reference;
        let n = r.samples_per_axis;
        json!({
            "scene": self.scene,
            "settings": {
                "strategy": s["strategy"],
                "adapter": s["adapter"],
                "width": s["width"],
                "height": s["height"],
                "pixel_samples": s["pixel_samples"],
                "mp_size_px": s["mp_size_px"],
                "bound_px": s["bound_px"],
            },
            "gpu_ms": s["gpu_ms"],
            "wall_ms": s["wall_ms"],
            "geom_err_max_px": g.err_max_px,
            "geom_err_p99_px": g.err_p99_px,
            "mp_edge_max_px": g.edge_max_px,
            "mp_area_mean_px": g.area_mean_px,
            "micropolygons": s["micropolygons"],
            "micropolygons_measured": g.micropolygons,
            "micropolygons_per_covered_pixel": s["micropolygons_per_covered_pixel"],
            "psnr_db": if self.image.psnr_db.is_finite() { json!(self.image.psnr_db) } else { Value::Null },
            "flip_mean": self.image.flip_mean,
            "pinholes": self.pinholes,
            // Grown or shrunk silhouettes show here: the render's covered area against the
            // exact surfaces' (both in square pixels).
            "coverage_px": self.coverage_px,
            "reference_coverage_px": r.coverage.area(),
            "reference": {
                "samples_per_pixel": [n, n],
                "covered_samples": r.covered_samples,
                "unconverged_samples": r.unconverged_samples,
                "cpu_ms": r.cpu_ms,
            },
        })
    }
}
