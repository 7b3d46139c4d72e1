// SplitU / SplitV: de Casteljau halves at the parameter midpoint, then back to Bound.
// Thread 0 builds the first half and thread 1 the second, each from the parent in registers;
// exchanging rows through workgroup memory would cost 24 KiB per workgroup in the megakernel
// (64 items per step), lowering occupancy for every stage. Rust twin: reyes/src/stages/split.rs.
//
// A rational item's cp are its homogeneous x w, y w, z w, which split linearly like the points
// of a polynomial patch: the same code is exact subdivision of both. Its weights need no
// splitting: they follow from the child's uv (rational_weights in common.wgsl).

// Half `second` of the cubic through p0..p3 at t = 1/2. Every operation is (a + b) * 0.5, which
// is symmetric, so a curve shared by two patches (in either direction) splits to the same bits.
fn half_curve(p0: vec3<f32>, p1: vec3<f32>, p2: vec3<f32>, p3: vec3<f32>, second: bool) -> array<vec3<f32>, 4> {
    let a = (p0 + p1) * 0.5;
    let b = (p1 + p2) * 0.5;
    let c = (p2 + p3) * 0.5;
    let d = (a + b) * 0.5;
    let e = (b + c) * 0.5;
    let m = (d + e) * 0.5;
    if second { return array<vec3<f32>, 4>(m, e, c, p3); }
    return array<vec3<f32>, 4>(p0, a, d, m);
}

// Half of `item` along u (step 1 within rows of 4) or v (step 4 within columns). Each row (or
// column) is halved in place: it reads only its own four points, so the child's net needs no
// second array beside the parent's (H200: the Reyes megakernel's local memory 1,392 -> 1,200
// bytes; docs/scheduler.md 4).
fn split_half(item: PatchItem, along_u: bool, second: bool) -> PatchItem {
    var cp = item.cp;
    let step = select(4u, 1u, along_u);
    let across = select(1u, 4u, along_u);
    for (var r = 0u; r < 4u; r++) {
        let o = r * across;
        let h = half_curve(cp_point(&cp, o), cp_point(&cp, o + step), cp_point(&cp, o + 2u * step),
                           cp_point(&cp, o + 3u * step), second);
        for (var i = 0u; i < 4u; i++) { set_cp_point(&cp, o + i * step, h[i]); }
    }
    var child = item;
    child.cp = cp;
    if along_u {
        let m = (item.uv.x + item.uv.y) * 0.5;
        if second { child.uv.x = m; } else { child.uv.y = m; }
    } else {
        let m = (item.uv.z + item.uv.w) * 0.5;
        if second { child.uv.z = m; } else { child.uv.w = m; }
    }
    child.depth = item.depth + 1u;
    return child;
}

fn splitu_execute(item: PatchItem, inv: Invocation) {
    if !inv.live || inv.thread > 1u { return; }
    enqueue_bound(split_half(item, true, inv.thread == 1u));
}

fn splitv_execute(item: PatchItem, inv: Invocation) {
    if !inv.live || inv.thread > 1u { return; }
    enqueue_bound(split_half(item, false, inv.thread == 1u));
}
