//! A deep scene made on demand: `layers` stacked screen-filling layers of bicubic patches, the
//! nearest in front, each hiding every layer behind it. What occlusion culling is for
//! (docs/reyes.md, *Occlusion culling*): without it the renderer splits, dices and shades
//! every layer; with it, about the front layer's work. Written as RIB text, so that the
//! tests, `reyes/examples/stacked_rib.rs` and `reyes render` read the same scene.

use std::fmt::Write;

/// Distance of the front layer from the eye (camera space).
pub const FRONT_Z: f64 = 4.0;
/// Distance between neighbouring layers.
pub const LAYER_GAP: f64 = 0.05;
/// Field of view of the scene's camera, degrees.
pub const FOV_DEG: f64 = 40.0;

/// The RIB of `layers` stacked layers (1..) at `width` x `height` pixels (`Format`), each a
/// grid of `per_side` x `per_side` bicubic patches that reaches 10% beyond the image on every
/// side at its depth. Each layer is gently wavy (its inner control points move along z by at
/// most a tenth of [`LAYER_GAP`], so neighbouring layers never meet) and has its own grey
/// matte colour; an ambient and a distant light.
pub fn stacked_rib(layers: u32, per_side: u32, width: u32, height: u32) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "# {layers} stacked screen-filling layers of {per_side}x{per_side} bicubic patches \
         (reyes::scene::stacked)"
    );
    let _ = writeln!(out, "Format {width} {height} 1");
    let _ = writeln!(out, "Projection \"perspective\" \"fov\" [{FOV_DEG}]");
    let _ = writeln!(out, "WorldBegin");
    let _ = writeln!(
        out,
        "LightSource \"ambientlight\" 1 \"intensity\" [0.3]\n\
         LightSource \"distantlight\" 2 \"intensity\" [0.8] \"from\" [0 0 0] \"to\" [0.3 -0.4 1]"
    );
    let _ = writeln!(out, "Surface \"matte\"");
    // Half the shorter side spans FOV / 2; the longer side in proportion.
    let t = (FOV_DEG.to_radians() / 2.0).tan();
    let (ax, ay) = if width >= height {
        (width as f64 / height as f64, 1.0)
    } else {
        (1.0, height as f64 / width as f64)
    };
    let n = per_side.max(1);
    for k in 0..layers {
        let z = FRONT_Z + k as f64 * LAYER_GAP;
        let (hx, hy) = (1.1 * z * t * ax, 1.1 * z * t * ay);
        let g = 0.3 + 0.6 * ((k * 37 % 101) as f64 / 100.0);
        let _ = writeln!(
            out,
            "Color [{g:.3} {:.3} {:.3}]",
            1.0 - g * 0.5,
            0.5 + g * 0.3
        );
        for pj in 0..n {
            for pi in 0..n {
                let mut p = Vec::with_capacity(48);
                for j in 0..4 {
                    for i in 0..4 {
                        let u = (pi as f64 + i as f64 / 3.0) / n as f64;
                        let v = (pj as f64 + j as f64 / 3.0) / n as f64;
                        // Inner control points bulge towards or away from the eye.
                        let inner = (1..3).contains(&i) && (1..3).contains(&j);
                        let bump = if inner {
                            0.1 * LAYER_GAP
                                * if (i + j + pi + pj + k) % 2 == 0 {
                                    1.0
                                } else {
                                    -1.0
                                }
                        } else {
                            0.0
                        };
                        p.extend([-hx + 2.0 * hx * u, -hy + 2.0 * hy * v, z + bump]);
                    }
                }
                let nums: Vec<String> = p.iter().map(|x| format!("{x:.6}")).collect();
                let _ = writeln!(out, "Patch \"bicubic\" \"P\" [{}]", nums.join(" "));
            }
        }
    }
    let _ = writeln!(out, "WorldEnd");
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The RIB reads back as layers x per_side^2 patches at the stated size.
    #[test]
    fn the_stacked_scene_reads_back() {
        let s = crate::scene::parse_rib(&stacked_rib(3, 2, 64, 48), "stacked.rib").unwrap();
        assert_eq!(s.patches.len(), 12);
        assert_eq!((s.width, s.height), (64, 48));
    }
}
