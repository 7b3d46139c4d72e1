// Root items on the GPU (reyes bench and the real-time renderer): each patch's homogeneous
// control points (x w, y w, z w, w), uploaded once, times this frame's camera transform, make
// the patch's root PatchItem, the seed of Bound: the xyz of the transformed points (the
// weights, which an affine transform keeps, are in the patch's weight table). Rust twin: frame::root_item (the same item
// from the host's camera-space patch); keep the two in step. Needs patch_item.wgsl.

struct Orbit {
    // Column-major affine transform of camera-space points (orbit::orbit_matrix).
    m: mat4x4<f32>,
    patches: u32,
    // Threads per row of workgroups (the dispatch is 2D for many patches).
    row: u32,
    // 1: the frame culls from the previous frame's visibility (two phases, bound.wgsl): each
    // root is tagged ROOT_HISTORY, and ROOT_WAS_VISIBLE from `visible`, which is then cleared
    // for this frame's Bound to set. 0: untagged roots, `visible` untouched.
    history: u32,
}

@group(0) @binding(0) var<storage, read> orbit: Orbit;
// 16 homogeneous control points per patch, cp[4*v + u].
@group(0) @binding(1) var<storage, read> objects: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read_write> roots: array<PatchItem>;
// Per patch: nonzero when some piece of its root passed Bound's occlusion test in the last
// frame (`visible` in common.wgsl, the same buffer). Binding 10: tessellate.wgsl, which
// includes this file, declares 3 to 9.
@group(0) @binding(10) var<storage, read_write> root_visible: array<u32>;

// The root item of patch `id` from its 16 transformed homogeneous control points (an affine
// transform of (x w, y w, z w, w) is the homogeneous point of the transformed x, with the same
// w): PatchItem keeps their xyz.
fn root_item(id: u32, cp: array<vec4<f32>, 16>) -> PatchItem {
    var item: PatchItem;
    for (var i = 0u; i < 16u; i++) {
        item.cp[3u * i] = cp[i].x;
        item.cp[3u * i + 1u] = cp[i].y;
        item.cp[3u * i + 2u] = cp[i].z;
    }
    item.uv = vec4<f32>(0.0, 1.0, 0.0, 1.0);
    item.patch_id = id;
    item.depth = 0u;
    item.rates = 0u;
    item.dilate = 0u;
    return item;
}

@compute @workgroup_size(64)
fn make_roots(@builtin(global_invocation_id) gid: vec3<u32>) {
    let id = gid.x + gid.y * orbit.row;
    if id >= orbit.patches { return; }
    var cp: array<vec4<f32>, 16>;
    for (var i = 0u; i < 16u; i++) {
        cp[i] = orbit.m * objects[16u * id + i];
    }
    var item = root_item(id, cp);
    if orbit.history != 0u {
        item.rates = ROOT_HISTORY | select(0u, ROOT_WAS_VISIBLE, root_visible[id] != 0u);
        root_visible[id] = 0u;
    }
    roots[id] = item;
}
