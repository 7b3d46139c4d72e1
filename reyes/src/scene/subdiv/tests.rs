//! The limit patches against independent references: Halstead et al.'s limit masks applied
//! to the control mesh, and deep uniform subdivision (every face, six levels).

use super::topology::{Mesh, Topology};
use super::*;
use crate::scene::eval_bezier;
use glam::DVec3;
use std::f64::consts::PI;

/// The cube [-1, 1]³, faces outward (counter-clockwise seen from outside).
fn cube() -> (Vec<usize>, Vec<u32>, Vec<DVec3>) {
    let p = (0..8)
        .map(|k| {
            DVec3::new(
                if k & 1 != 0 { 1.0 } else { -1.0 },
                if k & 2 != 0 { 1.0 } else { -1.0 },
                if k & 4 != 0 { 1.0 } else { -1.0 },
            )
        })
        .collect();
    let f = vec![
        0, 2, 3, 1, 4, 5, 7, 6, 0, 1, 5, 4, 2, 6, 7, 3, 0, 4, 6, 2, 1, 3, 7, 5,
    ];
    (vec![4; 6], f, p)
}

/// The field file's tetrahedron.
fn tetrahedron() -> (Vec<usize>, Vec<u32>, Vec<DVec3>) {
    let p = vec![
        DVec3::new(77.3773, 0.0, 0.0),
        DVec3::new(-38.6887, 67.0107, 0.0),
        DVec3::new(-38.6887, -67.0107, 0.0),
        DVec3::new(0.0, 0.0, 72.4387),
    ];
    (vec![3; 4], vec![0, 1, 3, 1, 2, 3, 2, 0, 3, 2, 1, 0], p)
}

fn mesh_of(sizes: &[usize], idx: &[u32], p: &[DVec3], tags: &Tags) -> Mesh {
    control_mesh(sizes, idx, p.len(), tags).unwrap()
}

/// Halstead et al. 1993, written out from the paper rather than through `limit`: the limit
/// position and normal of smooth interior vertex `v` of a quad mesh.
fn halstead(mesh: &Mesh, p: &[DVec3], v: u32) -> (DVec3, DVec3) {
    let t = Topology::new(mesh).unwrap();
    let r = t.canonical_ring(mesh, v).unwrap();
    let n = r.edge.len();
    let nf = n as f64;
    let e: DVec3 = r.edge.iter().map(|&i| p[i as usize]).sum();
    let d: DVec3 = r.diag.iter().map(|&i| p[i as usize]).sum();
    let pos = (nf * nf * p[v as usize] + 4.0 * e + d) / (nf * (nf + 5.0));
    let c = (2.0 * PI / nf).cos();
    let a = 1.0 + c + (PI / nf).cos() * (2.0 * (9.0 + c)).sqrt();
    let (mut t1, mut t2) = (DVec3::ZERO, DVec3::ZERO);
    for i in 0..n {
        let th = |j: usize| 2.0 * PI * j as f64 / nf;
        let (ei, di) = (p[r.edge[i] as usize], p[r.diag[i] as usize]);
        t1 += a * th(i).cos() * ei + (th(i).cos() + th(i + 1).cos()) * di;
        t2 += a * th(i).sin() * ei + (th(i).sin() + th(i + 1).sin()) * di;
    }
    (pos, t1.cross(t2).normalize())
}

/// Closest distance from `q` to the patches' surfaces (dense samples, then Gauss-Newton in
/// the best sample's patch).
fn distance(patches: &[LimitPatch], samples: &[(usize, f64, f64, DVec3)], q: DVec3) -> f64 {
    let &(k, mut u, mut v, _) = samples
        .iter()
        .min_by(|a, b| a.3.distance(q).total_cmp(&b.3.distance(q)))
        .unwrap();
    let cp = &patches[k].channels[0];
    for _ in 0..20 {
        let (p, pu, pv) = eval_bezier(cp, u, v);
        let r = p - q;
        let (a, b, c) = (pu.dot(pu), pu.dot(pv), pv.dot(pv));
        let (g0, g1) = (pu.dot(r), pv.dot(r));
        let det = a * c - b * b;
        if det.abs() < 1e-300 {
            break;
        }
        u = (u - (c * g0 - b * g1) / det).clamp(0.0, 1.0);
        v = (v - (a * g1 - b * g0) / det).clamp(0.0, 1.0);
    }
    eval_bezier(cp, u, v).0.distance(q)
}

fn samples(patches: &[LimitPatch], n: usize) -> Vec<(usize, f64, f64, DVec3)> {
    let mut out = Vec::new();
    for (k, p) in patches.iter().enumerate() {
        for j in 0..=n {
            for i in 0..=n {
                let (u, v) = (i as f64 / n as f64, j as f64 / n as f64);
                out.push((k, u, v, eval_bezier(&p.channels[0], u, v).0));
            }
        }
    }
    out
}

/// Largest distance from the limit points of the level-5 uniform subdivision's smooth
/// vertices (Halstead's mask applied there) to the patches; also checks every limit point
/// lies within `tol`.
fn max_error_to_uniform(mesh: &Mesh, p: &[DVec3], patches: &[LimitPatch]) -> f64 {
    let (fine, data) = uniform(mesh, &[p.to_vec()], 4).unwrap();
    let t = Topology::new(&fine).unwrap();
    let s = samples(patches, 6);
    let mut worst: f64 = 0.0;
    for v in 0..fine.nverts as u32 {
        if fine.vertex_sharpness[v as usize] != 0.0
            || t.vertex_edges[v as usize]
                .iter()
                .any(|&e| fine.edge_sharpness.contains_key(&t.edges[e as usize]))
            || t.canonical_ring(&fine, v).is_none()
        {
            continue;
        }
        let (q, _) = halstead(&fine, &data[0], v);
        worst = worst.max(distance(patches, &s, q));
    }
    worst
}

#[test]
fn halstead_limit_of_the_control_mesh_is_where_deep_subdivision_converges() {
    let (sizes, idx, p) = cube();
    let mesh = mesh_of(&sizes, &idx, &p, &Tags::default());
    let (lim, nrm) = halstead(&mesh, &p, 7);
    // Vertex points keep their index from level to level.
    let (fine, data) = uniform(&mesh, std::slice::from_ref(&p), 6).unwrap();
    assert!(data[0][7].distance(lim) < 1e-3, "{} vs {lim}", data[0][7]);
    // The mask applied at any level gives the same point and normal (eigen-analysis).
    let (lim6, nrm6) = halstead(&fine, &data[0], 7);
    assert!(lim6.distance(lim) < 1e-12 && nrm6.distance(nrm) < 1e-9);
    // The corner (1, 1, 1): (9 v + 4 (1, 1, 1) - (1, 1, 1)) / 24 = (1/2, 1/2, 1/2), the
    // normal along the diagonal.
    assert!(lim.distance(DVec3::splat(0.5)) < 1e-15, "{lim}");
    assert!(nrm.distance(DVec3::splat(1.0 / 3f64.sqrt())) < 1e-12);
}

/// Patch corner nearest `q` and the patch normal there.
fn normal_at(patches: &[LimitPatch], q: DVec3) -> (f64, DVec3) {
    let mut best = (f64::INFINITY, DVec3::ZERO);
    for p in patches {
        for (u, v) in [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)] {
            let (x, pu, pv) = eval_bezier(&p.channels[0], u, v);
            if x.distance(q) < best.0 {
                best = (x.distance(q), pu.cross(pv).normalize());
            }
        }
    }
    best
}

#[test]
fn a_cube_becomes_a_rounded_cube_close_to_its_limit_surface() {
    let (sizes, idx, p) = cube();
    let tags = Tags::default();
    let patches = catmull_clark(&sizes, &idx, &tags, vec![p.clone()], &[]).unwrap();
    let exact = patches.iter().filter(|p| p.exact).count();
    eprintln!("cube: {} patches, {exact} exact", patches.len());
    // Level 2: 96 faces, 72 away from the 8 valence-3 corners are B-spline patches; the 24 at
    // the corners subdivide to 96 at level 3, 72 more B-spline patches and 24 approximated.
    assert_eq!((patches.len(), exact), (168, 144));
    let mesh = mesh_of(&sizes, &idx, &p, &tags);
    // Limit position and normal at the corners (Halstead) are the patches'.
    for v in 0..8 {
        let (lim, nrm) = halstead(&mesh, &p, v);
        let (d, n) = normal_at(&patches, lim);
        assert!(d < 1e-12, "corner {v}: {d}");
        assert!(n.dot(nrm) > 1.0 - 1e-12, "corner {v}: {n} vs {nrm}");
    }
    // Rounded: inside the cube, no flat face left.
    for p in &patches {
        for c in &p.channels[0] {
            assert!(c.abs().max_element() < 1.0);
        }
    }
    let err = max_error_to_uniform(&mesh, &p, &patches);
    eprintln!("cube: max distance to the limit surface {err:.2e} (size 2)");
    assert!(err < 5e-4 * 2.0, "{err}");
}

#[test]
fn a_tetrahedron_becomes_a_smooth_watertight_blob() {
    let (sizes, idx, p) = tetrahedron();
    let patches = catmull_clark(&sizes, &idx, &Tags::default(), vec![p.clone()], &[]).unwrap();
    let mesh = mesh_of(&sizes, &idx, &p, &Tags::default());
    let size = 150.0;
    let err = max_error_to_uniform(&mesh, &p, &patches);
    eprintln!(
        "tetrahedron: {} patches, max distance to the limit surface {err:.2e} (size {size})",
        patches.len()
    );
    assert!(err < 5e-4 * size, "{err}");
    // Watertight: every point on a patch's boundary lies on another patch.
    let s = samples(&patches, 6);
    for (k, pa) in patches.iter().enumerate() {
        let others: Vec<_> = s.iter().filter(|x| x.0 != k).copied().collect();
        for t in [0.0, 0.3, 0.5, 0.8, 1.0] {
            for (u, v) in [(t, 0.0), (1.0, t), (t, 1.0), (0.0, t)] {
                let q = eval_bezier(&pa.channels[0], u, v).0;
                let d = distance(&patches, &others, q);
                assert!(d < 1e-9 * size, "patch {k} at ({u}, {v}): gap {d}");
            }
        }
    }
}

#[test]
fn infinitely_sharp_cube_edges_keep_the_cube() {
    let (sizes, idx, p) = cube();
    let edges = [
        (0, 1),
        (2, 3),
        (4, 5),
        (6, 7),
        (0, 2),
        (1, 3),
        (4, 6),
        (5, 7),
        (0, 4),
        (1, 5),
        (2, 6),
        (3, 7),
    ];
    let tags = Tags {
        creases: edges.iter().map(|&(a, b)| (vec![a, b], 10.0)).collect(),
        ..Tags::default()
    };
    let patches = catmull_clark(&sizes, &idx, &tags, vec![p], &[]).unwrap();
    for pa in &patches {
        for c in &pa.channels[0] {
            assert!((c.abs().max_element() - 1.0).abs() < 1e-12, "{c}");
        }
    }
}

#[test]
fn boundaries_holes_and_colours() {
    // A 3x3 grid of quads with interpolateboundary: corners interpolated, surface planar.
    let mut idx = Vec::new();
    for r in 0..3u32 {
        for c in 0..3u32 {
            let v = r * 4 + c;
            idx.extend([v, v + 1, v + 5, v + 4]);
        }
    }
    let p: Vec<DVec3> = (0..16)
        .map(|k| DVec3::new((k % 4) as f64, (k / 4) as f64, 0.0))
        .collect();
    let colour: Vec<DVec3> = vec![DVec3::new(0.2, 0.4, 0.6); 16];
    let tags = Tags {
        boundary: BoundaryMode::EdgesAndCorners,
        ..Tags::default()
    };
    let sizes = [4; 9];
    let patches = catmull_clark(&sizes, &idx, &tags, vec![p.clone(), colour], &[]).unwrap();
    let s = samples(&patches, 4);
    for corner in [0, 3, 12, 15] {
        assert!(s.iter().any(|x| x.3.distance(p[corner]) < 1e-12));
    }
    for pa in &patches {
        assert!(pa.channels[0].iter().all(|c| c.z == 0.0));
        let inside = |c: &DVec3| c.x >= -1e-12 && c.x <= 3.0 + 1e-12;
        assert!(pa.channels[0].iter().all(inside));
        // An affine combination of one colour is that colour.
        for c in &pa.channels[1] {
            assert!(c.distance(DVec3::new(0.2, 0.4, 0.6)) < 1e-12);
        }
    }
    // The centre face is regular: one exact B-spline patch at level 0.
    assert_eq!(patches.iter().filter(|p| p.level == 0).count(), 1);
    // Without interpolateboundary only the centre face (away from the boundary) is drawn.
    let inner = catmull_clark(&sizes, &idx, &Tags::default(), vec![p.clone()], &[]).unwrap();
    assert!(inner.len() == 1 && inner[0].origin == 4);
    // A hole leaves its face out.
    let holed = Tags {
        holes: vec![4],
        ..tags
    };
    let patches = catmull_clark(&sizes, &idx, &holed, vec![p], &[]).unwrap();
    assert!(patches.iter().all(|p| p.origin != 4));
    assert!(patches.iter().any(|p| p.origin == 5));
}

#[test]
fn large_meshes_subdivide_less_deep() {
    assert_eq!(max_level_for(6), DEFAULT_MAX_LEVEL);
    assert_eq!(max_level_for(FACES_FOR_FULL_DEPTH), DEFAULT_MAX_LEVEL);
    assert_eq!(
        max_level_for(FACES_FOR_FULL_DEPTH + 1),
        DEFAULT_MAX_LEVEL - 1
    );
    assert_eq!(max_level_for(usize::MAX), 1);
}
