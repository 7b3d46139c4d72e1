//! The device-driven multi-pass's part of a [`crate::RecordedRun`]: a fixed number of rounds
//! on queues of fixed capacity, seeded on the device, in one pass. A round that would not fit
//! is refused on the device as in a run (inputs intact, no later round planned), and an empty
//! round costs only its empty indirect dispatches.

use super::Multipass;
use super::layout::*;
use crate::error::RunError;
use crate::gpu::Gpu;
use crate::item_layout::{ItemLayout, PlanarScatter};
use crate::program::Program;
use crate::queue_layout::QueueLayout;
use crate::stats::{Outcome, RunStats};

/// The rounds' queues and start state, recorded again for every record of the run.
pub(crate) struct RecordedRounds {
    d: super::DeviceRounds,
    /// mp_ctrl at the start: the seed counts as the first round's inputs, all else 0.
    ctrl_start: wgpu::Buffer,
    rounds: u32,
    /// Planar queues: the device copy of the seeds into their planes.
    scatter: Option<PlanarScatter>,
    item_layout: ItemLayout,
    /// Indirect dispatches a round (the multi-pass's dispatch groups).
    dispatches_per_round: u64,
    /// [`Multipass::round_dispatch`].
    round_dispatch: &'static str,
    /// `MultipassConfig::max_workgroups` as resolved.
    max_workgroups: Option<u32>,
}

impl Multipass {
    /// Queues of `wanted[q]` slots each (lowered to each queue's limit under the device and
    /// `max_queue_bytes`, raised to its seeds) and `rounds` (at least 1) rounds per record;
    /// with the capacities allocated.
    pub(crate) fn recorded_rounds(
        &self,
        gpu: &Gpu,
        seeded: &[u32],
        wanted: &[u32],
        rounds: u32,
        max_queue_bytes: Option<u64>,
    ) -> Result<(RecordedRounds, Vec<u32>), RunError> {
        let max_cap = QueueLayout::within_budget(
            &self.program,
            QueueLayout::capacity_limits(
                &self.program,
                gpu.max_binding_bytes(),
                self.config.max_capacity,
            ),
            max_queue_bytes,
            2,
        );
        QueueLayout::check_seeds(&self.program, seeded, &max_cap)?;
        let capacity: Vec<u32> = (0..seeded.len())
            .map(|q| wanted[q].min(max_cap[q]).max(seeded[q]).max(1))
            .collect();
        // No partial rounds: a recorded run has a fixed round count, so a round that does not
        // fit halts and the run reports itself incomplete (the caller re-renders that frame).
        let rounds = rounds.max(1);
        let d = self.device_rounds(
            gpu,
            QueueLayout::new(&self.program, capacity.clone())?,
            vec![false; seeded.len()],
            rounds,
        )?;
        let nq = seeded.len();
        let mut ctrl = vec![0u32; ctrl_words(nq)];
        for (q, &n) in seeded.iter().enumerate() {
            ctrl[c(q, C_APPEND)] = n;
        }
        ctrl[g(nq, G_CHUNK)] = rounds;
        let ctrl_start = gpu.upload("mp_ctrl at start", &ctrl)?;
        let scatter = match self.item_layout() {
            ItemLayout::Interleaved => None,
            ItemLayout::Planar => Some(PlanarScatter::new(gpu, &d.layout, seeded)?),
        };
        Ok((
            RecordedRounds {
                d,
                ctrl_start,
                rounds,
                scatter,
                item_layout: self.item_layout(),
                dispatches_per_round: self.dispatches_per_round(),
                round_dispatch: self.round_dispatch(),
                max_workgroups: self.config.max_workgroups,
            },
            capacity,
        ))
    }
}

impl RecordedRounds {
    /// Rounds encoded per record.
    pub fn rounds(&self) -> u32 {
        self.rounds
    }

    /// Words of the run's control block, which each record copies to the caller's status.
    pub fn status_words(&self) -> u64 {
        self.d.ctrl.size() / 4
    }

    /// See [`crate::RecordedRun::record`]; seeds are `(queue, buffer, count)`.
    pub fn record(
        &self,
        m: &Multipass,
        enc: &mut wgpu::CommandEncoder,
        seeds: &[(usize, &wgpu::Buffer, u32)],
        user: Option<&wgpu::BindGroup>,
        status: &wgpu::Buffer,
        status_word: u64,
    ) -> Result<(), RunError> {
        m.kernels.check_user_group(user)?;
        let d = &self.d;
        match &self.scatter {
            Some(s) => s.record(enc, seeds, &d.items[0]),
            None => d.layout.encode_seed_copies(enc, seeds, &d.items[0]),
        }
        enc.copy_buffer_to_buffer(&self.ctrl_start, 0, &d.ctrl, 0, d.ctrl.size());
        m.encode_rounds(enc, d, self.rounds, 0, None, None, user);
        enc.copy_buffer_to_buffer(&d.ctrl, 0, status, status_word * 4, d.ctrl.size());
        Ok(())
    }

    /// Done when no round was refused and the last left no inputs; an emit beyond a
    /// declaration is an error. `capacity`: the slots per queue
    /// [`Multipass::recorded_rounds`] allocated.
    pub fn outcome(
        &self,
        program: &Program,
        capacity: &[u32],
        ctrl: &[u32],
    ) -> Result<Outcome, RunError> {
        let nq = program.queue_count();
        let error = ctrl[g(nq, G_ERROR)];
        let (a, b) = (ctrl[g(nq, G_ERR_A)] as usize, ctrl[g(nq, G_ERR_B)]);
        if error == ERR_EMIT {
            return Err(RunError::EmitLimit {
                procedure: program.procs[a].proc.name.clone(),
                target: program.procs[b as usize].proc.name.clone(),
                declared: program.procs[a].emits[b as usize],
            });
        }
        if error == ERR_ROOM {
            return Err(RunError::Device(format!(
                "device-driven multi-pass: an append past the capacity the plan made room for \
                 (queue {a}, slot {b})"
            )));
        }
        if error == ERR_OVERFLOW {
            return Ok(Outcome::Incomplete(format!(
                "a round refused: queue `{}` may receive {b} items, more than its {} slots",
                program.procs[a].proc.name, capacity[a]
            )));
        }
        let pending = pending_window(nq, ctrl, 0);
        let left: u64 = (0..nq).map(|q| window_count(ctrl, q, pending) as u64).sum();
        if left > 0 {
            return Ok(Outcome::Incomplete(format!(
                "{left} items left after {} rounds",
                self.rounds
            )));
        }
        Ok(Outcome::Done(RunStats {
            strategy: "multipass".into(),
            item_layout: self.item_layout.name().into(),
            round_dispatch: self.round_dispatch.into(),
            max_workgroups: self.max_workgroups,
            executed: (0..nq).map(|q| ctrl[c(q, C_EXEC)] as u64).collect(),
            peak_occupancy: (0..nq).map(|q| ctrl[c(q, C_PEAK)] as u64).collect(),
            rounds: ctrl[g(nq, G_ROUNDS)] as u64,
            launches: 1 + self.rounds as u64 * self.dispatches_per_round,
            queue_bytes: self.d.layout.total_words * 4 * 2,
            ..Default::default()
        }))
    }
}
