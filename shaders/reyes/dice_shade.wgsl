// DiceShade: 256 threads per grid. Each thread evaluates one grid point of the (nu+1) x (nv+1)
// grid (position, normal from the patch derivatives, shaded colour) into workgroup memory; then
// each thread samples one micropolygon (sample.wgsl). Rust twin: reyes/src/stages/dice_shade.rs.

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

// Squares of the largest control-net steps along u and v: 3 times the steps bound |Pu| and
// |Pv| on the patch. (Squares: no square roots per grid point.)
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

// The outside normal at (u, v). Where it is degenerate (a tangent vanishes at a collapsed
// edge, e.g. the teapot lid's apex; or the tangents are parallel, e.g. rows on one line) it is
// taken a little inside the patch, where it is close to the limit normal: steps of 1e-3, 1e-2
// and 1e-1 of the way to the centre until |Pu x Pv| is at least 1e-3 of its largest possible
// value on the patch (9 |net steps|^2); a fixed relative test on |Pu| |Pv| would accept
// tangents made of rounding noise. A patch with no tangent plane anywhere (all control points
// equal) gets the direction to the eye.
// `e` is eval_patch at (u, v), which the caller has already computed.
fn patch_normal(cp: ptr<function, array<f32, 48>>, e: array<vec3<f32>, 3>, u: f32, v: f32,
                flip: bool) -> vec3<f32> {
    var n = cross(e[1], e[2]);
    let steps2 = net_steps2(cp);
    let least2 = 8.1e-5 * steps2.x * steps2.y;
    var inward = 1.0e-3;
    for (var k = 0u; k < 3u && !(dot(n, n) > least2); k++) {
        let q = vec2<f32>(u, v) + (vec2<f32>(0.5) - vec2<f32>(u, v)) * inward;
        let f = eval_patch(cp, q.x, q.y);
        n = cross(f[1], f[2]);
        inward *= 10.0;
    }
    if !(dot(n, n) > 0.0) {
        return select(-e[0], vec3<f32>(0.0, 0.0, -1.0), !(dot(e[0], e[0]) > 0.0));
    }
    return select(n, -n, flip);
}

// Two procedures dice: DiceShade with 256 threads per grid, and DiceSmall with 64 for grids of
// at most 64 points (most grids of a finely split model), so that four small grids share a
// workgroup instead of leaving three quarters of its threads idle. Both use diceshade_shared:
// a workgroup step runs one procedure, and 4 x 64 = 256 points fit either way.
fn diceshade_execute(item: PatchItem, inv: Invocation) { dice_grid(item, inv, 256u); }
fn dicesmall_execute(item: PatchItem, inv: Invocation) { dice_grid(item, inv, 64u); }

fn dice_grid(item: PatchItem, inv: Invocation, threads: u32) {
    var cp = item.cp;
    let nu = item.rates & 255u;
    let nv = (item.rates >> 8u) & 255u;
    let cols = nu + 1u;
    let t = inv.thread;
    let base = inv.slot * threads;
    if inv.live && t < cols * (nv + 1u) {
        let u = f32(t % cols) / f32(nu);
        let v = f32(t / cols) / f32(nv);
        let info = patch_info[item.patch_id];
        let e = eval_patch(&cp, u, v);
        let n = patch_normal(&cp, e, u, v, (info.flags & 1u) != 0u);
        let c = shade(e[0], n, materials[info.material]);
        let back = dot(n, e[0]) > 0.0;
        let color = bitcast<f32>(pack_color(c, back));
        if (item.rates & NEAR_CLIP_GRID) != 0u {
            // Crosses the near plane: camera space, projected after clipping (sample.wgsl).
            diceshade_shared[base + t] = vec4<f32>(e[0], color);
        } else {
            let z = max(e[0].z, frame.near);
            diceshade_shared[base + t] = vec4<f32>(project(vec3<f32>(e[0].xy, z)), z, color);
        }
    }
    workgroupBarrier();
    if !inv.live { return; }
    if t == 0u { atomicAdd(&counters[C_MICROPOLYGONS], nu * nv); }
    if t < nu * nv {
        let i = t % nu;
        let j = t / nu;
        let two_sided = (patch_info[item.patch_id].flags & 2u) != 0u;
        let a = diceshade_shared[base + j * cols + i];
        let b = diceshade_shared[base + j * cols + i + 1u];
        let c = diceshade_shared[base + (j + 1u) * cols + i + 1u];
        let d = diceshade_shared[base + (j + 1u) * cols + i];
        let grow = micropolygon_dilation(item.dilate, i, j, nu, nv);
        if (item.rates & NEAR_CLIP_GRID) != 0u {
            sample_near_clipped(a, b, c, d, grow, two_sided);
        } else {
            sample_micropolygon(a, b, c, d, grow, two_sided);
        }
    }
}
