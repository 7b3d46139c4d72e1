// The raster peer's image: the MSAA-resolved colour (premultiplied by coverage) made straight
// with coverage as alpha, and the nearest depth of the multisampled depth target, into the
// buffers Reyes's resolve writes (resolve.wgsl: linear RGBA f32 per pixel and camera-space
// depth, 3e38 where the background shows). `RasterDepth` is an alias prepended by the host:
// texture_depth_multisampled_2d, or texture_depth_2d for one sample.
// Rust twin: raster_peer::RasterResolveParams (the layout).

struct RasterResolveParams {
    width: u32,
    height: u32,
    // Samples of the depth target.
    samples: u32,
    // Threads per row of workgroups (the dispatch is 2D for large images).
    row: u32,
    near: f32,
    pad0: u32,
    pad1: u32,
    pad2: u32,
}

@group(0) @binding(0) var<storage, read> raster: RasterResolveParams;
@group(0) @binding(1) var raster_color: texture_2d<f32>;
@group(0) @binding(2) var raster_depth: RasterDepth;
@group(0) @binding(3) var<storage, read_write> raster_rgba: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read_write> raster_z: array<f32>;

@compute @workgroup_size(256)
fn raster_resolve(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x + gid.y * raster.row;
    if i >= raster.width * raster.height { return; }
    let xy = vec2<u32>(i % raster.width, i / raster.width);
    let c = textureLoad(raster_color, xy, 0);
    var d = 0.0;
    for (var s = 0u; s < raster.samples; s++) { d = max(d, textureLoad(raster_depth, xy, s)); }
    var rgba = vec4<f32>(0.0);
    if c.a > 0.0 { rgba = vec4<f32>(c.rgb / c.a, c.a); }
    raster_rgba[i] = rgba;
    raster_z[i] = select(3.0e38, raster.near / d, d > 0.0);
}
