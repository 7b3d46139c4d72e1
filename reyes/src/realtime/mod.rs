//! Frames whose wall time is their GPU time: a persistent renderer for many frames of one scene
//! under a moving camera: the turntable of [`crate::orbit`] (`reyes bench`), or any camera-space
//! transform per frame, as the viewer's orbit, pan and dolly ([`crate::camera`], `reyes view`).
//!
//! [`GpuRenderer::render`] makes its root items on the host, runs with counters read back
//! between launches, and reads back the f32 image. Here, instead:
//! - the scene is uploaded once ([`SceneBuffers::with_patches`]): each patch's homogeneous
//!   control points (`x w, y w, z w, w`) in a table, the materials, lights and patch flags; a
//!   frame writes only an 80-byte [`Orbit`] (its camera transform);
//! - the root items are made on the GPU (`roots.wgsl`: the transform, then the same root item
//!   as [`crate::frame::FrameData::new`] makes on the host), every frame rebuilt from the
//!   patches; nothing is cached between frames but buffers and pipelines;
//! - every buffer is allocated once ([`RealtimeRenderer::new`]) and reused: the
//!   [`FrameTarget`] (samples, counters, image), the queues of a [`RecordedRun`] (the scheduler's run of fixed sizes, recorded
//!   without host waits);
//! - frames are pipelined: frame i+1 is recorded and submitted while the GPU runs frame i (at
//!   most [`IN_FLIGHT`] submitted and unfinished); each frame's status (the scheduler's control
//!   block, the Reyes counters, two GPU timestamps: about 100 words) is copied into a mapped
//!   staging ring and read a frame late; nothing else is read back unless an image is wanted
//!   ([`Pixels`]), which is converted to 8-bit on the GPU (`rgba8.wgsl`); the 8-bit image
//!   also stays on the GPU ([`RealtimeRenderer::image_buffer`]) for a window to draw without a
//!   read-back.
//!
//! A frame whose fixed sizes did not suffice (a queue out of room, a megakernel launch at its
//! loop bound, multi-pass out of rounds) is found a frame late from its status and rendered again
//! by the offline renderer's core (that of [`GpuRenderer::render`], on this renderer's scene
//! tables and target) from the same root items (read back from the GPU), which grows its queues, splits batches and cuts buckets as needed: the frame comes out right and says that it
//! was rendered again ([`RealtimeFrame::rerendered`]); the fixed sizes then grow to what that
//! render needed. A wrong frame is never returned.
//!
//! Occlusion culling (`--occlusion on`, or `auto` on a deep scene): each frame in two phases
//! from the previous frame's visibility, all on the GPU ([`occlusion`]); the image is the same.
//!
//! Motion blur: a moving patch's motion (camera space, [`crate::scene::Patch::motion`]) is
//! seen by a frame of camera transform T as T D T^-1; a frame whose transform differs from the
//! last one's rewrites the primitive-variable table that holds them (one upload per frame).
//!
//! Not pipelined (every frame by [`GpuRenderer::render`] from GPU-made roots, each reported as
//! rendered again with the reason): the host-driven multi-pass (it plans rounds on the host),
//! and a memory budget too small for the whole frame's samples (those frames need buckets).

use crate::buckets;
use crate::frame::{FrameData, PatchItem, RenderOptions};
use crate::gpu::{FrameTarget, SceneBuffers};
use crate::gpu_render::{GpuFrame, GpuRenderer, RendererConfig, dispatch_2d, resolve_params};
use crate::image::FrameImage;
use crate::orbit;
use crate::progress::Progress;
use crate::scene::Scene;
use crate::stages::COUNTERS;
use bytemuck::{Pod, Zeroable};
use glam::DMat4;
use scheduler::timing::SpanTimer;
use scheduler::{
    DeviceSeeds, Gpu, Outcome, RecordedRun, RecordedSize, RunError, RunStats, StrategyKind,
};
use std::collections::VecDeque;
use std::rc::Rc;
use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

pub mod occlusion;
mod readback;
use occlusion::{Culling, PHASES};
pub use readback::Pixels;
pub(crate) use readback::{await_mapped, map_buffer, map_for_read, read_mapped};

/// Frames submitted and not yet finished, at most: the GPU runs one while the host records the
/// next.
pub const IN_FLIGHT: usize = 2;

/// Fixed sizes are this much above what a full render of the first frame needed (a turning
/// scene needs more in some frames than in others).
pub const HEADROOM: f64 = 1.5;

/// The per-frame uniform: the camera transform of the frame's root items (`Orbit` in roots.wgsl).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct Orbit {
    /// Column-major affine transform of camera-space points ([`orbit::orbit_matrix`],
    /// [`crate::camera::ViewCamera::transform`]).
    pub m: [[f32; 4]; 4],
    /// Root patches (threads of the roots dispatch).
    pub patches: u32,
    /// Threads per row of the 2D dispatch.
    pub row: u32,
    /// 1: tag the roots with the occlusion history and clear it ([`occlusion`]); 0: not.
    pub history: u32,
    /// Padding to a multiple of 16 bytes.
    pub pad: u32,
}

impl Orbit {
    /// The frame at turntable `angle` (radians) of a scene of `patches` patches turning about
    /// `centre` ([`orbit::orbit_matrix`]), with `make_roots`'s dispatch row (64 threads a group).
    pub fn at(centre: glam::DVec3, angle: f64, patches: u32) -> Orbit {
        Orbit::from_transform(orbit::orbit_transform(centre, angle), patches)
    }

    /// The frame of camera-space transform `transform` (affine, f64, applied on the GPU in
    /// f32; e.g. [`crate::camera::ViewCamera::transform`]).
    pub fn from_transform(transform: DMat4, patches: u32) -> Orbit {
        let (_, row) = dispatch_2d(patches as u64, 64);
        Orbit {
            m: (transform.to_cols_array_2d()).map(|col| col.map(|v| v as f32)),
            patches,
            row,
            history: 0,
            pad: 0,
        }
    }
}

/// One finished frame.
#[derive(Clone, Debug)]
pub struct RealtimeFrame {
    /// The camera-space transform of the scene the frame was rendered under (f64; the GPU
    /// applies it in f32).
    pub transform: DMat4,
    /// GPU time: from the start of the frame's first pass to the end of its last, plus, for a
    /// frame rendered again, that render's timed passes. `None` without timestamp queries.
    pub gpu_ms: Option<f64>,
    /// Host time between this frame's completion and the previous one's (the first: since its
    /// recording began): what a viewer waits per frame.
    pub wall_ms: f64,
    /// The Reyes counters ([`crate::stages`]).
    pub counters: [u64; COUNTERS],
    /// The scheduler's statistics of the frame's run.
    pub run: RunStats,
    /// Why the pipelined attempt did not finish, when the frame was rendered again by
    /// [`GpuRenderer::render`].
    pub rerendered: Option<String>,
    /// With [`Pixels::Rgba8`]: the 8-bit image, row-major RGBA.
    pub rgba8: Option<Vec<u8>>,
    /// With [`Pixels::Float`]: the f32 image and depth.
    pub image: Option<FrameImage>,
}

/// Buffers of one frame in flight.
struct Slot {
    orbit: wgpu::Buffer,
    roots: wgpu::Buffer,
    roots_bind: wgpu::BindGroup,
    /// MAP_READ: the frame's status.
    status: wgpu::Buffer,
    /// MAP_READ, per [`Pixels`]: rgba8, or rgba f32 and depth.
    pixels: Vec<wgpu::Buffer>,
}

struct InFlight {
    transform: DMat4,
    slot: usize,
    submission: wgpu::SubmissionIndex,
    /// The run recorded (the sizes may grow while this frame is in flight).
    recorded: Option<Rc<RecordedRun>>,
    /// Scheduler runs recorded: 1, or [`PHASES`] when the frame culls.
    phases: usize,
    /// Buffers mapped for reading (status, then pixels), and maps completed by their callbacks.
    maps: Vec<wgpu::Buffer>,
    mapped: Arc<AtomicUsize>,
    pixels: Pixels,
}

/// A renderer of many frames of one scene; see the module documentation.
pub struct RealtimeRenderer {
    renderer: GpuRenderer,
    kind: StrategyKind,
    /// The frame's settings and scene tables; `items` are the host's unturned roots.
    base: FrameData,
    centre: glam::DVec3,
    patches: u32,
    pixels: Pixels,
    /// The scene's tables and patch table, uploaded once.
    scene: SceneBuffers,
    /// What every frame renders into, with its 8-bit image.
    target: FrameTarget,
    scene_bind: wgpu::BindGroup,
    resolve_bind: wgpu::BindGroup,
    rgba8_bind: wgpu::BindGroup,
    /// Kept alive for the bind groups: the resolve and rgba8 parameters.
    _params: Vec<wgpu::Buffer>,
    slots: Vec<Slot>,
    timer: SpanTimer,
    /// The pipelined run; `None` when frames are not pipelined (`not_pipelined` says why).
    recorded: Option<Rc<RecordedRun>>,
    /// The sizes asked for (before the device's and the budget's limits).
    wanted: RecordedSize,
    not_pipelined: Option<String>,
    roots_groups: (u32, u32),
    resolve_groups: (u32, u32),
    rgba8_groups: (u32, u32),
    /// Moving patches' motion (motion blur): each one's entry in the primitive-variable table
    /// and its camera-space map from shutter open to close under the unturned camera. A frame
    /// of transform T moves by T D T^-1 ([`motion_primvars`]); the table on the GPU holds the
    /// rows of the transform in `motion_written`.
    motion: Vec<(u32, DMat4)>,
    motion_written: std::cell::Cell<DMat4>,
    /// Pipelined frames cull from the previous frame ([`occlusion`]) when `Some`.
    culling: Option<Culling>,
    /// `FrameUniforms::occlusion` of the options (`base.frame` has it off): frames that are
    /// not pipelined render with it.
    asked_occlusion: u32,
}

/// `base`'s primitive-variable table with each moving patch's motion `d` (at entry `at`) as
/// seen by a frame of camera-space transform `t`: `t d t^-1`.
fn motion_primvars(base: &[[f32; 4]], motion: &[(u32, DMat4)], t: DMat4) -> Vec<[f32; 4]> {
    let mut table = base.to_vec();
    let inv = t.inverse();
    for &(at, d) in motion {
        let m = t * d * inv;
        for r in 0..3 {
            table[at as usize + r] = std::array::from_fn(|c| m.col(c)[r] as f32);
        }
    }
    table
}

const STATUS_COUNTERS: u64 = COUNTERS as u64;

impl RealtimeRenderer {
    /// Uploads `scene` for frames of `options` under `strategy`, compiles the pipelines, and
    /// renders the unturned frame once with [`GpuRenderer::render`] to size the pipelined run
    /// ([`HEADROOM`] above its needs). Errors: the options' ([`FrameData::new`], as
    /// [`RunError::Program`]), [`StrategyKind::MultipassFloor`] ([`RunError::Program`]: it
    /// replays one kept frame's work and cannot follow a moving view), and those of a render.
    pub fn new(
        gpu: &Gpu,
        scene: &Scene,
        options: &RenderOptions,
        strategy: StrategyKind,
        pixels: Pixels,
    ) -> Result<RealtimeRenderer, RunError> {
        if strategy == StrategyKind::MultipassFloor {
            return Err(RunError::Program(
                "the multi-pass floor replays one kept frame's work and cannot render frames \
                 of a moving view"
                    .into(),
            ));
        }
        let mut base =
            FrameData::new(scene, options).map_err(|e| RunError::Program(e.to_string()))?;
        // `base.frame` has culling off: pipelined frames that cull say so per phase
        // (`occlusion::Culling`); the frame that sizes the pipelined run and a frame rendered
        // again set it per call (`RealtimeRenderer::render_occlusion`).
        let asked_occlusion = base.frame.occlusion;
        base.frame.occlusion = crate::stages::hiz::OCCLUSION_OFF;
        let config = RendererConfig::new(strategy).features(base.features());
        let renderer = GpuRenderer::new(gpu, config.lavapipe_tuning(false))?;
        let f = base.frame;
        let n = scene.patches.len() as u32;
        let mut scene_buffers = SceneBuffers::with_patches(gpu, scene, &base)?;
        let pixels_n = f.width as u64 * f.height as u64;
        let spp = (f.spp_x * f.spp_y) as u64;
        let target = FrameTarget::new(gpu, pixels_n * spp * 2, pixels_n, true)?;
        let pipelines = &renderer.pipelines;
        let scene_bind = scene_buffers.bind_group(gpu, pipelines.scene_layout(), &target);
        let (resolve, resolve_groups) = resolve_params(&f, base.background);
        let resolve_buf = gpu.upload("resolve params", &resolve)?;
        let resolve_bind = gpu.bind_buffers(
            "resolve",
            &pipelines.resolve(gpu)?.get_bind_group_layout(0),
            &[&resolve_buf, &target.samples, &target.rgba, &target.depth],
        );
        let (rgba8_groups, row) = dispatch_2d(pixels_n, 256);
        let rgba8_buf = gpu.upload("rgba8 params", &[pixels_n as u32, row, 0, 0])?;
        let rgba8_bind = gpu.bind_buffers(
            "rgba8",
            &pipelines.rgba8(gpu)?.get_bind_group_layout(0),
            &[&rgba8_buf, &target.rgba, target.rgba8()],
        );
        let roots_pipeline = pipelines.roots(gpu)?;
        let (roots_groups, _) = dispatch_2d(n as u64, 64);
        let mut slots = Vec::new();
        for _ in 0..IN_FLIGHT {
            let orbit = gpu.storage_buffer("orbit", (size_of::<Orbit>() / 4) as u64)?;
            let roots = gpu.upload("roots", &vec![PatchItem::zeroed(); n as usize])?;
            let roots_bind = gpu.bind_buffers_at(
                "roots",
                &roots_pipeline.get_bind_group_layout(0),
                &[
                    (0, &orbit),
                    (1, scene_buffers.objects()),
                    (2, &roots),
                    (10, scene_buffers.visible()),
                ],
            );
            slots.push(Slot {
                orbit,
                roots,
                roots_bind,
                status: map_buffer(gpu, "frame status", 4)?,
                pixels: Vec::new(),
            });
        }
        let mut r = RealtimeRenderer {
            renderer,
            kind: strategy,
            centre: orbit::scene_centre(scene),
            patches: n,
            pixels: Pixels::None,
            scene: scene_buffers,
            target,
            scene_bind,
            resolve_bind,
            rgba8_bind,
            _params: vec![resolve_buf, rgba8_buf],
            slots,
            timer: SpanTimer::new(gpu, IN_FLIGHT as u32),
            recorded: None,
            wanted: RecordedSize {
                capacity: Vec::new(),
                rounds: 0,
            },
            not_pipelined: None,
            roots_groups,
            resolve_groups,
            rgba8_groups,
            motion: (scene.patches.iter().zip(&base.patch_info))
                .filter_map(|(p, i)| p.motion.as_deref().map(|m| (i.motion, *m)))
                .collect(),
            motion_written: std::cell::Cell::new(DMat4::IDENTITY),
            base,
            culling: None,
            asked_occlusion,
        };
        r.set_pixels(gpu, pixels)?;
        if strategy == StrategyKind::MultipassHost {
            r.not_pipelined =
                Some("the host-driven multi-pass plans each round on the host".into());
        } else if buckets::plan(&f, r.base.memory_budget).len() > 1 {
            r.not_pipelined = Some(format!(
                "the memory budget of {} bytes does not hold the whole frame's samples: frames \
                 render in buckets",
                r.base.memory_budget.unwrap_or(0)
            ));
        } else {
            if occlusion::wanted(&r.base, asked_occlusion) {
                r.culling = Culling::new(gpu, &r.renderer, &r.base.frame, &r.target)?;
            }
            // Sized by the single frame with the culling the pipelined frames will do (its
            // passes, `stages::hiz::passes`), not by the unculled frame: on a deep scene that
            // one is many times the work and the queues' memory.
            let mut first = r.base.clone();
            first.frame.occlusion = r.render_occlusion();
            let g = r.render_on_target(gpu, &first)?;
            let size = r.size_from(&g.run);
            r.resize(gpu, size)?;
            r.start_history(gpu, &r.base.items);
        }
        Ok(r)
    }

    /// `FrameUniforms::occlusion` of a frame rendered by [`GpuRenderer::render`] (the frame
    /// that sizes the pipelined run, a frame rendered again): the options' when frames are not
    /// pipelined; when they cull, the single frame's culling passes; else none.
    fn render_occlusion(&self) -> u32 {
        if self.not_pipelined.is_some() {
            self.asked_occlusion
        } else if self.culling.is_some() {
            crate::stages::hiz::OCCLUSION_ON
        } else {
            crate::stages::hiz::OCCLUSION_OFF
        }
    }

    /// Sets the occlusion history that the next frame submitted reads
    /// ([`occlusion::start_history`] of `items`, this scene's untagged root items, one per
    /// patch) when pipelined frames cull; queue order puts the write after the frames already
    /// submitted.
    fn start_history(&self, gpu: &Gpu, items: &[PatchItem]) {
        if self.culling.is_none() || items.len() != self.patches as usize {
            return;
        }
        let history = occlusion::start_history(&self.base, items);
        gpu.queue
            .write_buffer(self.scene.visible(), 0, bytemuck::cast_slice(&history));
    }

    /// Whether pipelined frames cull from the previous frame ([`occlusion`]): with
    /// `--occlusion on`, or `auto` where the unturned frame's root patches lie deep over each
    /// other; never when frames are not pipelined (those cull as `reyes render` does).
    pub fn occlusion(&self) -> bool {
        self.culling.is_some()
    }

    /// Why frames are not pipelined, when they are not.
    pub fn not_pipelined(&self) -> Option<&str> {
        self.not_pipelined.as_deref()
    }

    /// The fixed sizes of the pipelined run, after the device's and the budget's limits.
    pub fn size(&self) -> Option<&RecordedSize> {
        self.recorded.as_ref().map(|r| &r.size)
    }

    /// Image width and height in pixels, and pixel samples per axis.
    pub fn frame_size(&self) -> (u32, u32, [u32; 2]) {
        let f = &self.base.frame;
        (f.width, f.height, [f.spp_x, f.spp_y])
    }

    /// The frame's settings (size, samples, focal length, micropolygon size).
    pub fn frame(&self) -> &crate::frame::FrameUniforms {
        &self.base.frame
    }

    /// The strategy frames are rendered with.
    pub fn strategy(&self) -> StrategyKind {
        self.kind
    }

    /// Centre of the scene's control points' bounding box, camera space: the point the
    /// turntable and the viewer's camera turn about ([`orbit::scene_centre`]).
    pub fn centre(&self) -> glam::DVec3 {
        self.centre
    }

    /// The 8-bit sRGB image on the GPU: `width * height` u32 words, row-major from the top row,
    /// each the bytes r, g, b, a in memory order (`rgba8.wgsl`); `STORAGE | COPY_SRC`. When
    /// [`RealtimeRenderer::render`] or [`RealtimeRenderer::render_transforms`] returns, it holds
    /// the last returned frame (a frame rendered again is written here too), until the next
    /// call's frames overwrite it: work submitted in between (a draw to a window) reads it.
    pub fn image_buffer(&self) -> &wgpu::Buffer {
        self.target.rgba8()
    }

    /// The strategy's scheduler and the renderer that renders a frame again.
    pub fn renderer(&self) -> &GpuRenderer {
        &self.renderer
    }

    /// What each frame brings back ([`Pixels`]); allocates the staging buffers it needs (not
    /// between frames: call it before [`RealtimeRenderer::render`]).
    pub fn set_pixels(&mut self, gpu: &Gpu, pixels: Pixels) -> Result<(), RunError> {
        let n = self.base.frame.width as u64 * self.base.frame.height as u64;
        for s in &mut self.slots {
            s.pixels = pixels.read_back_buffers(gpu, "frame pixels", n)?;
        }
        self.pixels = pixels;
        Ok(())
    }

    /// Sets the fixed sizes of the pipelined run (allocating its queues; tests use it to force
    /// a frame that does not fit). Does nothing when frames are not pipelined.
    pub fn resize(&mut self, gpu: &Gpu, size: RecordedSize) -> Result<(), RunError> {
        if self.not_pipelined.is_some() {
            return Ok(());
        }
        let run = RecordedRun::new(
            gpu,
            &self.renderer.scheduler,
            &[("bound", self.patches)],
            &size,
            Some(&self.scene_bind),
            self.base.memory_budget.map(|b| {
                b.saturating_sub(
                    buckets::sample_bytes_per_pixel(&self.base.frame) * self.pixels_n(),
                )
            }),
        )?;
        let words = PHASES as u64 * run.status_words() + STATUS_COUNTERS + SpanTimer::WORDS;
        for s in &mut self.slots {
            if s.status.size() < words * 4 {
                s.status = map_buffer(gpu, "frame status", words)?;
            }
        }
        self.recorded = Some(Rc::new(run));
        self.wanted = size;
        Ok(())
    }

    /// The GPU buffers [`Pixels`] copies back: rgba8, or rgba and depth.
    fn pixel_sources(&self) -> Vec<&wgpu::Buffer> {
        let t = &self.target;
        (self.pixels).sources(t.rgba8(), &t.rgba, &t.depth)
    }

    fn pixels_n(&self) -> u64 {
        self.base.frame.width as u64 * self.base.frame.height as u64
    }

    /// Renders `data` (this scene's frame with host-made or read-back root items) by the
    /// offline core on this renderer's scene tables and target: the frame that sizes the
    /// pipelined run, and a frame rendered again. Queue order keeps frames already submitted
    /// apart: they read the tables and target before this frame's writes.
    fn render_on_target(&mut self, gpu: &Gpu, data: &FrameData) -> Result<GpuFrame, RunError> {
        self.scene.update(gpu, data)?;
        let bind =
            (self.scene).bind_group(gpu, self.renderer.pipelines.scene_layout(), &self.target);
        (self.renderer).render_on(gpu, &self.scene, &self.target, &bind, data, Instant::now())
    }

    /// The fixed sizes for frames like `run` (a render by [`GpuRenderer::render`] of this
    /// scene), [`HEADROOM`] above its needs. Every record (each phase of a frame that culls) is
    /// seeded with every root, while the single frame's culling passes each seed a part: the
    /// roots count in Bound's peak, so that the multi-pass plan has room for what they may emit.
    fn size_from(&self, run: &RunStats) -> RecordedSize {
        let program = self.renderer.scheduler.program();
        let mut seeds = vec![0; program.queue_count()];
        let bound = program.index_of("bound").unwrap();
        seeds[bound] = self.patches;
        let mut run = run.clone();
        if run.peak_occupancy.len() > bound {
            let peak = &mut run.peak_occupancy[bound];
            *peak = (*peak).max(self.patches as u64);
        }
        RecordedSize::from_stats(program, self.kind, &run, &seeds, HEADROOM)
    }

    /// Renders one frame per turntable angle (radians; [`orbit::orbit_transform`] about the
    /// scene's centre), pipelined, and returns them in order; `progress` advances by one as
    /// each frame is finished. Errors: as [`RealtimeRenderer::render_transforms`].
    pub fn render(
        &mut self,
        gpu: &Gpu,
        angles: &[f64],
        progress: &dyn Progress,
    ) -> Result<Vec<RealtimeFrame>, RunError> {
        let transforms: Vec<DMat4> = (angles.iter())
            .map(|&a| orbit::orbit_transform(self.centre, a))
            .collect();
        self.render_transforms(gpu, &transforms, progress)
    }

    /// Renders one frame per camera-space transform of the scene's control points (an affine
    /// f64 matrix, applied on the GPU in f32; e.g. [`crate::camera::ViewCamera::transform`]),
    /// pipelined, and returns them in order; `progress` advances by one per finished frame.
    /// Errors: a device error or timeout, an emit beyond a procedure's declaration, and those
    /// of a frame rendered again (e.g. a queue overflow of one patch in the smallest bucket).
    pub fn render_transforms(
        &mut self,
        gpu: &Gpu,
        transforms: &[DMat4],
        progress: &dyn Progress,
    ) -> Result<Vec<RealtimeFrame>, RunError> {
        let mut out = Vec::with_capacity(transforms.len());
        let mut flight: VecDeque<InFlight> = VecDeque::new();
        let mut last = Instant::now();
        for (i, &transform) in transforms.iter().enumerate() {
            flight.push_back(self.submit(gpu, i % IN_FLIGHT, transform)?);
            // Frame i runs on the GPU (after i - 1) while frame i - 1 is finished here; then
            // frame i + 1 is recorded while i runs.
            if flight.len() == IN_FLIGHT {
                let f = flight.pop_front().unwrap();
                out.push(self.finish(gpu, f, &mut last)?);
                progress.advance(1);
            }
        }
        while let Some(f) = flight.pop_front() {
            out.push(self.finish(gpu, f, &mut last)?);
            progress.advance(1);
        }
        Ok(out)
    }

    /// Records and submits one frame in ring slot `slot`.
    fn submit(&mut self, gpu: &Gpu, slot: usize, transform: DMat4) -> Result<InFlight, RunError> {
        if !self.motion.is_empty() && self.motion_written.get() != transform {
            // Queue order: the frames already submitted read the table before this write.
            let table = motion_primvars(&self.base.primvars, &self.motion, transform);
            self.scene.write_primvars(gpu, &table)?;
            self.motion_written.set(transform);
        }
        let s = &self.slots[slot];
        let orbit = Orbit {
            history: self.culling.is_some() as u32,
            ..Orbit::from_transform(transform, self.patches)
        };
        gpu.queue
            .write_buffer(&s.orbit, 0, bytemuck::bytes_of(&orbit));
        let recorded = self.recorded.clone();
        let timer_slot = slot as u32;
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        let groups = |pass: &mut wgpu::ComputePass, (x, y): (u32, u32)| {
            if x > 0 {
                pass.dispatch_workgroups(x, y, 1);
            }
        };
        {
            let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("roots"),
                timestamp_writes: recorded.as_ref().and_then(|_| self.timer.begin(timer_slot)),
            });
            pass.set_pipeline(self.renderer.pipelines.roots(gpu)?);
            pass.set_bind_group(0, &s.roots_bind, &[]);
            groups(&mut pass, self.roots_groups);
        }
        let mut maps = Vec::new();
        let mut phases = 1;
        if let Some(rec) = &recorded {
            enc.clear_buffer(&self.target.samples, 0, None);
            enc.clear_buffer(&self.target.counters, 0, None);
            let seeds = [DeviceSeeds {
                procedure: "bound",
                buffer: &s.roots,
                count: self.patches,
            }];
            let words = rec.status_words();
            match &self.culling {
                Some(c) => {
                    let scene = (&self.scene, &self.scene_bind);
                    let (status, r) = (&s.status, &self.renderer);
                    c.record(gpu, r, &mut enc, (rec, &seeds), scene, status, words)?;
                    phases = PHASES;
                }
                None => rec.record(
                    &self.renderer.scheduler,
                    &mut enc,
                    &seeds,
                    Some(&self.scene_bind),
                    &s.status,
                    0,
                )?,
            }
            let at = PHASES as u64 * words;
            enc.copy_buffer_to_buffer(
                &self.target.counters,
                0,
                &s.status,
                at * 4,
                STATUS_COUNTERS * 4,
            );
            {
                let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: Some("resolve"),
                    timestamp_writes: self.timer.end(timer_slot),
                });
                let pipelines = &self.renderer.pipelines;
                pass.set_pipeline(pipelines.resolve(gpu)?);
                pass.set_bind_group(0, &self.resolve_bind, &[]);
                groups(&mut pass, self.resolve_groups);
                pass.set_pipeline(pipelines.rgba8(gpu)?);
                pass.set_bind_group(0, &self.rgba8_bind, &[]);
                groups(&mut pass, self.rgba8_groups);
            }
            self.timer
                .copy(&mut enc, timer_slot, &s.status, at + STATUS_COUNTERS);
            maps.push(s.status.clone());
            for (src, dst) in self.pixel_sources().into_iter().zip(&s.pixels) {
                enc.copy_buffer_to_buffer(src, 0, dst, 0, src.size());
                maps.push(dst.clone());
            }
        }
        let submission = gpu.submit(enc);
        let mapped = map_for_read(&maps);
        Ok(InFlight {
            transform,
            slot,
            submission,
            recorded,
            phases,
            mapped,
            maps,
            pixels: self.pixels,
        })
    }

    /// Waits for a frame (bounded), reads its status and pixels, and renders it again when its
    /// run did not finish.
    fn finish(
        &mut self,
        gpu: &Gpu,
        f: InFlight,
        last: &mut Instant,
    ) -> Result<RealtimeFrame, RunError> {
        gpu.wait_for(Some(f.submission.clone()), "a pipelined frame")?;
        await_mapped(gpu, &f.mapped, f.maps.len(), "a pipelined frame")?;
        let Some(rec) = f.recorded else {
            let why = self.not_pipelined.clone().unwrap_or_default();
            return self.render_again(gpu, f.slot, f.transform, why, None, last);
        };
        let words = rec.status_words();
        let at = PHASES as u64 * words;
        let status = read_mapped(&f.maps[0], at + STATUS_COUNTERS + SpanTimer::WORDS)?;
        let (sched, rest) = status.split_at(at as usize);
        let gpu_ms = self.timer.ms(&rest[COUNTERS..]);
        let mut pixels: Vec<Vec<u32>> = Vec::new();
        for (b, src) in f.maps[1..].iter().zip(self.pixel_sources()) {
            pixels.push(read_mapped(b, src.size() / 4)?);
        }
        let program = self.renderer.scheduler.program();
        // Each phase's run; the frame is done when all are.
        let mut outcome = Outcome::Done(RunStats::default());
        for (k, status) in sched.chunks(words as usize).take(f.phases).enumerate() {
            outcome = match (outcome, rec.outcome(program, status)?) {
                (Outcome::Done(mut a), Outcome::Done(b)) => {
                    match k {
                        0 => a = b,
                        _ => a.absorb(&b),
                    }
                    Outcome::Done(a)
                }
                (Outcome::Incomplete(why), _) => Outcome::Incomplete(why),
                (_, Outcome::Incomplete(why)) if f.phases > 1 => {
                    Outcome::Incomplete(format!("phase {} of {}: {why}", k + 1, f.phases))
                }
                (_, o) => o,
            };
        }
        match outcome {
            Outcome::Done(run) => {
                let mut counters = [0u64; COUNTERS];
                for (c, v) in counters.iter_mut().zip(&rest[..COUNTERS]) {
                    *c = *v as u64;
                }
                let now = Instant::now();
                let wall_ms = now.duration_since(*last).as_secs_f64() * 1e3;
                *last = now;
                let (w, h) = (self.base.frame.width, self.base.frame.height);
                let (rgba8, image) = match f.pixels {
                    Pixels::None => (None, None),
                    Pixels::Rgba8 => (Some(bytemuck::cast_slice(&pixels[0]).to_vec()), None),
                    Pixels::Float => {
                        let fl: &[f32] = bytemuck::cast_slice(&pixels[0]);
                        let image = FrameImage {
                            width: w,
                            height: h,
                            rgba: fl.chunks(4).map(|c| [c[0], c[1], c[2], c[3]]).collect(),
                            depth: pixels[1].iter().map(|&z| f32::from_bits(z)).collect(),
                        };
                        (None, Some(image))
                    }
                };
                Ok(RealtimeFrame {
                    transform: f.transform,
                    gpu_ms,
                    wall_ms,
                    counters,
                    run,
                    rerendered: None,
                    rgba8,
                    image,
                })
            }
            Outcome::Incomplete(why) => {
                self.render_again(gpu, f.slot, f.transform, why, gpu_ms, last)
            }
        }
    }

    /// Renders the frame whose roots are in `slot` with [`GpuRenderer::render`] and grows the
    /// fixed sizes to what it needed. `attempt_ms`: GPU time of the pipelined attempt.
    fn render_again(
        &mut self,
        gpu: &Gpu,
        slot: usize,
        transform: DMat4,
        why: String,
        attempt_ms: Option<f64>,
        last: &mut Instant,
    ) -> Result<RealtimeFrame, RunError> {
        let bytes = self.patches as u64 * size_of::<PatchItem>() as u64;
        let roots = gpu.read_buffer(&self.slots[slot].roots, 0, bytes)?;
        let mut items: Vec<PatchItem> = bytemuck::pod_collect_to_vec(&roots);
        occlusion::untag(&mut items);
        let mut data = FrameData {
            items,
            primvars: motion_primvars(&self.base.primvars, &self.motion, transform),
            ..self.base.clone()
        };
        // A frame that is never pipelined culls as `reyes render` does; one whose pipelined
        // attempt fell short renders with the culling passes when frames cull (the sizes then
        // grow to its needs, or double: `occlusion::grow`), else all the work.
        data.frame.occlusion = self.render_occlusion();
        let g = self.render_on_target(gpu, &data)?;
        // The attempt left a partial history: start again from this frame's front roots.
        self.start_history(gpu, &data.items);
        // The table now holds this frame's motion: the next frame writes its own.
        self.motion_written.set(transform);
        // The GPU image holds the incomplete attempt: the right frame replaces it (converted
        // on the host: FrameImage::rgba8, within one step of rgba8.wgsl).
        let rgba8 = g.image.rgba8();
        gpu.queue.write_buffer(self.target.rgba8(), 0, &rgba8);
        if self.recorded.is_some() {
            let mut size = self.size_from(&g.run).max(&self.wanted);
            if self.culling.is_some() {
                size = occlusion::grow(&why, &self.wanted, size);
            }
            if size != self.wanted {
                self.resize(gpu, size)?;
            }
        }
        let now = Instant::now();
        let wall_ms = now.duration_since(*last).as_secs_f64() * 1e3;
        *last = now;
        let rerun_ms = g.run.gpu_ms.zip(g.resolve_gpu_ms).map(|(a, b)| a + b);
        let gpu_ms = match attempt_ms {
            Some(a) => rerun_ms.map(|r| a + r),
            None => rerun_ms,
        };
        Ok(RealtimeFrame {
            transform,
            gpu_ms,
            wall_ms,
            counters: g.counters,
            rerendered: Some(why),
            rgba8: (self.pixels == Pixels::Rgba8).then_some(rgba8),
            image: (self.pixels == Pixels::Float).then(|| g.image.clone()),
            run: g.run,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shaders;

    /// One read-back buffer per source buffer, each sized for its pixels: 1 word a pixel for
    /// packed sRGB and depth, 4 for f32 RGBA.
    #[test]
    fn read_back_words_per_pixels_mode() {
        assert!(Pixels::None.read_back_words(6).is_empty());
        assert_eq!(Pixels::Rgba8.read_back_words(6), [6]);
        assert_eq!(Pixels::Float.read_back_words(6), [24, 6]);
    }

    #[test]
    fn orbit_matches_its_wgsl_layout() {
        let src = [shaders::PATCH_ITEM, shaders::ROOTS].concat();
        let l = scheduler::wgsl::struct_layout(&src, "Orbit").unwrap();
        // WGSL rounds the struct up to its 16-byte alignment (the mat4x4's).
        assert_eq!(l.size as usize, size_of::<Orbit>());
        for (field, off) in [
            ("m", std::mem::offset_of!(Orbit, m)),
            ("patches", std::mem::offset_of!(Orbit, patches)),
            ("row", std::mem::offset_of!(Orbit, row)),
            ("history", std::mem::offset_of!(Orbit, history)),
        ] {
            let got = l
                .members
                .iter()
                .find(|(n, _)| n == field)
                .map(|m| m.1 as usize);
            assert_eq!(got, Some(off), "Orbit.{field}");
        }
    }
}
