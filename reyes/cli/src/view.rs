//! `reyes view [SCENE] [--frames N] [--screenshot OUT.png] [render options]`: a window (winit)
//! on a scene rendered by the persistent renderer (`reyes::realtime`) at the window's size, each
//! frame drawn to the window's wgpu surface straight from the GPU image (`reyes::present`: no
//! read-back). The camera (`reyes::camera`) orbits, pans and dollies with the mouse; keys switch
//! the strategy and the quality (controls in cli.rs, `VIEW_CONTROLS`).
//!
//! Frames are rendered on demand: a redraw follows a change (camera, settings, window size) and
//! none while nothing changes, since a frame of an unchanged camera is the same image; an idle
//! viewer costs nothing on a shared machine. The title's fps is therefore that of continuous
//! dragging (one over the time between the last two shown frames), beside the frame's own GPU
//! and wall ms. The surface presents with vsync (`AutoVsync`): on-demand frames gain nothing
//! from tearing.
//!
//! Each frame is waited for before it is shown (a frame whose fixed sizes did not suffice is
//! rendered again first), so a wrong frame is never shown; every wait is bounded (the GPU's
//! timeout; a scripted run that shows no frame within it fails).

use crate::cli::ViewCmd;
use crate::error::CliError;
use reyes::camera::ViewCamera;
use reyes::frame::{MAX_PIXEL_SAMPLES, Occlusion, RenderOptions};
use reyes::gpu_render::required_features;
use reyes::present::Presenter;
use reyes::progress::NoProgress;
use reyes::realtime::{Pixels, RealtimeFrame, RealtimeRenderer};
use reyes::scene::Scene;
use reyes::stages::{C_CULL_OCCLUDED, C_MICROPOLYGONS};
use scheduler::{Gpu, StrategyKind};
use std::path::PathBuf;
use std::sync::Arc;
use std::time::{Duration, Instant};
use winit::application::ApplicationHandler;
use winit::dpi::PhysicalSize;
use winit::event::{ElementState, MouseButton, MouseScrollDelta, StartCause, WindowEvent};
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop};
use winit::keyboard::{Key, NamedKey};
use winit::window::{Window, WindowId};

/// The micropolygon size's range under `[` and `]`, pixels.
const MP_SIZE_RANGE: (f32, f32) = (0.125, 64.0);

/// Wheel pixels (touchpads) per dolly step.
const PIXELS_PER_STEP: f64 = 40.0;

pub fn main(a: ViewCmd) -> Result<(), CliError> {
    // The scene's own size and samples, unless the flags say otherwise; a bad option fails
    // here, before a window opens.
    let setup = crate::setup::Setup::load(a.scene.as_deref(), &a.render)?;
    let first = setup.frame_data()?.frame;
    let crate::setup::Setup {
        scene,
        name,
        options,
    } = setup;
    let event_loop = EventLoop::new().map_err(CliError::NoDisplay)?;
    let mut app = Viewer {
        deadline: a.frames.map(|_| Instant::now()),
        settings: Settings {
            strategy: a.render.strategy,
            mp_size: options.mp_size,
            samples: (first.spp_x, first.spp_y),
            occlusion: options.occlusion,
        },
        first_size: (first.width, first.height),
        options,
        scene,
        name,
        a,
        state: None,
        camera: ViewCamera::default(),
        drag: None,
        cursor: None,
        shown: 0,
        last_shown: None,
        fps: None,
        dirty: true,
        rebuild: true,
        error: None,
        pending_shot: None,
    };
    event_loop.run_app(&mut app).map_err(CliError::EventLoop)?;
    match app.error {
        Some(e) => Err(e),
        None => Ok(()),
    }
}

/// What the keys change; a change rebuilds the renderer.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Settings {
    /// `None` until the adapter is known (then [`crate::cli::RenderArgs::strategy_for`]).
    strategy: Option<StrategyKind>,
    mp_size: f32,
    samples: (u32, u32),
    /// `--occlusion`, cycled by O: whether frames cull from the previous frame
    /// ([`RealtimeRenderer::occlusion`]).
    occlusion: Occlusion,
}

/// The window and what draws into it, made when the event loop resumes.
struct State {
    renderer: Option<RealtimeRenderer>,
    presenter: Presenter,
    config: wgpu::SurfaceConfiguration,
    surface: wgpu::Surface<'static>,
    gpu: Gpu,
    window: Arc<Window>,
}

/// The size frames are rendered at for a window of `window` pixels: the window's own, or,
/// where that would not fit the device (its sub-samples, 8 bytes each, in one binding of
/// `max_binding` bytes) or the renderer ([`reyes::frame::MAX_IMAGE_SIDE`] a side), the
/// largest size of the window's aspect that does. The presenter scales it up to the window
/// and the title says so: a window resized to 3000x3000 keeps running instead of failing
/// on a buffer too large.
fn render_size(window: (u32, u32), samples: (u32, u32), max_binding: u64) -> (u32, u32) {
    let (w, h) = (window.0.max(1) as f64, window.1.max(1) as f64);
    let per_pixel = 8.0 * samples.0.max(1) as f64 * samples.1.max(1) as f64;
    let fits_memory = (max_binding as f64 / per_pixel / (w * h)).sqrt();
    let side = reyes::frame::MAX_IMAGE_SIDE as f64;
    let scale = fits_memory.min(side / w).min(side / h).min(1.0);
    if scale >= 1.0 {
        return window;
    }
    // Floors, so that the product stays within the bound.
    let fit = |x: f64| ((x * scale).floor() as u32).max(1);
    (fit(w), fit(h))
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Drag {
    Orbit,
    Pan,
}

struct Viewer {
    a: ViewCmd,
    scene: Scene,
    name: String,
    options: RenderOptions,
    first_size: (u32, u32),
    settings: Settings,
    state: Option<State>,
    camera: ViewCamera,
    drag: Option<Drag>,
    cursor: Option<(f64, f64)>,
    /// Frames shown so far.
    shown: u32,
    last_shown: Option<Instant>,
    /// One over the time between the last two shown frames.
    fps: Option<f64>,
    /// Something changed since the last frame: draw again.
    dirty: bool,
    /// The settings or the window's size changed: make the renderer again.
    rebuild: bool,
    /// Scripted runs (--frames): when the last frame was shown (or the run began); no frame
    /// within the GPU's timeout is an error.
    deadline: Option<Instant>,
    error: Option<CliError>,
    /// S was pressed after a change: saved here after the next frame.
    pending_shot: Option<PathBuf>,
}

impl Viewer {
    fn fail(&mut self, event_loop: &ActiveEventLoop, e: CliError) {
        if self.error.is_none() {
            self.error = Some(e);
        }
        event_loop.exit();
    }

    /// Opens the window, its surface, and a device that can present to it.
    fn open(&mut self, event_loop: &ActiveEventLoop) -> Result<State, CliError> {
        let (w, h) = self.first_size;
        let attrs = Window::default_attributes()
            .with_title(format!("reyes view: {}", self.name))
            .with_inner_size(PhysicalSize::new(w, h));
        let window = Arc::new(event_loop.create_window(attrs).map_err(CliError::Window)?);
        let instance = Gpu::instance_from_env();
        let surface = instance
            .create_surface(window.clone())
            .map_err(CliError::Surface)?;
        let mut gpu = Gpu::from_env_for_surface(&instance, &surface, required_features())?;
        crate::setup::trust_loops(&mut gpu);
        let caps = surface.get_capabilities(&gpu.adapter);
        // An 8-bit UNORM format shows the image's sRGB bytes as they are; an sRGB one makes the
        // draw decode them first (present.wgsl).
        use wgpu::TextureFormat::{Bgra8Unorm, Bgra8UnormSrgb, Rgba8Unorm, Rgba8UnormSrgb};
        let format = [Bgra8Unorm, Rgba8Unorm, Bgra8UnormSrgb, Rgba8UnormSrgb]
            .into_iter()
            .find(|f| caps.formats.contains(f))
            .or(caps.formats.first().copied())
            .ok_or_else(|| CliError::CannotPresent {
                adapter: gpu.adapter_name(),
            })?;
        let size = window.inner_size();
        let config = wgpu::SurfaceConfiguration {
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
            format,
            width: size.width.max(1),
            height: size.height.max(1),
            present_mode: wgpu::PresentMode::AutoVsync,
            desired_maximum_frame_latency: 2,
            alpha_mode: caps.alpha_modes.first().copied().unwrap_or_default(),
            view_formats: vec![],
            color_space: wgpu::SurfaceColorSpace::Auto,
        };
        surface.configure(&gpu.device, &config);
        let presenter = Presenter::new(&gpu, format)?;
        if self.settings.strategy.is_none() {
            self.settings.strategy = Some(self.a.render.strategy_for(&gpu));
        }
        Ok(State {
            renderer: None,
            presenter,
            config,
            surface,
            gpu,
            window,
        })
    }

    /// Renders the camera's frame and shows it; `Ok(false)` when the surface had no texture
    /// to draw to this time (it is drawn again on the next event).
    fn redraw(&mut self) -> Result<bool, CliError> {
        let Some(st) = self.state.as_mut() else {
            return Ok(false);
        };
        let window = (st.config.width, st.config.height);
        let size = render_size(window, self.settings.samples, st.gpu.max_binding_bytes());
        if self.rebuild || st.renderer.is_none() {
            // Free the old buffers before the new ones are made.
            st.renderer = None;
            let options = RenderOptions {
                width: Some(size.0),
                height: Some(size.1),
                pixel_samples: Some(self.settings.samples),
                mp_size: self.settings.mp_size,
                occlusion: self.settings.occlusion,
                ..self.options.clone()
            };
            let strategy = self.settings.strategy.unwrap_or(StrategyKind::Multipass);
            let r = RealtimeRenderer::new(&st.gpu, &self.scene, &options, strategy, Pixels::None)?;
            if let Some(why) = r.not_pipelined() {
                log::info!("frames not pipelined: {why}");
            }
            st.renderer = Some(r);
            self.rebuild = false;
        }
        let r = st.renderer.as_mut().expect("made above");
        // Pipelined frames cull from the previous frame where the renderer chose to; frames
        // that are not pipelined cull as `reyes render` does, unless occlusion is off.
        let culling = match r.not_pipelined() {
            Some(_) => self.settings.occlusion != Occlusion::Off,
            None => r.occlusion(),
        };
        let transform = self.camera.transform(r.centre());
        let frame = (r.render_transforms(&st.gpu, &[transform], &NoProgress))?
            .pop()
            .expect("one frame per transform");
        let texture = match st.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(t) => t,
            wgpu::CurrentSurfaceTexture::Suboptimal(t) => {
                self.dirty = true;
                t
            }
            wgpu::CurrentSurfaceTexture::Timeout | wgpu::CurrentSurfaceTexture::Occluded => {
                return Ok(false);
            }
            wgpu::CurrentSurfaceTexture::Outdated | wgpu::CurrentSurfaceTexture::Lost => {
                st.surface.configure(&st.gpu.device, &st.config);
                self.dirty = true;
                return Ok(false);
            }
            wgpu::CurrentSurfaceTexture::Validation => {
                return Err(CliError::SurfaceValidation(
                    st.gpu.take_error().unwrap_or("a validation error".into()),
                ));
            }
        };
        let view = texture.texture.create_view(&Default::default());
        let f = r.frame();
        let mut enc = st.gpu.device.create_command_encoder(&Default::default());
        st.presenter.draw(
            &st.gpu,
            &mut enc,
            r.image_buffer(),
            (f.width, f.height),
            &view,
            window,
        );
        st.gpu.submit(enc);
        st.window.pre_present_notify();
        st.gpu.queue.present(texture);
        if let Some(e) = st.gpu.take_error() {
            return Err(CliError::Draw(e));
        }
        let now = Instant::now();
        if let Some(t) = self.last_shown {
            self.fps = Some(1.0 / now.duration_since(t).as_secs_f64().max(1e-9));
        }
        self.last_shown = Some(now);
        self.shown += 1;
        let mut title = self.title(&frame, culling);
        if size != window {
            title += &format!(
                " | rendered at {}x{}, scaled up to the window",
                size.0, size.1
            );
        }
        let st = self.state.as_ref().expect("checked above");
        st.window.set_title(&title);
        if self.a.frames.is_some() {
            eprintln!("frame {}: {}", self.shown, title);
        }
        Ok(true)
    }

    fn title(&self, frame: &RealtimeFrame, culling: bool) -> String {
        let ms = |v: Option<f64>| v.map_or("n/a".into(), |v| format!("{v:.1}"));
        let s = &self.settings;
        let occlusion = match culling {
            true => format!("{} culled", frame.counters[C_CULL_OCCLUDED]),
            false => "no culling".into(),
        };
        format!(
            "reyes view: {} | {} fps | wall {} ms | GPU {} ms | {} micropolygons | {occlusion} | {} | mp {:.2} px | {}x{} samples{}",
            self.name,
            self.fps.map_or("-".into(), |f| format!("{f:.1}")),
            ms(Some(frame.wall_ms)),
            ms(frame.gpu_ms),
            frame.counters[C_MICROPOLYGONS],
            s.strategy.map_or("-", |k| k.name()),
            s.mp_size,
            s.samples.0,
            s.samples.1,
            if frame.rerendered.is_some() {
                " | rendered again"
            } else {
                ""
            }
        )
    }

    /// Saves the last frame as PNG (one read-back of the GPU image) to `path`.
    fn screenshot(&self, path: &std::path::Path) -> Result<(), CliError> {
        let st = self.state.as_ref().ok_or(CliError::NoWindow)?;
        let r = st.renderer.as_ref().ok_or(CliError::NoFrame)?;
        let f = r.frame();
        let bytes =
            (st.gpu).read_buffer(r.image_buffer(), 0, f.width as u64 * f.height as u64 * 4)?;
        let img = image::RgbaImage::from_raw(f.width, f.height, bytes)
            .ok_or(reyes::Error::BufferSizeMismatch)?;
        reyes::output::write_atomic(path, &reyes::output::png(&img)?)?;
        eprintln!("wrote {}", path.display());
        Ok(())
    }

    /// `--screenshot`, else the first free reyes-view-NNNN.png in the current folder.
    fn screenshot_path(&self) -> PathBuf {
        if let Some(p) = &self.a.screenshot {
            return p.clone();
        }
        (1..)
            .map(|i| PathBuf::from(format!("reyes-view-{i:04}.png")))
            .find(|p| !p.exists())
            .expect("a free name")
    }

    /// A key press; `Ok(true)` to quit. `repeat`: the press is the window system's autorepeat
    /// of a held key; only [`steps_on_repeat`] keys act on those, so a held (or, on a busy
    /// machine, a late-released) S saves one screenshot and M or O moves one step.
    fn key(&mut self, key: &Key, repeat: bool) -> Result<bool, CliError> {
        if repeat && !steps_on_repeat(key) {
            return Ok(false);
        }
        let s = &mut self.settings;
        let before = *s;
        match key {
            Key::Named(NamedKey::Escape) => return Ok(true),
            Key::Character(c) => match c.as_str() {
                "q" | "Q" => return Ok(true),
                "m" | "M" => {
                    let all = StrategyKind::ALL;
                    let i = (all.iter())
                        .position(|k| Some(*k) == s.strategy)
                        .map_or(0, |i| (i + 1) % all.len());
                    s.strategy = Some(all[i]);
                }
                "o" | "O" => {
                    s.occlusion = match s.occlusion {
                        Occlusion::Auto => Occlusion::On,
                        Occlusion::On => Occlusion::Off,
                        Occlusion::Off => Occlusion::Auto,
                    }
                }
                "[" => s.mp_size = (s.mp_size / 2f32.sqrt()).max(MP_SIZE_RANGE.0),
                "]" => s.mp_size = (s.mp_size * 2f32.sqrt()).min(MP_SIZE_RANGE.1),
                "1" | "2" | "3" | "4" => {
                    let n = c.parse::<u32>().expect("a digit");
                    s.samples = (n, n);
                }
                "+" | "=" => {
                    let up = |n: u32| (n + 1).min(MAX_PIXEL_SAMPLES);
                    s.samples = (up(s.samples.0), up(s.samples.1));
                }
                "-" => {
                    let down = |n: u32| n.saturating_sub(1).max(1);
                    s.samples = (down(s.samples.0), down(s.samples.1));
                }
                "r" | "R" => {
                    self.camera = ViewCamera::default();
                    self.dirty = true;
                }
                "s" | "S" => {
                    // After a change, the frame of the changed camera and settings.
                    let p = self.screenshot_path();
                    if self.dirty || self.rebuild {
                        self.pending_shot = Some(p);
                    } else {
                        self.screenshot(&p)?;
                    }
                }
                _ => {}
            },
            _ => {}
        }
        if self.settings != before {
            self.rebuild = true;
            self.dirty = true;
        }
        Ok(false)
    }

    fn request_redraw(&self) {
        if let Some(st) = &self.state {
            st.window.request_redraw();
        }
    }

    /// A scripted run wants frames until it has `--frames` of them.
    fn wants_frames(&self) -> bool {
        self.a.frames.is_some_and(|n| self.shown < n)
    }
}

/// Keys that step a setting up or down (`[`, `]`, `+`, `=`, `-`): holding one keeps stepping,
/// as held keys do in editors. Every other key acts once per press.
fn steps_on_repeat(key: &Key) -> bool {
    matches!(key, Key::Character(c) if matches!(c.as_str(), "[" | "]" | "+" | "=" | "-"))
}

impl ApplicationHandler for Viewer {
    fn new_events(&mut self, event_loop: &ActiveEventLoop, _cause: StartCause) {
        // A scripted run never hangs: no frame shown for the GPU's timeout is an error.
        if let (Some(t), Some(st)) = (self.deadline, &self.state) {
            let limit = st.gpu.timeout;
            if t.elapsed() > limit {
                let e = CliError::NoFrameShown {
                    seconds: limit.as_secs_f64(),
                };
                self.fail(event_loop, e);
            }
        }
    }

    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.state.is_some() {
            return;
        }
        match self.open(event_loop) {
            Ok(st) => {
                st.window.request_redraw();
                self.state = Some(st);
            }
            Err(e) => self.fail(event_loop, e),
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _id: WindowId, event: WindowEvent) {
        match event {
            WindowEvent::CloseRequested => event_loop.exit(),
            WindowEvent::Resized(size) => {
                if let Some(st) = self.state.as_mut()
                    && size.width > 0
                    && size.height > 0
                    && (size.width, size.height) != (st.config.width, st.config.height)
                {
                    st.config.width = size.width;
                    st.config.height = size.height;
                    st.surface.configure(&st.gpu.device, &st.config);
                    self.rebuild = true;
                    self.dirty = true;
                }
            }
            // winit makes a synthetic press for every key already down when the window gains
            // focus: a key held while focusing the window (or, on a busy machine, a focus
            // change handled after the key went down) is not a press meant for the viewer.
            WindowEvent::KeyboardInput {
                event,
                is_synthetic: false,
                ..
            } if event.state == ElementState::Pressed => {
                match self.key(&event.logical_key, event.repeat) {
                    Ok(true) => event_loop.exit(),
                    Ok(false) => {}
                    Err(e) => self.fail(event_loop, e),
                }
            }
            WindowEvent::MouseInput { state, button, .. } => {
                let drag = match button {
                    MouseButton::Left => Some(Drag::Orbit),
                    MouseButton::Right | MouseButton::Middle => Some(Drag::Pan),
                    _ => None,
                };
                match state {
                    ElementState::Pressed if drag.is_some() => self.drag = drag,
                    ElementState::Released if drag == self.drag => self.drag = None,
                    _ => {}
                }
            }
            WindowEvent::CursorMoved { position, .. } => {
                let (x, y) = (position.x, position.y);
                if let (Some(drag), Some((px, py))) = (self.drag, self.cursor) {
                    let (dx, dy) = (x - px, y - py);
                    match drag {
                        Drag::Orbit => self.camera.orbit_by_pixels(dx, dy),
                        Drag::Pan => {
                            let focal = (self.state.as_ref())
                                .and_then(|s| s.renderer.as_ref())
                                .map(|r| (r.centre().z, r.frame().focal as f64));
                            if let Some((z, focal)) = focal {
                                self.camera.pan_by_pixels(dx, dy, z, focal);
                            }
                        }
                    }
                    self.dirty = true;
                }
                self.cursor = Some((x, y));
            }
            WindowEvent::CursorLeft { .. } => self.cursor = None,
            WindowEvent::MouseWheel { delta, .. } => {
                let steps = match delta {
                    MouseScrollDelta::LineDelta(_, y) => y as f64,
                    MouseScrollDelta::PixelDelta(p) => p.y / PIXELS_PER_STEP,
                };
                self.camera.zoom_by_steps(steps);
                self.dirty = true;
            }
            WindowEvent::RedrawRequested => {
                let was_dirty = std::mem::replace(&mut self.dirty, false);
                match self.redraw() {
                    Ok(true) => {
                        if self.deadline.is_some() {
                            self.deadline = Some(Instant::now());
                        }
                        if let Some(p) = self.pending_shot.take()
                            && let Err(e) = self.screenshot(&p)
                        {
                            self.fail(event_loop, e);
                        }
                        if self.a.frames.is_some() && !self.wants_frames() {
                            if let Some(p) = self.a.screenshot.clone()
                                && let Err(e) = self.screenshot(&p)
                            {
                                self.fail(event_loop, e);
                            }
                            event_loop.exit();
                        }
                    }
                    Ok(false) => self.dirty |= was_dirty,
                    Err(e) => self.fail(event_loop, e),
                }
            }
            _ => {}
        }
    }

    fn about_to_wait(&mut self, event_loop: &ActiveEventLoop) {
        if self.dirty || self.wants_frames() {
            self.request_redraw();
        }
        // Scripted runs wake at least once a second to check their deadline.
        event_loop.set_control_flow(if self.deadline.is_some() {
            ControlFlow::wait_duration(Duration::from_secs(1))
        } else {
            ControlFlow::Wait
        });
    }
}

#[cfg(test)]
mod tests {
    use super::{Key, NamedKey, render_size, steps_on_repeat};

    /// A window that fits is rendered at its size; a larger one at the largest size of its
    /// aspect whose sub-samples fit one binding (and each side the renderer's limit).
    #[test]
    fn large_windows_render_at_a_size_that_fits() {
        let mib = 1u64 << 20;
        assert_eq!(render_size((640, 480), (2, 2), 128 * mib), (640, 480));
        // 3000x3000 at 2x2 samples: 288 MB of sub-samples against a 128 MiB binding.
        let (w, h) = render_size((3000, 3000), (2, 2), 128 * mib);
        assert_eq!(w, h);
        assert!(w as u64 * h as u64 * 4 * 8 <= 128 * mib, "{w}x{h}");
        assert!(w > 1900, "{w}: more than needed was taken off");
        // The aspect is kept (to the pixel), and sides stay within MAX_IMAGE_SIDE.
        let (w, h) = render_size((4000, 1000), (4, 4), 64 * mib);
        assert!((w as f64 / h as f64 - 4.0).abs() < 0.01, "{w}x{h}");
        assert!(w as u64 * h as u64 * 16 * 8 <= 64 * mib);
        let side = reyes::frame::MAX_IMAGE_SIDE;
        let (w, _) = render_size((4 * side, 10), (1, 1), u64::MAX);
        assert!(w <= side);
        assert_eq!(render_size((0, 0), (1, 1), 1), (1, 1));
    }

    /// Held S, M, O, R and Q act once; the stepping keys keep stepping.
    #[test]
    fn only_stepping_keys_act_on_autorepeat() {
        let ch = |c: &str| Key::Character(c.into());
        for c in ["s", "S", "m", "o", "r", "q", "1"] {
            assert!(!steps_on_repeat(&ch(c)), "{c}");
        }
        for c in ["[", "]", "+", "=", "-"] {
            assert!(steps_on_repeat(&ch(c)), "{c}");
        }
        assert!(!steps_on_repeat(&Key::Named(NamedKey::Escape)));
    }
}
