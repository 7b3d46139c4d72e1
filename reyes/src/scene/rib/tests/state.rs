//! Options, transformations, attribute and transform blocks, orientation.

use super::*;
use crate::scene::eval_bezier;
use glam::DVec3;

#[test]
fn defaults() {
    let s = parse("WorldBegin WorldEnd");
    assert_eq!((s.width, s.height), (640, 480));
    assert_eq!(s.pixel_samples, (2, 2));
    assert_eq!(
        s.camera,
        crate::scene::Camera {
            fov_deg: 90.0,
            near: 1e-10,
            far: 1e38,
            ..Default::default()
        }
    );
    assert!(s.patches.is_empty() && s.lights.is_empty() && s.warnings.is_empty());
}

#[test]
fn options() {
    let s = parse(&format!(
        "Format 320 200 1\nPixelSamples 3 1.5\nProjection \"perspective\" \"fov\" [40]\n\
         Clipping 0.5 100\n{}",
        world("")
    ));
    assert_eq!((s.width, s.height), (320, 200));
    assert_eq!(s.pixel_samples, (3, 2));
    assert_eq!(
        s.camera,
        crate::scene::Camera {
            fov_deg: 40.0,
            near: 0.5,
            far: 100.0,
            ..Default::default()
        }
    );
    let s = parse(&format!(
        "Projection \"perspective\" \"fov\" 35 {}",
        world("")
    ));
    assert_eq!(s.camera.fov_deg, 35.0);
    // No fov: RenderMan's 90.
    let s = parse(&format!("Projection \"perspective\" {}", world("")));
    assert_eq!(s.camera.fov_deg, 90.0);
}

#[test]
fn option_errors() {
    let e = err(&format!("\nProjection \"fisheye\"\n{}", world("")));
    assert_eq!(
        e,
        "t.rib:2: `Projection`: projection \"fisheye\" is not supported (only \"perspective\" and \"orthographic\")"
    );
    assert!(err("Projection \"perspective\" \"fov\" 0 WorldBegin WorldEnd").contains("fov 0"));
    assert!(
        err("Format 640 0 1 WorldBegin WorldEnd")
            .starts_with("t.rib:1: `Format`: the y resolution")
    );
    assert!(err("Format 640 480.5 1 WorldBegin WorldEnd").contains("integer"));
    assert!(err("Clipping 10 1 WorldBegin WorldEnd").contains("near < far"));
    assert!(err("PixelSamples 0 1 WorldBegin WorldEnd").contains("sample count"));
    assert!(err("WorldBegin Projection \"perspective\" WorldEnd").contains("inside"));
}

#[test]
fn transforms_apply_last_first() {
    // Translate then Scale: points are scaled first, then translated.
    let s = parse(&world(&format!("Translate 1 0 0\nScale 2 2 2\n{QUAD}")));
    let cp = &s.patches[0].cp();
    assert!(close(cp[3], DVec3::new(3.0, 0.0, 0.0)), "{}", cp[3]);
    assert!(close(cp[12], DVec3::new(1.0, 2.0, 0.0)));
    let s = parse(&world(&format!("Scale 2 2 2\nTranslate 1 0 0\n{QUAD}")));
    assert!(close(s.patches[0].cp()[3], DVec3::new(4.0, 0.0, 0.0)));
}

#[test]
fn rotate_convention() {
    let s = parse(&world(&format!("Rotate 90 0 0 1\n{QUAD}")));
    assert!(
        close(s.patches[0].cp()[3], DVec3::new(0.0, 1.0, 0.0)),
        "x -> y about z"
    );
    let s = parse(&world(&format!("Rotate 90 1 0 0\n{QUAD}")));
    assert!(
        close(s.patches[0].cp()[12], DVec3::new(0.0, 0.0, 1.0)),
        "y -> z about x"
    );
    let s = parse(&world(&format!("Rotate 90 0 2 0\n{QUAD}")));
    assert!(
        close(s.patches[0].cp()[3], DVec3::new(0.0, 0.0, -1.0)),
        "x -> -z about y"
    );
    assert!(err(&world("Rotate 30 0 0 0")).contains("axis is zero"));
}

#[test]
fn camera_transform_and_identity_in_world() {
    let s = parse(&format!(
        "Translate 0 0 5\n{}",
        world(&format!("Translate 1 0 0\nIdentity\n{QUAD}"))
    ));
    assert!(close(s.patches[0].cp()[0], DVec3::new(0.0, 0.0, 5.0)));
    // Before WorldBegin, Identity really is the identity.
    let s = parse(&format!(
        "Translate 0 0 5 Identity Translate 0 0 2\n{}",
        world(QUAD)
    ));
    assert!(close(s.patches[0].cp()[0], DVec3::new(0.0, 0.0, 2.0)));
}

#[test]
fn transform_matrices_are_row_vector_order() {
    let m = "[1 0 0 0  0 1 0 0  0 0 1 0  10 20 30 1]";
    // Transform inside the world block is relative to world space.
    let s = parse(&format!(
        "Translate 0 0 5\n{}",
        world(&format!("Translate 7 7 7\nTransform {m}\n{QUAD}"))
    ));
    assert!(close(s.patches[0].cp()[0], DVec3::new(10.0, 20.0, 35.0)));
    let s = parse(&format!(
        "Translate 0 0 5\n{}",
        world(&format!("Scale 2 2 2\nConcatTransform {m}\n{QUAD}"))
    ));
    assert!(close(s.patches[0].cp()[0], DVec3::new(20.0, 40.0, 65.0)));
    // A non-symmetric linear part: the first row is where x goes.
    let s = parse(&world(&format!(
        "ConcatTransform [0 1 0 0  -1 0 0 0  0 0 1 0  0 0 0 1]\n{QUAD}"
    )));
    assert!(close(s.patches[0].cp()[3], DVec3::new(0.0, 1.0, 0.0)));
    assert!(
        err(&world("Transform [1 0 0 0 0 1 0 0 0 0 1 0 0 0 0]")).contains("expected 16 numbers")
    );
}

#[test]
fn transform_and_attribute_blocks() {
    let s = parse(&world(&format!(
        "TransformBegin\nTranslate 5 0 0\nColor [1 0 0]\nTransformEnd\n{QUAD}\n\
         AttributeBegin\nTranslate 0 3 0\nColor [0 1 0]\nSides 1\nReverseOrientation\n{QUAD}\nAttributeEnd\n{QUAD}"
    )));
    let [a, b, c] = [&s.patches[0], &s.patches[1], &s.patches[2]];
    assert!(
        close(a.cp()[0], DVec3::ZERO),
        "TransformEnd restores the transform"
    );
    assert_eq!(
        s.materials[a.material as usize].color,
        DVec3::new(1.0, 0.0, 0.0),
        "but not attributes"
    );
    assert!(close(b.cp()[0], DVec3::new(0.0, 3.0, 0.0)));
    assert_eq!(
        s.materials[b.material as usize].color,
        DVec3::new(0.0, 1.0, 0.0)
    );
    assert!(!b.two_sided && b.flip_normal);
    assert!(close(c.cp()[0], DVec3::ZERO));
    assert_eq!(c.material, a.material);
    assert!(c.two_sided && !c.flip_normal);
    assert_eq!(s.materials.len(), 2);
}

#[test]
fn orientation_and_handedness() {
    let flips = |body: &str| parse(&world(&format!("{body}\n{QUAD}"))).patches[0].flip_normal;
    assert!(!flips(""));
    assert!(flips("ReverseOrientation"));
    assert!(!flips("ReverseOrientation ReverseOrientation"));
    assert!(flips("Orientation \"rh\""));
    assert!(!flips("Orientation \"lh\""));
    assert!(!flips("Orientation \"outside\""));
    assert!(flips("Orientation \"inside\""));
    // A mirror flips the current orientation along with the coordinate system...
    assert!(flips("Scale -1 1 1"));
    assert!(!flips("Scale -1 1 1 Scale 1 -1 1"));
    // ... so "outside" and "inside" then mean rh and lh.
    assert!(flips("Scale -1 1 1 Orientation \"outside\""));
    assert!(!flips("Scale -1 1 1 Orientation \"inside\""));
    // Explicit lh/rh are absolute.
    assert!(!flips("Scale -1 1 1 Orientation \"lh\""));
    // Restoring a transform restores the handedness, and the orientation with it.
    assert!(!flips("TransformBegin Scale 1 1 -1 TransformEnd"));
    assert!(flips(
        "TransformBegin Scale 1 1 -1 TransformEnd ReverseOrientation"
    ));
    // A mirrored camera transform counts too (killeroo.rib's Transform).
    let s = parse(&format!("Scale 1 1 -1\n{}", world(QUAD)));
    assert!(s.patches[0].flip_normal);
    assert!(err(&world("Orientation \"up\"")).contains("not one of"));
}

#[test]
fn mirrored_patch_keeps_its_outside() {
    // The outside normal of a mirror image is the mirror image of the outside normal.
    let outside = |body: &str| {
        let s = parse(&world(&format!("{body}\n{QUAD}")));
        let (_, du, dv) = eval_bezier(&s.patches[0].cp(), 0.5, 0.5);
        let n = du.cross(dv).normalize();
        if s.patches[0].flip_normal { -n } else { n }
    };
    let n = outside("");
    // Unflipped, the quad (counter-clockwise on screen) faces away from the camera: the
    // spec's left-handed rule (clockwise vertices face the viewer).
    assert!(close(n, DVec3::Z));
    assert!(
        close(outside("Scale -1 1 1"), DVec3::Z),
        "x mirror keeps a z normal"
    );
    assert!(
        close(outside("Scale 1 1 -1"), -DVec3::Z),
        "z mirror mirrors it"
    );
}

/// `Skew 45` of y towards x shears x by y (BMRT's and Pixie's matrix): the quad's corner at
/// y = 1 moves by +1 in x; other transforms still apply around it. A skew that would reach
/// its second vector, or of parallel vectors, is an error at its line.
#[test]
fn skew_shears_along_the_second_vector() {
    let s = parse(&world(&format!(
        "Translate 0 0 5\nSkew 45 0 1 0 1 0 0\n{QUAD}"
    )));
    let cp = s.patches[0].cp();
    assert!(close(cp[0], DVec3::new(0.0, 0.0, 5.0)), "{:?}", cp[0]);
    assert!(close(cp[3], DVec3::new(1.0, 0.0, 5.0)), "{:?}", cp[3]);
    assert!(close(cp[12], DVec3::new(1.0, 1.0, 5.0)), "{:?}", cp[12]);
    assert!(close(cp[15], DVec3::new(2.0, 1.0, 5.0)), "{:?}", cp[15]);
    // Turning y by -45 degrees (away from x) shears the other way.
    let s = parse(&world(&format!("Skew -45 0 1 0 1 0 0\n{QUAD}")));
    assert!(close(s.patches[0].cp()[12], DVec3::new(-1.0, 1.0, 0.0)));
    for bad in [
        "Skew 90 0 1 0 1 0 0",
        "Skew 10 1 0 0 2 0 0",
        "Skew 10 0 1 0 0 0 0",
    ] {
        let e = err(&world(&format!("{bad}\n{QUAD}")));
        assert!(
            e.starts_with("t.rib:2:") && e.contains("no shear"),
            "{bad}: {e}"
        );
    }
}
