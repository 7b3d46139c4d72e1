//! Twin of `shaders/reyes/sample.wgsl`: jittered sub-samples, inside test, depth by max-key.

use super::reyes_hash;
use crate::frame::Frame;
use glam::Vec2;

fn cross2(a: Vec2, b: Vec2) -> f32 {
    a.x * b.y - a.y * b.x
}

pub fn sample_position(f: &Frame, px: u32, py: u32, sx: u32, sy: u32) -> Vec2 {
    let id = ((py * f.width + px) * f.spp_y + sy) * f.spp_x + sx;
    let h = reyes_hash(id ^ f.seed);
    let j = Vec2::new((h & 0xffff) as f32, (h >> 16) as f32) / 65536.0;
    Vec2::new(px as f32, py as f32)
        + (Vec2::new(sx as f32, sy as f32) + j) / Vec2::new(f.spp_x as f32, f.spp_y as f32)
}

/// `Triangle` in sample.wgsl: the inside test's per-triangle values, computed once.
struct Triangle {
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

fn triangle_setup(a: [f32; 4], b: [f32; 4], c: [f32; 4], grow: f32) -> Triangle {
    let (pa, pb, pc) = (xy(a), xy(b), xy(c));
    Triangle {
        a,
        b,
        c,
        area: cross2(pb - pa, pc - pa),
        g: [
            -grow * pb.distance(pc),
            -grow * pa.distance(pc),
            -grow * pa.distance(pb),
        ],
    }
}

fn triangle_depth(t: &Triangle, q: Vec2) -> f32 {
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
    (wa * t.a[2] + wb * t.b[2] + wc * t.c[2]) / t.area.abs()
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

/// Samples quad `q` (a, b, c, d around); false when it was culled as back-facing.
pub fn sample_micropolygon(
    q: [[f32; 4]; 4],
    grow: f32,
    two_sided: bool,
    f: &Frame,
    samples: &mut [u64],
) -> bool {
    let c = q.map(|v| v[3].to_bits());
    if !two_sided && (c[0] & c[1] & c[2] & c[3] & (1 << 30)) != 0 {
        return false;
    }
    let color = average_color(c);
    let xy = q.map(|v| Vec2::new(v[0], v[1]));
    let lo = xy[0].min(xy[1]).min(xy[2].min(xy[3])) - Vec2::splat(grow);
    let hi = xy[0].max(xy[1]).max(xy[2].max(xy[3])) + Vec2::splat(grow);
    let (t0, t1) = (
        [f.tile_x0, f.tile_y0],
        [f.tile_x0 + f.tile_w, f.tile_y0 + f.tile_h],
    );
    let inside = |k: usize| hi[k] >= t0[k] as f32 && lo[k] < t1[k] as f32;
    if !(inside(0) && inside(1)) {
        return true;
    }
    let p0 = |k: usize| lo[k].max(t0[k] as f32) as u32;
    let p1 = |k: usize| (hi[k].min(t1[k] as f32) as u32).min(t1[k] - 1);
    let spp = f.spp_x * f.spp_y;
    let abc = triangle_setup(q[0], q[1], q[2], grow);
    let acd = triangle_setup(q[0], q[2], q[3], grow);
    for py in p0(1)..=p1(1) {
        for px in p0(0)..=p1(0) {
            for sy in 0..f.spp_y {
                for sx in 0..f.spp_x {
                    let s = sample_position(f, px, py, sx, sy);
                    if s.x < lo.x || s.y < lo.y || s.x > hi.x || s.y > hi.y {
                        continue;
                    }
                    let mut z = triangle_depth(&abc, s);
                    if z < 0.0 {
                        z = triangle_depth(&acd, s);
                    }
                    if z < 0.0 {
                        continue;
                    }
                    let pixel = (py - t0[1]) * f.tile_w + px - t0[0];
                    let idx = (pixel * spp + sy * f.spp_x + sx) as usize;
                    samples[idx] = samples[idx].max(sample_key(z, color));
                }
            }
        }
    }
    true
}
