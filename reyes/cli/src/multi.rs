//! `reyes render --devices` and `reyes devices`: frames on several devices of one process
//! (`reyes::devices` opens them and splits one frame's buckets over them).
//!
//! A sequence: the command's reading loop names and checks each frame as before (so the
//! skip-existing contract, the output names and the exit codes are unchanged), then hands it
//! to one queue (a rendezvous channel: a frame is read only when a device is free to take
//! it), from which each device's thread takes the next frame, renders it and writes its
//! outputs atomically, in whatever order the frames finish. A frame that fails is reported
//! naming it and its device; the others still render; the run exits 1. One frame: its
//! buckets are split over the devices (`reyes::devices::render_split`).

use crate::cli::RenderCmd;
use crate::error::CliError;
use crate::frames::Outputs;
use reyes::devices::{self, DeviceSelection, OpenedDevice};
use reyes::frame::{FrameData, SceneFeatures};
use reyes::gpu_render::{GpuRenderer, required_features};
use reyes::scene::Scene;
use reyes::stats::DeviceStats;
use std::sync::mpsc::{Receiver, SyncSender};
use std::sync::{Arc, Mutex};
use std::thread::{Scope, ScopedJoinHandle};

/// `reyes devices`: every adapter with its index and whether it can render, then what
/// `--devices all` opens. Errors: none can render.
pub fn list_devices() -> Result<(), CliError> {
    let list = devices::adapters(&scheduler::Gpu::instance_from_env(), required_features());
    for a in &list {
        reyes_cli::outln!("{}", a.describe());
    }
    let all = devices::usable_indices(&list);
    if all.is_empty() {
        // The environment may have narrowed the search (wgpu's own variables).
        let narrowed: Vec<String> = ["WGPU_BACKEND", "WGPU_ADAPTER_NAME"]
            .iter()
            .filter_map(|v| std::env::var(v).ok().map(|x| format!("{v}={x}")))
            .collect();
        let hint = if narrowed.is_empty() {
            String::new()
        } else {
            format!(" (searched only where {} allows)", narrowed.join(" and "))
        };
        return Err(scheduler::RunError::NoAdapter(format!(
            "no adapter can render (64-bit atomic min/max){hint}; install a Vulkan driver (on \
             Debian: `apt-get install -y mesa-vulkan-drivers` for lavapipe)"
        ))
        .into());
    }
    let all: Vec<String> = all.iter().map(usize::to_string).collect();
    reyes_cli::outln!("--devices all: {}", all.join(","));
    Ok(())
}

/// What every device's thread shares with the command: its flags, the progress bar, the
/// `--compare-to` reference, and where failed frames are listed.
pub struct Shared<'a> {
    pub a: &'a RenderCmd,
    pub bar: &'a indicatif::ProgressBar,
    pub reference: Option<&'a crate::Reference>,
    pub failed: &'a Mutex<Vec<String>>,
}

/// A frame named, checked and made ready to render.
pub struct Prepared {
    pub number: u32,
    /// The file has several frames (each is announced).
    pub sequence: bool,
    pub scene: Scene,
    pub data: FrameData,
    pub outputs: Outputs,
    /// The file's warnings so far, for the frame's statistics.
    pub file_warnings: Vec<String>,
}

/// One opened device with its renderer (compiled for what its frames so far need) and what
/// it did.
struct Slot {
    slot: usize,
    name: String,
    device: OpenedDevice,
    renderer: Option<(GpuRenderer, SceneFeatures)>,
    frames: u32,
    buckets: u32,
    gpu_ms: Option<f64>,
    wall_ms: f64,
}

impl Slot {
    /// The renderer for `need` (and what earlier frames needed), compiled again when a frame
    /// needs more.
    fn renderer(&mut self, a: &RenderCmd, need: SceneFeatures) -> Result<&GpuRenderer, CliError> {
        let have = self.renderer.as_ref().map(|r| r.1);
        if have.is_none_or(|h| h.union(need) != h) {
            let all = have.map_or(need, |h| h.union(need));
            self.renderer = Some((crate::gpu_renderer(a, &self.device.gpu, all)?, all));
        }
        Ok(&self.renderer.as_ref().expect("made above").0)
    }

    /// Counts a part of a frame this device rendered.
    fn count(&mut self, frames: u32, buckets: u32, gpu_ms: Option<f64>, wall_ms: f64) {
        self.frames += frames;
        self.buckets += buckets;
        self.gpu_ms = self.gpu_ms.zip(gpu_ms).map(|(a, b)| a + b);
        self.wall_ms += wall_ms;
    }

    /// Renders a frame of a sequence on this device and writes its outputs.
    fn render(&mut self, s: &Shared, p: &Prepared) -> Result<(), CliError> {
        let a = s.a;
        self.renderer(a, p.data.features())?;
        if p.sequence {
            reyes_cli::progress::note(format!("frame {} on {}:", p.number, self.name));
        }
        s.bar.inc_length(a.runs.max(1) as u64);
        let renderer = &self.renderer.as_ref().expect("made above").0;
        let gpu = &self.device.gpu;
        let (frame, times) = crate::gpu_frame(a, gpu, renderer, &p.data, s.bar)?;
        let adapter = gpu.adapter_name();
        let stat = DeviceStats {
            slot: self.slot,
            device: self.name.clone(),
            frames: 1,
            buckets: frame.buckets,
            gpu_ms: devices::gpu_ms(&frame),
            wall_ms: frame.wall_ms,
        };
        self.count(1, stat.buckets, stat.gpu_ms, stat.wall_ms);
        let f = (&p.scene, &p.file_warnings[..], &p.data);
        let r = s.reference;
        crate::write_frame(f, &p.outputs, frame, times, &adapter, r, Some(vec![stat]))
    }

    /// `device N (name): F frames, B buckets, GPU g ms, wall w ms`.
    fn summary(&self) -> String {
        let gpu = self.gpu_ms.map_or("n/a".into(), |g| format!("{g:.1} ms"));
        format!(
            "device {} ({}): {} frames, {} buckets, GPU {gpu}, busy {:.1} ms",
            self.slot, self.name, self.frames, self.buckets, self.wall_ms
        )
    }
}

/// The devices of `--devices`, opened with the first frame to render.
pub struct Pool<'scope, 'env> {
    selection: DeviceSelection,
    /// Several frames may be rendered: a queue of frames; else the frame's buckets are split.
    several: bool,
    scope: &'scope Scope<'scope, 'env>,
    shared: &'env Shared<'env>,
    state: State<'scope>,
}

enum State<'scope> {
    Unopened,
    Split(Vec<Slot>),
    Queue {
        tx: SyncSender<Prepared>,
        workers: Vec<ScopedJoinHandle<'scope, Slot>>,
    },
}

impl<'scope, 'env> Pool<'scope, 'env> {
    /// The devices of `selection` for a run of several frames (`several`) or one, their
    /// threads spawned in `scope`.
    pub fn new(
        selection: DeviceSelection,
        several: bool,
        scope: &'scope Scope<'scope, 'env>,
        shared: &'env Shared<'env>,
    ) -> Pool<'scope, 'env> {
        Pool {
            selection,
            several,
            scope,
            shared,
            state: State::Unopened,
        }
    }

    /// Renders a frame: hands it to the devices' queue (blocking until a device takes it),
    /// or, for one frame, splits its buckets over the devices. Errors: the devices cannot be
    /// opened (an error of the run), a split frame that fails (the frame's).
    pub fn dispatch(&mut self, p: Prepared) -> Result<(), (Option<u32>, CliError)> {
        if let State::Unopened = self.state {
            let mut opened = devices::open(&self.selection, required_features())
                .map_err(|e| (None, e.into()))?;
            for d in &mut opened {
                crate::setup::trust_loops(&mut d.gpu);
            }
            let slots: Vec<Slot> = (opened.into_iter().enumerate())
                .map(|(slot, device)| Slot {
                    slot,
                    name: device.name(),
                    device,
                    renderer: None,
                    frames: 0,
                    buckets: 0,
                    gpu_ms: Some(0.0),
                    wall_ms: 0.0,
                })
                .collect();
            let names: Vec<String> = slots.iter().map(|s| s.name.clone()).collect();
            reyes_cli::progress::note(format!("{} devices: {}", names.len(), names.join(", ")));
            self.state = match self.several {
                false => State::Split(slots),
                true => {
                    let (tx, rx) = std::sync::mpsc::sync_channel(0);
                    let rx = Arc::new(Mutex::new(rx));
                    let workers = (slots.into_iter())
                        .map(|slot| {
                            let (rx, shared) = (rx.clone(), self.shared);
                            self.scope.spawn(move || worker(shared, slot, &rx))
                        })
                        .collect();
                    State::Queue { tx, workers }
                }
            };
        }
        let n = p.number;
        match &mut self.state {
            State::Unopened => unreachable!("opened above"),
            State::Queue { tx, .. } => tx.send(p).map_err(|_| {
                let e = scheduler::RunError::Device("every device's thread has ended".into());
                (Some(n), e.into())
            }),
            State::Split(slots) => split(self.shared, slots, &p).map_err(|e| (Some(n), e)),
        }
    }

    /// Closes the queue, waits for the devices' threads, and prints what each device did.
    pub fn finish(self) {
        let slots = match self.state {
            State::Unopened => return,
            State::Split(slots) => slots,
            State::Queue { tx, workers } => {
                drop(tx);
                let joined = workers.into_iter().map(|w| w.join());
                joined
                    .map(|j| j.unwrap_or_else(|p| std::panic::resume_unwind(p)))
                    .collect()
            }
        };
        for s in &slots {
            reyes_cli::progress::note(s.summary());
        }
    }
}

/// A device's thread: takes the next frame from the queue until it closes; a frame that
/// fails is reported (naming the frame and the device) and listed, and the thread goes on.
fn worker(s: &Shared, mut slot: Slot, rx: &Mutex<Receiver<Prepared>>) -> Slot {
    loop {
        let next = rx.lock().unwrap_or_else(|p| p.into_inner()).recv();
        let Ok(p) = next else { return slot };
        if let Err(e) = slot.render(s, &p) {
            eprintln!("reyes render: frame {} (on {}): {e}", p.number, slot.name);
            (s.failed.lock().unwrap_or_else(|p| p.into_inner()))
                .push(format!("frame {}", p.number));
        }
    }
}

/// Renders one frame split into buckets over every device (with --runs N > 1: after a
/// warm-up frame and the devices' clock warm-up, N times, each timed) and writes its outputs.
fn split(s: &Shared, slots: &mut [Slot], p: &Prepared) -> Result<(), CliError> {
    let a = s.a;
    // The renderers are compiled on every device at once.
    let need = p.data.features();
    std::thread::scope(|sc| {
        let made: Vec<_> = (slots.iter_mut())
            .map(|slot| sc.spawn(move || slot.renderer(a, need).map(|_| ())))
            .collect();
        made.into_iter()
            .map(|h| h.join().unwrap_or_else(|p| std::panic::resume_unwind(p)))
            .collect::<Result<Vec<()>, CliError>>()
    })?;
    let devs: Vec<(&str, &scheduler::Gpu, &GpuRenderer)> = (slots.iter())
        .map(|s| {
            let r = &s.renderer.as_ref().expect("made above").0;
            (s.name.as_str(), &s.device.gpu, r)
        })
        .collect();
    if a.runs > 1 {
        devices::render_split(&devs, &p.data)?;
        std::thread::scope(|sc| {
            let raised: Vec<_> = (devs.iter())
                .map(|d| {
                    sc.spawn(|| scheduler::clocks::raise_clocks(d.1, reyes::gpu_render::WARM_UP))
                })
                .collect();
            raised
                .into_iter()
                .map(|h| h.join().unwrap_or_else(|p| std::panic::resume_unwind(p)))
                .collect::<Result<Vec<()>, _>>()
        })?;
    }
    s.bar.inc_length(a.runs as u64);
    let (mut times, mut last) = (Vec::new(), None);
    for i in 0..a.runs {
        let f = devices::render_split(&devs, &p.data)?;
        s.bar.inc(1);
        let g = devices::gpu_ms(&f.frame);
        if a.runs > 1 {
            let gs = g.map_or("n/a".into(), |g| format!("{g:.3}"));
            let w = f.frame.wall_ms;
            reyes_cli::progress::note(format!(
                "run {i}: GPU {gs} ms (all devices), wall {w:.2} ms"
            ));
        }
        times.push((g, f.frame.wall_ms));
        last = Some(f);
    }
    let last = last.expect("at least one run");
    let stats: Vec<DeviceStats> = (last.shares.iter().enumerate())
        .map(|(slot, d)| DeviceStats {
            slot,
            device: d.device.clone(),
            frames: 1,
            buckets: d.buckets,
            gpu_ms: d.gpu_ms,
            wall_ms: d.wall_ms,
        })
        .collect();
    let adapter = (devs.iter().map(|d| d.1.adapter_name()))
        .collect::<Vec<_>>()
        .join(" + ");
    drop(devs);
    for (slot, d) in slots.iter_mut().zip(&last.shares) {
        slot.count(1, d.buckets, d.gpu_ms, d.wall_ms);
    }
    let f = (&p.scene, &p.file_warnings[..], &p.data);
    crate::write_frame(
        f,
        &p.outputs,
        last.frame,
        times,
        &adapter,
        s.reference,
        Some(stats),
    )
}
