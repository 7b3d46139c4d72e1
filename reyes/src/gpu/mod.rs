//! The GPU resources every renderer of the crate shares, one type each: the scene's tables on
//! the device ([`SceneBuffers`], uploaded once and rewritten only where a frame changes them),
//! the per-frame targets of one image size ([`FrameTarget`]: samples, counters, the resolved
//! image and its 8-bit form), and the pipelines that are not the scheduler's ([`Pipelines`]:
//! resolve, 8-bit conversion, GPU-made root items, the raster peer's tessellation, draw and
//! resolve), each built once per registry and device, on first use.
//!
//! The offline renderer ([`crate::gpu_render::GpuRenderer`]) keeps one scene and one target
//! across its frames; the pipelined renderer ([`crate::realtime::RealtimeRenderer`]) holds its
//! own and renders a frame again on them; the raster peer ([`crate::raster_peer`]) draws from
//! the same scene tables.

pub(crate) mod hiz;
pub(crate) mod pipelines;
mod scene;
mod target;

pub use pipelines::Pipelines;
pub mod raster;
pub(crate) use pipelines::RasterPipelines;
pub(crate) use pipelines::scene_layout_entries;
pub use scene::SceneBuffers;
pub use target::FrameTarget;
