//! From command-line options to a frame, one way for every subcommand: the scene named on the
//! command line (or the built-in teapot) with `--spin` and `--dof` applied and its warnings
//! logged, the render options, the frame data, the GPU with the features the pipeline needs,
//! and the offline renderer of a configuration. Messages and their order are the subcommands'
//! own: a bad scene or option fails before the GPU is opened.

use crate::cli::RenderArgs;
use crate::error::CliError;
use reyes::frame::{FrameData, RenderOptions};
use reyes::gpu_render::{GpuRenderer, RendererConfig, required_features};
use reyes::scene::{self, FrameStream, Scene};
use scheduler::Gpu;
use std::path::Path;

/// The scene named on the command line (none or `teapot`: the built-in teapot) and a short
/// name for it (the file's stem), for the commands that measure, compare or time frames
/// (`measure`, `holes`, `sweep`, `drift`, `bench`, `view`): without its `Imager
/// "background"`, whose opaque pixels would hide the coverage (alpha) they compare. `render`
/// streams the file itself ([`stream_sequence`]) and keeps it. Errors: the file's.
pub fn load_scene(path: Option<&Path>) -> Result<(Scene, String), CliError> {
    match path {
        None => Ok((scene::builtin_teapot(), "teapot".into())),
        Some(p) if p.as_os_str() == "teapot" => Ok((scene::builtin_teapot(), "teapot".into())),
        Some(p) => {
            let mut s = scene::load(p)?;
            s.background = None;
            let name = p
                .file_stem()
                .map_or("scene".into(), |s| s.to_string_lossy().into_owned());
            Ok((s, name))
        }
    }
}

/// The scene file's frames (the built-in teapot: one) as a stream, read one at a time, and
/// the file's stem for default output names. Errors: the file cannot be read (a Newell or
/// BPT file's errors too); a RIB file's come with its frames.
pub fn stream_sequence(path: Option<&Path>) -> Result<(FrameStream, String), CliError> {
    Ok(match path {
        None => (
            FrameStream::single(scene::builtin_teapot()),
            "teapot".into(),
        ),
        Some(p) if p.as_os_str() == "teapot" => (
            FrameStream::single(scene::builtin_teapot()),
            "teapot".into(),
        ),
        Some(p) => (
            scene::stream_frames(p)?,
            p.file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or("out".into()),
        ),
    })
}

/// One scene ready to render: loaded, edited by the flags, its warnings logged.
pub struct Setup {
    /// The scene after `--spin` and `--dof`.
    pub scene: Scene,
    /// Its short name ([`load_scene`]).
    pub name: String,
    /// The render options of the flags.
    pub options: RenderOptions,
}

impl Setup {
    /// Loads the scene at `path` ([`load_scene`]), applies `render`'s scene edits, logs the
    /// scene's warnings and takes `render`'s options. Errors: the file's and the edits'.
    pub fn load(path: Option<&Path>, render: &RenderArgs) -> Result<Setup, CliError> {
        let (mut scene, name) = load_scene(path)?;
        render.change_scene(&mut scene)?;
        for w in &scene.warnings {
            log::warn!("{w}");
        }
        Ok(Setup {
            scene,
            name,
            options: render.options(),
        })
    }

    /// The frame of the scene under the options. Errors: the options' ([`FrameData::new`]).
    pub fn frame_data(&self) -> Result<FrameData, CliError> {
        Ok(FrameData::new(&self.scene, &self.options)?)
    }
}

/// The GPU from the environment, with the features the Reyes pipeline needs. Errors: no
/// adapter, or one without them.
pub fn open_gpu() -> Result<Gpu, CliError> {
    let mut gpu = Gpu::from_env_requiring(required_features())?;
    trust_loops(&mut gpu);
    Ok(gpu)
}

/// Leaves naga's loop bounding out of the modules `gpu` compiles ([`Gpu::trust_loops`]; a
/// third of a frame's GPU time on NVIDIA). For the command's own devices only.
pub(crate) fn trust_loops(gpu: &mut Gpu) {
    // SAFETY: the command compiles the scheduler's and reyes's shaders only, whose loops all
    // end (docs/scheduler.md 4, "Naga's loop bounding").
    #[allow(
        unsafe_code,
        reason = "Gpu::trust_loops: every loop of this device's shaders ends"
    )]
    unsafe {
        gpu.trust_loops()
    };
}

/// The offline renderer of `config` on `gpu`. Errors: the device's.
pub fn renderer(gpu: &Gpu, config: impl Into<RendererConfig>) -> Result<GpuRenderer, CliError> {
    Ok(GpuRenderer::new(gpu, config)?)
}
