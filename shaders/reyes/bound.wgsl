// Bound: 16 threads per patch, one per control point. Projects the control points, reduces them
// to a screen bound, culls, and decides: split in u, split in v, or dice (with its rates).
// Rust twin: reyes/src/stages/bound.rs.
//
// A rational patch (positive weights) lies in the convex hull of its Euclidean control points
// xyz / w, as a polynomial one does in that of its points; every bound below uses those, so
// screen bounds, culling and the near plane mean the same for both. The weights come from the
// patch's table (rational_weights in common.wgsl): each of the 16 threads blossoms its own,
// thread 0 all 16 for its reduction. The back-face test runs on the homogeneous xyz and the
// crack bound has a rational form (their comments say why).

// Workgroup memory per item (32 vec4): from `base`, the 16 control points as (x, y) in pixels,
// z in camera space, w = 1 (in front of the near plane) + 2 (this thread's back-face terms all
// hold); from `base + 16`, the item's 16 control points as they came (homogeneous for a rational
// patch) with their weights (1 for a polynomial patch). Thread 0's decision reads the net there
// (`net_point`, `net_weight`) and its children take it back from there (`bound_child`), so that
// no thread holds the item's 48 control-point words past the barrier: Bound's register count
// is the megakernel's floor (docs/scheduler.md 4).
fn bound_execute(item_in: PatchItem, inv: Invocation) {
    // `var`: trimming may mark the item TRIM_INSIDE before it is split or diced.
    var item = item_in;
    var cp = item.cp;
    let t = inv.thread;
    let info = patch_info[item.patch_id];
    let rational = SCENE_RATIONAL && (info.flags & PATCH_RATIONAL) != 0u;
    // This thread's Euclidean control point (a polynomial patch's cp are the points: no weight,
    // no division).
    let h = cp_point(&cp, t);
    var wt = 1.0;
    if rational { wt = rational_weight(info.weights, item.uv, t % 4u, t / 4u); }
    var p = h;
    if rational { p = h / wt; }
    let front = p.z >= frame.near;
    var s = vec2<f32>(0.0);
    if front { s = project(p); }
    let one_sided = (info.flags & 2u) == 0u;
    var back = false;
    if one_sided { back = backfacing_terms(&cp, t, (info.flags & 1u) != 0u); }
    let base = inv.slot * 32u;
    bound_shared[base + t] = vec4<f32>(s, p.z, select(0.0, 1.0, front) + select(0.0, 2.0, back));
    bound_shared[base + 16u + t] = vec4<f32>(h, wt);
    workgroupBarrier();
    if !inv.live || t != 0u { return; }
    // Pipelined frames that cull from the previous frame (roots tagged by make_roots in
    // roots.wgsl; docs/reyes.md, *Occlusion culling*) seed every root in both phases. Phase 1
    // (no pyramid yet) takes the roots some piece of which passed the occlusion test last frame
    // and drops the others here; phase 2 (OCCLUSION_TEST) takes the others, with the test, and
    // only tests phase 1's roots again, at the root (`retest`), which draws and counts nothing.
    // The next frame's phase 1 takes the roots of which some piece was diced in phase 2 and
    // those of phase 1 that passed the test again (`visible`, mark_visible). Any split of the
    // roots between the phases gives the same image.
    let history = (item.rates & ROOT_HISTORY) != 0u;
    let root = (item.depth & 255u) == 0u;
    let was_visible = (item.rates & ROOT_WAS_VISIBLE) != 0u;
    let testing = frame.occlusion == OCCLUSION_TEST;
    if history && root && !testing && !was_visible { return; }
    let retest = history && root && testing && was_visible;
    var zmin = bound_point(base, 0u).z;
    var zmax = zmin;
    for (var k = 1u; k < 16u; k++) {
        let z = bound_point(base, k).z;
        zmin = min(zmin, z);
        zmax = max(zmax, z);
    }
    // A displaced patch: each point moves at most r (camera space; "displacementbound"), so
    // its bound is the control points' hull grown by a ball of radius r: depths by r, and the
    // screen bound below by the most any control point's ball can reach on screen.
    var r = 0.0;
    if SCENE_DISPLACEMENT && (info.flags & PATCH_DISPLACED) != 0u {
        r = primvars[info.displacement].y;
        zmin -= r;
        zmax += r;
    }
    // Motion blur or depth of field: culling uses the bound over the shutter and the lens
    // (uvt_bound); splitting and dicing the patch at shutter open.
    var moving = false;
    var ub = array<vec2<f32>, 2>(vec2<f32>(0.0), vec2<f32>(0.0));
    var uz = vec2<f32>(zmin, zmax);
    var ucoc = 0.0;
    if SCENE_UVT && frame.uvt != UVT_OFF {
        moving = (info.flags & PATCH_MOVING) != 0u;
        let u = uvt_bound(base, rational, info, r, zmin, zmax);
        ub = array<vec2<f32>, 2>(u[0].xy, u[0].zw);
        uz = u[1].xy;
        ucoc = u[1].z;
    }
    if uz.y < frame.near || uz.x > frame.far {
        count_cull(C_CULL_CLIP, retest);
        return;
    }
    // (A displaced surface may face the eye where its patch does not; a moving one may turn.)
    var all_back = one_sided && r == 0.0 && !moving;
    for (var k = 0u; k < 16u; k++) { all_back = all_back && bound_point(base, k).w >= 2.0; }
    if all_back {
        count_cull(C_CULL_BACKFACE, retest);
        return;
    }
    // Trimmed (trim.wgsl): a piece wholly cut away is dropped; one wholly kept is marked so
    // that nothing below it tests again.
    if needs_trim(item, info) {
        let c = trim_classify(trim_header(info), item.uv);
        if c == TRIM_OUT {
            count_cull(C_CULL_TRIMMED, retest);
            return;
        }
        if c == TRIM_IN { item.depth |= TRIM_INSIDE; }
    }
    let depth = item.depth & 255u;
    let eye = (item.depth >> 8u) & 255u;
    let t0 = vec2<f32>(f32(frame.tile_x0), f32(frame.tile_y0)) - CULL_MARGIN_PX;
    let t1 = vec2<f32>(f32(frame.tile_x0 + frame.tile_w), f32(frame.tile_y0 + frame.tile_h))
        + CULL_MARGIN_PX;
    if zmin < frame.near {
        // Crossing the near plane: only the part in front can be seen, and its screen bound
        // decides whether anything of it reaches the bucket.
        let undisplaced = near_visible_bound(base, rational);
        var vis = undisplaced;
        // Displaced: a ball reaching the near plane reaches the whole image (and so may a
        // patch that moves or is blurred by the lens).
        if r > 0.0 || (SCENE_UVT && frame.uvt != UVT_OFF) {
            vis = array<vec2<f32>, 2>(vec2<f32>(-3.0e38), vec2<f32>(3.0e38));
        }
        if any(vis[1] < t0) || any(vis[0] > t1) {
            count_cull(C_CULL_OFFSCREEN, retest);
            return;
        }
        // Never culled by occlusion: seen, for the next frame.
        if retest {
            mark_visible(item.patch_id);
            return;
        }
        // Split while what can be seen of it spans more of the image than one finest grid
        // should: its micropolygons then stay small where they are seen. (The image, not the
        // bucket: decisions that do not depend on the bucket keep bucketed images exact.)
        // A displaced piece splits by what its undisplaced surface shows: its grown bound
        // keeps the radius r however small the piece, so it would reach the whole image at
        // every split, and a patch whose balls all reach the eye (z = 5, "Km" 6) would split
        // into 2^max_eye_splits pieces. Its grids are clipped at the near plane instead.
        var split_vis = vis;
        if r > 0.0 { split_vis = undisplaced; }
        let seen = min(split_vis[1], vec2<f32>(f32(frame.width), f32(frame.height))
            + CULL_MARGIN_PX) - max(split_vis[0], vec2<f32>(-CULL_MARGIN_PX));
        let grid_px = select(f32(frame.grid_max) * frame.mp_size, frame.bound_px,
            frame.bound_px > 0.0);
        if max(seen.x, seen.y) > grid_px && eye < frame.max_eye_splits && depth < frame.max_depth {
            var e = bound_child(item, base);
            e.depth = item.depth + 256u;
            atomicAdd(&counters[C_EYE_SPLITS], 1u);
            if polygon_length(base, rational, 1u, 4u)
                >= polygon_length(base, rational, 4u, 1u) {
                enqueue_splitu(e);
            } else {
                enqueue_splitv(e);
            }
            return;
        }
        // Dice at the finest grid and clip each micropolygon against the near plane in camera
        // space (sample.wgsl), as rasterizers clip triangles.
        atomicAdd(&counters[C_NEAR_CLIPPED], 1u);
        atomicMax(&counters[C_MAX_DEPTH], depth);
        if history && testing { mark_visible(item.patch_id); }
        var g = bound_child(item, base);
        g.rates = frame.grid_max | (frame.grid_max << 8u) | NEAR_CLIP_GRID;
        // The dilation bound at the nearest front control point, not at the near plane (where
        // it would always be the cap): what lies nearer is a sliver whose chord error is
        // seen only in a few pixels at the view axis (docs/reyes.md, near plane).
        var zfront = zmax;
        for (var k = 0u; k < 16u; k++) {
            let z = bound_point(base, k).z;
            if z >= frame.near { zfront = min(zfront, z); }
        }
        g.dilate = select(0u, crack_dilation(base, rational, frame.grid_max, frame.grid_max,
            zfront),
            frame.crack_dilation != 0u);
        if (frame.grid_max + 1u) * (frame.grid_max + 1u) <= SMALL_GRID_POINTS {
            enqueue_dicesmall(g);
        } else {
            enqueue_diceshade(g);
        }
        return;
    }
    var lo = bound_point(base, 0u).xy;
    var hi = lo;
    for (var k = 1u; k < 16u; k++) {
        let xy = bound_point(base, k).xy;
        lo = min(lo, xy);
        hi = max(hi, xy);
    }
    // The extent a split decides by (bound_px): the undisplaced one, which halves as the
    // piece splits; the growth below does not (it would split to max_depth).
    let extent = hi - lo;
    if r > 0.0 {
        // Every control point q has q.z >= zmin + r > r here. A point q + d, |d| <= r, projects
        // within focal r |q| / (q.z (q.z - r)) of q's projection along x and along y:
        // |(x + dx)/(z + dz) - x/z| = |dx z - x dz| / (z (z + dz)) <= r |(x, z)| / (z (z - r)).
        // Perspective maps the hull of the balls onto the hull of their images.
        var g = 0.0;
        for (var k = 0u; k < 16u; k++) {
            let q = net_point(base, k, rational);
            g = max(g, length(q) / (q.z * (q.z - r)));
        }
        lo -= vec2<f32>(frame.focal * r * g);
        hi += vec2<f32>(frame.focal * r * g);
    }
    var clo = lo;
    var chi = hi;
    if SCENE_UVT && frame.uvt != UVT_OFF {
        clo = min(lo - vec2<f32>(ucoc), ub[0]);
        chi = max(hi + vec2<f32>(ucoc), ub[1]);
    }
    if any(chi < t0) || any(clo > t1) {
        count_cull(C_CULL_OFFSCREEN, retest);
        return;
    }
    // Occlusion: hidden behind what the bucket's samples already hold (hiz_occluded), by the
    // bound over the shutter and the lens (the screen bound and depths the culls above use).
    if testing && hiz_occluded(clo, chi, hiz_depth(uz.x, uz.y)) {
        count_cull(C_CULL_OCCLUDED, retest);
        return;
    }
    if retest {
        mark_visible(item.patch_id);
        return;
    }
    // Screen lengths of the control polygon along u and v bound the curves' lengths. (Chords
    // through a 4x4 grid of surface points made 1.5% fewer micropolygons on Killeroo but cost
    // more than that in Bound on the H100.)
    var lu = 0.0;
    var lv = 0.0;
    for (var r = 0u; r < 4u; r++) {
        var su = 0.0;
        var sv = 0.0;
        for (var i = 0u; i < 3u; i++) {
            su += distance(bound_point(base, 4u * r + i).xy,
                           bound_point(base, 4u * r + i + 1u).xy);
            sv += distance(bound_point(base, 4u * i + r).xy,
                           bound_point(base, 4u * (i + 1u) + r).xy);
        }
        lu = max(lu, su);
        lv = max(lv, sv);
    }
    let d = dice_decision(lu, lv, extent);
    if d.x != 0u && depth < frame.max_depth {
        if d.x == 1u {
            enqueue_splitu(bound_child(item, base));
        } else {
            enqueue_splitv(bound_child(item, base));
        }
        return;
    }
    if d.x != 0u { atomicAdd(&counters[C_DEPTH_LIMIT], 1u); }
    atomicMax(&counters[C_MAX_DEPTH], depth);
    // Diced after passing the occlusion test: visible, for the next frame's phase 1.
    if history && testing { mark_visible(item.patch_id); }
    var g = bound_child(item, base);
    g.rates = d.y | (d.z << 8u);
    if frame.crack_dilation != 0u {
        g.dilate = crack_dilation(base, rational, d.y, d.z, zmin);
        // Undisplaced and seen through the pinhole at one time: the tighter bound on screen.
        if r == 0.0 && !(SCENE_UVT && frame.uvt != UVT_OFF) {
            g.dilate = packed_min(g.dilate, screen_crack_dilation(base, rational, d.y, d.z));
        }
    } else {
        g.dilate = 0u;
    }
    if (d.y + 1u) * (d.z + 1u) <= SMALL_GRID_POINTS {
        enqueue_dicesmall(g);
    } else {
        enqueue_diceshade(g);
    }
}

// Control point k of the patch whose 16 points Bound's threads stored from `base`: (x, y) in
// pixels, camera depth, flags (bound_execute's first comment). Thread 0 reads them where it
// needs them instead of copying all 16 into a private array, which stayed live through the
// whole decision (H200: a megakernel with Bound alone 196 -> 128 registers, the host-driven
// Bound kernel 180 -> 128; docs/scheduler.md 4).
fn bound_point(base: u32, k: u32) -> vec4<f32> {
    return bound_shared[base + k];
}

// Euclidean control point k of the item at `base` (bound_execute's first comment): a rational
// patch's homogeneous point divided by its weight.
fn net_point(base: u32, k: u32, rational: bool) -> vec3<f32> {
    let h = bound_shared[base + 16u + k];
    if rational { return h.xyz / h.w; }
    return h.xyz;
}

// The weight of control point k of the item at `base` (1 for a polynomial patch).
fn net_weight(base: u32, k: u32) -> f32 {
    return bound_shared[base + 16u + k].w;
}

// `item` with its control points taken back from workgroup memory (the same words it came
// with), for the child Bound enqueues.
fn bound_child(item: PatchItem, base: u32) -> PatchItem {
    var cp: array<f32, 48>;
    for (var k = 0u; k < 16u; k++) { set_cp_point(&cp, k, bound_shared[base + 16u + k].xyz); }
    var c = item;
    c.cp = cp;
    return c;
}

// A piece culled in Bound, counted unless it is a root only tested again (bound_execute's
// `retest`: phase 1 of its frame drew it and counted its culls).
fn count_cull(counter: u32, retest: bool) {
    if !retest { atomicAdd(&counters[counter], 1u); }
}

// Root patch `id` is visible: a piece of it passed the occlusion test and is diced, or it
// passed the test again as a root of phase 1; it is drawn in phase 1 of the next pipelined
// frame (`visible` in common.wgsl; cleared by make_roots).
fn mark_visible(id: u32) {
    if atomicLoad(&visible[id]) == 0u { atomicStore(&visible[id], 1u); }
}

// Motion blur and depth of field: the screen bound (lo.xy, hi.xy in [0]) and depth range ([1].xy)
// of the patch over the shutter and the lens. The patch at shutter close is the hull of its
// control points under the motion (an affine map keeps the hull), a displaced one grown by r
// times the map's Frobenius norm (at least its largest stretch); a point moves linearly
// between its two positions, the bound holds both. The screen bound then grows by the largest
// circle of confusion over the depth range (|coc| is monotonic in depth on either side of the
// focal plane). A shutter-close point behind the near plane: the whole image.
// The item's net at `base` (net_point); (zmin, zmax): the depths at shutter open, displacement
// included.
fn uvt_bound(base: u32, rational: bool, info: PatchInfo, r: f32, zmin: f32, zmax: f32)
    -> array<vec4<f32>, 2> {
    var lo = vec2<f32>(3.0e38);
    var hi = vec2<f32>(-3.0e38);
    var z = vec2<f32>(zmin, zmax);
    if (info.flags & PATCH_MOVING) != 0u {
        let m0 = primvars[info.motion].xyz;
        let m1 = primvars[info.motion + 1u].xyz;
        let m2 = primvars[info.motion + 2u].xyz;
        let r1 = r * sqrt(dot(m0, m0) + dot(m1, m1) + dot(m2, m2));
        var g = 0.0;
        var near = false;
        for (var k = 0u; k < 16u; k++) {
            let q = moved_point(info.motion, net_point(base, k, rational));
            z = vec2<f32>(min(z.x, q.z - r1), max(z.y, q.z + r1));
            if q.z - r1 < frame.near { near = true; continue; }
            let s = project(q);
            lo = min(lo, s);
            hi = max(hi, s);
            if r1 > 0.0 { g = max(g, length(q) / (q.z * (q.z - r1))); }
        }
        lo -= vec2<f32>(frame.focal * r1 * g);
        hi += vec2<f32>(frame.focal * r1 * g);
        if near { lo = vec2<f32>(-3.0e38); hi = vec2<f32>(3.0e38); }
    }
    // Depths below the near plane are never sampled (DiceShade clamps them to it).
    let zn = max(z.x, frame.near);
    let c = max(abs(coc(zn)), abs(coc(max(z.y, zn))));
    // bound_execute grows the shutter-open bound by c too and takes the union.
    return array<vec4<f32>, 2>(vec4<f32>(lo - vec2<f32>(c), hi + vec2<f32>(c)),
        vec4<f32>(z, c, 0.0));
}

// Screen bound (lo, hi) of the part of the patch in front of the near plane. The patch lies in
// the convex hull of its control points; the part of that hull with z >= near is the hull of
// the front control points and of the points where segments from a front to a behind control
// point cross the plane; and perspective projection maps a convex set in front of the eye onto
// the convex hull of its vertices' projections. Coordinates may be huge (a point at the near
// plane far off the view axis), never NaN: near > 0.
fn near_visible_bound(base: u32, rational: bool) -> array<vec2<f32>, 2> {
    var lo = vec2<f32>(3.0e38);
    var hi = vec2<f32>(-3.0e38);
    for (var a = 0u; a < 16u; a++) {
        let p = net_point(base, a, rational);
        if p.z < frame.near { continue; }
        let s = project(p);
        lo = min(lo, s);
        hi = max(hi, s);
        for (var b = 0u; b < 16u; b++) {
            let q = net_point(base, b, rational);
            if q.z >= frame.near { continue; }
            let x = p + (q - p) * ((p.z - frame.near) / (p.z - q.z));
            let c = project(vec3<f32>(x.xy, frame.near));
            lo = min(lo, c);
            hi = max(hi, c);
        }
    }
    return array<vec2<f32>, 2>(lo, hi);
}

// Sum of |P[i+1] - P[i]| over a row (step along u = 1) or column (step = 4), in camera space,
// maximised over the 4 rows/columns (`across` = 4 or 1).
fn polygon_length(base: u32, rational: bool, step: u32, across: u32) -> f32 {
    var best = 0.0;
    for (var r = 0u; r < 4u; r++) {
        var s = 0.0;
        for (var i = 0u; i < 3u; i++) {
            s += distance(net_point(base, r * across + i * step, rational),
                          net_point(base, r * across + (i + 1u) * step, rational));
        }
        best = max(best, s);
    }
    return best;
}

// x: 0 dice, 1 split u, 2 split v; y, z: dice rates in u and v.
fn dice_decision(lu: f32, lv: f32, extent: vec2<f32>) -> vec3<u32> {
    let gmax = f32(frame.grid_max);
    if frame.bound_px > 0.0 {
        // Patney & Owens: split until the screen bound fits bound_px, then a fixed grid.
        let split = max(extent.x, extent.y) > frame.bound_px;
        return vec3<u32>(select(0u, select(2u, 1u, lu >= lv), split), frame.grid_max, frame.grid_max);
    }
    let nu = ceil(lu / frame.mp_size);
    let nv = ceil(lv / frame.mp_size);
    if nu > gmax || nv > gmax {
        return vec3<u32>(select(2u, 1u, nu / gmax >= nv / gmax), frame.grid_max, frame.grid_max);
    }
    return vec3<u32>(0u, u32(max(nu, 1.0)), u32(max(nv, 1.0)));
}

// Largest gap, in pixels, between each boundary curve of this patch and the chord polyline a
// neighbour may use for it: the chord error of a segment of parameter length h is
// max|C''| h^2 / 8, with |C''| <= 6 max|second difference| of the curve's control points
// (polynomial; curve_c2_rational for a rational curve), and a camera-space distance d at
// depth >= zmin spans at most 2 d f / zmin pixels inside a 90 degree view. Sampling grows
// only the micropolygon edges on that boundary by this much (sample.wgsl), so that T-junction
// gaps between grids diced at different rates close: a gap can exist only there. Packed 8 bits
// per edge (v = 0, v = 1, u = 0, u = 1), rounded up; each at most MAX_DILATE_PX (a grid that
// coarse is far above any sane micropolygon size), at least one step (float rounding).
// The item's net and weights are at `base` (net_point, net_weight; the weights read only if
// rational).
fn crack_dilation(base: u32, rational: bool, nu: u32, nv: u32, zmin: f32) -> u32 {
    let slack = 2.0 * (1.0 + max(f32(frame.width), f32(frame.height)) / frame.focal);
    var packed = 0u;
    for (var e = 0u; e < 4u; e++) {
        let start = edge_start(e);
        let step = edge_step(e);
        let n = edge_segments(e, nu, nv);
        var c2 = 0.0;
        if rational {
            let k1 = start + step;
            let k2 = start + 2u * step;
            let k3 = start + 3u * step;
            c2 = curve_c2_rational(
                vec4<f32>(net_point(base, start, rational), net_weight(base, start)),
                vec4<f32>(net_point(base, k1, rational), net_weight(base, k1)),
                vec4<f32>(net_point(base, k2, rational), net_weight(base, k2)),
                vec4<f32>(net_point(base, k3, rational), net_weight(base, k3)));
        } else {
            let b0 = net_point(base, start, rational);
            let b1 = net_point(base, start + step, rational);
            let b2 = net_point(base, start + 2u * step, rational);
            let b3 = net_point(base, start + 3u * step, rational);
            c2 = 6.0 * max(length(b0 - 2.0 * b1 + b2), length(b1 - 2.0 * b2 + b3));
        }
        packed |= pack_edge_dilation(c2 / (8.0 * n * n) * frame.focal / zmin * slack, e);
    }
    return packed;
}

// Boundary edge e of a 4x4 control net (0: v = 0, 1: v = 1, both along u; 2: u = 0, 3: u = 1,
// along v): the index of its first control point, the stride to the next, and the grid's
// segments along it.
fn edge_start(e: u32) -> u32 {
    return select(select(0u, 3u, e == 3u), select(0u, 12u, e == 1u), e < 2u);
}

fn edge_step(e: u32) -> u32 {
    return select(4u, 1u, e < 2u);
}

fn edge_segments(e: u32, nu: u32, nv: u32) -> f32 {
    return f32(select(nv, nu, e < 2u));
}

// Edge e's dilation of `px` pixels in its 8 bits of a packed crack dilation: rounded up to
// MAX_DILATE_PX / 255 steps, at least one step, at most MAX_DILATE_PX.
fn pack_edge_dilation(px: f32, e: u32) -> u32 {
    return u32(clamp(ceil(px * (255.0 / MAX_DILATE_PX)), 1.0, 255.0)) << (8u * e);
}

// crack_dilation from the boundary curves as they are on screen: workgroup memory from `base`
// holds the control points projected (xy, pixels) with their camera depths (z), all in front
// of the eye (`bound_point`). The perspective image of a rational curve with points b_i and
// weights w_i is the rational curve with points project(b_i) and weights w_i b_i.z (a
// polynomial curve: weights b_i.z), so
// curve_c2_rational bounds |C''| in pixels, with no allowance for the view (crack_dilation's
// slack, about 3.5 at a 40 degree view): rims and seams of thin surfaces grow by their own
// chords' sagitta, |C''| / (8 n^2), and no more. Rust twin: stages::bound.
fn screen_crack_dilation(base: u32, rational: bool, nu: u32, nv: u32) -> u32 {
    var packed = 0u;
    for (var e = 0u; e < 4u; e++) {
        let start = edge_start(e);
        let step = edge_step(e);
        let n = edge_segments(e, nu, nv);
        var q: array<vec4<f32>, 4>;
        for (var k = 0u; k < 4u; k++) {
            let i = start + k * step;
            let p = bound_point(base, i);
            q[k] = vec4<f32>(p.xy, 0.0, select(1.0, net_weight(base, i), rational) * p.z);
        }
        packed |= pack_edge_dilation(curve_c2_rational(q[0], q[1], q[2], q[3]) / (8.0 * n * n), e);
    }
    return packed;
}

// The smaller of two packed crack dilations, edge by edge.
fn packed_min(a: u32, b: u32) -> u32 {
    var m = 0u;
    for (var s = 0u; s < 32u; s += 8u) {
        m |= min((a >> s) & 255u, (b >> s) & 255u) << s;
    }
    return m;
}

// An upper bound of |C''| on [0, 1] for the rational cubic C with Euclidean control points
// b_i and weights w_i > 0 (each argument is (b_i, w_i)). Fix t, let c = C(t), and let
// Y(s) = sum B_i(s) w_i (b_i - c) and w(s) = sum B_i(s) w_i, so Y = w (C - c). Differentiating
// twice and using Y(t) = 0: w C'' = Y'' - 2 w' Y' / w at t. Bernstein sums are convex
// combinations, c lies in the hull of the b_i (so |b_i - c| <= r, the net's diameter), and
//   Y'  = 3 sum B2_i [w_{i+1} (b_{i+1} - b_i) + (w_{i+1} - w_i)(b_i - c)],
//   Y'' = 6 sum B1_i [w_{i+2} (b_{i+2} - 2 b_{i+1} + b_i) + (w_{i+2} - w_i)(b_{i+1} - b_i)
//                     + (w_{i+2} - 2 w_{i+1} + w_i)(b_{i+1} - c)],
//   w'  = 3 sum B2_i (w_{i+1} - w_i),  w >= wmin;
// so with d1, d2 the largest first and second differences of the b_i and dw1, dw2, ddw those
// of the w_i (dw2 = max|w_{i+2} - w_i|):
//   |C''| <= (6 (wmax d2 + dw2 d1 + ddw r) + 18 dw1 / wmin (wmax d1 + dw1 r)) / wmin.
// With equal weights this is 6 d2, the polynomial bound. Rust twin: stages::bound.
fn curve_c2_rational(p0: vec4<f32>, p1: vec4<f32>, p2: vec4<f32>, p3: vec4<f32>) -> f32 {
    let b0 = p0.xyz;
    let b1 = p1.xyz;
    let b2 = p2.xyz;
    let b3 = p3.xyz;
    let w = vec4<f32>(p0.w, p1.w, p2.w, p3.w);
    let wmin = min(min(w.x, w.y), min(w.z, w.w));
    let wmax = max(max(w.x, w.y), max(w.z, w.w));
    let d1 = max(max(length(b1 - b0), length(b2 - b1)), length(b3 - b2));
    let d2 = max(length(b0 - 2.0 * b1 + b2), length(b1 - 2.0 * b2 + b3));
    let r = max(d1, max(max(length(b2 - b0), length(b3 - b1)), length(b3 - b0)));
    let dw1 = max(max(abs(w.y - w.x), abs(w.z - w.y)), abs(w.w - w.z));
    let dw2 = max(abs(w.z - w.x), abs(w.w - w.y));
    let ddw = max(abs(w.x - 2.0 * w.y + w.z), abs(w.y - 2.0 * w.z + w.w));
    return (6.0 * (wmax * d2 + dw2 * d1 + ddw * r) + 18.0 * dw1 / wmin * (wmax * d1 + dw1 * r))
        / wmin;
}

// Safe back-face cull. With the eye at the origin a point is back-facing when
// det[P, Pu, Pv] = P . (Pu x Pv) has the sign of a back face (dice_shade.wgsl's test). P lies in
// the hull of the 16 control points, Pu in the hull of the 12 row differences and Pv of the 12
// column differences, all with non-negative weights, and det is linear in each argument: so if
// det[b_a, dU_b, dV_c] has the back-face sign for every triple, every point of the patch is
// back-facing. Thread t checks the (dU_b, dV_c) pairs t, t + 16, ... against all 16 b_a,
// with a relative margin that keeps f32 rounding on the safe side.
// `cp` is the item's net, the homogeneous xyz of a rational patch: the test runs on the
// polynomial patch X = w P (X = P for a polynomial patch): Pu = (Xu - wu P) / w and likewise Pv, and
// det is multilinear and vanishes with X in two places, so det[P, Pu, Pv] = det[X, Xu, Xv] / w^3
// has the sign of det[X, Xu, Xv] (w > 0), to which the hull argument applies.
fn backfacing_terms(cp: ptr<function, array<f32, 48>>, t: u32, flip: bool) -> bool {
    let sgn = select(1.0, -1.0, flip);
    for (var k = t; k < 144u; k += 16u) {
        let b = k / 12u;
        let c = k % 12u;
        let ru = 4u * (b / 3u) + b % 3u;
        let du = cp_point(cp, ru + 1u) - cp_point(cp, ru);
        let dv = cp_point(cp, c + 4u) - cp_point(cp, c);
        let n = cross(du, dv);
        let nl = 1.0e-3 * length(n);
        for (var a = 0u; a < 16u; a++) {
            let p = cp_point(cp, a);
            if !(sgn * dot(p, n) > nl * length(p)) { return false; }
        }
    }
    return true;
}

// Side of a level-0 tile of the depth pyramid, pixels; tiles per side Bound reads at most.
// Rust twin: stages::hiz (HIZ_TILE_PX, HIZ_SPAN).
const HIZ_TILE_PX: u32 = 8u;
const HIZ_SPAN: u32 = 4u;
// stages::hiz::DEPTH_MARGIN: relative margin off an item's nearest depth (f32 rounding of the
// surface points DiceShade evaluates stays far below it).
const HIZ_DEPTH_MARGIN: f32 = 1.0e-4;

// The depth an item's occlusion test uses: its nearest depth less the margin.
fn hiz_depth(zmin: f32, zmax: f32) -> f32 {
    return zmin - HIZ_DEPTH_MARGIN * max(abs(zmax), abs(zmin));
}

// Whether every sub-sample of the bucket within the screen bound [lo, hi] grown by
// CULL_MARGIN_PX (every sample a micropolygon of the item can write: its corners lie in the
// bound, crack dilation reaches MAX_DILATE_PX beyond) holds a depth strictly nearer than z.
// Then each key the item could write loses to the key already there (atomicMax on the
// inverted depth bits), so culling it changes no sample. DiceShade's depths are at least z:
// grid points lie in the control points' hull (up to rounding, which HIZ_DEPTH_MARGIN covers)
// and sampling clamps interpolated depth to the micropolygon's corners (sample.wgsl).
// Climbs the pyramid until the bound spans at most HIZ_SPAN tiles each way, reads them all.
// Rust twin: stages::hiz::occluded.
fn hiz_occluded(lo: vec2<f32>, hi: vec2<f32>, z: f32) -> bool {
    let x0 = max(floor(lo.x - CULL_MARGIN_PX), f32(frame.tile_x0));
    let y0 = max(floor(lo.y - CULL_MARGIN_PX), f32(frame.tile_y0));
    let x1 = min(floor(hi.x + CULL_MARGIN_PX), f32(frame.tile_x0 + frame.tile_w - 1u));
    let y1 = min(floor(hi.y + CULL_MARGIN_PX), f32(frame.tile_y0 + frame.tile_h - 1u));
    if !(x0 <= x1 && y0 <= y1) || !(z > 0.0) { return false; }
    var t0 = (vec2<u32>(vec2<f32>(x0, y0)) - vec2<u32>(frame.tile_x0, frame.tile_y0)) / HIZ_TILE_PX;
    var t1 = (vec2<u32>(vec2<f32>(x1, y1)) - vec2<u32>(frame.tile_x0, frame.tile_y0)) / HIZ_TILE_PX;
    // Level 0's size and each level's offset (stages::hiz::levels).
    var lw = (frame.tile_w + HIZ_TILE_PX - 1u) / HIZ_TILE_PX;
    var lh = (frame.tile_h + HIZ_TILE_PX - 1u) / HIZ_TILE_PX;
    var off = 0u;
    while t1.x - t0.x >= HIZ_SPAN || t1.y - t0.y >= HIZ_SPAN {
        t0 = t0 / 2u;
        t1 = t1 / 2u;
        off += lw * lh;
        lw = (lw + 1u) / 2u;
        lh = (lh + 1u) / 2u;
    }
    let zb = bitcast<u32>(z);
    for (var ty = t0.y; ty <= t1.y; ty++) {
        for (var tx = t0.x; tx <= t1.x; tx++) {
            if zb <= hiz[off + ty * lw + tx] { return false; }
        }
    }
    return true;
}
