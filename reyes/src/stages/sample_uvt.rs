//! Twin of `shaders/reyes/sample_uvt.wgsl`: sampling in time and on the lens (motion blur and
//! depth of field) by Simple UVT, Interleave UVT or the bounding-box algorithm
//! ([`crate::frame::Sampling`]).

use super::sample::{
    Cover, Triangle, covers, micropolygon_color, sample_id, sample_position, triangle_depth,
    triangle_setup, write_sample,
};
use super::{coc, reyes_hash};
use crate::frame::{FrameUniforms, UVT_INTERLEAVE, UVT_SIMPLE};
use glam::{Vec2, Vec3};

/// `UVT_SALT` and `PERM_SALT` in sample_uvt.wgsl.
pub const UVT_SALT: u32 = 0x9e3779b9;
/// Salt of the hash that picks an Interleave UVT tile's permutation.
pub const PERM_SALT: u32 = 0x632be5ab;

/// `concentric_disc`: Shirley & Chiu's area-preserving map of the unit square to the disc.
pub fn concentric_disc(s: Vec2) -> Vec2 {
    let a = 2.0 * s - Vec2::ONE;
    if a.x == 0.0 && a.y == 0.0 {
        return Vec2::ZERO;
    }
    let (r, phi) = if a.x.abs() > a.y.abs() {
        (a.x, std::f32::consts::FRAC_PI_4 * (a.y / a.x))
    } else {
        (
            a.y,
            std::f32::consts::FRAC_PI_2 - std::f32::consts::FRAC_PI_4 * (a.x / a.y),
        )
    };
    r * Vec2::new(phi.cos(), phi.sin())
}

/// `uvt_sample`: lens position in the unit disc (x, y) and time (z), stratum `stratum` of `n`.
pub fn uvt_sample(f: &FrameUniforms, key: u32, stratum: u32, n: u32) -> Vec3 {
    let h1 = reyes_hash(key ^ f.seed ^ UVT_SALT);
    let h2 = reyes_hash(h1.wrapping_add(1));
    let h3 = reyes_hash(h2.wrapping_add(1));
    let t = (stratum as f32 + (h1 >> 8) as f32 / 16777216.0) / n as f32;
    let lens = concentric_disc(Vec2::new((h2 >> 8) as f32, (h3 >> 8) as f32) / 16777216.0);
    Vec3::new(lens.x, lens.y, t)
}

/// `uvt_table_sample`: the bounding-box algorithm's sample k of pixel (px, py).
pub fn uvt_table_sample(f: &FrameUniforms, px: u32, py: u32, k: u32, n: u32) -> Vec3 {
    let texel = py.wrapping_mul(f.width).wrapping_add(px);
    let shift = reyes_hash(texel ^ PERM_SALT) % n;
    uvt_sample(f, texel.wrapping_mul(n).wrapping_add(k), (k + shift) % n, n)
}

/// `table_slot`: the sub-sample of pixel (px, py) whose time lies in stratum `j` of `n` under
/// the bounding-box algorithm (the inverse of [`uvt_table_sample`]'s order).
pub fn table_slot(f: &FrameUniforms, px: u32, py: u32, j: u32, n: u32) -> u32 {
    let texel = py.wrapping_mul(f.width).wrapping_add(px);
    let shift = reyes_hash(texel ^ PERM_SALT) % n;
    (j + n - shift) % n
}

/// `stratum_margin`: growth of a time stratum's bound against rounding (pixels).
fn stratum_margin(x: Vec2) -> f32 {
    0.015625 + 1.0e-5 * x.x.abs().max(x.y.abs())
}

/// `permute`: Kensler's hashed permutation of [0, l) chosen by p (cycle walking, bounded).
pub fn permute(index: u32, l: u32, p: u32) -> u32 {
    let mut w = l - 1;
    w |= w >> 1;
    w |= w >> 2;
    w |= w >> 4;
    w |= w >> 8;
    w |= w >> 16;
    let mut i = index;
    for _ in 0..=w {
        i ^= p;
        i = i.wrapping_mul(0xe170893d);
        i ^= p >> 16;
        i ^= (i & w) >> 4;
        i ^= p >> 8;
        i = i.wrapping_mul(0x0929eb3f);
        i ^= p >> 23;
        i ^= (i & w) >> 1;
        i = i.wrapping_mul(1 | (p >> 27));
        i = i.wrapping_mul(0x6935fa69);
        i ^= (i & w) >> 11;
        i = i.wrapping_mul(0x74dcb303);
        i ^= (i & w) >> 2;
        i = i.wrapping_mul(0x9e501cc3);
        i ^= (i & w) >> 2;
        i = i.wrapping_mul(0xc860a3df);
        i &= w;
        i ^= i >> 5;
        if i < l {
            break;
        }
    }
    (i.wrapping_add(p)) % l
}

/// `uvt_corner`: corner `p0` (colour bits in `[3]`) moved to sample `s`; `p1` at shutter close.
fn uvt_corner(f: &FrameUniforms, p0: [f32; 4], p1: [f32; 4], s: Vec3) -> [f32; 4] {
    let a = Vec3::new(p0[0], p0[1], p0[2]);
    let b = Vec3::new(p1[0], p1[1], p1[2]);
    let p = a + (b - a) * s.z;
    let c = coc(f, p.z);
    [p.x + c * s.x, p.y + c * s.y, p.z, p0[3]]
}

/// `MovedQuad`: the micropolygon's two triangles at one sample, and their grown bound.
struct MovedQuad {
    abc: Triangle,
    acd: Triangle,
    lo: Vec2,
    hi: Vec2,
}

fn moved_quad(
    f: &FrameUniforms,
    q0: &[[f32; 4]; 4],
    q1: &[[f32; 4]; 4],
    s: Vec3,
    grow: [f32; 4],
) -> MovedQuad {
    let [a, b, c, d] = std::array::from_fn(|i| uvt_corner(f, q0[i], q1[i], s));
    let g = grow[0].max(grow[1]).max(grow[2].max(grow[3]));
    let diagonal = grow[0].min(grow[1]).min(grow[2].min(grow[3]));
    let xy = |p: [f32; 4]| Vec2::new(p[0], p[1]);
    MovedQuad {
        abc: triangle_setup(a, b, c, [grow[1], diagonal, grow[0]]),
        acd: triangle_setup(a, c, d, [grow[2], grow[3], diagonal]),
        lo: xy(a).min(xy(b)).min(xy(c).min(xy(d))) - Vec2::splat(g),
        hi: xy(a).max(xy(b)).max(xy(c).max(xy(d))) + Vec2::splat(g),
    }
}

/// `uvt_test`: sub-sample (sx, sy) of pixel (px, py) against the moved quad.
fn uvt_test(
    f: &FrameUniforms,
    samples: &mut [u64],
    m: &MovedQuad,
    [px, py, k]: [u32; 3],
    (color, cover): (u32, Cover),
) {
    let (sx, sy) = (k % f.spp_x, k / f.spp_x);
    let q = sample_position(f, px, py, sx, sy);
    if q.x < m.lo.x || q.y < m.lo.y || q.x > m.hi.x || q.y > m.hi.y {
        return;
    }
    let mut z = triangle_depth(&m.abc, q);
    if z < 0.0 {
        z = triangle_depth(&m.acd, q);
    }
    if z < 0.0 || !covers(f, cover, sample_id(f, px, py, sx, sy)) {
        return;
    }
    write_sample(f, samples, [px, py, sx, sy], z, color);
}

/// `bucket_pixels`: the bucket's pixels under [lo, hi], inclusive, or `None`.
fn bucket_pixels(f: &FrameUniforms, lo: Vec2, hi: Vec2) -> Option<([u32; 2], [u32; 2])> {
    let t0 = [f.tile_x0, f.tile_y0];
    let t1 = [f.tile_x0 + f.tile_w, f.tile_y0 + f.tile_h];
    let inside = |k: usize| hi[k] >= t0[k] as f32 && lo[k] < t1[k] as f32;
    if !(inside(0) && inside(1)) {
        return None;
    }
    let p0 = |k: usize| lo[k].max(t0[k] as f32) as u32;
    let p1 = |k: usize| (hi[k].min(t1[k] as f32) as u32).min(t1[k] - 1);
    Some(([p0(0), p0(1)], [p1(0), p1(1)]))
}

/// `sample_micropolygon_uvt`: quad `q0` at shutter open (colour bits in `[3]`), `q1` at close,
/// sampled in time and on the lens by `f.uvt`'s algorithm; false when culled as back-facing.
pub fn sample_micropolygon_uvt(
    q0: [[f32; 4]; 4],
    q1: [[f32; 4]; 4],
    grow: [f32; 4],
    two_sided: bool,
    cover: Cover,
    f: &FrameUniforms,
    samples: &mut [u64],
) -> bool {
    let Some(color) = micropolygon_color(&q0, two_sided) else {
        return false;
    };
    if cover.alpha.is_nan() || cover.alpha <= 0.0 {
        return true;
    }
    let spp = f.spp_x * f.spp_y;
    if f.uvt == UVT_SIMPLE {
        for k in 0..spp {
            let m = moved_quad(f, &q0, &q1, uvt_sample(f, k, k, spp), grow);
            let Some((p0, p1)) = bucket_pixels(f, m.lo, m.hi) else {
                continue;
            };
            for py in p0[1]..=p1[1] {
                for px in p0[0]..=p1[0] {
                    uvt_test(f, samples, &m, [px, py, k], (color, cover));
                }
            }
        }
    } else if f.uvt == UVT_INTERLEAVE {
        let kt = f.il_tile;
        let n = kt * kt * spp;
        let tiles_x = f.width / kt;
        for j in 0..n {
            let m = moved_quad(f, &q0, &q1, uvt_sample(f, j, j, n), grow);
            let Some((p0, p1)) = bucket_pixels(f, m.lo, m.hi) else {
                continue;
            };
            for ty in p0[1] / kt..=p1[1] / kt {
                for tx in p0[0] / kt..=p1[0] / kt {
                    let tile_number = ty * tiles_x + tx;
                    let perm = (tile_number + tx + ty) % f.il_perms;
                    let slot = permute(j, n, reyes_hash(perm ^ f.seed ^ PERM_SALT));
                    let k = slot % spp;
                    let px = tx * kt + (slot / spp) % kt;
                    let py = ty * kt + slot / (spp * kt);
                    if px < p0[0] || px > p1[0] || py < p0[1] || py > p1[1] {
                        continue;
                    }
                    uvt_test(f, samples, &m, [px, py, k], (color, cover));
                }
            }
        }
    } else {
        // By time stratum: see sample_uvt.wgsl.
        let g = grow[0].max(grow[1]).max(grow[2].max(grow[3]));
        for j in 0..spp {
            let tb = Vec2::new(j as f32, (j + 1) as f32) / spp as f32;
            let (mut lo, mut hi, mut r) = (Vec2::splat(3.0e38), Vec2::splat(-3.0e38), 0f32);
            for i in 0..4 {
                let (a, b) = (Vec3::from_slice(&q0[i][..3]), Vec3::from_slice(&q1[i][..3]));
                let (e0, e1) = (a + (b - a) * tb.x, a + (b - a) * tb.y);
                lo = lo.min(e0.truncate().min(e1.truncate()));
                hi = hi.max(e0.truncate().max(e1.truncate()));
                r = r.max(coc(f, e0.z).abs().max(coc(f, e1.z).abs()));
            }
            let (glo, ghi) = (g + r + stratum_margin(lo), g + r + stratum_margin(hi));
            let Some((p0, p1)) = bucket_pixels(f, lo - Vec2::splat(glo), hi + Vec2::splat(ghi))
            else {
                continue;
            };
            for py in p0[1]..=p1[1] {
                for px in p0[0]..=p1[0] {
                    let k = table_slot(f, px, py, j, spp);
                    let s = uvt_table_sample(f, px, py, k, spp);
                    // The moved corners' bound first (see sample_uvt.wgsl).
                    let c: [[f32; 4]; 4] = std::array::from_fn(|i| uvt_corner(f, q0[i], q1[i], s));
                    let xy = |p: [f32; 4]| Vec2::new(p[0], p[1]);
                    let lo = xy(c[0]).min(xy(c[1])).min(xy(c[2]).min(xy(c[3]))) - Vec2::splat(g);
                    let hi = xy(c[0]).max(xy(c[1])).max(xy(c[2]).max(xy(c[3]))) + Vec2::splat(g);
                    let q = sample_position(f, px, py, k % f.spp_x, k / f.spp_x);
                    if q.x < lo.x || q.y < lo.y || q.x > hi.x || q.y > hi.y {
                        continue;
                    }
                    let m = moved_quad(f, &q0, &q1, s, grow);
                    uvt_test(f, samples, &m, [px, py, k], (color, cover));
                }
            }
        }
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each permutation is a bijection of [0, l), for the sizes Interleave UVT uses.
    #[test]
    fn permute_is_a_bijection() {
        for l in [1u32, 4, 9, 16, 36, 64, 144, 1000, 4096] {
            for p in [0u32, 1, 0xdeadbeef, reyes_hash(7)] {
                let mut seen = vec![false; l as usize];
                for i in 0..l {
                    let j = permute(i, l, p) as usize;
                    assert!(j < l as usize && !seen[j], "l {l} p {p:#x} i {i}");
                    seen[j] = true;
                }
            }
        }
    }

    /// The bounding-box algorithm, as it was written before it went stratum by stratum: one
    /// pass over the bound of the whole shutter and lens, every sub-sample of every pixel
    /// under it tested with its own sample.
    fn bbox_one_pass(
        q0: [[f32; 4]; 4],
        q1: [[f32; 4]; 4],
        grow: [f32; 4],
        f: &FrameUniforms,
        samples: &mut [u64],
    ) {
        let color = micropolygon_color(&q0, true).unwrap();
        let cover = Cover {
            alpha: 1.0,
            salt: 0,
        };
        let spp = f.spp_x * f.spp_y;
        let (mut lo, mut hi, mut r) = (Vec2::splat(3.0e38), Vec2::splat(-3.0e38), 0f32);
        for i in 0..4 {
            let (a, b) = (Vec2::new(q0[i][0], q0[i][1]), Vec2::new(q1[i][0], q1[i][1]));
            lo = lo.min(a.min(b));
            hi = hi.max(a.max(b));
            r = r.max(coc(f, q0[i][2]).abs().max(coc(f, q1[i][2]).abs()));
        }
        let g = grow[0].max(grow[1]).max(grow[2].max(grow[3])) + r;
        if let Some((p0, p1)) = bucket_pixels(f, lo - Vec2::splat(g), hi + Vec2::splat(g)) {
            for py in p0[1]..=p1[1] {
                for px in p0[0]..=p1[0] {
                    for k in 0..spp {
                        let m = moved_quad(f, &q0, &q1, uvt_table_sample(f, px, py, k, spp), grow);
                        uvt_test(f, samples, &m, [px, py, k], (color, cover));
                    }
                }
            }
        }
    }

    /// Stratum by stratum, the bounding-box algorithm tests only the pixels under each time
    /// stratum's bound, and writes the same samples, bit for bit, as one pass over the whole
    /// shutter's bound: on 400 random micropolygons moving up to 60 px (some through depth,
    /// with and without depth of field), at 1x1 to 4x4 samples, one bucket beside the origin.
    #[test]
    fn bbox_by_stratum_writes_what_one_pass_writes() {
        let mut h = 0x1234_5678u32;
        let mut rnd = move || {
            h = reyes_hash(h);
            (h >> 8) as f32 / 16777216.0
        };
        let mut written = 0;
        for case in 0..400 {
            let spp = [1u32, 2, 3, 4][case % 4];
            let f = FrameUniforms {
                width: 96,
                height: 64,
                tile_x0: 16,
                tile_y0: 8,
                tile_w: 64,
                tile_h: 48,
                spp_x: spp,
                spp_y: spp,
                seed: case as u32,
                uvt: crate::frame::UVT_BBOX,
                coc_scale: if case % 3 == 0 { 0.0 } else { 40.0 },
                inv_focus: 0.2,
                ..bytemuck::Zeroable::zeroed()
            };
            let (cx, cy, z) = (10.0 + 76.0 * rnd(), 5.0 + 54.0 * rnd(), 3.0 + 6.0 * rnd());
            let size = 0.3 + 4.0 * rnd();
            let motion = Vec3::new(
                120.0 * rnd() - 60.0,
                120.0 * rnd() - 60.0,
                4.0 * rnd() - 2.0,
            );
            let corner = |i: usize| -> [f32; 4] {
                let (dx, dy) = [(0.0, 0.0), (1.0, 0.1), (0.9, 1.0), (-0.1, 0.8)][i];
                [
                    cx + size * dx,
                    cy + size * dy,
                    z + 0.1 * dx,
                    f32::from_bits(0x3ff),
                ]
            };
            let q0: [[f32; 4]; 4] = std::array::from_fn(corner);
            let q1 = q0.map(|p| [p[0] + motion.x, p[1] + motion.y, p[2] + motion.z, p[3]]);
            let grow = [0.0, 0.01, 0.3 * rnd(), 0.001];
            let n = (f.tile_w * f.tile_h * spp * spp) as usize;
            let (mut by_stratum, mut one_pass) = (vec![0u64; n], vec![0u64; n]);
            let cover = Cover {
                alpha: 1.0,
                salt: 0,
            };
            sample_micropolygon_uvt(q0, q1, grow, true, cover, &f, &mut by_stratum);
            bbox_one_pass(q0, q1, grow, &f, &mut one_pass);
            assert!(by_stratum == one_pass, "case {case}: the samples differ");
            written += by_stratum.iter().filter(|&&k| k != 0).count();
        }
        assert!(
            written > 5_000,
            "only {written} samples written: the test tests little"
        );
    }

    /// Lens positions lie in the unit disc; times in [0, 1) in their strata.
    #[test]
    fn samples_lie_in_the_disc_and_their_time_strata() {
        let f = FrameUniforms {
            seed: 0x5eed,
            ..bytemuck::Zeroable::zeroed()
        };
        for k in 0..256 {
            let s = uvt_sample(&f, k, k % 16, 16);
            assert!(s.truncate().length() <= 1.0 + 1e-6, "{s}");
            let stratum = (k % 16) as f32 / 16.0;
            assert!(s.z >= stratum && s.z < stratum + 1.0 / 16.0 + 1e-7, "{s}");
        }
    }
}
