//! Occlusion culling of pipelined frames from the previous frame: the two-phase scheme of
//! GPU-driven renderers (Haar and Aaltonen, "GPU-Driven Rendering Pipelines", SIGGRAPH 2015
//! course), on the GPU with no read-back; docs/reyes.md, *Occlusion culling*.
//!
//! Every frame, `make_roots` (roots.wgsl) tags each root item with [`ROOT_HISTORY`] and, when
//! some piece of that root passed Bound's occlusion test in the frame before,
//! [`ROOT_WAS_VISIBLE`] (the scene's per-patch history, `visible` in common.wgsl), then clears
//! the history for this frame. Then two scheduler runs of the same recorded sizes, each seeded
//! with every root:
//! 1. **phase 1** (`Frame.occlusion = OCCLUSION_ON`): Bound drops, at the root, the roots not
//!    visible last frame; the others render without culling;
//! 2. the depth pyramid of the samples phase 1 wrote (`hiz.wgsl`, the single frame's passes);
//! 3. **phase 2** (`OCCLUSION_TEST`): the other roots render with the occlusion test, and
//!    phase 1's roots are only tested again, at the root, drawing and counting nothing. A
//!    root is visible for the next frame when some piece of it passed the test and was diced
//!    (a piece crossing the near plane is never culled), or when, as a root of phase 1, it
//!    passed the test again; Bound then sets its patch's history.
//!
//! The first frame finds every patch visible (the history starts so), as the frame after a
//! scene's upload should. The image is that of the frame without culling, bit for bit,
//! whatever the history holds: any split of the roots between the phases draws every root
//! once, and phase 2 tests only against a pyramid of samples really written (the argument of
//! [`crate::stages::hiz`]). A stale or partial history (a frame rendered again, whose
//! attempt wrote part of it) costs work, never pixels.
//!
//! Queue sizes: each phase does part of the work of the frame without culling, which sized
//! the recorded run ([`super::RealtimeRenderer::new`]) and which a frame rendered again
//! renders (culling off, so that the sizes it grows to cover either phase). A phase out of
//! room says so in its status, like a frame without culling: the frame is rendered again.

use crate::frame::{FrameData, FrameUniforms};
use crate::gpu::hiz::HizPasses;
use crate::gpu::{FrameTarget, SceneBuffers};
use crate::gpu_render::GpuRenderer;
use crate::stages::hiz::{
    AUTO_MIN_DEPTH_COMPLEXITY, OCCLUSION_AUTO, OCCLUSION_ON, OCCLUSION_TEST, depth_complexity,
};
use scheduler::{DeviceSeeds, Gpu, RecordedRun, RunError};

/// `PatchItem::rates` of a root item of a frame that culls from the previous frame
/// (`ROOT_HISTORY` in patch_item.wgsl).
pub const ROOT_HISTORY: u32 = 0x10_0000;
/// `PatchItem::rates` of such a root visible in the frame before (`ROOT_WAS_VISIBLE`).
pub const ROOT_WAS_VISIBLE: u32 = 0x20_0000;

/// Scheduler runs a frame that culls records: phase 1 and phase 2.
pub const PHASES: usize = 2;

/// What a renderer of pipelined frames needs to cull: each phase's frame uniform and the
/// pyramid's passes, made once.
pub(crate) struct Culling {
    /// The whole image's frame uniform with `occlusion` [`OCCLUSION_ON`] (phase 1) and
    /// [`OCCLUSION_TEST`] (phase 2), copied into the scene's before each phase.
    phases: [wgpu::Buffer; PHASES],
    hiz: HizPasses,
}

impl Culling {
    /// For frames of `f` (the whole image) on `target`. `None` when the pyramid of the whole
    /// image does not fit the target's buffer (never: it is sized for it). Errors: a pipeline
    /// or buffer the device refuses.
    pub(crate) fn new(
        gpu: &Gpu,
        renderer: &GpuRenderer,
        f: &FrameUniforms,
        target: &FrameTarget,
    ) -> Result<Option<Culling>, RunError> {
        let f = f.with_tile(f.whole_image());
        let pixels = f.width as u64 * f.height as u64;
        let hiz = renderer.pipelines.hiz(gpu)?;
        let Some(hiz) = hiz.passes(gpu, &f, &target.samples, &target.hiz, pixels)? else {
            return Ok(None);
        };
        let phase = |occlusion| FrameUniforms { occlusion, ..f };
        Ok(Some(Culling {
            phases: [
                gpu.upload("frame, phase 1", &[phase(OCCLUSION_ON)])?,
                gpu.upload("frame, phase 2", &[phase(OCCLUSION_TEST)])?,
            ],
            hiz,
        }))
    }

    /// Records the frame's two phases into `enc` (module documentation), run `rec` seeded
    /// with `seeds` (every root) each time, phase k's status copied to word `k * words` of
    /// `status` (`words`: [`RecordedRun::status_words`]).
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn record(
        &self,
        gpu: &Gpu,
        renderer: &GpuRenderer,
        enc: &mut wgpu::CommandEncoder,
        (rec, seeds): (&RecordedRun, &[DeviceSeeds]),
        (scene, scene_bind): (&SceneBuffers, &wgpu::BindGroup),
        status: &wgpu::Buffer,
        words: u64,
    ) -> Result<(), RunError> {
        let frame = scene.frame_buffer();
        for (k, uniform) in self.phases.iter().enumerate() {
            if k > 0 {
                renderer.pipelines.hiz(gpu)?.record_passes(enc, &self.hiz);
            }
            enc.copy_buffer_to_buffer(uniform, 0, frame, 0, uniform.size());
            let sched = &renderer.scheduler;
            rec.record(
                sched,
                enc,
                seeds,
                Some(scene_bind),
                status,
                k as u64 * words,
            )?;
        }
        Ok(())
    }
}

/// Whether frames of `base` (its unturned roots) cull, asked `occlusion`
/// (`FrameUniforms::occlusion` of the options): always with [`OCCLUSION_ON`], never with
/// `OCCLUSION_OFF`; with [`OCCLUSION_AUTO`] where the roots lie
/// [`AUTO_MIN_DEPTH_COMPLEXITY`] deep or more over the image ([`depth_complexity`], as
/// `reyes render` decides per bucket): phase 2 seeds every root again and the pyramid costs a
/// pass over the samples, which a shallow scene does not win back.
pub(crate) fn wanted(base: &FrameData, occlusion: u32) -> bool {
    match occlusion {
        OCCLUSION_ON => true,
        OCCLUSION_AUTO => {
            let whole = base.frame.whole_image();
            depth_complexity(base, &base.items, whole) >= AUTO_MIN_DEPTH_COMPLEXITY
        }
        _ => false,
    }
}

/// Clears the tags `make_roots` gives root items ([`ROOT_HISTORY`], [`ROOT_WAS_VISIBLE`]):
/// roots read back for a frame rendered again by the offline core, which renders every root.
pub(crate) fn untag(items: &mut [crate::frame::PatchItem]) {
    for i in items {
        i.rates &= !(ROOT_HISTORY | ROOT_WAS_VISIBLE);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The tags are those of patch_item.wgsl, clear of the bits Bound's dice rates use.
    #[test]
    fn tags_match_the_wgsl_constants() {
        let src = crate::shaders::PATCH_ITEM;
        for (name, v) in [
            ("ROOT_HISTORY", ROOT_HISTORY),
            ("ROOT_WAS_VISIBLE", ROOT_WAS_VISIBLE),
        ] {
            let line = format!("const {name}: u32 = {v:#x}u;");
            assert!(src.contains(&line), "patch_item.wgsl lacks `{line}`");
        }
        assert_eq!((ROOT_HISTORY | ROOT_WAS_VISIBLE) & 0x1_ffff, 0);
    }
}
