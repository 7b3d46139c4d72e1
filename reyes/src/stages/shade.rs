//! Twin of `shaders/reyes/shade.wgsl`: RenderMan's constant, matte, plastic and metal surfaces.

use crate::frame::{GpuLight, GpuMaterial};
use glam::Vec3;

/// `n` is the outside normal (unnormalised); `cs` the surface colour (the material's `Color`
/// or the patch's `"Cs"`), which the standard shaders multiply into ambient and diffuse light.
/// Returns linear RGB.
pub fn shade(p: Vec3, n: Vec3, m: &GpuMaterial, cs: Vec3, lights: &[GpuLight]) -> Vec3 {
    let i = p.normalize();
    let nn = n.normalize();
    let nf = if nn.dot(i) > 0.0 { -nn } else { nn };
    let v = -i;
    let (mut amb, mut diff, mut spec) = (Vec3::ZERO, Vec3::ZERO, Vec3::ZERO);
    for l in lights {
        let color = Vec3::from(l.color);
        if l.kind == 0 {
            amb += color;
            continue;
        }
        let mut dir = -Vec3::from(l.vec);
        let mut cl = color;
        if l.kind == 2 {
            let d = Vec3::from(l.vec) - p;
            cl = color / d.dot(d).max(1.0e-20);
            dir = d;
        }
        let ld = dir.normalize();
        diff += cl * nf.dot(ld).max(0.0);
        let h = (ld + v).normalize();
        spec += cl * nf.dot(h).max(0.0).powf(1.0 / m.roughness.max(1.0e-4));
    }
    if m.kind == 0 {
        return cs;
    }
    let mut c = cs * (m.ka * amb + m.kd * diff);
    if m.kind == 2 {
        c += Vec3::from(m.specular) * m.ks * spec;
    }
    // metal: no diffuse (Kd is 0), the highlight tinted by the surface colour.
    if m.kind == 3 {
        c += cs * m.ks * spec;
    }
    c
}

/// The sRGB transfer function (IEC 61966-2-1) of a linear value, clamped to [0, 1] first.
pub fn srgb_encode(x: f32) -> f32 {
    let c = x.clamp(0.0, 1.0);
    if c <= 0.0031308 {
        12.92 * c
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    }
}

/// The inverse of [`srgb_encode`]: linear value of an sRGB-encoded `x` in [0, 1].
pub fn srgb_decode(x: f32) -> f32 {
    if x <= 0.04045 {
        x / 12.92
    } else {
        ((x + 0.055) / 1.055).powf(2.4)
    }
}

/// 10 bits per channel of sRGB-encoded colour; bit 30 marks a point seen from its back.
pub fn pack_color(c: Vec3, back: bool) -> u32 {
    let q = |x: f32| (srgb_encode(x) * 1023.0).round() as u32;
    q(c.x) | q(c.y) << 10 | q(c.z) << 20 | (back as u32) << 30
}
