//! Twin of `shaders/reyes/hiz.wgsl` and of `hiz_occluded` in common.wgsl: the hierarchical
//! depth (Hi-Z) pyramid of a bucket's samples and the occlusion test Bound runs against it
//! (Greene, Kass and Miller, "Hierarchical Z-buffer visibility", SIGGRAPH 1993, with a
//! max-depth pyramid built from what is already drawn, as GPU renderers build it); and the
//! choice of the root patches drawn before the pyramid is built ([`front_items`]).
//!
//! Depths are compared as the bits of positive f32 (monotonic as u32): a sample's depth bits
//! are the complement of its key's high word ([`super::sample::sample_key`]), so an empty
//! sample (key 0) reads `u32::MAX`, deeper than anything, and is never an occluder. A tile of
//! level 0 holds the largest depth bits of every sub-sample of its [`HIZ_TILE_PX`]-pixel
//! square; a tile of level k the largest of its (up to) 2x2 tiles of level k - 1. An item is
//! occluded when its nearest depth is strictly beyond every tile under its screen bound: each
//! of its keys then loses to the key already at every sample it could write (`atomicMax`), so
//! leaving it out changes no sample. docs/reyes.md, *Occlusion culling*, gives the argument.

use crate::frame::{FrameData, FrameUniforms, PatchItem, Tile};
use crate::stages::{bound::CULL_MARGIN_PX, cp_point, item_weights, project};

/// Side of a level-0 tile, pixels (`HIZ_TILE_PX` in common.wgsl).
pub const HIZ_TILE_PX: u32 = 8;

/// Tiles per side of the square Bound tests (`HIZ_SPAN` in common.wgsl): it climbs the
/// pyramid until the bound spans at most this many tiles each way, then reads them all.
pub const HIZ_SPAN: u32 = 4;

/// `FrameUniforms::occlusion`: no occlusion culling (`--occlusion off`).
pub const OCCLUSION_OFF: u32 = 0;
/// `FrameUniforms::occlusion`: culling allowed; no pyramid yet (the first pass of a frame).
pub const OCCLUSION_ON: u32 = 1;
/// `FrameUniforms::occlusion`: Bound tests items against the bucket's pyramid (the second
/// pass). Set by the renderers only, for the runs after the pyramid is built.
pub const OCCLUSION_TEST: u32 = 2;
/// `FrameUniforms::occlusion`: as [`OCCLUSION_ON`] in a bucket whose [`depth_complexity`] is
/// at least [`AUTO_MIN_DEPTH_COMPLEXITY`], else as [`OCCLUSION_OFF`] (`--occlusion auto`).
/// Bound reads only [`OCCLUSION_TEST`].
pub const OCCLUSION_AUTO: u32 = 3;

/// The [`depth_complexity`] from which `--occlusion auto` renders a bucket in passes. Killeroo
/// and the teapot (about 1-2) stay in one pass, where the extra passes cost more than they
/// save on an H200; a stack of screen-filling layers (its layer count) is culled.
pub const AUTO_MIN_DEPTH_COMPLEXITY: f32 = 4.0;

/// Relative margin taken off an item's nearest depth before the test: the f32 rounding of a
/// surface point evaluated from its control points (a convex combination, a few operations)
/// stays far below it, so a grid point is never nearer than the reduced depth.
pub const DEPTH_MARGIN: f32 = 1.0e-4;

/// One level of the pyramid: (tiles across, tiles down, offset of its first tile in words).
pub type Level = [u32; 3];

/// The levels of the pyramid of a `w` x `h` pixel bucket, from level 0 (tiles of
/// [`HIZ_TILE_PX`]) up to a single tile; `hiz_level` in common.wgsl computes the same.
pub fn levels(w: u32, h: u32) -> Vec<Level> {
    let (mut lw, mut lh) = (w.div_ceil(HIZ_TILE_PX), h.div_ceil(HIZ_TILE_PX));
    let mut out = vec![[lw, lh, 0]];
    let mut off = lw * lh;
    while lw > 1 || lh > 1 {
        lw = lw.div_ceil(2);
        lh = lh.div_ceil(2);
        out.push([lw, lh, off]);
        off += lw * lh;
    }
    out
}

/// Words of the pyramid of a `w` x `h` bucket.
pub fn words(w: u32, h: u32) -> u64 {
    let l = levels(w, h);
    let last = l.last().unwrap();
    last[2] as u64 + last[0] as u64 * last[1] as u64
}

/// Words a pyramid buffer for buckets of at most `pixels` pixels holds: enough for every
/// shape (a 1-pixel-wide bucket included: about `pixels / 4`), plus room for the level
/// rounding. [`words`] of a bucket within it is at most this (tested).
pub fn capacity(pixels: u64) -> u64 {
    pixels / 4 + 256
}

/// A bucket's pyramid on the host: the twin of the GPU's buffer.
pub struct Hiz {
    /// The levels ([`levels`] of the bucket).
    pub levels: Vec<Level>,
    /// Every level's tiles, row-major, level after level: largest depth bits under each.
    pub words: Vec<u32>,
}

/// The depth bits a sample key stands for: its high word complemented (`u32::MAX` for an
/// empty sample).
pub fn key_depth_bits(key: u64) -> u32 {
    !((key >> 32) as u32)
}

/// The pyramid of a bucket's samples (`f`'s tile, `spp` sub-samples a pixel, in the sample
/// buffer's order): `hiz_level0` and `hiz_reduce` in hiz.wgsl.
pub fn build(f: &FrameUniforms, samples: &[u64]) -> Hiz {
    let (w, h, spp) = (f.tile_w, f.tile_h, f.spp_x * f.spp_y);
    let levels = levels(w, h);
    let mut words = vec![0u32; words(w, h) as usize];
    let [lw, lh, _] = levels[0];
    for ty in 0..lh {
        for tx in 0..lw {
            let mut m = 0u32;
            for y in ty * HIZ_TILE_PX..((ty + 1) * HIZ_TILE_PX).min(h) {
                for x in tx * HIZ_TILE_PX..((tx + 1) * HIZ_TILE_PX).min(w) {
                    let base = ((y * w + x) * spp) as usize;
                    for s in 0..spp as usize {
                        m = m.max(key_depth_bits(samples[base + s]));
                    }
                }
            }
            words[(ty * lw + tx) as usize] = m;
        }
    }
    for k in 1..levels.len() {
        let [sw, sh, so] = levels[k - 1];
        let [dw, dh, dof] = levels[k];
        for ty in 0..dh {
            for tx in 0..dw {
                let mut m = 0u32;
                for y in 2 * ty..(2 * ty + 2).min(sh) {
                    for x in 2 * tx..(2 * tx + 2).min(sw) {
                        m = m.max(words[(so + y * sw + x) as usize]);
                    }
                }
                words[(dof + ty * dw + tx) as usize] = m;
            }
        }
    }
    Hiz { levels, words }
}

/// The depth an item's test uses: its nearest depth `zmin` (displacement included) less
/// [`DEPTH_MARGIN`] of the larger magnitude of `zmin` and `zmax` (`hiz_depth` in common.wgsl).
pub fn test_depth(zmin: f32, zmax: f32) -> f32 {
    zmin - DEPTH_MARGIN * zmax.abs().max(zmin.abs())
}

/// `hiz_occluded` in common.wgsl: whether every sample of the bucket within the screen bound
/// [lo, hi] (pixels, grown by [`CULL_MARGIN_PX`] here) holds a depth strictly nearer than `z`
/// (camera space, positive). `hiz`: the bucket's pyramid.
pub fn occluded(f: &FrameUniforms, hiz: &Hiz, lo: glam::Vec2, hi: glam::Vec2, z: f32) -> bool {
    // Pixels of the bucket the bound reaches, as bucket coordinates.
    let x0 = (lo.x - CULL_MARGIN_PX).floor().max(f.tile_x0 as f32);
    let y0 = (lo.y - CULL_MARGIN_PX).floor().max(f.tile_y0 as f32);
    let x1 = (hi.x + CULL_MARGIN_PX)
        .floor()
        .min((f.tile_x0 + f.tile_w - 1) as f32);
    let y1 = (hi.y + CULL_MARGIN_PX)
        .floor()
        .min((f.tile_y0 + f.tile_h - 1) as f32);
    if !(x0 <= x1 && y0 <= y1 && z > 0.0) {
        return false;
    }
    let mut t0 = [
        (x0 as u32 - f.tile_x0) / HIZ_TILE_PX,
        (y0 as u32 - f.tile_y0) / HIZ_TILE_PX,
    ];
    let mut t1 = [
        (x1 as u32 - f.tile_x0) / HIZ_TILE_PX,
        (y1 as u32 - f.tile_y0) / HIZ_TILE_PX,
    ];
    let mut level = 0;
    while t1[0] - t0[0] >= HIZ_SPAN || t1[1] - t0[1] >= HIZ_SPAN {
        t0 = [t0[0] / 2, t0[1] / 2];
        t1 = [t1[0] / 2, t1[1] / 2];
        level += 1;
    }
    let [lw, _, off] = hiz.levels[level];
    let zb = z.to_bits();
    for ty in t0[1]..=t1[1] {
        for tx in t0[0]..=t1[0] {
            if zb <= hiz.words[(off + ty * lw + tx) as usize] {
                return false;
            }
        }
    }
    true
}

/// Which root items of a bucket are drawn in the first pass, before the pyramid is built: the
/// nearest item of each cell. The bucket is cut into a grid of cells (at most 16 x 16); in
/// each, of the items whose control points' bound reaches it, the one of the nearest near
/// depth goes first. Items crossing the near plane go first too: Bound never culls them. A heuristic only (it looks
/// at control points at shutter open, without displacement): either pass may hold any item
/// without changing the image, only the work.
pub fn front_items(data: &FrameData, items: &[PatchItem], tile: Tile) -> Vec<bool> {
    front_of(&screen_extents(data, items), tile)
}

/// [`front_items`] from the items' [`screen_extents`].
fn front_of(extents: &[Extent], tile: Tile) -> Vec<bool> {
    let grid = CellGrid::of(tile);
    let (nx, ny) = (grid.nx, grid.ny);
    let extents: Vec<Option<([usize; 4], f32, f32)>> = (extents.iter())
        .map(|e| {
            let (lo, hi, z0, z1) = (*e)?;
            Some((grid.cells(lo, hi), z0, z1))
        })
        .collect();
    // Per cell, the item of the nearest near depth (the first on a tie).
    let mut nearest = vec![(f32::MAX, usize::MAX); nx * ny];
    for (k, e) in extents.iter().enumerate() {
        let Some((c, z0, _)) = e else { continue };
        for y in c[1]..=c[3] {
            for x in c[0]..=c[2] {
                if *z0 < nearest[y * nx + x].0 {
                    nearest[y * nx + x] = (*z0, k);
                }
            }
        }
    }
    let mut first: Vec<bool> = extents.iter().map(|e| e.is_none()).collect();
    for (_, k) in nearest {
        if k != usize::MAX {
            first[k] = true;
        }
    }
    first
}

/// How many times over a bucket's root items cover the screen cells they reach: the sum of
/// their screen bounds' areas (clipped to the bucket) over the area of the cells of the
/// [`front_items`] grid that some bound reaches. About 1-2 for one object seen from outside,
/// the layer count for stacked layers; infinite when an item crosses the near plane (its bound
/// is unknown). Control points at shutter open, without displacement: a heuristic for
/// `--occlusion auto`, never for what may be culled.
pub fn depth_complexity(data: &FrameData, items: &[PatchItem], tile: Tile) -> f32 {
    complexity_of(&screen_extents(data, items), tile)
}

/// [`depth_complexity`] from the items' [`screen_extents`].
fn complexity_of(extents: &[Extent], tile: Tile) -> f32 {
    let grid = CellGrid::of(tile);
    let mut reached = vec![false; grid.nx * grid.ny];
    let (x0, y0) = (tile.x0 as f32, tile.y0 as f32);
    let (x1, y1) = (x0 + tile.w as f32, y0 + tile.h as f32);
    let mut area = 0.0f64;
    for e in extents {
        let Some((lo, hi, _, _)) = *e else {
            return f32::INFINITY;
        };
        let w = (hi.x.min(x1) - lo.x.max(x0)).max(0.0);
        let h = (hi.y.min(y1) - lo.y.max(y0)).max(0.0);
        if w * h <= 0.0 {
            continue;
        }
        area += (w * h) as f64;
        let c = grid.cells(lo, hi);
        for y in c[1]..=c[3] {
            for x in c[0]..=c[2] {
                reached[y * grid.nx + x] = true;
            }
        }
    }
    let cells = reached.iter().filter(|r| **r).count() as f64;
    match cells > 0.0 {
        true => (area / (cells * grid.cw as f64 * grid.ch as f64)) as f32,
        false => 0.0,
    }
}

/// An item's screen bound (pixels, lower and upper corner) and depth range (camera z, near and
/// far) from its control points at shutter open; `None` when one is not in front of the near
/// plane.
type Extent = Option<(glam::Vec2, glam::Vec2, f32, f32)>;

/// Every item's [`Extent`], in order: [`passes`] computes them once for its two uses (each
/// projects 16 points per item; Killeroo's 11,532 roots cost about 0.5 ms a pass on the
/// development machine).
fn screen_extents(data: &FrameData, items: &[PatchItem]) -> Vec<Extent> {
    items.iter().map(|item| screen_extent(data, item)).collect()
}

/// One item's [`Extent`].
fn screen_extent(data: &FrameData, item: &PatchItem) -> Extent {
    let f = &data.frame;
    let info = &data.patch_info[item.patch_id as usize];
    let w = item_weights(item, info, &data.primvars);
    let (mut lo, mut hi) = (glam::Vec2::splat(f32::MAX), glam::Vec2::splat(f32::MIN));
    let (mut z0, mut z1) = (f32::MAX, f32::MIN);
    for k in 0..16 {
        let p = cp_point(&item.cp, k) / w.map_or(1.0, |w| w[k]);
        if !(p.z >= f.near) {
            return None;
        }
        let s = glam::Vec2::from(project(f, p));
        lo = lo.min(s);
        hi = hi.max(s);
        z0 = z0.min(p.z);
        z1 = z1.max(p.z);
    }
    Some((lo, hi, z0, z1))
}

/// The grid of at most 16 x 16 cells a bucket is cut into by [`front_items`].
struct CellGrid {
    tile: Tile,
    cw: f32,
    ch: f32,
    nx: usize,
    ny: usize,
}

impl CellGrid {
    fn of(tile: Tile) -> Self {
        const CELLS: u32 = 16;
        let (cw, ch) = (
            tile.w.div_ceil(CELLS).max(1) as f32,
            tile.h.div_ceil(CELLS).max(1) as f32,
        );
        let (nx, ny) = (
            (tile.w as f32 / cw).ceil() as usize,
            (tile.h as f32 / ch).ceil() as usize,
        );
        CellGrid {
            tile,
            cw,
            ch,
            nx,
            ny,
        }
    }

    /// The cells `[x0, y0, x1, y1]` (inclusive) a screen bound reaches, clamped to the grid.
    fn cells(&self, lo: glam::Vec2, hi: glam::Vec2) -> [usize; 4] {
        let cell = |v: f32, o: u32, c: f32, n: usize| {
            (((v - o as f32) / c).floor().max(0.0) as usize).min(n - 1)
        };
        [
            cell(lo.x, self.tile.x0, self.cw, self.nx),
            cell(lo.y, self.tile.y0, self.ch, self.ny),
            cell(hi.x, self.tile.x0, self.cw, self.nx),
            cell(hi.y, self.tile.y0, self.ch, self.ny),
        ]
    }
}

/// A bucket's items in the order the passes take them, and where each pass starts (one pass,
/// the items as given, under `--occlusion auto` when [`depth_complexity`] is below
/// [`AUTO_MIN_DEPTH_COMPLEXITY`]): first the
/// [`front_items`], then the others by their nearest control point's depth, nearest first, in
/// two passes (the nearer half, then the rest). Before each pass after the first the renderers
/// build the pyramid of everything drawn so far and Bound tests against it, so each pass is
/// culled against all the passes in front of it.
pub fn passes(data: &FrameData, items: &[PatchItem], tile: Tile) -> (Vec<PatchItem>, Vec<usize>) {
    let extents = screen_extents(data, items);
    if data.frame.occlusion == OCCLUSION_AUTO
        && complexity_of(&extents, tile) < AUTO_MIN_DEPTH_COMPLEXITY
    {
        return (items.to_vec(), vec![0]);
    }
    let front = front_of(&extents, tile);
    let mut ordered: Vec<PatchItem> = Vec::with_capacity(items.len());
    ordered.extend(
        (items.iter().zip(&front))
            .filter(|(_, f)| **f)
            .map(|(i, _)| *i),
    );
    let n = ordered.len();
    // The rest by depth, sorting (depth, index) pairs rather than the items themselves (a
    // patch item is hundreds of bytes; the stable sort keeps equal depths in item order).
    let mut rest: Vec<(f32, usize)> = (items.iter().zip(&front).enumerate())
        .filter(|(_, (_, f))| !**f)
        .map(|(k, (i, _))| {
            let zmin = (0..16)
                .map(|k| cp_point(&i.cp, k).z)
                .fold(f32::MAX, f32::min);
            (zmin, k)
        })
        .collect();
    rest.sort_by(|a, b| a.0.total_cmp(&b.0));
    ordered.extend(rest.iter().map(|r| items[r.1]));
    let mut starts = vec![0, n, n + rest.len() / 2];
    starts.retain(|&s| s == 0 || s < ordered.len());
    starts.dedup();
    (ordered, starts)
}

#[cfg(test)]
mod tests {
    use super::*;
    use bytemuck::Zeroable;

    /// Every bucket shape fits the buffer sized from its pixel count, the levels end in one
    /// tile, and each level halves the one below (rounding up).
    #[test]
    fn the_pyramid_fits_its_buffer() {
        for (w, h) in [
            (1, 1),
            (1, 4096),
            (4096, 1),
            (7, 9),
            (1920, 1080),
            (16, 16),
            (33, 17),
        ] {
            let l = levels(w, h);
            assert!(words(w, h) <= capacity(w as u64 * h as u64), "{w}x{h}");
            assert_eq!(&l.last().unwrap()[..2], &[1, 1]);
            for k in 1..l.len() {
                assert_eq!(l[k][0], l[k - 1][0].div_ceil(2));
                assert_eq!(l[k][1], l[k - 1][1].div_ceil(2));
            }
        }
    }

    /// On random sample buffers with empty samples, over random buckets and bounds: whenever
    /// [`occluded`] says so, every sample of every pixel within the bound grown by
    /// [`CULL_MARGIN_PX`] holds a depth strictly nearer than the test depth; and it does
    /// cull a good share.
    #[test]
    fn an_occluded_bound_is_behind_every_sample_under_it() {
        let mut seed = 0x0cc1_0de5u32;
        let mut rnd = || {
            seed = crate::stages::reyes_hash(seed);
            seed as f32 / u32::MAX as f32
        };
        let mut culled = 0;
        for _ in 0..300 {
            let (w, h) = (1 + (rnd() * 70.0) as u32, 1 + (rnd() * 50.0) as u32);
            let f = FrameUniforms {
                tile_x0: (rnd() * 40.0) as u32,
                tile_y0: (rnd() * 40.0) as u32,
                tile_w: w,
                tile_h: h,
                spp_x: 2,
                spp_y: 1,
                ..FrameUniforms::zeroed()
            };
            let samples: Vec<u64> = (0..w * h * 2)
                .map(|_| match rnd() < 0.002 {
                    true => 0,
                    false => super::super::sample::sample_key(1.0 + 0.5 * rnd(), 7),
                })
                .collect();
            let hiz = build(&f, &samples);
            for _ in 0..20 {
                let c = glam::Vec2::new(rnd() * 130.0 - 10.0, rnd() * 110.0 - 10.0);
                let e = glam::Vec2::new(rnd(), rnd()) * 30.0;
                let z = 1.2 + rnd() * 0.6;
                if !occluded(&f, &hiz, c, c + e, z) {
                    continue;
                }
                culled += 1;
                for y in 0..h {
                    for x in 0..w {
                        let (px, py) = ((x + f.tile_x0) as f32, (y + f.tile_y0) as f32);
                        let reach = px + 1.0 >= c.x - CULL_MARGIN_PX
                            && px <= c.x + e.x + CULL_MARGIN_PX
                            && py + 1.0 >= c.y - CULL_MARGIN_PX
                            && py <= c.y + e.y + CULL_MARGIN_PX;
                        for s in 0..2 {
                            let key = samples[((y * w + x) * 2 + s) as usize];
                            assert!(
                                !reach || key_depth_bits(key) < z.to_bits(),
                                "pixel ({px}, {py}) under the bound holds {key:x}, z {z}"
                            );
                        }
                    }
                }
            }
        }
        assert!(
            culled > 100,
            "only {culled} bounds culled: the test proves little"
        );
    }
}
