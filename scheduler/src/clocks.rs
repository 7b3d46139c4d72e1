//! Raising a GPU's clocks before timing. A GPU whose work comes in short bursts between host
//! work does not raise its clocks: on the H100, frames of 2 ms every 30 ms ran at the 345 MHz
//! idle clock (5.7x below the 1980 MHz boost) whenever the process had let the GPU idle for a
//! few seconds, e.g. while `reyes sweep` rendered its CPU reference (sampled with nvidia-smi).
//! A few hundred milliseconds of full load brings the boost clock, which then holds for
//! seconds; timings taken right after are the GPU's, not its power governor's.

use crate::error::RunError;
use crate::gpu::Gpu;
use std::time::{Duration, Instant};

const BUSY: &str = r#"
@group(0) @binding(0) var<storage, read_write> sink: array<f32>;

@compute @workgroup_size(256)
fn busy(@builtin(global_invocation_id) id: vec3<u32>) {
    var x = f32(id.x) * 1.0e-6;
    for (var i = 0u; i < 20000u; i++) { x = fma(x, 0.999999, 1.0e-6); }
    // Never true in practice, but the compiler cannot know: the loop must run.
    if x == 12345.0 { sink[0] = x; }
}
"#;

/// How long a raised boost clock is trusted without full load. On the H100 (2026-12-05, sixth
/// session, nvidia-smi every 100 ms) the clock held 1980 MHz for 1.7-3.7 s of idle after full
/// load, then fell to 345 MHz within 1.5 s; bursts of 20 ms of load every 300 ms did not hold
/// it (schedbench's Killeroo runs, each followed by its check against the CPU twin).
pub const HOLD: Duration = Duration::from_millis(1000);

/// Full load that brings the boost clock back once [`HOLD`] has passed: the clock went from
/// 405 to 1980 MHz within 200 ms of full load on the H100 (same samples).
pub const RAISE_AGAIN: Duration = Duration::from_millis(250);

/// Keeps a GPU's clocks raised over a series of timed runs with host work between them: full
/// load for a warm-up, then again for [`RAISE_AGAIN`] before any run that starts more than
/// [`HOLD`] after the last load. The busy pipeline is compiled once. Does nothing on CPU
/// adapters (lavapipe), which have no clocks to raise.
pub struct ClockKeeper<'a> {
    gpu: &'a Gpu,
    busy: Option<(wgpu::ComputePipeline, wgpu::BindGroup)>,
    raised: Instant,
}

impl<'a> ClockKeeper<'a> {
    /// Compiles the busy kernel and loads every compute unit for `warm_up`. Errors: the
    /// kernel cannot be built, or a wait for it runs out ([`RunError`]).
    pub fn new(gpu: &'a Gpu, warm_up: Duration) -> Result<Self, RunError> {
        let busy = if gpu.is_cpu_adapter() {
            None
        } else {
            let pipeline = gpu.compute_pipeline("raise clocks", BUSY, "busy")?;
            let sink = gpu.storage_buffer("raise clocks sink", 1)?;
            let layout = pipeline.get_bind_group_layout(0);
            let bind = gpu.bind_buffers("raise clocks", &layout, &[&sink]);
            Some((pipeline, bind))
        };
        let mut k = ClockKeeper {
            gpu,
            busy,
            raised: Instant::now(),
        };
        k.load(warm_up)?;
        Ok(k)
    }

    /// Before a timed run: loads the GPU for [`RAISE_AGAIN`] when more than [`HOLD`] has
    /// passed since the last load, and says whether it did. Errors as [`ClockKeeper::new`].
    pub fn keep_up(&mut self) -> Result<bool, RunError> {
        if self.busy.is_none() || self.raised.elapsed() <= HOLD {
            return Ok(false);
        }
        self.load(RAISE_AGAIN)?;
        Ok(true)
    }

    /// Keeps every compute unit busy for about `duration` (several submissions, each waited
    /// for).
    fn load(&mut self, duration: Duration) -> Result<(), RunError> {
        let Some((pipeline, bind)) = &self.busy else {
            return Ok(());
        };
        let start = Instant::now();
        while start.elapsed() < duration {
            let mut enc = self.gpu.device.create_command_encoder(&Default::default());
            {
                let mut pass = enc.begin_compute_pass(&Default::default());
                pass.set_pipeline(pipeline);
                pass.set_bind_group(0, bind, &[]);
                pass.dispatch_workgroups(4096, 1, 1);
            }
            self.gpu.submit(enc);
            self.gpu.wait("raising the GPU clocks")?;
        }
        self.raised = Instant::now();
        Ok(())
    }
}

/// Keeps every compute unit busy for about `duration` (several submissions, each waited
/// for). Does nothing on CPU adapters (lavapipe), which have no clocks to raise. Errors as
/// [`ClockKeeper::new`].
pub fn raise_clocks(gpu: &Gpu, duration: Duration) -> Result<(), RunError> {
    ClockKeeper::new(gpu, duration).map(|_| ())
}
