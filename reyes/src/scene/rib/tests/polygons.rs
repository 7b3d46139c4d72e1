//! `Polygon`, `GeneralPolygon`, `PointsPolygons`, `PointsGeneralPolygons`: their pieces, the
//! primitive variables each piece gets, and the errors of bad topology.

use super::*;
use crate::scene::{ColorField, eval_bezier};

/// Sum of the pieces' areas (each piece is planar: a bilinear patch's area is its two
/// triangles' when it is a parallelogram or a degenerate triangle, as these are).
fn area(s: &Scene) -> f64 {
    let tri = |a: DVec3, b: DVec3, c: DVec3| 0.5 * (b - a).cross(c - a).length();
    s.patches
        .iter()
        .map(|p| {
            let (c0, c1, c2, c3) = (p.cp()[0], p.cp()[3], p.cp()[12], p.cp()[15]);
            tri(c0, c1, c3) + tri(c0, c3, c2)
        })
        .sum()
}

#[test]
fn polygon_square_is_one_bilinear_patch() {
    let s = parse(&world("Polygon \"P\" [0 0 0  2 0 0  2 2 0  0 2 0]"));
    assert_eq!(s.patches.len(), 1);
    assert!((area(&s) - 4.0).abs() < 1e-12);
    let (p, du, dv) = eval_bezier(&s.patches[0].cp(), 0.5, 0.5);
    assert!(close(p, DVec3::new(1.0, 1.0, 0.0)));
    // The polygon's winding normal, +z.
    assert!(du.cross(dv).z > 0.0);
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
}

#[test]
fn points_polygons_share_points_and_cover_their_area() {
    // A 2x1 strip of two quads and a triangle on top: area 2 + 1.
    let s = parse(&world(
        "PointsPolygons [4 4 3] [0 1 4 3  1 2 5 4  3 4 6] \
         \"P\" [0 0 0  1 0 0  2 0 0  0 1 0  1 1 0  2 1 0  0 3 0]",
    ));
    assert_eq!(s.patches.len(), 3);
    assert!((area(&s) - 3.0).abs() < 1e-12, "{}", area(&s));
    // The shared edge (1,0)-(1,1) has bit-identical control points in both quads.
    let (a, b) = (&s.patches[0].cp(), &s.patches[1].cp());
    let right: Vec<DVec3> = [3, 7, 11, 15].iter().map(|&k| a[k]).collect();
    let left: Vec<DVec3> = [0, 4, 8, 12].iter().map(|&k| b[k]).collect();
    assert_eq!(right, left);
}

#[test]
fn general_polygon_cuts_its_hole() {
    let s = parse(&world(
        "GeneralPolygon [4 4] \"P\" [0 0 0  3 0 0  3 3 0  0 3 0   1 1 0  1 2 0  2 2 0  2 1 0]",
    ));
    assert!((area(&s) - 8.0).abs() < 1e-12, "{}", area(&s));
    let s = parse(&world(
        "PointsGeneralPolygons [2 1] [4 4 3] [0 1 2 3  4 5 6 7  0 1 2] \
         \"P\" [0 0 0  3 0 0  3 3 0  0 3 0   1 1 0  1 2 0  2 2 0  2 1 0]",
    ));
    assert!((area(&s) - 8.0 - 4.5).abs() < 1e-12, "{}", area(&s));
}

#[test]
fn colours_of_every_class_reach_the_pieces() {
    let quads = "PointsPolygons [4 3] [0 1 2 3  1 4 2] \
                 \"P\" [0 0 0  1 0 0  1 1 0  0 1 0  2 0 0]";
    let cs = |p: &crate::scene::Patch| p.primvars.as_ref().unwrap().cs.clone().unwrap();
    // uniform: one per face.
    let s = parse(&world(&format!(
        "{quads} \"uniform color Cs\" [1 0 0  0 1 0]"
    )));
    assert_eq!(cs(&s.patches[0]), ColorField::Flat(DVec3::X));
    assert_eq!(cs(&s.patches[1]), ColorField::Flat(DVec3::Y));
    // vertex (and varying): one per point, at the piece's corners (0,0) (1,0) (0,1) (1,1),
    // which run v0, v1, v3, v2 on a quad and v0, v1, v2, v2 on a triangle.
    let pts = "1 0 0  0 1 0  0 0 1  1 1 1  0.5 0.5 0.5";
    for class in ["vertex", "varying"] {
        let s = parse(&world(&format!("{quads} \"{class} color Cs\" [{pts}]")));
        assert_eq!(
            cs(&s.patches[0]),
            ColorField::Bilinear([DVec3::X, DVec3::Y, DVec3::ONE, DVec3::Z])
        );
        assert_eq!(
            cs(&s.patches[1]),
            ColorField::Bilinear([DVec3::Y, DVec3::splat(0.5), DVec3::Z, DVec3::Z])
        );
    }
    // facevarying: one per face corner, 4 + 3.
    let s = parse(&world(&format!(
        "{quads} \"facevarying color Cs\" [{pts}  0 0 0  0.25 0.25 0.25]"
    )));
    assert_eq!(
        cs(&s.patches[1]),
        ColorField::Bilinear([
            DVec3::splat(0.5),
            DVec3::ZERO,
            DVec3::splat(0.25),
            DVec3::splat(0.25)
        ])
    );
    // Counts are checked per class.
    let e = err(&world(&format!("{quads} \"uniform color Cs\" [1 0 0]")));
    assert!(e.contains("needs 2 values"), "{e}");
    let e = err(&world(&format!("{quads} \"facevarying color Cs\" [{pts}]")));
    assert!(e.contains("needs 7 values"), "{e}");
}

#[test]
fn bad_topology_is_an_error_naming_the_line() {
    for (body, want) in [
        (
            "PointsPolygons [4] [0 1 2] \"P\" [0 0 0 1 0 0 1 1 0]",
            "add up to 4, but 3",
        ),
        (
            "PointsPolygons [3] [0 1 2.5] \"P\" [0 0 0 1 0 0 1 1 0]",
            "not an integer",
        ),
        (
            "PointsPolygons [3] [0 1 -2] \"P\" [0 0 0 1 0 0 1 1 0]",
            "not an integer",
        ),
        (
            "PointsPolygons [3] [0 1 3] \"P\" [0 0 0 1 0 0 1 1 0]",
            "needs 12 numbers",
        ),
        (
            "PointsGeneralPolygons [2] [3] [0 1 2] \"P\" [0 0 0 1 0 0 1 1 0]",
            "add up to 2, but 1",
        ),
        ("Polygon \"Cs\" [1 1 1]", "missing the \"P\""),
    ] {
        let e = err(&world(body));
        assert!(e.starts_with("t.rib:2:"), "{e}");
        assert!(e.contains(want), "{body}: {e}");
    }
}

#[test]
fn short_loops_are_skipped_with_a_warning() {
    let s = parse(&world(
        "PointsPolygons [2 3] [0 1  0 1 2] \"P\" [0 0 0 1 0 0 1 1 0]",
    ));
    assert_eq!(s.patches.len(), 1);
    assert!(
        s.warnings.iter().any(|w| w.contains("fewer than 3")),
        "{:?}",
        s.warnings
    );
}

/// The exporters' file: a square, an archive's triangle and a smaller square, constant shaded.
#[test]
fn exporters_polygons_readarchive() {
    let path = crate::shared_data_dir().join("field/exporters/polygons/readarchive.rib");
    let s = crate::scene::load(&path).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(s.patches.len(), 3);
    assert!(
        !s.warnings.iter().any(|w| w.contains("Polygon")),
        "{:?}",
        s.warnings
    );
    let colors: Vec<DVec3> = s
        .patches
        .iter()
        .map(|p| s.materials[p.material as usize].color)
        .collect();
    assert_eq!(colors, [DVec3::ONE, DVec3::X, DVec3::new(1.0, 1.0, 0.0)]);
}

#[test]
fn normals_go_to_camera_space_as_normals() {
    // A non-uniform scale: a normal (1, 1, 0) of the object becomes (1/2, 1, 0) (inverse
    // transpose), not (2, 1, 0).
    let s = parse(&world(
        "Scale 2 1 1 Polygon \"P\" [0 0 0  1 0 0  1 1 0] \"N\" [1 1 0  1 1 0  1 1 0]",
    ));
    let n = s.patches[0].primvars.as_ref().unwrap().n.clone().unwrap();
    assert_eq!(n, ColorField::Bilinear([DVec3::new(0.5, 1.0, 0.0); 4]));
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    let s = parse(&world(
        "PointsPolygons [3 3] [0 1 2  0 2 3] \"P\" [0 0 0  1 0 0  1 1 0  0 1 0] \
         \"facevarying normal N\" [0 0 1  0 0 1  0 0 1  0 1 0  0 1 0  0 1 0]",
    ));
    let n = s.patches[1].primvars.as_ref().unwrap().n.clone().unwrap();
    assert_eq!(n, ColorField::Bilinear([DVec3::Y; 4]));
    let e = err(&world("Polygon \"P\" [0 0 0  1 0 0  1 1 0] \"N\" [0 0 1]"));
    assert!(e.contains("\"N\" (varying normal) needs 3 values"), "{e}");
}
