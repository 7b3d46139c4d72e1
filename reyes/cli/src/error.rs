//! The `reyes` command's errors: one enum, [`CliError`], with a variant per kind of failure (a
//! usage conflict, a scene or option the renderer library refuses, a failed GPU run, an output
//! that cannot be planned or written, a window that cannot be opened or drawn, a check that
//! fails). Each variant's message is the text `reyes SUBCOMMAND: ` is followed by on stderr.

use reyes::scene::SceneError;
use scheduler::RunError;
use std::path::PathBuf;

/// What can make a `reyes` subcommand fail. [`CliError::Conflict`] is a usage error (exit 2,
/// reported through clap), and so is [`CliError::NoFrameSelected`] ([`CliError::exit_code`]);
/// every other variant exits 1.
#[derive(Debug, thiserror::Error)]
pub enum CliError {
    /// Two options that cannot go together (`--raster nearest` with `--spin` or `--dof`).
    #[error(
        "the argument '--raster nearest' cannot be used with '{flag}': motion blur and \
         depth of field need bounding-box rasterization (--raster bbox)"
    )]
    Conflict {
        /// The flag that conflicts with `--raster nearest`.
        flag: &'static str,
    },
    /// `--strategy multipass-floor` where the frames move: the floor replays one kept
    /// frame's work (`scheduler::HostMultipassConfig::replay_floor`).
    #[error(
        "`reyes {command} --strategy multipass-floor`: the multi-pass floor replays the work of \
         one kept frame and cannot render a moving view; use it with `reyes render --runs N` \
         or `reyes measure`"
    )]
    FloorNotHere {
        /// The subcommand.
        command: &'static str,
    },
    /// A scene file that could not be read or parsed.
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// The renderer library's error: options out of range, an output file that could not be
    /// written, an image that could not be read or encoded.
    #[error(transparent)]
    Reyes(#[from] reyes::Error),
    /// A GPU run that failed (no adapter, a device error, a timeout, a queue overflow).
    #[error(transparent)]
    Run(#[from] RunError),
    /// A device of `--devices` that failed while rendering its part of a split frame (the
    /// device and bucket named).
    #[error(transparent)]
    Device(#[from] reyes::devices::DeviceError),
    /// `--spin` that cannot turn the scene.
    #[error("--spin: {0}")]
    Spin(#[source] reyes::Error),
    /// `--compare-to`'s reference image could not be read.
    #[error("--compare-to {0}")]
    CompareToUnreadable(#[source] reyes::Error),
    /// `--compare-to`'s reference is not the frame's size.
    #[error(
        "--compare-to {}: the reference is {}x{}, the frame {}x{}",
        path.display(), reference.0, reference.1, frame.0, frame.1
    )]
    CompareToSize {
        /// The reference image's file.
        path: PathBuf,
        /// Its width and height.
        reference: (u32, u32),
        /// The frame's width and height.
        frame: (u32, u32),
    },
    /// `--frames` selects none of the scene's frames (a file's, or the built-in teapot's one).
    #[error("--frames selects none of the scene's frames ({numbers})")]
    NoFrameSelected {
        /// The file's frame numbers, comma-separated.
        numbers: String,
    },
    /// Frames of the selection that failed (each reported on stderr as it failed).
    #[error("{failed} failed; the other selected frames are done")]
    FramesFailed {
        /// The failed frames, e.g. "frame 2, frame 5".
        failed: String,
    },
    /// An output name without `#` when several frames are rendered.
    #[error(
        "{flag}: several frames are rendered; give a name with #### or %04d for the frame number"
    )]
    UnnumberedOutput {
        /// The output's flag, e.g. `--stats`.
        flag: &'static str,
    },
    /// Two frames whose images would have one name.
    #[error("frames {first} and {second} would both write {}", path.display())]
    SameOutput {
        /// The earlier frame's number.
        first: u32,
        /// The later frame's number.
        second: u32,
        /// The image both would write.
        path: PathBuf,
    },
    /// An output that is one of the scene's inputs (the scene file, an archive, a map).
    #[error(
        "{} would overwrite {}, an input of the scene; write the output under another name",
        output.display(), input.display()
    )]
    OutputIsInput {
        /// The output file.
        output: PathBuf,
        /// The input it is, as the scene names it.
        input: PathBuf,
    },
    /// An output name the file system cannot hold: a NUL, or a component longer than
    /// [`crate::frames::MAX_NAME_BYTES`] bytes.
    #[error("{what}: {why}")]
    BadOutputName {
        /// The output, e.g. "frame 2's Display name \"...\"" or "-o out.png".
        what: String,
        /// What is wrong with it.
        why: String,
    },
    /// An output whose folder does not exist.
    #[error("{}: the folder {} does not exist", path.display(), folder.display())]
    MissingFolder {
        /// The output file.
        path: PathBuf,
        /// Its folder.
        folder: PathBuf,
    },
    /// An output folder that could not be made.
    #[error("{}: {source}", path.display())]
    CreateFolder {
        /// The folder.
        path: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
    /// A report that could not be written as JSON.
    #[error(transparent)]
    Json(#[from] serde_json::Error),
    /// A figure (`reyes sweep`'s plots) that could not be drawn or written.
    #[error(transparent)]
    Plot(#[from] reyes_accuracy::plot::PlotError),
    /// `reyes drift`: the split-tree walk and the CPU pipeline disagree on the scene's depth or
    /// grids.
    #[error(
        "the split-tree walk disagrees with cpu_render: depth {tree_depth} vs {cpu_depth}, \
         grids {tree_grids} vs {cpu_grids}"
    )]
    DriftDisagrees {
        /// The walk's deepest split.
        tree_depth: u64,
        /// The CPU pipeline's deepest split.
        cpu_depth: u64,
        /// The walk's grids.
        tree_grids: u64,
        /// The CPU pipeline's grids.
        cpu_grids: u64,
    },
    /// `reyes view`: no event loop, most often for want of a display.
    #[error(
        "cannot open a window: {0} (no display? set DISPLAY, or run it under Xvfb: \
         `xvfb-run reyes view ...`)"
    )]
    NoDisplay(#[source] winit::error::EventLoopError),
    /// `reyes view`: the event loop failed while running.
    #[error("the window's event loop: {0}")]
    EventLoop(#[source] winit::error::EventLoopError),
    /// `reyes view`: the window could not be made.
    #[error("cannot open a window: {0}")]
    Window(#[source] winit::error::OsError),
    /// `reyes view`: no wgpu surface for the window.
    #[error("cannot make a wgpu surface for the window: {0}")]
    Surface(#[source] wgpu::CreateSurfaceError),
    /// `reyes view`: the adapter has no format to present in.
    #[error("{adapter} cannot present to this window")]
    CannotPresent {
        /// The adapter's name.
        adapter: String,
    },
    /// `reyes view`: the surface reported a validation error.
    #[error("the window's surface: {0}")]
    SurfaceValidation(String),
    /// `reyes view`: the device reported an error drawing the frame.
    #[error("drawing the frame: {0}")]
    Draw(String),
    /// `reyes view`: a scripted run showed no frame within the GPU's timeout.
    #[error("no frame shown in {seconds:.0} s (the window never drew)")]
    NoFrameShown {
        /// The timeout, in seconds.
        seconds: f64,
    },
    /// `reyes view`: a screenshot before the window opened.
    #[error("no window yet")]
    NoWindow,
    /// `reyes view`: a screenshot before the first frame.
    #[error("no frame yet")]
    NoFrame,
}

impl CliError {
    /// The exit status of this error: 2 for a usage error (a `--frames` selection that names
    /// none of the file's frames, a `--stats`-like name without a frame pattern when several
    /// frames are rendered), 1 for the rest (bad input, a failed render or write).
    pub fn exit_code(&self) -> u8 {
        match self {
            CliError::Conflict { .. }
            | CliError::FloorNotHere { .. }
            | CliError::NoFrameSelected { .. }
            | CliError::UnnumberedOutput { .. } => 2,
            _ => 1,
        }
    }
}
