//! Read-back of device results with one host wait: a reusable mapped buffer for the small
//! per-launch or per-round counters, and a one-shot read of several buffer ranges together.

use std::time::Duration;

use crate::error::RunError;
use crate::gpu::Gpu;
use crate::timing::SpanTimer;

/// A `MAP_READ` buffer of `words` u32 words, kept for a scheduler's lifetime, that the caller fills
/// with [`Readback::copy`] in the same command encoder as the work it reads (so no extra
/// submission) and reads with [`Readback::read`] after submitting (one bounded wait).
pub struct Readback {
    buf: wgpu::Buffer,
    words: u64,
}

impl Readback {
    /// A read-back of at least `words` words (rounded up to an even count).
    pub fn new(gpu: &Gpu, label: &str, words: u64) -> Readback {
        // Even, so that any prefix rounded up to 8 bytes stays inside.
        let words = words.max(2).next_multiple_of(2);
        Readback {
            buf: gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: words * 4,
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
            words,
        }
    }

    /// `kept` where it holds at least `words` words, else a new one of `words`: a scheduler's
    /// read-back, reused run after run and grown when a run reads more.
    pub fn reuse(kept: Option<Readback>, gpu: &Gpu, label: &str, words: u64) -> Readback {
        kept.filter(|rb| rb.words >= words)
            .unwrap_or_else(|| Readback::new(gpu, label, words))
    }

    /// Copies `ranges` here, one after another from word `at`, in a submission of their own and
    /// reads them back (one bounded wait), one vector per range.
    pub fn read_ranges(
        &self,
        gpu: &Gpu,
        ranges: &[ReadRange],
        at: u64,
    ) -> Result<Vec<Vec<u32>>, RunError> {
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        copy_ranges(self, &mut enc, ranges, at);
        gpu.submit(enc);
        let words = self.read(gpu, at + ranges_words(ranges))?;
        Ok(split_ranges(&words[at as usize..], ranges))
    }

    /// Records the resolve of `timer`'s span `slot` and its copy here at word `dst_word`, after
    /// the span's last pass: the span's GPU time comes back with the counters of the same
    /// read-back, with no submission or wait of its own.
    pub fn copy_span(
        &self,
        enc: &mut wgpu::CommandEncoder,
        timer: &SpanTimer,
        slot: u32,
        dst_word: u64,
    ) {
        assert!(
            dst_word + SpanTimer::WORDS <= self.words,
            "Readback: span copy past its end"
        );
        timer.copy(enc, slot, &self.buf, dst_word);
    }

    /// Records a copy of `words` words of `src` from word `src_word` to word `dst_word` here.
    pub fn copy(
        &self,
        enc: &mut wgpu::CommandEncoder,
        src: &wgpu::Buffer,
        src_word: u64,
        dst_word: u64,
        words: u64,
    ) {
        assert!(
            dst_word + words <= self.words,
            "Readback: copy past its end"
        );
        if words == 0 {
            return;
        }
        enc.copy_buffer_to_buffer(src, src_word * 4, &self.buf, dst_word * 4, words * 4);
    }

    /// The first `words` words, after the submission that copied them; waits at most
    /// `gpu.timeout`.
    pub fn read(&self, gpu: &Gpu, words: u64) -> Result<Vec<u32>, RunError> {
        // Map ranges must be a multiple of 8 bytes long.
        let bytes = (words.min(self.words) * 4)
            .next_multiple_of(8)
            .min(self.words * 4);
        let slice = self.buf.slice(0..bytes);
        let (tx, rx) = std::sync::mpsc::channel();
        slice.map_async(wgpu::MapMode::Read, move |r| {
            let _ = tx.send(r);
        });
        gpu.wait("reading counters back")?;
        match rx.recv_timeout(Duration::from_secs(1)) {
            Ok(Ok(())) => {}
            Ok(Err(e)) => return Err(RunError::Device(format!("map_async: {e}"))),
            Err(_) => return Err(RunError::Device("buffer map never completed".into())),
        }
        let out = {
            let view = slice
                .get_mapped_range()
                .map_err(|e| RunError::Device(format!("mapped range: {e}")))?;
            bytemuck::cast_slice::<u8, u32>(&view)[..words as usize].to_vec()
        };
        self.buf.unmap();
        Ok(out)
    }
}

/// What a run waits for once per submission: a [`Readback`] of `counters` words of the run's
/// counters, then the two timestamps of the submission's timed pass ([`SpanTimer::WORDS`]),
/// then the caller's ranges ([`ReadRange`]), with the [`SpanTimer`] whose span it copies. So a
/// submission's GPU time and results come back in the wait for its counters, with no submission
/// or wait of their own. Kept between runs by the megakernel, the device-driven multi-pass and
/// a workload's own baseline (the frontier BFS), and grown when a run reads more.
pub struct TimedReadback {
    rb: Readback,
    timer: SpanTimer,
    counters: u64,
}

impl TimedReadback {
    /// `kept` (its buffer grown where `ranges` need more words), else a new one, for
    /// `counters` counter words and `ranges` after the timestamps.
    pub fn reuse(
        kept: Option<TimedReadback>,
        gpu: &Gpu,
        label: &str,
        counters: u64,
        ranges: &[ReadRange],
    ) -> TimedReadback {
        let words = counters + SpanTimer::WORDS + ranges_words(ranges);
        let (rb, timer) = match kept {
            Some(k) if k.counters == counters => (Some(k.rb), k.timer),
            _ => (None, SpanTimer::new(gpu, 1)),
        };
        TimedReadback {
            rb: Readback::reuse(rb, gpu, label, words),
            timer,
            counters,
        }
    }

    /// The timestamp writes of the submission's timed pass (its beginning and end); `None`
    /// without timestamp queries.
    pub fn pass_writes(&self) -> Option<wgpu::ComputePassTimestampWrites<'_>> {
        self.timer.whole(0)
    }

    /// Records, after the submission's last pass: the counters (the first `counters` words of
    /// `src`; `None` for a read-back of no counters), the timed pass's timestamps where `timed`
    /// (a pass took [`Self::pass_writes`]), and `ranges`.
    pub fn copy(
        &self,
        enc: &mut wgpu::CommandEncoder,
        src: Option<&wgpu::Buffer>,
        timed: bool,
        ranges: &[ReadRange],
    ) {
        assert!(
            src.is_some() || self.counters == 0,
            "TimedReadback: counters without their buffer"
        );
        if let Some(src) = src {
            self.rb.copy(enc, src, 0, 0, self.counters);
        }
        if timed {
            self.rb.copy_span(enc, &self.timer, 0, self.counters);
        }
        copy_ranges(&self.rb, enc, ranges, self.counters + SpanTimer::WORDS);
    }

    /// The submission's words after it finished (one bounded wait): counters, timestamps,
    /// `ranges`. Errors: [`RunError::Timeout`], [`RunError::Device`].
    pub fn read(&self, gpu: &Gpu, ranges: &[ReadRange]) -> Result<Vec<u32>, RunError> {
        self.rb
            .read(gpu, self.counters + SpanTimer::WORDS + ranges_words(ranges))
    }

    /// The counters of `words` (what [`Self::read`] returned).
    pub fn counters<'a>(&self, words: &'a [u32]) -> &'a [u32] {
        &words[..self.counters as usize]
    }

    /// Adds the timed pass's GPU milliseconds in `words` to `total` (left `None` without
    /// timestamp queries).
    pub fn add_ms(&self, words: &[u32], total: &mut Option<f64>) {
        if let (Some(t), Some(ms)) = (
            total.as_mut(),
            self.timer.ms(&words[self.counters as usize..]),
        ) {
            *t += ms;
        }
    }

    /// `ranges` as `words` holds them, one vector per range.
    pub fn ranges(&self, words: &[u32], ranges: &[ReadRange]) -> Vec<Vec<u32>> {
        split_ranges(
            &words[(self.counters + SpanTimer::WORDS) as usize..],
            ranges,
        )
    }
}

/// A range of a buffer to read back: `(buffer, first word, words)`. The buffer needs
/// `COPY_SRC` usage (every [`Gpu::storage_buffer`] has it).
pub type ReadRange<'a> = (&'a wgpu::Buffer, u64, u64);

/// Words of all `ranges` together.
pub fn ranges_words(ranges: &[ReadRange]) -> u64 {
    ranges.iter().map(|r| r.2).sum()
}

/// Records copies of `ranges` into `rb`, one after another from word `at`.
pub fn copy_ranges(rb: &Readback, enc: &mut wgpu::CommandEncoder, ranges: &[ReadRange], at: u64) {
    let mut at = at;
    for &(buf, first, words) in ranges {
        rb.copy(enc, buf, first, at, words);
        at += words;
    }
}

/// `words` (read back from where [`copy_ranges`] put `ranges`) cut into one vector per range.
pub fn split_ranges(words: &[u32], ranges: &[ReadRange]) -> Vec<Vec<u32>> {
    let mut at = 0;
    ranges
        .iter()
        .map(|r| {
            let v = words[at..at + r.2 as usize].to_vec();
            at += r.2 as usize;
            v
        })
        .collect()
}

/// Reads every range in one submission and one bounded wait.
pub fn read_ranges(gpu: &Gpu, ranges: &[ReadRange]) -> Result<Vec<Vec<u32>>, RunError> {
    let total = ranges_words(ranges);
    if total == 0 {
        return Ok(vec![Vec::new(); ranges.len()]);
    }
    Readback::new(gpu, "read ranges", total).read_ranges(gpu, ranges, 0)
}
