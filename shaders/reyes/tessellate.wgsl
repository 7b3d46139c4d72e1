// The raster peer's tessellation (reyes bench --peer raster): what an engine does on an API
// without tessellation shaders, spread over the whole GPU. Three dispatches:
// - `tess_rates`, one thread per patch: its homogeneous control points times the frame's
//   camera transform (the `orbit` and `objects` of roots.wgsl), culled by their bound (wholly
//   in front of near or beyond far, or off screen), a rate per side from the projected control
//   polygon (triangles of about `frame.mp_size` pixels, at most `tess.max_rate` per side, the
//   hardware tessellator's 64); room for its grid points and quads taken with atomics, and one
//   tile (TESS_TILE grid points, TESS_TILE quads) per 64 points appended to `tiles`;
//   `tile_dispatch` then writes the indirect dispatch of those tiles;
// - `tess_points`, one thread per grid point (a workgroup per tile): the point evaluated,
//   shaded exactly as DiceShade shades it (surface.wgsl, shade.wgsl) into a vertex;
// - `tess_quads`, one thread per quad (the same tiles): two triangles per quad into the index
//   buffer. `finish_draw` writes the indirect draw.
// Rust twin: reyes/src/raster_peer/tessellation.rs (grid_rate, tessellate_cpu).
// Needs patch_item.wgsl, roots.wgsl, common.wgsl, shade.wgsl, surface.wgsl.

struct TessParams {
    patches: u32,
    // Threads per row of `tess_rates`'s 2D dispatch (one thread per patch).
    row: u32,
    // Room in `vertices` and in `indices` (6 per quad).
    vertex_capacity: u32,
    quad_capacity: u32,
    // Most segments per grid side.
    max_rate: u32,
    // Room in `tiles`.
    tile_capacity: u32,
    pad1: u32,
    pad2: u32,
}

// A vertex: the clip position divided by the near distance, (x, y, 1, w) with
// x = 2 focal px / (width near), y = 2 focal py / (height near), w = pz / near for the camera-
// space point p (so depth = 1 / w = near / pz: reversed, infinite far plane), and the packed
// shaded colour of pack_color (10-bit sRGB channels, bit 30 = seen from its back).
struct RasterVertex {
    x: f32,
    y: f32,
    w: f32,
    color: u32,
}

@group(0) @binding(3) var<storage, read> tess: TessParams;
@group(0) @binding(4) var<storage, read_write> vertices: array<RasterVertex>;
@group(0) @binding(5) var<storage, read_write> indices: array<u32>;
// T_* below, then the tiles' indirect dispatch (x, y, z) at T_DISPATCH.
@group(0) @binding(6) var<storage, read_write> tess_counts: array<atomic<u32>, 12>;
// Per patch, two entries: (nu, nv, first vertex, first quad), nu = 0 when culled or out of
// room; and its edge rates (GridRate.edges).
@group(0) @binding(7) var<storage, read_write> grids: array<vec4<u32>>;
// DrawIndexedIndirectArgs: index count, instance count, first index, base vertex, first instance.
@group(0) @binding(8) var<storage, read_write> draw_args: array<u32, 5>;
// The frame's tiles: patch << TILE_BITS | tile of the patch (its points and quads
// TESS_TILE * tile onwards), in no particular order.
@group(0) @binding(9) var<storage, read_write> tiles: array<u32>;

// Grid points and quads the frame's patches need (counted whether or not they fit).
const T_VERTICES: u32 = 0u;
const T_QUADS: u32 = 1u;
const T_DRAWN: u32 = 2u;
const T_CULLED: u32 = 3u;
// Quads of one-sided patches whose four corners face away (drawn as degenerate triangles).
const T_BACKFACE: u32 = 4u;
// Patches that did not fit: the frame draws nothing and is drawn again with more room.
const T_OVER: u32 = 5u;
// Tiles appended to `tiles`.
const T_TILES: u32 = 6u;
// DispatchIndirectArgs of `tess_points` and `tess_quads` (3 words; copied to an INDIRECT
// buffer between the passes).
const T_DISPATCH: u32 = 8u;

// Grid points (and quads) per tile: one workgroup of `tess_points` and `tess_quads`.
const TESS_TILE: u32 = 64u;
// Bits of a tile entry for the tile of its patch (65 x 65 points: at most 67 tiles).
const TILE_BITS: u32 = 7u;
// Workgroups per row of the tiles' 2D dispatch (WebGPU allows 65535 per dimension).
const TILE_ROW: u32 = 32768u;

var<workgroup> tess_cp: array<vec4<f32>, 16>;
var<workgroup> tess_backface: atomic<u32>;

// A patch's grid: `n` = (nu, nv) segments, (0, 0) when culled; `edges` the segments of its
// boundary curves v = 0, v = 1 (along u, at most nu) and u = 0, u = 1 (along v, at most nv).
struct GridRate {
    n: vec2<u32>,
    edges: vec4<u32>,
}

// The segments of the patch whose Euclidean camera-space control points are `e`; culled when
// wholly in front of the near plane or beyond the far one, or (in front of the eye) when its
// projected control points' bound misses the image. A patch crossing the near plane is kept
// at the most segments: the rasterizer clips its triangles. Otherwise each direction's rate is
// the longest projected control polygon along it (which bounds the curve's length) over
// mp_size, rounded up, in 1..max_rate; and each boundary's rate is its own control polygon's
// (as a hardware tessellator's outer levels): it depends only on the 4 control points the
// patch shares with its neighbour there, so both place the same points on the shared curve
// and no T-junction cracks open (edge_param). Twin: raster_peer::grid_rate.
fn grid_rate(e: array<vec3<f32>, 16>) -> GridRate {
    var zmin = 3.0e38;
    var zmax = -3.0e38;
    for (var k = 0u; k < 16u; k++) {
        zmin = min(zmin, e[k].z);
        zmax = max(zmax, e[k].z);
    }
    if zmax < frame.near || zmin > frame.far { return GridRate(vec2<u32>(0u), vec4<u32>(0u)); }
    if zmin < frame.near { return GridRate(vec2<u32>(tess.max_rate), vec4<u32>(tess.max_rate)); }
    var s: array<vec2<f32>, 16>;
    var lo = vec2<f32>(3.0e38);
    var hi = vec2<f32>(-3.0e38);
    for (var k = 0u; k < 16u; k++) {
        s[k] = project(e[k]);
        lo = min(lo, s[k]);
        hi = max(hi, s[k]);
    }
    if hi.x < 0.0 || hi.y < 0.0 || lo.x > f32(frame.width) || lo.y > f32(frame.height) {
        return GridRate(vec2<u32>(0u), vec4<u32>(0u));
    }
    // Row a along u in .x, column a along v in .y.
    var len: array<vec2<f32>, 4>;
    for (var a = 0u; a < 4u; a++) {
        for (var b = 0u; b < 3u; b++) {
            len[a].x += distance(s[4u * a + b + 1u], s[4u * a + b]);
            len[a].y += distance(s[4u * (b + 1u) + a], s[4u * b + a]);
        }
    }
    let n = segments(max(max(len[0], len[1]), max(len[2], len[3])));
    return GridRate(n, vec4<u32>(segments(vec2<f32>(len[0].x, len[3].x)),
                                 segments(vec2<f32>(len[0].y, len[3].y))));
}

// Segments for curves of projected lengths `len` (pixels): one per mp_size, in 1..max_rate.
fn segments(len: vec2<f32>) -> vec2<u32> {
    let n = min(ceil(len / frame.mp_size), vec2<f32>(f32(tess.max_rate)));
    return vec2<u32>(max(n, vec2<f32>(1.0)));
}

// The parameter of point i of n along a boundary of `e` <= n segments: round(i e / n) / e in
// integers, so the boundary's points lie only at its own k / e (several points of the grid
// coincide there: zero-area triangles); i / n when e = n.
fn edge_param(i: u32, n: u32, e: u32) -> f32 {
    return f32((2u * i * e + n) / (2u * n)) / f32(e);
}

// The tile of workgroup `wg` of the tiles' dispatch: (patch, first point or quad), or
// (patches, 0) past the last tile (the last row's spare workgroups).
fn tile_at(wg: vec3<u32>) -> vec2<u32> {
    let t = wg.x + wg.y * TILE_ROW;
    if t >= atomicLoad(&tess_counts[T_TILES]) { return vec2<u32>(tess.patches, 0u); }
    let e = tiles[t];
    return vec2<u32>(e >> TILE_BITS, (e & ((1u << TILE_BITS) - 1u)) * TESS_TILE);
}

// One thread per patch: its rate, culling and room (see the top of the file).
@compute @workgroup_size(64)
fn tess_rates(@builtin(global_invocation_id) gid: vec3<u32>) {
    let id = gid.x + gid.y * tess.row;
    if id >= tess.patches { return; }
    var e: array<vec3<f32>, 16>;
    for (var k = 0u; k < 16u; k++) {
        let h = orbit.m * objects[16u * id + k];
        e[k] = h.xyz / h.w;
    }
    let rate = grid_rate(e);
    let r = rate.n;
    var g = vec4<u32>(0u);
    if r.x == 0u {
        atomicAdd(&tess_counts[T_CULLED], 1u);
    } else {
        let points = (r.x + 1u) * (r.y + 1u);
        let quads = r.x * r.y;
        let vb = atomicAdd(&tess_counts[T_VERTICES], points);
        let qb = atomicAdd(&tess_counts[T_QUADS], quads);
        if vb + points <= tess.vertex_capacity && qb + quads <= tess.quad_capacity {
            g = vec4<u32>(r, vb, qb);
            atomicAdd(&tess_counts[T_DRAWN], 1u);
            // Quads are fewer than points: the points' tiles cover them.
            let n = (points + TESS_TILE - 1u) / TESS_TILE;
            let tb = atomicAdd(&tess_counts[T_TILES], n);
            for (var t = 0u; t < n; t++) {
                if tb + t < tess.tile_capacity { tiles[tb + t] = (id << TILE_BITS) | t; }
            }
        } else {
            atomicAdd(&tess_counts[T_OVER], 1u);
        }
    }
    grids[2u * id] = g;
    grids[2u * id + 1u] = rate.edges;
}

// The tiles' indirect dispatch: TILE_ROW workgroups per row.
@compute @workgroup_size(1)
fn tile_dispatch() {
    let n = min(atomicLoad(&tess_counts[T_TILES]), tess.tile_capacity);
    atomicStore(&tess_counts[T_TILES], n);
    atomicStore(&tess_counts[T_DISPATCH], min(n, TILE_ROW));
    // Rows stay within the dispatch limit, as wgpu's indirect validation (off by default,
    // scheduler::gpu::instance_flags) would require: n <= tile_capacity, and a tile buffer of
    // 4 bytes a tile within a 4 GiB binding holds at most 32,768 rows; the min only states it.
    atomicStore(&tess_counts[T_DISPATCH + 1u], min((n + TILE_ROW - 1u) / TILE_ROW, 65535u));
    atomicStore(&tess_counts[T_DISPATCH + 2u], 1u);
}

// One thread per grid point of a tile: evaluated and shaded into its vertex.
@compute @workgroup_size(64)
fn tess_points(@builtin(workgroup_id) wg: vec3<u32>,
               @builtin(local_invocation_index) lid: u32) {
    let tile = tile_at(wg);
    let id = tile.x;
    if lid < 16u && id < tess.patches { tess_cp[lid] = orbit.m * objects[16u * id + lid]; }
    workgroupBarrier();
    if id >= tess.patches { return; }
    let g = grids[2u * id];
    let edges = grids[2u * id + 1u];
    let nu = g.x;
    let nv = g.y;
    let cols = nu + 1u;
    let k = tile.y + lid;
    if k >= cols * (nv + 1u) { return; }
    let info = patch_info[id];
    let rational = SCENE_RATIONAL && (info.flags & PATCH_RATIONAL) != 0u;
    // The root item's net: homogeneous xyz and the weights, which are the patch's weight table
    // (rational_weights of the whole range gives exactly these); w = 1 for a polynomial patch.
    var cp: array<f32, 48>;
    var w: array<f32, 16>;
    for (var c = 0u; c < 16u; c++) {
        set_cp_point(&cp, c, tess_cp[c].xyz);
        w[c] = tess_cp[c].w;
    }
    let flip = (info.flags & 1u) != 0u;
    let m = materials[info.material];
    let near = frame.near;
    let scale = 2.0 * frame.focal / (vec2<f32>(f32(frame.width), f32(frame.height)) * near);
    let i = k % cols;
    let j = k / cols;
    var u = f32(i) / f32(nu);
    var v = f32(j) / f32(nv);
    if j == 0u { u = edge_param(i, nu, edges.x); }
    if j == nv { u = edge_param(i, nu, edges.y); }
    if i == 0u { v = edge_param(j, nv, edges.z); }
    if i == nu { v = edge_param(j, nv, edges.w); }
    // As dice_grid in dice_shade.wgsl, for the root item (uv = 0..1).
    let e = eval_surface(&cp, &w, rational, u, v);
    let n = patch_normal(&cp, &w, rational, e, u, v, flip);
    var cs = m.color;
    if SCENE_PRIMVARS && info.cs != 0u { cs = color_field(info.cs, u, v); }
    var ns = n;
    if SCENE_PRIMVARS && info.normal != 0u && (info.flags & PATCH_DISPLACED) == 0u {
        ns = color_field(info.normal, u, v);
    }
    let c = shade(e[0], ns, m, cs);
    let back = dot(n, e[0]) > 0.0;
    let p = e[0];
    vertices[g.z + k] = RasterVertex(p.x * scale.x, p.y * scale.y, p.z / near,
                                     pack_color(c, back));
}

// Whether vertex `k` faces away (pack_color's bit 30).
fn vertex_back(k: u32) -> bool {
    return (vertices[k].color & (1u << 30u)) != 0u;
}

// One thread per quad of a tile: its two triangles.
@compute @workgroup_size(64)
fn tess_quads(@builtin(workgroup_id) wg: vec3<u32>,
              @builtin(local_invocation_index) lid: u32) {
    if lid == 0u { atomicStore(&tess_backface, 0u); }
    workgroupBarrier();
    let tile = tile_at(wg);
    let id = tile.x;
    if id < tess.patches {
        let g = grids[2u * id];
        let nu = g.x;
        let q = tile.y + lid;
        if q < nu * g.y {
            let one_sided = (patch_info[id].flags & 2u) == 0u;
            // Quad (i, j) with corners a b c d as DiceShade's micropolygon, split along ac as
            // sampling splits it.
            let cols = nu + 1u;
            let a = g.z + (q / nu) * cols + q % nu;
            let b = a + 1u;
            let c = a + cols + 1u;
            let d = a + cols;
            let at = 6u * (g.w + q);
            if one_sided && vertex_back(a) && vertex_back(b) && vertex_back(c) && vertex_back(d) {
                // Culled as sampling culls it (micropolygon_color): a degenerate pair.
                for (var s = 0u; s < 6u; s++) { indices[at + s] = a; }
                atomicAdd(&tess_backface, 1u);
            } else {
                indices[at] = a;
                indices[at + 1u] = b;
                indices[at + 2u] = c;
                indices[at + 3u] = a;
                indices[at + 4u] = c;
                indices[at + 5u] = d;
            }
        }
    }
    workgroupBarrier();
    if lid == 0u {
        let n = atomicLoad(&tess_backface);
        if n > 0u { atomicAdd(&tess_counts[T_BACKFACE], n); }
    }
}

// The indirect draw of every triangle written; none when some patch did not fit (the frame is
// then drawn again with more room: a partial frame is never shown).
@compute @workgroup_size(1)
fn finish_draw() {
    let fits = atomicLoad(&tess_counts[T_OVER]) == 0u;
    let quads = atomicLoad(&tess_counts[T_QUADS]);
    draw_args[0] = select(0u, 6u * quads, fits);
    draw_args[1] = 1u;
    draw_args[2] = 0u;
    draw_args[3] = 0u;
    draw_args[4] = 0u;
}
