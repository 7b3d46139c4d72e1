//! The warnings of a rendered frame: where the renderer gave up on part of the scene (pieces
//! still crossing the near plane after the allowed eye splits, grids diced at the split limit)
//! or drew nothing at all. Read from the stage counters, so the GPU and CPU pipelines give the
//! same messages.

use crate::frame::FrameData;
use crate::stages::{self as s, COUNTERS};

/// One message per kind of give-up the counters show; empty for a clean frame.
pub fn frame_warnings(data: &FrameData, counters: &[u64; COUNTERS]) -> Vec<String> {
    let f = &data.frame;
    let mut out = Vec::new();
    let near = counters[s::C_CULL_NEAR];
    if near > 0 {
        out.push(format!(
            "{near} patch pieces still crossed the near plane (z = {}) after {} eye splits and \
             were culled",
            f.near,
            f.max_eye_splits.min(f.max_depth)
        ));
    }
    let limited = counters[s::C_DEPTH_LIMIT];
    if limited > 0 {
        out.push(format!(
            "{limited} grids reached the split limit (max_depth {}) and were diced coarser than \
             the requested micropolygon size",
            f.max_depth
        ));
    }
    if !data.items.is_empty() && counters[s::C_MICROPOLYGONS] == 0 {
        out.push(format!(
            "nothing was drawn: all {} patches were culled ({} pieces outside the near/far \
             range, {} off screen, {} at the near plane)",
            data.items.len(),
            counters[s::C_CULL_CLIP],
            counters[s::C_CULL_OFFSCREEN],
            near
        ));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frame::RenderOptions;

    #[test]
    fn each_counter_gives_its_message_and_a_clean_frame_none() {
        let data =
            FrameData::new(&crate::scene::builtin_teapot(), &RenderOptions::default()).unwrap();
        let mut c = [0u64; COUNTERS];
        c[s::C_MICROPOLYGONS] = 100;
        assert!(frame_warnings(&data, &c).is_empty());
        c[s::C_CULL_NEAR] = 3;
        c[s::C_DEPTH_LIMIT] = 2;
        let w = frame_warnings(&data, &c);
        assert_eq!(w.len(), 2);
        assert!(w[0].starts_with("3 patch pieces still crossed the near plane"));
        assert!(w[1].starts_with("2 grids reached the split limit (max_depth 24)"));
        c = [0; COUNTERS];
        c[s::C_CULL_OFFSCREEN] = 32;
        let w = frame_warnings(&data, &c);
        assert_eq!(w.len(), 1);
        assert!(w[0].contains("nothing was drawn: all 32 patches"), "{w:?}");
    }
}
