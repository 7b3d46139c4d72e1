//! Real-time Reyes on the `scheduler` crate: bicubic Bezier patch scenes (RIB, Newell, BPT)
//! bounded, split, diced, shaded and sampled on the GPU by either scheduling strategy, with a
//! CPU twin of every stage as the reference.
//!
//! The stages are those of Patney & Owens, "Real-Time Reyes-Style Adaptive Surface
//! Subdivision", with the sampling of Sattler & Steinberger, "Reyes Rendering on the GPU":
//! Bound (cull, choose split or dice), SplitU / SplitV (de Casteljau halving), DiceShade and
//! DiceSmall (grids of micropolygons, shaded at their points) and the sampling into a buffer of
//! jittered sub-samples, resolved to an image. Each is a procedure of a `scheduler` program in
//! WGSL (`shaders/reyes/*.wgsl`) with a Rust twin in [`stages`].
//!
//! Entry points, in the order a frame takes them:
//! - scenes: [`scene::load`] (a file of any supported format; [`scene::load_frames`] for
//!   every frame of a RIB file) or [`scene::builtin_teapot`], giving a [`scene::Scene`] in
//!   camera space, f64;
//! - the frame: [`frame::FrameData::new`] of a scene under [`frame::RenderOptions`], the f32
//!   tables every stage reads (uniforms, materials, lights, per-patch tables, root items);
//! - the GPU: [`gpu_render::GpuRenderer`], built from a [`gpu_render::RendererConfig`]
//!   (strategy, stage timing, compiled features), renders a [`frame::FrameData`] into a
//!   [`gpu_render::GpuFrame`] (image, counters, run statistics; [`stats`] makes its JSON);
//! - many frames of one scene under a moving camera at GPU speed: [`realtime`]
//!   ([`realtime::RealtimeRenderer`]), and the rasterizing peer it is compared with,
//!   [`raster_peer`];
//! - the CPU: [`cpu_render::render_cpu`], the same pipeline on the host, the twin the GPU
//!   output is tested against; [`mod@reference`] holds the exact f64 references.
//!
//! Errors: [`Error`] for scenes, options and files (a scene file's: [`scene::SceneError`]); a
//! GPU run's are the scheduler's `RunError`.

#![warn(missing_docs)]

pub mod buckets;
pub mod camera;
pub mod cpu_render;
pub mod devices;
pub mod driver_env;
pub mod error;
pub mod frame;
pub mod gpu;
pub mod gpu_render;
pub mod image;
pub mod orbit;
pub mod output;
pub mod present;
pub mod progress;
pub mod raster_peer;
pub mod realtime;
pub mod reference;
pub mod scene;
pub(crate) mod shaders;
pub mod stages;
pub mod stats;
pub mod warnings;

pub use error::Error;

/// Where the shared test scenes are (they may not be copied into the repository): the folder
/// named by the environment variable `REYES_SHARED_DATA`, else `shared/data` beside the
/// repository (a sibling of its top folder). When the scenes are elsewhere, set
/// `REYES_SHARED_DATA`; a missing folder shows as the scene file's "cannot read file" error.
pub fn shared_data_dir() -> std::path::PathBuf {
    match std::env::var_os("REYES_SHARED_DATA") {
        Some(d) => d.into(),
        None => std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared/data"),
    }
}
