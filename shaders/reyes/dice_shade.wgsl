// DiceShade: 256 threads per grid. Each thread evaluates one grid point of the (nu+1) x (nv+1)
// grid (position, normal from the patch derivatives, shaded colour) into workgroup memory; then
// each thread samples one micropolygon (sample.wgsl). Rust twin: reyes/src/stages/dice.rs.

// Bernstein weights of degree 3 and their derivatives at t.
fn bern3(t: f32) -> vec4<f32> {
    let s = 1.0 - t;
    return vec4<f32>(s * s * s, 3.0 * t * s * s, 3.0 * t * t * s, t * t * t);
}
fn dbern3(t: f32) -> vec4<f32> {
    let s = 1.0 - t;
    return vec4<f32>(-3.0 * s * s, 3.0 * s * s - 6.0 * t * s, 6.0 * t * s - 3.0 * t * t, 3.0 * t * t);
}

// Position and the two tangents of the patch at (u, v) in its own [0,1]^2.
fn eval_patch(cp: ptr<function, array<f32, 48>>, u: f32, v: f32) -> array<vec3<f32>, 3> {
    let bu = bern3(u);
    let bv = bern3(v);
    let du = dbern3(u);
    let dv = dbern3(v);
    var p = vec3<f32>(0.0);
    var pu = vec3<f32>(0.0);
    var pv = vec3<f32>(0.0);
    for (var j = 0u; j < 4u; j++) {
        for (var i = 0u; i < 4u; i++) {
            let c = cp_point(cp, 4u * j + i);
            p += c * (bu[i] * bv[j]);
            pu += c * (du[i] * bv[j]);
            pv += c * (bu[i] * dv[j]);
        }
    }
    return array<vec3<f32>, 3>(p, pu, pv);
}

// The outside normal at (u, v). Where a tangent vanishes (a collapsed edge, e.g. the teapot
// lid's apex) the normal is taken a little inside the patch, where it is the limit normal.
fn patch_normal(cp: ptr<function, array<f32, 48>>, u: f32, v: f32, flip: bool) -> vec3<f32> {
    let e = eval_patch(cp, u, v);
    var n = cross(e[1], e[2]);
    let scale = dot(e[1], e[1]) * dot(e[2], e[2]);
    if !(dot(n, n) > 1.0e-12 * scale) {
        let inward = vec2<f32>(u, v) + (vec2<f32>(0.5) - vec2<f32>(u, v)) * 1.0e-3;
        let f = eval_patch(cp, inward.x, inward.y);
        n = cross(f[1], f[2]);
    }
    return select(n, -n, flip);
}

fn diceshade_execute(item: PatchItem, inv: Invocation) {
    var cp = item.cp;
    let nu = item.rates & 255u;
    let nv = (item.rates >> 8u) & 255u;
    let cols = nu + 1u;
    let t = inv.thread;
    let base = inv.slot * 256u;
    if inv.live && t < cols * (nv + 1u) {
        let u = f32(t % cols) / f32(nu);
        let v = f32(t / cols) / f32(nv);
        let info = patch_info[item.patch_id];
        let e = eval_patch(&cp, u, v);
        let n = patch_normal(&cp, u, v, (info.flags & 1u) != 0u);
        let c = shade(e[0], n, materials[info.material]);
        let back = dot(n, e[0]) > 0.0;
        let z = max(e[0].z, frame.near);
        let s = project(vec3<f32>(e[0].xy, z));
        diceshade_shared[base + t] = vec4<f32>(s, z, bitcast<f32>(pack_color(c, back)));
    }
    workgroupBarrier();
    if !inv.live { return; }
    if t == 0u { atomicAdd(&counters[C_MICROPOLYGONS], nu * nv); }
    if t < nu * nv {
        let i = t % nu;
        let j = t / nu;
        let two_sided = (patch_info[item.patch_id].flags & 2u) != 0u;
        sample_micropolygon(
            diceshade_shared[base + j * cols + i],
            diceshade_shared[base + j * cols + i + 1u],
            diceshade_shared[base + (j + 1u) * cols + i + 1u],
            diceshade_shared[base + (j + 1u) * cols + i],
            item.dilate, two_sided);
    }
}
