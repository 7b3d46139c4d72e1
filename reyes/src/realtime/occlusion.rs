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
//! The first frame's history is the first pass of the single frame (`start_history`): the
//! roots [`front_items`] marks for the host's unturned roots, the nearest patch of each cell,
//! so that the first frame's phase 1 draws about the front and phase 2 culls the rest (a
//! history of every patch would make the first frame draw everything, the unculled frame). A
//! frame rendered again resets it the same way from that frame's roots. The image is that of
//! the frame without culling, bit for bit, whatever the history holds: any split of the roots between the phases draws every root
//! once, and phase 2 tests only against a pyramid of samples really written (the argument of
//! [`crate::stages::hiz`]). A stale or partial history (a frame rendered again, whose
//! attempt wrote part of it) costs work, never pixels.
//!
//! Queue sizes: the recorded run is sized by the single frame with its culling passes
//! ([`super::RealtimeRenderer::new`]), and a frame rendered again renders with them too (the
//! unculled frame of a deep scene is many times the culled one's work and memory). A phase
//! out of room says so in its status, like a frame without culling: the frame is rendered
//! again, and the sizes grow to that render's needs; where a phase needed more than the
//! culled single frame measured (they split the roots differently), so that the sizes would
//! not grow, the queues out of room (or the rounds) double instead (`grow`): each frame
//! rendered again grows them, so frames stop being rendered again once a phase fits.

use crate::frame::{FrameData, FrameUniforms, PatchItem};
use crate::gpu::hiz::HizPasses;
use crate::gpu::{FrameTarget, SceneBuffers};
use crate::gpu_render::GpuRenderer;
use crate::stages::hiz::{
    AUTO_MIN_DEPTH_COMPLEXITY, OCCLUSION_AUTO, OCCLUSION_ON, OCCLUSION_TEST, depth_complexity,
    front_items,
};
use scheduler::{DeviceSeeds, Gpu, RecordedRun, RecordedSize, RunError};

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

/// The occlusion history to start from (`visible`, one word per patch: 1 visible, 0 not) for
/// root items `items` of `data` (one per patch, in patch order, untagged): the roots the
/// single frame draws in its first pass ([`front_items`] over the whole image), the nearest
/// of each cell and those crossing the near plane. Any history gives the same image (module
/// documentation); this one lets the next frame's phase 1 draw about the front only.
pub(crate) fn start_history(data: &FrameData, items: &[PatchItem]) -> Vec<u32> {
    let front = front_items(data, items, data.frame.whole_image());
    front.into_iter().map(u32::from).collect()
}

/// The fixed sizes after a pipelined frame that culls ran out of room (`why`, the scheduler's
/// reason) and was rendered again with the culling passes, which measured `measured` (already
/// at least `wanted`, the sizes that ran out). Where that render asked for no more than
/// `wanted` (its passes split the roots otherwise than the phases), the capacities double
/// when a queue was out of room (the megakernel's `out of room`, the multi-pass's `a round
/// refused`) and the rounds when items were left after the last round; a launch at its loop
/// bound grows nothing (more room does not help it).
pub(crate) fn grow(why: &str, wanted: &RecordedSize, measured: RecordedSize) -> RecordedSize {
    if measured != *wanted {
        return measured;
    }
    let mut size = measured;
    if why.contains("out of room") || why.contains("a round refused") {
        for c in &mut size.capacity {
            *c = c.saturating_mul(2);
        }
    }
    if why.contains("items left after") {
        size.rounds = size.rounds.saturating_mul(2).max(1);
    }
    size
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

    /// Sizes a culled render measured above those that ran out are taken as they are; equal
    /// ones double where room or rounds ran out, and stay where a launch hit its loop bound.
    #[test]
    fn sizes_grow_after_every_shortfall_of_room() {
        let wanted = RecordedSize {
            capacity: vec![4, 10],
            rounds: 3,
        };
        let more = RecordedSize {
            capacity: vec![5, 10],
            rounds: 3,
        };
        assert_eq!(
            grow("queue `dice` out of room", &wanted, more.clone()),
            more
        );
        let doubled = RecordedSize {
            capacity: vec![8, 20],
            rounds: 3,
        };
        let room = "7 items pending, 0 abandoned: queue `bound` out of room at 4 slots";
        assert_eq!(grow(room, &wanted, wanted.clone()), doubled);
        let refused = "a round refused: queue `split` may receive 9 items, more than its 4 slots";
        assert_eq!(grow(refused, &wanted, wanted.clone()), doubled);
        let rounds = grow("5 items left after 3 rounds", &wanted, wanted.clone());
        assert_eq!(rounds.rounds, 6);
        assert_eq!(rounds.capacity, wanted.capacity);
        let bound = "3 items pending, 0 abandoned: the launch ended at its loop bound";
        assert_eq!(grow(bound, &wanted, wanted.clone()), wanted);
    }
}
