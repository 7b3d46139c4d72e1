// DiceShade: 256 threads per grid. Each thread evaluates one grid point of the (nu+1) x (nv+1)
// grid (position, normal from the patch derivatives, shaded colour) into workgroup memory; then
// each thread samples one micropolygon (sample.wgsl). Rust twin: reyes/src/stages/dice_shade.rs.
// With motion blur or depth of field (SCENE_UVT) workgroup memory holds each point at shutter
// open and, UVT_CLOSE further on, at shutter close: the patch's motion applied to the
// camera-space point (after displacement), shaded once, at shutter open.
// A displaced patch's points move along their normal before they are shaded (docs/reyes.md,
// "Displacement"; only when SCENE_DISPLACEMENT).

// The surface functions (eval_surface, patch_normal, color_field, original_uv) are in
// surface.wgsl.

// The fraction of samples micropolygon (i, j) covers: the mean of Os at its centre.
fn micropolygon_cover(item: PatchItem, info: PatchInfo, i: u32, j: u32, nu: u32, nv: u32) -> Cover {
    var alpha = materials[info.material].opacity;
    if SCENE_PRIMVARS && info.os != 0u {
        let q = original_uv(item, (f32(i) + 0.5) / f32(nu), (f32(j) + 0.5) / f32(nv));
        let o = color_field(info.os, q.x, q.y);
        alpha = (o.x + o.y + o.z) / 3.0;
    }
    // Trimmed (trim.wgsl): a micropolygon whose centre is cut away covers nothing.
    if needs_trim(item, info) {
        let q = original_uv(item, (f32(i) + 0.5) / f32(nu), (f32(j) + 0.5) / f32(nv));
        if !trim_keeps(trim_header(info), q.x, q.y) { alpha = 0.0; }
    }
    return Cover(alpha, reyes_hash(item.patch_id ^ COVER_SALT));
}

// Two procedures dice: DiceShade with 256 threads per grid, and DiceSmall with 64 for grids of
// at most 64 points (most grids of a finely split model), so that four small grids share a
// workgroup instead of leaving three quarters of its threads idle. Both use diceshade_shared:
// a workgroup step runs one procedure, and 4 x 64 = 256 points fit either way. DiceSmall runs
// this function too (Procedure::execute_of), told apart by inv.threads: the megakernel then
// holds one copy of the dicing code, where a compiler that inlines every call (lavapipe) would
// compile two (docs/scheduler.md, "Start-up on lavapipe").
fn diceshade_execute(item: PatchItem, inv: Invocation) { dice_grid(item, inv, inv.threads); }

fn dice_grid(item: PatchItem, inv: Invocation, threads: u32) {
    var cp = item.cp;
    let nu = item.rates & 255u;
    let nv = (item.rates >> 8u) & 255u;
    let cols = nu + 1u;
    let t = inv.thread;
    let base = inv.slot * threads;
    let point = inv.live && t < cols * (nv + 1u);
    let u = f32(t % cols) / f32(nu);
    let v = f32(t / cols) / f32(nv);
    var e: array<vec3<f32>, 3>;
    var n = vec3<f32>(0.0);
    var displaced = false;
    if point {
        let info = patch_info[item.patch_id];
        let rational = SCENE_RATIONAL && (info.flags & PATCH_RATIONAL) != 0u;
        // A rational item's weights: the blossoms of its patch's (common.wgsl), once per
        // thread; its polynomial numerator is its own xyz net (see docs/reyes.md).
        var w: array<f32, 16>;
        if rational { w = rational_weights(info.weights, item.uv); }
        e = eval_surface(&cp, &w, rational, u, v);
        n = patch_normal(&cp, &w, rational, e, u, v, (info.flags & 1u) != 0u);
        displaced = SCENE_DISPLACEMENT && (info.flags & PATCH_DISPLACED) != 0u;
        if !displaced { shade_point(item, info, base + t, e[0], n, u, v); }
    }
    if SCENE_DISPLACEMENT {
        // Displaced grids (all threads of the workgroup pass the barriers; only the slots of
        // displaced items change). Exact normals: each point moves by d along the patch's
        // normal n (from its derivatives, Sattler et al.'s eq. 1) and shades with the normal of
        // the displaced surface, (Pu + du n^) x (Pv + dv n^) = n + dv Pu x n^ + du n^ x Pv
        // (du, dv: central differences of d over the original patch's (u, v), scaled to the
        // item's; the curvature term d dn^/du is left out). With d = 0 that is n itself.
        // Approximate normals: each point moves along the normal of the undisplaced grid's
        // finite differences and shades with that of the displaced grid (the paper's
        // approximation, which opens holes between grids of different rates).
        let flip = (patch_info[item.patch_id].flags & 1u) != 0u;
        let approx = frame.displacement_normals == DISPLACE_APPROX_NORMALS;
        if displaced { diceshade_shared[base + t] = vec4<f32>(e[0], 0.0); }
        workgroupBarrier();
        var p = e[0];
        var ns = n;
        var dir = n;
        if displaced {
            let at = patch_info[item.patch_id].displacement;
            let amount = primvars[at].x;
            let q = original_uv(item, u, v);
            dir = normalize(n);
            if approx {
                dir = grid_normal(base, t % cols, t / cols, nu, nv, dir, flip);
            } else {
                let span = vec2<f32>(item.uv.y - item.uv.x, item.uv.w - item.uv.z);
                let dq = displacement_slope(at, q) * amount * span;
                let s = select(1.0, -1.0, flip);
                ns = n + s * (dq.y * cross(e[1], dir) + dq.x * cross(dir, e[2]));
            }
            p = e[0] + dir * (amount * displacement_pattern(at, q));
        }
        workgroupBarrier();
        if displaced { diceshade_shared[base + t] = vec4<f32>(p, 0.0); }
        workgroupBarrier();
        if displaced && approx { ns = grid_normal(base, t % cols, t / cols, nu, nv, dir, flip); }
        workgroupBarrier();
        if displaced { shade_point(item, patch_info[item.patch_id], base + t, p, ns, u, v); }
    }
    workgroupBarrier();
    if !inv.live { return; }
    if t == 0u { atomicAdd(&counters[C_MICROPOLYGONS], nu * nv); }
    if t < nu * nv {
        let i = t % nu;
        let j = t / nu;
        let info = patch_info[item.patch_id];
        let two_sided = (info.flags & 2u) != 0u;
        let cover = micropolygon_cover(item, info, i, j, nu, nv);
        let a = diceshade_shared[base + j * cols + i];
        let b = diceshade_shared[base + j * cols + i + 1u];
        let c = diceshade_shared[base + (j + 1u) * cols + i + 1u];
        let d = diceshade_shared[base + (j + 1u) * cols + i];
        let grow = micropolygon_dilation(item.dilate, i, j, nu, nv);
        if SCENE_UVT && frame.uvt != UVT_OFF && (item.rates & NEAR_CLIP_GRID) == 0u {
            // Motion blur or depth of field (sample_uvt.wgsl): the corners at shutter close too.
            let at = base + UVT_CLOSE;
            sample_micropolygon_uvt(a, b, c, d, diceshade_shared[at + j * cols + i],
                diceshade_shared[at + j * cols + i + 1u],
                diceshade_shared[at + (j + 1u) * cols + i + 1u],
                diceshade_shared[at + (j + 1u) * cols + i], grow, two_sided, cover);
        } else if (item.rates & NEAR_CLIP_GRID) != 0u {
            sample_near_clipped(a, b, c, d, grow, two_sided, cover);
        } else {
            sample_micropolygon(a, b, c, d, grow, two_sided, cover);
        }
    }
}

// Shades grid point (u, v) of `item` at camera-space position p with normal n and stores it in
// workgroup memory at `at`: projected, or in camera space for a grid crossing the near plane.
fn shade_point(item: PatchItem, info: PatchInfo, at: u32, p: vec3<f32>, n: vec3<f32>, u: f32,
               v: f32) {
    let m = materials[info.material];
    var cs = m.color;
    if SCENE_PRIMVARS && info.cs != 0u {
        let q = original_uv(item, u, v);
        cs = color_field(info.cs, q.x, q.y);
    }
    // A patch's "N" shades in place of its own normal; which side faces the eye stays the
    // surface's (Sides 1).
    var ns = n;
    if SCENE_PRIMVARS && info.normal != 0u && (info.flags & PATCH_DISPLACED) == 0u {
        let q = original_uv(item, u, v);
        ns = color_field(info.normal, q.x, q.y);
    }
    let c = shade(p, ns, m, cs);
    let back = dot(n, p) > 0.0;
    let color = bitcast<f32>(pack_color(c, back));
    if (item.rates & NEAR_CLIP_GRID) != 0u {
        // Crosses the near plane: camera space, projected after clipping (sample.wgsl).
        diceshade_shared[at] = vec4<f32>(p, color);
    } else {
        let z = max(p.z, frame.near);
        diceshade_shared[at] = vec4<f32>(project(vec3<f32>(p.xy, z)), z, color);
        if SCENE_UVT && frame.uvt != UVT_OFF {
            // The point at shutter close (sample_uvt.wgsl), after the open points.
            var p1 = p;
            if (info.flags & PATCH_MOVING) != 0u { p1 = moved_point(info.motion, p); }
            let z1 = max(p1.z, frame.near);
            diceshade_shared[UVT_CLOSE + at] = vec4<f32>(project(vec3<f32>(p1.xy, z1)), z1, 0.0);
        }
    }
}

// The outside normal of grid point (i, j) of the nu x nv grid in workgroup memory from `base`
// (camera-space points in xyz): the cross product of its central differences along u and v,
// one-sided on the grid's border; `fallback` where that is degenerate (|du x dv|^2 at most
// 1e-6 (|du|^2 + |dv|^2)^2: a collapsed row, e.g. a sphere's pole, whose differences are
// rounding noise).
fn grid_normal(base: u32, i: u32, j: u32, nu: u32, nv: u32, fallback: vec3<f32>, flip: bool)
    -> vec3<f32> {
    let cols = nu + 1u;
    let il = select(i - 1u, 0u, i == 0u);
    let jl = select(j - 1u, 0u, j == 0u);
    let du = diceshade_shared[base + j * cols + min(i + 1u, nu)].xyz
        - diceshade_shared[base + j * cols + il].xyz;
    let dv = diceshade_shared[base + min(j + 1u, nv) * cols + i].xyz
        - diceshade_shared[base + jl * cols + i].xyz;
    let g = cross(du, dv);
    let scale = dot(du, du) + dot(dv, dv);
    if !(dot(g, g) > 1.0e-6 * scale * scale) { return fallback; }
    return normalize(select(g, -g, flip));
}
