//! `Displacement` and `Attribute "displacementbound"`.

use super::*;
use crate::scene::DisplacementPattern;

#[test]
fn displacement_and_its_bound_follow_the_attributes() {
    let s = parse(&world(&format!(
        "{QUAD}\nAttributeBegin\nDisplacement \"bumps\" \"Km\" 0.25\n{QUAD}\n\
         Attribute \"displacementbound\" \"sphere\" [2] \"coordinatesystem\" [\"object\"]\n\
         Scale 3 3 3\n{QUAD}\nAttributeEnd\n{QUAD}\nDisplacement \"bumps\" \"frequency\" 3\n{QUAD}"
    )));
    assert!(s.patches[0].displacement.is_none(), "none by default");
    let d = s.patches[1].displacement.as_ref().unwrap();
    assert_eq!(d.pattern, DisplacementPattern::Bumps { frequency: 1 });
    assert_eq!((d.amount, d.bound), (0.25, 0.25), "bound at least |amount|");
    // Scaled by 3: the amount by the mean scale, the declared radius by the largest stretch.
    let d = s.patches[2].displacement.as_ref().unwrap();
    assert!((d.amount - 0.75).abs() < 1e-12, "{}", d.amount);
    assert!(
        (d.bound - 6.0).abs() < 1e-4 && d.bound >= 6.0,
        "{}",
        d.bound
    );
    assert!(s.patches[3].displacement.is_none(), "AttributeEnd restores");
    let d = s.patches[4].displacement.as_ref().unwrap();
    assert_eq!((d.amount, d.bound), (1.0, 1.0), "Km defaults to 1");
    assert_eq!(d.pattern, DisplacementPattern::Bumps { frequency: 3 });
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
}

/// A bound in world or camera space is taken to camera space where it is given.
#[test]
fn a_bound_in_world_or_camera_space() {
    let s = parse(&format!(
        "Scale 2 2 2\n{}",
        world(&format!(
            "Displacement \"bumps\" \"Km\" 0.1\nScale 5 5 5\n\
             Attribute \"displacementbound\" \"sphere\" [1] \"coordinatesystem\" [\"world\"]\n{QUAD}\n\
             Attribute \"displacementbound\" \"sphere\" [1] \"coordinatesystem\" \"camera\"\n{QUAD}"
        ))
    ));
    let b: Vec<f64> = (s.patches.iter())
        .map(|p| p.displacement.as_ref().unwrap().bound)
        .collect();
    assert!((b[0] - 2.0).abs() < 1e-5 && b[0] >= 2.0, "world: {}", b[0]);
    // Km 0.1 at a scale of 10 is 1: the larger of the two.
    assert!((b[1] - 1.0).abs() < 1e-9, "camera: {}", b[1]);
}

#[test]
fn unknown_displacements_and_attributes_are_skipped_with_a_warning() {
    let s = parse(&world(&format!(
        "Displacement \"dented\" \"Km\" 2\nAttribute \"render\" \"integer diffuse\" [1]\n\
         Attribute \"identifier\" \"name\" \"x\"\n{QUAD}"
    )));
    assert!(s.patches[0].displacement.is_none());
    // `identifier` names the object and changes nothing in the image: no warning for it.
    assert_eq!(s.warnings.len(), 2, "{:?}", s.warnings);
    assert!(s.warnings[0].contains("t.rib:2") && s.warnings[0].contains("\"dented\""));
    assert!(s.warnings[1].contains("t.rib:3") && s.warnings[1].contains("\"render\""));
}

#[test]
fn bad_displacement_values_are_errors_naming_the_line() {
    let e = err(&world("Displacement \"bumps\" \"Km\" \"big\""));
    assert!(e.contains("t.rib:2") && e.contains("\"Km\""), "{e}");
    let e = err(&world("Displacement \"bumps\" \"Km\" 1e300"));
    assert!(e.contains("t.rib:2") && e.contains("f32"), "{e}");
    for f in ["0", "2.5", "65"] {
        let e = err(&world(&format!("Displacement \"bumps\" \"frequency\" {f}")));
        assert!(e.contains("t.rib:2") && e.contains("frequency"), "{e}");
    }
    let e = err(&world("Displacement \"mapped\" \"Km\" 1"));
    assert!(e.contains("t.rib:2") && e.contains("mapname"), "{e}");
    let e = err(&world(
        "Displacement \"mapped\" \"mapname\" \"no-such-map.png\"",
    ));
    assert!(
        e.contains("t.rib:2") && e.contains("no-such-map.png"),
        "{e}"
    );
    let e = err(&world("\nAttribute \"displacementbound\" \"sphere\" [-1]"));
    assert!(e.contains("t.rib:3") && e.contains("sphere"), "{e}");
    let e = err(&world("Attribute \"displacementbound\" \"sphere\" [1 2]"));
    assert!(e.contains("t.rib:2") && e.contains("sphere"), "{e}");
    let e = err(&world(
        "Attribute \"displacementbound\" \"sphere\" 1 \"coordinatesystem\" \"raster\"",
    ));
    assert!(e.contains("t.rib:2") && e.contains("\"world\""), "{e}");
}

/// A PNG map is read once, as luminance in [0, 1], row-major from the top row.
#[test]
fn a_png_map_is_read_as_luminance() {
    let dir = tempfile::tempdir().unwrap();
    let png = dir.path().join("ramp.png");
    let img = image::GrayImage::from_fn(4, 2, |x, y| image::Luma([(x * 80 + y) as u8]));
    img.save(&png).unwrap();
    let rib = dir.path().join("scene.rib");
    let text = world(&format!(
        "Displacement \"mapped\" \"mapname\" \"ramp.png\" \"Km\" 0.5\n{QUAD}\n{QUAD}"
    ));
    std::fs::write(&rib, &text).unwrap();
    let s = parse_rib(&text, rib.to_str().unwrap()).unwrap();
    let (a, b) = (
        s.patches[0].displacement.as_ref().unwrap(),
        s.patches[1].displacement.as_ref().unwrap(),
    );
    let (DisplacementPattern::Map(ma), DisplacementPattern::Map(mb)) = (&a.pattern, &b.pattern)
    else {
        panic!("a map")
    };
    assert!(std::sync::Arc::ptr_eq(ma, mb), "one map for both");
    assert_eq!((ma.width, ma.height), (4, 2));
    for (k, t) in ma.texels.iter().enumerate() {
        let want = ((k % 4) * 80 + k / 4) as f32 / 255.0;
        assert!((t - want).abs() < 1e-6, "texel {k}: {t} vs {want}");
    }
}

/// An OpenEXR map is read through the same path: luminance, clamped to [0, 1].
#[test]
fn an_exr_map_is_read_and_clamped() {
    let dir = tempfile::tempdir().unwrap();
    let exr = dir.path().join("height.exr");
    let values = [0.0f32, 0.25, 0.5, 2.0];
    let img = image::Rgb32FImage::from_fn(4, 1, |x, _| image::Rgb([values[x as usize]; 3]));
    img.save(&exr).unwrap();
    let rib = dir.path().join("scene.rib");
    let text = world(&format!(
        "Displacement \"mapped\" \"mapname\" \"height.exr\"\n{QUAD}"
    ));
    let s = parse_rib(&text, rib.to_str().unwrap()).unwrap();
    let DisplacementPattern::Map(m) = &s.patches[0].displacement.as_ref().unwrap().pattern else {
        panic!("a map")
    };
    assert_eq!((m.width, m.height), (4, 1));
    for (t, want) in m.texels.iter().zip([0.0, 0.25, 0.5, 1.0]) {
        assert!((t - want).abs() < 1e-3, "{t} vs {want}");
    }
}
