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
}

struct Material {
    color: vec3<f32>,
    // 0 constant, 1 matte, 2 plastic
    kind: u32,
    specular: vec3<f32>,
    ka: f32,
    kd: f32,
    ks: f32,
    roughness: f32,
    pad: f32,
}

struct Light {
    color: vec3<f32>,
    // 0 ambient, 1 distant (vec = direction the light travels), 2 point (vec = position)
    kind: u32,
    vec: vec3<f32>,
    pad: f32,
}

// Per original patch: material index, and flags bit 0 = flip normal, bit 1 = two-sided.
struct PatchInfo {
    material: u32,
    flags: u32,
}

@group(1) @binding(0) var<storage, read> frame: Frame;
@group(1) @binding(1) var<storage, read> materials: array<Material>;
@group(1) @binding(2) var<storage, read> lights: array<Light>;
@group(1) @binding(3) var<storage, read> patch_info: array<PatchInfo>;
// One 64-bit key per sample: (inverted depth bits << 32) | packed colour; 0 = background.
// atomicMax keeps the nearest, and the result does not depend on the order of writes.
@group(1) @binding(4) var<storage, read_write> samples: array<atomic<u64>>;
@group(1) @binding(5) var<storage, read_write> counters: array<atomic<u32>, 16>;

const C_CULL_CLIP: u32 = 0u;       // wholly in front of near or behind far
const C_CULL_OFFSCREEN: u32 = 1u;  // screen bound misses the image
const C_NEAR_CLIPPED: u32 = 2u;    // grids diced with near-plane clipping (crossing after max_eye_splits)
const C_DEPTH_LIMIT: u32 = 3u;     // diced at max_depth although it wanted another split
const C_MICROPOLYGONS: u32 = 4u;
const C_MAX_DEPTH: u32 = 5u;
const C_EYE_SPLITS: u32 = 6u;
const C_BACKFACE: u32 = 7u;        // micropolygons culled as back-facing (Sides 1)
const C_CULL_BACKFACE: u32 = 8u;   // patches culled in Bound as back-facing everywhere

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

fn cp_point(cp: ptr<function, array<f32, 48>>, i: u32) -> vec3<f32> {
    return vec3<f32>((*cp)[3u * i], (*cp)[3u * i + 1u], (*cp)[3u * i + 2u]);
}

fn set_cp_point(cp: ptr<function, array<f32, 48>>, i: u32, p: vec3<f32>) {
    (*cp)[3u * i] = p.x;
    (*cp)[3u * i + 1u] = p.y;
    (*cp)[3u * i + 2u] = p.z;
}

// Camera space to pixels; only meaningful for z > 0.
fn project(p: vec3<f32>) -> vec2<f32> {
    return vec2<f32>(
        0.5 * f32(frame.width) + frame.focal * p.x / p.z,
        0.5 * f32(frame.height) - frame.focal * p.y / p.z,
    );
}

fn reyes_hash(x: u32) -> u32 {
    var h = x;
    h ^= h >> 16u; h *= 0x7feb352du; h ^= h >> 15u; h *= 0x846ca68bu; h ^= h >> 16u;
    return h;
}
