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

/// Keeps every compute unit busy for about `duration` (several submissions, each waited
/// for). Does nothing on CPU adapters (lavapipe), which have no clocks to raise.
pub fn raise_clocks(gpu: &Gpu, duration: Duration) -> Result<(), RunError> {
    if gpu.is_cpu_adapter() {
        return Ok(());
    }
    let pipeline = gpu.compute_pipeline("raise clocks", BUSY, "busy")?;
    let sink = gpu.storage_buffer("raise clocks sink", 1)?;
    let bind = gpu.bind_buffers("raise clocks", &pipeline.get_bind_group_layout(0), &[&sink]);
    let start = Instant::now();
    while start.elapsed() < duration {
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        {
            let mut pass = enc.begin_compute_pass(&Default::default());
            pass.set_pipeline(&pipeline);
            pass.set_bind_group(0, &bind, &[]);
            pass.dispatch_workgroups(4096, 1, 1);
        }
        gpu.submit(enc);
        gpu.wait("raising the GPU clocks")?;
    }
    Ok(())
}
