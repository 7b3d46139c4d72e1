//! The peer's geometry buffers: grid points, indices, counters, the per-patch grids, the tile
//! list and the indirect arguments, sized for a number of vertices and quads, and grown when a
//! frame needs more ([`RasterPeer`]'s `fit`).

use super::{COUNT_WORDS, MAX_RATE, RasterPeer, TESS_TILE, TessCounts, TessParams};
use crate::gpu::SceneBuffers;
use crate::gpu_render::dispatch_2d;
use crate::realtime::HEADROOM;
use scheduler::{Gpu, RunError};

/// The vertex, index and draw buffers, sized for a number of vertices and quads.
pub(super) struct Geometry {
    pub(super) vertices: wgpu::Buffer,
    pub(super) indices: wgpu::Buffer,
    pub(super) counts: wgpu::Buffer,
    pub(super) grids: wgpu::Buffer,
    /// The frame's tiles (`tiles` in tessellate.wgsl).
    pub(super) tiles: wgpu::Buffer,
    /// The tiles' indirect dispatch, copied from the counters between the passes (a buffer
    /// bound for storage cannot be an indirect argument in the same dispatch).
    pub(super) tile_args: wgpu::Buffer,
    pub(super) draw_args: wgpu::Buffer,
    pub(super) params: wgpu::Buffer,
    pub(super) vertex_capacity: u32,
    pub(super) quad_capacity: u32,
}

fn buffer(
    gpu: &Gpu,
    label: &str,
    bytes: u64,
    usage: wgpu::BufferUsages,
) -> Result<wgpu::Buffer, RunError> {
    if bytes > gpu.max_binding_bytes() {
        return Err(RunError::Device(format!(
            "the raster peer's `{label}` needs {bytes} bytes, more than this device's storage \
             binding limit of {} bytes (a larger --mp-size needs fewer triangles)",
            gpu.max_binding_bytes()
        )));
    }
    Ok(gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: bytes.max(16).next_multiple_of(4),
        usage: usage | wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    }))
}

impl RasterPeer {
    /// The buffers for `vertices` grid points and `quads` quads of `patches` patches. The
    /// tile list holds every tile a frame that fits can take: the patches that fit hold at
    /// most `vertices` points, one tile per [`TESS_TILE`] of them plus one partial per patch.
    pub(super) fn geometry_buffers(
        gpu: &Gpu,
        patches: u32,
        vertices: u64,
        quads: u64,
    ) -> Result<Geometry, RunError> {
        let u = wgpu::BufferUsages::empty();
        let vertex_capacity = vertices.min(u32::MAX as u64) as u32;
        let tile_capacity = (vertex_capacity as u64).div_ceil(TESS_TILE as u64) + patches as u64;
        let params = TessParams {
            patches,
            row: dispatch_2d(patches as u64, 64).1,
            vertex_capacity,
            quad_capacity: quads.min(u32::MAX as u64 / 6) as u32,
            max_rate: MAX_RATE,
            tile_capacity: tile_capacity.min(u32::MAX as u64) as u32,
            pad: [0; 2],
        };
        Ok(Geometry {
            vertices: buffer(
                gpu,
                "raster vertices",
                vertices * 16,
                wgpu::BufferUsages::VERTEX,
            )?,
            indices: buffer(gpu, "raster indices", quads * 24, wgpu::BufferUsages::INDEX)?,
            counts: buffer(
                gpu,
                "raster counts",
                COUNT_WORDS * 4,
                wgpu::BufferUsages::COPY_DST,
            )?,
            grids: buffer(gpu, "raster grids", patches.max(1) as u64 * 32, u)?,
            tiles: buffer(gpu, "raster tiles", tile_capacity * 4, u)?,
            tile_args: buffer(
                gpu,
                "raster tile dispatch",
                12,
                wgpu::BufferUsages::INDIRECT | wgpu::BufferUsages::COPY_DST,
            )?,
            draw_args: buffer(gpu, "raster draw", 20, wgpu::BufferUsages::INDIRECT)?,
            params: gpu.upload("raster tessellate params", &[params])?,
            vertex_capacity: params.vertex_capacity,
            quad_capacity: params.quad_capacity,
        })
    }

    pub(super) fn tess_bind(
        gpu: &Gpu,
        layout: &wgpu::BindGroupLayout,
        orbit: &wgpu::Buffer,
        tables: &SceneBuffers,
        g: &Geometry,
    ) -> wgpu::BindGroup {
        gpu.bind_buffers_at(
            "raster tessellate",
            layout,
            &[
                (0, orbit),
                (1, tables.objects()),
                (3, &g.params),
                (4, &g.vertices),
                (5, &g.indices),
                (6, &g.counts),
                (7, &g.grids),
                (8, &g.draw_args),
                (9, &g.tiles),
            ],
        )
    }

    /// Grows the geometry buffers to [`HEADROOM`] above `counts`' needs when they do not hold
    /// them. Errors: needs beyond the device's limits.
    pub(super) fn fit(&mut self, gpu: &Gpu, counts: &TessCounts) -> Result<(), RunError> {
        let g = &self.geometry;
        let (v, q) = (counts.vertices as u64, counts.quads as u64);
        if v <= g.vertex_capacity as u64 && q <= g.quad_capacity as u64 {
            return Ok(());
        }
        let max = gpu.max_binding_bytes();
        let room = |need: u64, bytes: u64| {
            ((need as f64 * HEADROOM).ceil() as u64)
                .min(max / bytes)
                .max(need)
        };
        self.geometry = Self::geometry_buffers(gpu, self.patches, room(v, 16), room(q, 24))?;
        for s in &mut self.slots {
            s.tess_bind = Self::tess_bind(
                gpu,
                &self.raster.tess_layout,
                &s.orbit,
                &self.tables,
                &self.geometry,
            );
        }
        Ok(())
    }
}
