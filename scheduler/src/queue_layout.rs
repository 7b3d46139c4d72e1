//! Where each procedure's queue lives in the shared item storage: one region per queue,
//! `capacity` slots of the item's words. Both strategies use it; growing a queue means a new layout.

use std::borrow::Cow;

use crate::error::RunError;
use crate::program::{Program, Seed};

#[derive(Debug, Clone, PartialEq)]
pub struct QueueLayout {
    pub capacity: Vec<u32>,
    pub words: Vec<u32>,
    /// First word of queue q's slots.
    pub slot_base: Vec<u32>,
    /// First slot index of queue q (for per-slot arrays such as flags).
    pub flag_base: Vec<u32>,
    pub total_words: u64,
    pub total_slots: u64,
}

impl QueueLayout {
    /// Encodes the copy of each `(queue, buffer, count)` seed buffer (its items back to back)
    /// to the queue's first slots in `items`, a buffer of this layout's words.
    pub(crate) fn encode_seed_copies(
        &self,
        enc: &mut wgpu::CommandEncoder,
        seeds: &[(usize, &wgpu::Buffer, u32)],
        items: &wgpu::Buffer,
    ) {
        for &(q, buf, n) in seeds {
            let bytes = n as u64 * self.words[q] as u64 * 4;
            if bytes > 0 {
                let at = self.slot_base[q] as u64 * 4;
                enc.copy_buffer_to_buffer(buf, 0, items, at, bytes);
            }
        }
    }

    pub fn new(program: &Program, capacity: Vec<u32>) -> Result<QueueLayout, RunError> {
        let words: Vec<u32> = program.procs.iter().map(|p| p.words()).collect();
        let (mut w, mut f) = (0u64, 0u64);
        let (mut slot_base, mut flag_base) = (Vec::new(), Vec::new());
        for (c, wd) in capacity.iter().zip(&words) {
            // Every region starts on a 16-byte boundary: the shaders move items that are a
            // whole number of vec4s 16 bytes at a time (`wgsl::moves_by_vec4`), and the item
            // buffers are `array<vec4<u32>>`, so their size is a multiple of 16 bytes too.
            slot_base.push(w as u32);
            flag_base.push(f as u32);
            w = (w + *c as u64 * *wd as u64).next_multiple_of(4);
            f += *c as u64;
        }
        if w >= u32::MAX as u64 / 2 {
            return Err(RunError::Program(format!(
                "queues need {w} words; word indices must stay below 2^31"
            )));
        }
        Ok(QueueLayout {
            capacity,
            words,
            slot_base,
            flag_base,
            total_words: w,
            total_slots: f,
        })
    }

    /// The most slots each queue may grow to: the configured limit, and an equal share of the
    /// largest storage binding the device allows (all queues live in one binding), so that a
    /// queue that would not fit is reported as an overflow instead of failing buffer creation.
    pub fn capacity_limits(program: &Program, max_binding_bytes: u64, configured: u32) -> Vec<u32> {
        // Less the alignment padding of each region (under 16 bytes).
        let share =
            (max_binding_bytes / program.queue_count().max(1) as u64).saturating_sub(16) / 4;
        program
            .procs
            .iter()
            .map(|p| (share / p.words() as u64).min(configured as u64).max(1) as u32)
            .collect()
    }

    /// Lowers `limits` so that all queues together fit in `budget` bytes, shared equally between
    /// queues, when each slot costs `words_copies` copies of its item's words plus one flag
    /// word (the megakernel keeps one copy, multi-pass three). Lets a caller bound a run's
    /// queue memory; a run that needs more reports [`RunError::QueueOverflow`].
    pub fn within_budget(
        program: &Program,
        limits: Vec<u32>,
        budget: Option<u64>,
        words_copies: u64,
    ) -> Vec<u32> {
        let Some(budget) = budget else { return limits };
        // Less the alignment padding of each copy of the region (under 16 bytes each).
        let share =
            (budget / program.queue_count().max(1) as u64).saturating_sub(16 * words_copies);
        limits
            .into_iter()
            .zip(&program.procs)
            .map(|(l, p)| {
                let slot_bytes = 4 * (p.words() as u64 * words_copies + 1);
                (share / slot_bytes).min(l as u64).max(1) as u32
            })
            .collect()
    }

    /// What every strategy's run starts from: the seed items per queue, their counts, and each
    /// queue's most slots ([`QueueLayout::capacity_limits`] under `configured`, then
    /// [`QueueLayout::within_budget`] with `words_copies`). Errors: a malformed seed, and
    /// [`RunError::QueueOverflow`] naming the first queue whose seeds alone exceed its limit.
    pub(crate) fn run_start<'a>(
        program: &Program,
        seeds: &'a [Seed],
        max_binding_bytes: u64,
        configured: u32,
        budget: Option<u64>,
        words_copies: u64,
    ) -> Result<RunStart<'a>, RunError> {
        let live = Self::seed_items(program, seeds)?;
        let max_cap = Self::within_budget(
            program,
            Self::capacity_limits(program, max_binding_bytes, configured),
            budget,
            words_copies,
        );
        let seeded: Vec<u32> = (0..program.queue_count())
            .map(|q| (live[q].len() / program.procs[q].words() as usize) as u32)
            .collect();
        Self::check_seeds(program, &seeded, &max_cap)?;
        Ok(RunStart {
            live,
            seeded,
            max_cap,
        })
    }

    /// Seeds of `seeded[q]` items per queue against each queue's most slots `max_cap[q]`: the
    /// seeds of one queue that exceed its limit are a [`RunError::QueueOverflow`] naming the
    /// first such queue, as in a run.
    pub(crate) fn check_seeds(
        program: &Program,
        seeded: &[u32],
        max_cap: &[u32],
    ) -> Result<(), RunError> {
        if let Some(q) = (0..seeded.len()).find(|&q| seeded[q] > max_cap[q]) {
            return Err(RunError::QueueOverflow {
                queue: program.procs[q].proc.name.clone(),
                capacity: max_cap[q] as u64,
                needed_more_than: seeded[q] as u64,
            });
        }
        Ok(())
    }

    /// Per-queue seed items (words back to back), validated against the program: borrowed
    /// from `seeds` where a queue has one seed (a frame's thousands of patches are not copied
    /// again on their way to the device), else joined.
    pub fn seed_items<'a>(
        program: &Program,
        seeds: &'a [Seed],
    ) -> Result<Vec<Cow<'a, [u32]>>, RunError> {
        let mut per_queue: Vec<Cow<'a, [u32]>> = vec![Cow::Borrowed(&[]); program.queue_count()];
        for s in seeds {
            let q = program.index_of(&s.procedure).ok_or_else(|| {
                RunError::Program(format!("seed for unknown procedure `{}`", s.procedure))
            })?;
            let w = program.procs[q].words() as usize;
            if s.words.len() % w != 0 {
                return Err(RunError::Program(format!(
                    "seed for `{}`: {} words is not a whole number of {w}-word items",
                    s.procedure,
                    s.words.len()
                )));
            }
            match per_queue[q].is_empty() {
                true => per_queue[q] = Cow::Borrowed(&s.words),
                false => per_queue[q].to_mut().extend_from_slice(&s.words),
            }
        }
        Ok(per_queue)
    }
}

/// See [`QueueLayout::run_start`].
pub(crate) struct RunStart<'a> {
    /// Seed items per queue, words back to back (see [`QueueLayout::seed_items`]).
    pub live: Vec<Cow<'a, [u32]>>,
    /// Seed items per queue.
    pub seeded: Vec<u32>,
    /// The most slots each queue may grow to in this run.
    pub max_cap: Vec<u32>,
}
