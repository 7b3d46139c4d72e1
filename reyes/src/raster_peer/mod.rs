//! The raster peer of `reyes bench --peer raster`: what a real-time developer would do instead
//! of Reyes with the same patches. The patches are tessellated into triangles and drawn by the
//! hardware rasterizer with MSAA, as engines do on APIs without tessellation shaders (wgpu has
//! none): a compute pass does the hardware tessellator's work.
//!
//! Per frame, pipelined like [`crate::realtime`] (the same uploaded scene tables, the same
//! [`Orbit`] turntable uniform, at most [`IN_FLIGHT`] frames submitted, the status read a
//! frame late, no per-frame allocation):
//! 1. tessellation (tessellate.wgsl), three dispatches that fill the GPU: `tess_rates`, one
//!    thread per patch, turns its control points by the frame's transform, culls them by
//!    their bound (wholly in front of the near plane or beyond the far one, or off screen; a
//!    patch crossing the near plane is kept: the rasterizer clips), takes a rate per side from
//!    the projected control polygon so that triangles are about `--mp-size` pixels
//!    ([`grid_rate`], at most [`MAX_RATE`] = 64 per side, the hardware tessellator's maximum),
//!    takes room for its points and quads with atomics and appends a tile per [`TESS_TILE`]
//!    grid points to the tile list, whose indirect dispatch one thread writes; `tess_points`,
//!    a workgroup per tile and a thread per grid point, evaluates and shades the point with
//!    Reyes's shading (surface.wgsl, shade.wgsl: the same materials, lights, normals and
//!    10-bit packed colour as DiceShade) into a [`RasterVertex`]; `tess_quads`, a thread per
//!    quad over the same tiles, writes two triangles per quad into the index buffer (a quad
//!    of a one-sided patch whose four corners face away is culled as Reyes's sampling culls
//!    it); then the indirect draw;
//! 2. a render pass (raster_draw.wgsl) draws them indexed-indirect into a multisampled
//!    colour (`Rgba16Float`, linear) and depth (`Depth32Float`, reversed: nearest greatest)
//!    target, resolved by the hardware;
//! 3. `raster_resolve` (raster_resolve.wgsl) makes the image Reyes's resolve makes: straight
//!    linear RGB with coverage as alpha and the nearest camera-space depth, and rgba8.wgsl the
//!    8-bit image.
//!
//! The pipelines (tessellation, draw, resolve, 8-bit conversion) are the crate's registry's
//! ([`Pipelines`]): built once per device, feature set and sample count, and shared with the
//! real-time renderer through [`RasterPeer::with_pipelines`].
//!
//! MSAA samples: the frame's pixel samples N x M when the adapter supports N*M for both
//! targets ([`msaa_samples`]), else the nearest supported count (WebGPU guarantees 1 and 4).
//!
//! What it is not: Reyes's image. Triangles are flat between their vertices where Reyes dices
//! to micropolygons sized per sub-patch (split until a grid fits), colour is interpolated per
//! vertex (Gouraud) where Reyes gives a micropolygon the mean of its corners, sample positions
//! are the hardware's standard pattern where Reyes jitters, there is no crack dilation (a
//! patch's edge rate differs from its neighbour's, so T-junction cracks can show single
//! samples), and transparency (Os < 1) is drawn opaque ([`RasterPeer::warnings`]): the peer
//! has no order-independent transparency.
//!
//! Buffers are sized from the unturned frame ([`HEADROOM`](crate::realtime::HEADROOM) above its needs). A frame whose
//! patches do not fit draws nothing (the indirect draw is empty), is found a frame late from
//! its status, and is drawn again alone with buffers grown to its needs
//! ([`PeerFrame::redrawn`]): a partial frame is never returned.

mod geometry;
mod tessellation;
use geometry::Geometry;
pub use tessellation::*;

use crate::frame::{FrameData, FrameUniforms, RenderOptions};
use crate::gpu::{Pipelines, RasterPipelines, SceneBuffers};
use crate::gpu_render::dispatch_2d;
use crate::image::FrameImage;
use crate::orbit;
use crate::realtime::{IN_FLIGHT, Orbit, Pixels, map_buffer, read_mapped};
use crate::scene::Scene;
use scheduler::timing::SpanTimer;
use scheduler::{Gpu, RunError};
use std::collections::VecDeque;
use std::sync::Arc;
use std::sync::atomic::AtomicUsize;
use std::time::Instant;

/// One finished frame of the peer.
#[derive(Clone, Debug)]
pub struct PeerFrame {
    /// Turntable angle, radians.
    pub angle: f64,
    /// GPU time from the start of tessellation to the end of the image conversion (plus, for
    /// a frame drawn again, its first attempt); `None` without timestamp queries.
    pub gpu_ms: Option<f64>,
    /// Host time between this frame's completion and the previous one's.
    pub wall_ms: f64,
    /// What the frame's tessellation counted.
    pub counts: TessCounts,
    /// Why the frame was drawn again (its patches did not fit the buffers).
    pub redrawn: Option<String>,
    /// With [`Pixels::Rgba8`]: the 8-bit image, row-major RGBA.
    pub rgba8: Option<Vec<u8>>,
    /// With [`Pixels::Float`]: the f32 image and depth, as Reyes's resolve gives them.
    pub image: Option<FrameImage>,
}

/// The MSAA sample count for `wanted` (the frame's N*M pixel samples): `wanted` when the
/// adapter can render and resolve it for [`COLOR_FORMAT`] and render [`DEPTH_FORMAT`] with it
/// (beyond WebGPU's 1 and 4 only with `TEXTURE_ADAPTER_SPECIFIC_FORMAT_FEATURES`), else the
/// nearest count that it can (the larger of two as near).
pub fn msaa_samples(gpu: &Gpu, wanted: u32) -> u32 {
    let specific =
        (gpu.device.features()).contains(wgpu::Features::TEXTURE_ADAPTER_SPECIFIC_FORMAT_FEATURES);
    let ok = |n: u32| {
        if !specific {
            return n == 1 || n == 4;
        }
        let c = gpu.adapter.get_texture_format_features(COLOR_FORMAT).flags;
        let d = gpu.adapter.get_texture_format_features(DEPTH_FORMAT).flags;
        c.sample_count_supported(n)
            && d.sample_count_supported(n)
            && (n == 1 || c.contains(wgpu::TextureFormatFeatureFlags::MULTISAMPLE_RESOLVE))
    };
    [1u32, 2, 4, 8, 16]
        .into_iter()
        .filter(|&n| ok(n))
        .min_by_key(|&n| (n.abs_diff(wanted), u32::MAX - n))
        .unwrap_or(1)
}

/// The peer's tessellation of the last frame drawn, read back ([`RasterPeer::geometry`]).
#[derive(Clone, Debug)]
pub struct Tessellation {
    /// Per patch: `[nu, nv, first vertex, first quad]`, `nu = 0` when culled.
    pub grids: Vec<[u32; 4]>,
    /// Per patch: its boundaries' segments ([`GridRate::edges`]).
    pub edges: Vec<[u32; 4]>,
    /// The grid points of every drawn patch, each grid's from its first vertex (`grids`).
    pub vertices: Vec<RasterVertex>,
    /// 6 per quad: triangles (a, b, c) and (a, c, d) of quad corners a b c d.
    pub indices: Vec<u32>,
    /// What the tessellation counted.
    pub counts: TessCounts,
}

/// Buffers of one frame in flight.
struct Slot {
    orbit: wgpu::Buffer,
    tess_bind: wgpu::BindGroup,
    /// MAP_READ: the tessellation counters and the GPU timestamps.
    status: wgpu::Buffer,
    /// MAP_READ, per [`Pixels`].
    pixels: Vec<wgpu::Buffer>,
}

struct InFlight {
    angle: f64,
    slot: usize,
    submission: wgpu::SubmissionIndex,
    maps: Vec<wgpu::Buffer>,
    mapped: Arc<AtomicUsize>,
    pixels: Pixels,
}

/// The raster peer: see the module documentation.
pub struct RasterPeer {
    base: FrameData,
    centre: glam::DVec3,
    patches: u32,
    samples: u32,
    tables: SceneBuffers,
    /// The tessellation, draw and resolve, from the registry ([`Pipelines`]).
    raster: Arc<RasterPipelines>,
    /// The registry's 8-bit conversion.
    rgba8_pipeline: wgpu::ComputePipeline,
    scene_bind: wgpu::BindGroup,
    resolve_bind: wgpu::BindGroup,
    rgba8_bind: wgpu::BindGroup,
    color: wgpu::TextureView,
    /// The single-sample target the hardware resolves into; `None` with one sample.
    resolved: Option<wgpu::TextureView>,
    depth_view: wgpu::TextureView,
    rgba: wgpu::Buffer,
    depth: wgpu::Buffer,
    rgba8: wgpu::Buffer,
    geometry: Geometry,
    slots: Vec<Slot>,
    timer: SpanTimer,
    pixels: Pixels,
    /// `tess_rates`'s workgroups (one thread per patch).
    tess_groups: (u32, u32),
    resolve_groups: (u32, u32),
    /// Kept alive for the bind groups.
    _buffers: Vec<wgpu::Buffer>,
}

fn target(
    gpu: &Gpu,
    label: &str,
    f: &FrameUniforms,
    format: wgpu::TextureFormat,
    samples: u32,
    usage: wgpu::TextureUsages,
) -> wgpu::Texture {
    gpu.device.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size: wgpu::Extent3d {
            width: f.width,
            height: f.height,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: samples,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage,
        view_formats: &[],
    })
}

impl RasterPeer {
    /// Uploads `scene` for frames of `options`, compiles the stages into a registry of its
    /// own, and draws the unturned frame once to size the buffers
    /// ([`HEADROOM`](crate::realtime::HEADROOM) above its needs). Errors: the options'
    /// ([`FrameData::new`]) and too many patches ([`MAX_PATCHES`]) as [`RunError::Program`];
    /// an image larger than the device's render targets, buffers beyond its limits, and those
    /// of a frame, as [`RunError::Device`] or [`RunError::Timeout`].
    pub fn new(
        gpu: &Gpu,
        scene: &Scene,
        options: &RenderOptions,
        pixels: Pixels,
    ) -> Result<RasterPeer, RunError> {
        Self::with_pipelines(gpu, &Pipelines::new(gpu), scene, options, pixels)
    }

    /// [`RasterPeer::new`] taking its pipelines from `pipelines` (another renderer's on the
    /// same device, such as [`GpuRenderer::pipelines`](crate::gpu_render::GpuRenderer::pipelines)),
    /// which builds those it lacks and keeps them. Errors: as [`RasterPeer::new`].
    pub fn with_pipelines(
        gpu: &Gpu,
        pipelines: &Pipelines,
        scene: &Scene,
        options: &RenderOptions,
        pixels: Pixels,
    ) -> Result<RasterPeer, RunError> {
        let base = FrameData::new(scene, options).map_err(|e| RunError::Program(e.to_string()))?;
        if scene.patches.len() > MAX_PATCHES {
            return Err(RunError::Program(format!(
                "the raster peer draws at most {MAX_PATCHES} patches; the scene has {}",
                scene.patches.len()
            )));
        }
        let f = base.frame;
        let side = gpu.device.limits().max_texture_dimension_2d;
        if f.width > side || f.height > side {
            return Err(RunError::Device(format!(
                "the raster peer's render target of {}x{} exceeds this device's {side} pixels",
                f.width, f.height
            )));
        }
        let n = scene.patches.len() as u32;
        let samples = msaa_samples(gpu, f.spp_x * f.spp_y);
        let tables = SceneBuffers::with_patches(gpu, scene, &base)?;
        let raster = pipelines.raster(gpu, base.features(), samples)?;
        let rgba8_pipeline = pipelines.rgba8(gpu)?.clone();
        let scene_bind =
            gpu.bind_buffers_at("raster scene", &raster.scene_layout, &tables.tables());
        let attachment = wgpu::TextureUsages::RENDER_ATTACHMENT;
        let binding = wgpu::TextureUsages::TEXTURE_BINDING;
        let mut textures = vec![target(
            gpu,
            "raster colour",
            &f,
            COLOR_FORMAT,
            samples,
            if samples > 1 {
                attachment
            } else {
                attachment | binding
            },
        )];
        if samples > 1 {
            textures.push(target(
                gpu,
                "raster resolved",
                &f,
                COLOR_FORMAT,
                1,
                attachment | binding,
            ));
        }
        let depth_tex = target(
            gpu,
            "raster depth",
            &f,
            DEPTH_FORMAT,
            samples,
            attachment | binding,
        );
        let color = textures[0].create_view(&Default::default());
        let resolved = textures.get(1).map(|t| t.create_view(&Default::default()));
        let depth_view = depth_tex.create_view(&Default::default());
        let pixels_n = f.width as u64 * f.height as u64;
        let rgba = gpu.storage_buffer("raster rgba", pixels_n * 4)?;
        let depth = gpu.storage_buffer("raster depth", pixels_n)?;
        let rgba8 = gpu.storage_buffer("raster rgba8", pixels_n)?;
        let (resolve_groups, row) = dispatch_2d(pixels_n, 256);
        let params = RasterResolveParams {
            width: f.width,
            height: f.height,
            samples,
            row,
            near: f.near,
            pad: [0; 3],
        };
        let params = gpu.upload("raster resolve params", &[params])?;
        let resolve_bind = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("raster resolve"),
            layout: &raster.resolve.get_bind_group_layout(0),
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: params.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::TextureView(
                        resolved.as_ref().unwrap_or(&color),
                    ),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: wgpu::BindingResource::TextureView(&depth_view),
                },
                wgpu::BindGroupEntry {
                    binding: 3,
                    resource: rgba.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 4,
                    resource: depth.as_entire_binding(),
                },
            ],
        });
        let rgba8_params = gpu.upload("raster rgba8 params", &[pixels_n as u32, row, 0, 0])?;
        let rgba8_bind = gpu.bind_buffers(
            "raster rgba8",
            &rgba8_pipeline.get_bind_group_layout(0),
            &[&rgba8_params, &rgba, &rgba8],
        );
        let geometry = Self::geometry_buffers(gpu, n, 4 * n as u64, n as u64)?;
        let mut slots = Vec::new();
        for _ in 0..IN_FLIGHT {
            let orbit = gpu.storage_buffer("raster orbit", (size_of::<Orbit>() / 4) as u64)?;
            slots.push(Slot {
                tess_bind: Self::tess_bind(gpu, &raster.tess_layout, &orbit, &tables, &geometry),
                orbit,
                status: map_buffer(gpu, "raster status", COUNT_WORDS + SpanTimer::WORDS)?,
                pixels: Vec::new(),
            });
        }
        // The colour, resolve and depth textures live while their views do.
        drop(textures);
        drop(depth_tex);
        let mut peer = RasterPeer {
            centre: orbit::scene_centre(scene),
            patches: n,
            samples,
            raster,
            rgba8_pipeline,
            scene_bind,
            resolve_bind,
            rgba8_bind,
            color,
            resolved,
            depth_view,
            rgba,
            depth,
            rgba8,
            geometry,
            slots,
            timer: SpanTimer::new(gpu, IN_FLIGHT as u32),
            pixels: Pixels::None,
            tess_groups: dispatch_2d(n as u64, 64).0,
            resolve_groups,
            _buffers: vec![params, rgba8_params],
            tables,
            base,
        };
        let first = peer.render(gpu, &[0.0])?;
        peer.fit(gpu, &first[0].counts)?;
        peer.set_pixels(gpu, pixels)?;
        Ok(peer)
    }

    /// The MSAA sample count the peer draws with ([`msaa_samples`]).
    pub fn msaa_samples(&self) -> u32 {
        self.samples
    }

    /// Image width and height in pixels, and Reyes's pixel samples per axis.
    pub fn frame_size(&self) -> (u32, u32, [u32; 2]) {
        let f = &self.base.frame;
        (f.width, f.height, [f.spp_x, f.spp_y])
    }

    /// Room in the geometry buffers: vertices and quads.
    pub fn capacity(&self) -> (u32, u32) {
        (self.geometry.vertex_capacity, self.geometry.quad_capacity)
    }

    /// What the peer draws differently from what the scene asks: transparency drawn opaque,
    /// displacement, trimming, motion blur and depth of field left out.
    pub fn warnings(&self) -> Vec<String> {
        let mut w = Vec::new();
        if self.base.features().transparent {
            w.push(
                "the scene has transparent surfaces (Opacity or \"Os\" below 1): the raster \
                 peer draws them opaque (it has no order-independent transparency)"
                    .into(),
            );
        }
        if self.base.features().displacement {
            w.push(
                "the scene has displaced surfaces (`Displacement`): the raster peer draws them \
                 undisplaced (only the Reyes pipeline's DiceShade displaces)"
                    .into(),
            );
        }
        if self.base.features().trim {
            w.push(
                "the scene has trimmed surfaces (`TrimCurve`): the raster peer draws them \
                 untrimmed (only the Reyes pipeline's Bound and DiceShade trim)"
                    .into(),
            );
        }
        if self.base.features().uvt {
            w.push(
                "the scene has motion blur or depth of field: the raster peer draws it at \
                 shutter open through a pinhole (only the Reyes pipeline samples time and lens)"
                    .into(),
            );
        }
        w
    }

    /// What each frame brings back ([`Pixels`]); allocates its staging buffers (call it
    /// before [`RasterPeer::render`], not between frames).
    pub fn set_pixels(&mut self, gpu: &Gpu, pixels: Pixels) -> Result<(), RunError> {
        let n = self.base.frame.width as u64 * self.base.frame.height as u64;
        for s in &mut self.slots {
            s.pixels = pixels.read_back_buffers(gpu, "raster pixels", n)?;
        }
        self.pixels = pixels;
        Ok(())
    }

    /// Reads back the tessellation of the last frame drawn (tests).
    pub fn geometry(&self, gpu: &Gpu) -> Result<Tessellation, RunError> {
        let g = &self.geometry;
        let counts = TessCounts::from_words(&gpu.read_words(&g.counts, 0, COUNT_WORDS)?);
        let grids = gpu.read_words(&g.grids, 0, 8 * self.patches as u64)?;
        let entries: Vec<[u32; 4]> = grids.chunks(4).map(|c| [c[0], c[1], c[2], c[3]]).collect();
        let vertices = gpu.read_buffer(
            &g.vertices,
            0,
            16 * counts.vertices.min(g.vertex_capacity) as u64,
        )?;
        let indices =
            gpu.read_words(&g.indices, 0, 6 * counts.quads.min(g.quad_capacity) as u64)?;
        Ok(Tessellation {
            grids: entries.iter().step_by(2).copied().collect(),
            edges: entries.iter().skip(1).step_by(2).copied().collect(),
            vertices: bytemuck::pod_collect_to_vec(&vertices),
            indices,
            counts,
        })
    }

    fn pixel_sources(&self) -> Vec<&wgpu::Buffer> {
        (self.pixels).sources(&self.rgba8, &self.rgba, &self.depth)
    }

    /// Draws one frame per turntable angle (radians), pipelined, and returns them in order.
    /// Errors: a device error or timeout, and buffers a frame needs beyond the device's limits.
    pub fn render(&mut self, gpu: &Gpu, angles: &[f64]) -> Result<Vec<PeerFrame>, RunError> {
        let mut out = Vec::with_capacity(angles.len());
        let mut flight: VecDeque<InFlight> = VecDeque::new();
        let mut last = Instant::now();
        for (i, &angle) in angles.iter().enumerate() {
            flight.push_back(self.submit(gpu, i % IN_FLIGHT, angle)?);
            if flight.len() == IN_FLIGHT {
                let f = flight.pop_front().unwrap();
                out.push(self.finish(gpu, f, &mut last, false)?);
            }
        }
        while let Some(f) = flight.pop_front() {
            out.push(self.finish(gpu, f, &mut last, false)?);
        }
        Ok(out)
    }

    /// Records and submits one frame in ring slot `slot`.
    fn submit(&self, gpu: &Gpu, slot: usize, angle: f64) -> Result<InFlight, RunError> {
        let s = &self.slots[slot];
        let orbit = Orbit::at(self.centre, angle, self.patches);
        gpu.queue
            .write_buffer(&s.orbit, 0, bytemuck::bytes_of(&orbit));
        let g = &self.geometry;
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        enc.clear_buffer(&g.counts, 0, None);
        {
            // One thread per patch: rates, culling, room and tiles; then the tiles' dispatch.
            let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("raster tessellate"),
                timestamp_writes: self.timer.begin(slot as u32),
            });
            pass.set_bind_group(0, &s.tess_bind, &[]);
            pass.set_bind_group(1, &self.scene_bind, &[]);
            if self.patches > 0 {
                pass.set_pipeline(&self.raster.tessellate[0]);
                pass.dispatch_workgroups(self.tess_groups.0, self.tess_groups.1, 1);
            }
            pass.set_pipeline(&self.raster.tessellate[1]);
            pass.dispatch_workgroups(1, 1, 1);
        }
        enc.copy_buffer_to_buffer(&g.counts, DISPATCH_WORD * 4, &g.tile_args, 0, 12);
        {
            // One thread per grid point, then per quad, over the tiles; the indirect draw.
            let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("raster dice"),
                timestamp_writes: None,
            });
            pass.set_bind_group(0, &s.tess_bind, &[]);
            pass.set_bind_group(1, &self.scene_bind, &[]);
            for p in &self.raster.tessellate[2..] {
                pass.set_pipeline(p);
                pass.dispatch_workgroups_indirect(&g.tile_args, 0);
            }
            pass.set_pipeline(&self.raster.finish_draw);
            pass.dispatch_workgroups(1, 1, 1);
        }
        {
            let store = if self.resolved.is_some() {
                wgpu::StoreOp::Discard
            } else {
                wgpu::StoreOp::Store
            };
            let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("raster draw"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &self.color,
                    depth_slice: None,
                    resolve_target: self.resolved.as_ref(),
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                        store,
                    },
                })],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &self.depth_view,
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Clear(0.0),
                        store: wgpu::StoreOp::Store,
                    }),
                    stencil_ops: None,
                }),
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(&self.raster.draw);
            pass.set_vertex_buffer(0, g.vertices.slice(..));
            pass.set_index_buffer(g.indices.slice(..), wgpu::IndexFormat::Uint32);
            pass.draw_indexed_indirect(&g.draw_args, 0);
        }
        {
            let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("raster resolve"),
                timestamp_writes: self.timer.end(slot as u32),
            });
            pass.set_pipeline(&self.raster.resolve);
            pass.set_bind_group(0, &self.resolve_bind, &[]);
            pass.dispatch_workgroups(self.resolve_groups.0, self.resolve_groups.1, 1);
            pass.set_pipeline(&self.rgba8_pipeline);
            pass.set_bind_group(0, &self.rgba8_bind, &[]);
            pass.dispatch_workgroups(self.resolve_groups.0, self.resolve_groups.1, 1);
        }
        enc.copy_buffer_to_buffer(&g.counts, 0, &s.status, 0, COUNT_WORDS * 4);
        self.timer
            .copy(&mut enc, slot as u32, &s.status, COUNT_WORDS);
        let mut maps = vec![s.status.clone()];
        for (src, dst) in self.pixel_sources().into_iter().zip(&s.pixels) {
            enc.copy_buffer_to_buffer(src, 0, dst, 0, src.size());
            maps.push(dst.clone());
        }
        let submission = gpu.submit(enc);
        let mapped = crate::realtime::map_for_read(&maps);
        Ok(InFlight {
            angle,
            slot,
            submission,
            maps,
            mapped,
            pixels: self.pixels,
        })
    }

    /// Waits for a frame (bounded) and reads its status and pixels; a frame whose patches did
    /// not fit is drawn again alone after the buffers grow (`again`: this is that drawing).
    fn finish(
        &mut self,
        gpu: &Gpu,
        f: InFlight,
        last: &mut Instant,
        again: bool,
    ) -> Result<PeerFrame, RunError> {
        gpu.wait_for(Some(f.submission.clone()), "a raster peer frame")?;
        crate::realtime::await_mapped(gpu, &f.mapped, f.maps.len(), "a raster peer frame")?;
        let status = read_mapped(&f.maps[0], COUNT_WORDS + SpanTimer::WORDS)?;
        let counts = TessCounts::from_words(&status);
        let gpu_ms = self.timer.ms(&status[COUNT_WORDS as usize..]);
        let mut pixels: Vec<Vec<u32>> = Vec::new();
        for b in &f.maps[1..] {
            pixels.push(read_mapped(b, b.size() / 4)?);
        }
        if counts.over > 0 {
            if again {
                return Err(RunError::Device(format!(
                    "a raster peer frame did not fit buffers grown to its needs ({} vertices, \
                     {} quads)",
                    counts.vertices, counts.quads
                )));
            }
            self.fit(gpu, &counts)?;
            let redo = self.submit(gpu, f.slot, f.angle)?;
            let mut frame = self.finish(gpu, redo, last, true)?;
            frame.redrawn = Some(format!(
                "{} patches did not fit the buffers ({} vertices, {} quads needed)",
                counts.over, counts.vertices, counts.quads
            ));
            frame.gpu_ms = gpu_ms.zip(frame.gpu_ms).map(|(a, b)| a + b);
            return Ok(frame);
        }
        let now = Instant::now();
        let wall_ms = now.duration_since(*last).as_secs_f64() * 1e3;
        *last = now;
        let (w, h) = (self.base.frame.width, self.base.frame.height);
        let n = (w * h) as usize;
        let (rgba8, image) = match f.pixels {
            Pixels::None => (None, None),
            Pixels::Rgba8 => (Some(bytemuck::cast_slice(&pixels[0][..n]).to_vec()), None),
            Pixels::Float => {
                let fl: &[f32] = bytemuck::cast_slice(&pixels[0][..4 * n]);
                let image = FrameImage {
                    width: w,
                    height: h,
                    rgba: fl.chunks(4).map(|c| [c[0], c[1], c[2], c[3]]).collect(),
                    depth: pixels[1][..n].iter().map(|&z| f32::from_bits(z)).collect(),
                };
                (None, Some(image))
            }
        };
        Ok(PeerFrame {
            angle: f.angle,
            gpu_ms,
            wall_ms,
            counts,
            redrawn: None,
            rgba8,
            image,
        })
    }
}
