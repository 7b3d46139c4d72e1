// Sampling: one micropolygon (a bilinear quad of grid points, flat colour) against the jittered
// sub-samples under its screen bound, with an inside test per triangle and a depth test by
// 64-bit atomicMax: bounding-box rasterization (RASTER_BBOX, Sattler & Steinberger 4.2). Or,
// with frame.raster = RASTER_NEAREST, the paper's naive mode: only the sub-sample nearest the
// micropolygon's centre (sample_nearest). Rust twin: reyes/src/stages/sample.rs.

fn cross2(a: vec2<f32>, b: vec2<f32>) -> f32 { return a.x * b.y - a.y * b.x; }

// Index of sub-sample (sx, sy) of pixel (px, py) in the whole image (not the bucket).
fn sample_id(px: u32, py: u32, sx: u32, sy: u32) -> u32 {
    return ((py * frame.width + px) * frame.spp_y + sy) * frame.spp_x + sx;
}

// Position of sub-sample (sx, sy) of pixel (px, py): stratified, jittered by a hash.
fn sample_position(px: u32, py: u32, sx: u32, sy: u32) -> vec2<f32> {
    let h = reyes_hash(sample_id(px, py, sx, sy) ^ frame.seed);
    let j = vec2<f32>(f32(h & 0xffffu), f32(h >> 16u)) / 65536.0;
    return vec2<f32>(f32(px), f32(py)) + (vec2<f32>(f32(sx), f32(sy)) + j)
        / vec2<f32>(f32(frame.spp_x), f32(frame.spp_y));
}

// A triangle of a micropolygon with what its inside test needs, computed once per triangle:
// the signed area and each edge's threshold for growing it outward by that edge's pixels.
struct Triangle {
    a: vec3<f32>,
    b: vec3<f32>,
    c: vec3<f32>,
    area: f32,
    // -grow * length of the edge opposite a, b, c.
    ga: f32,
    gb: f32,
    gc: f32,
}

// `grow`: pixels to grow the edges opposite a, b and c (bc, ca, ab).
fn triangle_setup(a: vec4<f32>, b: vec4<f32>, c: vec4<f32>, grow: vec3<f32>) -> Triangle {
    return Triangle(a.xyz, b.xyz, c.xyz, cross2(b.xy - a.xy, c.xy - a.xy),
        -grow.x * distance(b.xy, c.xy), -grow.y * distance(a.xy, c.xy),
        -grow.z * distance(a.xy, b.xy));
}

// Depth at q if q is inside the grown triangle; negative otherwise.
fn triangle_depth(t: Triangle, q: vec2<f32>) -> f32 {
    if abs(t.area) < 1.0e-12 { return -1.0; }
    let s = sign(t.area);
    let wa = s * cross2(t.c.xy - t.b.xy, q - t.b.xy);
    let wb = s * cross2(t.a.xy - t.c.xy, q - t.c.xy);
    let wc = s * cross2(t.b.xy - t.a.xy, q - t.a.xy);
    if wa < t.ga || wb < t.gb || wc < t.gc { return -1.0; }
    // Clamped to the corners' depths: a sample the dilation reaches outside the triangle
    // would extrapolate the plane, and rounding can leave the range even inside; Bound's
    // occlusion test relies on no sample being nearer than the nearest corner.
    let z = (wa * t.a.z + wb * t.b.z + wc * t.c.z) / abs(t.area);
    return clamp(z, min(t.a.z, min(t.b.z, t.c.z)), max(t.a.z, max(t.b.z, t.c.z)));
}

fn average_color(a: u32, b: u32, c: u32, d: u32) -> u32 {
    var out = 0u;
    for (var k = 0u; k < 30u; k += 10u) {
        let sum = ((a >> k) & 1023u) + ((b >> k) & 1023u) + ((c >> k) & 1023u) + ((d >> k) & 1023u);
        out |= ((sum + 2u) / 4u) << k;
    }
    return out;
}

// No colour: what micropolygon_color gives a culled micropolygon (colours use bits 0..29).
const CULLED: u32 = 0xffffffffu;

// The flat colour of a micropolygon, the average of its corners' packed colours (in .w); CULLED,
// and counted, when it is one-sided and all four corners face away.
fn micropolygon_color(a: vec4<f32>, b: vec4<f32>, c: vec4<f32>, d: vec4<f32>, two_sided: bool)
    -> u32 {
    let ca = bitcast<u32>(a.w);
    let cb = bitcast<u32>(b.w);
    let cc = bitcast<u32>(c.w);
    let cd = bitcast<u32>(d.w);
    if !two_sided && (ca & cb & cc & cd & (1u << 30u)) != 0u {
        atomicAdd(&counters[C_BACKFACE], 1u);
        return CULLED;
    }
    return average_color(ca, cb, cc, cd);
}

// Stochastic transparency (Enderton et al. 2010): a micropolygon of opacity `alpha` < 1 covers
// each sample under it with probability alpha, decided by a hash of the sample (its image index)
// and the original patch (`salt`), so every strategy, bucket and the CPU twin decide alike, and
// micropolygons of one patch that overlap (crack dilation) decide alike at a sample.
struct Cover {
    alpha: f32,
    salt: u32,
}

// Mixed into the patch id before hashing, so the coverage hash differs from the jitter hash.
const COVER_SALT: u32 = 0x5bd1e995u;

fn covers(c: Cover, id: u32) -> bool {
    if !SCENE_TRANSPARENT || c.alpha >= 1.0 { return true; }
    let h = reyes_hash(reyes_hash(id ^ frame.seed) ^ c.salt);
    return f32(h >> 8u) < c.alpha * 16777216.0;
}

// Keeps the nearest of the keys written to sub-sample (sx, sy) of pixel (px, py) of the bucket.
fn write_sample(px: u32, py: u32, sx: u32, sy: u32, z: f32, color: u32) {
    let key = (u64(~bitcast<u32>(z)) << 32u) | u64(color);
    let pixel = (py - frame.tile_y0) * frame.tile_w + px - frame.tile_x0;
    atomicMax(&samples[pixel * frame.spp_x * frame.spp_y + sy * frame.spp_x + sx], key);
}

// Pixels to grow each edge of micropolygon (i, j) of an nu x nv grid by, (ab, bc, cd, da): its
// boundary edges by the crack dilation Bound packed for that side of the grid, its inner edges
// by ROUNDING_DILATE_PX; nothing when dilation is off (packed = 0).
fn micropolygon_dilation(packed: u32, i: u32, j: u32, nu: u32, nv: u32) -> vec4<f32> {
    let side = vec4<f32>(f32(packed & 255u), f32((packed >> 24u) & 255u),
        f32((packed >> 8u) & 255u), f32((packed >> 16u) & 255u)) * (MAX_DILATE_PX / 255.0);
    let inner = select(0.0, ROUNDING_DILATE_PX, packed != 0u);
    return select(vec4<f32>(inner), side, vec4<bool>(j == 0u, i + 1u == nu, j + 1u == nv, i == 0u));
}

// `grow`: pixels to grow edges ab, bc, cd and da by (micropolygon_dilation); the diagonal ac,
// inside the micropolygon, by the least of them.
// `cover`: the fraction of samples it covers (stochastic transparency, `covers`).
fn sample_micropolygon(a: vec4<f32>, b: vec4<f32>, c: vec4<f32>, d: vec4<f32>, grow: vec4<f32>, two_sided: bool,
                       cover: Cover) {
    let color = micropolygon_color(a, b, c, d, two_sided);
    if color == CULLED || !(cover.alpha > 0.0) { return; }
    // SCENE_NEAREST_RASTER (SceneFeatures): false in a program for bbox frames, which then
    // compiles to the bounding-box code alone.
    if SCENE_NEAREST_RASTER && frame.raster == RASTER_NEAREST {
        sample_nearest(a, b, c, d, color, cover);
        return;
    }
    let g = max(max(grow.x, grow.y), max(grow.z, grow.w));
    let lo = min(min(a.xy, b.xy), min(c.xy, d.xy)) - vec2<f32>(g);
    let hi = max(max(a.xy, b.xy), max(c.xy, d.xy)) + vec2<f32>(g);
    // Pixels of this bucket under the bound; the sample test below does not depend on the
    // bucket, so bucketed and whole-frame renders agree sample for sample.
    let t0 = vec2<u32>(frame.tile_x0, frame.tile_y0);
    let t1 = t0 + vec2<u32>(frame.tile_w, frame.tile_h);
    if !(all(hi >= vec2<f32>(t0)) && all(lo < vec2<f32>(t1))) { return; }
    let p0 = vec2<u32>(max(lo, vec2<f32>(t0)));
    let p1 = min(vec2<u32>(min(hi, vec2<f32>(t1))), t1 - vec2<u32>(1u));
    let diagonal = min(min(grow.x, grow.y), min(grow.z, grow.w));
    let abc = triangle_setup(a, b, c, vec3<f32>(grow.y, diagonal, grow.x));
    let acd = triangle_setup(a, c, d, vec3<f32>(grow.z, grow.w, diagonal));
    for (var py = p0.y; py <= p1.y; py++) {
        for (var px = p0.x; px <= p1.x; px++) {
            for (var sy = 0u; sy < frame.spp_y; sy++) {
                for (var sx = 0u; sx < frame.spp_x; sx++) {
                    let q = sample_position(px, py, sx, sy);
                    if any(q < lo) || any(q > hi) { continue; }
                    var z = triangle_depth(abc, q);
                    if z < 0.0 { z = triangle_depth(acd, q); }
                    if z < 0.0 || !covers(cover, sample_id(px, py, sx, sy)) { continue; }
                    write_sample(px, py, sx, sy, z, color);
                }
            }
        }
    }
}

// RASTER_NEAREST: the micropolygon (corners projected, depth in .z) writes one sample, the
// jittered sub-sample nearest its centre (the mean of its corners; the first in row-major order
// of the image's sample grid on a tie) at the mean depth of its corners, when the centre lies
// in the image. Sample (sx, sy) of pixel (px, py) lies in its stratum, cell (px * spp_x + sx,
// py * spp_y + sy) of the grid of cells 1/spp_x by 1/spp_y pixels, so the nearest is within
// the stratum cell's diagonal of the centre: only the cells that reach that far are searched.
// That reach is at most sqrt(2) px (1x1 samples), inside Bound's CULL_MARGIN_PX (3 px), so a
// bucket never culls a micropolygon whose nearest sample it holds: bucketed renders agree.
fn sample_nearest(a: vec4<f32>, b: vec4<f32>, c: vec4<f32>, d: vec4<f32>, color: u32,
                  cover: Cover) {
    let centre = (a.xy + b.xy + c.xy + d.xy) * 0.25;
    let size = vec2<f32>(f32(frame.width), f32(frame.height));
    if !(all(centre >= vec2<f32>(0.0)) && all(centre < size)) { return; }
    let spp = vec2<u32>(frame.spp_x, frame.spp_y);
    let cell = 1.0 / vec2<f32>(spp);
    let reach = length(cell);
    let cells = vec2<u32>(frame.width, frame.height) * spp;
    let k0 = vec2<u32>(max((centre - vec2<f32>(reach)) / cell, vec2<f32>(0.0)));
    let k1 = min(vec2<u32>((centre + vec2<f32>(reach)) / cell), cells - vec2<u32>(1u));
    var best = vec2<u32>(0u);
    var best_d2 = 3.0e38;
    for (var ky = k0.y; ky <= k1.y; ky++) {
        for (var kx = k0.x; kx <= k1.x; kx++) {
            let q = sample_position(kx / spp.x, ky / spp.y, kx % spp.x, ky % spp.y);
            let e = q - centre;
            let d2 = e.x * e.x + e.y * e.y;
            if d2 < best_d2 {
                best_d2 = d2;
                best = vec2<u32>(kx, ky);
            }
        }
    }
    let p = best / spp;
    let s = best % spp;
    let t0 = vec2<u32>(frame.tile_x0, frame.tile_y0);
    if any(p < t0) || any(p >= t0 + vec2<u32>(frame.tile_w, frame.tile_h)) { return; }
    if !covers(cover, sample_id(p.x, p.y, s.x, s.y)) { return; }
    write_sample(p.x, p.y, s.x, s.y, (a.z + b.z + c.z + d.z) * 0.25, color);
}

// Pixels beyond the image edge that clipped polygons keep: wider than Bound's cull margin plus
// the largest crack dilation, so clipping never cuts what a bucket's samples could see.
const GUARD_BAND_PX: f32 = 16.0;
// Vertices a triangle can have after clipping by the near plane and four guard-band planes.
const CLIPPED_MAX: u32 = 8u;

// The clip planes (a, b, c, d): the part of camera space with a x + b y + c z + d >= 0 is kept.
// 0: the near plane; 1-4: the image's sides grown by the guard band, through the eye.
fn clip_plane(k: u32) -> vec4<f32> {
    let gx = 0.5 * f32(frame.width) + GUARD_BAND_PX;
    let gy = 0.5 * f32(frame.height) + GUARD_BAND_PX;
    let f = frame.focal;
    switch k {
        case 0u: { return vec4<f32>(0.0, 0.0, 1.0, -frame.near); }
        case 1u: { return vec4<f32>(f, 0.0, gx, 0.0); }
        case 2u: { return vec4<f32>(-f, 0.0, gx, 0.0); }
        case 3u: { return vec4<f32>(0.0, -f, gy, 0.0); }
        default: { return vec4<f32>(0.0, f, gy, 0.0); }
    }
}

// One Sutherland-Hodgman step: the part of convex polygon `poly` (n vertices) on the kept side
// of `plane`; returns the new vertex count. An edge's crossing is computed from its kept end,
// so the edge two triangles share is cut at the same point in both.
fn clip_by_plane(poly: ptr<function, array<vec3<f32>, 8>>, n: u32, plane: vec4<f32>) -> u32 {
    var out: array<vec3<f32>, 8>;
    var m = 0u;
    for (var i = 0u; i < n; i++) {
        let p = (*poly)[i];
        let q = (*poly)[(i + 1u) % n];
        let dp = dot(plane.xyz, p) + plane.w;
        let dq = dot(plane.xyz, q) + plane.w;
        if dp >= 0.0 {
            out[m] = p;
            m++;
            if dq < 0.0 { out[m] = p + (q - p) * (dp / (dp - dq)); m++; }
        } else if dq >= 0.0 {
            out[m] = q + (p - q) * (dq / (dq - dp));
            m++;
        }
    }
    *poly = out;
    return m;
}

// A micropolygon of a grid that crosses the near plane, corners in camera space. One wholly in
// front is projected and sampled like any other. Otherwise each of its triangles (abc, acd, the
// split sample_micropolygon uses) is clipped in camera space against the near plane and the
// image's guard band, as hardware rasterizers clip, and what is left is sampled as a fan.
// Every edge of the clipped polygons grows by the micropolygon's largest `grow` (a rare path).
fn sample_near_clipped(a: vec4<f32>, b: vec4<f32>, c: vec4<f32>, d: vec4<f32>, grow: vec4<f32>,
                       two_sided: bool, cover: Cover) {
    if min(min(a.z, b.z), min(c.z, d.z)) >= frame.near {
        sample_micropolygon(projected(a), projected(b), projected(c), projected(d), grow,
            two_sided, cover);
        return;
    }
    let color = micropolygon_color(a, b, c, d, two_sided);
    if color == CULLED || !(cover.alpha > 0.0) { return; }
    let g = max(max(grow.x, grow.y), max(grow.z, grow.w));
    sample_clipped_triangle(a.xyz, b.xyz, c.xyz, g, color, cover);
    sample_clipped_triangle(a.xyz, c.xyz, d.xyz, g, color, cover);
}

fn projected(p: vec4<f32>) -> vec4<f32> {
    return vec4<f32>(project(p.xyz), p.z, p.w);
}

fn sample_clipped_triangle(a: vec3<f32>, b: vec3<f32>, c: vec3<f32>, grow: f32, color: u32,
                           cover: Cover) {
    var poly: array<vec3<f32>, 8>;
    poly[0] = a;
    poly[1] = b;
    poly[2] = c;
    var n = 3u;
    for (var k = 0u; k < 5u && n >= 3u; k++) {
        n = clip_by_plane(&poly, n, clip_plane(k));
        if k == 0u {
            // Crossings of the near plane lie on it; rounding must not put them behind the eye.
            for (var i = 0u; i < n; i++) { poly[i].z = max(poly[i].z, frame.near); }
        }
    }
    if n < 3u { return; }
    var s: array<vec4<f32>, 8>;
    var lo = vec2<f32>(3.0e38);
    var hi = vec2<f32>(-3.0e38);
    for (var i = 0u; i < n; i++) {
        s[i] = vec4<f32>(project(poly[i]), poly[i].z, 0.0);
        lo = min(lo, s[i].xy);
        hi = max(hi, s[i].xy);
    }
    // The fan (s0, s1, s2), (s0, s2, s3), ...
    var fan: array<Triangle, 6>;
    for (var i = 0u; i + 2u < n; i++) {
        fan[i] = triangle_setup(s[0], s[i + 1u], s[i + 2u], vec3<f32>(grow));
    }
    lo -= vec2<f32>(grow);
    hi += vec2<f32>(grow);
    let t0 = vec2<u32>(frame.tile_x0, frame.tile_y0);
    let t1 = t0 + vec2<u32>(frame.tile_w, frame.tile_h);
    if !(all(hi >= vec2<f32>(t0)) && all(lo < vec2<f32>(t1))) { return; }
    let p0 = vec2<u32>(max(lo, vec2<f32>(t0)));
    let p1 = min(vec2<u32>(min(hi, vec2<f32>(t1))), t1 - vec2<u32>(1u));
    for (var py = p0.y; py <= p1.y; py++) {
        for (var px = p0.x; px <= p1.x; px++) {
            for (var sy = 0u; sy < frame.spp_y; sy++) {
                for (var sx = 0u; sx < frame.spp_x; sx++) {
                    let q = sample_position(px, py, sx, sy);
                    if any(q < lo) || any(q > hi) { continue; }
                    var z = -1.0;
                    for (var i = 0u; i + 2u < n && z < 0.0; i++) { z = triangle_depth(fan[i], q); }
                    if z < 0.0 || !covers(cover, sample_id(px, py, sx, sy)) { continue; }
                    write_sample(px, py, sx, sy, z, color);
                }
            }
        }
    }
}
