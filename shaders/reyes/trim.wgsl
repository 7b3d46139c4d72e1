// Trimming (RIB `TrimCurve`; docs/reyes.md, "Trim curves"). Rust twin: reyes/src/stages/trim.rs.
// A trimmed patch (PATCH_TRIMMED) has its trim header's entry in `primvars` in flags bits 8..31:
// entry h = (u0, u1 - u0, v0, v1 - v0), the map from the patch's (u, v) to the surface's
// parameter space; entry h + 1 = (first edge entry, edge count, 1 to keep the outside, 0) as
// u32 bits; each edge entry (ax, ay, bx, by), the loops closed. Bound classifies an item's
// rectangle (trim_classify): wholly cut away, culled; wholly kept, marked TRIM_INSIDE in its
// depth so that neither its pieces nor DiceShade test again; else DiceShade drops each
// micropolygon whose centre is cut away (trim_keeps). Read only when SCENE_TRIM.

const PATCH_TRIMMED: u32 = 32u;
const TRIM_SHIFT: u32 = 8u;
const TRIM_INSIDE: u32 = 0x10000u;
const TRIM_OUT: u32 = 0u;
const TRIM_IN: u32 = 1u;
const TRIM_CROSSING: u32 = 2u;

// The item still needs trimming tests: its patch is trimmed and Bound has not found it inside.
fn needs_trim(item: PatchItem, info: PatchInfo) -> bool {
    return SCENE_TRIM && (info.flags & PATCH_TRIMMED) != 0u && (item.depth & TRIM_INSIDE) == 0u;
}

fn trim_header(info: PatchInfo) -> u32 { return info.flags >> TRIM_SHIFT; }

fn trim_param(h: u32, u: f32, v: f32) -> vec2<f32> {
    let m = primvars[h];
    return vec2<f32>(m.x + m.y * u, m.z + m.w * v);
}

// The even-odd rule: a ray from p towards +u crosses the loops an odd number of times.
fn trim_odd(h: u32, p: vec2<f32>) -> bool {
    let e = primvars[h + 1u];
    let at = bitcast<u32>(e.x);
    let n = bitcast<u32>(e.y);
    var odd = false;
    for (var k = 0u; k < n; k++) {
        let g = primvars[at + k];
        if (g.y > p.y) != (g.w > p.y) {
            let x = g.x + (p.y - g.y) / (g.w - g.y) * (g.z - g.x);
            if p.x < x { odd = !odd; }
        }
    }
    return odd;
}

// Whether the surface is kept at (u, v) of the original patch.
fn trim_keeps(h: u32, u: f32, v: f32) -> bool {
    let outside = bitcast<u32>(primvars[h + 1u].z) != 0u;
    return trim_odd(h, trim_param(h, u, v)) != outside;
}

// The rectangle uv = (u0, u1, v0, v1) of the original patch against the loops: TRIM_CROSSING
// when an edge meets it grown by 1e-5 of its size (the edge's box, then its line against the
// corners), else TRIM_IN or TRIM_OUT by its centre.
fn trim_classify(h: u32, uv: vec4<f32>) -> u32 {
    let a = trim_param(h, uv.x, uv.z);
    let b = trim_param(h, uv.y, uv.w);
    let g = (b - a) * 1.0e-5;
    let lo = a - g;
    let hi = b + g;
    let e = primvars[h + 1u];
    let at = bitcast<u32>(e.x);
    let n = bitcast<u32>(e.y);
    for (var k = 0u; k < n; k++) {
        let s = primvars[at + k];
        let p = s.xy;
        let q = s.zw;
        if max(p.x, q.x) < lo.x || min(p.x, q.x) > hi.x || max(p.y, q.y) < lo.y
            || min(p.y, q.y) > hi.y { continue; }
        let d = q - p;
        let s0 = d.x * (lo.y - p.y) - d.y * (lo.x - p.x);
        let s1 = d.x * (lo.y - p.y) - d.y * (hi.x - p.x);
        let s2 = d.x * (hi.y - p.y) - d.y * (hi.x - p.x);
        let s3 = d.x * (hi.y - p.y) - d.y * (lo.x - p.x);
        let all_pos = s0 > 0.0 && s1 > 0.0 && s2 > 0.0 && s3 > 0.0;
        let all_neg = s0 < 0.0 && s1 < 0.0 && s2 < 0.0 && s3 < 0.0;
        if !all_pos && !all_neg { return TRIM_CROSSING; }
    }
    let outside = bitcast<u32>(e.z) != 0u;
    if trim_odd(h, (a + b) * 0.5) != outside { return TRIM_IN; }
    return TRIM_OUT;
}
