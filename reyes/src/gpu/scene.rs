//! The scene's tables on the device: the frame uniform, materials, lights, patch info and
//! primitive variables that common.wgsl binds (group 1), optionally the patch table of
//! homogeneous control points that roots.wgsl turns into root items, and the scene bind group
//! that joins them to a [`FrameTarget`]'s samples and counters.

use super::FrameTarget;
use crate::frame::{FrameData, FrameUniforms};
use crate::scene::Scene;
use scheduler::{Gpu, RunError};

/// One table on the device and the bytes it holds, so that a frame whose table did not change
/// writes nothing.
struct Table {
    label: &'static str,
    buffer: wgpu::Buffer,
    bytes: Vec<u8>,
}

impl Table {
    fn new<T: bytemuck::Pod>(
        gpu: &Gpu,
        label: &'static str,
        items: &[T],
    ) -> Result<Table, RunError> {
        Ok(Table {
            label,
            buffer: gpu.upload(label, items)?,
            bytes: bytemuck::cast_slice(items).to_vec(),
        })
    }

    /// Makes the table hold `items`: nothing when it does already, a write in place when the
    /// size is the same, else a new buffer (true: the bind groups of the old one are stale).
    fn set<T: bytemuck::Pod>(&mut self, gpu: &Gpu, items: &[T]) -> Result<bool, RunError> {
        let bytes: &[u8] = bytemuck::cast_slice(items);
        if self.bytes == bytes {
            return Ok(false);
        }
        if self.bytes.len() == bytes.len() {
            gpu.queue.write_buffer(&self.buffer, 0, bytes);
            self.bytes.copy_from_slice(bytes);
            return Ok(false);
        }
        *self = Table::new(gpu, self.label, items)?;
        Ok(true)
    }
}

/// A scene's tables on the device, uploaded once and shared by every frame rendered from it
/// (see the module documentation).
pub struct SceneBuffers {
    /// The frame uniform (`FrameUniforms`, common.wgsl); the offline renderer writes each bucket's.
    frame: wgpu::Buffer,
    materials: Table,
    lights: Table,
    infos: Table,
    primvars: Table,
    /// Homogeneous control points (x w, y w, z w, w), 16 per patch, cp[4*v + u], whose xyz
    /// are the host's root item and whose w its patch's weight table
    /// (`frame::homogeneous_points`: weights scaled to a largest of 1); `objects` in
    /// roots.wgsl. Only for renderers that make root items on the GPU.
    objects: Option<wgpu::Buffer>,
    /// Per patch, one u32: the occlusion history of pipelined frames that cull (`visible` in
    /// common.wgsl, `root_visible` in roots.wgsl), every patch visible at upload; a renderer
    /// that culls sets the first frame's (`realtime::occlusion::start_history`); one word when
    /// the scene was uploaded without its patch table.
    visible: wgpu::Buffer,
    /// The scene bind group last made and the target it binds ([`FrameTarget::id`]).
    bind: Option<(u64, wgpu::BindGroup)>,
}

impl SceneBuffers {
    /// Uploads `data`'s tables and its frame uniform. Errors: a table beyond the device's
    /// binding limit ([`RunError::Device`]).
    pub fn new(gpu: &Gpu, data: &FrameData) -> Result<SceneBuffers, RunError> {
        // Each table holds at least one element, also for an empty scene (Gpu::upload).
        Ok(SceneBuffers {
            frame: gpu.upload("frame", &[data.frame])?,
            materials: Table::new(gpu, "materials", &data.materials)?,
            lights: Table::new(gpu, "lights", &data.lights)?,
            infos: Table::new(gpu, "patch info", &data.patch_info)?,
            primvars: Table::new(gpu, "primvars", &data.primvars)?,
            objects: None,
            visible: gpu.storage_buffer("occlusion history", 1)?,
            bind: None,
        })
    }

    /// As [`SceneBuffers::new`], with `scene`'s patch table for root items made on the GPU
    /// (`data` must be `scene`'s frame data). Errors: as [`SceneBuffers::new`].
    pub fn with_patches(
        gpu: &Gpu,
        scene: &Scene,
        data: &FrameData,
    ) -> Result<SceneBuffers, RunError> {
        let objects: Vec<[f32; 4]> = (scene.patches.iter())
            .flat_map(crate::frame::homogeneous_points)
            .collect();
        let objects = gpu.upload("patch table", &objects)?;
        let mut s = SceneBuffers::new(gpu, data)?;
        s.objects = Some(objects);
        s.visible = gpu.upload("occlusion history", &vec![1u32; scene.patches.len()])?;
        Ok(s)
    }

    /// Makes the tables hold `data`'s, writing only those that changed (a frame of the same
    /// scene writes nothing). The frame uniform is left alone: renderers write it per bucket
    /// (`SceneBuffers::write_frame`). Errors: as [`SceneBuffers::new`].
    pub fn update(&mut self, gpu: &Gpu, data: &FrameData) -> Result<(), RunError> {
        let mut stale = self.materials.set(gpu, &data.materials)?;
        stale |= self.lights.set(gpu, &data.lights)?;
        stale |= self.infos.set(gpu, &data.patch_info)?;
        stale |= self.primvars.set(gpu, &data.primvars)?;
        if stale {
            self.bind = None;
        }
        Ok(())
    }

    /// The frame uniform's buffer (pipelined frames copy each phase's into it).
    pub(crate) fn frame_buffer(&self) -> &wgpu::Buffer {
        &self.frame
    }

    /// Writes the frame uniform (queue order: work submitted before reads the old one).
    pub(crate) fn write_frame(&self, gpu: &Gpu, f: &FrameUniforms) {
        gpu.queue
            .write_buffer(&self.frame, 0, bytemuck::bytes_of(f));
    }

    /// Writes the primitive-variable table in place (`table` as long as the scene's; motion
    /// blur under a moving camera rewrites the moving patches' entries).
    pub(crate) fn write_primvars(&mut self, gpu: &Gpu, table: &[[f32; 4]]) -> Result<(), RunError> {
        if self.primvars.set(gpu, table)? {
            self.bind = None;
        }
        Ok(())
    }

    /// The scene bind group (common.wgsl's group: frame, materials, lights, patch info,
    /// `target`'s samples and counters, primvars, `target`'s depth pyramid, the occlusion
    /// history) for the layout of
    /// [`Pipelines::scene_layout`](super::Pipelines::scene_layout); made again only when the
    /// target or a table's buffer changed.
    pub(crate) fn bind_group(
        &mut self,
        gpu: &Gpu,
        layout: &wgpu::BindGroupLayout,
        target: &FrameTarget,
    ) -> wgpu::BindGroup {
        if let Some((id, bind)) = &self.bind
            && *id == target.id()
        {
            return bind.clone();
        }
        let bind = gpu.bind_buffers(
            "reyes scene",
            layout,
            &[
                &self.frame,
                &self.materials.buffer,
                &self.lights.buffer,
                &self.infos.buffer,
                &target.samples,
                &target.counters,
                &self.primvars.buffer,
                &target.hiz,
                &self.visible,
            ],
        );
        self.bind = Some((target.id(), bind.clone()));
        bind
    }

    /// Drops the scene bind group (before its target is replaced, so that the old target's
    /// memory is freed before the new one is allocated).
    pub(crate) fn forget_bind_group(&mut self) {
        self.bind = None;
    }

    /// The tables without the samples and counters, for a layout of bindings 0-3 and 6 (the
    /// raster peer's group 1): frame, materials, lights, patch info, primvars.
    pub(crate) fn tables(&self) -> [(u32, &wgpu::Buffer); 5] {
        [
            (0, &self.frame),
            (1, &self.materials.buffer),
            (2, &self.lights.buffer),
            (3, &self.infos.buffer),
            (6, &self.primvars.buffer),
        ]
    }

    /// The per-patch occlusion history ([`SceneBuffers::with_patches`]: one word a patch).
    pub(crate) fn visible(&self) -> &wgpu::Buffer {
        &self.visible
    }

    /// The patch table ([`SceneBuffers::with_patches`]). Panics when the scene was uploaded
    /// without it (a renderer's own invariant).
    pub(crate) fn objects(&self) -> &wgpu::Buffer {
        self.objects
            .as_ref()
            .expect("the scene was uploaded with its patch table")
    }
}
