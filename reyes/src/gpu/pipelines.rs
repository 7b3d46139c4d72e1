//! The renderers' pipelines besides the scheduler's: the resolve from sub-samples to pixels
//! (resolve.wgsl), the conversion to 8-bit sRGB (rgba8.wgsl) and the root items made on the GPU
//! from the patch table (roots.wgsl), with the layout of the scene bind group. Each is built on
//! first use and kept: a renderer that never converts to 8-bit never compiles it.

use crate::shaders;
use scheduler::{Gpu, RunError, storage_entry};
use std::sync::OnceLock;

/// Layout entries of the scene bind group: 0-3 frame, materials, lights, patch info (read
/// only); 4-5 samples, counters; 6 primitive variables (read only).
pub(crate) fn scene_layout_entries() -> Vec<wgpu::BindGroupLayoutEntry> {
    (0..7).map(|b| storage_entry(b, b < 4 || b == 6)).collect()
}

/// One device's pipelines of the renderers (see the module documentation).
pub struct Pipelines {
    scene_layout: wgpu::BindGroupLayout,
    resolve: OnceLock<wgpu::ComputePipeline>,
    rgba8: OnceLock<wgpu::ComputePipeline>,
    roots: OnceLock<wgpu::ComputePipeline>,
}

/// The pipeline in `cell`, built by `make` the first time.
fn get_or_make(
    cell: &OnceLock<wgpu::ComputePipeline>,
    make: impl FnOnce() -> Result<wgpu::ComputePipeline, RunError>,
) -> Result<&wgpu::ComputePipeline, RunError> {
    if let Some(p) = cell.get() {
        return Ok(p);
    }
    let p = make()?;
    Ok(cell.get_or_init(|| p))
}

impl Pipelines {
    /// The scene bind group's layout; pipelines come later, each on first use.
    pub fn new(gpu: &Gpu) -> Pipelines {
        let scene_layout = gpu
            .device
            .create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("reyes scene"),
                entries: &scene_layout_entries(),
            });
        Pipelines {
            scene_layout,
            resolve: OnceLock::new(),
            rgba8: OnceLock::new(),
            roots: OnceLock::new(),
        }
    }

    /// The layout of the scene bind group ([`super::SceneBuffers`]).
    pub(crate) fn scene_layout(&self) -> &wgpu::BindGroupLayout {
        &self.scene_layout
    }

    /// The resolve pass (`resolve` in resolve.wgsl). Errors: a shader the device rejects.
    pub(crate) fn resolve(&self, gpu: &Gpu) -> Result<&wgpu::ComputePipeline, RunError> {
        get_or_make(&self.resolve, || {
            gpu.compute_pipeline("reyes resolve", shaders::RESOLVE, "resolve")
        })
    }

    /// The conversion of linear RGBA to 8-bit sRGB (`to_rgba8` in rgba8.wgsl). Errors: as
    /// [`Pipelines::resolve`].
    pub(crate) fn rgba8(&self, gpu: &Gpu) -> Result<&wgpu::ComputePipeline, RunError> {
        get_or_make(&self.rgba8, || {
            let src = [shaders::COMMON, shaders::SHADE, shaders::RGBA8].concat();
            gpu.compute_pipeline("reyes rgba8", &src, "to_rgba8")
        })
    }

    /// The root items made from the patch table (`make_roots` in roots.wgsl). Errors: as
    /// [`Pipelines::resolve`].
    pub(crate) fn roots(&self, gpu: &Gpu) -> Result<&wgpu::ComputePipeline, RunError> {
        get_or_make(&self.roots, || {
            let src = [shaders::PATCH_ITEM, shaders::ROOTS].concat();
            gpu.compute_pipeline("reyes roots", &src, "make_roots")
        })
    }
}
