// Sampling in time and on the lens (motion blur and depth of field; Sattler & Steinberger,
// "Reyes Rendering on the GPU", section 3.3). Only when SCENE_UVT and frame.uvt != UVT_OFF.
// A micropolygon arrives with its corners at shutter open (q0: x, y in pixels, z camera depth,
// w colour bits) and at shutter close (q1: x, y, z). A 3D sample s = (lens u, lens v, time t)
// moves each corner to q0 + t (q1 - q0) (the paper's linear screen-space motion vector) plus
// coc(z) * (u, v), the lens offset scaled by the corner's circle of confusion at its depth at t;
// the moved micropolygon is tested against one sub-sample position. Every sub-sample of every
// pixel has one fixed 3D sample, whatever micropolygon is tested there, so the depth test
// compares surfaces at the same time and lens position. The algorithms differ in which 3D
// sample a sub-sample gets and in the loop order:
//   UVT_SIMPLE: sub-sample k of every pixel has the same sample k of S (S = spp): the
//     micropolygon is moved S times and rasterized into sub-sample k each time;
//   UVT_INTERLEAVE: K x K pixel tiles share N = K^2 S samples; tile (tx, ty) assigns sample j
//     to the sub-sample at slot permute(j, N, perm) (slot = (ly K + lx) S + k) with
//     perm = (tile number + tx + ty) mod P (the paper's eq. 2-3); the micropolygon is moved N
//     times, and at each the one sub-sample per tile holding that sample is tested;
//   UVT_BBOX (the default): each pixel's S samples are its own, hashed from its index, one per
//     time stratum in an order shifted per pixel; for each stratum the
//     bound of the micropolygon over that stratum's times, grown by the circles of confusion,
//     tests the one sub-sample per pixel under it whose time lies in the stratum, at its own
//     time and lens position (stochastic sampling: Cook, Porter and Carpenter 1984).
// Rust twin: reyes/src/stages/sample_uvt.rs.

// Mixed into the keys of the 3D samples and the permutations (differ from the jitter hash).
const UVT_SALT: u32 = 0x9e3779b9u;
const PERM_SALT: u32 = 0x632be5abu;
// Where DiceShade keeps the shutter-close points in diceshade_shared (after the open ones).
const UVT_CLOSE: u32 = 256u;

// The unit disc from the unit square, area-preserving (Shirley & Chiu's concentric map).
fn concentric_disc(s: vec2<f32>) -> vec2<f32> {
    let a = 2.0 * s - vec2<f32>(1.0);
    if a.x == 0.0 && a.y == 0.0 { return vec2<f32>(0.0); }
    var r: f32;
    var phi: f32;
    if abs(a.x) > abs(a.y) {
        r = a.x;
        phi = 0.7853981633974483 * (a.y / a.x);
    } else {
        r = a.y;
        phi = 1.5707963267948966 - 0.7853981633974483 * (a.x / a.y);
    }
    return r * vec2<f32>(cos(phi), sin(phi));
}

// A 3D sample: lens position in the unit disc (xy) and time in [0, 1) (z), stratum `stratum`
// of `n` in time, the rest hashed from `key`.
fn uvt_sample(key: u32, stratum: u32, n: u32) -> vec3<f32> {
    let h1 = reyes_hash(key ^ frame.seed ^ UVT_SALT);
    let h2 = reyes_hash(h1 + 1u);
    let h3 = reyes_hash(h2 + 1u);
    let t = (f32(stratum) + f32(h1 >> 8u) / 16777216.0) / f32(n);
    let lens = concentric_disc(vec2<f32>(f32(h2 >> 8u), f32(h3 >> 8u)) / 16777216.0);
    return vec3<f32>(lens, t);
}

// The 3D sample of sub-sample k of pixel (px, py) under UVT_BBOX, hashed from the pixel's index
// in the image (no table repeated over the image: a repeat would show as a pattern in the
// noise and correlate the estimate across the repeats): its S samples are stratified in time,
// their order shifted per pixel.
fn uvt_table_sample(px: u32, py: u32, k: u32, n: u32) -> vec3<f32> {
    let texel = py * frame.width + px;
    let shift = reyes_hash(texel ^ PERM_SALT) % n;
    return uvt_sample(texel * n + k, (k + shift) % n, n);
}

// The sub-sample of pixel (px, py) whose time lies in stratum j of n (UVT_BBOX): the inverse
// of uvt_table_sample's (k + shift) mod n.
fn table_slot(px: u32, py: u32, j: u32, n: u32) -> u32 {
    let texel = py * frame.width + px;
    let shift = reyes_hash(texel ^ PERM_SALT) % n;
    return (j + n - shift) % n;
}

// Growth of a time stratum's bound against rounding: the stratum's end points and a sample's
// point inside it are computed by different roundings (one may be fused), each within an ulp
// or two of |x|; 1/64 px plus 1e-5 |x| is far above that and costs at most a pixel row.
fn stratum_margin(x: vec2<f32>) -> f32 {
    return 0.015625 + 1.0e-5 * max(abs(x.x), abs(x.y));
}

// Kensler's hashed permutation ("Correlated Multi-Jittered Sampling", 2013): a bijection of
// [0, l) chosen by p, by cycle walking a bijection of [0, 2^b) (2^b >= l). The walk leaves
// [l, 2^b) within 2^b - l < l steps; the loop's bound is that.
fn permute(index: u32, l: u32, p: u32) -> u32 {
    var w = l - 1u;
    w |= w >> 1u;
    w |= w >> 2u;
    w |= w >> 4u;
    w |= w >> 8u;
    w |= w >> 16u;
    var i = index;
    for (var step = 0u; step <= w; step++) {
        i ^= p; i *= 0xe170893du;
        i ^= p >> 16u;
        i ^= (i & w) >> 4u;
        i ^= p >> 8u; i *= 0x0929eb3fu;
        i ^= p >> 23u;
        i ^= (i & w) >> 1u; i *= 1u | (p >> 27u);
        i *= 0x6935fa69u;
        i ^= (i & w) >> 11u; i *= 0x74dcb303u;
        i ^= (i & w) >> 2u; i *= 0x9e501cc3u;
        i ^= (i & w) >> 2u; i *= 0xc860a3dfu;
        i &= w;
        i ^= i >> 5u;
        if i < l { break; }
    }
    return (i + p) % l;
}

// Corner p0 (shutter open, colour in w) moved to 3D sample s, p1 its shutter-close point.
fn uvt_corner(p0: vec4<f32>, p1: vec4<f32>, s: vec3<f32>) -> vec4<f32> {
    let p = p0.xyz + (p1.xyz - p0.xyz) * s.z;
    return vec4<f32>(p.xy + coc(p.z) * s.xy, p.z, p0.w);
}

// The two triangles of the micropolygon moved to s, with the growth of sample_micropolygon.
struct MovedQuad {
    abc: Triangle,
    acd: Triangle,
    lo: vec2<f32>,
    hi: vec2<f32>,
}

fn moved_quad(q0: array<vec4<f32>, 4>, q1: array<vec4<f32>, 4>, s: vec3<f32>, grow: vec4<f32>)
    -> MovedQuad {
    let a = uvt_corner(q0[0], q1[0], s);
    let b = uvt_corner(q0[1], q1[1], s);
    let c = uvt_corner(q0[2], q1[2], s);
    let d = uvt_corner(q0[3], q1[3], s);
    let g = max(max(grow.x, grow.y), max(grow.z, grow.w));
    let diagonal = min(min(grow.x, grow.y), min(grow.z, grow.w));
    return MovedQuad(triangle_setup(a, b, c, vec3<f32>(grow.y, diagonal, grow.x)),
        triangle_setup(a, c, d, vec3<f32>(grow.z, grow.w, diagonal)),
        min(min(a.xy, b.xy), min(c.xy, d.xy)) - vec2<f32>(g),
        max(max(a.xy, b.xy), max(c.xy, d.xy)) + vec2<f32>(g));
}

// Tests sub-sample (sx, sy) of pixel (px, py) (in the bucket) against the moved quad.
fn uvt_test(m: MovedQuad, px: u32, py: u32, sx: u32, sy: u32, color: u32, cover: Cover) {
    let q = sample_position(px, py, sx, sy);
    if any(q < m.lo) || any(q > m.hi) { return; }
    var z = triangle_depth(m.abc, q);
    if z < 0.0 { z = triangle_depth(m.acd, q); }
    if z < 0.0 || !covers(cover, sample_id(px, py, sx, sy)) { return; }
    write_sample(px, py, sx, sy, z, color);
}

// The bucket's pixels under [lo, hi], as (p0, p1) inclusive; p0 > p1 when none.
fn bucket_pixels(lo: vec2<f32>, hi: vec2<f32>) -> array<vec2<u32>, 2> {
    let t0 = vec2<u32>(frame.tile_x0, frame.tile_y0);
    let t1 = t0 + vec2<u32>(frame.tile_w, frame.tile_h);
    if !(all(hi >= vec2<f32>(t0)) && all(lo < vec2<f32>(t1))) {
        return array<vec2<u32>, 2>(vec2<u32>(1u), vec2<u32>(0u));
    }
    let p0 = vec2<u32>(max(lo, vec2<f32>(t0)));
    let p1 = min(vec2<u32>(min(hi, vec2<f32>(t1))), t1 - vec2<u32>(1u));
    return array<vec2<u32>, 2>(p0, p1);
}

// Samples micropolygon (a, b, c, d at shutter open; a1, b1, c1, d1 at close) in time and on
// the lens by frame.uvt's algorithm. `grow`, `two_sided`, `cover`: as sample_micropolygon.
fn sample_micropolygon_uvt(a: vec4<f32>, b: vec4<f32>, c: vec4<f32>, d: vec4<f32>,
                           a1: vec4<f32>, b1: vec4<f32>, c1: vec4<f32>, d1: vec4<f32>,
                           grow: vec4<f32>, two_sided: bool, cover: Cover) {
    let color = micropolygon_color(a, b, c, d, two_sided);
    if color == CULLED || !(cover.alpha > 0.0) { return; }
    let q0 = array<vec4<f32>, 4>(a, b, c, d);
    let q1 = array<vec4<f32>, 4>(a1, b1, c1, d1);
    let spp = frame.spp_x * frame.spp_y;
    if frame.uvt == UVT_SIMPLE {
        for (var k = 0u; k < spp; k++) {
            let m = moved_quad(q0, q1, uvt_sample(k, k, spp), grow);
            let p = bucket_pixels(m.lo, m.hi);
            for (var py = p[0].y; py <= p[1].y; py++) {
                for (var px = p[0].x; px <= p[1].x; px++) {
                    uvt_test(m, px, py, k % frame.spp_x, k / frame.spp_x, color, cover);
                }
            }
        }
    } else if frame.uvt == UVT_INTERLEAVE {
        let kt = frame.il_tile;
        let n = kt * kt * spp;
        let tiles_x = frame.width / kt;
        for (var j = 0u; j < n; j++) {
            let m = moved_quad(q0, q1, uvt_sample(j, j, n), grow);
            let p = bucket_pixels(m.lo, m.hi);
            if p[0].x > p[1].x || p[0].y > p[1].y { continue; }
            for (var ty = p[0].y / kt; ty <= p[1].y / kt; ty++) {
                for (var tx = p[0].x / kt; tx <= p[1].x / kt; tx++) {
                    // The paper's eq. (2) and (3).
                    let tile_number = ty * tiles_x + tx;
                    let perm = (tile_number + tx + ty) % frame.il_perms;
                    let slot = permute(j, n, reyes_hash(perm ^ frame.seed ^ PERM_SALT));
                    let k = slot % spp;
                    let px = tx * kt + (slot / spp) % kt;
                    let py = ty * kt + slot / (spp * kt);
                    if px < p[0].x || px > p[1].x || py < p[0].y || py > p[1].y { continue; }
                    uvt_test(m, px, py, k % frame.spp_x, k / frame.spp_x, color, cover);
                }
            }
        }
    } else {
        // Time stratum by time stratum: pixel (px, py)'s sub-sample k has its time in stratum
        // (k + shift) mod S (uvt_table_sample), so stratum j is held by its sub-sample
        // (j + S - shift) mod S. The micropolygon over [j / S, (j + 1) / S] lies in the bound of
        // both ends of each corner's motion (linear in t, rounding monotone in t), grown by the
        // largest circle of confusion there (monotone in depth, which moves linearly): only
        // the pixels under that bound can hold a sample of stratum j it covers. The same
        // samples and tests as one pass over the whole shutter's bound, S times fewer when the
        // motion dominates.
        let g = max(max(grow.x, grow.y), max(grow.z, grow.w));
        for (var j = 0u; j < spp; j++) {
            let tb = vec2<f32>(f32(j), f32(j + 1u)) / f32(spp);
            var lo = vec2<f32>(3.0e38);
            var hi = vec2<f32>(-3.0e38);
            var r = 0.0;
            for (var i = 0u; i < 4u; i++) {
                let e0 = q0[i].xyz + (q1[i].xyz - q0[i].xyz) * tb.x;
                let e1 = q0[i].xyz + (q1[i].xyz - q0[i].xyz) * tb.y;
                lo = min(lo, min(e0.xy, e1.xy));
                hi = max(hi, max(e0.xy, e1.xy));
                r = max(r, max(abs(coc(e0.z)), abs(coc(e1.z))));
            }
            let p = bucket_pixels(lo - vec2<f32>(g + r + stratum_margin(lo)),
                hi + vec2<f32>(g + r + stratum_margin(hi)));
            for (var py = p[0].y; py <= p[1].y; py++) {
                for (var px = p[0].x; px <= p[1].x; px++) {
                    let k = table_slot(px, py, j, spp);
                    let s = uvt_table_sample(px, py, k, spp);
                    // Most pixels of a long blur miss the micropolygon at their sample's time:
                    // the moved corners' bound (moved_quad's lo, hi, the same bits) rejects
                    // them before the triangles are set up.
                    let ma = uvt_corner(q0[0], q1[0], s).xy;
                    let mb = uvt_corner(q0[1], q1[1], s).xy;
                    let mc = uvt_corner(q0[2], q1[2], s).xy;
                    let md = uvt_corner(q0[3], q1[3], s).xy;
                    let q = sample_position(px, py, k % frame.spp_x, k / frame.spp_x);
                    if any(q < min(min(ma, mb), min(mc, md)) - vec2<f32>(g))
                        || any(q > max(max(ma, mb), max(mc, md)) + vec2<f32>(g)) {
                        continue;
                    }
                    let m = moved_quad(q0, q1, s, grow);
                    uvt_test(m, px, py, k % frame.spp_x, k / frame.spp_x, color, cover);
                }
            }
        }
    }
}
