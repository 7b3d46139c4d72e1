// Reyes declarations shared by every stage: the frame constants, scene tables, counters and
// small maths. The Rust twins are in reyes/src/frame.rs and reyes/src/stages/*.rs.

// PatchItem (patch_item.wgsl) is declared by the scheduler as the procedures' item type.

struct Frame {
    width: u32,
    height: u32,
    spp_x: u32,
    spp_y: u32,
    focal: f32,
    near: f32,
    far: f32,
    // Target micropolygon edge in pixels (adaptive dicing).
    mp_size: f32,
    // > 0: the paper's fixed rule, split until the screen bound is at most this many pixels.
    bound_px: f32,
    grid_max: u32,
    max_depth: u32,
    max_eye_splits: u32,
    n_lights: u32,
    seed: u32,
    // The screen bucket this run renders (the whole image without a memory budget); the
    // sample buffer holds only its pixels.
    tile_x0: u32,
    tile_y0: u32,
    tile_w: u32,
    tile_h: u32,
    // 1: grow micropolygons by their crack bound (bound.wgsl); 0 only to show what it buys.
    crack_dilation: u32,
    // Direction displaced grid points move along: DISPLACE_EXACT_NORMALS (the patch's
    // analytic normal) or DISPLACE_APPROX_NORMALS (the grid's finite differences; holes).
    displacement_normals: u32,
    // How micropolygons are rasterized: RASTER_BBOX or RASTER_NEAREST (sample.wgsl).
    raster: u32,
    // Time and lens sampling: UVT_OFF (no motion blur or depth of field) or the algorithm,
    // UVT_SIMPLE, UVT_INTERLEAVE or UVT_BBOX (sample_uvt.wgsl); read only when SCENE_UVT.
    uvt: u32,
    // Interleave UVT: tile side K in pixels, and the number P of permutations.
    il_tile: u32,
    il_perms: u32,
    // Depth of field: the signed circle of confusion of depth z is
    // coc_scale * (inv_focus - 1 / z) pixels (0 without depth of field).
    coc_scale: f32,
    inv_focus: f32,
    // Occlusion culling in Bound: OCCLUSION_OFF, OCCLUSION_ON (no pyramid yet; for roots
    // tagged ROOT_HISTORY, phase 1 of a pipelined frame) or OCCLUSION_TEST (test items against
    // the bucket's depth pyramid, hiz; phase 2 of a pipelined frame).
    occlusion: u32,
}

const OCCLUSION_OFF: u32 = 0u;
const OCCLUSION_ON: u32 = 1u;
const OCCLUSION_TEST: u32 = 2u;

const UVT_OFF: u32 = 0u;
const UVT_SIMPLE: u32 = 1u;
const UVT_INTERLEAVE: u32 = 2u;
const UVT_BBOX: u32 = 3u;

// Frame.raster: every sub-sample under the micropolygon's bound, tested against its triangles.
const RASTER_BBOX: u32 = 0u;
// Frame.raster: only the sub-sample nearest the micropolygon's centre (the paper's naive mode).
const RASTER_NEAREST: u32 = 1u;

struct Material {
    color: vec3<f32>,
    // 0 constant, 1 matte, 2 plastic
    kind: u32,
    specular: vec3<f32>,
    ka: f32,
    kd: f32,
    ks: f32,
    roughness: f32,
    // `Opacity` as one fraction of samples covered: the mean of its channels.
    opacity: f32,
}

struct Light {
    color: vec3<f32>,
    // 0 ambient, 1 distant (vec = direction the light travels), 2 point (vec = position)
    kind: u32,
    vec: vec3<f32>,
    pad: f32,
}

// Per original patch: material index, and flags bit 0 = flip normal, bit 1 = two-sided,
// bit 2 = rational (PATCH_RATIONAL); its "Cs" and "Os" fields in `primvars` (0: the material's
// Color / Opacity), each the entry index << 2 | its shape (FIELD_*); and for a rational patch
// the entry index in `primvars` of its 16 weights (4 entries, row v = l in entry l, u in
// x..w), 0 for a polynomial one (read only under PATCH_RATIONAL).
struct PatchInfo {
    material: u32,
    flags: u32,
    cs: u32,
    os: u32,
    weights: u32,
    // A displaced patch's entry in `primvars` (PATCH_DISPLACED; layout at `displacement_at`
    // in surface.wgsl), 0 when undisplaced.
    displacement: u32,
    // A moving patch's motion (PATCH_MOVING): 3 entries of `primvars`, the rows of the
    // camera-space affine map from shutter open to shutter close; 0 when still.
    motion: u32,
    // Its "N" field (shading normal, camera space; entry << 2 | shape as cs), 0 for the
    // surface's own normal; read for undisplaced patches only.
    normal: u32,
}

@group(1) @binding(0) var<storage, read> frame: Frame;
@group(1) @binding(1) var<storage, read> materials: array<Material>;
@group(1) @binding(2) var<storage, read> lights: array<Light>;
@group(1) @binding(3) var<storage, read> patch_info: array<PatchInfo>;
// One 64-bit key per sample: (inverted depth bits << 32) | packed colour; 0 = background.
// atomicMax keeps the nearest, and the result does not depend on the order of writes.
@group(1) @binding(4) var<storage, read_write> samples: array<atomic<u64>>;
@group(1) @binding(5) var<storage, read_write> counters: array<atomic<u32>, 16>;
// Colour fields of the patches with primitive variables (rgb, w unused), over the original
// patch's (u, v): one value, 4 bilinear corners or 16 bicubic Bezier coefficients; and the
// weights of the rational patches (PatchInfo.weights).
@group(1) @binding(6) var<storage, read> primvars: array<vec4<f32>>;
// The bucket's depth pyramid (hiz.wgsl builds it between runs): level 0 holds, per tile of
// HIZ_TILE_PX x HIZ_TILE_PX pixels, the largest depth bits of its sub-samples (u32::MAX where
// one is empty); each level above the largest of up to 2x2 tiles below. Read by Bound only
// when frame.occlusion == OCCLUSION_TEST.
@group(1) @binding(7) var<storage, read> hiz: array<u32>;
// Per patch, the occlusion history of pipelined frames that cull (roots.wgsl reads and clears
// it when it makes the next frame's roots): Bound sets 1 where some piece of a root tagged
// ROOT_HISTORY passes the occlusion test and goes on. Untouched by other frames.
@group(1) @binding(8) var<storage, read_write> visible: array<atomic<u32>>;

const FIELD_FLAT: u32 = 1u;
const FIELD_BILINEAR: u32 = 2u;
const FIELD_BEZIER: u32 = 3u;

const C_CULL_CLIP: u32 = 0u;       // wholly in front of near or behind far
const C_CULL_OFFSCREEN: u32 = 1u;  // screen bound misses the image
const C_NEAR_CLIPPED: u32 = 2u;    // grids diced with near-plane clipping (crossing after max_eye_splits)
const C_DEPTH_LIMIT: u32 = 3u;     // diced at max_depth although it wanted another split
const C_MICROPOLYGONS: u32 = 4u;
const C_MAX_DEPTH: u32 = 5u;
const C_EYE_SPLITS: u32 = 6u;
const C_BACKFACE: u32 = 7u;        // micropolygons culled as back-facing (Sides 1)
const C_CULL_BACKFACE: u32 = 8u;   // patches culled in Bound as back-facing everywhere
const C_CULL_OCCLUDED: u32 = 9u;   // pieces culled in Bound as hidden by what is drawn (hiz)
const C_CULL_TRIMMED: u32 = 10u;   // pieces culled in Bound as wholly cut away by trim curves

// Bound culls only what lies this far outside the bucket, so that a micropolygon grown by its
// crack dilation (at most MAX_DILATE_PX) never reaches a sample of a bucket that culled it:
// bucketed and whole-frame renders give the same samples.
const MAX_DILATE_PX: f32 = 2.0;
// Edges inside a grid meet no T-junction; with dilation on they grow by this much only, so that
// float rounding in two triangles' edge tests cannot leave a sample on a shared edge uncovered.
const ROUNDING_DILATE_PX: f32 = 1.0e-3;
// Bit of PatchItem.rates: the grid crosses the near plane, so DiceShade keeps its points in
// camera space and sampling clips each micropolygon that crosses (sample.wgsl).
const NEAR_CLIP_GRID: u32 = 0x10000u;
// Grids of at most this many points go to DiceSmall (64 threads per grid).
const SMALL_GRID_POINTS: u32 = 64u;
const CULL_MARGIN_PX: f32 = 3.0;
// Bit of PatchInfo.flags: some weight of the patch is not 1. Without it the item's cp are the
// points themselves: the stages read no weights and divide by nothing.
const PATCH_RATIONAL: u32 = 4u;
// Bit of PatchInfo.flags: DiceShade displaces the grid (PatchInfo.displacement) and Bound grows
// the bound by its radius. Read only when SCENE_DISPLACEMENT.
const PATCH_DISPLACED: u32 = 8u;
// Bit of PatchInfo.flags: the patch moves over the shutter (PatchInfo.motion). Read only when
// SCENE_UVT.
const PATCH_MOVING: u32 = 16u;
const DISPLACE_BUMPS: u32 = 0u;
const DISPLACE_MAP: u32 = 1u;
const DISPLACE_EXACT_NORMALS: u32 = 0u;
const DISPLACE_APPROX_NORMALS: u32 = 1u;

fn cp_point(cp: ptr<function, array<f32, 48>>, i: u32) -> vec3<f32> {
    return vec3<f32>((*cp)[3u * i], (*cp)[3u * i + 1u], (*cp)[3u * i + 2u]);
}

fn set_cp_point(cp: ptr<function, array<f32, 48>>, i: u32, p: vec3<f32>) {
    (*cp)[3u * i] = p.x;
    (*cp)[3u * i + 1u] = p.y;
    (*cp)[3u * i + 2u] = p.z;
}

// Weights of a rational item. Its patch's weight function W(u, v) has the 16 Bernstein
// coefficients in its table (scaled so that the largest is 1); the item is the sub-patch of
// the parameter range uv = (u0, u1, v0, v1), and the weight of its control point (i, j) is the
// blossom (polar form) of W at the u-arguments of i and the v-arguments of j, where the
// arguments of i = 0..3 are (t0, t0, t0), (t0, t0, t1), (t0, t1, t1), (t1, t1, t1) (Ramshaw,
// "Blossoms are polar forms", 1989: the Bezier points of a cubic on [t0, t1]). Each weight is
// a convex combination of the table's, computed from them afresh (no error accumulates over
// splits), the same bits wherever it is computed: a point on an edge two sub-patches share
// has all its u- (or v-) arguments equal to the edge's parameter in both.

// (1 - t) a + t b: exactly a at t = 0 and b at t = 1, so a root item (uv = (0, 1, 0, 1))
// gets the table's weights exactly.
fn blossom_lerp(a: f32, b: f32, t: f32) -> f32 {
    return (1.0 - t) * a + t * b;
}

// The blossom of the cubic with Bernstein coefficients c at the i-th argument triple of
// [t0, t1]: de Casteljau with one argument per level.
fn blossom_at(c: vec4<f32>, t0: f32, t1: f32, i: u32) -> f32 {
    let a = select(t0, t1, i >= 3u);
    let b = select(t0, t1, i >= 2u);
    let d = select(t0, t1, i >= 1u);
    let p0 = blossom_lerp(c.x, c.y, a);
    let p1 = blossom_lerp(c.y, c.z, a);
    let p2 = blossom_lerp(c.z, c.w, a);
    return blossom_lerp(blossom_lerp(p0, p1, b), blossom_lerp(p1, p2, b), d);
}

// The 4 table rows (v = l) of the weights at `at`, each blossomed at the u-arguments of i.
fn weight_column(at: u32, uv: vec4<f32>, i: u32) -> vec4<f32> {
    return vec4<f32>(
        blossom_at(primvars[at], uv.x, uv.y, i),
        blossom_at(primvars[at + 1u], uv.x, uv.y, i),
        blossom_at(primvars[at + 2u], uv.x, uv.y, i),
        blossom_at(primvars[at + 3u], uv.x, uv.y, i),
    );
}

// The weight of control point (i, j) of the rational item with range uv whose patch has its
// weights at `at` (PatchInfo.weights): 30 lerps.
fn rational_weight(at: u32, uv: vec4<f32>, i: u32, j: u32) -> f32 {
    return blossom_at(weight_column(at, uv, i), uv.z, uv.w, j);
}

// All 16 weights of the item, w[4 j + i], the same bits as rational_weight: 192 lerps.
fn rational_weights(at: u32, uv: vec4<f32>) -> array<f32, 16> {
    var w: array<f32, 16>;
    for (var i = 0u; i < 4u; i++) {
        let c = weight_column(at, uv, i);
        for (var j = 0u; j < 4u; j++) { w[4u * j + i] = blossom_at(c, uv.z, uv.w, j); }
    }
    return w;
}

// Camera space to pixels; only meaningful for z > 0.
fn project(p: vec3<f32>) -> vec2<f32> {
    return vec2<f32>(
        0.5 * f32(frame.width) + frame.focal * p.x / p.z,
        0.5 * f32(frame.height) - frame.focal * p.y / p.z,
    );
}

// Point p (camera space, at shutter open) at shutter close: the affine map at `at` in
// primvars (PatchInfo.motion). Rust twin: stages::motion::moved_point.
fn moved_point(at: u32, p: vec3<f32>) -> vec3<f32> {
    let r0 = primvars[at];
    let r1 = primvars[at + 1u];
    let r2 = primvars[at + 2u];
    return vec3<f32>(r0.x * p.x + r0.y * p.y + r0.z * p.z + r0.w,
                     r1.x * p.x + r1.y * p.y + r1.z * p.z + r1.w,
                     r2.x * p.x + r2.y * p.y + r2.z * p.z + r2.w);
}

// The signed circle of confusion, in pixels, of camera-space depth z > 0 (thin lens): a lens
// position l in the unit disc moves the point's image by coc(z) * l.
fn coc(z: f32) -> f32 {
    return frame.coc_scale * (frame.inv_focus - 1.0 / z);
}

fn reyes_hash(x: u32) -> u32 {
    var h = x;
    h ^= h >> 16u; h *= 0x7feb352du; h ^= h >> 15u; h *= 0x846ca68bu; h ^= h >> 16u;
    return h;
}
