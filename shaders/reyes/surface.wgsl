// The surface of a patch at (u, v): position and tangents (polynomial and rational), the
// normal with its degenerate-point fallback, and the colour fields of primitive variables.
// Shared by DiceShade (dice_shade.wgsl) and the raster peer's tessellation (tessellate.wgsl).
// Rust twin: reyes/src/stages/dice_shade.rs. Needs common.wgsl.

// Bernstein weights of degree 3 at t.
fn bern3(t: f32) -> vec4<f32> {
    let s = 1.0 - t;
    return vec4<f32>(s * s * s, 3.0 * t * s * s, 3.0 * t * t * s, t * t * t);
}

// Bernstein weights of degree 2 (the hodograph's basis).
fn bern2(t: f32) -> vec3<f32> {
    let s = 1.0 - t;
    return vec3<f32>(s * s, 2.0 * t * s, t * t);
}

// Position and the two tangents of the patch at (u, v) in its own [0,1]^2. The tangents come
// from the hodograph (differences of neighbouring control points), so where control points
// coincide (a collapsed edge) the tangent is exactly zero, not rounding noise of the size of
// the coordinates that the degenerate-normal test below could not tell from a real tangent.
// Polynomial patches only (cp the points); eval_rational is the general form.
fn eval_patch(cp: ptr<function, array<f32, 48>>, u: f32, v: f32) -> array<vec3<f32>, 3> {
    let bu = bern3(u);
    let bv = bern3(v);
    let hu = bern2(u);
    let hv = bern2(v);
    var p = vec3<f32>(0.0);
    var pu = vec3<f32>(0.0);
    var pv = vec3<f32>(0.0);
    for (var j = 0u; j < 4u; j++) {
        for (var i = 0u; i < 4u; i++) {
            let c = cp_point(cp, 4u * j + i);
            p += c * (bu[i] * bv[j]);
            if i < 3u { pu += (cp_point(cp, 4u * j + i + 1u) - c) * (hu[i] * bv[j]); }
            if j < 3u { pv += (cp_point(cp, 4u * j + i + 4u) - c) * (bu[i] * hv[j]); }
        }
    }
    return array<vec3<f32>, 3>(p, 3.0 * pu, 3.0 * pv);
}

// Position and the two tangents of a rational item at (u, v) of its own [0,1]^2, from its
// homogeneous net: the xyz of the item and its 16 weights (rational_weights, the exact weights
// of the sub-patch). X = sum B_i B_j (cp_ij, w_ij) in 4D with its hodograph derivatives as in
// eval_patch, then the quotient rule: P = X.xyz / w and Pu = (Xu.xyz - wu P) / w (likewise
// Pv), exact derivatives of the rational surface. (Where control points coincide the tangent
// is rounding noise of the size |wu P| eps rather than zero; patch_normal's threshold is far
// above it.)
fn eval_rational(cp: ptr<function, array<f32, 48>>, w: ptr<function, array<f32, 16>>, u: f32,
                 v: f32) -> array<vec3<f32>, 3> {
    let bu = bern3(u);
    let bv = bern3(v);
    let hu = bern2(u);
    let hv = bern2(v);
    var x = vec4<f32>(0.0);
    var xu = vec4<f32>(0.0);
    var xv = vec4<f32>(0.0);
    for (var j = 0u; j < 4u; j++) {
        for (var i = 0u; i < 4u; i++) {
            let c = cp_h(cp, w, 4u * j + i);
            x += c * (bu[i] * bv[j]);
            if i < 3u { xu += (cp_h(cp, w, 4u * j + i + 1u) - c) * (hu[i] * bv[j]); }
            if j < 3u { xv += (cp_h(cp, w, 4u * j + i + 4u) - c) * (bu[i] * hv[j]); }
        }
    }
    let p = x.xyz / x.w;
    let s = 3.0 / x.w;
    return array<vec3<f32>, 3>(p, (xu.xyz - xu.w * p) * s, (xv.xyz - xv.w * p) * s);
}

// Homogeneous control point k of a rational item: (x w, y w, z w, w).
fn cp_h(cp: ptr<function, array<f32, 48>>, w: ptr<function, array<f32, 16>>, k: u32) -> vec4<f32> {
    return vec4<f32>(cp_point(cp, k), (*w)[k]);
}

// eval_rational for a rational patch, else eval_patch (which reads no weights).
fn eval_surface(cp: ptr<function, array<f32, 48>>, w: ptr<function, array<f32, 16>>,
                rational: bool, u: f32, v: f32) -> array<vec3<f32>, 3> {
    if rational { return eval_rational(cp, w, u, v); }
    return eval_patch(cp, u, v);
}

// Squares of the largest control-net steps along u and v: 3 times the steps bound |Pu| and
// |Pv| on the patch. (Squares: no square roots per grid point.) Polynomial patches.
fn net_steps2(cp: ptr<function, array<f32, 48>>) -> vec2<f32> {
    var m = vec2<f32>(0.0);
    for (var j = 0u; j < 4u; j++) {
        for (var i = 0u; i < 3u; i++) {
            let du = cp_point(cp, 4u * j + i + 1u) - cp_point(cp, 4u * j + i);
            let dv = cp_point(cp, 4u * i + j + 4u) - cp_point(cp, 4u * i + j);
            m = max(m, vec2<f32>(dot(du, du), dot(dv, dv)));
        }
    }
    return m;
}

// net_steps2 of a rational patch (homogeneous net): squares of s_u, s_v with |Pu| <= 3 s_u.
// w Pu = Xu - wu P = 3 sum B_j(v) sum B2_i(u) [w_{i+1,j} (b_{i+1,j} - b_ij)
// + (w_{i+1,j} - w_ij)(b_ij - P)] for Euclidean points b and weights w (convex combinations),
// and |b_ij - P| <= r, the diagonal of the points' bounding box (P lies in their hull); so
// s_u = (wmax du + dwu r) / wmin with du, dwu the largest steps along u of points and weights.
fn net_steps2_rational(cp: ptr<function, array<f32, 48>>, w: ptr<function, array<f32, 16>>)
    -> vec2<f32> {
    var lo = vec3<f32>(3.0e38);
    var hi = vec3<f32>(-3.0e38);
    var wmin = 3.0e38;
    var wmax = 0.0;
    var m = vec4<f32>(0.0);
    for (var j = 0u; j < 4u; j++) {
        for (var i = 0u; i < 4u; i++) {
            let h = cp_h(cp, w, 4u * j + i);
            lo = min(lo, h.xyz / h.w);
            hi = max(hi, h.xyz / h.w);
            wmin = min(wmin, h.w);
            wmax = max(wmax, h.w);
        }
        for (var i = 0u; i < 3u; i++) {
            let a = cp_h(cp, w, 4u * j + i);
            let b = cp_h(cp, w, 4u * j + i + 1u);
            let c = cp_h(cp, w, 4u * i + j);
            let d = cp_h(cp, w, 4u * i + j + 4u);
            let du = b.xyz / b.w - a.xyz / a.w;
            let dv = d.xyz / d.w - c.xyz / c.w;
            m = max(m, vec4<f32>(dot(du, du), dot(dv, dv), abs(b.w - a.w), abs(d.w - c.w)));
        }
    }
    let r = length(hi - lo);
    let s = (wmax * sqrt(m.xy) + m.zw * r) / wmin;
    return s * s;
}

// The outside normal at (u, v). Where it is degenerate (a tangent vanishes at a collapsed
// edge, e.g. the teapot lid's apex; or the tangents are parallel, e.g. rows on one line) it is
// taken a little inside the patch, where it is close to the limit normal: steps of 1e-3, 1e-2
// and 1e-1 of the way to the centre until |Pu x Pv| is at least 1e-3 of its largest possible
// value on the patch (9 |net steps|^2; net_steps2_rational for a rational patch); a fixed
// relative test on |Pu| |Pv| would accept tangents made of rounding noise. A patch with no
// tangent plane anywhere (all control points equal) gets the direction to the eye.
// `e` is eval_surface at (u, v), which the caller has already computed.
fn patch_normal(cp: ptr<function, array<f32, 48>>, w: ptr<function, array<f32, 16>>,
                rational: bool, e: array<vec3<f32>, 3>, u: f32, v: f32, flip: bool) -> vec3<f32> {
    var n = cross(e[1], e[2]);
    var steps2 = vec2<f32>(0.0);
    if rational { steps2 = net_steps2_rational(cp, w); } else { steps2 = net_steps2(cp); }
    let least2 = 8.1e-5 * steps2.x * steps2.y;
    var inward = 1.0e-3;
    for (var k = 0u; k < 3u && !(dot(n, n) > least2); k++) {
        let q = vec2<f32>(u, v) + (vec2<f32>(0.5) - vec2<f32>(u, v)) * inward;
        let f = eval_surface(cp, w, rational, q.x, q.y);
        n = cross(f[1], f[2]);
        inward *= 10.0;
    }
    if !(dot(n, n) > 0.0) {
        return select(-e[0], vec3<f32>(0.0, 0.0, -1.0), !(dot(e[0], e[0]) > 0.0));
    }
    return select(n, -n, flip);
}

// The value at (u, v) of the original patch of colour field `field` (PatchInfo.cs or .os): one
// value, bilinear between 4 corners, or bicubic Bezier in 16 coefficients. Twin: color_field in
// dice_shade.rs.
fn color_field(field: u32, u: f32, v: f32) -> vec3<f32> {
    let at = field >> 2u;
    let shape = field & 3u;
    if shape == FIELD_FLAT { return primvars[at].xyz; }
    if shape == FIELD_BILINEAR {
        let lo = primvars[at].xyz + (primvars[at + 1u].xyz - primvars[at].xyz) * u;
        let hi = primvars[at + 2u].xyz + (primvars[at + 3u].xyz - primvars[at + 2u].xyz) * u;
        return lo + (hi - lo) * v;
    }
    let bu = bern3(u);
    let bv = bern3(v);
    var c = vec3<f32>(0.0);
    for (var j = 0u; j < 4u; j++) {
        for (var i = 0u; i < 4u; i++) {
            c += primvars[at + 4u * j + i].xyz * (bu[i] * bv[j]);
        }
    }
    return c;
}

// (u, v) of the item's own [0,1]^2 in its original patch, where primitive variables are given.
fn original_uv(item: PatchItem, u: f32, v: f32) -> vec2<f32> {
    return vec2<f32>(item.uv.x + (item.uv.y - item.uv.x) * u, item.uv.z + (item.uv.w - item.uv.z) * v);
}

// Displacement (PATCH_DISPLACED; docs/reyes.md, "Displacement"). A displaced patch's entry `at`
// in `primvars` is (amount, bound, kind, map): the camera-space distance per unit of pattern,
// the radius Bound grows by, DISPLACE_BUMPS or DISPLACE_MAP (u32 bits), and (u32 bits) the
// bumps' frequency or the entry of the map's block: (width, height, 0, 0) as u32 bits, then the texels 4 to an entry, row-major from the
// top row. Twins: displacement_pattern etc. in dice_shade.rs.

const PI: f32 = 3.14159265358979;

// The pattern of entry `at` at (u, v) = q of the original patch, in [0, 1]: "bumps"
// (sin(pi f u) sin(pi f v))^2 (f bumps per side), 0 on every patch edge; or the map bilinearly (texel centres at
// (x + 0.5) / width, clamped to the edge texels).
fn displacement_pattern(at: u32, q: vec2<f32>) -> f32 {
    let e = primvars[at];
    if bitcast<u32>(e.z) == DISPLACE_BUMPS {
        let f = f32(bitcast<u32>(e.w));
        let s = sin(PI * f * q.x) * sin(PI * f * q.y);
        return s * s;
    }
    let m = bitcast<u32>(e.w);
    let w = bitcast<u32>(primvars[m].x);
    let h = bitcast<u32>(primvars[m].y);
    let x = clamp(q.x * f32(w) - 0.5, 0.0, f32(w - 1u));
    let y = clamp(q.y * f32(h) - 0.5, 0.0, f32(h - 1u));
    let x0 = u32(x);
    let y0 = u32(y);
    let x1 = min(x0 + 1u, w - 1u);
    let y1 = min(y0 + 1u, h - 1u);
    let fx = x - f32(x0);
    let fy = y - f32(y0);
    let top = map_texel(m, w, x0, y0) * (1.0 - fx) + map_texel(m, w, x1, y0) * fx;
    let bottom = map_texel(m, w, x0, y1) * (1.0 - fx) + map_texel(m, w, x1, y1) * fx;
    return top * (1.0 - fy) + bottom * fy;
}

// Step of the central differences of a pattern, in the original patch's (u, v).
const DISPLACE_FD_STEP: f32 = 0.0009765625;

// Central differences (d/du, d/dv) of the pattern of entry `at` at q in the original patch's
// (u, v), step DISPLACE_FD_STEP (1/1024).
fn displacement_slope(at: u32, q: vec2<f32>) -> vec2<f32> {
    let h = DISPLACE_FD_STEP;
    let du = displacement_pattern(at, q + vec2<f32>(h, 0.0)) - displacement_pattern(at, q - vec2<f32>(h, 0.0));
    let dv = displacement_pattern(at, q + vec2<f32>(0.0, h)) - displacement_pattern(at, q - vec2<f32>(0.0, h));
    return vec2<f32>(du, dv) * (0.5 / h);
}

// Texel (x, y) of the map whose block starts at entry m (w texels per row).
fn map_texel(m: u32, w: u32, x: u32, y: u32) -> f32 {
    let k = y * w + x;
    return primvars[m + 1u + k / 4u][k % 4u];
}
