//! The command line (clap derive): subcommands, flags, defaults, units and ranges. Usage errors
//! (an unknown flag, a value out of range, options that conflict) exit with status 2 and name
//! the flag; `--help` and `--version` print to stdout and exit 0. Errors found later (a bad
//! scene file, a GPU error, a setting the renderer cannot make) are the subcommands' own and
//! exit 1.

use crate::error::CliError;
use clap::{Args, Parser, Subcommand, ValueEnum, value_parser};
use reyes::devices::DeviceSelection;
use reyes::frame::{DisplacementNormals, RasterMode, RenderOptions, Sampling};
use reyes::scene::{DepthOfField, FrameRanges, Scene};
use reyes_accuracy::drift::PathOptions;
use reyes_accuracy::exact_image::DEFAULT_SAMPLES_PER_AXIS;
use scheduler::StrategyKind;
use std::path::PathBuf;

const SEQUENCES: &str = "Frame sequences: a RIB file of several frames writes each frame's \
Display name into -o's folder, or -o NAME.####.png or NAME.%04d.png (the frame number, \
zero-padded; %d unpadded; also for --stats, --float, --depth, --exr, which need a pattern when \
several frames are rendered). Frames are read and rendered one at a time. With --frames or \
--frame, a frame whose outputs all exist is skipped (--overwrite renders it again), and a \
frame that fails is named and the others still render; exit status 0: every selected frame \
done, 1: some frame failed, 2: usage.";

/// Renders RenderMan RIB, Newell and BPT scenes with the Reyes pipeline on the scheduler, and
/// measures the result against the exact surfaces.
#[derive(Debug, Parser)]
#[command(name = "reyes", version, arg_required_else_help = true)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

/// Each takes negative numbers as values (`--height -3` is a bad height, not a flag `-3`), and a
/// flag given twice takes its last value (as the hand-written parser did).
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Render a scene to PNG (the built-in teapot without a file).
    #[command(after_help = SEQUENCES, allow_negative_numbers = true, args_override_self = true)]
    Render(RenderCmd),
    /// A frame's geometric and image error against the exact surfaces (GPU render), printed
    /// as a table or JSON.
    #[command(allow_negative_numbers = true, args_override_self = true)]
    Measure(MeasureCmd),
    /// Holes of a frame (GPU render, --raster mode) against a reference coverage: pixels and
    /// sub-samples left empty where the exact surfaces (or a bbox render) cover the pixel and
    /// its 8 neighbours; one table row or JSON.
    #[command(after_help = HOLES_ROW, allow_negative_numbers = true, args_override_self = true)]
    Holes(HolesCmd),
    /// Speed against error over quality settings: writes sweep.csv, sweep.md, sweep.png and sweep.svg.
    #[command(allow_negative_numbers = true, args_override_self = true)]
    Sweep(SweepCmd),
    /// f32 split drift against f64 over 0-24 split levels, in pixels (CPU).
    #[command(allow_negative_numbers = true, args_override_self = true)]
    Drift(DriftCmd),
    /// Time frames of a scene (turning about its centre with --turntable), pipelined on the GPU:
    /// per-frame wall and GPU ms (median, p95) and frames per second, as a table or JSON.
    #[command(allow_negative_numbers = true, args_override_self = true)]
    Bench(BenchCmd),
    /// Open a window on a scene: orbit, pan and zoom with the mouse, keys for strategy and
    /// quality, frame times in the title, S saves a screenshot (`reyes view --help` lists the controls).
    #[command(after_help = VIEW_CONTROLS, allow_negative_numbers = true, args_override_self = true)]
    View(ViewCmd),
    /// List the adapters wgpu finds (WGPU_BACKEND narrows the backends), each with the index
    /// that --devices takes, and whether it can render (64-bit atomic min/max) or is skipped.
    Devices,
}

const VIEW_CONTROLS: &str = "Controls: left drag orbits about the scene's centre; right or \
middle drag pans; the wheel zooms (dollies towards the centre); M cycles the strategy \
(megakernel, multipass, multipass-host); O cycles --occlusion (auto, on, off); [ and ] divide and multiply the micropolygon size \
by sqrt 2; 1-4 set NxN pixel samples, + and - add or remove one per axis; R resets the camera; \
S saves a screenshot PNG; Esc or Q quits. A held key acts once, except [ ] + = - which \
keep stepping. The title shows frames per second, wall and GPU \
milliseconds, micropolygons, pieces culled by occlusion (or no culling), the strategy, \
micropolygon size and samples.";

impl Command {
    /// The subcommand's name, for error messages.
    pub fn name(&self) -> &'static str {
        match self {
            Command::Render(_) => "render",
            Command::Measure(_) => "measure",
            Command::Holes(_) => "holes",
            Command::Sweep(_) => "sweep",
            Command::Drift(_) => "drift",
            Command::Bench(_) => "bench",
            Command::View(_) => "view",
            Command::Devices => "devices",
        }
    }

    /// The frame options of subcommands that render one.
    fn render_args(&self) -> Option<&RenderArgs> {
        match self {
            Command::Render(c) => Some(&c.render),
            Command::Measure(c) => Some(&c.render),
            Command::Holes(c) => Some(&c.render),
            Command::Bench(c) => Some(&c.render),
            Command::View(c) => Some(&c.render),
            Command::Sweep(_) | Command::Drift(_) | Command::Devices => None,
        }
    }

    /// Conflicts between options that clap's attributes cannot express, as usage errors (exit
    /// 2, like clap's own): `--raster nearest` samples no motion or lens, so it cannot go with
    /// `--spin` or `--dof`. (A scene file's own motion with `--raster nearest` is refused when
    /// the scene is read, naming the flag.)
    pub fn check_conflicts(&self) -> Result<(), CliError> {
        if let Some(r) = self.render_args()
            && r.raster == Raster::Nearest
            && (r.spin.is_some() || r.dof.is_some())
        {
            let flag = if r.spin.is_some() { "--spin" } else { "--dof" };
            return Err(CliError::Conflict { flag });
        }
        if let Some(r) = self.render_args()
            && r.strategy == Some(StrategyKind::MultipassFloor)
            && matches!(self, Command::Bench(_) | Command::View(_))
        {
            return Err(CliError::FloorNotHere {
                command: self.name(),
            });
        }
        Ok(())
    }
}

/// The options of one rendered frame, shared by `render` and `measure`.
#[derive(Debug, Clone, Args)]
pub struct RenderArgs {
    /// Image width in pixels [default: the scene's Format].
    #[arg(long, value_name = "PX", value_parser = value_parser!(u32).range(1..=MAX_SIDE))]
    pub width: Option<u32>,

    /// Image height in pixels [default: the scene's Format].
    #[arg(long, value_name = "PX", value_parser = value_parser!(u32).range(1..=MAX_SIDE))]
    pub height: Option<u32>,

    /// Pixel samples per axis: N (NxN) or NxM, each 1..=16 [default: the scene's PixelSamples].
    #[arg(long, value_name = "N|NxM", value_parser = parse_samples)]
    pub samples: Option<(u32, u32)>,

    /// Target micropolygon edge in pixels (RenderMan's shading rate is its square).
    #[arg(long, value_name = "PX", default_value_t = RenderOptions::default().mp_size,
          value_parser = positive_f32)]
    pub mp_size: f32,

    /// Dice by Patney & Owens' fixed rule instead: split to this screen bound in pixels, then
    /// dice 16x16 [default: off, adaptive dicing to --mp-size].
    #[arg(long, value_name = "PX", value_parser = positive_f32)]
    pub bound_px: Option<f32>,

    /// Most split levels of a patch.
    #[arg(long, value_name = "N", default_value_t = RenderOptions::default().max_depth)]
    pub max_depth: u32,

    /// Working memory (sample buffer plus queues) a frame may use, in bytes with an optional
    /// binary suffix K, M or G (64K, 16M, 1G); beyond it the frame renders in screen buckets
    /// [default: no limit, one bucket].
    #[arg(long, value_name = "BYTES[K|M|G]", value_parser = parse_bytes)]
    pub memory_budget: Option<u64>,

    /// Do not grow micropolygons to close cracks (for comparisons only).
    #[arg(long)]
    pub no_crack_dilation: bool,

    /// The normal displaced patches move along: exact (from the patch's derivatives) or
    /// approximate (the grid's finite differences, which leave holes; for comparisons only).
    #[arg(long, value_enum, value_name = "NORMALS", default_value_t = Normals::Exact)]
    pub displacement_normals: Normals,

    /// Micropolygon rasterization: bbox (every sub-sample under its screen bound, tested
    /// against its two triangles) or nearest (only the sub-sample nearest its centre, the
    /// paper's naive mode: leaves holes where micropolygons outgrow the sample spacing).
    #[arg(long, value_name = "MODE", value_enum, default_value_t = Raster::Bbox)]
    pub raster: Raster,

    /// GPU strategy: megakernel, multipass or multipass-host [default: megakernel; multipass
    /// on a CPU adapter such as lavapipe, where it is several times faster]; or
    /// multipass-floor, a reference for `render` and `measure` (bench and view refuse it): an
    /// untimed host-driven frame keeps every item it executed, and each timed frame replays
    /// them in one round, one dispatch per procedure (the bodies' work without the rounds'
    /// cost; docs/scheduler.md 5.4).
    #[arg(long, value_name = "NAME", value_parser = parse_strategy)]
    pub strategy: Option<StrategyKind>,

    /// How motion blur and depth of field sample time and the lens (each pixel's --samples
    /// sub-samples get one (lens, time) sample each): simple (Simple UVT: the same samples in
    /// every pixel; ghosts when few), interleave (Interleave UVT: KxK pixel tiles share K^2
    /// times as many, permuted per tile; noise instead) or bbox (Bounding box, the default:
    /// per-pixel samples, stratified in time, from a repeated 64x64 table, each tested at its
    /// own time against the micropolygon's bound over its time stratum; noise instead of
    /// ghosts). Scenes without motion or depth of field ignore it.
    #[arg(long, value_name = "ALGORITHM", value_enum, default_value_t = SamplingArg::BoundingBox)]
    pub sampling: SamplingArg,

    /// Interleave UVT's tile side K in pixels: 2, 3 or 4.
    #[arg(long, value_name = "K", default_value_t = RenderOptions::default().il_tile,
          value_parser = value_parser!(u32).range(2..=4))]
    pub il_tile: u32,

    /// Interleave UVT's number of sample permutations the tiles choose from (1..=1024).
    #[arg(long, value_name = "P", default_value_t = RenderOptions::default().il_perms,
          value_parser = value_parser!(u32).range(1..=1024))]
    pub il_perms: u32,

    /// Spin the scene by DEG degrees over the shutter about the world's z axis through the
    /// centre of its bound (motion blur without editing the file; composed with the file's
    /// own motion).
    #[arg(long, value_name = "DEG", value_parser = finite_f64)]
    pub spin: Option<f64>,

    /// Occlusion culling in Bound: pieces hidden behind what is already drawn (a depth
    /// pyramid of the samples after a first pass over the nearest patches; in `bench` and
    /// `view`, over the patches seen in the previous frame) are not split or diced. The image
    /// is the same in every mode. `auto`: passes only in buckets (bench, view: frames) whose
    /// patches lie about 4 deep or more over the screen they reach (each pass costs a
    /// scheduler run); `on`: always; `off`: never.
    #[arg(long, value_name = "AUTO|ON|OFF", value_enum, default_value_t = OcclusionArg::Auto)]
    pub occlusion: OcclusionArg,

    /// Depth of field: RenderMan's `DepthOfField fstop focallength focaldistance` (lengths in
    /// camera-space units), replacing the file's.
    #[arg(long, value_name = "FSTOP,FOCALLENGTH,DIST", value_parser = parse_dof)]
    pub dof: Option<DepthOfField>,
}

impl RenderArgs {
    /// The strategy to run on `gpu`: the one asked for; else the megakernel, except on a CPU
    /// adapter (lavapipe), where its persistent workgroups run one at a time and the
    /// device-driven multi-pass renders the teapot several times faster (README, "Without a
    /// GPU"). A default chosen for the adapter is said on stderr, with how to override it.
    pub fn strategy_for(&self, gpu: &scheduler::Gpu) -> StrategyKind {
        if let Some(s) = self.strategy {
            return s;
        }
        if gpu.is_cpu_adapter() {
            eprintln!(
                "note: strategy multipass, the default on a CPU adapter ({}): the megakernel's \
                 persistent workgroups do not run side by side there (--strategy megakernel to \
                 use it anyway)",
                gpu.adapter_name()
            );
            return StrategyKind::Multipass;
        }
        StrategyKind::Megakernel
    }

    /// The renderer's options (the others at their defaults).
    pub fn options(&self) -> RenderOptions {
        RenderOptions {
            width: self.width,
            height: self.height,
            pixel_samples: self.samples,
            mp_size: self.mp_size,
            bound_px: self.bound_px,
            max_depth: self.max_depth,
            memory_budget: self.memory_budget,
            crack_dilation: !self.no_crack_dilation,
            displacement_normals: self.displacement_normals.into(),
            raster: self.raster.mode(),
            sampling: self.sampling.into(),
            il_tile: self.il_tile,
            il_perms: self.il_perms,
            occlusion: match self.occlusion {
                OcclusionArg::Auto => reyes::frame::Occlusion::Auto,
                OcclusionArg::On => reyes::frame::Occlusion::On,
                OcclusionArg::Off => reyes::frame::Occlusion::Off,
            },
            ..RenderOptions::default()
        }
    }

    /// What `--spin` and `--dof` change in a loaded scene.
    pub fn change_scene(&self, scene: &mut Scene) -> Result<(), CliError> {
        if let Some(deg) = self.spin {
            reyes::scene::spin(scene, deg).map_err(CliError::Spin)?;
        }
        if let Some(d) = self.dof {
            scene.camera.depth_of_field = Some(d);
        }
        Ok(())
    }
}

/// `reyes render`.
#[derive(Debug, Args)]
pub struct RenderCmd {
    /// A RIB (.rib, .rib.gz), Newell or .bpt scene file, or `teapot` (built in)
    /// [default: teapot].
    #[arg(value_name = "SCENE")]
    pub scene: Option<PathBuf>,

    /// Output PNG [default: SCENE's stem .png; for sequences see below]. A name with another
    /// image extension (.exr, .pfm, .jpg, .tif, ...) is refused: --exr and --float write
    /// those formats.
    #[arg(short = 'o', long = "output", value_name = "OUT.png", value_parser = png_path)]
    pub out: Option<PathBuf>,

    /// Write what the render did (counts, times, warnings) as JSON.
    #[arg(long, value_name = "OUT.json")]
    pub stats: Option<PathBuf>,

    /// Write the linear float image as PFM (a name ending in .exr is refused: --exr writes
    /// OpenEXR).
    #[arg(long, value_name = "OUT.pfm", value_parser = pfm_path)]
    pub float: Option<PathBuf>,

    /// Write the depth image as PFM (not to a .exr name: --exr holds depth as channel Z).
    #[arg(long, value_name = "OUT.pfm", value_parser = pfm_path)]
    pub depth: Option<PathBuf>,

    /// Write colour, alpha and depth as one OpenEXR file: channels R, G, B (premultiplied by
    /// A), A (coverage) and Z (camera-space depth, +inf on the background), 32-bit float,
    /// linear.
    #[arg(long, value_name = "OUT.exr")]
    pub exr: Option<PathBuf>,

    /// Multipass and multipass-host: time each procedure's passes on their own and print the
    /// last run's times (also in --stats' `gpu_ms_per_stage`; the extra pass boundaries add a
    /// little time, and the device-driven multi-pass's rounds are not fused; "queue work" is
    /// the device-driven multi-pass's one-thread plan before each submission's rounds, 0 for
    /// the host-driven one, whose host plans the rounds). The megakernel's stages share one
    /// launch: it warns and times the run as one.
    #[arg(long)]
    pub stage_times: bool,

    /// Render on the CPU reference instead of the GPU: writes the PNG only (not with --strategy,
    /// --runs, --stage-times, --stats, --float, --depth or --exr).
    #[arg(long, conflicts_with_all = ["strategy", "runs", "stage_times", "stats", "float", "depth", "exr"])]
    pub cpu: bool,

    /// Render on the GPU adapter even when it is a CPU (lavapipe, llvmpipe, WARP), where the
    /// default is the CPU reference when nothing GPU-only is asked for.
    #[arg(long, conflicts_with = "cpu")]
    pub gpu: bool,

    /// Render on several devices: `all` (every adapter that can render, with 64-bit atomic
    /// min/max; only the GPUs when there are any), or adapter indices as `reyes devices`
    /// lists them, e.g. `0,1` (an index given twice, `0,0`, opens two logical devices on
    /// one adapter, each its own device and queue). The frames of a sequence go to the
    /// devices from one queue (each device takes the next frame); one frame alone is split
    /// into screen buckets over them and its image assembled, identical bit for bit to one
    /// device's. Renders on the adapters even when they are CPUs (as --gpu).
    #[arg(long, value_name = "all|N,M", conflicts_with = "cpu")]
    pub devices: Option<DeviceSelection>,

    /// Frames of a sequence to render: N, A-B or a comma list of them (2-3, 2, 1,3)
    /// [default: all].
    #[arg(long, value_name = "N|A-B|A,B,..", value_parser = FrameRanges::parse)]
    pub frames: Option<FrameRanges>,

    /// The one frame to render (the same as --frames N).
    #[arg(long, value_name = "N", conflicts_with = "frames")]
    pub frame: Option<u32>,

    /// With --frames / --frame: render frames whose outputs already exist again (by default
    /// they are skipped, so that a resubmitted farm task renders only what is missing).
    #[arg(long)]
    pub overwrite: bool,

    /// GPU frames to time (N > 1: after a warm-up; median ± MAD reported).
    #[arg(long, value_name = "N", default_value_t = 1, value_parser = value_parser!(u32).range(1..))]
    pub runs: u32,

    /// Report the image error (PSNR, FLIP) against a reference image of the same size, an
    /// OpenEXR file as --exr writes it (e.g. a many-sample render); also in --stats.
    #[arg(long, value_name = "REF.exr")]
    pub compare_to: Option<PathBuf>,

    #[command(flatten)]
    pub render: RenderArgs,
}

impl RenderCmd {
    /// The frames selected by `--frames` or `--frame`; `None`: every frame.
    pub fn selection(&self) -> Option<FrameRanges> {
        (self.frame.map(FrameRanges::one)).or_else(|| self.frames.clone())
    }

    /// Whether this render asks for something only the GPU path gives: `--gpu`, a strategy,
    /// timed runs, stage times, statistics, float, depth or EXR output (what `--cpu` refuses).
    pub fn gpu_only(&self) -> bool {
        self.gpu
            || self.devices.is_some()
            || self.render.strategy.is_some()
            || self.runs > 1
            || self.stage_times
            || self.stats.is_some()
            || self.float.is_some()
            || self.depth.is_some()
            || self.exr.is_some()
    }

    /// Whether to render on the CPU reference although an adapter was found: when the adapter
    /// is itself a CPU (software Vulkan: lavapipe on two cores renders the 800x600 teapot in
    /// about 2.5 s where the CPU reference, the same pipeline compiled natively, takes 0.2 s)
    /// and nothing GPU-only was asked for ([`RenderCmd::gpu_only`]). Says so on stderr.
    pub fn cpu_by_default(&self, gpu: &scheduler::Gpu) -> bool {
        let cpu = gpu.is_cpu_adapter() && !self.gpu_only();
        if cpu {
            eprintln!(
                "note: rendering with the CPU reference (the same pipeline, compiled natively): \
                 the adapter is a CPU ({}), on which the GPU path is about 10x slower or more (--gpu or \
                 --strategy NAME renders on it anyway)",
                gpu.adapter_name()
            );
        }
        cpu
    }
}

/// `reyes measure`: a warm-up frame, 0.5 s of full GPU load (clocks), one more frame, then
/// `--runs` timed ones (median reported).
#[derive(Debug, Args)]
pub struct MeasureCmd {
    /// A RIB (.rib, .rib.gz), Newell or .bpt scene file, or `teapot` (built in)
    /// [default: teapot].
    #[arg(value_name = "SCENE")]
    pub scene: Option<PathBuf>,

    /// Also write the GPU frame as PNG.
    #[arg(short = 'o', long = "output", value_name = "OUT.png", value_parser = png_path)]
    pub out: Option<PathBuf>,

    /// Samples per pixel axis of the f64 reference render on the exact surfaces (1..=64).
    #[arg(long, value_name = "N", default_value_t = DEFAULT_SAMPLES_PER_AXIS,
          value_parser = value_parser!(u32).range(1..=64))]
    pub ref_samples: u32,

    /// Write the reference render as PNG.
    #[arg(long, value_name = "OUT.png")]
    pub reference_png: Option<PathBuf>,

    /// Print one JSON object instead of the table.
    #[arg(long)]
    pub json: bool,

    /// GPU frames to time (N > 1: after a warm-up; median ± MAD reported).
    #[arg(long, value_name = "N", default_value_t = 1, value_parser = value_parser!(u32).range(1..))]
    pub runs: u32,

    #[command(flatten)]
    pub render: RenderArgs,
}

/// The most timed (and, apart, warm-up) frames of `reyes bench`: every frame's record is
/// held for the report, and 100,000 teapot frames take minutes even on a large GPU.
pub const MAX_BENCH_FRAMES: u32 = 100_000;

/// `reyes bench`: frames of a turning scene rendered by the persistent pipelined renderer
/// (`reyes::realtime`), after 0.5 s of full GPU load (clocks) and `--warmup` untimed frames.
#[derive(Debug, Args)]
pub struct BenchCmd {
    /// A RIB (.rib, .rib.gz), Newell or .bpt scene file, or `teapot` (built in)
    /// [default: teapot].
    #[arg(value_name = "SCENE")]
    pub scene: Option<PathBuf>,

    /// Frames to time, 1..=100000 (each frame's record is kept for the report).
    #[arg(long, value_name = "N", default_value_t = 100,
          value_parser = value_parser!(u32).range(1..=MAX_BENCH_FRAMES as i64))]
    pub frames: u32,

    /// Turn the scene one full turn over the timed frames (360/N degrees per frame) about the
    /// camera's up axis through its centre [default: every frame at --angle].
    #[arg(long)]
    pub turntable: bool,

    /// Turntable angle of the first frame, degrees.
    #[arg(long, value_name = "DEG", default_value_t = 0.0, value_parser = finite_f64)]
    pub angle: f64,

    /// Untimed frames before the timed ones (after the clock warm-up), 0..=100000.
    #[arg(long, value_name = "N", default_value_t = 10,
          value_parser = value_parser!(u32).range(0..=MAX_BENCH_FRAMES as i64))]
    pub warmup: u32,

    /// Print one JSON object instead of the table (pretty-printed over several lines).
    #[arg(long)]
    pub json: bool,

    /// Write the last timed frame's angle once more as PNG (8-bit, converted on the GPU).
    #[arg(short = 'o', long = "output", value_name = "OUT.png", value_parser = png_path)]
    pub out: Option<PathBuf>,

    /// Also time a peer renderer on the same frames and report its image difference against
    /// the Reyes image of the first and last timed frame. `raster`: the patches tessellated
    /// in a compute pass and drawn as triangles by the hardware rasterizer with MSAA
    /// (`reyes::raster_peer`; docs/reyes.md).
    #[arg(long, value_name = "PEER")]
    pub peer: Option<Peer>,

    /// Time the frames on several devices: `all` or adapter indices (`0,1`; `0,0`: two
    /// logical devices on adapter 0), as for `reyes render --devices`. Each device warms up
    /// on its own, then the timed frames go to the devices from one queue, a few frames at a
    /// time (each device pipelines its frames); reports frames per second over all devices
    /// (timed frames over the wall time from the start to the last frame) and per device.
    #[arg(long, value_name = "all|N,M", conflicts_with = "peer")]
    pub devices: Option<DeviceSelection>,

    #[command(flatten)]
    pub render: RenderArgs,
}

/// `reyes view`: a window on a scene, rendered by the persistent renderer (`reyes::realtime`)
/// and drawn without a read-back; see `VIEW_CONTROLS`. `--width`/`--height` set the window's
/// first size; frames then render at the window's size.
#[derive(Debug, Args)]
pub struct ViewCmd {
    /// A RIB (.rib, .rib.gz), Newell or .bpt scene file, or `teapot` (built in)
    /// [default: teapot].
    #[arg(value_name = "SCENE")]
    pub scene: Option<PathBuf>,

    /// Render this many frames, then exit (with --screenshot: save the last first); for
    /// scripts and tests [default: run until closed].
    #[arg(long, value_name = "N", value_parser = value_parser!(u32).range(1..))]
    pub frames: Option<u32>,

    /// Where S saves the frame (PNG, 8-bit sRGB, the rendered image without the window's
    /// background) [default: reyes-view-NNNN.png in the current folder, the first free NNNN].
    #[arg(long, value_name = "OUT.png")]
    pub screenshot: Option<PathBuf>,

    #[command(flatten)]
    pub render: RenderArgs,
}

/// The columns of `reyes holes`' table (a macro so that the help text can include them).
macro_rules! holes_columns {
    () => {
        "| scene | raster | width x height | pixel samples | mp size (px) | reference | \
         micropolygons | interior px | hole px | hole samples | hole sample share |"
    };
}

/// The header row of `reyes holes`' table.
pub const HOLES_COLUMNS: &str = holes_columns!();

const HOLES_ROW: &str = concat!(
    "The table: a header row and its markdown rule (not with --no-header), then one row: ",
    holes_columns!()
);

/// `reyes holes`.
#[derive(Debug, Args)]
pub struct HolesCmd {
    /// A RIB (.rib, .rib.gz), Newell or .bpt scene file, or `teapot` (built in)
    /// [default: teapot].
    #[arg(value_name = "SCENE")]
    pub scene: Option<PathBuf>,

    /// The coverage holes are counted against: exact (the f64 surfaces, without displacement)
    /// or bbox (a bounding-box render of the same frame: for displaced surfaces).
    #[arg(long, value_name = "REF", value_enum, default_value_t = HoleReference::Exact)]
    pub reference: HoleReference,

    /// Samples per pixel axis of the exact reference coverage (1..=64).
    #[arg(long, value_name = "N", default_value_t = DEFAULT_SAMPLES_PER_AXIS,
          value_parser = value_parser!(u32).range(1..=64))]
    pub ref_samples: u32,

    /// Print one JSON object instead of the table row.
    #[arg(long)]
    pub json: bool,

    /// Print the table row without its header (to append rows of several runs to one table).
    #[arg(long, conflicts_with = "json")]
    pub no_header: bool,

    #[command(flatten)]
    pub render: RenderArgs,
}

/// `reyes holes --reference`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum HoleReference {
    /// The exact f64 coverage of the scene's patches (`reyes::reference::coverage`).
    Exact,
    /// A bounding-box render of the same frame.
    Bbox,
}

/// `--occlusion`: [`reyes::frame::Occlusion`] on the command line.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum OcclusionArg {
    /// Passes where the patches lie deep over each other.
    Auto,
    /// Passes in every bucket.
    On,
    /// One pass, nothing culled.
    Off,
}

/// `--raster`: [`RasterMode`] on the command line.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Raster {
    /// Bounding-box rasterization: every sub-sample under the micropolygon's screen bound.
    Bbox,
    /// One sample per micropolygon, nearest its centre.
    Nearest,
}

impl Raster {
    /// The renderer's mode.
    pub fn mode(self) -> RasterMode {
        match self {
            Raster::Bbox => RasterMode::BoundingBox,
            Raster::Nearest => RasterMode::NearestSample,
        }
    }
}

/// `--displacement-normals`: [`DisplacementNormals`] on the command line.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Normals {
    /// The surface normal from the patch's analytic derivatives (Sattler et al.'s eq. 1):
    /// one direction per point of the original patch, whatever grid computes it, so grids
    /// that share an edge move it alike.
    Exact,
    /// The normal of the grid's own finite differences (central inside, one-sided at its
    /// border): neighbouring grids of other rates move a shared edge differently, which
    /// opens holes. For comparison only.
    Approximate,
}

impl From<Normals> for DisplacementNormals {
    fn from(n: Normals) -> DisplacementNormals {
        match n {
            Normals::Exact => DisplacementNormals::Exact,
            Normals::Approximate => DisplacementNormals::Approximate,
        }
    }
}

/// `--sampling`: [`Sampling`] on the command line.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum SamplingArg {
    /// Simple UVT: the same S triples in every pixel (S = samples per pixel); each
    /// micropolygon is moved to each triple and rasterized into that triple's sub-sample.
    /// Ghost images when S is small.
    Simple,
    /// Interleave UVT: K x K pixel tiles share K^2 S triples, each sub-sample of the tile one of
    /// them, assigned by one of P permutations chosen per tile (the paper's eq. 2-3). Noise
    /// instead of ghosts.
    Interleave,
    /// Bounding box (the default): each pixel's triples come from a 64 x 64 pixel table repeated
    /// over the image, stratified in time; each is tested at its own time against the
    /// micropolygon's bound over its time stratum. Noise instead of ghosts.
    #[value(name = "bbox")]
    BoundingBox,
}

impl From<SamplingArg> for Sampling {
    fn from(s: SamplingArg) -> Sampling {
        match s {
            SamplingArg::Simple => Sampling::Simple,
            SamplingArg::Interleave => Sampling::Interleave,
            SamplingArg::BoundingBox => Sampling::BoundingBox,
        }
    }
}

/// A peer renderer of `reyes bench --peer`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Peer {
    /// Tessellation to triangles and the hardware rasterizer with MSAA (`reyes::raster_peer`).
    Raster,
}

/// `reyes sweep`: every scene x dicing setting x sample count x strategy. Its lists differ
/// from one frame's options (and its sizes default to 1920x1080), so it has its own flags.
#[derive(Debug, Args)]
pub struct SweepCmd {
    /// Scenes: teapot (built in), killeroo (the shared data's) or scene file paths.
    #[arg(
        long,
        value_name = "NAME|PATH,..",
        value_delimiter = ',',
        default_value = "teapot,killeroo"
    )]
    pub scenes: Vec<String>,

    /// Output folder for sweep.csv, sweep.md, sweep.png and sweep.svg (created if missing).
    #[arg(long, value_name = "DIR", default_value = "sweep")]
    pub out: PathBuf,

    /// Image width in pixels.
    #[arg(long, value_name = "PX", default_value_t = 1920, value_parser = value_parser!(u32).range(1..=MAX_SIDE))]
    pub width: u32,

    /// Image height in pixels.
    #[arg(long, value_name = "PX", default_value_t = 1080, value_parser = value_parser!(u32).range(1..=MAX_SIDE))]
    pub height: u32,

    /// Timed GPU frames per setting, after a warm-up (median ± MAD reported).
    #[arg(long, value_name = "N", default_value_t = 5, value_parser = value_parser!(u32).range(1..))]
    pub runs: u32,

    /// Samples per pixel axis of the f64 reference render.
    #[arg(long, value_name = "N", default_value_t = DEFAULT_SAMPLES_PER_AXIS,
          value_parser = value_parser!(u32).range(1..))]
    pub ref_samples: u32,

    /// Adaptive dicing: target micropolygon edges in pixels.
    #[arg(long, value_name = "PX,..", value_delimiter = ',', default_value = "0.5,0.71,1,1.41,2,4",
          value_parser = positive_f32)]
    pub mp_sizes: Vec<f32>,

    /// Fixed-bound dicing (split to the bound, dice 16x16): screen bounds in pixels, or none.
    #[arg(long, value_name = "PX,..|none", default_value = "8", value_parser = parse_bounds)]
    pub bound_px: Bounds,

    /// Pixel samples per axis: N (NxN) or NxM, each >= 1 (the scene's own count is always
    /// added).
    #[arg(long, value_name = "N|NxM,..", value_delimiter = ',', default_value = "1,2,4",
          value_parser = parse_samples)]
    pub samples: Vec<(u32, u32)>,

    /// GPU strategies: megakernel, multipass, multipass-host.
    #[arg(long, value_name = "NAME,..", value_delimiter = ',', default_value = "megakernel,multipass",
          value_parser = parse_strategy)]
    pub strategies: Vec<StrategyKind>,
}

/// `--bound-px` of `sweep`: a list of positive screen bounds (px), empty for `none`.
#[derive(Debug, Clone, PartialEq)]
pub struct Bounds(pub Vec<f32>);

/// `reyes drift`.
#[derive(Debug, Args)]
pub struct DriftCmd {
    /// A RIB (.rib, .rib.gz), Newell or .bpt scene file, or `teapot` (built in)
    /// [default: teapot].
    #[arg(value_name = "SCENE")]
    pub scene: Option<PathBuf>,

    /// Image width in pixels.
    #[arg(long, value_name = "PX", default_value_t = 1920, value_parser = value_parser!(u32).range(1..=MAX_SIDE))]
    pub width: u32,

    /// Image height in pixels.
    #[arg(long, value_name = "PX", default_value_t = 1080, value_parser = value_parser!(u32).range(1..=MAX_SIDE))]
    pub height: u32,

    /// Random-direction split paths per patch, besides the two alternating ones.
    #[arg(long, value_name = "N", default_value_t = PathOptions::default().random_paths)]
    pub paths: usize,

    /// Seed of the random paths.
    #[arg(long, value_name = "N", default_value_t = PathOptions::default().seed)]
    pub seed: u64,

    /// Print one JSON object instead of the tables.
    #[arg(long)]
    pub json: bool,
}

/// Largest image side (`reyes::frame::MAX_IMAGE_SIDE`), as a clap range bound.
const MAX_SIDE: i64 = reyes::frame::MAX_IMAGE_SIDE as i64;

// The value parsers below return `Result<T, String>`: that is clap's contract for a
// `value_parser` function (the text becomes the usage error, exit 2), not the command's
// error type (`CliError`).

/// `N` (NxN) or `NxM`, each in 1..=`reyes::frame::MAX_PIXEL_SAMPLES`.
fn parse_samples(v: &str) -> Result<(u32, u32), String> {
    let (x, y) = v.split_once('x').unwrap_or((v, v));
    let max = reyes::frame::MAX_PIXEL_SAMPLES;
    let p = |s: &str| {
        s.trim()
            .parse::<u32>()
            .ok()
            .filter(|&n| (1..=max).contains(&n))
    };
    p(x).zip(p(y))
        .ok_or(format!("`{v}` is not N or NxM with N, M in 1..={max}"))
}

/// A finite number.
/// A PFM output's name: any but one ending in `.exr`, which would hold PFM bytes under an
/// OpenEXR name (`--exr` writes OpenEXR).
fn pfm_path(v: &str) -> Result<PathBuf, String> {
    let p = PathBuf::from(v);
    let exr = p.extension().is_some_and(|e| e.eq_ignore_ascii_case("exr"));
    if exr {
        return Err(format!(
            "`{v}`: this option writes PFM, not OpenEXR; name it .pfm, or write OpenEXR with \
             --exr"
        ));
    }
    Ok(p)
}

/// A PNG output's name (`-o`): any but one whose extension names another image format
/// (`out.exr`, `out.jpg`), which would hold PNG bytes under that name; the error says which
/// flag writes the format, where one does.
fn png_path(v: &str) -> Result<PathBuf, String> {
    let p = PathBuf::from(v);
    let ext = p
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase());
    let flag = match ext.as_deref() {
        Some("exr") => Some("write OpenEXR with --exr"),
        Some("pfm") => Some("write PFM with --float (colour) or --depth (depth)"),
        Some(
            "jpg" | "jpeg" | "tif" | "tiff" | "bmp" | "gif" | "webp" | "tga" | "hdr" | "ppm"
            | "pgm" | "pbm" | "pnm" | "ico" | "dds" | "qoi" | "avif" | "ff",
        ) => Some("no flag writes that format"),
        _ => None,
    };
    match flag {
        Some(flag) => Err(format!("`{v}`: -o writes PNG; name it .png ({flag})")),
        None => Ok(p),
    }
}

fn finite_f64(v: &str) -> Result<f64, String> {
    v.trim()
        .parse::<f64>()
        .ok()
        .filter(|x| x.is_finite())
        .ok_or(format!("`{v}` is not a finite number"))
}

/// A finite number > 0.
fn positive_f32(v: &str) -> Result<f32, String> {
    v.trim()
        .parse::<f32>()
        .ok()
        .filter(|x| x.is_finite() && *x > 0.0)
        .ok_or(format!("`{v}` is not a finite number > 0"))
}

/// A byte count with an optional binary suffix: 512K, 64M, 2G.
fn parse_bytes(v: &str) -> Result<u64, String> {
    let (digits, shift) = match v.to_ascii_uppercase().chars().last() {
        Some('K') => (&v[..v.len() - 1], 10),
        Some('M') => (&v[..v.len() - 1], 20),
        Some('G') => (&v[..v.len() - 1], 30),
        _ => (v, 0),
    };
    match digits.parse::<u64>() {
        Ok(n) if n > 0 && n.leading_zeros() >= shift => Ok(n << shift),
        _ => Err(format!(
            "--memory-budget: `{v}` is not a positive byte count like 64M"
        )),
    }
}

/// `--dof FSTOP,FOCALLENGTH,DIST`: three positive finite numbers.
fn parse_dof(v: &str) -> Result<DepthOfField, String> {
    let n: Vec<f64> = v
        .split(',')
        .map(|s| {
            s.trim()
                .parse::<f64>()
                .ok()
                .filter(|x| x.is_finite() && *x > 0.0)
        })
        .collect::<Option<_>>()
        .filter(|n: &Vec<f64>| n.len() == 3)
        .ok_or(format!(
            "`{v}` is not FSTOP,FOCALLENGTH,DIST (three positive numbers in camera-space units, e.g. 2.8,50,454 for killeroo.rib, whose camera is 454 units from the model)"
        ))?;
    Ok(DepthOfField {
        fstop: n[0],
        focal_length: n[1],
        focal_distance: n[2],
    })
}

fn parse_strategy(v: &str) -> Result<StrategyKind, String> {
    StrategyKind::parse(v).ok_or_else(|| {
        let names: Vec<&str> = StrategyKind::NAMED.iter().map(|k| k.name()).collect();
        format!("unknown strategy `{v}` (one of {})", names.join(", "))
    })
}

fn parse_bounds(v: &str) -> Result<Bounds, String> {
    if v == "none" {
        return Ok(Bounds(Vec::new()));
    }
    v.split(',')
        .filter(|s| !s.is_empty())
        .map(positive_f32)
        .collect::<Result<_, _>>()
        .map(Bounds)
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::CommandFactory;

    fn parse(args: &[&str]) -> Result<Cli, clap::Error> {
        Cli::try_parse_from(std::iter::once("reyes").chain(args.iter().copied()))
    }

    #[test]
    fn the_definition_is_consistent() {
        Cli::command().debug_assert();
    }

    #[test]
    fn values_parse_and_ranges_are_checked() {
        let Command::Render(r) = parse(&[
            "render",
            "s.rib",
            "--samples",
            "2x3",
            "--memory-budget",
            "64K",
            "--frames",
            "1,3",
        ])
        .unwrap()
        .command
        else {
            panic!("not render")
        };
        assert_eq!(r.scene, Some("s.rib".into()));
        assert_eq!(r.render.samples, Some((2, 3)));
        assert_eq!(r.render.memory_budget, Some(64 << 10));
        assert!(r.frames.unwrap().contains(3));
        assert_eq!(r.render.options().mp_size, 1.0);
        assert_eq!(parse_samples("4"), Ok((4, 4)));
        assert_eq!(parse_bytes("1G"), Ok(1 << 30));
        for bad in [
            &["render", "--width", "0"][..],
            &["render", "--runs", "0"],
            &["render", "--bound-px", "0"],
            &["render", "--height", "-3"],
            &["render", "--mp-size", "inf"],
            &["render", "--mp-size", "NaN"],
            &["render", "--samples", "0x2"],
            &["render", "--memory-budget", "0"],
            &["render", "--memory-budget", "99999999999G"],
            &["render", "--cpu", "--runs", "5"],
            &["render", "--cpu", "--strategy", "multipass"],
            &["render", "--cpu", "--stats", "s.json"],
            &["render", "--cpu", "--exr", "x.exr"],
            &["measure", "--cpu"],
            &["measure", "--ref-samples", "65"],
            &["sweep", "--mp-sizes", "1,-1"],
            &["sweep", "--strategies", "megakernel,magic"],
            &["drift", "--height", "0"],
            &["render", "--float", "out.exr"],
            &["render", "--depth", "d.EXR"],
            // `-o` writes PNG bytes: these names would be lies.
            &["render", "-o", "out.exr"],
            &["render", "-o", "out.PFM"],
            &["render", "-o", "out.####.jpg"],
            &["measure", "-o", "m.tif"],
            &["bench", "-o", "b.exr"],
            &["bench", "--frames", "0"],
            // Up front, a frame count this large would allocate 34 GB.
            &["bench", "--frames", "4294967295"],
            &["bench", "--warmup", "4294967295"],
            &["bench", "--frames", "100001"],
            &["bench", "--angle", "inf"],
            &["bench", "--runs", "3"],
            &["view", "--frames", "0"],
            &["view", "--mp-size", "0"],
            &[],
        ] {
            let e = parse(bad).map(|_| ()).unwrap_err();
            assert_eq!(e.exit_code(), 2, "{bad:?}: {e}");
        }
        // A flag given twice: the last value.
        let Command::Drift(d) = parse(&["drift", "--width", "5", "--width", "7"])
            .unwrap()
            .command
        else {
            panic!("not drift")
        };
        assert_eq!(d.width, 7);
        // --cpu takes what the CPU twin uses.
        assert!(parse(&["render", "--cpu", "--memory-budget", "64K", "--frames", "2"]).is_ok());
        // -o: PNG names, folders, patterns and names without an extension are taken; another
        // format's extension names the flag that writes it.
        for ok in [
            "o.png",
            "o.PNG",
            "o",
            "d/",
            "o.####.png",
            "o.%04d",
            "o.0001",
        ] {
            assert!(parse(&["render", "-o", ok]).is_ok(), "{ok}");
        }
        let e = parse(&["render", "-o", "out.exr"]).map(|_| ()).unwrap_err();
        assert!(e.to_string().contains("--exr"), "{e}");
        let e = parse(&["render", "-o", "out.pfm"]).map(|_| ()).unwrap_err();
        assert!(e.to_string().contains("--float"), "{e}");
    }

    #[test]
    fn sweep_lists() {
        let Command::Sweep(s) = parse(&["sweep", "--bound-px", "none", "--samples", "1,2x4"])
            .unwrap()
            .command
        else {
            panic!("not sweep")
        };
        assert_eq!(s.bound_px, Bounds(vec![]));
        assert_eq!(s.samples, [(1, 1), (2, 4)]);
        assert_eq!(s.mp_sizes, [0.5, 0.71, 1.0, 1.41, 2.0, 4.0]);
        assert_eq!(
            s.strategies,
            [StrategyKind::Megakernel, StrategyKind::Multipass]
        );
        assert_eq!(s.scenes, ["teapot", "killeroo"]);
    }
}
