// Sampling: one micropolygon (a bilinear quad of grid points, flat colour) against the jittered
// sub-samples under its screen bound, with an inside test per triangle and a depth test by
// 64-bit atomicMax. Rust twin: reyes/src/stages/sample.rs.

fn cross2(a: vec2<f32>, b: vec2<f32>) -> f32 { return a.x * b.y - a.y * b.x; }

// Position of sub-sample (sx, sy) of pixel (px, py): stratified, jittered by a hash.
fn sample_position(px: u32, py: u32, sx: u32, sy: u32) -> vec2<f32> {
    let id = ((py * frame.width + px) * frame.spp_y + sy) * frame.spp_x + sx;
    let h = reyes_hash(id ^ frame.seed);
    let j = vec2<f32>(f32(h & 0xffffu), f32(h >> 16u)) / 65536.0;
    return vec2<f32>(f32(px), f32(py)) + (vec2<f32>(f32(sx), f32(sy)) + j)
        / vec2<f32>(f32(frame.spp_x), f32(frame.spp_y));
}

// A triangle of a micropolygon with what its inside test needs, computed once per triangle:
// the signed area and each edge's threshold for growing it by `grow` pixels.
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

fn triangle_setup(a: vec4<f32>, b: vec4<f32>, c: vec4<f32>, grow: f32) -> Triangle {
    return Triangle(a.xyz, b.xyz, c.xyz, cross2(b.xy - a.xy, c.xy - a.xy),
        -grow * distance(b.xy, c.xy), -grow * distance(a.xy, c.xy), -grow * distance(a.xy, b.xy));
}

// Depth at q if q is inside the grown triangle; negative otherwise.
fn triangle_depth(t: Triangle, q: vec2<f32>) -> f32 {
    if abs(t.area) < 1.0e-12 { return -1.0; }
    let s = sign(t.area);
    let wa = s * cross2(t.c.xy - t.b.xy, q - t.b.xy);
    let wb = s * cross2(t.a.xy - t.c.xy, q - t.c.xy);
    let wc = s * cross2(t.b.xy - t.a.xy, q - t.a.xy);
    if wa < t.ga || wb < t.gb || wc < t.gc { return -1.0; }
    return (wa * t.a.z + wb * t.b.z + wc * t.c.z) / abs(t.area);
}

fn average_color(a: u32, b: u32, c: u32, d: u32) -> u32 {
    var out = 0u;
    for (var k = 0u; k < 30u; k += 10u) {
        let sum = ((a >> k) & 1023u) + ((b >> k) & 1023u) + ((c >> k) & 1023u) + ((d >> k) & 1023u);
        out |= ((sum + 2u) / 4u) << k;
    }
    return out;
}

fn sample_micropolygon(a: vec4<f32>, b: vec4<f32>, c: vec4<f32>, d: vec4<f32>, grow: f32, two_sided: bool) {
    let ca = bitcast<u32>(a.w);
    let cb = bitcast<u32>(b.w);
    let cc = bitcast<u32>(c.w);
    let cd = bitcast<u32>(d.w);
    let back = 1u << 30u;
    if !two_sided && (ca & cb & cc & cd & back) != 0u {
        atomicAdd(&counters[C_BACKFACE], 1u);
        return;
    }
    let color = average_color(ca, cb, cc, cd);
    let lo = min(min(a.xy, b.xy), min(c.xy, d.xy)) - vec2<f32>(grow);
    let hi = max(max(a.xy, b.xy), max(c.xy, d.xy)) + vec2<f32>(grow);
    // Pixels of this bucket under the bound; the sample test below does not depend on the
    // bucket, so bucketed and whole-frame renders agree sample for sample.
    let t0 = vec2<u32>(frame.tile_x0, frame.tile_y0);
    let t1 = t0 + vec2<u32>(frame.tile_w, frame.tile_h);
    if !(all(hi >= vec2<f32>(t0)) && all(lo < vec2<f32>(t1))) { return; }
    let p0 = vec2<u32>(max(lo, vec2<f32>(t0)));
    let p1 = min(vec2<u32>(min(hi, vec2<f32>(t1))), t1 - vec2<u32>(1u));
    let spp = frame.spp_x * frame.spp_y;
    let abc = triangle_setup(a, b, c, grow);
    let acd = triangle_setup(a, c, d, grow);
    for (var py = p0.y; py <= p1.y; py++) {
        for (var px = p0.x; px <= p1.x; px++) {
            for (var sy = 0u; sy < frame.spp_y; sy++) {
                for (var sx = 0u; sx < frame.spp_x; sx++) {
                    let q = sample_position(px, py, sx, sy);
                    if any(q < lo) || any(q > hi) { continue; }
                    var z = triangle_depth(abc, q);
                    if z < 0.0 { z = triangle_depth(acd, q); }
                    if z < 0.0 { continue; }
                    let key = (u64(~bitcast<u32>(z)) << 32u) | u64(color);
                    let idx = ((py - t0.y) * frame.tile_w + px - t0.x) * spp + sy * frame.spp_x + sx;
                    atomicMax(&samples[idx], key);
                }
            }
        }
    }
}
