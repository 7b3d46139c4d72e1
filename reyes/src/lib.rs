//! Real-time Reyes on the `scheduler` crate: bicubic Bezier patch scenes (RIB, Newell, BPT)
//! bounded, split, diced, shaded and sampled on the GPU by either scheduling strategy, with a
//! CPU twin of every stage as the reference.

#![warn(missing_docs)]

pub mod buckets;
pub mod camera;
pub mod cpu_render;
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
