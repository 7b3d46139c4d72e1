//! The renderers' pipelines besides the scheduler's: the resolve from sub-samples to pixels
//! (resolve.wgsl), the conversion to 8-bit sRGB (rgba8.wgsl) and the root items made on the GPU
//! from the patch table (roots.wgsl), with the layout of the scene bind group; and the raster
//! peer's ([`RasterPipelines`]: tessellation, draw and resolve, per feature set and MSAA sample
//! count). Each is built on first use and kept: a renderer that never converts to 8-bit never
//! compiles it.

use super::raster::{COLOR_FORMAT, DEPTH_FORMAT, RasterVertex};
use crate::frame::SceneFeatures;
use crate::shaders;
use scheduler::{Gpu, RunError, storage_entry};
use std::collections::HashMap;
use std::sync::{Arc, Mutex, OnceLock};

/// Layout entries of the scene bind group: 0-3 frame, materials, lights, patch info (read
/// only); 4-5 samples, counters; 6 primitive variables, 7 the depth pyramid (read only); 8 the
/// per-patch occlusion history of pipelined frames (`visible` in common.wgsl).
pub(crate) fn scene_layout_entries() -> Vec<wgpu::BindGroupLayoutEntry> {
    (0..9)
        .map(|b| storage_entry(b, !(4..6).contains(&b) && b != 8))
        .collect()
}

/// One device's pipelines of the renderers (see the module documentation).
pub struct Pipelines {
    scene_layout: wgpu::BindGroupLayout,
    resolve: OnceLock<wgpu::ComputePipeline>,
    rgba8: OnceLock<wgpu::ComputePipeline>,
    roots: OnceLock<wgpu::ComputePipeline>,
    hiz: OnceLock<super::hiz::HizPipelines>,
    /// The raster peer's, per feature set and MSAA sample count.
    raster: Mutex<HashMap<(SceneFeatures, u32), Arc<RasterPipelines>>>,
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
            hiz: OnceLock::new(),
            raster: Mutex::new(HashMap::new()),
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

    /// The depth pyramid's passes (hiz.wgsl). Errors: as [`Pipelines::resolve`].
    pub(crate) fn hiz(&self, gpu: &Gpu) -> Result<&super::hiz::HizPipelines, RunError> {
        if let Some(p) = self.hiz.get() {
            return Ok(p);
        }
        let p = super::hiz::HizPipelines::new(gpu)?;
        Ok(self.hiz.get_or_init(|| p))
    }

    /// The raster peer's pipelines for scenes of `features` drawn with `samples` MSAA samples
    /// ([`RasterPipelines`]), built the first time they are asked for. Errors: as
    /// [`Pipelines::resolve`].
    pub(crate) fn raster(
        &self,
        gpu: &Gpu,
        features: SceneFeatures,
        samples: u32,
    ) -> Result<Arc<RasterPipelines>, RunError> {
        let key = (features, samples);
        if let Some(p) = self.raster.lock().unwrap().get(&key) {
            return Ok(p.clone());
        }
        let p = Arc::new(RasterPipelines::new(gpu, features, samples)?);
        Ok(self.raster.lock().unwrap().entry(key).or_insert(p).clone())
    }
}

/// The raster peer's pipelines ([`crate::raster_peer`]) for one feature set and MSAA sample
/// count: the tessellation (tessellate.wgsl) with its bind group layouts, the draw
/// (raster_draw.wgsl) and the resolve of the drawn targets (raster_resolve.wgsl).
pub(crate) struct RasterPipelines {
    /// Group 0 of the tessellation: orbit, objects (roots.wgsl), then tessellate.wgsl's.
    pub(crate) tess_layout: wgpu::BindGroupLayout,
    /// Group 1 of the tessellation: common.wgsl's tables (frame, materials, lights, patch
    /// info, primvars; not the samples, counters).
    pub(crate) scene_layout: wgpu::BindGroupLayout,
    /// `tess_rates`, `tile_dispatch`, `tess_points`, `tess_quads`.
    pub(crate) tessellate: [wgpu::ComputePipeline; 4],
    /// `finish_draw`: the indirect draw's arguments.
    pub(crate) finish_draw: wgpu::ComputePipeline,
    /// The indexed draw into the multisampled colour and depth targets.
    pub(crate) draw: wgpu::RenderPipeline,
    /// `raster_resolve`: the drawn targets to Reyes's resolved image and depth.
    pub(crate) resolve: wgpu::ComputePipeline,
}

impl RasterPipelines {
    fn new(gpu: &Gpu, features: SceneFeatures, samples: u32) -> Result<RasterPipelines, RunError> {
        let ro = |b| storage_entry(b, true);
        let rw = |b| storage_entry(b, false);
        let layout = |label, entries: &[wgpu::BindGroupLayoutEntry]| {
            gpu.device
                .create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                    label: Some(label),
                    entries,
                })
        };
        let tess_layout = layout(
            "raster tessellate",
            &[
                ro(0),
                ro(1),
                ro(3),
                rw(4),
                rw(5),
                rw(6),
                rw(7),
                rw(8),
                rw(9),
            ],
        );
        let scene_layout = layout("raster scene", &[ro(0), ro(1), ro(2), ro(3), ro(6)]);
        let pipeline_layout = gpu
            .device
            .create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("raster tessellate"),
                bind_group_layouts: &[Some(&tess_layout), Some(&scene_layout)],
                immediate_size: 0,
            });
        let module = gpu.shader("raster tessellate", &tessellate_source(features))?;
        let compute = |entry: &str| {
            gpu.device
                .create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                    label: Some(entry),
                    layout: Some(&pipeline_layout),
                    module: &module,
                    entry_point: Some(entry),
                    compilation_options: Default::default(),
                    cache: None,
                })
        };
        let tessellate = [
            compute("tess_rates"),
            compute("tile_dispatch"),
            compute("tess_points"),
            compute("tess_quads"),
        ];
        let finish_draw = compute("finish_draw");
        let draw = raster_draw(gpu, samples)?;
        let depth_type = if samples > 1 {
            "texture_depth_multisampled_2d"
        } else {
            "texture_depth_2d"
        };
        let src = format!(
            "alias RasterDepth = {depth_type};\n{}",
            shaders::RASTER_RESOLVE
        );
        let resolve = gpu.compute_pipeline("raster resolve", &src, "raster_resolve")?;
        Ok(RasterPipelines {
            tess_layout,
            scene_layout,
            tessellate,
            finish_draw,
            draw,
            resolve,
        })
    }
}

/// The raster peer's draw (`raster_vertex`, `raster_fragment` in raster_draw.wgsl) into
/// [`COLOR_FORMAT`] and reversed [`DEPTH_FORMAT`] targets of `samples` samples.
fn raster_draw(gpu: &Gpu, samples: u32) -> Result<wgpu::RenderPipeline, RunError> {
    let src = [shaders::RESOLVE, shaders::RASTER_DRAW].concat();
    let module = gpu.shader("raster draw", &src)?;
    let layout = gpu
        .device
        .create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("raster draw"),
            bind_group_layouts: &[],
            immediate_size: 0,
        });
    let attributes = wgpu::vertex_attr_array![0 => Float32x3, 1 => Uint32];
    Ok(gpu
        .device
        .create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("raster draw"),
            layout: Some(&layout),
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("raster_vertex"),
                compilation_options: Default::default(),
                buffers: &[Some(wgpu::VertexBufferLayout {
                    array_stride: size_of::<RasterVertex>() as u64,
                    step_mode: wgpu::VertexStepMode::Vertex,
                    attributes: &attributes,
                })],
            },
            primitive: wgpu::PrimitiveState {
                topology: wgpu::PrimitiveTopology::TriangleList,
                // One-sided patches' back faces are culled per quad in tessellate.wgsl,
                // as Reyes culls them; the winding of a patch's grid says nothing.
                cull_mode: None,
                ..Default::default()
            },
            depth_stencil: Some(wgpu::DepthStencilState {
                format: DEPTH_FORMAT,
                depth_write_enabled: Some(true),
                depth_compare: Some(wgpu::CompareFunction::Greater),
                stencil: Default::default(),
                bias: Default::default(),
            }),
            multisample: wgpu::MultisampleState {
                count: samples,
                mask: !0,
                alpha_to_coverage_enabled: false,
            },
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some("raster_fragment"),
                compilation_options: Default::default(),
                targets: &[Some(wgpu::ColorTargetState {
                    format: COLOR_FORMAT,
                    blend: None,
                    write_mask: wgpu::ColorWrites::ALL,
                })],
            }),
            multiview_mask: None,
            cache: None,
        }))
}

/// The raster peer's tessellation shader for frames of `features`: root items made from the
/// patch table, shaded grid points, quads (`tessellate.wgsl` and what it calls).
pub(crate) fn tessellate_source(features: SceneFeatures) -> String {
    [
        &features.wgsl(),
        shaders::PATCH_ITEM,
        shaders::ROOTS,
        shaders::COMMON,
        shaders::SHADE,
        shaders::SURFACE,
        shaders::TESSELLATE,
    ]
    .concat()
}
