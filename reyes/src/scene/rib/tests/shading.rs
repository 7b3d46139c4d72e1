//! Surfaces, materials, lights, sides.

use super::*;
use crate::scene::{Light, Material, SurfaceKind};
use glam::DVec3;

#[test]
fn materials() {
    let s = parse(&world(&format!(
        "{QUAD}\nColor [1 0 0]\nOpacity .5 .5 .5\nSurface \"plastic\" \"Ks\" .8 \"uniform float roughness\" [.2] \"specularcolor\" [1 1 0]\n{QUAD}\n\
         Surface \"wood\"\n{QUAD}\nSurface \"constant\"\n{QUAD}\nSurface \"matte\" \"Kd\" .7\n{QUAD}\n\
         Surface \"plastic\" \"Ks\" .8 \"roughness\" .2 \"specularcolor\" [1 1 0]\n{QUAD}"
    )));
    let m = patch_materials(&s);
    assert_eq!(
        *m[0],
        Material::standard(SurfaceKind::Matte),
        "default surface: matte"
    );
    let plastic = Material {
        color: DVec3::new(1.0, 0.0, 0.0),
        opacity: DVec3::splat(0.5),
        ks: 0.8,
        roughness: 0.2,
        specular_color: DVec3::new(1.0, 1.0, 0.0),
        ..Material::standard(SurfaceKind::Plastic)
    };
    assert_eq!(*m[1], plastic);
    assert_eq!(
        s.patches[2].material, s.patches[1].material,
        "unknown shader keeps the surface"
    );
    assert_eq!(m[3].kind, SurfaceKind::Constant);
    assert_eq!(
        (m[4].kind, m[4].ka, m[4].kd),
        (SurfaceKind::Matte, 1.0, 0.7)
    );
    assert_eq!(
        s.patches[5].material, s.patches[1].material,
        "equal materials are shared"
    );
    assert_eq!(s.materials.len(), 4);
    assert!(s.warnings.iter().any(|w| w
        == "t.rib:7: skipped unsupported surface shader \"wood\" (keeping the previous surface)"));
    assert!(err(&world("Surface \"plastic\" \"Ks\" \"high\"")).contains("needs one finite number"));
    assert!(err(&world("Color [1 0]")).contains("expected 3 numbers"));
}

#[test]
fn lights() {
    let s = parse(&format!(
        "Rotate 90 0 1 0\nTranslate 0 0 5\n{}",
        world(
            "LightSource \"ambientlight\" 1 \"intensity\" .5 \"lightcolor\" [1 0 0]\n\
             LightSource \"distantlight\" 2\n\
             LightSource \"distantlight\" 3 \"from\" [0 0 0] \"to\" [0 -2 0] \"intensity\" 2\n\
             LightSource \"pointlight\" \"key\" \"from\" [1 2 3]\n\
             LightSource \"spotlight\" 5\n\
             LightSource \"pointlight\" 6"
        )
    ));
    assert_eq!(s.lights.len(), 5);
    assert_eq!(
        s.lights[0],
        Light::Ambient {
            color: DVec3::new(0.5, 0.0, 0.0)
        }
    );
    let Light::Distant { color, dir } = &s.lights[1] else {
        panic!()
    };
    // World +z, rotated 90 degrees about y: camera +x.
    assert!(*color == DVec3::ONE && close(*dir, DVec3::X), "{dir}");
    let Light::Distant { color, dir } = &s.lights[2] else {
        panic!()
    };
    assert!(*color == DVec3::splat(2.0) && close(*dir, -DVec3::Y));
    let Light::Point { pos, .. } = &s.lights[3] else {
        panic!()
    };
    // (1,2,3) + (0,0,5) = (1,2,8), then about y: (8, 2, -1).
    assert!(close(*pos, DVec3::new(8.0, 2.0, -1.0)), "{pos}");
    let Light::Point { pos, .. } = &s.lights[4] else {
        panic!()
    };
    assert!(close(*pos, DVec3::new(5.0, 0.0, 0.0)), "{pos}");
    assert!(
        s.warnings
            .iter()
            .any(|w| w.contains("light shader \"spotlight\""))
    );
    assert!(
        err(&world(
            "LightSource \"distantlight\" 1 \"from\" [1 1 1] \"to\" [1 1 1]"
        ))
        .contains("no direction")
    );
}

#[test]
fn sides() {
    let s = parse(&world(&format!("Sides 1\n{QUAD}\nSides 2\n{QUAD}")));
    assert!(!s.patches[0].two_sided && s.patches[1].two_sided);
    assert_eq!(
        err(&world("Sides 3")),
        "t.rib:2: `Sides`: sides must be 1 or 2, found 3"
    );
}

/// RenderMan's `metal` (Ka, Ks, roughness; no Kd): its parameters, its defaults (Ka 1, Ks 1,
/// roughness 0.1, no diffuse), and a `Kd` it does not have ignored with a warning.
#[test]
fn metal_surface() {
    let s = parse(&world(&format!(
        "Surface \"metal\" \"Ka\" .5 \"Ks\" .7 \"roughness\" .05\n{QUAD}\nSurface \"metal\" \"Kd\" .9\n{QUAD}"
    )));
    let m = patch_materials(&s);
    assert_eq!(
        *m[0],
        Material {
            ka: 0.5,
            ks: 0.7,
            roughness: 0.05,
            ..Material::standard(SurfaceKind::Metal)
        }
    );
    assert_eq!(
        (m[1].kind, m[1].ka, m[1].kd, m[1].ks, m[1].roughness),
        (SurfaceKind::Metal, 1.0, 0.0, 1.0, 0.1)
    );
    assert!(
        s.warnings.iter().any(|w| w.contains("Kd")),
        "{:?}",
        s.warnings
    );
}

/// `shinymetal` and `paintedplastic` without their texture are metal and plastic; their texture
/// parameters are ignored with a warning naming them.
#[test]
fn textured_standard_surfaces_without_textures() {
    let s = parse(&world(&format!(
        "Surface \"shinymetal\" \"Ks\" .6 \"Kr\" 1 \"texturename\" \"env.tx\"\n{QUAD}\n\
         Surface \"paintedplastic\" \"Kd\" .8 \"texturename\" \"grid.tx\"\n{QUAD}"
    )));
    let m = patch_materials(&s);
    assert_eq!((m[0].kind, m[0].ks), (SurfaceKind::Metal, 0.6));
    assert_eq!((m[1].kind, m[1].kd), (SurfaceKind::Plastic, 0.8));
    for p in ["Kr", "texturename"] {
        assert!(
            s.warnings.iter().any(|w| w.contains(p)),
            "{p}: {:?}",
            s.warnings
        );
    }
}

/// Each patch's material, in patch order.
fn patch_materials(s: &crate::scene::Scene) -> Vec<&Material> {
    s.patches
        .iter()
        .map(|p| &s.materials[p.material as usize])
        .collect()
}
