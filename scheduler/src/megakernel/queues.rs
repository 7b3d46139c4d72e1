//! A launch's device queues: the buffers of one queue layout (ctrl, slots, flags, outbox) and
//! the host's writes that start a launch from live items: the items and their flags' stamps,
//! ctrl, and the clearing of only those flags an earlier launch may have written
//! (`docs/scheduler.md` 2.1).

use std::borrow::Cow;

use super::Megakernel;
use super::layout::{self, *};
use crate::error::RunError;
use crate::gpu::Gpu;
use crate::queue_layout::QueueLayout;

/// Buffers of one queue layout.
pub(super) struct DeviceQueues {
    pub(super) layout: QueueLayout,
    /// The workgroups whose local areas (in `slots`) and outbox parts the buffers hold.
    pub(super) workgroups: u32,
    pub(super) ctrl: wgpu::Buffer,
    pub(super) slots: wgpu::Buffer,
    pub(super) flags: wgpu::Buffer,
    /// Per queue, how many of its first flags the launches so far may have left other than
    /// `EMPTY`: the highest reserve a launch ended with (every flag a launch writes, stamp or
    /// `CONSUMED`, is a ticket below it). The rest are still `EMPTY`, as wgpu zero-initializes
    /// new buffers, so an upload clears only these instead of the whole capacity.
    pub(super) dirty: Vec<u32>,
    /// Per-workgroup scratch; its size does not depend on the layout, so growth keeps it.
    pub(super) outbox: wgpu::Buffer,
    pub(super) bind: wgpu::BindGroup,
}

impl DeviceQueues {
    /// Notes what a launch on these buffers wrote, from its `ctrl` read back: its flags lie
    /// below each queue's final `Q_RESERVE` (tickets never pass the capacity), which the next
    /// upload clears (`dirty`).
    pub(super) fn launched(&mut self, ctrl: &[u32]) {
        for (q, dirty) in self.dirty.iter_mut().enumerate() {
            let reserve = ctrl[layout::q(q, Q_RESERVE)].min(self.layout.capacity[q]);
            *dirty = (*dirty).max(reserve);
        }
    }
}

impl Megakernel {
    /// New buffers for `layout` and `workgroups` (the outbox kept where given: growth keeps
    /// it), their params written and bind group made; every flag `EMPTY` (wgpu zero-initializes
    /// them). Errors: [`RunError::Device`] if a buffer cannot be made.
    pub(super) fn device_queues(
        &self,
        gpu: &Gpu,
        layout: QueueLayout,
        params: &[u32],
        workgroups: u32,
        outbox: Option<wgpu::Buffer>,
    ) -> Result<DeviceQueues, RunError> {
        let nq = self.program.queue_count();
        let ctrl = gpu.storage_buffer("ctrl", ctrl_words(nq) as u64)?;
        let slots_words = layout.total_words + self.local_area_words(workgroups);
        let slots = gpu.storage_buffer("slots", slots_words)?;
        let flags = gpu.storage_buffer("flags", layout.total_slots)?;
        let outbox = match outbox {
            Some(o) => o,
            None => gpu.storage_buffer("outbox", workgroups as u64 * self.outbox_stride as u64)?,
        };
        let params_buf = gpu.storage_buffer("params", params.len() as u64)?;
        gpu.queue
            .write_buffer(&params_buf, 0, bytemuck::cast_slice(params));
        let bind = self.kernels.bind_group0(
            gpu,
            &[
                (0, &ctrl),
                (1, &slots),
                (2, &flags),
                (3, &outbox),
                (4, &params_buf),
            ],
        );
        Ok(DeviceQueues {
            dirty: vec![0; layout.capacity.len()],
            layout,
            workgroups,
            ctrl,
            slots,
            flags,
            outbox,
            bind,
        })
    }

    /// Writes ctrl for a launch that starts with `counts[q]` seeds in the first slots of each
    /// queue: reserve, count, budget and peak at the seed count, pending their sum, all else 0.
    pub(super) fn write_ctrl(&self, gpu: &Gpu, ctrl_buf: &wgpu::Buffer, counts: &[u32]) {
        let nq = self.program.queue_count();
        let mut ctrl = vec![0u32; ctrl_words(nq)];
        for (q, &n) in counts.iter().enumerate() {
            for w in [Q_RESERVE, Q_COUNT, Q_BUDGET, Q_PEAK] {
                ctrl[layout::q(q, w)] = n;
            }
        }
        ctrl[g(nq, G_PENDING)] = counts.iter().sum();
        gpu.queue
            .write_buffer(ctrl_buf, 0, bytemuck::cast_slice(&ctrl));
    }

    /// Writes live items (per queue, words back to back) as the whole queue state of a launch,
    /// with no submission of its own: items, their flags' stamps and ctrl by queue writes (which
    /// land before the launch's submission), and the clearing of every other flag an earlier
    /// launch may have written (`DeviceQueues::dirty`) recorded in `enc`, the launch's encoder,
    /// on ranges disjoint from the stamps (so the two orders agree). Returns the flag words
    /// cleared.
    pub(super) fn upload(
        &self,
        gpu: &Gpu,
        dq: &mut DeviceQueues,
        live: &[Cow<[u32]>],
        enc: &mut wgpu::CommandEncoder,
    ) -> u64 {
        let mut cleared = 0;
        let mut counts = Vec::new();
        for (q, items) in live.iter().enumerate() {
            let n = (items.len() / dq.layout.words[q] as usize) as u32;
            counts.push(n);
            let base = dq.layout.flag_base[q] as u64;
            if n > 0 {
                (self.item_layout()).write_items(&gpu.queue, &dq.slots, &dq.layout, q, items);
                let f = vec![SEED_STAMP; n as usize];
                gpu.queue
                    .write_buffer(&dq.flags, base * 4, bytemuck::cast_slice(&f));
            }
            // Only the flags an earlier launch may have written: a run's queues are sized for
            // its whole work, and clearing all of them cost every run a fill of the capacity
            // (BFS scale 16: about 100 MB of flags against a 0.12 ms launch).
            let rest = dq.dirty[q].saturating_sub(n) as u64;
            if rest > 0 {
                enc.clear_buffer(&dq.flags, (base + n as u64) * 4, Some(rest * 4));
            }
            cleared += rest;
            dq.dirty[q] = n;
        }
        self.write_ctrl(gpu, &dq.ctrl, &counts);
        cleared
    }
}
