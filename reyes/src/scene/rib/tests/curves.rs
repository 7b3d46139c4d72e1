//! `Curves` and `Points`: segment counts for every basis and wrap mode, the ribbons' centre
//! lines and widths, the primitive variables each piece gets, the discs, the errors of bad
//! counts, and the exporters' files.

use super::super::tests::{close, err, parse, world};
use crate::scene::{ColorField, Patch, eval_bezier};
use glam::DVec3;

/// The ribbon's centre and width vector at v on a patch (u runs across the width).
fn across(p: &Patch, v: f64) -> (DVec3, DVec3) {
    let a = eval_bezier(&p.cp(), 0.0, v).0;
    let b = eval_bezier(&p.cp(), 1.0, v).0;
    ((a + b) * 0.5, b - a)
}

#[test]
fn straight_linear_curve_is_a_rectangle_facing_the_eye() {
    let s = parse(&world(
        "Curves \"linear\" [2] \"nonperiodic\" \"P\" [-5 0 6  5 0 6] \"constantwidth\" [0.4]",
    ));
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    assert_eq!(s.patches.len(), 1);
    let p = &s.patches[0];
    assert_eq!((p.source.line, p.source.index), (2, 0));
    let corners = [p.cp()[0], p.cp()[3], p.cp()[12], p.cp()[15]];
    let want = [(-5.0, -0.2), (-5.0, 0.2), (5.0, -0.2), (5.0, 0.2)];
    for (c, (x, y)) in corners.iter().zip(want) {
        assert!(close(*c, DVec3::new(x, y, 6.0)), "{c}");
    }
    // The outside (dPdu x dPdv, not flipped) faces the eye.
    let (_, du, dv) = eval_bezier(&p.cp(), 0.5, 0.5);
    assert!(!p.flip_normal && du.cross(dv).z < 0.0);
}

#[test]
fn widths_follow_the_transform_and_default_to_one() {
    let s = parse(&world(
        "Scale 2 2 2 Curves \"linear\" [2] \"nonperiodic\" \"P\" [-1 0 3  1 0 3]",
    ));
    let (_, w) = across(&s.patches[0], 0.5);
    assert!((w.length() - 2.0).abs() < 1e-12, "{w}");
}

#[test]
fn varying_width_interpolates_along_each_segment() {
    let s = parse(&world(
        "Curves \"linear\" [3] \"nonperiodic\" \"P\" [0 0 5  1 0 5  2 0 5] \"width\" [0.1 0.3 0.2]",
    ));
    assert_eq!(s.patches.len(), 2);
    let w = |k: usize, v: f64| across(&s.patches[k], v).1.length();
    assert!((w(0, 0.0) - 0.1).abs() < 1e-12);
    assert!((w(0, 0.5) - 0.2).abs() < 1e-12);
    assert!((w(1, 0.0) - 0.3).abs() < 1e-12);
    assert!((w(1, 1.0) - 0.2).abs() < 1e-12);
}

/// A cubic curve in `basis` (step `step`), n vertices: segment counts and the centre line
/// through the curve as the basis defines it, evaluated here with the basis matrix.
fn check_cubic(basis: &str, step: usize, n: usize, periodic: bool) {
    let pts: Vec<DVec3> = (0..n)
        .map(|k| {
            let t = k as f64;
            DVec3::new(t * 0.5 - 1.0, (t * 1.3).sin(), 6.0 + (t * 0.7).cos())
        })
        .collect();
    let nums: Vec<String> = pts
        .iter()
        .map(|p| format!("{} {} {}", p.x, p.y, p.z))
        .collect();
    let wrap = if periodic { "periodic" } else { "nonperiodic" };
    let s = parse(&world(&format!(
        "Translate 0.5 -1 2 Basis \"{basis}\" {step} \"{basis}\" {step}\n\
         Curves \"cubic\" [{n}] \"{wrap}\" \"P\" [{}] \"constantwidth\" 0.05",
        nums.join("  ")
    )));
    let segments = if periodic {
        n / step
    } else {
        (n - 4) / step + 1
    };
    let m = crate::scene::Basis::by_name(basis).unwrap().matrix;
    let exact = |seg: usize, t: f64| {
        let tt = [t * t * t, t * t, t, 1.0];
        (0..4)
            .map(|j| {
                let w: f64 = (0..4).map(|k| tt[k] * m[k][j]).sum();
                pts[(seg * step + j) % n] * w
            })
            .sum::<DVec3>()
            + DVec3::new(0.5, -1.0, 2.0)
    };
    let mut seen = vec![false; segments];
    for p in &s.patches {
        seen[p.source.index as usize] = true;
    }
    assert!(seen.iter().all(|x| *x), "{basis} {wrap}: {seen:?}");
    // Each segment's pieces in order: the centre line is the curve (a piece's own
    // parameter is not the segment's, so a point is compared with the nearest of 4000 curve
    // points, at most 1e-3 apart: within 1e-3), the width 0.05.
    for seg in 0..segments {
        let pieces: Vec<&Patch> = (s.patches.iter())
            .filter(|p| p.source.index as usize == seg)
            .collect();
        for p in &pieces {
            for v in [0.0, 0.3, 0.7, 1.0] {
                let (c, w) = across(p, v);
                assert!(
                    (w.length() - 0.05).abs() < 1e-3,
                    "{basis} width {}",
                    w.length()
                );
                let d = (0..=4000)
                    .map(|k| exact(seg, k as f64 / 4000.0).distance(c))
                    .fold(f64::MAX, f64::min);
                assert!(d < 1e-3, "{basis} seg {seg} at {v}: {d}");
            }
        }
        // Start and end of the segment are the curve's.
        let c0 = across(pieces[0], 0.0).0;
        let c1 = across(pieces.last().unwrap(), 1.0).0;
        assert!(
            c0.distance(exact(seg, 0.0)) < 1e-9,
            "{basis} start of {seg}"
        );
        assert!(c1.distance(exact(seg, 1.0)) < 1e-9, "{basis} end of {seg}");
    }
}

#[test]
fn cubic_curves_in_every_basis_and_wrap_mode() {
    for (basis, step) in [
        ("bezier", 3),
        ("b-spline", 1),
        ("catmull-rom", 1),
        ("hermite", 2),
        ("power", 4),
    ] {
        check_cubic(basis, step, 4 + 2 * step, false);
        check_cubic(basis, step, 4 * step.max(2), true);
    }
}

#[test]
fn a_bezier_curve_centre_passes_through_the_curve_points() {
    let cp = [
        DVec3::new(-2.0, -1.0, 8.0),
        DVec3::new(-1.0, 3.0, 6.0),
        DVec3::new(1.0, -3.0, 9.0),
        DVec3::new(2.0, 1.0, 7.0),
    ];
    let nums: Vec<String> = cp
        .iter()
        .map(|p| format!("{} {} {}", p.x, p.y, p.z))
        .collect();
    let s = parse(&world(&format!(
        "Curves \"cubic\" [4] \"nonperiodic\" \"P\" [{}] \"constantwidth\" 0.1",
        nums.join(" ")
    )));
    // Every exact curve point lies on some piece's centre line (u = 1/2).
    for k in 0..=20 {
        let t = k as f64 / 20.0;
        let e = crate::scene::curves::eval(&cp, t);
        let best = (s.patches.iter())
            .flat_map(|p| (0..=4000).map(move |j| across(p, j as f64 / 4000.0).0.distance(e)))
            .fold(f64::MAX, f64::min);
        // Within the spacing of the 4000 points searched per piece.
        assert!(best < 1e-3, "t {t}: {best}");
    }
}

#[test]
fn linear_curves_periodic_and_mitred() {
    // A closed square: 4 segments, every corner shared by its two ribbons.
    let s = parse(&world(
        "Curves \"linear\" [4] \"periodic\" \"P\" [0 0 5  1 0 5  1 1 5  0 1 5] \
         \"constantwidth\" 0.1",
    ));
    assert_eq!(s.patches.len(), 4);
    for k in 0..4 {
        let (a, b) = (&s.patches[k].cp(), &s.patches[(k + 1) % 4].cp());
        assert_eq!(a[12..16], b[0..4], "corner {k}");
    }
}

#[test]
fn colours_of_every_class_reach_the_pieces() {
    let curve = "Curves \"linear\" [3 2] \"nonperiodic\" \"P\" [0 0 5  1 0 5  2 0 5  0 1 5  1 1 5]";
    let cs = |p: &Patch| p.primvars.as_ref().unwrap().cs.clone().unwrap();
    let s = parse(&world(&format!(
        "{curve} \"uniform color Cs\" [1 0 0  0 1 0]"
    )));
    assert_eq!(s.patches.len(), 3);
    assert_eq!(cs(&s.patches[1]), ColorField::Flat(DVec3::X));
    assert_eq!(cs(&s.patches[2]), ColorField::Flat(DVec3::Y));
    // varying (= vertex on linear curves): one per vertex, along v.
    for class in ["varying", "vertex"] {
        let s = parse(&world(&format!(
            "{curve} \"{class} color Cs\" [1 0 0  0 1 0  0 0 1  1 1 1  0 0 0]"
        )));
        assert_eq!(
            cs(&s.patches[1]),
            ColorField::Bilinear([DVec3::Y, DVec3::Y, DVec3::Z, DVec3::Z])
        );
        assert_eq!(
            cs(&s.patches[2]),
            ColorField::Bilinear([DVec3::ONE, DVec3::ONE, DVec3::ZERO, DVec3::ZERO])
        );
    }
    // A cubic curve's vertex colours follow the basis: at the ends of a Bezier segment, its
    // end values.
    let s = parse(&world(
        "Curves \"cubic\" [4] \"nonperiodic\" \"P\" [0 0 5  1 1 5  2 -1 5  3 0 5] \
         \"vertex color Os\" [1 0 0  0 1 0  0 0 1  1 1 1]",
    ));
    let os = |p: &Patch, v: f64| {
        p.primvars
            .as_ref()
            .unwrap()
            .os
            .clone()
            .unwrap()
            .eval(0.3, v)
    };
    assert!(os(&s.patches[0], 0.0).distance(DVec3::X) < 1e-12);
    assert!(os(s.patches.last().unwrap(), 1.0).distance(DVec3::ONE) < 1e-12);
}

#[test]
fn normals_orient_the_ribbon() {
    let s = parse(&world(
        "Curves \"linear\" [2] \"nonperiodic\" \"P\" [-1 0 5  1 0 5] \"N\" [0 1 0  0 1 0] \
         \"constantwidth\" 0.2",
    ));
    let p = &s.patches[0];
    let (_, w) = across(p, 0.5);
    assert!(w.normalize().cross(DVec3::Z).length() < 1e-12, "{w}");
    let (_, du, dv) = eval_bezier(&p.cp(), 0.5, 0.5);
    assert!(du.cross(dv).normalize().distance(DVec3::Y) < 1e-12);
    let n = p.primvars.as_ref().unwrap().n.clone().unwrap();
    assert_eq!(n.eval(0.5, 0.5), DVec3::Y);
}

#[test]
fn points_are_discs_facing_the_eye() {
    let s = parse(&world(
        "Points \"P\" [0 0 5  1 2 8] \"width\" [0.5 1] \"Cs\" [1 0 0  0 0 1]",
    ));
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    assert_eq!(s.patches.len(), 2);
    for (k, (centre, r)) in [
        (DVec3::new(0.0, 0.0, 5.0), 0.25),
        (DVec3::new(1.0, 2.0, 8.0), 0.5),
    ]
    .into_iter()
    .enumerate()
    {
        let discs: Vec<&Patch> = (s.patches.iter())
            .filter(|p| p.source.index as usize == k)
            .collect();
        assert_eq!(discs.len(), 1);
        for p in discs {
            // The rim (v = 0) at the radius, in the plane across the view.
            for u in [0.0, 0.4, 1.0] {
                let q = crate::scene::eval_rational_bezier(&p.cp(), &p.w(), u, 0.0).0;
                let tol = crate::scene::curves::DISC_RIM_ERROR * r;
                assert!(((q - centre).length() - r).abs() < tol);
                assert!((q - centre).dot(centre).abs() < 1e-9);
            }
            let vars = p.primvars.as_ref().unwrap();
            let want = if k == 0 { DVec3::X } else { DVec3::Z };
            assert_eq!(vars.cs, Some(ColorField::Flat(want)));
            // Shaded as facing the eye.
            let n = vars.n.clone().unwrap().eval(0.5, 0.5);
            assert!(n.distance(-centre.normalize()) < 1e-12);
        }
    }
    let s = parse(&world("Points \"P\" [0 0 5] \"constantwidth\" 0.2"));
    let q = crate::scene::eval_rational_bezier(&s.patches[0].cp(), &s.patches[0].w(), 0.5, 0.0).0;
    assert!((q.distance(DVec3::new(0.0, 0.0, 5.0)) - 0.1).abs() < 0.1 * 3e-4);
}

#[test]
fn orthographic_ribbons_and_discs_face_along_z() {
    let s = parse(&format!(
        "Projection \"orthographic\"\n{}",
        world(
            "Curves \"linear\" [2] \"nonperiodic\" \"P\" [-1 3 5  1 3 5] \"constantwidth\" 0.2\n\
             Points \"P\" [0 4 7] \"constantwidth\" 0.2"
        )
    ));
    // Off the axis, a perspective ribbon would tilt towards the eye; an orthographic one
    // faces -z exactly.
    let (_, du, dv) = eval_bezier(&s.patches[0].cp(), 0.5, 0.5);
    assert!(du.cross(dv).normalize().distance(-DVec3::Z) < 1e-12);
    let vars = s.patches[1].primvars.as_ref().unwrap();
    assert_eq!(vars.n, Some(ColorField::Flat(-DVec3::Z)));
}

#[test]
fn bad_curves_are_errors_naming_file_and_line() {
    let e = err(&world(
        "Curves \"cubic\" [5] \"nonperiodic\" \"P\" [0 0 0 1 0 0 2 0 0 3 0 0 4 0 0]",
    ));
    assert!(
        e.starts_with("t.rib:2: `Curves`: nvertices: curve 0 has 5 vertices"),
        "{e}"
    );
    assert!(e.contains("4 + k * vstep (vstep 3"), "{e}");
    let e = err(&world(
        "Curves \"linear\" [2 1] \"nonperiodic\" \"P\" [0 0 0 1 0 0 2 0 0]",
    ));
    assert!(e.contains("curve 1 has 1 vertices"), "{e}");
    let e = err(&world(
        "Curves \"linear\" [2 1.5] \"nonperiodic\" \"P\" [0 0 0 1 0 0]",
    ));
    assert!(
        e.contains("curve 1 has 1.5 vertices, not an integer"),
        "{e}"
    );
    let e = err(&world(
        "Curves \"linear\" [3] \"nonperiodic\" \"P\" [0 0 0 1 0 0]",
    ));
    assert!(
        e.starts_with("t.rib:2:") && e.contains("\"P\" needs 9 numbers"),
        "{e}"
    );
    let e = err(&world(
        "Curves \"linear\" [3] \"nonperiodic\" \"P\" [0 0 0 1 0 0 2 0 0] \"width\" [1 2]",
    ));
    assert!(
        e.contains("\"width\" (varying float) needs 3 values"),
        "{e}"
    );
    let e = err(&world(
        "Curves \"linear\" [2] \"periodic\" \"P\" [0 0 0 1 0 0] \"width\" [1 2 3]",
    ));
    assert!(e.contains("needs 2 values"), "{e}");
    let e = err(&world(
        "Curves \"linear\" [2] \"nonperiodic\" \"P\" [0 0 0 1 0 0] \"width\" [1 -2]",
    ));
    assert!(e.contains("value 1 of \"width\" is negative"), "{e}");
    let e = err(&world(
        "Curves \"linear\" [2] \"nonperiodic\" \"P\" [0 0 0 1 0 0] \"Cs\" [1 0 0]",
    ));
    assert!(e.contains("\"Cs\" (varying color) needs 2 values"), "{e}");
    let e = err(&world(
        "Curves \"quadratic\" [2] \"nonperiodic\" \"P\" [0 0 0 1 0 0]",
    ));
    assert!(e.contains("curve type \"quadratic\""), "{e}");
    let e = err(&world(
        "Curves \"linear\" [2] \"closed\" \"P\" [0 0 0 1 0 0]",
    ));
    assert!(
        e.contains("\"closed\" is not \"periodic\" or \"nonperiodic\""),
        "{e}"
    );
    let e = err(&world("Points \"P\" [0 0 0 1 0 0] \"width\" [1]"));
    assert!(
        e.starts_with("t.rib:2: `Points`:") && e.contains("needs 2 values"),
        "{e}"
    );
    let e = err(&world("Points \"width\" [1]"));
    assert!(e.contains("missing the \"P\" parameter"), "{e}");
    let e = err("Points \"P\" [0 0 0]\n");
    assert!(e.contains("outside `WorldBegin`"), "{e}");
}

#[test]
fn other_parameters_are_ignored_with_a_warning() {
    let s = parse(&world(
        "Points \"P\" [0 0 5] \"N\" [0 0 1] \"id\" [7]\n\
         Curves \"linear\" [2] \"nonperiodic\" \"P\" [0 0 5 1 0 5] \"width\" [1 1] \
         \"constantwidth\" 2",
    ));
    let w = s.warnings.join("\n");
    for name in [
        "\"N\" of `Points`",
        "\"id\" of `Points`",
        "\"constantwidth\" of `Curves`",
    ] {
        assert!(w.contains(name), "{name}: {w}");
    }
}

/// The exporters' files: drawn, with no warning about curves or points.
#[test]
fn exporters_curves_and_points_are_read() {
    for (file, min) in [("curves-linear.rib", 2), ("points.rib", 100)] {
        let path = crate::shared_data_dir().join("field/exporters").join(file);
        let s = crate::scene::load(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        assert!(
            s.patches.len() >= min,
            "{file}: {} patches",
            s.patches.len()
        );
        let w = s.warnings.join("\n");
        assert!(
            !w.contains("Curves") && !w.contains("Points"),
            "{file}: {w}"
        );
    }
}

/// `Points` counts its points from "P": a length that is not a whole number of points says so.
#[test]
fn points_with_a_partial_point_name_the_multiple() {
    let e = err(&world("Points \"P\" [0 0 5 1 0 5 2 0]"));
    assert!(
        e.starts_with("t.rib:2:") && e.contains("\"P\" needs a multiple of 3 numbers"),
        "{e}"
    );
}
