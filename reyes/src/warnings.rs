//! The warnings of a rendered frame: where the renderer gave up on part of the scene (grids
//! diced at the split limit) or drew nothing at all. (Pieces still crossing the near plane after
//! the allowed eye splits are not among them: they are diced and clipped, nothing is lost.) Read from the stage counters, so the GPU and CPU pipelines give the
//! same messages.

use crate::frame::FrameData;
use crate::stages::{self as s, COUNTERS};

/// One message per kind of give-up the counters show; empty for a clean frame.
pub fn frame_warnings(data: &FrameData, counters: &[u64; COUNTERS]) -> Vec<String> {
    let f = &data.frame;
    let mut out = Vec::new();
    let limited = counters[s::C_DEPTH_LIMIT];
    if limited > 0 {
        out.push(format!(
            "{limited} grids reached the split limit (max_depth {}) and were diced coarser than \
             the requested micropolygon size",
            f.max_depth
        ));
    }
    if data.items.is_empty() {
        out.push(
            "nothing was drawn: the world holds no patch (none was given, or every primitive \
             was skipped)"
                .to_string(),
        );
    } else if counters[s::C_MICROPOLYGONS] == 0 {
        out.push(format!(
            "nothing was drawn: all {} patches were culled ({} pieces outside the near/far \
             range, {} off screen, {} facing away)",
            data.items.len(),
            counters[s::C_CULL_CLIP],
            counters[s::C_CULL_OFFSCREEN],
            counters[s::C_CULL_BACKFACE]
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
        c[s::C_NEAR_CLIPPED] = 3;
        assert!(
            frame_warnings(&data, &c).is_empty(),
            "near-clipped grids lose nothing"
        );
        c[s::C_DEPTH_LIMIT] = 2;
        let w = frame_warnings(&data, &c);
        assert_eq!(w.len(), 1);
        assert!(w[0].starts_with("2 grids reached the split limit (max_depth 24)"));
        let empty = FrameData {
            items: Vec::new(),
            ..data.clone()
        };
        let w = frame_warnings(&empty, &[0; COUNTERS]);
        assert_eq!(w.len(), 1);
        assert!(w[0].starts_with("nothing was drawn: the world holds no patch"));
        c = [0; COUNTERS];
        c[s::C_CULL_OFFSCREEN] = 32;
        let w = frame_warnings(&data, &c);
        assert_eq!(w.len(), 1);
        assert!(w[0].contains("nothing was drawn: all 32 patches"), "{w:?}");
    }
}
