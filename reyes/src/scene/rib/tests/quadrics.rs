//! The quadric requests: arguments, the transform and orientation they are emitted with,
//! errors, and the field airplane's quadrics. (The geometry itself is checked against the
//! spec's equations in `scene/quadric/tests.rs`.)

use super::*;
use crate::scene::{Patch, eval_rational_bezier};

/// Samples of every patch: (position, geometric normal after `flip_normal`).
fn samples(s: &Scene) -> Vec<(DVec3, DVec3)> {
    let mut out = Vec::new();
    for p in &s.patches {
        for a in 0..=8 {
            for b in 0..=8 {
                let (pos, du, dv) =
                    eval_rational_bezier(&p.cp(), &p.w(), a as f64 / 8.0, b as f64 / 8.0);
                let n = du.cross(dv);
                out.push((pos, if p.flip_normal { -n } else { n }));
            }
        }
    }
    out
}

#[test]
fn each_quadric_request_makes_its_patches() {
    for (req, n) in [
        ("Sphere 1 -1 1 360", 8),
        ("Sphere [1 -1 1 360]", 8),
        ("Sphere 1 -0.5 0.5 180", 2),
        ("Cylinder 1 -1 1 360", 4),
        ("Cone 1 0.5 270", 3),
        ("Disk 0.2 1 -90", 1),
        ("Torus 1 0.25 0 360 360", 16),
        ("Paraboloid 1 0 1 360", 4),
        ("Hyperboloid 1 -1 -1 1 1 1 360", 4),
        ("Hyperboloid [0 0 0 1.3 0 0 360]", 4),
        // No area: nothing to draw, no error.
        ("Sphere 1 -1 1 0", 0),
        ("Cylinder 1 0.5 0.5 360", 0),
    ] {
        let s = parse(&world(req));
        assert_eq!(s.patches.len(), n, "{req}");
        assert!(s.warnings.is_empty(), "{req}: {:?}", s.warnings);
        for (k, p) in s.patches.iter().enumerate() {
            assert!(p.is_rational(), "{req}");
            assert!(p.w().iter().all(|&w| w > 0.0 && w <= 1.0), "{req}");
            assert_eq!((p.source.line, p.source.index), (2, k as u32));
        }
    }
    // The parameter list is read and ignored with a warning.
    let s = parse(&world(
        "Sphere 1 -1 1 360 \"Cs\" [1 0 0  0 1 0  0 0 1  1 1 1]",
    ));
    assert_eq!(s.patches.len(), 8);
    assert_eq!(
        s.warnings,
        ["t.rib:2: ignored parameter \"Cs\" of `Sphere`"]
    );
}

#[test]
fn quadrics_follow_the_transform_and_orientation() {
    let centre = DVec3::new(1.0, 2.0, 3.0);
    // Default orientation: outward; a mirroring transform flips RenderMan's current
    // orientation along with the coordinate system, so still outward; ReverseOrientation
    // turns it inward; so does a negative thetamax.
    for (before, sweep, outward) in [
        ("", 360, true),
        ("Scale 1 1 -1", 360, true),
        ("ReverseOrientation", 360, false),
        ("", -360, false),
        ("Scale -1 1 1\nReverseOrientation", -360, true),
    ] {
        let rib = world(&format!(
            "Translate 1 2 3\n{before}\nScale 2 2 2\nSphere 1 -1 1 {sweep}"
        ));
        let s = parse(&rib);
        assert_eq!(s.patches.len(), 8);
        for (pos, n) in samples(&s) {
            assert!(
                (pos.distance(centre) - 2.0).abs() < 1e-12,
                "{before}: {pos}"
            );
            if n.length() > 1e-9 {
                assert_eq!(
                    n.dot(pos - centre) > 0.0,
                    outward,
                    "{before} {sweep}: {pos}"
                );
            }
        }
    }
    // The disk faces +z of its object space, here turned to face -y.
    let s = parse(&world("Rotate 90 1 0 0\nDisk 0 1 360"));
    for (pos, n) in samples(&s) {
        assert!(
            pos.y.abs() < 1e-12 && n.dot(DVec3::NEG_Y) >= 0.0,
            "{pos} {n}"
        );
    }
}

#[test]
fn quadric_errors_name_the_line() {
    let e = err(&world("\nSphere 1 -1 1"));
    assert_eq!(
        e,
        "t.rib:3: `Sphere`: expected 4 numbers for radius zmin zmax thetamax, found 3"
    );
    let e = err(&world("Torus [1 0.5 0 360]"));
    assert_eq!(
        e,
        "t.rib:2: `Torus`: expected 5 numbers for majorradius minorradius phimin phimax \
         thetamax, found 4"
    );
    let e = err(&world("Paraboloid 1 0 0 360"));
    assert!(e.starts_with("t.rib:2: `Paraboloid`: zmax is 0"), "{e}");
    let e = err(&world("Paraboloid 1 -1 1 360"));
    assert!(e.contains("opposite sides of 0"), "{e}");
    let e = err("Sphere 1 -1 1 360\nWorldBegin\nWorldEnd\n");
    assert!(e.starts_with("t.rib:1: `Sphere`: geometry outside"), "{e}");
    let e = err(&world(
        "Scale 1e30 1e30 1e30\nScale 1e10 1 1\nSphere 1 -1 1 360",
    ));
    assert!(e.contains("beyond the f32 range"), "{e}");
}

/// The field airplane: every quadric request now gives patches, and it loads without a warning.
#[test]
fn field_airplane_quadrics_become_patches() {
    let path = crate::shared_data_dir().join("field/airplane.rib");
    let s = crate::scene::load(&path).unwrap();
    let text = std::fs::read_to_string(&path).unwrap();
    let names = [
        "Sphere",
        "Cylinder",
        "Cone",
        "Disk",
        "Torus",
        "Paraboloid",
        "Hyperboloid",
    ];
    for w in &s.warnings {
        assert!(!names.iter().any(|n| w.contains(n)), "{w}");
    }
    // Nor any other: its `Attribute "identifier"` names objects, which needs no warning.
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    let mut quadrics = 0;
    for (i, line) in text.lines().enumerate() {
        let first = line.split_whitespace().next().unwrap_or("");
        if names.contains(&first) {
            quadrics += 1;
            let line_no = i as u64 + 1;
            let n = s
                .patches
                .iter()
                .filter(|p| p.source.line == line_no)
                .count();
            assert!(n > 0, "line {line_no}: {line}");
            assert!(
                s.patches
                    .iter()
                    .filter(|p| p.source.line == line_no)
                    .all(Patch::is_rational)
            );
        }
    }
    assert_eq!(quadrics, 42);
    assert!(
        s.patches.iter().any(|p| !p.is_rational()),
        "the bezier patch meshes"
    );
}
