// The viewer's draw of a frame (`reyes view`): one full-screen triangle whose fragments each
// show the nearest pixel of the renderer's 8-bit image (rgba8.wgsl's buffer, read where the
// frame left it: no read-back), the image fitted into the target with its aspect kept, centred,
// the rest the background. The image's colour is composited over the background by its
// coverage (alpha), in the 8-bit sRGB values, in integers, so that on a UNORM target the
// result is exact.
// Rust twin: reyes::present::present_pixel (the fit, the pixel chosen and the composite, bit for
// bit on a UNORM target; an sRGB target re-encodes on store, within one step).

struct PresentParams {
    // Image and target sizes in pixels.
    image_w: u32,
    image_h: u32,
    target_w: u32,
    target_h: u32,
    // 1: the target encodes sRGB on store, so the shader decodes the sRGB values to linear.
    srgb_target: u32,
    // The background, as an rgba8 word (bytes r, g, b in memory order; alpha unused).
    background: u32,
    pad0: u32,
    pad1: u32,
}

@group(0) @binding(0) var<storage, read> present: PresentParams;
@group(0) @binding(1) var<storage, read> present_image: array<u32>;

@vertex
fn present_vertex(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    // (-1,-1), (3,-1), (-1,3): one triangle covering the whole target.
    let uv = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
    return vec4<f32>(uv * 2.0 - 1.0, 0.0, 1.0);
}

// The image's placement in the target: (x0, y0, width, height) in target pixels. The image is
// scaled by the largest factor that fits (integer division rounds the scaled side down).
fn present_fit() -> vec4<u32> {
    let iw = present.image_w;
    let ih = present.image_h;
    let tw = present.target_w;
    let th = present.target_h;
    var w = tw;
    var h = th;
    if tw * ih <= th * iw {
        h = max(tw * ih / iw, 1u);
    } else {
        w = max(th * iw / ih, 1u);
    }
    return vec4<u32>((tw - w) / 2u, (th - h) / 2u, w, h);
}

fn present_srgb_decode(c: f32) -> f32 {
    if c <= 0.04045 { return c / 12.92; }
    return pow((c + 0.055) / 1.055, 2.4);
}

@fragment
fn present_fragment(@builtin(position) pos: vec4<f32>) -> @location(0) vec4<f32> {
    // Fragment centres are at half pixels: the floor is the target pixel.
    let x = u32(pos.x);
    let y = u32(pos.y);
    let f = present_fit();
    let bg = present.background;
    var c = bg;
    if x >= f.x && x < f.x + f.z && y >= f.y && y < f.y + f.w {
        let ix = (x - f.x) * present.image_w / f.z;
        let iy = (y - f.y) * present.image_h / f.w;
        let p = present_image[iy * present.image_w + ix];
        // Coverage composite in 8-bit values: (p a + bg (255 - a) + 127) / 255 per channel.
        let a = p >> 24u;
        c = 0u;
        for (var k = 0u; k < 24u; k += 8u) {
            let v = (((p >> k) & 255u) * a + ((bg >> k) & 255u) * (255u - a) + 127u) / 255u;
            c |= v << k;
        }
    }
    var rgb = unpack4x8unorm(c).xyz;
    if present.srgb_target != 0u {
        rgb = vec3<f32>(present_srgb_decode(rgb.x), present_srgb_decode(rgb.y), present_srgb_decode(rgb.z));
    }
    return vec4<f32>(rgb, 1.0);
}
