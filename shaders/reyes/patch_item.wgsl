// The queue item of every Reyes stage: a (sub)patch. Host twin: reyes/src/frame.rs.
struct PatchItem {
    // 16 control points, xyz each, camera space, row-major cp[4*v + u] (u fastest): the points
    // themselves for a polynomial patch; for a rational one (PATCH_RATIONAL in patch_info) their
    // homogeneous x w, y w, z w, whose weights w are not in the item but follow from uv and the
    // patch's weight table (rational_weights in common.wgsl; docs/reyes.md).
    cp: array<f32, 48>,
    // The item's parameter range in its original patch: (u0, u1, v0, v1).
    uv: vec4<f32>,
    // Index of the original patch (material, sides, orientation).
    patch_id: u32,
    // Bits 0..7: splits so far; bits 8..15: of those, splits made because of the near plane.
    depth: u32,
    // Set by Bound for DiceShade: segments in u (bits 0..7) and v (bits 8..15). Before that,
    // on the root items of pipelined frames that cull (roots.wgsl), and on their pieces:
    // ROOT_HISTORY and ROOT_WAS_VISIBLE.
    rates: u32,
    // Set by Bound: crack dilation of each boundary edge (v = 0, v = 1, u = 0, u = 1), 8 bits
    // each from bit 0, in steps of MAX_DILATE_PX / 255 (docs/reyes.md, "No cracks").
    dilate: u32,
}

// PatchItem.rates of a root item made by make_roots (roots.wgsl) for a pipelined frame that culls
// from the previous frame (two phases; docs/reyes.md, *Occlusion culling*), kept by its pieces
// until Bound sets the dice rates: the frame keeps an occlusion history ...
const ROOT_HISTORY: u32 = 0x100000u;
// ... and some piece of this root passed Bound's occlusion test in the frame before (drawn in
// phase 1, only tested again in phase 2).
const ROOT_WAS_VISIBLE: u32 = 0x200000u;
