// DiceShade: 256 threads per grid. Each thread evaluates one grid point of the (nu+1) x (nv+1)
// grid (position, normal from the patch derivatives, shaded colour) into workgroup memory; then
// each thread samples one micropolygon (sample.wgsl). Rust twin: reyes/src/stages/dice_shade.rs.

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
    return Cover(alpha, reyes_hash(item.patch_id ^ COVER_SALT));
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
        let rational = SCENE_RATIONAL && (info.flags & PATCH_RATIONAL) != 0u;
        // A rational item's weights: the blossoms of its patch's (common.wgsl), once per
        // thread; its polynomial numerator is its own xyz net (see docs/reyes.md).
        var w: array<f32, 16>;
        if rational { w = rational_weights(info.weights, item.uv); }
        let e = eval_surface(&cp, &w, rational, u, v);
        let n = patch_normal(&cp, &w, rational, e, u, v, (info.flags & 1u) != 0u);
        let m = materials[info.material];
        var cs = m.color;
        if SCENE_PRIMVARS && info.cs != 0u {
            let q = original_uv(item, u, v);
            cs = color_field(info.cs, q.x, q.y);
        }
        let c = shade(e[0], n, m, cs);
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
        let info = patch_info[item.patch_id];
        let two_sided = (info.flags & 2u) != 0u;
        let cover = micropolygon_cover(item, info, i, j, nu, nv);
        let a = diceshade_shared[base + j * cols + i];
        let b = diceshade_shared[base + j * cols + i + 1u];
        let c = diceshade_shared[base + (j + 1u) * cols + i + 1u];
        let d = diceshade_shared[base + (j + 1u) * cols + i];
        let grow = micropolygon_dilation(item.dilate, i, j, nu, nv);
        if (item.rates & NEAR_CLIP_GRID) != 0u {
            sample_near_clipped(a, b, c, d, grow, two_sided, cover);
        } else {
            sample_micropolygon(a, b, c, d, grow, two_sided, cover);
        }
    }
}
