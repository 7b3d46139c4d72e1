// Shading of one grid point with RenderMan's standard surfaces (constant, matte, plastic, metal) and
// lights (ambient, distant, point). Rust twin: reyes/src/stages/shade.rs.

// `n` is the outside normal (unnormalised); `cs` the surface colour (the material's Color or the
// patch's "Cs"), which the standard shaders multiply into ambient and diffuse light. Returns
// linear RGB.
fn shade(p: vec3<f32>, n: vec3<f32>, m: Material, cs: vec3<f32>) -> vec3<f32> {
    let i = normalize(p);
    let nn = normalize(n);
    // faceforward(N, I): the side the eye sees.
    let nf = select(nn, -nn, dot(nn, i) > 0.0);
    let v = -i;
    var amb = vec3<f32>(0.0);
    var diff = vec3<f32>(0.0);
    var spec = vec3<f32>(0.0);
    for (var k = 0u; k < frame.n_lights; k++) {
        let l = lights[k];
        if l.kind == 0u { amb += l.color; continue; }
        var dir = -l.vec;
        var cl = l.color;
        if l.kind == 2u {
            let d = l.vec - p;
            cl = l.color / max(dot(d, d), 1.0e-20);
            dir = d;
        }
        let ld = normalize(dir);
        diff += cl * max(dot(nf, ld), 0.0);
        let h = normalize(ld + v);
        spec += cl * pow(max(dot(nf, h), 0.0), 1.0 / max(m.roughness, 1.0e-4));
    }
    if m.kind == 0u { return cs; }
    var c = cs * (m.ka * amb + m.kd * diff);
    if m.kind == 2u { c += m.specular * m.ks * spec; }
    // metal: no diffuse (Kd is 0), the highlight tinted by the surface colour.
    if m.kind == 3u { c += cs * m.ks * spec; }
    return c;
}

fn srgb_encode(x: f32) -> f32 {
    let c = clamp(x, 0.0, 1.0);
    if c <= 0.0031308 { return 12.92 * c; }
    return 1.055 * pow(c, 1.0 / 2.4) - 0.055;
}

// 10 bits per channel of sRGB-encoded colour; bit 30 marks a point seen from its back.
fn pack_color(c: vec3<f32>, back: bool) -> u32 {
    let r = u32(round(srgb_encode(c.x) * 1023.0));
    let g = u32(round(srgb_encode(c.y) * 1023.0));
    let b = u32(round(srgb_encode(c.z) * 1023.0));
    return r | (g << 10u) | (b << 20u) | select(0u, 1u << 30u, back);
}
