//! Twin of `shaders/reyes/sample.wgsl`: jittered sub-samples, inside test, depth by max-key;
//! bounding-box rasterization or the nearest sample ([`crate::frame::RasterMode`]).

use super::reyes_hash;
use crate::frame::{FrameUniforms, RASTER_NEAREST};
use glam::{Vec2, Vec3, Vec4};

fn cross2(a: Vec2, b: Vec2) -> f32 {
    a.x * b.y - a.y * b.x
}

/// `sample_id` in sample.wgsl: the index of sub-sample (sx, sy) of pixel (px, py) in the whole
/// image (not the bucket).
pub fn sample_id(f: &FrameUniforms, px: u32, py: u32, sx: u32, sy: u32) -> u32 {
    ((py * f.width + px) * f.spp_y + sy) * f.spp_x + sx
}

/// `sample_position` in sample.wgsl: sub-sample (sx, sy) of pixel (px, py), stratified and
/// jittered by a hash.
pub fn sample_position(f: &FrameUniforms, px: u32, py: u32, sx: u32, sy: u32) -> Vec2 {
    let h = reyes_hash(sample_id(f, px, py, sx, sy) ^ f.seed);
    let j = Vec2::new((h & 0xffff) as f32, (h >> 16) as f32) / 65536.0;
    Vec2::new(px as f32, py as f32)
        + (Vec2::new(sx as f32, sy as f32) + j) / Vec2::new(f.spp_x as f32, f.spp_y as f32)
}

/// `Triangle` in sample.wgsl: the inside test's per-triangle values, computed once.
pub(super) struct Triangle {
    a: [f32; 4],
    b: [f32; 4],
    c: [f32; 4],
    area: f32,
    /// -grow * length of the edge opposite a, b, c.
    g: [f32; 3],
}

fn xy(p: [f32; 4]) -> Vec2 {
    Vec2::new(p[0], p[1])
}

/// `grow`: pixels to grow the edges opposite a, b and c (bc, ca, ab).
pub(super) fn triangle_setup(a: [f32; 4], b: [f32; 4], c: [f32; 4], grow: [f32; 3]) -> Triangle {
    let (pa, pb, pc) = (xy(a), xy(b), xy(c));
    Triangle {
        a,
        b,
        c,
        area: cross2(pb - pa, pc - pa),
        g: [
            -grow[0] * pb.distance(pc),
            -grow[1] * pa.distance(pc),
            -grow[2] * pa.distance(pb),
        ],
    }
}

/// `micropolygon_dilation` in sample.wgsl: pixels to grow edges ab, bc, cd, da of micropolygon
/// (i, j) of an nu x nv grid: boundary edges by their side's packed crack dilation, inner edges
/// by `ROUNDING_DILATE_PX`, nothing when dilation is off (`packed` = 0).
pub fn micropolygon_dilation(packed: u32, i: u32, j: u32, nu: u32, nv: u32) -> [f32; 4] {
    let side = |e: u32| ((packed >> (8 * e)) & 255) as f32 * (super::bound::MAX_DILATE_PX / 255.0);
    let inner = if packed != 0 { ROUNDING_DILATE_PX } else { 0.0 };
    let pick = |on_side: bool, e: u32| if on_side { side(e) } else { inner };
    [
        pick(j == 0, 0),
        pick(i + 1 == nu, 3),
        pick(j + 1 == nv, 1),
        pick(i == 0, 2),
    ]
}

/// `ROUNDING_DILATE_PX` in common.wgsl: the growth of edges inside a grid.
pub const ROUNDING_DILATE_PX: f32 = 1.0e-3;

pub(super) fn triangle_depth(t: &Triangle, q: Vec2) -> f32 {
    if t.area.abs() < 1.0e-12 {
        return -1.0;
    }
    let (pa, pb, pc) = (xy(t.a), xy(t.b), xy(t.c));
    let s = t.area.signum();
    let wa = s * cross2(pc - pb, q - pb);
    let wb = s * cross2(pa - pc, q - pc);
    let wc = s * cross2(pb - pa, q - pa);
    if wa < t.g[0] || wb < t.g[1] || wc < t.g[2] {
        return -1.0;
    }
    // Clamped to the corners' depths (see sample.wgsl).
    let z = (wa * t.a[2] + wb * t.b[2] + wc * t.c[2]) / t.area.abs();
    z.clamp(
        t.a[2].min(t.b[2].min(t.c[2])),
        t.a[2].max(t.b[2].max(t.c[2])),
    )
}

fn average_color(c: [u32; 4]) -> u32 {
    let mut out = 0;
    for k in [0, 10, 20] {
        let sum: u32 = c.iter().map(|x| (x >> k) & 1023).sum();
        out |= ((sum + 2) / 4) << k;
    }
    out
}

/// The sample key: nearer (smaller z) and then larger colour wins under `max`.
pub fn sample_key(z: f32, color: u32) -> u64 {
    ((!z.to_bits() as u64) << 32) | color as u64
}

/// `micropolygon_color` in sample.wgsl: the average of the corners' packed colours; `None`
/// when the micropolygon is one-sided and all four corners face away.
pub(super) fn micropolygon_color(q: &[[f32; 4]; 4], two_sided: bool) -> Option<u32> {
    let c = q.map(|v| v[3].to_bits());
    if !two_sided && (c[0] & c[1] & c[2] & c[3] & (1 << 30)) != 0 {
        return None;
    }
    Some(average_color(c))
}

/// `Cover` in sample.wgsl: the fraction `alpha` of samples a micropolygon covers (its opacity),
/// and the hash of its original patch that, with each sample's index, decides which
/// (stochastic transparency, Enderton et al. 2010, "Stochastic Transparency").
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cover {
    /// Fraction of samples covered, in [0, 1]: the micropolygon's opacity.
    pub alpha: f32,
    /// Hash of the original patch, mixed into each sample's coverage decision.
    pub salt: u32,
}

/// `COVER_SALT` in sample.wgsl: mixed into the patch id so that the coverage hash differs
/// from the jitter hash.
pub const COVER_SALT: u32 = 0x5bd1e995;

impl Cover {
    /// The cover of a micropolygon of opacity `alpha` on original patch `patch_id`.
    pub fn new(alpha: f32, patch_id: u32) -> Cover {
        Cover {
            alpha,
            salt: reyes_hash(patch_id ^ COVER_SALT),
        }
    }
}

/// `covers` in sample.wgsl: whether the micropolygon covers sample `id` (always when
/// opaque; else when a hash of the sample and the patch, as 24 bits, is below alpha * 2^24).
pub fn covers(f: &FrameUniforms, c: Cover, id: u32) -> bool {
    if c.alpha >= 1.0 {
        return true;
    }
    let h = reyes_hash(reyes_hash(id ^ f.seed) ^ c.salt);
    ((h >> 8) as f32) < c.alpha * 16777216.0
}

/// Keeps the nearest key at sub-sample (sx, sy) of pixel (px, py) of the bucket.
pub(super) fn write_sample(
    f: &FrameUniforms,
    samples: &mut [u64],
    [px, py, sx, sy]: [u32; 4],
    z: f32,
    color: u32,
) {
    let pixel = (py - f.tile_y0) * f.tile_w + px - f.tile_x0;
    let idx = (pixel * f.spp_x * f.spp_y + sy * f.spp_x + sx) as usize;
    samples[idx] = samples[idx].max(sample_key(z, color));
}

/// The sampling loop of `sample_micropolygon` and `sample_clipped_triangle` in sample.wgsl:
/// every sub-sample of the bucket inside the bound [lo, hi] whose `depth` is not negative and
/// that `cover` covers keeps the nearest key.
fn sample_under(
    f: &FrameUniforms,
    samples: &mut [u64],
    (lo, hi): (Vec2, Vec2),
    color: u32,
    cover: Cover,
    depth: impl Fn(Vec2) -> f32,
) {
    let (t0, t1) = (
        [f.tile_x0, f.tile_y0],
        [f.tile_x0 + f.tile_w, f.tile_y0 + f.tile_h],
    );
    let inside = |k: usize| hi[k] >= t0[k] as f32 && lo[k] < t1[k] as f32;
    if !(inside(0) && inside(1)) {
        return;
    }
    let p0 = |k: usize| lo[k].max(t0[k] as f32) as u32;
    let p1 = |k: usize| (hi[k].min(t1[k] as f32) as u32).min(t1[k] - 1);
    for py in p0(1)..=p1(1) {
        for px in p0(0)..=p1(0) {
            for sy in 0..f.spp_y {
                for sx in 0..f.spp_x {
                    let q = sample_position(f, px, py, sx, sy);
                    if q.x < lo.x || q.y < lo.y || q.x > hi.x || q.y > hi.y {
                        continue;
                    }
                    let z = depth(q);
                    if z >= 0.0 && covers(f, cover, sample_id(f, px, py, sx, sy)) {
                        write_sample(f, samples, [px, py, sx, sy], z, color);
                    }
                }
            }
        }
    }
}

/// Samples quad `q` (a, b, c, d around), its edges ab, bc, cd, da grown by `grow` pixels (the
/// diagonal by the least of them), covering the samples `cover` says; false when it was culled
/// as back-facing.
pub fn sample_micropolygon(
    q: [[f32; 4]; 4],
    grow: [f32; 4],
    two_sided: bool,
    cover: Cover,
    f: &FrameUniforms,
    samples: &mut [u64],
) -> bool {
    let Some(color) = micropolygon_color(&q, two_sided) else {
        return false;
    };
    if !(cover.alpha > 0.0) {
        return true;
    }
    if f.raster == RASTER_NEAREST {
        sample_nearest(&q, color, cover, f, samples);
        return true;
    }
    let xy = q.map(|v| Vec2::new(v[0], v[1]));
    let g = grow[0].max(grow[1]).max(grow[2].max(grow[3]));
    let lo = xy[0].min(xy[1]).min(xy[2].min(xy[3])) - Vec2::splat(g);
    let hi = xy[0].max(xy[1]).max(xy[2].max(xy[3])) + Vec2::splat(g);
    let diagonal = grow[0].min(grow[1]).min(grow[2].min(grow[3]));
    let abc = triangle_setup(q[0], q[1], q[2], [grow[1], diagonal, grow[0]]);
    let acd = triangle_setup(q[0], q[2], q[3], [grow[2], grow[3], diagonal]);
    sample_under(f, samples, (lo, hi), color, cover, |s| {
        let z = triangle_depth(&abc, s);
        if z < 0.0 { triangle_depth(&acd, s) } else { z }
    });
    true
}

/// `sample_nearest` in sample.wgsl ([`crate::frame::RasterMode::NearestSample`]): quad `q`
/// (projected corners, depth in `[2]`) writes only the jittered sub-sample nearest its centre
/// (the mean of its corners; the first in row-major order of the image's sample grid on a tie),
/// at the mean depth of its corners, when the centre lies in the image and the sample in the
/// bucket. Searches the stratum cells within one cell diagonal of the centre, which hold the
/// nearest sample since the centre's own cell's sample is at most that far.
fn sample_nearest(
    q: &[[f32; 4]; 4],
    color: u32,
    cover: Cover,
    f: &FrameUniforms,
    samples: &mut [u64],
) {
    let centre = (xy(q[0]) + xy(q[1]) + xy(q[2]) + xy(q[3])) * 0.25;
    let size = Vec2::new(f.width as f32, f.height as f32);
    if !(centre.x >= 0.0 && centre.y >= 0.0 && centre.x < size.x && centre.y < size.y) {
        return;
    }
    let spp = [f.spp_x, f.spp_y];
    let cell = Vec2::ONE / Vec2::new(spp[0] as f32, spp[1] as f32);
    let reach = cell.length();
    let cells = [f.width * spp[0], f.height * spp[1]];
    let lo = ((centre - Vec2::splat(reach)) / cell).max(Vec2::ZERO);
    let hi = (centre + Vec2::splat(reach)) / cell;
    let k0 = [lo.x as u32, lo.y as u32];
    let k1 = [
        (hi.x as u32).min(cells[0] - 1),
        (hi.y as u32).min(cells[1] - 1),
    ];
    let (mut best, mut best_d2) = ([0, 0], 3.0e38_f32);
    for ky in k0[1]..=k1[1] {
        for kx in k0[0]..=k1[0] {
            let s = sample_position(f, kx / spp[0], ky / spp[1], kx % spp[0], ky % spp[1]);
            let e = s - centre;
            let d2 = e.x * e.x + e.y * e.y;
            if d2 < best_d2 {
                best_d2 = d2;
                best = [kx, ky];
            }
        }
    }
    let [px, py] = [best[0] / spp[0], best[1] / spp[1]];
    let [sx, sy] = [best[0] % spp[0], best[1] % spp[1]];
    if px < f.tile_x0 || py < f.tile_y0 || px >= f.tile_x0 + f.tile_w || py >= f.tile_y0 + f.tile_h
    {
        return;
    }
    if !covers(f, cover, sample_id(f, px, py, sx, sy)) {
        return;
    }
    let z = (q[0][2] + q[1][2] + q[2][2] + q[3][2]) * 0.25;
    write_sample(f, samples, [px, py, sx, sy], z, color);
}

/// `GUARD_BAND_PX` in sample.wgsl: clipped polygons keep this much beyond the image's edges.
pub const GUARD_BAND_PX: f32 = 16.0;

/// `clip_plane` in sample.wgsl: 0 the near plane, 1-4 the guard band's sides through the eye;
/// (a, b, c, d) keeps a x + b y + c z + d >= 0.
fn clip_plane(f: &FrameUniforms, k: usize) -> Vec4 {
    let gx = 0.5 * f.width as f32 + GUARD_BAND_PX;
    let gy = 0.5 * f.height as f32 + GUARD_BAND_PX;
    let fo = f.focal;
    match k {
        0 => Vec4::new(0.0, 0.0, 1.0, -f.near),
        1 => Vec4::new(fo, 0.0, gx, 0.0),
        2 => Vec4::new(-fo, 0.0, gx, 0.0),
        3 => Vec4::new(0.0, -fo, gy, 0.0),
        _ => Vec4::new(0.0, fo, gy, 0.0),
    }
}

/// `clip_by_plane` in sample.wgsl: one Sutherland-Hodgman step, crossings computed from the
/// kept end of each edge.
fn clip_by_plane(poly: &[Vec3], plane: Vec4) -> Vec<Vec3> {
    let n = poly.len();
    let mut out = Vec::with_capacity(n + 1);
    for i in 0..n {
        let (p, q) = (poly[i], poly[(i + 1) % n]);
        let dp = plane.truncate().dot(p) + plane.w;
        let dq = plane.truncate().dot(q) + plane.w;
        if dp >= 0.0 {
            out.push(p);
            if dq < 0.0 {
                out.push(p + (q - p) * (dp / (dp - dq)));
            }
        } else if dq >= 0.0 {
            out.push(q + (p - q) * (dq / (dq - dp)));
        }
    }
    out
}

/// `sample_near_clipped` in sample.wgsl: a micropolygon of a grid crossing the near plane, its
/// corners in camera space; false when culled as back-facing.
pub fn sample_near_clipped(
    q: [[f32; 4]; 4],
    grow: [f32; 4],
    two_sided: bool,
    cover: Cover,
    f: &FrameUniforms,
    samples: &mut [u64],
) -> bool {
    if q.iter().map(|v| v[2]).fold(f32::MAX, f32::min) >= f.near {
        let projected = q.map(|v| {
            let s = super::project(f, Vec3::new(v[0], v[1], v[2]));
            [s[0], s[1], v[2], v[3]]
        });
        return sample_micropolygon(projected, grow, two_sided, cover, f, samples);
    }
    let Some(color) = micropolygon_color(&q, two_sided) else {
        return false;
    };
    if !(cover.alpha > 0.0) {
        return true;
    }
    let p = q.map(|v| Vec3::new(v[0], v[1], v[2]));
    let g = grow[0].max(grow[1]).max(grow[2].max(grow[3]));
    let paint = (color, cover);
    sample_clipped_triangle(&[p[0], p[1], p[2]], g, paint, f, samples);
    sample_clipped_triangle(&[p[0], p[2], p[3]], g, paint, f, samples);
    true
}

fn sample_clipped_triangle(
    tri: &[Vec3; 3],
    grow: f32,
    (color, cover): (u32, Cover),
    f: &FrameUniforms,
    samples: &mut [u64],
) {
    let mut poly = tri.to_vec();
    for k in 0..5 {
        if poly.len() < 3 {
            break;
        }
        poly = clip_by_plane(&poly, clip_plane(f, k));
        if k == 0 {
            for v in &mut poly {
                v.z = v.z.max(f.near);
            }
        }
    }
    if poly.len() < 3 {
        return;
    }
    let s: Vec<[f32; 4]> = poly
        .iter()
        .map(|&v| {
            let p = super::project(f, v);
            [p[0], p[1], v.z, 0.0]
        })
        .collect();
    let (mut lo, mut hi) = (Vec2::splat(3.0e38), Vec2::splat(-3.0e38));
    for v in &s {
        lo = lo.min(xy(*v));
        hi = hi.max(xy(*v));
    }
    lo -= Vec2::splat(grow);
    hi += Vec2::splat(grow);
    let fan: Vec<Triangle> = (0..s.len() - 2)
        .map(|i| triangle_setup(s[0], s[i + 1], s[i + 2], [grow; 3]))
        .collect();
    sample_under(f, samples, (lo, hi), color, cover, |q| {
        let mut z = -1.0;
        for t in &fan {
            if z >= 0.0 {
                break;
            }
            z = triangle_depth(t, q);
        }
        z
    });
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frame::{RASTER_BBOX, RASTER_NEAREST};
    use bytemuck::Zeroable;

    fn frame(spp: [u32; 2], raster: u32) -> FrameUniforms {
        FrameUniforms {
            width: 9,
            height: 7,
            spp_x: spp[0],
            spp_y: spp[1],
            seed: 0x5eed,
            tile_w: 9,
            tile_h: 7,
            raster,
            ..FrameUniforms::zeroed()
        }
    }

    /// Nearest mode writes exactly the sub-sample nearest the quad's centre, found here by
    /// brute force over every sample of the image, for quads all over (and off) the image and
    /// for square and oblong strata; bbox mode writes every sample inside the quad.
    #[test]
    fn nearest_mode_writes_the_one_sample_nearest_the_centre() {
        let mut rng = 0x1234_5678u32;
        let mut next = || {
            rng = reyes_hash(rng);
            (rng >> 8) as f32 / 16777216.0
        };
        for spp in [[1, 1], [2, 2], [4, 1], [1, 3], [3, 5]] {
            let f = frame(spp, RASTER_NEAREST);
            let n = (f.width * f.height * f.spp_x * f.spp_y) as usize;
            for _ in 0..300 {
                let (cx, cy, r) = (next() * 11.0 - 1.0, next() * 9.0 - 1.0, next() * 2.0);
                let q: [[f32; 4]; 4] = std::array::from_fn(|k| {
                    let a = k as f32 * std::f32::consts::FRAC_PI_2 + next();
                    [cx + r * a.cos(), cy + r * a.sin(), 2.0 + k as f32, 0.0]
                });
                let mut samples = vec![0u64; n];
                let cover = Cover::new(1.0, 0);
                assert!(sample_micropolygon(
                    q,
                    [0.0; 4],
                    true,
                    cover,
                    &f,
                    &mut samples
                ));
                let written: Vec<usize> = (0..n).filter(|&i| samples[i] != 0).collect();
                let c = (xy(q[0]) + xy(q[1]) + xy(q[2]) + xy(q[3])) * 0.25;
                let inside = c.x >= 0.0 && c.y >= 0.0 && c.x < 9.0 && c.y < 7.0;
                if !inside {
                    assert!(
                        written.is_empty(),
                        "centre {c} off the image wrote {written:?}"
                    );
                    continue;
                }
                let mut best = (f32::MAX, 0usize);
                for py in 0..f.height {
                    for px in 0..f.width {
                        for sy in 0..f.spp_y {
                            for sx in 0..f.spp_x {
                                let d = sample_position(&f, px, py, sx, sy).distance(c);
                                let id = sample_id(&f, px, py, sx, sy) as usize;
                                if d < best.0 {
                                    best = (d, id);
                                }
                            }
                        }
                    }
                }
                assert_eq!(written, vec![best.1], "spp {spp:?}, centre {c}");
                // At the mean depth of the corners: 2, 3, 4, 5.
                assert_eq!(samples[best.1], sample_key(3.5, samples[best.1] as u32));
            }
        }
    }

    /// The same quad in bbox mode covers every sample inside it: about its area in samples.
    #[test]
    fn bbox_mode_writes_every_sample_inside() {
        let f = frame([2, 2], RASTER_BBOX);
        let n = (9 * 7 * 4) as usize;
        let mut samples = vec![0u64; n];
        let q = [
            [1.0, 1.0, 1.0, 0.0],
            [6.0, 1.0, 1.0, 0.0],
            [6.0, 5.0, 1.0, 0.0],
            [1.0, 5.0, 1.0, 0.0],
        ];
        sample_micropolygon(q, [0.0; 4], true, Cover::new(1.0, 0), &f, &mut samples);
        // 5 x 4 pixels of 4 samples, jittered in their strata: exactly those.
        assert_eq!(samples.iter().filter(|k| **k != 0).count(), 80);
    }
}
