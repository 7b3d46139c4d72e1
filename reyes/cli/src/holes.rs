//! `reyes holes [SCENE] [render options] [--reference exact|bbox] [--ref-samples N] [--json]`:
//! renders a frame on the GPU in the `--raster` mode asked for and counts its holes
//! (`reyes_accuracy::holes`) against a reference coverage: the exact f64 surfaces, or a
//! bounding-box render of the same frame (for surfaces the exact reference does not know, such
//! as displaced ones). Prints a table (header and one row) or a JSON object (docs/reyes.md, *Rasterization
//! modes*).

use crate::cli::{HOLES_COLUMNS, HoleReference, HolesCmd};
use crate::error::CliError;
use crate::setup::{self, Setup};
use reyes::frame::{FrameData, RasterMode, RenderOptions};
use reyes::gpu_render::RendererConfig;
use reyes::stages;
use reyes_accuracy::holes::{Holes, coverage_of, holes};
use serde::Serialize;

/// What `reyes holes --json` prints.
#[derive(Debug, Serialize)]
struct HolesReport {
    scene: String,
    /// `--raster`: `bbox` or `nearest`.
    raster: &'static str,
    /// `exact` or `bbox`.
    reference: &'static str,
    width: u32,
    height: u32,
    pixel_samples: [u32; 2],
    mp_size_px: f64,
    micropolygons: u64,
    covered_px: usize,
    #[serde(flatten)]
    holes: Holes,
}

/// Runs the subcommand.
pub fn main(a: HolesCmd) -> Result<(), CliError> {
    let setup = Setup::load(a.scene.as_deref(), &a.render)?;
    let data = setup.frame_data()?;
    let gpu = setup::open_gpu()?;
    let config = RendererConfig::new(a.render.strategy_for(&gpu)).features(data.features());
    let renderer = setup::renderer(&gpu, config)?;
    let Setup {
        scene,
        name,
        options,
    } = setup;
    let frame = renderer.render(&gpu, &data)?;
    let f = &data.frame;
    let reference = match a.reference {
        HoleReference::Exact => {
            reyes::reference::coverage(&scene, f.width, f.height, a.ref_samples)
        }
        HoleReference::Bbox => {
            let bbox = FrameData::new(
                &scene,
                &RenderOptions {
                    raster: RasterMode::BoundingBox,
                    ..options.clone()
                },
            )?;
            let g = renderer.render(&gpu, &bbox)?;
            coverage_of(&g.image)
        }
    };
    let report = HolesReport {
        scene: name,
        raster: options.raster.name(),
        reference: match a.reference {
            HoleReference::Exact => "exact",
            HoleReference::Bbox => "bbox",
        },
        width: f.width,
        height: f.height,
        pixel_samples: [f.spp_x, f.spp_y],
        mp_size_px: f.mp_size as f64,
        micropolygons: frame.counters[stages::C_MICROPOLYGONS],
        covered_px: frame.image.covered_pixels(),
        holes: holes(&frame.image, &reference, f.spp_x * f.spp_y),
    };
    if a.json {
        reyes_cli::outln!("{}", serde_json::to_string(&report)?);
    } else {
        let r = &report;
        if !a.no_header {
            reyes_cli::outln!("{HOLES_COLUMNS}");
            reyes_cli::outln!("{}", markdown_rule(HOLES_COLUMNS));
        }
        reyes_cli::outln!(
            "| {} | {} | {}x{} | {}x{} | {} | {} | {} | {} | {} | {} | {:.4} |",
            r.scene,
            r.raster,
            r.width,
            r.height,
            r.pixel_samples[0],
            r.pixel_samples[1],
            r.mp_size_px,
            r.reference,
            r.micropolygons,
            r.holes.interior_px,
            r.holes.hole_px,
            r.holes.hole_samples,
            r.holes.hole_sample_share
        );
    }
    Ok(())
}

/// The markdown rule under a header row: `| --- |` for each of its columns.
fn markdown_rule(header: &str) -> String {
    let columns = header.matches('|').count().saturating_sub(1);
    format!("|{}", " --- |".repeat(columns))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rule_has_a_cell_per_column() {
        assert_eq!(markdown_rule("| a | b |"), "| --- | --- |");
        assert_eq!(
            markdown_rule(HOLES_COLUMNS).matches('|').count(),
            HOLES_COLUMNS.matches('|').count()
        );
    }
}
