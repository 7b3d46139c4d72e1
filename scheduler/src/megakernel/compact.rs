//! Between two megakernel launches, the live items (published, unconsumed slots) become the next
//! launch's seeds. Two ways: on the host ([`host_compact`], when the queues keep their layout: one
//! read-back of every reserved range, re-uploaded by `Megakernel::upload`), or on the device
//! ([`DeviceCompaction`], when queues grow: copied from the old buffers into the new ones in the
//! next launch's own pass, so growth costs no read-back of the items). Protocol:
//! `docs/scheduler.md` section 2.5.

use super::DeviceQueues;
use super::layout::*;
use crate::error::RunError;
use crate::gpu::{Gpu, MAX_WORKGROUPS_PER_DIMENSION};
use crate::item_layout::ItemLayout;
use crate::program::Program;

const SOURCE: &str = include_str!("../../../shaders/megakernel_compact.wgsl");
/// Parameter words per queue (`CP_QUEUE_WORDS` in the shader).
const CP_QUEUE_WORDS: usize = 10;

/// Reads back each queue's reserved slots and keeps the published, unconsumed ones, in ticket
/// order, as items back to back (whatever the queues' `items` layout); one submission and one
/// wait for all queues. An `EMPTY` flag below `Q_RESERVE`, or a
/// kept count other than `G_PENDING + G_ABANDONED`, is a protocol violation (`Device` error).
pub(super) fn host_compact(
    gpu: &Gpu,
    program: &Program,
    d: &DeviceQueues,
    ctrl: &[u32],
    items: ItemLayout,
) -> Result<Vec<Vec<u32>>, RunError> {
    let nq = program.queue_count();
    // Per queue: its flags, then its slots' word ranges (one, or one per plane).
    let (mut ranges, mut parts_of) = (Vec::new(), Vec::new());
    for qi in 0..nq {
        let reserved = ctrl[q(qi, Q_RESERVE)];
        ranges.push((&d.flags, d.layout.flag_base[qi] as u64, reserved as u64));
        let parts = items.copy_ranges(&d.layout, &d.layout, qi, reserved);
        parts_of.push(parts.len());
        ranges.extend(
            parts
                .into_iter()
                .map(|(from, _, words)| (&d.slots, from, words)),
        );
    }
    let data = crate::readback::read_ranges(gpu, &ranges)?;
    let mut live = vec![Vec::new(); nq];
    let mut total_live = 0u64;
    let mut at = 0;
    for qi in 0..nq {
        let w = d.layout.words[qi] as usize;
        let flags = &data[at];
        let parts = &data[at + 1..at + 1 + parts_of[qi]];
        at += 1 + parts_of[qi];
        // Items back to back, whichever layout the slots have.
        let slots: Vec<u32> = match items {
            ItemLayout::Interleaved => parts.concat(),
            ItemLayout::Planar => (0..flags.len() * w).map(|x| parts[x % w][x / w]).collect(),
        };
        for (i, f) in flags.iter().enumerate() {
            match *f {
                CONSUMED => {}
                EMPTY => {
                    let empties = flags.iter().filter(|&&f| f == EMPTY).count();
                    return Err(RunError::Device(format!(
                        "queue `{}` slot {i} was reserved but never published: protocol \
                         violation ({empties} such slots; reserve {}, head {}, count {}, \
                         budget {}, capacity {})",
                        program.procs[qi].proc.name,
                        flags.len(),
                        ctrl[q(qi, Q_HEAD)],
                        ctrl[q(qi, Q_COUNT)] as i32,
                        ctrl[q(qi, Q_BUDGET)],
                        d.layout.capacity[qi]
                    )));
                }
                _ => {
                    live[qi].extend_from_slice(&slots[i * w..(i + 1) * w]);
                    total_live += 1;
                }
            }
        }
    }
    // Every item still pending or abandoned must be among the live slots, and nothing else.
    let expected = ctrl[g(nq, G_PENDING)] as u64 + ctrl[g(nq, G_ABANDONED)] as u64;
    if total_live != expected {
        return Err(RunError::Device(format!(
            "queue accounting mismatch after a launch: {total_live} live slots, {expected} pending"
        )));
    }
    Ok(live)
}

/// The compaction kernel of `shaders/megakernel_compact.wgsl`: old queue buffers → new ones.
pub struct DeviceCompaction {
    pipeline: wgpu::ComputePipeline,
}

/// One compaction, ready to record: its bind group and dispatch size.
pub struct CompactionPass {
    bind: wgpu::BindGroup,
    workgroups: u32,
    queues: u32,
}

impl DeviceCompaction {
    pub fn new(gpu: &Gpu) -> Result<DeviceCompaction, RunError> {
        Ok(DeviceCompaction {
            pipeline: gpu.compute_pipeline("megakernel compaction", SOURCE, "compact")?,
        })
    }

    /// Prepares the copy of the live slots among the first `reserved[q]` tickets of `old` into
    /// `new` (freshly created, so its flags are zero). The host must write `new`'s ctrl with
    /// `Q_KEPT` and `G_LOST` zero before the submission; afterwards `Q_KEPT[q]` must equal the
    /// live count and `G_LOST` zero ([`check`]).
    pub(super) fn prepare(
        &self,
        gpu: &Gpu,
        old: &DeviceQueues,
        new: &DeviceQueues,
        reserved: &[u32],
        items: ItemLayout,
    ) -> Result<CompactionPass, RunError> {
        let nq = reserved.len();
        let mut cp = vec![0u32; 8 + CP_QUEUE_WORDS * nq];
        cp[0] = g(nq, G_LOST) as u32;
        for (qi, &r) in reserved.iter().enumerate() {
            let at = 8 + CP_QUEUE_WORDS * qi;
            cp[at..at + CP_QUEUE_WORDS].copy_from_slice(&[
                r,
                old.layout.slot_base[qi],
                old.layout.flag_base[qi],
                new.layout.slot_base[qi],
                new.layout.flag_base[qi],
                new.layout.words[qi],
                new.layout.capacity[qi],
                q(qi, Q_KEPT) as u32,
                old.layout.capacity[qi],
                (items == ItemLayout::Planar) as u32,
            ]);
        }
        let params = gpu.storage_buffer("compaction params", cp.len() as u64)?;
        gpu.queue
            .write_buffer(&params, 0, bytemuck::cast_slice(&cp));
        let bind = gpu.bind_buffers(
            "megakernel compaction",
            &self.pipeline.get_bind_group_layout(0),
            &[
                &old.slots, &old.flags, &new.slots, &new.flags, &new.ctrl, &params,
            ],
        );
        let most = reserved.iter().copied().max().unwrap_or(0);
        Ok(CompactionPass {
            bind,
            workgroups: most.div_ceil(256).clamp(1, MAX_WORKGROUPS_PER_DIMENSION),
            queues: nq as u32,
        })
    }

    /// Records the compaction into `pass` (before the launch that consumes its output).
    pub fn record(&self, pass: &mut wgpu::ComputePass, c: &CompactionPass) {
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &c.bind, &[]);
        pass.dispatch_workgroups(c.workgroups, c.queues, 1);
    }
}

/// After the launch that followed a device compaction: every queue kept exactly its `live`
/// count and no slot was lost, or a `Device` error (a protocol violation).
pub fn check(program: &Program, ctrl: &[u32], live: &[u32]) -> Result<(), RunError> {
    let nq = program.queue_count();
    let lost = ctrl[g(nq, G_LOST)];
    for (qi, &n) in live.iter().enumerate() {
        let kept = ctrl[q(qi, Q_KEPT)];
        if kept != n || lost != 0 {
            return Err(RunError::Device(format!(
                "device compaction of queue `{}` kept {kept} slots of {n} live ({lost} slots \
                 reserved but never published or without room: protocol violation)",
                program.procs[qi].proc.name
            )));
        }
    }
    Ok(())
}
