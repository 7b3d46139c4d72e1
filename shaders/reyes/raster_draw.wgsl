// The raster peer's draw: the tessellated triangles (tessellate.wgsl) through the hardware
// rasterizer with MSAA, depth-tested (reversed depth: 1 / w = near / z, nearest greatest).
// Colour is interpolated per vertex (Gouraud; Reyes gives each micropolygon the mean of its
// corners) in linear light, decoded from the packed 10-bit sRGB exactly as resolve.wgsl does
// (unpack_linear). Needs resolve.wgsl.

struct RasterFragment {
    @builtin(position) clip: vec4<f32>,
    @location(0) color: vec3<f32>,
}

// `p`: a RasterVertex's (x, y, w); the clip position is (x, y, 1, w).
@vertex
fn raster_vertex(@location(0) p: vec3<f32>, @location(1) color: u32) -> RasterFragment {
    return RasterFragment(vec4<f32>(p.x, p.y, 1.0, p.z), unpack_linear(color));
}

// Alpha 1: the resolved alpha is the fraction of covered samples, the colour premultiplied by
// it (raster_resolve.wgsl divides it out).
@fragment
fn raster_fragment(f: RasterFragment) -> @location(0) vec4<f32> {
    return vec4<f32>(f.color, 1.0);
}
