// Resolve: a plain compute pass after the scheduler run. Per pixel, averages the colours of the
// covered sub-samples (in linear light) and gives coverage as alpha, and the nearest depth.
// Rust twin: reyes/src/stages/resolve.rs.

// One bucket's samples (`width` x `height` pixels) into the image at (x0, y0), `image_width`
// wide. `row` = threads per row of workgroups (the dispatch is 2D for large images).
// `imager` 1: RenderMan's background imager (`Imager "background"`): each pixel composited
// over `background` (linear RGB) and made opaque, Ci += (1 - alpha) background, alpha = 1.
struct ResolveParams {
    width: u32,
    height: u32,
    spp: u32,
    row: u32,
    image_width: u32,
    x0: u32,
    y0: u32,
    imager: u32,
    background: vec4<f32>,
}

@group(0) @binding(0) var<storage, read> params: ResolveParams;
// The sample keys as (low, high) words.
@group(0) @binding(1) var<storage, read> keys: array<vec2<u32>>;
@group(0) @binding(2) var<storage, read_write> rgba: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read_write> depth: array<f32>;

fn srgb_decode(x: f32) -> f32 {
    if x <= 0.04045 { return x / 12.92; }
    return pow((x + 0.055) / 1.055, 2.4);
}

fn unpack_linear(c: u32) -> vec3<f32> {
    return vec3<f32>(
        srgb_decode(f32(c & 1023u) / 1023.0),
        srgb_decode(f32((c >> 10u) & 1023u) / 1023.0),
        srgb_decode(f32((c >> 20u) & 1023u) / 1023.0),
    );
}

@compute @workgroup_size(256)
fn resolve(@builtin(global_invocation_id) gid: vec3<u32>) {
    let pixel = gid.x + gid.y * params.row;
    if pixel >= params.width * params.height { return; }
    var sum = vec3<f32>(0.0);
    var covered = 0u;
    var zmin = 3.0e38;
    for (var s = 0u; s < params.spp; s++) {
        let k = keys[pixel * params.spp + s];
        if k.y == 0u { continue; }
        covered += 1u;
        sum += unpack_linear(k.x);
        zmin = min(zmin, bitcast<f32>(~k.y));
    }
    var c = vec3<f32>(0.0);
    if covered > 0u { c = sum / f32(covered); }
    let out = (params.y0 + pixel / params.width) * params.image_width + params.x0
        + pixel % params.width;
    let alpha = f32(covered) / f32(params.spp);
    if params.imager != 0u {
        rgba[out] = vec4<f32>(c * alpha + params.background.xyz * (1.0 - alpha), 1.0);
    } else {
        rgba[out] = vec4<f32>(c, alpha);
    }
    depth[out] = zmin;
}
