//! The viewer's draw of a frame to a window (`reyes view`): a render pipeline of one full-screen
//! triangle (`present.wgsl`) that reads the renderer's 8-bit image where the frame left it on
//! the GPU ([`crate::realtime::RealtimeRenderer::image_buffer`]), so a frame is shown without a
//! read-back. The image is fitted into the target with its aspect kept, centred, nearest pixel,
//! and composited by its coverage over a background ([`present_pixel`], the shader's twin).

use crate::shaders;
use bytemuck::{Pod, Zeroable};
use scheduler::{Gpu, RunError};

/// The background behind the scene and around a letterboxed image: dark grey, sRGB 8-bit
/// (r, g, b, unused alpha).
pub const BACKGROUND: [u8; 4] = [48, 48, 48, 255];

/// The draw's parameters (`PresentParams` in present.wgsl).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq, Pod, Zeroable)]
pub struct PresentParams {
    /// Image width in pixels.
    pub image_w: u32,
    /// Image height in pixels.
    pub image_h: u32,
    /// Target (window surface) width in pixels.
    pub target_w: u32,
    /// Target height in pixels.
    pub target_h: u32,
    /// 1: the target format encodes sRGB on store, so the shader decodes first.
    pub srgb_target: u32,
    /// The background as an rgba8 word (bytes r, g, b, a in memory order).
    pub background: u32,
    /// Padding to the WGSL struct's 32 bytes.
    pub pad: [u32; 2],
}

impl PresentParams {
    /// The parameters of drawing a `image` (width, height) image onto a `target` (width,
    /// height) of format `format`, over [`BACKGROUND`].
    pub fn new(image: (u32, u32), target: (u32, u32), format: wgpu::TextureFormat) -> Self {
        PresentParams {
            image_w: image.0.max(1),
            image_h: image.1.max(1),
            target_w: target.0.max(1),
            target_h: target.1.max(1),
            srgb_target: format.is_srgb() as u32,
            background: u32::from_le_bytes(BACKGROUND),
            pad: [0; 2],
        }
    }

    /// Where the image lands in the target: (x0, y0, width, height) in target pixels; the
    /// largest scale that fits, the scaled side rounded down, centred (present.wgsl's
    /// `present_fit`).
    pub fn fit(&self) -> (u32, u32, u32, u32) {
        let (iw, ih, tw, th) = (self.image_w, self.image_h, self.target_w, self.target_h);
        let (mut w, mut h) = (tw, th);
        if tw * ih <= th * iw {
            h = (tw * ih / iw).max(1);
        } else {
            w = (th * iw / ih).max(1);
        }
        ((tw - w) / 2, (th - h) / 2, w, h)
    }
}

/// The 8-bit colour the draw writes at target pixel (`x`, `y`) on a UNORM target: the nearest
/// image pixel of the fitted image composited by its alpha over the background, per channel
/// `(p a + bg (255 - a) + 127) / 255`; the background outside the image. Alpha is 255 (the
/// window is opaque). `image`: `image_w * image_h` rgba8 words (rgba8.wgsl's layout).
pub fn present_pixel(p: &PresentParams, image: &[u32], x: u32, y: u32) -> [u8; 4] {
    let (x0, y0, w, h) = p.fit();
    let bg = p.background;
    let mut c = bg;
    if (x0..x0 + w).contains(&x) && (y0..y0 + h).contains(&y) {
        let ix = (x - x0) * p.image_w / w;
        let iy = (y - y0) * p.image_h / h;
        let px = image[(iy * p.image_w + ix) as usize];
        let a = px >> 24;
        c = 0;
        for k in [0, 8, 16] {
            let v = (((px >> k) & 255) * a + ((bg >> k) & 255) * (255 - a) + 127) / 255;
            c |= v << k;
        }
    }
    let b = c.to_le_bytes();
    [b[0], b[1], b[2], 255]
}

/// The draw's pipeline for one target format.
pub struct Presenter {
    pipeline: wgpu::RenderPipeline,
    params: wgpu::Buffer,
    format: wgpu::TextureFormat,
}

impl Presenter {
    /// Compiles present.wgsl for targets of `format`. Errors: [`RunError::Program`] from the
    /// WGSL, [`RunError::Device`].
    pub fn new(gpu: &Gpu, format: wgpu::TextureFormat) -> Result<Presenter, RunError> {
        let module = gpu.shader("reyes present", shaders::PRESENT)?;
        let pipeline = gpu
            .device
            .create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some("reyes present"),
                layout: None,
                vertex: wgpu::VertexState {
                    module: &module,
                    entry_point: Some("present_vertex"),
                    compilation_options: Default::default(),
                    buffers: &[],
                },
                primitive: wgpu::PrimitiveState::default(),
                depth_stencil: None,
                multisample: wgpu::MultisampleState::default(),
                fragment: Some(wgpu::FragmentState {
                    module: &module,
                    entry_point: Some("present_fragment"),
                    compilation_options: Default::default(),
                    targets: &[Some(wgpu::ColorTargetState {
                        format,
                        blend: None,
                        write_mask: wgpu::ColorWrites::ALL,
                    })],
                }),
                multiview_mask: None,
                cache: None,
            });
        let params = gpu.upload("present params", &[PresentParams::zeroed()])?;
        Ok(Presenter {
            pipeline,
            params,
            format,
        })
    }

    /// The target format this draw was compiled for.
    pub fn format(&self) -> wgpu::TextureFormat {
        self.format
    }

    /// Records the draw of `image` (`image_size` pixels, rgba8 words) onto `target`
    /// (`target_size` pixels, this presenter's format) into `enc`. The parameters are written
    /// through the queue, so they take effect at the next submit: one draw per submit.
    pub fn draw(
        &self,
        gpu: &Gpu,
        enc: &mut wgpu::CommandEncoder,
        image: &wgpu::Buffer,
        image_size: (u32, u32),
        target: &wgpu::TextureView,
        target_size: (u32, u32),
    ) {
        let p = PresentParams::new(image_size, target_size, self.format);
        gpu.queue
            .write_buffer(&self.params, 0, bytemuck::bytes_of(&p));
        let bind = gpu.bind_buffers(
            "present",
            &self.pipeline.get_bind_group_layout(0),
            &[&self.params, image],
        );
        let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("present"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: target,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: None,
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &bind, &[]);
        pass.draw(0..3, 0..1);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn params_match_their_wgsl_layout() {
        let l = scheduler::wgsl::struct_layout(shaders::PRESENT, "PresentParams").unwrap();
        assert_eq!(l.size as usize, size_of::<PresentParams>());
        for (field, off) in [
            ("image_w", std::mem::offset_of!(PresentParams, image_w)),
            ("target_h", std::mem::offset_of!(PresentParams, target_h)),
            (
                "srgb_target",
                std::mem::offset_of!(PresentParams, srgb_target),
            ),
            (
                "background",
                std::mem::offset_of!(PresentParams, background),
            ),
        ] {
            let got = l.members.iter().find(|(n, _)| n == field).map(|m| m.1);
            assert_eq!(got.map(|o| o as usize), Some(off), "PresentParams.{field}");
        }
    }

    #[test]
    fn the_fit_keeps_the_aspect_and_centres() {
        let f = |i, t| PresentParams::new(i, t, wgpu::TextureFormat::Rgba8Unorm).fit();
        assert_eq!(f((320, 240), (320, 240)), (0, 0, 320, 240));
        assert_eq!(f((320, 240), (640, 480)), (0, 0, 640, 480));
        // A wider target: pillarbox.
        assert_eq!(f((320, 240), (800, 480)), (80, 0, 640, 480));
        // A taller one: letterbox.
        assert_eq!(f((320, 240), (320, 400)), (0, 80, 320, 240));
        assert_eq!(f((4, 4), (1, 1000)), (0, 499, 1, 1));
    }

    #[test]
    fn same_size_shows_each_pixel_composited_over_the_background() {
        let p = PresentParams::new((2, 1), (2, 1), wgpu::TextureFormat::Bgra8Unorm);
        let img = [u32::from_le_bytes([10, 20, 30, 255]), 0];
        assert_eq!(present_pixel(&p, &img, 0, 0), [10, 20, 30, 255]);
        assert_eq!(present_pixel(&p, &img, 1, 0), BACKGROUND);
        // Half coverage: halfway to the background, rounded.
        let img = [u32::from_le_bytes([200, 0, 48, 128]), 0];
        assert_eq!(present_pixel(&p, &img, 0, 0), [124, 24, 48, 255]);
    }
}
