//! Patch, PatchMesh, NuPatch and Basis: the Bezier patches they become.

use super::*;
use crate::scene::PatchSource;
use crate::scene::eval_bezier;
use glam::DVec3;

fn eval_bspline(pts: &[DVec3], nu: usize, r0: usize, c0: usize, u: f64, v: f64) -> DVec3 {
    let w = |t: f64| {
        let s = 1.0 - t;
        [
            s * s * s / 6.0,
            (3.0 * t * t * t - 6.0 * t * t + 4.0) / 6.0,
            (-3.0 * t * t * t + 3.0 * t * t + 3.0 * t + 1.0) / 6.0,
            t * t * t / 6.0,
        ]
    };
    let (wu, wv) = (w(u), w(v));
    let mut p = DVec3::ZERO;
    for j in 0..4 {
        for i in 0..4 {
            p += pts[(r0 + j) * nu + c0 + i] * (wu[i] * wv[j]);
        }
    }
    p
}

#[test]
fn basis_b_spline_patch_becomes_the_same_surface() {
    let (pts, nums) = grid_numbers(4, 4);
    let by_name = parse(&world(&format!(
        "Basis \"b-spline\" 1 \"b-spline\" 1\nPatch \"bicubic\" \"P\" [{nums}]"
    )));
    let by_matrix = parse(&world(&format!(
        "Basis [-0.16666666666666666 0.5 -0.5 0.16666666666666666  0.5 -1 0.5 0  -0.5 0 0.5 0  \
         0.16666666666666666 0.6666666666666666 0.16666666666666666 0] 1 \"b-spline\" 1\n\
         Patch \"bicubic\" \"P\" [{nums}]"
    )));
    for (u, v) in [(0.0, 0.0), (0.5, 0.5), (0.2, 0.9), (1.0, 1.0)] {
        let want = eval_bspline(&pts, 4, 0, 0, u, v);
        assert!(close(eval_bezier(&by_name.patches[0].cp(), u, v).0, want));
        assert!(close(eval_bezier(&by_matrix.patches[0].cp(), u, v).0, want));
    }
    assert!(err(&world("Basis \"nurbs\" 1 \"bezier\" 3")).contains("unknown basis \"nurbs\""));
    assert!(err(&world("Basis \"bezier\" 0 \"bezier\" 3")).contains("step"));
}

#[test]
fn bilinear_patch_is_elevated() {
    let s = parse(&world(QUAD));
    let cp = &s.patches[0].cp();
    assert!(close(cp[0], DVec3::ZERO) && close(cp[3], DVec3::X) && close(cp[12], DVec3::Y));
    assert!(close(cp[15], DVec3::new(1.0, 1.0, 0.0)));
    assert!(close(cp[5], DVec3::new(1.0 / 3.0, 1.0 / 3.0, 0.0)));
    // The basis does not matter for bilinear patches.
    let t = parse(&world(&format!(
        "Basis \"b-spline\" 1 \"catmull-rom\" 1\n{QUAD}"
    )));
    assert_eq!(t.patches[0].cp(), *cp);
}

fn mesh(
    basis: &str,
    kind: &str,
    nu: usize,
    uwrap: &str,
    nv: usize,
    vwrap: &str,
) -> Result<Scene, SceneError> {
    let (_, nums) = grid_numbers(nu, nv);
    parse_rib(
        &world(&format!(
            "Basis {basis}\nPatchMesh \"{kind}\" {nu} \"{uwrap}\" {nv} \"{vwrap}\" \"P\" [{nums}]"
        )),
        "t.rib",
    )
}

#[test]
fn patch_mesh_counts() {
    let bz = "\"bezier\" 3 \"bezier\" 3";
    let bs = "\"b-spline\" 1 \"b-spline\" 1";
    let n = |r: Result<Scene, SceneError>| r.unwrap().patches.len();
    assert_eq!(
        n(mesh(bz, "bicubic", 7, "nonperiodic", 4, "nonperiodic")),
        2
    );
    assert_eq!(n(mesh(bz, "bicubic", 6, "periodic", 4, "nonperiodic")), 2);
    assert_eq!(
        n(mesh(bs, "bicubic", 6, "nonperiodic", 5, "nonperiodic")),
        6
    );
    assert_eq!(n(mesh(bs, "bicubic", 6, "periodic", 5, "periodic")), 30);
    assert_eq!(n(mesh(bs, "bicubic", 6, "periodic", 5, "nonperiodic")), 12);
    assert_eq!(
        n(mesh(
            "\"catmull-rom\" 1 \"hermite\" 2",
            "bicubic",
            5,
            "nonperiodic",
            6,
            "nonperiodic"
        )),
        2 * 2
    );
    assert_eq!(
        n(mesh(bz, "bilinear", 3, "nonperiodic", 2, "nonperiodic")),
        2
    );
    assert_eq!(n(mesh(bz, "bilinear", 3, "periodic", 2, "nonperiodic")), 3);
    let e = mesh(bz, "bicubic", 6, "nonperiodic", 4, "nonperiodic")
        .unwrap_err()
        .to_string();
    assert!(e.contains("nu = 6 does not fit the basis"), "{e}");
    let e = mesh(bz, "bicubic", 7, "periodic", 4, "nonperiodic")
        .unwrap_err()
        .to_string();
    assert!(e.contains("multiple of the step 3"), "{e}");
    let e = mesh(bz, "bicubic", 7, "closed", 4, "nonperiodic")
        .unwrap_err()
        .to_string();
    assert!(e.contains("\"closed\""), "{e}");
}

#[test]
fn patch_mesh_patches_follow_the_basis_steps() {
    let (pts, _) = grid_numbers(6, 5);
    let s = mesh(
        "\"b-spline\" 1 \"b-spline\" 1",
        "bicubic",
        6,
        "periodic",
        5,
        "nonperiodic",
    )
    .unwrap();
    // 6 u patches per row; patch (pu = 1, pv = 1) uses columns 1..5 and rows 1..5.
    let p = &s.patches[6 + 1];
    assert_eq!(p.source.index, 7);
    for (u, v) in [(0.0, 0.0), (0.4, 0.7), (1.0, 1.0)] {
        assert!(close(
            eval_bezier(&p.cp(), u, v).0,
            eval_bspline(&pts, 6, 1, 1, u, v)
        ));
    }
    // Periodic in u: the last patch of a row ends where the first begins.
    let (first, last) = (&s.patches[0], &s.patches[5]);
    for v in [0.0, 0.5, 1.0] {
        assert!(close(
            eval_bezier(&last.cp(), 1.0, v).0,
            eval_bezier(&first.cp(), 0.0, v).0
        ));
    }
    // Bezier meshes share edge points (step 3).
    let s = mesh(
        "\"bezier\" 3 \"bezier\" 3",
        "bicubic",
        7,
        "nonperiodic",
        4,
        "nonperiodic",
    )
    .unwrap();
    assert_eq!(s.patches[0].cp()[3], s.patches[1].cp()[0]);
}

/// NuPatch 5x4 cubic, clamped in u with one interior knot, a Bezier span in v.
pub(super) fn nu_patch(pw: bool, w: f64) -> String {
    let (_, nums) = grid_numbers(5, 4);
    let nums = if pw {
        nums.split(' ')
            .collect::<Vec<_>>()
            .chunks(3)
            .map(|c| format!("{} {w}", c.join(" ")))
            .collect::<Vec<_>>()
            .join(" ")
    } else {
        nums
    };
    let p = if pw { "Pw" } else { "P" };
    world(&format!(
        "NuPatch 5 4 [0 0 0 0 1 2 2 2 2] 0 2 4 4 [0 0 0 0 1 1 1 1] 0 1\n\"{p}\" [{nums}]"
    ))
}

#[test]
fn nu_patch_spans_become_patches() {
    let s = parse(&nu_patch(false, 1.0));
    assert_eq!(s.patches.len(), 2);
    assert_eq!(
        s.patches[1].source,
        PatchSource {
            file: "t.rib".into(),
            line: 2,
            index: 1
        }
    );
    let t = parse(&nu_patch(true, 1.0));
    assert_eq!(s.patches[0].cp(), t.patches[0].cp());
    // The two spans meet.
    assert!(close(
        eval_bezier(&s.patches[0].cp(), 1.0, 0.3).0,
        eval_bezier(&s.patches[1].cp(), 0.0, 0.3).0
    ));
}

#[test]
fn nu_patch_errors_name_the_line() {
    let e = err(&nu_patch(true, 0.0));
    assert_eq!(
        e,
        "t.rib:2: `NuPatch`: point 0 of \"Pw\" [0 0 0 0] has weight w = 0: \
         weights must be positive and finite"
    );
    let e = err(&nu_patch(true, -0.5));
    assert!(
        e.starts_with("t.rib:2: `NuPatch`: point 0 of \"Pw\""),
        "{e}"
    );
    assert!(e.contains("has weight w = -0.5"), "{e}");
    let e = err(&world(
        "\n\nNuPatch 5 5 [0 0 0 0 0 1 1 1 1 1] 0 1 3 3 [0 0 0 1 1 1] 0 1 \"P\" [0 0 0]",
    ));
    assert_eq!(
        e,
        "t.rib:4: `NuPatch`: u order 5 is not supported (orders 2 to 4: linear to cubic)"
    );
    let e = err(&world(
        "NuPatch 3 3 [0 0 0 1 1 1] 0 1 1 1 [0 1] 0 1 \"P\" [0 0 0]",
    ));
    assert_eq!(
        e,
        "t.rib:2: `NuPatch`: v order 1 is not supported (orders 2 to 4: linear to cubic)"
    );
    let e = err(&nu_patch(false, 1.0).replace("[0 0 0 0 1 2 2 2 2]", "[0 0 0 0 1 2 2 2]"));
    assert!(
        e.starts_with("t.rib:2: `NuPatch`: u knot vector has 8 values, expected nu + order = 9"),
        "{e}"
    );
    let e = err(&nu_patch(false, 1.0).replace("NuPatch 5 4", "NuPatch 6 4"));
    assert!(
        e.contains("u knot vector has 9 values, expected nu + order = 10"),
        "{e}"
    );
    let e = err(&nu_patch(false, 1.0)
        .replace("[0 0 0 0 1 1 1 1] 0 1", "[0 0 0 0 0.5 1 1 1 1] 0 1")
        .replace("4 4 [", "5 4 ["));
    assert!(
        e.contains("\"P\" needs 75 numbers (25 points), found 60"),
        "{e}"
    );
    let e = err(&nu_patch(false, 1.0)
        .replace("0 2 4 4", "0 2 3 4")
        .replace("[0 0 0 0 1 1 1 1]", "[0 0 0 0 1 1 1]"));
    assert!(e.contains("less than the order"), "{e}");
    let e = err(&nu_patch(false, 1.0).replace("\"P\" [0 ", "\"P\" ["));
    assert!(
        e.contains("\"P\" needs 60 numbers (20 points), found 59"),
        "{e}"
    );
}
