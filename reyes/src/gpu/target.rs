//! What one frame of one size renders into: the sub-samples (one 64-bit depth-and-colour key
//! each), the Reyes counters, the resolved linear RGBA and depth, and optionally the 8-bit
//! image; allocated once and reused by every frame of that size.

use crate::stages::COUNTERS;
use scheduler::{Gpu, RunError};
use std::sync::atomic::{AtomicU64, Ordering};

/// A frame's buffers on the device (see the module documentation).
pub struct FrameTarget {
    id: u64,
    /// (sample words, pixels)
    size: (u64, u64),
    pub(crate) samples: wgpu::Buffer,
    pub(crate) counters: wgpu::Buffer,
    /// Linear RGBA, 4 f32 a pixel, row-major from the top row.
    pub(crate) rgba: wgpu::Buffer,
    /// Camera-space depth, one f32 a pixel.
    pub(crate) depth: wgpu::Buffer,
    /// The depth pyramid of the bucket being rendered (`stages::hiz`, hiz.wgsl), sized for
    /// any bucket of the image ([`crate::stages::hiz::capacity`]).
    pub(crate) hiz: wgpu::Buffer,
    /// The 8-bit sRGB image (`rgba8.wgsl`), one u32 a pixel; only where asked for.
    pub(crate) rgba8: Option<wgpu::Buffer>,
}

impl FrameTarget {
    /// Buffers for `sample_words` u32 words of sub-samples (the largest bucket's) and an image
    /// of `pixels` pixels, with the 8-bit image when `rgba8`. Errors: a buffer beyond the
    /// device's binding limit ([`RunError::Device`]).
    pub fn new(
        gpu: &Gpu,
        sample_words: u64,
        pixels: u64,
        rgba8: bool,
    ) -> Result<FrameTarget, RunError> {
        static NEXT: AtomicU64 = AtomicU64::new(0);
        Ok(FrameTarget {
            id: NEXT.fetch_add(1, Ordering::Relaxed),
            size: (sample_words, pixels),
            samples: gpu.storage_buffer("samples", sample_words)?,
            counters: gpu.storage_buffer("counters", COUNTERS as u64)?,
            rgba: gpu.storage_buffer("rgba", pixels * 4)?,
            depth: gpu.storage_buffer("depth", pixels)?,
            hiz: gpu.storage_buffer("hiz", crate::stages::hiz::capacity(pixels))?,
            rgba8: match rgba8 {
                true => Some(gpu.storage_buffer("rgba8", pixels)?),
                false => None,
            },
        })
    }

    /// Sub-sample words and pixels the target holds.
    pub fn size(&self) -> (u64, u64) {
        self.size
    }

    /// A number no other target of this process has (bind groups made for it name it).
    pub(crate) fn id(&self) -> u64 {
        self.id
    }

    /// The 8-bit image buffer. Panics on a target made without it (a renderer's invariant).
    pub(crate) fn rgba8(&self) -> &wgpu::Buffer {
        self.rgba8.as_ref().expect("a target with its 8-bit image")
    }
}
