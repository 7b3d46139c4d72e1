//! GPU time of compute passes from timestamp queries, where the adapter has them.

use crate::error::RunError;
use crate::gpu::Gpu;

/// The u64 timestamp at `words[at..at + 2]`, as a query resolve writes it (little-endian),
/// read as a word pair: a slice of words need not be 8-byte aligned.
fn timestamp(words: &[u32], at: usize) -> u64 {
    words[at] as u64 | (words[at + 1] as u64) << 32
}

/// Times many passes per submission and adds each pass's time to its stage, so that a
/// strategy that runs stages as separate dispatches (multi-pass) can report GPU time per
/// procedure. Each timed pass costs a pass boundary, so this is opt-in.
pub(crate) struct StageTimer {
    set: Option<wgpu::QuerySet>,
    resolved: wgpu::Buffer,
    period_ns: f64,
    capacity: u32,
    /// Stage of each pass timed since the last collect.
    pending: std::cell::RefCell<Vec<usize>>,
    stage_ns: Vec<f64>,
}

impl StageTimer {
    /// `stages` buckets of time; at most `passes` timed passes between collects.
    pub fn new(gpu: &Gpu, stages: usize, passes: u32) -> StageTimer {
        let set = gpu.timestamps.then(|| {
            gpu.device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("stage timer"),
                ty: wgpu::QueryType::Timestamp,
                count: 2 * passes,
            })
        });
        let resolved = gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("stage timestamps"),
            size: 16 * passes as u64,
            usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        StageTimer {
            set,
            resolved,
            period_ns: gpu.queue.get_timestamp_period() as f64,
            capacity: passes,
            pending: Default::default(),
            stage_ns: vec![0.0; stages],
        }
    }

    /// Timestamp writes for the next pass, counted to `stage`.
    pub fn writes(&self, stage: usize) -> Option<wgpu::ComputePassTimestampWrites<'_>> {
        let mut p = self.pending.borrow_mut();
        let i = p.len() as u32;
        assert!(
            i < self.capacity,
            "StageTimer: more passes than its capacity"
        );
        p.push(stage);
        self.set
            .as_ref()
            .map(|set| wgpu::ComputePassTimestampWrites {
                query_set: set,
                beginning_of_pass_write_index: Some(2 * i),
                end_of_pass_write_index: Some(2 * i + 1),
            })
    }

    pub fn resolve(&self, enc: &mut wgpu::CommandEncoder) {
        let n = self.pending.borrow().len() as u32;
        if let (Some(set), true) = (&self.set, n > 0) {
            enc.resolve_query_set(set, 0..2 * n, &self.resolved, 0);
        }
    }

    /// Reads the passes since the last collect back into their stages.
    pub fn collect(&mut self, gpu: &Gpu) -> Result<(), RunError> {
        let n = self.pending.borrow().len() as u64;
        let words = match self.set.is_some() && n > 0 {
            true => bytemuck::pod_collect_to_vec(&gpu.read_buffer(&self.resolved, 0, 16 * n)?),
            false => Vec::new(),
        };
        self.collect_words(&words);
        Ok(())
    }

    /// Records the resolve of the passes since the last collect and the copy of their
    /// timestamps (4 words a pass) into `rb` from word `dst_word`, so that they come back with
    /// the caller's wait; [`StageTimer::collect_words`] then adds them up. Returns the words
    /// copied (0 without timestamp queries or passes).
    pub fn copy_pending(
        &self,
        enc: &mut wgpu::CommandEncoder,
        rb: &crate::readback::Readback,
        dst_word: u64,
    ) -> u64 {
        let n = self.pending.borrow().len() as u64;
        if self.set.is_none() || n == 0 {
            return 0;
        }
        self.resolve(enc);
        rb.copy(enc, &self.resolved, 0, dst_word, 4 * n);
        4 * n
    }

    /// Adds the passes since the last collect from `words` (their timestamps as
    /// [`StageTimer::copy_pending`] put them) and starts a new set.
    pub fn collect_words(&mut self, words: &[u32]) {
        let stages = std::mem::take(&mut *self.pending.borrow_mut());
        if self.set.is_none() {
            return;
        }
        for (k, s) in stages.into_iter().enumerate() {
            let (begin, end) = (timestamp(words, 4 * k), timestamp(words, 4 * k + 2));
            self.stage_ns[s] += end.saturating_sub(begin) as f64 * self.period_ns;
        }
    }

    pub fn stage_ms(&self) -> Option<Vec<f64>> {
        self.set
            .as_ref()
            .map(|_| self.stage_ns.iter().map(|n| n / 1e6).collect())
    }
}

/// Times every pass of a run of many short submissions (host-driven rounds) and brings the
/// timestamps back through the run's own read-back, in the submission after which its query
/// set could not hold another submission's passes and after the run's last one, so timing
/// costs no submission or wait of its own. Each pass counts to a stage (one, or one per
/// procedure with stage timing). The times are `None` when the adapter has no timestamp
/// queries.
pub(crate) struct RunTimer {
    inner: StageTimer,
    used: u32,
    passes: u32,
    per_submission: u32,
}

impl RunTimer {
    /// `stages` buckets of time; at most `per_submission` timed passes a submission; room for
    /// `submissions` submissions' passes between read-backs.
    pub fn new(gpu: &Gpu, stages: usize, per_submission: u32, submissions: u32) -> RunTimer {
        let per_submission = per_submission.max(1);
        let passes = per_submission * submissions.max(1);
        RunTimer {
            inner: StageTimer::new(gpu, stages.max(1), passes),
            used: 0,
            passes,
            per_submission,
        }
    }

    /// Timestamp writes for the next pass, counted to `stage`.
    pub fn writes(&mut self, stage: usize) -> Option<wgpu::ComputePassTimestampWrites<'_>> {
        self.used += 1;
        self.inner.writes(stage)
    }

    /// Most words [`RunTimer::end_submission`] and [`RunTimer::copy_rest`] copy.
    pub fn words(&self) -> u64 {
        4 * self.passes as u64
    }

    /// Whether the query set could not hold another submission's passes.
    fn full(&self) -> bool {
        self.used + self.per_submission > self.passes
    }

    /// Call after the last pass of a submission, in its encoder: when the query set is full,
    /// records its resolve and copy into `rb` from word `dst_word` and returns the words copied,
    /// which [`RunTimer::after_wait`] reads from what the wait brings back; else 0.
    pub fn end_submission(
        &mut self,
        enc: &mut wgpu::CommandEncoder,
        rb: &crate::readback::Readback,
        dst_word: u64,
    ) -> u64 {
        match self.full() {
            true => self.inner.copy_pending(enc, rb, dst_word),
            false => 0,
        }
    }

    /// Call after waiting for the submission: adds the timestamps in `words` (what
    /// [`RunTimer::end_submission`] copied; they start a new query set) when the set was full.
    pub fn after_wait(&mut self, words: &[u32]) {
        if self.full() {
            self.inner.collect_words(words);
            self.used = 0;
        }
    }

    /// Records, in the run's last encoder, the resolve of the timestamps not yet read and their
    /// copy into `rb` from word `dst_word` (no submission or wait of their own); returns the
    /// words copied (0 when none are left or without timestamp queries).
    pub fn copy_rest(
        &self,
        enc: &mut wgpu::CommandEncoder,
        rb: &crate::readback::Readback,
        dst_word: u64,
    ) -> u64 {
        self.inner.copy_pending(enc, rb, dst_word)
    }

    /// The GPU ms of every stage, the rest read from `words` (what [`RunTimer::copy_rest`]
    /// copied, after the wait); their sum is the run's GPU time.
    pub fn finish(mut self, words: &[u32]) -> Option<Vec<f64>> {
        self.inner.collect_words(words);
        self.inner.stage_ms()
    }
}

/// GPU time of a span of passes recorded in one encoder (from the start of its first pass to
/// the end of its last), read back later with other results instead of by a wait of its own:
/// for pipelined frames, whose status is read a frame late. `slots` spans may be in flight at
/// once (one per frame in flight). Without timestamp queries every call records nothing and
/// [`SpanTimer::ms`] is `None`.
///
/// Per span: [`SpanTimer::begin`] for the first pass's `timestamp_writes`, [`SpanTimer::end`]
/// for the last pass's, then [`SpanTimer::copy`] in the same encoder after the last pass, which
/// puts [`SpanTimer::WORDS`] words into the caller's buffer; [`SpanTimer::ms`] reads them.
pub struct SpanTimer {
    set: Option<wgpu::QuerySet>,
    resolved: wgpu::Buffer,
    period_ns: f64,
    slots: u32,
}

impl SpanTimer {
    /// Words [`SpanTimer::copy`] writes: two little-endian u64 timestamps.
    pub const WORDS: u64 = 4;

    /// A timer of `slots` (at least 1) spans, two timestamps each.
    pub fn new(gpu: &Gpu, slots: u32) -> SpanTimer {
        let slots = slots.max(1);
        let set = gpu.timestamps.then(|| {
            gpu.device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("span timer"),
                ty: wgpu::QueryType::Timestamp,
                count: 2 * slots,
            })
        });
        // Each slot's resolve lands at its own 256-byte aligned offset (wgpu's rule).
        let resolved = gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("span timestamps"),
            size: wgpu::QUERY_RESOLVE_BUFFER_ALIGNMENT * slots as u64,
            usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        SpanTimer {
            set,
            resolved,
            period_ns: gpu.queue.get_timestamp_period() as f64,
            slots,
        }
    }

    fn writes(
        &self,
        slot: u32,
        begin: bool,
        end: bool,
    ) -> Option<wgpu::ComputePassTimestampWrites<'_>> {
        assert!(
            slot < self.slots,
            "SpanTimer: slot {slot} of {}",
            self.slots
        );
        self.set
            .as_ref()
            .map(|set| wgpu::ComputePassTimestampWrites {
                query_set: set,
                beginning_of_pass_write_index: begin.then_some(2 * slot),
                end_of_pass_write_index: end.then_some(2 * slot + 1),
            })
    }

    /// Timestamp writes for a span of one pass (its beginning and its end).
    pub fn whole(&self, slot: u32) -> Option<wgpu::ComputePassTimestampWrites<'_>> {
        self.writes(slot, true, true)
    }

    /// Timestamp writes for the span's first pass.
    pub fn begin(&self, slot: u32) -> Option<wgpu::ComputePassTimestampWrites<'_>> {
        self.writes(slot, true, false)
    }

    /// Timestamp writes for the span's last pass.
    pub fn end(&self, slot: u32) -> Option<wgpu::ComputePassTimestampWrites<'_>> {
        self.writes(slot, false, true)
    }

    /// Records the resolve of the span's timestamps and their copy into `dst` (which needs
    /// `COPY_DST`) at word `dst_word`, after the span's last pass.
    pub fn copy(
        &self,
        enc: &mut wgpu::CommandEncoder,
        slot: u32,
        dst: &wgpu::Buffer,
        dst_word: u64,
    ) {
        if let Some(set) = &self.set {
            let at = wgpu::QUERY_RESOLVE_BUFFER_ALIGNMENT * slot as u64;
            enc.resolve_query_set(set, 2 * slot..2 * slot + 2, &self.resolved, at);
            enc.copy_buffer_to_buffer(&self.resolved, at, dst, dst_word * 4, Self::WORDS * 4);
        }
    }

    /// The span's GPU milliseconds from the [`SpanTimer::WORDS`] words its copy wrote; `None`
    /// without timestamp queries.
    pub fn ms(&self, words: &[u32]) -> Option<f64> {
        self.set.as_ref()?;
        let (begin, end) = (timestamp(words, 0), timestamp(words, 2));
        Some(end.saturating_sub(begin) as f64 * self.period_ns / 1e6)
    }
}
