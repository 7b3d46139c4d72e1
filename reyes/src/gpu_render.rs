//! The Reyes pipeline on the scheduler: Bound, SplitU, SplitV and DiceShade (which samples its
//! own grid, so micropolygons never leave workgroup memory) registered as procedures, run by
//! either strategy, then a resolve pass from sub-samples to pixels.

use crate::buckets;
use crate::frame::{FrameData, FrameUniforms, PatchItem, SceneFeatures, Tile};
use crate::gpu::{FrameTarget, Pipelines, SceneBuffers, scene_layout_entries};
use crate::image::FrameImage;
use crate::progress::Progress;
use crate::shaders;
use crate::stages::hiz::{OCCLUSION_OFF, OCCLUSION_TEST, passes};
use crate::stages::{C_MAX_DEPTH, COUNTERS};
use scheduler::readback::{ReadRange, TimedReadback};
use scheduler::{
    Gpu, ItemType, MultipassConfig, Procedure, Program, RunError, RunStats, Scheduler, Seed,
    StrategyKind, UserBindings,
};
use std::time::Instant;

/// Procedure names, in registration order. The default queue policy gives the last the highest
/// priority: dice before split, which keeps the queues short.
pub const PROCEDURES: [&str; 5] = ["bound", "splitu", "splitv", "diceshade", "dicesmall"];

/// Workgroup steps per megakernel batch for Reyes frames on `gpu` (`MegakernelConfig::batch_steps`):
/// 2 on GPUs, where Killeroo at 1920x1080 ran 1.90 -> 1.76 ms (teapot 1.10 -> 1.13; docs/results.md,
/// 2026-12-02, "Two-step batches"); 1 on lavapipe, whose loop limiter counts a turn's body loops
/// against the persistent loop's budget (`scheduler::LAVAPIPE_MAX_ITERATIONS`).
pub fn megakernel_batch_steps(gpu: &Gpu) -> u32 {
    if gpu.is_lavapipe() { 1 } else { 2 }
}

/// Steps per megakernel batch of named Reyes procedures on `gpu`, overriding
/// [`megakernel_batch_steps`] for them (`MegakernelConfig::procedure_batch_steps`): on GPUs 8 for
/// DiceShade and DiceSmall, whose step holds one grid (four small ones), so that a turn's
/// scheduling is paid once per 8 grids; Bound and Split keep 2, which publishes their pieces
/// early (4 for Bound made Killeroo slower). H200, Killeroo at 1920x1080: 1.768 -> 1.675 ms,
/// teapot 1.150 -> 1.120 (docs/results.md, 2026-12-02, "Batch steps per procedure"). None on
/// lavapipe ([`megakernel_batch_steps`]).
pub fn megakernel_procedure_steps(gpu: &Gpu) -> Vec<(String, u32)> {
    if gpu.is_lavapipe() {
        return Vec::new();
    }
    vec![("diceshade".into(), 8), ("dicesmall".into(), 8)]
}

/// The Reyes megakernel's queue order on `gpu` (`QueuePolicy::Priority`): on GPUs breadth
/// first, Bound, SplitU, SplitV, then DiceShade and DiceSmall, so that every patch is bounded
/// and split while the dicing queues fill, and the frame's last splits are not left waiting
/// behind grids; with [`megakernel_guided_claims`] the H200 renders Killeroo at 1920x1080 in
/// 0.792 ms against 0.807 in the scheduler's default order (later stages first) without them,
/// the teapot in 0.529 against 0.568 (docs/results.md, 2026-12-04 (third session)). It costs
/// memory: the dicing queue holds up to 3.5x the grids at once (Killeroo: 10,600 against
/// 3,000), which could cost bucket recuts under a tight memory budget (none for Killeroo at
/// 1080p under 80 MiB). Empty (the default order) on lavapipe, whose one workgroup gains
/// nothing from the order.
pub fn megakernel_priority(gpu: &Gpu) -> Vec<String> {
    if gpu.is_lavapipe() {
        return Vec::new();
    }
    ["bound", "splitu", "splitv", "diceshade", "dicesmall"]
        .map(String::from)
        .to_vec()
}

/// Whether the Reyes megakernel's claims are guided (`MegakernelConfig::guided_claims`): on
/// GPUs, with [`megakernel_priority`]. A frame runs short of claimable work in its last
/// phase, and full batches of 8 grids then leave most workgroups idle while a few dice.
/// Off on lavapipe (one workgroup: its share is everything).
pub fn megakernel_guided_claims(gpu: &Gpu) -> bool {
    !gpu.is_lavapipe()
}

/// Device features the pipeline needs: 64-bit atomicMax for the depth-and-colour samples.
pub fn required_features() -> wgpu::Features {
    wgpu::Features::SHADER_INT64 | wgpu::Features::SHADER_INT64_ATOMIC_MIN_MAX
}

/// The Reyes program for any frame ([`program_for`] with every feature).
pub fn program() -> Result<Program, RunError> {
    program_for(SceneFeatures::ALL)
}

/// The Reyes program compiled for frames that need at most `features`: the code paths of the
/// others are constants the GPU compiler removes ([`SceneFeatures`]).
pub fn program_for(features: SceneFeatures) -> Result<Program, RunError> {
    let item = ItemType::new("PatchItem", shaders::PATCH_ITEM);
    let bound = Procedure::new("bound", item.clone(), 16)
        // Per patch: its projected control points and its net (bound.wgsl's first comment).
        .shared("vec4<f32>", 32)
        .emits("splitu", 1)
        .emits("splitv", 1)
        .emits("diceshade", 1)
        .emits("dicesmall", 1)
        // Bound and Split recurse on a patch's pieces within the workgroup while they fit
        // (Micropolis' local bound-and-split; docs/scheduler.md 2.7).
        .local("splitu")
        .local("splitv")
        .body(shaders::BOUND);
    let splitu = Procedure::new("splitu", item.clone(), 4)
        .emits("bound", 2)
        .local("bound")
        .body(shaders::SPLIT);
    // splitv_execute is defined in split.wgsl, given once as SplitU's body.
    let splitv = Procedure::new("splitv", item.clone(), 4)
        .emits("bound", 2)
        .local("bound")
        .body("");
    let diceshade = Procedure::new("diceshade", item.clone(), 256)
        // With SCENE_UVT the points at shutter close follow the open ones (sample_uvt.wgsl).
        .shared("vec4<f32>", if features.uvt { 512 } else { 256 })
        .body(shaders::DICE_SHADE);
    // DiceSmall runs diceshade_execute (dice_shade.wgsl) and shares diceshade_shared.
    let dicesmall = Procedure::new("dicesmall", item, 64).execute_of("diceshade");
    let user = UserBindings {
        wgsl: [
            &features.wgsl(),
            shaders::COMMON,
            shaders::SHADE,
            shaders::SURFACE,
            shaders::TRIM,
            shaders::SAMPLE,
            shaders::SAMPLE_UVT,
        ]
        .concat(),
        // 0-3 frame, materials, lights, patch info; 4-5 samples, counters; 6 primvars.
        layout: scene_layout_entries(),
    };
    Program::new(vec![bound, splitu, splitv, diceshade, dicesmall], user)
}

/// What one GPU frame produced and cost; with several buckets, run statistics are summed
/// (peaks are maxima).
pub struct GpuFrame {
    /// The resolved image.
    pub image: FrameImage,
    /// The stages' counters (`stages::C_*`), summed over the runs ([`crate::stages::C_MAX_DEPTH`]:
    /// the maximum).
    pub counters: [u64; COUNTERS],
    /// The scheduler's statistics, summed over the runs (peaks are maxima).
    pub run: RunStats,
    /// GPU time of the resolve passes, when timestamps exist.
    pub resolve_gpu_ms: Option<f64>,
    /// Bytes of the sample buffer (one bucket's).
    pub sample_bytes: u64,
    /// Screen buckets rendered.
    pub buckets: u32,
    /// Buckets cut in four after their queues overflowed.
    pub buckets_recut: u32,
    /// Scheduler runs that finished: one per bucket, more where a bucket's patches were split
    /// into batches.
    pub runs: u32,
    /// Batches split in two because their work did not fit.
    pub batches_split: u32,
    /// Largest working memory of one bucket: sample buffer plus queue storage.
    pub peak_working_bytes: u64,
    /// Host time of [`GpuRenderer::render`], milliseconds.
    pub wall_ms: f64,
}
/// Queue slots a renderer's scheduler starts with (queues grow by doubling beyond).
pub const INITIAL_CAPACITY: u32 = 1 << 14;

/// The megakernel's workgroup steps per claimed batch on lavapipe (1 elsewhere), its turns per
/// launch divided by as much (the same steps per launch under lavapipe's loop cut; 16 steps
/// per batch at 96 turns broke the queue accounting): on 20,000 small patches a turn's own cost
/// was about a step's, and 8 steps took 5.1 s of lavapipe time against 5.7 with 4 and 8.7 with
/// 1 (`schedbench --workload reyes --batch-steps N`, docs/results.md).
pub const LAVAPIPE_BATCH_STEPS: u32 = 8;

/// Most root patches one megakernel run takes on lavapipe (more go in as further batches, to
/// the same image): a launch there runs 96 workgroup steps, and each launch that leaves work
/// copies the live queues through the host (`compact::host_compact`), so 100,000 roots in one
/// run cost 652 launches, each copying up to 100,000 items (200,000 patches: 57 s of lavapipe
/// time, 34 s more of host time; docs/results.md).
pub const LAVAPIPE_MEGAKERNEL_SEEDS: usize = 4096;

/// How a [`GpuRenderer`] is built: the scheduling strategy, whether multi-pass times its
/// stages, the scene features the program is compiled for, and optionally a scheduler the
/// caller compiled itself. A bare [`StrategyKind`] converts into the default configuration.
pub struct RendererConfig {
    /// The scheduling strategy (ignored when [`RendererConfig::scheduler`] is given).
    pub strategy: StrategyKind,
    /// Multi-pass times each procedure's passes on their own (`RunStats::stage_gpu_ms`); the
    /// megakernel interleaves its stages in one launch, where only their sum can be timed.
    pub stage_timing: bool,
    /// What the program is compiled for ([`program_for`]): frames needing more are refused by
    /// [`GpuRenderer::render`]; e.g. [`FrameData::features`] of the frames to render, the
    /// fastest program for them. Default: [`SceneFeatures::ALL`].
    pub features: SceneFeatures,
    /// A scheduler compiled by the caller from [`program_for`]`(features)` with its own
    /// configuration (e.g. another queue policy; [`INITIAL_CAPACITY`] is the usual start).
    pub scheduler: Option<Scheduler>,
    /// On lavapipe, the megakernel's settings for frames rendered one by one
    /// ([`LAVAPIPE_BATCH_STEPS`], [`LAVAPIPE_MEGAKERNEL_SEEDS`]); default `true`. `false` for
    /// pipelined frames (`realtime`), whose recorded launches take their queue sizes from a
    /// frame rendered here and add a batch's worst case per workgroup: they keep one step per
    /// batch and all roots in one run, as the frames they size.
    pub lavapipe_tuning: bool,
}

impl RendererConfig {
    /// The default configuration of `strategy`: no stage timing, every feature, the
    /// renderer's own scheduler.
    pub fn new(strategy: StrategyKind) -> RendererConfig {
        RendererConfig {
            strategy,
            stage_timing: false,
            features: SceneFeatures::ALL,
            scheduler: None,
            lavapipe_tuning: true,
        }
    }

    /// With or without the lavapipe settings ([`RendererConfig::lavapipe_tuning`]).
    pub fn lavapipe_tuning(self, lavapipe_tuning: bool) -> RendererConfig {
        RendererConfig {
            lavapipe_tuning,
            ..self
        }
    }

    /// With `stage_timing` ([`RendererConfig::stage_timing`]).
    pub fn stage_timing(self, stage_timing: bool) -> RendererConfig {
        RendererConfig {
            stage_timing,
            ..self
        }
    }

    /// Compiled for frames that need at most `features` ([`RendererConfig::features`]).
    pub fn features(self, features: SceneFeatures) -> RendererConfig {
        RendererConfig { features, ..self }
    }

    /// On the caller's `scheduler`, compiled from [`program_for`]`(features)` for the
    /// configuration's features ([`RendererConfig::scheduler`]); the strategy becomes the
    /// scheduler's.
    pub fn scheduler(self, scheduler: Scheduler) -> RendererConfig {
        RendererConfig {
            strategy: scheduler.kind(),
            scheduler: Some(scheduler),
            ..self
        }
    }
}

impl From<StrategyKind> for RendererConfig {
    fn from(strategy: StrategyKind) -> RendererConfig {
        RendererConfig::new(strategy)
    }
}

/// The offline renderer: one frame at a time from host-made root items, on a scene uploaded
/// once and a target reused by every frame of one size.
pub struct GpuRenderer {
    /// The Reyes program the scheduler runs.
    pub program: Program,
    /// What the program was compiled for; frames needing more are refused.
    pub features: SceneFeatures,
    /// The strategy's scheduler.
    pub scheduler: Scheduler,
    pub(crate) pipelines: Pipelines,
    /// The last frame's scene tables and target: a frame of the same scene writes only what
    /// changed, a frame of the same size allocates nothing large (a 1080p frame's samples are
    /// 66 MB).
    resources: std::sync::Mutex<Option<(SceneBuffers, Option<FrameTarget>)>>,
    /// The mapped buffer a bucket's resolve time (and, after the last bucket, the image) comes
    /// back through: one submission and one wait, kept between frames.
    resolve_readback: std::sync::Mutex<Option<TimedReadback>>,
    /// [`RendererConfig::lavapipe_tuning`], on lavapipe only.
    lavapipe_tuning: bool,
}

/// Full GPU load before frames are timed (`scheduler::clocks::raise_clocks`): frames alone,
/// a few ms of GPU work between host read-backs, leave an H100 that has idled at its idle
/// clock.
pub const WARM_UP: std::time::Duration = std::time::Duration::from_millis(500);

/// Timed frames of one setting: the last frame, and each timed frame's GPU ms (scheduler
/// run plus resolve, when timestamps exist) and wall ms.
pub struct TimedFrames {
    /// The last timed frame.
    pub last: GpuFrame,
    /// Each timed frame's GPU ms, when timestamps exist.
    pub gpu_ms: Vec<Option<f64>>,
    /// Each timed frame's wall ms.
    pub wall_ms: Vec<f64>,
}

impl GpuRenderer {
    /// A renderer of `config` ([`RendererConfig`]; a bare [`StrategyKind`] is its default).
    /// Errors: a program or pipeline the device rejects.
    pub fn new(gpu: &Gpu, config: impl Into<RendererConfig>) -> Result<GpuRenderer, RunError> {
        let RendererConfig {
            strategy,
            stage_timing,
            features,
            scheduler,
            lavapipe_tuning,
        } = config.into();
        let lavapipe_tuning = lavapipe_tuning && gpu.is_lavapipe();
        let (program, scheduler) = match scheduler {
            Some(s) => (s.program().clone(), s),
            None => {
                let program = program_for(features)?;
                let tuned = (stage_timing, features, lavapipe_tuning);
                let s = Self::scheduler(gpu, &program, strategy, tuned)?;
                (program, s)
            }
        };
        let pipelines = Pipelines::new(gpu);
        pipelines.resolve(gpu)?;
        Ok(GpuRenderer {
            program,
            features,
            scheduler,
            pipelines,
            resources: Default::default(),
            resolve_readback: Default::default(),
            lavapipe_tuning,
        })
    }

    /// The strategy its scheduler runs.
    pub fn strategy(&self) -> StrategyKind {
        self.scheduler.kind()
    }

    /// The renderer's pipelines besides the scheduler's ([`Pipelines`]), for another renderer
    /// on the same device to share ([`RasterPeer::with_pipelines`](crate::raster_peer::RasterPeer::with_pipelines)).
    pub fn pipelines(&self) -> &Pipelines {
        &self.pipelines
    }

    /// The scheduler of `strategy` for `program`.
    fn scheduler(
        gpu: &Gpu,
        program: &Program,
        strategy: StrategyKind,
        (stage_timing, features, lavapipe_tuning): (bool, SceneFeatures, bool),
    ) -> Result<Scheduler, RunError> {
        Ok(match strategy {
            StrategyKind::Multipass => Scheduler::multipass(
                gpu,
                program,
                MultipassConfig {
                    initial_capacity: INITIAL_CAPACITY,
                    stage_timing,
                    ..Default::default()
                },
            )?,
            StrategyKind::MultipassHost | StrategyKind::MultipassFloor => {
                Scheduler::multipass_host(
                    gpu,
                    program,
                    scheduler::HostMultipassConfig {
                        initial_capacity: INITIAL_CAPACITY,
                        stage_timing,
                        replay_floor: strategy == StrategyKind::MultipassFloor,
                        ..Default::default()
                    },
                )?
            }
            // lavapipe ends every loop of an invocation after 65,535 iterations in total over
            // the persistent loop and what it nests; blurred micropolygons sample in loops that
            // grow with the blur, so there each launch runs one turn (the host relaunches).
            StrategyKind::Megakernel if features.uvt && gpu.is_lavapipe() => Scheduler::megakernel(
                gpu,
                program,
                scheduler::MegakernelConfig {
                    initial_capacity: INITIAL_CAPACITY,
                    max_iterations: 1,
                    ..Default::default()
                },
            )?,
            // lavapipe runs the megakernel's one workgroup on one thread, and each loop turn's
            // claim and publish (barriers: its invocations are coroutines switched there) cost
            // about as much as a step of work: several steps per batch, and proportionally
            // fewer turns per launch (the same work under the loop cut), halve the turns' cost
            // (docs/results.md, "The megakernel on lavapipe").
            StrategyKind::Megakernel if lavapipe_tuning => Scheduler::megakernel(
                gpu,
                program,
                scheduler::MegakernelConfig {
                    initial_capacity: INITIAL_CAPACITY,
                    batch_steps: LAVAPIPE_BATCH_STEPS,
                    max_iterations: scheduler::megakernel::LAVAPIPE_MAX_ITERATIONS
                        / LAVAPIPE_BATCH_STEPS,
                    ..Default::default()
                },
            )?,
            StrategyKind::Megakernel => Scheduler::megakernel(
                gpu,
                program,
                scheduler::MegakernelConfig {
                    initial_capacity: INITIAL_CAPACITY,
                    batch_steps: megakernel_batch_steps(gpu),
                    procedure_batch_steps: megakernel_procedure_steps(gpu),
                    policy: scheduler::QueuePolicy::Priority(megakernel_priority(gpu)),
                    guided_claims: megakernel_guided_claims(gpu),
                    ..Default::default()
                },
            )?,
        })
    }

    /// Renders a frame; under `data.memory_budget` in screen buckets (see [`crate::buckets`]).
    /// The scene's tables are uploaded by the first frame and rewritten only where a later
    /// frame's differ; the target is reused while the size stays. Errors: a frame needing
    /// features the program was not compiled for ([`RunError::Program`]), and those of a run.
    pub fn render(&self, gpu: &Gpu, data: &FrameData) -> Result<GpuFrame, RunError> {
        let f = &data.frame;
        let mut todo = buckets::plan(f, data.memory_budget);
        let largest = todo.iter().map(|t| t.w as u64 * t.h as u64).max().unwrap();
        todo.reverse();
        let (frame, _) = self.render_tiles(gpu, data, largest, &mut || todo.pop(), false)?;
        Ok(frame)
    }

    /// Renders the buckets that `next` hands out, one at a time until it returns `None`, on
    /// the renderer's cached scene and target (as [`GpuRenderer::render`]); `largest`: pixels
    /// of the largest bucket `next` may give, for the sample buffer. A bucket `next` gives
    /// renders as a bucket of [`GpuRenderer::render`] does (patches that cannot reach it left
    /// out on the host, recut in four under a memory budget when its queues overflow), so
    /// each of its pixels is bit for bit the whole frame's. With `tiles_only`, the returned
    /// frame's image is left empty and the buckets come back with their pixels, read from
    /// the device (for [`crate::devices`], which assembles them); else the whole image is
    /// read back and the list is empty. Errors: as [`GpuRenderer::render`].
    pub fn render_tiles(
        &self,
        gpu: &Gpu,
        data: &FrameData,
        largest: u64,
        next: &mut dyn FnMut() -> Option<Tile>,
        tiles_only: bool,
    ) -> Result<(GpuFrame, Vec<TilePixels>), RunError> {
        self.check_features(data)?;
        let start = Instant::now();
        let f = &data.frame;
        let mut cache = self.resources.lock().unwrap();
        match cache.as_mut() {
            Some((scene, _)) => scene.update(gpu, data)?,
            None => *cache = Some((SceneBuffers::new(gpu, data)?, None)),
        }
        let (scene, target) = cache.as_mut().unwrap();
        let pixels = f.width as u64 * f.height as u64;
        let size = (largest * buckets::sample_bytes_per_pixel(f) / 4, pixels);
        if target.as_ref().is_none_or(|t| t.size() != size) {
            // The old buffers go before the new ones are made.
            scene.forget_bind_group();
            *target = None;
            *target = Some(FrameTarget::new(gpu, size.0, size.1, false)?);
        }
        let target = target.as_ref().unwrap();
        let bind = scene.bind_group(gpu, self.pipelines.scene_layout(), target);
        // A bucket beyond the sample buffer is the caller's error, refused before it renders.
        let mut checked = || match next() {
            Some(t) if t.w as u64 * t.h as u64 > largest => Some(Err(t)),
            t => t.map(Ok),
        };
        let mut too_large = None;
        let mut next = || match checked()? {
            Ok(t) => Some(t),
            Err(t) => {
                too_large = Some(t);
                None
            }
        };
        let r = self.render_buckets_on(
            gpu,
            (scene, target, &bind),
            (data, largest),
            start,
            &mut next,
            tiles_only,
        )?;
        if let Some(t) = too_large {
            return Err(RunError::Program(format!(
                "a {}x{} px bucket is larger than the {largest} pixels the sample buffer was \
                 sized for",
                t.w, t.h
            )));
        }
        Ok(r)
    }

    /// Refuses a frame that needs features the program was not compiled for.
    fn check_features(&self, data: &FrameData) -> Result<(), RunError> {
        let need = data.features();
        if !self.features.covers(need) {
            return Err(RunError::Program(format!(
                "the frame needs {need:?}; this renderer was compiled for {:?}",
                self.features
            )));
        }
        Ok(())
    }

    /// Renders `data` on `scene` (whose tables hold `data`'s) into `target` (large enough for
    /// `data`'s largest bucket), `bind` being their scene bind group: the core of every frame
    /// rendered from host-made root items. `start`: when the frame's wall time began.
    pub(crate) fn render_on(
        &self,
        gpu: &Gpu,
        scene: &SceneBuffers,
        target: &FrameTarget,
        bind: &wgpu::BindGroup,
        data: &FrameData,
        start: Instant,
    ) -> Result<GpuFrame, RunError> {
        let mut todo = buckets::plan(&data.frame, data.memory_budget);
        let largest = todo.iter().map(|t| t.w as u64 * t.h as u64).max().unwrap();
        todo.reverse();
        let (frame, _) = self.render_buckets_on(
            gpu,
            (scene, target, bind),
            (data, largest),
            start,
            &mut || todo.pop(),
            false,
        )?;
        Ok(frame)
    }

    /// The core of [`GpuRenderer::render_on`] and [`GpuRenderer::render_tiles`]: the buckets
    /// `next` gives (and their quarters, when recut), rendered one after another.
    fn render_buckets_on(
        &self,
        gpu: &Gpu,
        (scene, target, bind): (&SceneBuffers, &FrameTarget, &wgpu::BindGroup),
        (data, largest): (&FrameData, u64),
        start: Instant,
        next: &mut dyn FnMut() -> Option<Tile>,
        tiles_only: bool,
    ) -> Result<(GpuFrame, Vec<TilePixels>), RunError> {
        self.check_features(data)?;
        let f = &data.frame;
        let whole = f.whole_image();
        let per_pixel = buckets::sample_bytes_per_pixel(f);
        let pixels = f.width as u64 * f.height as u64;
        // Quarters of recut buckets, rendered before the next bucket of `next`.
        let mut todo: Vec<Tile> = Vec::new();
        let mut done: Vec<Tile> = Vec::new();
        let FrameTarget {
            samples,
            counters,
            rgba,
            depth,
            hiz,
            ..
        } = target;
        let mut out = GpuFrame {
            image: FrameImage::default(),
            counters: [0; COUNTERS],
            run: RunStats::default(),
            resolve_gpu_ms: Some(0.0),
            sample_bytes: largest * per_pixel,
            buckets: 0,
            buckets_recut: 0,
            runs: 0,
            batches_split: 0,
            peak_working_bytes: 0,
            wall_ms: 0.0,
        };
        // The whole image comes back with the last bucket's resolve: one submission, one wait.
        let image: [ReadRange; 2] = [(rgba, 0, pixels * 4), (depth, 0, pixels)];
        let image = match tiles_only {
            true => &image[..0],
            false => &image[..],
        };
        let kept = self.resolve_readback.lock().unwrap().take();
        let rb = TimedReadback::reuse(kept, gpu, "resolve read-back", 0, image);
        // The last bucket's resolve, recorded, submitted before anything else touches the
        // samples (the next bucket's clear) or after the last bucket with the image's copy
        // (one submission and one wait for both).
        let mut resolving: Option<wgpu::CommandEncoder> = None;
        let add_resolve = |ms: Option<f64>, out: &mut GpuFrame| {
            out.resolve_gpu_ms = out.resolve_gpu_ms.zip(ms).map(|(a, b)| a + b);
        };
        while let Some(tile) = todo.pop().or_else(&mut *next) {
            if let Some(enc) = resolving.take() {
                let (ms, _) = self.finish_resolve(gpu, enc, &rb, &[])?;
                add_resolve(ms, &mut out);
            }
            let tile_frame = f.with_tile(tile);
            // A bucket smaller than the image (under a budget, or one of several devices'
            // buckets) renders only the patches that may reach it.
            let items: std::borrow::Cow<[PatchItem]> = match tile == whole {
                true => (&data.items[..]).into(),
                false => (data.items.iter())
                    .filter(|i| {
                        let info = &data.patch_info[i.patch_id as usize];
                        let w = crate::stages::item_weights(i, info, &data.primvars);
                        buckets::may_reach(f, i, w.as_ref(), tile)
                    })
                    .copied()
                    .collect(),
            };
            // Occlusion culling (stages::hiz::passes): the nearest items first, then the rest
            // in passes front to back, each tested against the depth pyramid of all drawn.
            let (items, starts) = match f.occlusion != OCCLUSION_OFF {
                true => {
                    let (ordered, starts) = passes(data, &items, tile);
                    (ordered.into(), starts)
                }
                false => (items, vec![0]),
            };
            let first = starts.get(1).copied().unwrap_or(usize::MAX);
            let tile_sample_bytes = tile.w as u64 * tile.h as u64 * per_pixel;
            let queue_budget = data
                .memory_budget
                .map(|b| b.saturating_sub(tile_sample_bytes));
            scene.write_frame(gpu, &tile_frame);
            let mut enc = gpu.device.create_command_encoder(&Default::default());
            enc.clear_buffer(samples, 0, Some(tile_sample_bytes));
            gpu.submit(enc);
            // Each pass's patches go in as one batch; a batch whose work does not fit the
            // queues is halved and each half run on its own. Samples keep the nearest key
            // (atomicMax), so batches, in any order and even a refused batch's partial work run
            // again, give the same image bit for bit; counters are read per finished batch.
            // One batch per pass (one without occlusion culling), the first on top.
            // On lavapipe the megakernel's batches are at most LAVAPIPE_MEGAKERNEL_SEEDS
            // roots: each of its (short) launches compacts the live queues on the host.
            let chunk =
                match self.lavapipe_tuning && self.scheduler.kind() == StrategyKind::Megakernel {
                    true => LAVAPIPE_MEGAKERNEL_SEEDS,
                    false => usize::MAX,
                };
            let mut batches: Vec<std::ops::Range<usize>> = (starts.iter().enumerate())
                .rev()
                .map(|(k, &s)| s..starts.get(k + 1).copied().unwrap_or(items.len()))
                .flat_map(|r| match r.len() > chunk {
                    true => (r.clone().step_by(chunk).rev())
                        .map(|a| a..(a + chunk).min(r.end))
                        .collect(),
                    false => vec![r],
                })
                .collect();
            let mut recut = false;
            while let Some(batch) = batches.pop() {
                let mut enc = gpu.device.create_command_encoder(&Default::default());
                enc.clear_buffer(counters, 0, None);
                // A batch after the first pass: the pyramid of everything drawn so far, and the
                // test in Bound. (Halves of a batch stay ahead of later passes on the stack.)
                if batch.start >= first {
                    let test = FrameUniforms {
                        occlusion: OCCLUSION_TEST,
                        ..tile_frame
                    };
                    let hiz_passes = self.pipelines.hiz(gpu)?;
                    if hiz_passes.record(gpu, &mut enc, &tile_frame, samples, hiz, pixels)? {
                        scene.write_frame(gpu, &test);
                    }
                }
                gpu.submit(enc);
                let seeds = [Seed::new::<PatchItem>("bound", &items[batch.clone()])];
                // The counters come back with the run's last read-back.
                let reads = [(counters, 0, COUNTERS as u64)];
                let (run, mut counted) = match self.scheduler.run_reading(
                    gpu,
                    &seeds,
                    Some(bind),
                    queue_budget,
                    &reads,
                ) {
                    Err(RunError::QueueOverflow { .. }) if batch.len() > 1 => {
                        let mid = batch.start + batch.len() / 2;
                        batches.push(mid..batch.end);
                        batches.push(batch.start..mid);
                        out.batches_split += 1;
                        continue;
                    }
                    Err(RunError::QueueOverflow {
                        queue,
                        capacity,
                        needed_more_than,
                    }) if data.memory_budget.is_some() => {
                        if let Some(quarters) = buckets::quarter(tile) {
                            out.buckets_recut += 1;
                            todo.extend(quarters.into_iter().rev());
                            recut = true;
                            break;
                        }
                        return Err(RunError::QueueOverflow {
                            queue: format!(
                                "{queue} (one patch in a {}x{} px bucket at ({}, {}), the smallest, under a memory budget of {} bytes)",
                                tile.w,
                                tile.h,
                                tile.x0,
                                tile.y0,
                                data.memory_budget.unwrap()
                            ),
                            capacity,
                            needed_more_than,
                        });
                    }
                    r => r?,
                };
                let counted = counted.pop().expect("the counters' range");
                for (k, v) in counted.into_iter().enumerate() {
                    if k == C_MAX_DEPTH {
                        out.counters[k] = out.counters[k].max(v as u64);
                    } else {
                        out.counters[k] += v as u64;
                    }
                }
                out.peak_working_bytes = out
                    .peak_working_bytes
                    .max(tile_sample_bytes + run.queue_bytes);
                if out.runs == 0 {
                    out.run = run;
                } else {
                    out.run.absorb(&run);
                }
                out.runs += 1;
            }
            if recut {
                continue;
            }
            let enc = self.record_resolve(
                gpu,
                (&tile_frame, data.background),
                (samples, rgba, depth),
                &rb,
            )?;
            // Buckets handed out by the caller (several devices) resolve at once, so that a
            // failure belongs to the bucket the caller last gave; a frame's wait until the next
            // bucket, or the image's read.
            match tiles_only {
                true => add_resolve(self.finish_resolve(gpu, enc, &rb, &[])?.0, &mut out),
                false => resolving = Some(enc),
            }
            out.buckets += 1;
            done.push(tile);
        }
        let mut read = match resolving {
            Some(enc) => {
                let (ms, read) = self.finish_resolve(gpu, enc, &rb, image)?;
                add_resolve(ms, &mut out);
                read
            }
            // No bucket: the image as it stands.
            None => scheduler::readback::read_ranges(gpu, image)?,
        };
        *self.resolve_readback.lock().unwrap() = Some(rb);
        if tiles_only {
            let tiles = (done.into_iter())
                .map(|t| TilePixels::read(gpu, f.width, t, rgba, depth))
                .collect::<Result<_, _>>()?;
            out.wall_ms = start.elapsed().as_secs_f64() * 1e3;
            return Ok((out, tiles));
        }
        let z = read.pop().expect("the depth range");
        let words = read.pop().expect("the colour range");
        let floats: &[f32] = bytemuck::cast_slice(&words);
        out.image = FrameImage {
            width: f.width,
            height: f.height,
            rgba: floats.chunks(4).map(|c| [c[0], c[1], c[2], c[3]]).collect(),
            depth: z.into_iter().map(f32::from_bits).collect(),
        };
        out.wall_ms = start.elapsed().as_secs_f64() * 1e3;
        Ok((out, Vec::new()))
    }

    /// Renders one frame (it compiles pipelines and sizes the queues), raises the GPU's clocks
    /// for [`WARM_UP`], renders one more frame, then `runs` frames back to back, timing each,
    /// raising the clocks again between them where the frames' host work has left the GPU idle
    /// long enough for them to fall (`scheduler::clocks::ClockKeeper`); `progress` advances by
    /// one after each timed frame.
    pub fn timed_frames(
        &self,
        gpu: &Gpu,
        data: &FrameData,
        runs: u32,
        progress: &dyn Progress,
    ) -> Result<TimedFrames, RunError> {
        self.render(gpu, data)?;
        let mut keeper = scheduler::clocks::ClockKeeper::new(gpu, WARM_UP)?;
        let mut last = self.render(gpu, data)?;
        let (mut gpu_ms, mut wall_ms) = (Vec::new(), Vec::new());
        for _ in 0..runs.max(1) {
            keeper.keep_up()?;
            last = self.render(gpu, data)?;
            gpu_ms.push(last.run.gpu_ms.zip(last.resolve_gpu_ms).map(|(a, b)| a + b));
            wall_ms.push(last.wall_ms);
            progress.advance(1);
        }
        Ok(TimedFrames {
            last,
            gpu_ms,
            wall_ms,
        })
    }

    /// Records the resolve of bucket `f` (`samples` into its pixels of `rgba` and `depth`) in an
    /// encoder of its own, its pass timed by `rb`; [`GpuRenderer::finish_resolve`] submits it.
    fn record_resolve(
        &self,
        gpu: &Gpu,
        (f, background): (&FrameUniforms, Option<[f32; 3]>),
        (samples, rgba, depth): (&wgpu::Buffer, &wgpu::Buffer, &wgpu::Buffer),
        rb: &TimedReadback,
    ) -> Result<wgpu::CommandEncoder, RunError> {
        let (params, (gx, gy)) = resolve_params(f, background);
        let params_buf = gpu.storage_buffer("resolve params", params.len() as u64)?;
        gpu.queue
            .write_buffer(&params_buf, 0, bytemuck::cast_slice(&params));
        let resolve = self.pipelines.resolve(gpu)?;
        let layout = resolve.get_bind_group_layout(0);
        let bind = gpu.bind_buffers("resolve", &layout, &[&params_buf, samples, rgba, depth]);
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        {
            let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("resolve"),
                timestamp_writes: rb.pass_writes(),
            });
            pass.set_pipeline(resolve);
            pass.set_bind_group(0, &bind, &[]);
            pass.dispatch_workgroups(gx, gy, 1);
        }
        Ok(enc)
    }

    /// Submits a resolve [`GpuRenderer::record_resolve`] recorded, with `ranges` copied after
    /// it, and waits once: the resolve's GPU ms (`None` without timestamps) and the ranges.
    fn finish_resolve(
        &self,
        gpu: &Gpu,
        mut enc: wgpu::CommandEncoder,
        rb: &TimedReadback,
        ranges: &[ReadRange],
    ) -> Result<(Option<f64>, Vec<Vec<u32>>), RunError> {
        rb.copy(&mut enc, None, true, ranges);
        gpu.submit(enc);
        let words = rb.read(gpu, ranges)?;
        let mut ms = gpu.timestamps.then_some(0.0);
        rb.add_ms(&words, &mut ms);
        Ok((ms, rb.ranges(&words, ranges)))
    }
}

/// Workgroups of a 1D pass of `threads` threads, `per_group` per workgroup, as a 2D dispatch
/// (at most 32,768 groups per row, within every adapter's 65,535): `(x, y)` and the threads per
/// row the shader multiplies its y index by.
pub(crate) fn dispatch_2d(threads: u64, per_group: u32) -> ((u32, u32), u32) {
    let groups = threads.div_ceil(per_group as u64);
    let gx = groups.min(32768) as u32;
    let gy = groups.div_ceil(32768) as u32;
    ((gx, gy), gx * per_group)
}

/// The resolve pass's parameters for the bucket of `f` (`ResolveParams` in resolve.wgsl), with
/// the background imager's colour when there is one ([`FrameData::background`]), and its
/// dispatch size.
pub(crate) fn resolve_params(
    f: &FrameUniforms,
    background: Option<[f32; 3]>,
) -> ([u32; 12], (u32, u32)) {
    let pixels = f.tile_w as u64 * f.tile_h as u64;
    let ((gx, gy), row) = dispatch_2d(pixels, 256);
    let bg = background.unwrap_or([0.0; 3]);
    let params = [
        f.tile_w,
        f.tile_h,
        f.spp_x * f.spp_y,
        row,
        f.width,
        f.tile_x0,
        f.tile_y0,
        background.is_some() as u32,
        bg[0].to_bits(),
        bg[1].to_bits(),
        bg[2].to_bits(),
        0,
    ];
    (params, (gx, gy))
}

/// One bucket's resolved pixels, read from a device ([`GpuRenderer::render_tiles`]).
pub struct TilePixels {
    /// The bucket.
    pub tile: Tile,
    /// Its linear RGBA, row by row (`tile.w * tile.h`).
    pub rgba: Vec<[f32; 4]>,
    /// Its depth, row by row.
    pub depth: Vec<f32>,
}

impl TilePixels {
    /// Reads `tile`'s pixels from the image buffers of a frame `width` pixels wide: the
    /// rows it spans, whole (one read each for colour and depth), of which its columns are
    /// kept.
    fn read(
        gpu: &Gpu,
        width: u32,
        tile: Tile,
        rgba: &wgpu::Buffer,
        depth: &wgpu::Buffer,
    ) -> Result<TilePixels, RunError> {
        let (row0, rows) = (tile.y0 as u64 * width as u64, tile.h as u64 * width as u64);
        let words = gpu.read_words(rgba, row0 * 4, rows * 4)?;
        let z = gpu.read_words(depth, row0, rows)?;
        let floats: &[f32] = bytemuck::cast_slice(&words);
        let cols = tile.x0 as usize..(tile.x0 + tile.w) as usize;
        let (mut c, mut d) = (Vec::new(), Vec::new());
        for y in 0..tile.h as usize {
            let row = y * width as usize;
            for x in cols.clone() {
                let p = &floats[(row + x) * 4..(row + x) * 4 + 4];
                c.push([p[0], p[1], p[2], p[3]]);
                d.push(f32::from_bits(z[row + x]));
            }
        }
        Ok(TilePixels {
            tile,
            rgba: c,
            depth: d,
        })
    }
}
