//! The GPU context: adapter chosen from the environment (as wgpu's own tests do), the device with
//! the optional features the queues can use, and bounded waits.
//!
//! Environment: `WGPU_ADAPTER_NAME` (substring of the adapter name), `WGPU_BACKEND`
//! (e.g. `vulkan`), `WGPU_POWER_PREF`. No adapter is a loud error, never a silent skip.

use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use crate::error::RunError;

/// Most workgroups a dispatch may have along one dimension: WebGPU's (and wgpu's default)
/// `max_compute_workgroups_per_dimension`. Every grid this crate dispatches, directly or
/// through indirect arguments it plans on the device, stays within it.
pub const MAX_WORKGROUPS_PER_DIMENSION: u32 = 65_535;

/// How long any single wait for the GPU may last before the run is abandoned with an error.
/// Generous, because lavapipe on two cores is slow; a real GPU finishes in milliseconds.
pub const DEFAULT_GPU_TIMEOUT: Duration = Duration::from_secs(120);

/// Microseconds a wait polls before it blocks ([`Gpu::spin_wait`]); 0: none; unset: the
/// adapter's default ([`DEFAULT_SPIN_WAIT`] on a GPU, none on a CPU adapter).
pub const SPIN_WAIT_ENV: &str = "SCHED_SPIN_WAIT_US";

/// How long a wait polls before it blocks on a GPU unless [`SPIN_WAIT_ENV`] says otherwise.
/// Blocking at once costs a short run the wake-up of a blocked thread: on an H100 (driver
/// 580.159.04) the megakernel's tree and BFS runs of 0.08-1.03 GPU ms took 0.07-0.19 ms less
/// wall time polling first for up to 1 ms, and the host-driven multi-pass, which waits once a
/// round, 14-49% less (docs/results.md, 2026-12-05, seventh session). A wait that outlasts
/// the spin then blocks, so each wait costs a core for 1 ms at most.
pub const DEFAULT_SPIN_WAIT: Duration = Duration::from_millis(1);

/// The spin of [`SPIN_WAIT_ENV`], else `default`; a value that is not a count of
/// microseconds is reported and the default kept.
fn spin_wait_from_env(default: Duration) -> Duration {
    let Ok(v) = std::env::var(SPIN_WAIT_ENV) else {
        return default;
    };
    match v.trim().parse() {
        Ok(us) => Duration::from_micros(us),
        Err(_) => {
            log::warn!(
                "{SPIN_WAIT_ENV}={v:?} is not a count of microseconds: the default, {} us",
                default.as_micros()
            );
            default
        }
    }
}

/// wgpu's environment variable for its validation of indirect calls ([`instance_flags`]).
pub const INDIRECT_VALIDATION_ENV: &str = "WGPU_VALIDATION_INDIRECT_CALL";

/// The value of [`INDIRECT_VALIDATION_ENV`], if set (and UTF-8).
fn indirect_env() -> Option<String> {
    std::env::var(INDIRECT_VALIDATION_ENV).ok()
}

/// Whether [`Gpu::instance_from_env`]'s instances validate indirect calls, as this process's
/// environment sets it ([`instance_flags`]): what a benchmark record says of its runs.
pub fn indirect_validation() -> bool {
    instance_flags(indirect_env().as_deref())
        .contains(wgpu::InstanceFlags::VALIDATION_INDIRECT_CALL)
}

/// The instance flags of [`Gpu::instance_from_env`]: wgpu's defaults as its `WGPU_*`
/// environment variables change them, but with `VALIDATION_INDIRECT_CALL` only where
/// `indirect_env`, the value of [`INDIRECT_VALIDATION_ENV`], asks for it as wgpu reads such a
/// variable (set to anything but `0`); unset, it is off.
///
/// That validation precedes every indirect dispatch with a one-thread dispatch of wgpu's own
/// (gfx-rs/wgpu#6567), one more dispatch and barrier per round of the device-driven
/// multi-pass: on the H200 its fused rounds took 7-18% longer with it (docs/results.md,
/// 2026-12-02, "fused rounds"). It guards against arguments past
/// `max_compute_workgroups_per_dimension` (and, for draws, ranges past the bound vertex and
/// index buffers and a first instance without `INDIRECT_FIRST_INSTANCE`), and on D3D12 it is
/// what fills `@builtin(num_workgroups)` of an indirect dispatch and adds the first vertex and
/// instance to `vertex_index` and `instance_index` of an indirect draw. Every indirect call in
/// this workspace is safe without it: each sizes its grid within the limit on the device (the
/// multi-pass's plan, the frontier BFS's plan, the raster peer's tiles), none reads
/// `num_workgroups`, and the raster peer's indexed draw covers only the indices it wrote, from
/// first index, base vertex and first instance 0 (docs/scheduler.md 5.1). A program that
/// records its own indirect calls on a [`Gpu`]'s device must keep the same rules, or set
/// `WGPU_VALIDATION_INDIRECT_CALL=1`.
pub fn instance_flags(indirect_env: Option<&str>) -> wgpu::InstanceFlags {
    let mut flags = wgpu::InstanceFlags::from_env_or_default();
    flags.set(
        wgpu::InstanceFlags::VALIDATION_INDIRECT_CALL,
        indirect_env.is_some_and(|v| v != "0"),
    );
    flags
}

/// An adapter, its device and queue, and what they can do.
pub struct Gpu {
    /// The adapter the device was opened on.
    pub adapter: wgpu::Adapter,
    /// The device every buffer and pipeline of the scheduler lives on.
    pub device: wgpu::Device,
    /// The device's queue.
    pub queue: wgpu::Queue,
    /// The adapter's name, backend and type.
    pub info: wgpu::AdapterInfo,
    /// `@coherent` storage buffers are available, so queue payloads may use plain loads/stores.
    /// Without it the queue moves payload words with atomic loads/stores (always coherent).
    /// Clearing it before a scheduler is built forces that path (the tests do; wgpu's Vulkan
    /// backend reports the feature on every device).
    pub coherent: bool,
    /// Timestamp queries at pass boundaries are available: runs report GPU time.
    pub timestamps: bool,
    /// Subgroup operations (wgpu's `SUBGROUP`) are available: the megakernel aggregates its
    /// enqueue tickets per subgroup (`MegakernelConfig::subgroups`).
    pub subgroups: bool,
    /// Bound of every wait for the GPU ([`DEFAULT_GPU_TIMEOUT`] unless changed): a wait that
    /// runs out is a [`RunError::Timeout`].
    pub timeout: Duration,
    /// How long a wait polls the device before it blocks ([`SPIN_WAIT_ENV`], else
    /// [`DEFAULT_SPIN_WAIT`] on a GPU and zero, blocking at once, on a CPU adapter). Polling
    /// costs a CPU core for that long but sees the work finish without the wake-up of a
    /// blocked thread, which matters for runs of well under a millisecond; on a CPU adapter it
    /// would take a core from the work it waits for.
    pub spin_wait: Duration,
    /// wgpu errors not captured by an error scope (validation, out of memory), in order. wgpu's
    /// default handler panics; this device records them instead and [`Gpu::wait`] reports the
    /// first as [`RunError::Device`], so a bad dispatch is an error of the run, never a panic.
    uncaptured: Arc<Mutex<Vec<String>>>,
    /// Every loop of every module compiled on this device ends by itself ([`Gpu::trust_loops`]).
    loops_trusted: bool,
    /// Submissions made through [`Gpu::submit`] ([`Gpu::submissions`]).
    submitted: AtomicU64,
}

impl Gpu {
    /// Opens the adapter named by the environment, or the default one. Errors:
    /// [`RunError::NoAdapter`], with what to install, when there is none.
    pub fn from_env() -> Result<Gpu, RunError> {
        Self::from_env_requiring(wgpu::Features::empty())
    }

    /// Like [`Gpu::from_env`], for programs whose user code needs more `features` (e.g. 64-bit
    /// atomics); an adapter without them is an error that names them.
    pub fn from_env_requiring(features: wgpu::Features) -> Result<Gpu, RunError> {
        Self::open(&Self::instance_from_env(), None, features)
    }

    /// The wgpu instance [`Gpu::from_env`] opens its adapter from: the backends of
    /// `WGPU_BACKEND`, else the primary ones, and the flags of [`instance_flags`] (wgpu's,
    /// without its indirect-call validation unless `WGPU_VALIDATION_INDIRECT_CALL` asks for
    /// it). A window's surface is made from it before [`Gpu::from_env_for_surface`].
    pub fn instance_from_env() -> wgpu::Instance {
        wgpu::Instance::new(wgpu::InstanceDescriptor {
            backends: wgpu::Backends::from_env().unwrap_or(wgpu::Backends::PRIMARY),
            flags: instance_flags(indirect_env().as_deref()),
            ..wgpu::InstanceDescriptor::new_without_display_handle()
        })
    }

    /// Like [`Gpu::from_env_requiring`], on an adapter of `instance` that can present to
    /// `surface` (made from the same instance). Errors: [`RunError::NoAdapter`] when no
    /// adapter both presents to the surface and has `features`.
    pub fn from_env_for_surface(
        instance: &wgpu::Instance,
        surface: &wgpu::Surface<'_>,
        features: wgpu::Features,
    ) -> Result<Gpu, RunError> {
        Self::open(instance, Some(surface), features)
    }

    fn open(
        instance: &wgpu::Instance,
        surface: Option<&wgpu::Surface<'_>>,
        features: wgpu::Features,
    ) -> Result<Gpu, RunError> {
        let adapter = pollster::block_on(wgpu::util::initialize_adapter_from_env_or_default(
            instance, surface,
        ))
        .map_err(|e| {
            RunError::NoAdapter(format!(
                "{e}{}. Install a Vulkan driver (on Debian: `apt-get install -y \
                 mesa-vulkan-drivers` for lavapipe) or set WGPU_ADAPTER_NAME / WGPU_BACKEND",
                if surface.is_some() {
                    " (an adapter that can present to the window)"
                } else {
                    ""
                }
            ))
        })?;
        Self::from_adapter(adapter, features)
    }

    /// Opens a device on `adapter` with `required` features plus those the scheduler benefits
    /// from when present (`MEMORY_DECORATION_COHERENT`, `TIMESTAMP_QUERY`,
    /// `TEXTURE_ADAPTER_SPECIFIC_FORMAT_FEATURES`, `SUBGROUP`), the adapter's
    /// storage and workgroup-memory limits, and 256 invocations per workgroup. Errors:
    /// [`RunError::NoAdapter`] when the adapter lacks `required` or `request_device` fails.
    pub fn from_adapter(adapter: wgpu::Adapter, required: wgpu::Features) -> Result<Gpu, RunError> {
        let info = adapter.get_info();
        let available = adapter.features();
        if !available.contains(required) {
            return Err(RunError::NoAdapter(format!(
                "{} lacks the features {:?}",
                info.name,
                required - available
            )));
        }
        // TEXTURE_ADAPTER_SPECIFIC_FORMAT_FEATURES: render targets with the sample counts the
        // adapter supports beyond WebGPU's 1 and 4 (reyes's raster peer: 8 or 16 MSAA samples).
        let wanted = wgpu::Features::MEMORY_DECORATION_COHERENT
            | wgpu::Features::TIMESTAMP_QUERY
            | wgpu::Features::TEXTURE_ADAPTER_SPECIFIC_FORMAT_FEATURES
            | wgpu::Features::SUBGROUP;
        let features = (available & wanted) | required;
        let alimits = adapter.limits();
        let limits = wgpu::Limits {
            max_storage_buffer_binding_size: alimits.max_storage_buffer_binding_size,
            max_buffer_size: alimits.max_buffer_size,
            max_storage_buffers_per_shader_stage: alimits
                .max_storage_buffers_per_shader_stage
                .min(16),
            max_compute_workgroup_storage_size: alimits.max_compute_workgroup_storage_size,
            // Up to 1,024 (the megakernel's `workgroup_size`); other kernels use 256.
            max_compute_invocations_per_workgroup: alimits
                .max_compute_invocations_per_workgroup
                .clamp(256, 1024),
            max_compute_workgroup_size_x: alimits.max_compute_workgroup_size_x.clamp(256, 1024),
            ..wgpu::Limits::default()
        };
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("scheduler"),
            required_features: features,
            required_limits: limits,
            ..Default::default()
        }))
        .map_err(|e| RunError::NoAdapter(format!("request_device on {}: {e}", info.name)))?;
        let uncaptured = Arc::new(Mutex::new(Vec::new()));
        let sink = uncaptured.clone();
        device.on_uncaptured_error(Arc::new(move |e: wgpu::Error| {
            sink.lock()
                .unwrap_or_else(|p| p.into_inner())
                .push(e.to_string());
        }));
        let mut gpu = Gpu {
            uncaptured,
            coherent: features.contains(wgpu::Features::MEMORY_DECORATION_COHERENT),
            timestamps: features.contains(wgpu::Features::TIMESTAMP_QUERY),
            subgroups: features.contains(wgpu::Features::SUBGROUP),
            adapter,
            device,
            queue,
            info,
            timeout: DEFAULT_GPU_TIMEOUT,
            spin_wait: Duration::ZERO,
            loops_trusted: false,
            submitted: AtomicU64::new(0),
        };
        // A CPU adapter's work needs the cores a spin would take.
        gpu.spin_wait = spin_wait_from_env(match gpu.is_cpu_adapter() {
            true => Duration::ZERO,
            false => DEFAULT_SPIN_WAIT,
        });
        log::debug!(
            "{}: waits poll for {} us before they block",
            gpu.info.name,
            gpu.spin_wait.as_micros()
        );
        Ok(gpu)
    }

    /// Finishes `enc` and submits it to the queue, counted in [`Gpu::submissions`]. Every
    /// submission of the scheduler, its workloads and the renderer goes through here, so that
    /// a test can hold a run to the submissions it should cost (each costs host time and a gap
    /// on the device).
    pub fn submit(&self, enc: wgpu::CommandEncoder) -> wgpu::SubmissionIndex {
        self.submitted.fetch_add(1, Ordering::Relaxed);
        self.queue.submit([enc.finish()])
    }

    /// Submissions made through [`Gpu::submit`] since the device was opened.
    pub fn submissions(&self) -> u64 {
        self.submitted.load(Ordering::Relaxed)
    }

    /// A one-line description: name and backend.
    pub fn adapter_name(&self) -> String {
        format!("{} ({:?})", self.info.name, self.info.backend)
    }

    /// Waits for all submitted work, bounded by `self.timeout`. A wgpu error recorded since
    /// the last wait (see [`Gpu::take_error`]) is returned as [`RunError::Device`].
    pub fn wait(&self, what: &str) -> Result<(), RunError> {
        self.wait_for(None, what)
    }

    /// [`Gpu::wait`] for one submission (`None`: all submitted work), bounded by
    /// `self.timeout`; `what` names the work in the error.
    pub fn wait_for(
        &self,
        submission: Option<wgpu::SubmissionIndex>,
        what: &str,
    ) -> Result<(), RunError> {
        let begin = Instant::now();
        let mut polled = Err(wgpu::PollError::Timeout);
        // Poll (a wait of no time) while the spin lasts, then block for the rest.
        while !self.spin_wait.is_zero() {
            polled = self.device.poll(wgpu::PollType::Wait {
                submission_index: submission.clone(),
                timeout: Some(Duration::ZERO),
            });
            if !matches!(polled, Err(wgpu::PollError::Timeout)) || begin.elapsed() >= self.spin_wait
            {
                break;
            }
            std::hint::spin_loop();
        }
        if matches!(polled, Err(wgpu::PollError::Timeout)) {
            polled = self.device.poll(wgpu::PollType::Wait {
                submission_index: submission,
                timeout: Some(self.timeout.saturating_sub(begin.elapsed())),
            });
        }
        if let Some(e) = self.take_error() {
            return Err(RunError::Device(format!("{what}: {e}")));
        }
        match polled {
            Ok(_) => Ok(()),
            Err(wgpu::PollError::Timeout) => Err(RunError::Timeout {
                what: what.to_string(),
                seconds: self.timeout.as_secs_f64(),
            }),
            Err(e) => Err(RunError::Device(format!("{what}: {e}"))),
        }
    }

    /// The first wgpu error recorded since the last call (the rest are dropped with it: they
    /// usually follow from the first).
    pub fn take_error(&self) -> Option<String> {
        let mut errors = self.uncaptured.lock().unwrap_or_else(|p| p.into_inner());
        let first = errors.first().cloned();
        errors.clear();
        first
    }

    /// Copies `size` bytes of `src` (which needs `COPY_SRC` usage) from byte `offset` to the
    /// host; one bounded wait. Errors: [`RunError::Timeout`], [`RunError::Device`].
    pub fn read_buffer(
        &self,
        src: &wgpu::Buffer,
        offset: u64,
        size: u64,
    ) -> Result<Vec<u8>, RunError> {
        if size == 0 {
            return Ok(Vec::new());
        }
        let staging = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("readback"),
            size,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let mut enc = self.device.create_command_encoder(&Default::default());
        enc.copy_buffer_to_buffer(src, offset, &staging, 0, size);
        self.submit(enc);
        let slice = staging.slice(..);
        let (tx, rx) = std::sync::mpsc::channel();
        slice.map_async(wgpu::MapMode::Read, move |r| {
            let _ = tx.send(r);
        });
        self.wait("reading a buffer back")?;
        match rx.recv_timeout(Duration::from_secs(1)) {
            Ok(Ok(())) => {}
            Ok(Err(e)) => return Err(RunError::Device(format!("map_async: {e}"))),
            Err(_) => return Err(RunError::Device("buffer map never completed".into())),
        }
        let data = slice
            .get_mapped_range()
            .map_err(|e| RunError::Device(format!("mapped range: {e}")))?
            .to_vec();
        staging.unmap();
        Ok(data)
    }

    /// Reads `count` u32 words starting at word `offset` (as [`Gpu::read_buffer`]).
    pub fn read_words(
        &self,
        src: &wgpu::Buffer,
        offset: u64,
        count: u64,
    ) -> Result<Vec<u32>, RunError> {
        let bytes = self.read_buffer(src, offset * 4, count * 4)?;
        Ok(bytemuck::pod_collect_to_vec(&bytes))
    }

    /// The largest storage buffer binding this device allows, in bytes.
    pub fn max_binding_bytes(&self) -> u64 {
        let l = self.device.limits();
        l.max_storage_buffer_binding_size.min(l.max_buffer_size)
    }

    /// A storage buffer of `words` u32 words (at least one), zeroed, with `STORAGE | COPY_DST |
    /// COPY_SRC` usage. A size beyond the device's limits is a [`RunError::Device`] naming the
    /// buffer, not a panic in wgpu's error handler.
    pub fn storage_buffer(&self, label: &str, words: u64) -> Result<wgpu::Buffer, RunError> {
        let bytes = words.max(1) * 4;
        if bytes > self.max_binding_bytes() {
            return Err(RunError::Device(format!(
                "buffer `{label}` needs {bytes} bytes, more than this device's storage binding \
                 limit of {} bytes",
                self.max_binding_bytes()
            )));
        }
        Ok(self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size: words.max(1) * 4,
            usage: wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::COPY_DST
                | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        }))
    }

    /// A storage buffer holding `items`, sized for at least one `T`: a binding of an array of
    /// `T` must hold one element even when the data is empty (an empty scene, a bucket no
    /// patch reaches), or wgpu rejects the dispatch.
    pub fn upload<T: bytemuck::Pod>(
        &self,
        label: &str,
        items: &[T],
    ) -> Result<wgpu::Buffer, RunError> {
        let bytes = (items.len().max(1) * size_of::<T>()) as u64;
        let buffer = self.storage_buffer(label, bytes.div_ceil(4))?;
        if !items.is_empty() {
            self.queue
                .write_buffer(&buffer, 0, bytemuck::cast_slice(items));
        }
        Ok(buffer)
    }

    /// A bind group of whole storage buffers at bindings 0, 1, 2, ... in order.
    pub fn bind_buffers(
        &self,
        label: &str,
        layout: &wgpu::BindGroupLayout,
        buffers: &[&wgpu::Buffer],
    ) -> wgpu::BindGroup {
        bind_buffers(&self.device, label, layout, buffers)
    }

    /// A bind group of whole storage buffers at the given bindings (`(binding, buffer)`), for
    /// layouts whose bindings are not 0, 1, 2, ... in order.
    pub fn bind_buffers_at(
        &self,
        label: &str,
        layout: &wgpu::BindGroupLayout,
        buffers: &[(u32, &wgpu::Buffer)],
    ) -> wgpu::BindGroup {
        bind_buffers_at(&self.device, label, layout, buffers)
    }

    /// Compiles WGSL, turning a validation error into a `RunError` that carries the message
    /// (naga's error names the line), instead of a panic in wgpu's error handler. Naga's loop
    /// bounding is left out where [`Gpu::bounds_loops`] says so.
    #[allow(
        unsafe_code,
        reason = "a shader module without naga's loop bounding, where the driver bounds every loop itself or the owner of the device vouched that every loop ends (Gpu::trust_loops)"
    )]
    pub fn shader(&self, label: &str, source: &str) -> Result<wgpu::ShaderModule, RunError> {
        let start = std::time::Instant::now();
        crate::wgsl::validate(label, source)?;
        dump_wgsl(label, source);
        let desc = wgpu::ShaderModuleDescriptor {
            label: Some(label),
            source: wgpu::ShaderSource::Wgsl(source.into()),
        };
        let bounded = self.bounds_loops();
        let module = if bounded {
            self.device.create_shader_module(desc)
        } else {
            // SAFETY: wgpu requires that no loop of the shader runs forever once naga's bounding
            // is gone. Either the driver stops every loop itself (`driver_bounds_loops`) or
            // the caller of the unsafe `trust_loops` took on that every loop ends. Bounds
            // checks stay (`checked()`).
            unsafe {
                self.device.create_shader_module_trusted(
                    desc,
                    wgpu::ShaderRuntimeChecks {
                        force_loop_bounding: false,
                        ..wgpu::ShaderRuntimeChecks::checked()
                    },
                )
            }
        };
        log::debug!(
            "shader module `{label}` ({} bytes of WGSL, naga loop bounding {}): {:.1} ms",
            source.len(),
            if bounded { "on" } else { "off" },
            start.elapsed().as_secs_f64() * 1e3
        );
        Ok(module)
    }

    /// Leaves naga's loop bounding out of every module this device compiles from now on (unless
    /// `SCHED_LOOP_BOUNDING=on`, [`LOOP_BOUNDING_ENV`]). Call it right after opening the device,
    /// before building schedulers on it. wgpu adds the bounding on every backend: a 64-bit
    /// counter and a break in every loop, which on an H200 makes a Reyes frame about 1.6 times
    /// slower (Killeroo at 1920x1080, megakernel 1.557 -> 0.981 ms, host-driven multi-pass
    /// 1.405 -> 0.812 ms; docs/results.md, 2026-12-03; other GPUs not measured) and does not
    /// stop a hang: a loop that runs on is cut only after 2^64 trips. What it does prevent is
    /// the driver's compiler treating a loop that never ends as unreachable code.
    ///
    /// # Safety
    /// Every loop of every WGSL module compiled on this device, through [`Gpu::shader`] and
    /// [`Gpu::compute_pipeline`], the scheduler's generated modules with the user's procedure
    /// bodies included, must end on every input. A trip count read from a buffer is fine when
    /// the loop's own test ends it (`for (var i = 0u; i < n; i++)`); a loop that waits for
    /// another workgroup (a spin on an atomic) must also give up after a bounded number of
    /// trips, as the scheduler's waits do, since nothing guarantees that the workgroup it waits
    /// for is running. The scheduler's own loops end (the megakernel's persistent loop at its
    /// `max_iters` parameter, its waits at the spin limit, every other loop at a queue count, a
    /// word count or a constant); so do reyes's shaders' (docs/scheduler.md 4). A procedure body
    /// that could loop forever would hang the megakernel either way; without the bounding it is
    /// also undefined behaviour.
    #[allow(
        unsafe_code,
        reason = "the caller vouches that every loop ends; see # Safety"
    )]
    pub unsafe fn trust_loops(&mut self) {
        self.loops_trusted = true;
    }

    /// True when [`Gpu::shader`] keeps naga's loop bounding (`ShaderRuntimeChecks::
    /// force_loop_bounding`, which wgpu turns on for every backend but lavapipe's compiler
    /// makes moot): unless the driver bounds every loop itself ([`Gpu::driver_bounds_loops`]),
    /// or the loops are trusted ([`Gpu::trust_loops`]) and `SCHED_LOOP_BOUNDING` is not `on`.
    pub fn bounds_loops(&self) -> bool {
        let forced = std::env::var(LOOP_BOUNDING_ENV).is_ok_and(|v| v == "on");
        !(self.driver_bounds_loops() || (self.loops_trusted && !forced))
    }

    /// True when the driver bounds every loop itself, which makes naga's loop bounding
    /// (`wgpu::ShaderRuntimeChecks::force_loop_bounding`, a 64-bit counter and a break added to
    /// every loop) redundant, so [`Gpu::shader`] leaves it out: lavapipe (adapter name
    /// `llvmpipe`, Vulkan), whose LLVM code generator (gallivm) stops any loop after 65,535
    /// iterations. There naga's bounding makes lavapipe's SPIR-V to NIR step, on every run,
    /// about 2.5 times slower (the Reyes megakernel's pipeline: 1.9 s against 0.6-0.8 s), for
    /// frames no faster (docs/scheduler.md, "Start-up on lavapipe").
    pub fn driver_bounds_loops(&self) -> bool {
        self.info.backend == wgpu::Backend::Vulkan && self.is_lavapipe()
    }

    /// A compute pipeline of one entry point of a WGSL source, its layout derived from the
    /// shader (bind group 0 from `get_bind_group_layout(0)`).
    pub fn compute_pipeline(
        &self,
        label: &str,
        source: &str,
        entry: &str,
    ) -> Result<wgpu::ComputePipeline, RunError> {
        let module = self.shader(label, source)?;
        let start = std::time::Instant::now();
        let p = self
            .device
            .create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(label),
                layout: None,
                module: &module,
                entry_point: Some(entry),
                compilation_options: Default::default(),
                cache: None,
            });
        log_pipeline_time(label, entry, start);
        Ok(p)
    }
}

/// Logs (debug) how long creating the pipeline of `entry` in module `label` took since `start`:
/// WGSL to SPIR-V and the driver's own compile (on lavapipe, SPIR-V to NIR; the NIR to LLVM
/// step may wait for the first dispatch and Mesa's shader cache).
pub(crate) fn log_pipeline_time(label: &str, entry: &str, start: std::time::Instant) {
    log::debug!(
        "pipeline `{label}::{entry}`: {:.1} ms",
        start.elapsed().as_secs_f64() * 1e3
    );
}

/// A bind group of `buffers`, whole, at bindings 0, 1, 2, … (see [`Gpu::bind_buffers`]).
pub(crate) fn bind_buffers(
    device: &wgpu::Device,
    label: &str,
    layout: &wgpu::BindGroupLayout,
    buffers: &[&wgpu::Buffer],
) -> wgpu::BindGroup {
    let at: Vec<(u32, &wgpu::Buffer)> = (0..).zip(buffers.iter().copied()).collect();
    bind_buffers_at(device, label, layout, &at)
}

/// A bind group of whole buffers at the given bindings (see [`Gpu::bind_buffers_at`]).
pub(crate) fn bind_buffers_at(
    device: &wgpu::Device,
    label: &str,
    layout: &wgpu::BindGroupLayout,
    buffers: &[(u32, &wgpu::Buffer)],
) -> wgpu::BindGroup {
    let entries: Vec<_> = buffers
        .iter()
        .map(|&(binding, b)| wgpu::BindGroupEntry {
            binding,
            resource: b.as_entire_binding(),
        })
        .collect();
    device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some(label),
        layout,
        entries: &entries,
    })
}

/// Adapter quirks, named once: callers ask these instead of testing the adapter's name or type.
impl Gpu {
    /// True on an adapter that is a CPU (software Vulkan such as lavapipe, WARP): it has no
    /// clocks to raise, runs a megakernel's persistent workgroups one per hardware thread, and
    /// shares its cores with the host.
    pub fn is_cpu_adapter(&self) -> bool {
        self.info.device_type == wgpu::DeviceType::Cpu
    }

    /// True on Mesa's LLVM software rasterizer (adapter name `llvmpipe`: lavapipe under
    /// Vulkan), whose code generator ends every loop of an invocation after 65,535 iterations
    /// in total over an outermost loop and what it nests: long-running shaders relaunch
    /// instead (see [`Gpu::driver_bounds_loops`] for the Vulkan-only consequence).
    pub fn is_lavapipe(&self) -> bool {
        self.info.name.contains("llvmpipe")
    }
}

/// Environment variable that, set to `on`, keeps naga's loop bounding in the modules of a device
/// whose loops are trusted ([`Gpu::trust_loops`]): the A/B switch of its measurements. Other
/// values, and unset, leave the choice to `trust_loops`; lavapipe never gets the bounding
/// ([`Gpu::driver_bounds_loops`]).
pub const LOOP_BOUNDING_ENV: &str = "SCHED_LOOP_BOUNDING";

/// Environment variable naming a folder where [`Gpu::shader`] writes every WGSL module it
/// compiles, as `LABEL.wgsl`: the generated megakernel and multi-pass sources, to read or to
/// hand to `pipestats` (the driver's register and instruction counts, docs/scheduler.md 4).
pub const DUMP_WGSL_ENV: &str = "SCHED_DUMP_WGSL";

/// Writes `source` to `$SCHED_DUMP_WGSL/LABEL.wgsl` when the variable is set; a failed write is
/// logged, never fatal (the dump is a diagnostic).
fn dump_wgsl(label: &str, source: &str) {
    let Some(dir) = std::env::var_os(DUMP_WGSL_ENV) else {
        return;
    };
    let name: String = label
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect();
    let path = std::path::Path::new(&dir).join(format!("{name}.wgsl"));
    let written = std::fs::create_dir_all(&dir).and_then(|()| std::fs::write(&path, source));
    match written {
        Ok(()) => log::info!("shader module `{label}` written to {}", path.display()),
        Err(e) => log::warn!("{DUMP_WGSL_ENV}: could not write {}: {e}", path.display()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Without the variable the validation is off, `0` keeps it off, and any other value
    /// (wgpu's reading of its `WGPU_*` flags) turns it on; the other flags stay wgpu's.
    #[test]
    fn indirect_validation_is_off_unless_the_environment_asks() {
        let on = |env| instance_flags(env).contains(wgpu::InstanceFlags::VALIDATION_INDIRECT_CALL);
        assert!(!on(None));
        assert!(!on(Some("0")));
        assert!(on(Some("1")));
        assert!(on(Some("")));
        let others = !wgpu::InstanceFlags::VALIDATION_INDIRECT_CALL;
        assert_eq!(
            instance_flags(None) & others,
            wgpu::InstanceFlags::from_env_or_default() & others
        );
    }
}
