// 8-bit output on the GPU: the resolved image (straight linear RGB, coverage as alpha) as
// sRGB-encoded 8-bit RGBA, one u32 per pixel holding the bytes r, g, b, a in memory order.
// Rust twin: FrameImage::rgba8 (srgb_encode from shade.wgsl; the GPU's pow may round the other
// way at a step, so the two agree within one step).

struct Rgba8Params {
    pixels: u32,
    // Threads per row of workgroups (the dispatch is 2D for large images).
    row: u32,
    pad0: u32,
    pad1: u32,
}

@group(0) @binding(0) var<storage, read> rgba8_params: Rgba8Params;
@group(0) @binding(1) var<storage, read> linear: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read_write> rgba8: array<u32>;

@compute @workgroup_size(256)
fn to_rgba8(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x + gid.y * rgba8_params.row;
    if i >= rgba8_params.pixels { return; }
    let p = linear[i];
    let e = vec4<f32>(srgb_encode(p.x), srgb_encode(p.y), srgb_encode(p.z), clamp(p.w, 0.0, 1.0));
    let q = vec4<u32>(round(e * 255.0));
    rgba8[i] = q.x | (q.y << 8u) | (q.z << 16u) | (q.w << 24u);
}
