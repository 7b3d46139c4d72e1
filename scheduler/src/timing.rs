//! GPU time of compute passes from timestamp queries, where the adapter has them.

use crate::error::RunError;
use crate::gpu::Gpu;

/// Times passes one at a time: begin/end timestamps of a pass, resolved and read back with the
/// pass's other results. `total_ms` is `None` when the adapter has no timestamp queries.
pub struct PassTimer {
    set: Option<wgpu::QuerySet>,
    resolved: wgpu::Buffer,
    period_ns: f64,
    total_ns: f64,
}

impl PassTimer {
    pub fn new(gpu: &Gpu) -> PassTimer {
        let set = gpu.timestamps.then(|| {
            gpu.device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("pass timer"),
                ty: wgpu::QueryType::Timestamp,
                count: 2,
            })
        });
        let resolved = gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("timestamps"),
            size: 16,
            usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        PassTimer {
            set,
            resolved,
            period_ns: gpu.queue.get_timestamp_period() as f64,
            total_ns: 0.0,
        }
    }

    pub fn writes(&self) -> Option<wgpu::ComputePassTimestampWrites<'_>> {
        self.set
            .as_ref()
            .map(|set| wgpu::ComputePassTimestampWrites {
                query_set: set,
                beginning_of_pass_write_index: Some(0),
                end_of_pass_write_index: Some(1),
            })
    }

    /// Records the resolve after the timed pass, in the same encoder.
    pub fn resolve(&self, enc: &mut wgpu::CommandEncoder) {
        if let Some(set) = &self.set {
            enc.resolve_query_set(set, 0..2, &self.resolved, 0);
        }
    }

    /// Reads the last pass's time back and adds it to the total.
    pub fn collect(&mut self, gpu: &Gpu) -> Result<(), RunError> {
        if self.set.is_some() {
            let t: Vec<u64> =
                bytemuck::cast_slice(&gpu.read_buffer(&self.resolved, 0, 16)?).to_vec();
            self.total_ns += t[1].saturating_sub(t[0]) as f64 * self.period_ns;
        }
        Ok(())
    }

    pub fn total_ms(&self) -> Option<f64> {
        self.set.as_ref().map(|_| self.total_ns / 1e6)
    }
}
