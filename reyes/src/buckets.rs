//! Screen-space buckets under a memory budget (Patney & Owens 2008, §3.2 and §5.3): when a
//! frame's working memory (the sample buffer plus the scheduler's queues) would exceed the
//! budget, the image is cut into buckets rendered one after another, each with its own sample
//! buffer and only the patches that may reach it. A bucket whose queues still overflow is cut
//! into four and rendered again; nothing is dropped.

use crate::frame::{FrameUniforms, PatchItem, Tile};
use crate::stages::{Weights, bound::CULL_MARGIN_PX, cp_point, project};

/// Buckets are never cut below this side (pixels); a budget that a bucket this small cannot
/// meet is an error.
pub const MIN_BUCKET_SIDE: u32 = 16;

/// Bytes of one pixel's sub-samples (one 64-bit key each).
pub fn sample_bytes_per_pixel(f: &FrameUniforms) -> u64 {
    (f.spp_x * f.spp_y) as u64 * 8
}

/// The buckets to start with: the whole image when its samples fit in half the budget (the
/// other half is for the queues), else a grid of equal buckets that do.
pub fn plan(f: &FrameUniforms, budget: Option<u64>) -> Vec<Tile> {
    let whole = f.whole_image();
    let Some(budget) = budget else {
        return vec![whole];
    };
    let max_pixels = (budget / 2 / sample_bytes_per_pixel(f)).max(1);
    if (f.width as u64) * (f.height as u64) <= max_pixels {
        return vec![whole];
    }
    let side = ((max_pixels as f64).sqrt() as u32 / MIN_BUCKET_SIDE * MIN_BUCKET_SIDE)
        .max(MIN_BUCKET_SIDE);
    let w = side.min(f.width);
    let h = ((max_pixels / w as u64) as u32 / MIN_BUCKET_SIDE * MIN_BUCKET_SIDE)
        .clamp(MIN_BUCKET_SIDE, f.height);
    let mut tiles = Vec::new();
    for y0 in (0..f.height).step_by(h as usize) {
        for x0 in (0..f.width).step_by(w as usize) {
            tiles.push(Tile {
                x0,
                y0,
                w: w.min(f.width - x0),
                h: h.min(f.height - y0),
            });
        }
    }
    tiles
}

/// The four quarters of a bucket, or `None` when it is already at the smallest size.
pub fn quarter(t: Tile) -> Option<Vec<Tile>> {
    if t.w <= MIN_BUCKET_SIDE && t.h <= MIN_BUCKET_SIDE {
        return None;
    }
    let (hw, hh) = (t.w.div_ceil(2), t.h.div_ceil(2));
    let mut q = Vec::new();
    for (y0, h) in [(t.y0, hh), (t.y0 + hh, t.h - hh)] {
        for (x0, w) in [(t.x0, hw), (t.x0 + hw, t.w - hw)] {
            if w > 0 && h > 0 {
                q.push(Tile { x0, y0, w, h });
            }
        }
    }
    Some(q)
}

/// Whether a root patch may reach `tile`: conservative (one pixel wider than Bound's own cull,
/// which runs again on the GPU; the hull of the Euclidean control points holds a rational
/// patch too), and always true for a patch crossing the near plane, which
/// has no screen bound yet. `w`: the item's weights if its patch is rational
/// (`stages::item_weights`).
pub fn may_reach(f: &FrameUniforms, item: &PatchItem, w: Option<&Weights>, t: Tile) -> bool {
    // Motion blur and depth of field move patches beyond this bound: Bound culls them.
    if f.uvt != crate::frame::UVT_OFF {
        return true;
    }
    let mut lo = [f32::INFINITY; 2];
    let mut hi = [f32::NEG_INFINITY; 2];
    for k in 0..16 {
        // The Euclidean point.
        let p = match w {
            Some(w) => cp_point(&item.cp, k) / w[k],
            None => cp_point(&item.cp, k),
        };
        if !(p.z >= f.near) {
            return true;
        }
        let s = project(f, p);
        for a in 0..2 {
            lo[a] = lo[a].min(s[a]);
            hi[a] = hi[a].max(s[a]);
        }
    }
    let m = CULL_MARGIN_PX + 1.0;
    hi[0] >= t.x0 as f32 - m
        && hi[1] >= t.y0 as f32 - m
        && lo[0] <= (t.x0 + t.w) as f32 + m
        && lo[1] <= (t.y0 + t.h) as f32 + m
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frame(w: u32, h: u32) -> FrameUniforms {
        let scene = crate::scene::builtin_teapot();
        let o = crate::frame::RenderOptions {
            width: Some(w),
            height: Some(h),
            pixel_samples: Some((2, 2)),
            ..Default::default()
        };
        crate::frame::FrameData::new(&scene, &o).unwrap().frame
    }

    /// Every pixel belongs to exactly one bucket, and each bucket's samples fit half the budget.
    fn assert_partition(f: &FrameUniforms, tiles: &[Tile], budget: u64) {
        let mut hits = vec![0u8; (f.width * f.height) as usize];
        for t in tiles {
            assert!(t.w as u64 * t.h as u64 * sample_bytes_per_pixel(f) <= budget / 2);
            for y in t.y0..t.y0 + t.h {
                for x in t.x0..t.x0 + t.w {
                    hits[(y * f.width + x) as usize] += 1;
                }
            }
        }
        assert!(hits.iter().all(|&h| h == 1));
    }

    #[test]
    fn buckets_partition_the_image_within_the_budget() {
        let f = frame(301, 203);
        assert_eq!(plan(&f, None), vec![f.whole_image()]);
        assert_eq!(plan(&f, Some(1 << 30)), vec![f.whole_image()]);
        for budget in [64 << 10, 200 << 10, 1 << 20] {
            let tiles = plan(&f, Some(budget));
            assert!(tiles.len() > 1, "{budget}");
            assert_partition(&f, &tiles, budget);
        }
    }

    #[test]
    fn quartering_keeps_the_pixels_and_stops_at_the_smallest_bucket() {
        let t = Tile {
            x0: 5,
            y0: 7,
            w: 33,
            h: 17,
        };
        let q = quarter(t).unwrap();
        let area: u32 = q.iter().map(|t| t.w * t.h).sum();
        assert_eq!(area, 33 * 17);
        assert!(q.iter().all(|s| s.x0 >= 5 && s.x0 + s.w <= 38));
        let small = Tile {
            x0: 0,
            y0: 0,
            w: MIN_BUCKET_SIDE,
            h: MIN_BUCKET_SIDE,
        };
        assert_eq!(quarter(small), None);
    }
}
