//! What the pipelined renderer brings back to the host, and how: [`Pixels`] (which image a frame
//! reads back), mapped staging buffers and the bounded wait for their maps.

#[allow(unused_imports)]
use super::*;

/// What a frame brings back to the host besides its status.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Pixels {
    /// Nothing (timing).
    None,
    /// The 8-bit sRGB image, converted on the GPU: 4 bytes per pixel.
    Rgba8,
    /// The f32 linear image and depth ([`FrameImage`]), as `reyes render` gives them (tests).
    Float,
}

impl Pixels {
    /// Words (u32) of each read-back buffer a frame of `pixels` pixels brings back: none, the
    /// packed 8-bit sRGB image (1 a pixel), or the f32 RGBA image (4) and depth (1).
    pub fn read_back_words(self, pixels: u64) -> Vec<u64> {
        match self {
            Pixels::None => Vec::new(),
            Pixels::Rgba8 => vec![pixels],
            Pixels::Float => vec![4 * pixels, pixels],
        }
    }

    /// The GPU buffers a frame copies back, in [`Self::read_back_words`]' order: `rgba8`, or
    /// `rgba` and `depth`.
    pub(crate) fn sources<'a>(
        self,
        rgba8: &'a wgpu::Buffer,
        rgba: &'a wgpu::Buffer,
        depth: &'a wgpu::Buffer,
    ) -> Vec<&'a wgpu::Buffer> {
        match self {
            Pixels::None => vec![],
            Pixels::Rgba8 => vec![rgba8],
            Pixels::Float => vec![rgba, depth],
        }
    }

    /// The mapped read-back buffers of one frame slot ([`Self::read_back_words`]), shared by
    /// the pipelined Reyes renderer and the raster peer. Errors: [`RunError::Device`] for a
    /// buffer larger than the device allows.
    pub(crate) fn read_back_buffers(
        self,
        gpu: &Gpu,
        label: &str,
        pixels: u64,
    ) -> Result<Vec<wgpu::Buffer>, RunError> {
        (self.read_back_words(pixels).into_iter())
            .map(|w| map_buffer(gpu, label, w))
            .collect()
    }
}

/// Maps every buffer of `maps` for reading; the counter reaches `maps.len()` once all are
/// mapped (a frame's status and pixels, read a frame late).
pub(crate) fn map_for_read(maps: &[wgpu::Buffer]) -> Arc<AtomicUsize> {
    let mapped = Arc::new(AtomicUsize::new(0));
    for b in maps {
        let done = mapped.clone();
        b.slice(..).map_async(wgpu::MapMode::Read, move |r| {
            if r.is_ok() {
                done.fetch_add(1, Ordering::Release);
            }
        });
    }
    mapped
}

/// After a frame's submission finished: waits until every buffer of [`map_for_read`] is
/// mapped. wgpu may run a map callback on a later poll than the one that saw the submission
/// finish, or on another thread that polled the same device first (and is still running the
/// callbacks), so this polls once more, waits for all submitted work, then polls for up to 5 s
/// (all bounded), before reporting a frame that finished unmapped as [`RunError::Device`].
pub(crate) fn await_mapped(
    gpu: &Gpu,
    mapped: &AtomicUsize,
    n: usize,
    what: &str,
) -> Result<(), RunError> {
    if mapped.load(Ordering::Acquire) != n {
        let _ = gpu.device.poll(wgpu::PollType::Poll);
    }
    if mapped.load(Ordering::Acquire) != n {
        gpu.wait_for(None, what)?;
    }
    // Another thread polling the same device (tests share one) may have taken the callbacks
    // and be running them right now: give it the GPU's timeout, as every other wait, before
    // calling it an error (a few seconds could run out on a loaded machine, where that thread
    // may be descheduled; the wait ends as soon as the status is mapped).
    let deadline = std::time::Instant::now() + gpu.timeout;
    while mapped.load(Ordering::Acquire) != n && std::time::Instant::now() < deadline {
        let _ = gpu.device.poll(wgpu::PollType::Poll);
        std::thread::sleep(std::time::Duration::from_millis(1));
    }
    if mapped.load(Ordering::Acquire) != n {
        return Err(RunError::Device(format!(
            "{what} finished but its status was not mapped"
        )));
    }
    Ok(())
}

/// A `MAP_READ | COPY_DST` buffer of `words` u32 words (at least 2, an even count: maps are
/// 8-byte granular).
pub(crate) fn map_buffer(gpu: &Gpu, label: &str, words: u64) -> Result<wgpu::Buffer, RunError> {
    let bytes = words.max(2).next_multiple_of(2) * 4;
    if bytes > gpu.device.limits().max_buffer_size {
        return Err(RunError::Device(format!(
            "buffer `{label}` needs {bytes} bytes, more than this device allows"
        )));
    }
    Ok(gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: bytes,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    }))
}

/// The first `words` words of a mapped buffer; unmaps it.
pub(crate) fn read_mapped(b: &wgpu::Buffer, words: u64) -> Result<Vec<u32>, RunError> {
    let out = {
        let view = b
            .slice(..)
            .get_mapped_range()
            .map_err(|e| RunError::Device(format!("mapped range: {e}")))?;
        bytemuck::cast_slice::<u8, u32>(&view)[..words as usize].to_vec()
    };
    b.unmap();
    Ok(out)
}
