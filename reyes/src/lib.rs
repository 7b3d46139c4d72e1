//! Real-time Reyes on the `scheduler` crate: bicubic Bezier patch scenes (RIB, Newell, BPT)
//! bounded, split, diced, shaded and sampled on the GPU by either scheduling strategy, with a
//! CPU twin of every stage as the reference.

pub mod buckets;
pub mod camera;
pub mod cpu_render;
pub mod driver_env;
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
pub mod shaders;
pub mod stages;
pub mod stats;
pub mod warnings;

/// Where the shared test scenes are (they may not be copied into the repository):
/// `REYES_SHARED_DATA`, else `shared/data` next to the repository, else `/work/shared/data`.
pub fn shared_data_dir() -> std::path::PathBuf {
    if let Some(d) = std::env::var_os("REYES_SHARED_DATA") {
        return d.into();
    }
    let beside = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared/data");
    if beside.is_dir() {
        beside
    } else {
        "/work/shared/data".into()
    }
}
