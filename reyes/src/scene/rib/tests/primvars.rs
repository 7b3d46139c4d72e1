//! `Declare` and the `"Cs"` / `"Os"` primitive variables of Patch, PatchMesh and NuPatch:
//! classes, counts, and the colour field each emitted patch gets.

use super::*;
use crate::scene::{ColorField, Patch};
use glam::DVec3;

fn cs(p: &Patch) -> &ColorField {
    p.primvars.as_ref().unwrap().cs.as_ref().unwrap()
}

fn os(p: &Patch) -> &ColorField {
    p.primvars.as_ref().unwrap().os.as_ref().unwrap()
}

/// `n` colours as RIB numbers: colour k is (k, 10 k, 100 k) / 1000, so each is distinct.
fn colors(n: usize) -> (Vec<DVec3>, String) {
    let c: Vec<DVec3> = (0..n)
        .map(|k| DVec3::new(k as f64, 10.0 * k as f64, 100.0 * k as f64) / 1000.0)
        .collect();
    let s = c
        .iter()
        .map(|c| format!("{} {} {}", c.x, c.y, c.z))
        .collect::<Vec<_>>()
        .join(" ");
    (c, s)
}

/// The uniform cubic B-spline weights at t (independent of `Basis`).
fn bspline(t: f64) -> [f64; 4] {
    let s = 1.0 - t;
    [
        s * s * s / 6.0,
        (3.0 * t * t * t - 6.0 * t * t + 4.0) / 6.0,
        (-3.0 * t * t * t + 3.0 * t * t + 3.0 * t + 1.0) / 6.0,
        t * t * t / 6.0,
    ]
}

#[test]
fn varying_cs_on_a_patch_is_bilinear_between_its_corners() {
    let s = parse(&world(&format!(
        "{QUAD} \"Cs\" [1 0 0  0 1 0  0 0 1  1 1 1]"
    )));
    let p = &s.patches[0];
    assert_eq!(
        *cs(p),
        ColorField::Bilinear([DVec3::X, DVec3::Y, DVec3::Z, DVec3::ONE])
    );
    assert!(p.primvars.as_ref().unwrap().os.is_none());
    assert!(close(cs(p).eval(0.5, 0.5), DVec3::splat(0.5)));
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    // Without primitive variables a patch carries nothing.
    assert!(parse(&world(QUAD)).patches[0].primvars.is_none());
}

#[test]
fn classes_come_from_inline_declarations_then_declare_then_varying() {
    let flat = ColorField::Flat(DVec3::new(0.2, 0.4, 0.6));
    let s = parse(&world(&format!(
        "{QUAD} \"constant color Cs\" [0.2 0.4 0.6] \"uniform color Os\" [0.5 0.5 0.5]"
    )));
    assert_eq!(*cs(&s.patches[0]), flat);
    assert_eq!(*os(&s.patches[0]), ColorField::Flat(DVec3::splat(0.5)));
    // Declare holds for the rest of the file, across blocks; an inline declaration wins.
    let s = parse(&format!(
        "Declare \"Cs\" \"uniform color\"\n{}",
        world(&format!(
            "AttributeBegin\n{QUAD} \"Cs\" [0.2 0.4 0.6]\nAttributeEnd\n\
             {QUAD} \"Cs\" [0.2 0.4 0.6]\n{QUAD} \"varying color Cs\" [1 0 0 0 1 0 0 0 1 1 1 1]"
        ))
    ));
    assert_eq!(*cs(&s.patches[0]), flat);
    assert_eq!(*cs(&s.patches[1]), flat);
    assert!(matches!(cs(&s.patches[2]), ColorField::Bilinear(_)));
    // Vertex on a bilinear patch: 4 values, bilinear like the positions.
    let s = parse(&world(&format!(
        "{QUAD} \"vertex color Cs\" [1 0 0  0 1 0  0 0 1  1 1 1]"
    )));
    assert_eq!(
        *cs(&s.patches[0]),
        ColorField::Bilinear([DVec3::X, DVec3::Y, DVec3::Z, DVec3::ONE])
    );
}

#[test]
fn wrong_counts_and_types_are_errors_naming_the_line_and_the_count() {
    let e = err(&world(&format!("\n{QUAD} \"Cs\" [1 0 0  0 1 0  0 0 1]")));
    assert_eq!(
        e,
        "t.rib:3: `Patch`: \"Cs\" (varying color) needs 4 values (12 numbers), found 9 numbers"
    );
    let e = err(&world(&format!(
        "{QUAD} \"constant color Os\" [1 0 0  0 1 0]"
    )));
    assert!(
        e.starts_with("t.rib:2: `Patch`: \"Os\" (constant color) needs 1 value (3 numbers)"),
        "{e}"
    );
    let (_, p16) = grid_numbers(4, 4);
    let e = err(&world(&format!(
        "Patch \"bicubic\" \"P\" [{p16}] \"vertex color Cs\" [1 0 0  0 1 0  0 0 1  1 1 1]"
    )));
    assert!(
        e.contains("\"Cs\" (vertex color) needs 16 values (48 numbers), found 12"),
        "{e}"
    );
    let e = err(&world(&format!("{QUAD} \"varying float Cs\" [1 0 0 1]")));
    assert!(e.contains("\"Cs\" must be a color, found float"), "{e}");
    let e = err(&world(&format!(
        "{QUAD} \"Cs\" [1 0 0 0 1 0 0 0 1 1 1 1e300]"
    )));
    assert!(e.contains("value 3 of \"Cs\" (1e300) is not finite"), "{e}");
    let e = err(&world(&format!(
        "{QUAD} \"constant color Cs\" [1 0 0] \"Cs\" [1 0 0]"
    )));
    assert!(e.contains("\"Cs\" given twice"), "{e}");
    // An unreadable Declare is skipped with a warning; the name keeps its class.
    let s = parse(&format!(
        "Declare \"Cs\" \"sometimes color\"\n{}",
        world(&format!("{QUAD} \"Cs\" [1 0 0  0 1 0  0 0 1  1 1 1]"))
    ));
    assert!(
        s.warnings[0].starts_with("t.rib:1: skipped `Declare` of \"Cs\""),
        "{:?}",
        s.warnings
    );
}

#[test]
fn declarations_parse_as_the_spec_writes_them() {
    use super::super::primvars::{Class, parse_decl};
    let d = parse_decl("color").unwrap();
    assert_eq!(
        (d.class, d.ty.as_str(), d.len),
        (Class::Uniform, "color", 1)
    );
    let d = parse_decl("vertex point").unwrap();
    assert_eq!((d.class, d.ty.as_str()), (Class::Vertex, "point"));
    let d = parse_decl("  varying  float[2] ").unwrap();
    assert_eq!(
        (d.class, d.ty.as_str(), d.len),
        (Class::Varying, "float", 2)
    );
    let d = parse_decl("facevarying float [3]").unwrap();
    assert_eq!((d.class, d.len), (Class::FaceVarying, 3));
    assert!(parse_decl("varying").is_err());
    assert!(parse_decl("float[0]").is_err());
    assert!(parse_decl("uniform colour").is_err());
}

/// Vertex values go through the patch's basis like the positions: given the positions as
/// colours, the field's coefficients are the patch's Bezier control points, and the field is
/// the B-spline of the values.
#[test]
fn vertex_cs_is_converted_like_the_positions() {
    let (pts, nums) = grid_numbers(4, 4);
    let s = parse(&world(&format!(
        "Basis \"b-spline\" 1 \"b-spline\" 1\n\
         Patch \"bicubic\" \"P\" [{nums}] \"vertex color Cs\" [{nums}]"
    )));
    let p = &s.patches[0];
    assert_eq!(*cs(p), ColorField::Bezier(p.cp()));
    for (u, v) in [(0.0, 0.0), (0.3, 0.8), (1.0, 0.5)] {
        let (wu, wv) = (bspline(u), bspline(v));
        let want: DVec3 = (0..16).map(|k| pts[k] * (wu[k % 4] * wv[k / 4])).sum();
        assert!(close(cs(p).eval(u, v), want), "({u}, {v})");
    }
}

#[test]
fn patch_mesh_classes_count_sub_patches_and_corners() {
    // Bilinear 4 x 3 nonperiodic: 3 x 2 patches, 4 x 3 corners.
    let (_, p) = grid_numbers(4, 3);
    let mesh = |params: &str| {
        format!("PatchMesh \"bilinear\" 4 \"nonperiodic\" 3 \"nonperiodic\" \"P\" [{p}] {params}")
    };
    let (u, nums) = colors(6);
    let s = parse(&world(&mesh(&format!("\"uniform color Cs\" [{nums}]"))));
    assert_eq!(s.patches.len(), 6);
    for (k, patch) in s.patches.iter().enumerate() {
        assert_eq!(*cs(patch), ColorField::Flat(u[k]), "patch {k}");
    }
    let e = err(&world(&mesh("\"uniform color Cs\" [1 0 0  0 1 0]")));
    assert!(
        e.starts_with(
            "t.rib:2: `PatchMesh`: \"Cs\" (uniform color) needs 6 values (18 numbers), found 6 \
             numbers"
        ),
        "{e}"
    );
    let (c, nums) = colors(12);
    let s = parse(&world(&mesh(&format!("\"Cs\" [{nums}]"))));
    // Patch (pu, pv) = (2, 1) has corners at columns 2, 3 of rows 1, 2.
    assert_eq!(
        *cs(&s.patches[5]),
        ColorField::Bilinear([c[6], c[7], c[10], c[11]])
    );
    // Vertex values of a bilinear mesh are its control points: the positions as colours.
    let s = parse(&world(&mesh(&format!("\"vertex color Cs\" [{p}]"))));
    for patch in &s.patches {
        for (u, v) in [(0.0, 0.0), (0.5, 0.25), (1.0, 1.0)] {
            assert!(close(
                cs(patch).eval(u, v),
                crate::scene::eval_bezier(&patch.cp(), u, v).0
            ));
        }
    }
}

#[test]
fn periodic_patch_mesh_varying_wraps_to_the_first_corners() {
    // B-spline, 6 points periodic in u (6 patches, 6 corners per row), 5 nonperiodic in v
    // (2 patches, 3 corner rows): 18 varying values, 12 uniform ones.
    let (pts, p) = grid_numbers(6, 5);
    let mesh = |params: &str| {
        format!(
            "Basis \"b-spline\" 1 \"b-spline\" 1\n\
             PatchMesh \"bicubic\" 6 \"periodic\" 5 \"nonperiodic\" \"P\" [{p}] {params}"
        )
    };
    let (c, nums) = colors(18);
    let s = parse(&world(&mesh(&format!("\"Cs\" [{nums}]"))));
    assert_eq!(s.patches.len(), 12);
    // The last patch of the second row, (5, 1): its right corners wrap to column 0.
    assert_eq!(
        *cs(&s.patches[11]),
        ColorField::Bilinear([c[11], c[6], c[17], c[12]])
    );
    let e = err(&world(&mesh(&format!("\"Cs\" [{}]", colors(21).1))));
    assert!(e.contains("needs 18 values (54 numbers), found 63"), "{e}");
    let (_, nums) = colors(12);
    assert_eq!(
        parse(&world(&mesh(&format!("\"uniform color Os\" [{nums}]"))))
            .patches
            .len(),
        12
    );
    // Vertex: the positions as colours give the patches' own control points (wrapping too).
    let s = parse(&world(&mesh(&format!("\"vertex color Cs\" [{p}]"))));
    for patch in &s.patches {
        assert_eq!(*cs(patch), ColorField::Bezier(patch.cp()));
    }
    // And that is the B-spline of the values: patch (0, 0) at (u, v).
    let (wu, wv) = (bspline(0.3), bspline(0.6));
    let want: DVec3 = (0..16)
        .map(|k| pts[(k / 4) * 6 + k % 4] * (wu[k % 4] * wv[k / 4]))
        .sum();
    assert!(close(cs(&s.patches[0]).eval(0.3, 0.6), want));
}

#[test]
fn nu_patch_classes_follow_segments_and_knot_spans() {
    // 6 x 4 cubic: u knots [0 0 0 0 1 1 2 2 2 2] have 3 segments, the middle one empty, so
    // 2 patches; v has 1 segment. u range [0.5, 2] cuts the first span to [0.5, 1].
    let (_, p) = grid_numbers(6, 4);
    let nu = |params: &str| {
        format!(
            "NuPatch 6 4 [0 0 0 0 1 1 2 2 2 2] 0.5 2 4 4 [0 0 0 0 1 1 1 1] 0 1 \"P\" [{p}] {params}"
        )
    };
    let (c, nums) = colors(3);
    let s = parse(&world(&nu(&format!("\"uniform color Cs\" [{nums}]"))));
    assert_eq!(s.patches.len(), 2);
    assert_eq!(*cs(&s.patches[0]), ColorField::Flat(c[0]));
    assert_eq!(*cs(&s.patches[1]), ColorField::Flat(c[2]));
    // Varying: (2 + 6 - 4) x (2 + 4 - 4) = 4 x 2 corners, bilinear per segment.
    let (c, nums) = colors(8);
    let s = parse(&world(&nu(&format!("\"Os\" [{nums}]"))));
    let seg0 = ColorField::Bilinear([c[0], c[1], c[4], c[5]]);
    for (u, v) in [(0.0, 0.0), (0.5, 0.3), (1.0, 1.0)] {
        // Patch 0 is u in [0.5, 1] of segment 0 ([0, 1]).
        assert!(close(
            os(&s.patches[0]).eval(u, v),
            seg0.eval(0.5 + 0.5 * u, v)
        ));
    }
    assert_eq!(
        *os(&s.patches[1]),
        ColorField::Bilinear([c[2], c[3], c[6], c[7]])
    );
    let e = err(&world(&nu(&format!("\"Os\" [{}]", colors(9).1))));
    assert!(
        e.starts_with("t.rib:2: `NuPatch`: \"Os\" (varying color) needs 8 values (24 numbers)"),
        "{e}"
    );
    // Vertex values through the same conversion as the points.
    let s = parse(&world(&nu(&format!("\"vertex color Cs\" [{p}]"))));
    for patch in &s.patches {
        for (a, b) in cs(patch).values().iter().zip(&patch.cp()) {
            assert!(close(*a, *b), "{a} vs {b}");
        }
    }
}

/// Vertex values on a rational `NuPatch` ("Pw", orders 3 x 2) are weighted like the points:
/// given the Euclidean positions as colours, the field's coefficients are the patch's
/// Euclidean Bezier points (so the field meets the surface at its corners), and equal values
/// stay that value everywhere although the weights vary.
#[test]
fn vertex_cs_on_a_rational_nu_patch_is_weighted_like_the_points() {
    let (pts, nums) = grid_numbers(4, 3);
    let w: Vec<f64> = (0..12).map(|k| 1.3 + (k as f64 * 2.1).sin()).collect();
    let pw = (pts.iter().zip(&w))
        .map(|(p, w)| format!("{} {} {} {w}", p.x * w, p.y * w, p.z * w))
        .collect::<Vec<_>>()
        .join(" ");
    let nu = |params: &str| {
        format!("NuPatch 4 3 [0 0 0 1 2 2 2] 0 2 3 2 [0 0 1 2 2] 0 2 \"Pw\" [{pw}] {params}")
    };
    let s = parse(&world(&nu(&format!("\"vertex color Cs\" [{nums}]"))));
    assert_eq!(s.patches.len(), 4);
    for patch in &s.patches {
        assert!(patch.is_rational());
        for (a, b) in cs(patch).values().iter().zip(&patch.cp()) {
            assert!(close(*a, *b), "{a} vs {b}");
        }
        let surface = |u, v| crate::scene::eval_rational_bezier(&patch.cp(), &patch.w(), u, v).0;
        for (u, v) in [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)] {
            assert!(close(cs(patch).eval(u, v), surface(u, v)), "({u}, {v})");
        }
    }
    let grey = "0.25 0.5 0.75 ".repeat(12);
    let s = parse(&world(&nu(&format!("\"vertex color Cs\" [{grey}]"))));
    for patch in &s.patches {
        for (u, v) in [(0.0, 0.0), (0.3, 0.8), (0.6, 0.1)] {
            let c = cs(patch).eval(u, v);
            assert!(close(c, DVec3::new(0.25, 0.5, 0.75)), "{c}");
        }
    }
}
