//! The megakernel's part of a [`crate::RecordedRun`]: one launch on queues of fixed capacity,
//! seeded on the device. The launch's start state is what [`Megakernel::upload`] writes for the
//! same seed counts (flags cleared, the seeds' slots stamped [`SEED_STAMP`], ctrl from
//! [`Megakernel::write_ctrl`]), kept in two small buffers and copied in each record, so a record
//! writes nothing from the host.

use super::claim::worst_batch_output;
use super::layout::*;
use super::{DeviceQueues, Megakernel};
use crate::error::RunError;
use crate::gpu::Gpu;
use crate::item_layout::{ItemLayout, PlanarScatter};
use crate::program::Program;
use crate::queue_layout::QueueLayout;
use crate::stats::{Outcome, RunStats};

/// One launch's queues and start state, recorded again for every record of the run.
pub(crate) struct RecordedLaunch {
    dq: DeviceQueues,
    /// ctrl at the start of a launch with the recorded seed counts.
    ctrl_start: wgpu::Buffer,
    /// [`SEED_STAMP`] for the most seeds of one queue.
    stamps: wgpu::Buffer,
    workgroups: u32,
    /// Moves device seeds into planar queues (`None` for interleaved ones: a buffer copy).
    scatter: Option<PlanarScatter>,
    item_layout: ItemLayout,
    direct: bool,
    workgroup_size: u32,
    local_queues: bool,
    local_workgroup_bytes: u32,
    probed_workgroups: u32,
}

impl Megakernel {
    /// Queues of `wanted[q]` slots each, plus room for the worst case of one batch per
    /// workgroup (lowered to each queue's limit under the device and `max_queue_bytes`, raised
    /// to its seeds), for launches seeded with `seeded` items per queue; with the capacities
    /// allocated.
    pub(crate) fn recorded_launch(
        &self,
        gpu: &Gpu,
        seeded: &[u32],
        wanted: &[u32],
        user: Option<&wgpu::BindGroup>,
        max_queue_bytes: Option<u64>,
    ) -> Result<(RecordedLaunch, Vec<u32>), RunError> {
        self.kernels.check_user_group(user)?;
        let workgroups = self.workgroups(gpu, user)?;
        let max_cap = QueueLayout::within_budget(
            &self.program,
            QueueLayout::capacity_limits(
                &self.program,
                self.queue_binding_bytes(gpu, workgroups),
                self.config.max_capacity,
            ),
            self.queue_budget(max_queue_bytes, workgroups),
            1,
        );
        QueueLayout::check_seeds(&self.program, seeded, &max_cap)?;
        // A batch is claimed only when the worst case of its output fits beside every ticket
        // taken and every promise of the running batches (Q_BUDGET): on top of the tickets
        // `wanted` asks for, each queue keeps room for one batch's worst case per workgroup.
        let nq = seeded.len();
        let slack: Vec<u64> = (0..nq)
            .map(|t| workgroups as u64 * worst_batch_output(&self.program, &self.batch, t))
            .collect();
        let capacity: Vec<u32> = (0..nq)
            .map(|q| {
                let want = (wanted[q] as u64 + slack[q]).min(u32::MAX as u64) as u32;
                want.min(max_cap[q]).max(seeded[q]).max(1)
            })
            .collect();
        let layout = QueueLayout::new(&self.program, capacity.clone())?;
        let dq = self.device_queues(gpu, layout, &self.params_for(&capacity)?, workgroups, None)?;
        let ctrl_start = gpu.storage_buffer("ctrl at launch", ctrl_words(seeded.len()) as u64)?;
        self.write_ctrl(gpu, &ctrl_start, seeded);
        let most = seeded.iter().copied().max().unwrap_or(0) as usize;
        let stamps = gpu.upload("seed stamps", &vec![SEED_STAMP; most])?;
        let scatter = match self.item_layout() {
            ItemLayout::Interleaved => None,
            ItemLayout::Planar => Some(PlanarScatter::new(gpu, &dq.layout, seeded)?),
        };
        let r = RecordedLaunch {
            dq,
            ctrl_start,
            stamps,
            workgroups,
            scatter,
            item_layout: self.item_layout(),
            direct: self.direct_enqueue(),
            workgroup_size: self.config.workgroup_size,
            local_queues: self.local_wg_words > 0,
            local_workgroup_bytes: self.local_workgroup_bytes,
            probed_workgroups: self.probed_workgroups(),
        };
        Ok((r, capacity))
    }

    fn params_for(&self, capacity: &[u32]) -> Result<Vec<u32>, RunError> {
        Ok(self.params(&QueueLayout::new(&self.program, capacity.to_vec())?))
    }
}

impl RecordedLaunch {
    /// Words of the run's control block, which each record copies to the caller's status.
    pub fn status_words(&self) -> u64 {
        self.dq.ctrl.size() / 4
    }

    /// See [`crate::RecordedRun::record`]; seeds are `(queue, buffer, count)`.
    pub fn record(
        &self,
        m: &Megakernel,
        enc: &mut wgpu::CommandEncoder,
        seeds: &[(usize, &wgpu::Buffer, u32)],
        user: Option<&wgpu::BindGroup>,
        status: &wgpu::Buffer,
        status_word: u64,
    ) -> Result<(), RunError> {
        m.kernels.check_user_group(user)?;
        let d = &self.dq;
        enc.clear_buffer(&d.flags, 0, None);
        match &self.scatter {
            Some(s) => s.record(enc, seeds, &d.slots),
            None => d.layout.encode_seed_copies(enc, seeds, &d.slots),
        }
        for &(q, _, n) in seeds.iter().filter(|s| s.2 > 0) {
            enc.copy_buffer_to_buffer(
                &self.stamps,
                0,
                &d.flags,
                d.layout.flag_base[q] as u64 * 4,
                n as u64 * 4,
            );
        }
        enc.copy_buffer_to_buffer(&self.ctrl_start, 0, &d.ctrl, 0, d.ctrl.size());
        {
            let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("megakernel (recorded)"),
                timestamp_writes: None,
            });
            pass.set_pipeline(&m.kernels.pipelines[0]);
            pass.set_bind_group(0, &d.bind, &[]);
            if let Some(u) = user {
                pass.set_bind_group(1, u, &[]);
            }
            pass.dispatch_workgroups(self.workgroups, 1, 1);
        }
        enc.copy_buffer_to_buffer(&d.ctrl, 0, status, status_word * 4, d.ctrl.size());
        Ok(())
    }

    /// Done when nothing is pending or abandoned; an emit beyond a declaration is an error.
    /// `capacity`: the slots per queue [`Megakernel::recorded_launch`] allocated.
    pub fn outcome(
        &self,
        program: &Program,
        capacity: &[u32],
        ctrl: &[u32],
    ) -> Result<Outcome, RunError> {
        let nq = program.queue_count();
        if ctrl[g(nq, G_ERROR)] == ERR_EMIT {
            let (p, t) = (ctrl[g(nq, G_ERR_A)] as usize, ctrl[g(nq, G_ERR_B)] as usize);
            return Err(RunError::EmitLimit {
                procedure: program.procs[p].proc.name.clone(),
                target: program.procs[t].proc.name.clone(),
                declared: program.procs[p].emits[t],
            });
        }
        let (pending, abandoned) = (ctrl[g(nq, G_PENDING)], ctrl[g(nq, G_ABANDONED)]);
        if pending != 0 || abandoned != 0 {
            let blocked: Vec<String> = (0..nq)
                .filter(|&qi| ctrl[q(qi, Q_BLOCKED)] != 0)
                .map(|qi| {
                    format!(
                        "queue `{}` out of room at {} slots",
                        program.procs[qi].proc.name, capacity[qi]
                    )
                })
                .collect();
            let why = if !blocked.is_empty() {
                blocked.join(", ")
            } else if ctrl[g(nq, G_ITER_EXITS)] != 0 {
                "the launch ended at its loop bound".to_string()
            } else {
                "slots abandoned after a bounded wait".to_string()
            };
            return Ok(Outcome::Incomplete(format!(
                "{pending} items pending, {abandoned} abandoned: {why}"
            )));
        }
        let mut stats = RunStats {
            strategy: "megakernel".into(),
            item_layout: self.item_layout.name().into(),
            enqueue: if self.direct { "direct" } else { "outbox" }.into(),
            executed: (0..nq)
                .map(|qi| ctrl[q(qi, Q_EXECUTED)] as u64 + ctrl[q(qi, Q_LOCAL)] as u64)
                .collect(),
            local_items: (0..nq).map(|qi| ctrl[q(qi, Q_LOCAL)] as u64).sum(),
            peak_occupancy: (0..nq).map(|qi| ctrl[q(qi, Q_PEAK)] as u64).collect(),
            batches: (0..nq).map(|qi| ctrl[q(qi, Q_BATCHES)] as u64).sum(),
            idle_polls: ctrl[g(nq, G_IDLE)] as u64,
            launches: 1,
            workgroups: self.workgroups,
            probed_workgroups: self.probed_workgroups,
            workgroup_size: self.workgroup_size,
            local_queues: self.local_queues,
            local_workgroup_bytes: self.local_workgroup_bytes,
            queue_bytes: self.dq.slots.size() + self.dq.layout.total_slots * 4,
            ..Default::default()
        };
        stats.submits = 0;
        Ok(Outcome::Done(stats))
    }
}
