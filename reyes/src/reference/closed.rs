//! The closed test surface `reyes/scenes/closed_blob.rib`: six bicubic Bezier patches made
//! from the faces of the cube [-1, 1]^3 (a 4x4 grid at -1, -1/3, 1/3, 1 per face), every grid
//! point p mapped by g(p) = p / |p|^0.5. The same cube point always goes through the same
//! arithmetic and prints the same, so faces sharing a cube edge have bit-identical boundary
//! control points: the surface is watertight, and any pinhole in a rendering of it is the
//! renderer's fault.
//!
//! [`closed_blob_rib`] generates the file; a test keeps the shipped copy in step.
//!
//! Also an exact sphere of eight rational patches ([`rational_sphere`]), the closed surface
//! with a known silhouette that the rational pipeline is tested on.

use crate::scene::{Patch, PatchNet, PatchSource};
use glam::{DVec3, DVec4};

/// Grid coordinates along each face.
const GRID: [f64; 4] = [-1.0, -1.0 / 3.0, 1.0 / 3.0, 1.0];

/// The smooth map from the cube to the blob.
fn g(p: DVec3) -> DVec3 {
    p / p.length().sqrt()
}

/// The six patches in object space, cp[4*v + u]. Face `axis`/`sign` has u along the next
/// axis and v along the one after (cyclically) for sign +1, swapped for sign -1, so
/// dPdu x dPdv always points outward.
pub fn blob_patches() -> Vec<[DVec3; 16]> {
    let mut out = Vec::new();
    for axis in 0..3 {
        for sign in [1.0, -1.0] {
            let (i, j) = ((axis + 1) % 3, (axis + 2) % 3);
            out.push(std::array::from_fn(|k| {
                let (a, b) = (GRID[k % 4], GRID[k / 4]);
                let (a, b) = if sign > 0.0 { (a, b) } else { (b, a) };
                let mut p = [0.0; 3];
                p[axis] = sign;
                p[i] = a;
                p[j] = b;
                g(DVec3::from_array(p))
            }));
        }
    }
    out
}

/// The sphere of `radius` about `centre` as eight exact rational bicubic patches, one per
/// octant. Each is the surface of revolution of a quarter circle: the rational quadratic arc
/// (1, 0), (1, 1), (0, 1) with weights 1, sqrt(1/2), 1 (Piegl & Tiller, *The NURBS Book*,
/// 7.3) swept about z by the same arc; the 3x3 tensor net (weights multiplied) is raised to
/// degree 3 in homogeneous coordinates (Q0 = P0, Q1 = (P0 + 2 P1)/3, Q2 = (2 P1 + P2)/3,
/// Q3 = P2 along each direction). u runs round z from +x to +y, v from the equator to the pole
/// (the row v = 1 collapses to it); the octant of signs (sx, sy, sz) mirrors that, with
/// `flip_normal` set where the mirror reverses orientation, so every outside normal points
/// away from the centre. Octants sharing an edge have bit-identical boundary control points.
pub fn rational_sphere(centre: DVec3, radius: f64) -> Vec<Patch> {
    let s = 0.5f64.sqrt();
    let arc = [(1.0, 0.0, 1.0), (1.0, 1.0, s), (0.0, 1.0, 1.0)];
    let elevate = |a: [DVec4; 3]| {
        [
            a[0],
            (a[0] + 2.0 * a[1]) / 3.0,
            (2.0 * a[1] + a[2]) / 3.0,
            a[2],
        ]
    };
    // Quadratic homogeneous net of the first octant, unit sphere: (x, y) from the circle,
    // scaled by the meridian's radius, z the meridian's height.
    let quad: [[DVec4; 3]; 3] = std::array::from_fn(|j| {
        std::array::from_fn(|i| {
            let ((cx, cy, wc), (mr, mz, wm)) = (arc[i], arc[j]);
            let w = wc * wm;
            (DVec3::new(cx * mr, cy * mr, mz) * w).extend(w)
        })
    });
    let rows = quad.map(elevate);
    let cols: [[DVec4; 4]; 4] = std::array::from_fn(|i| elevate(rows.map(|r| r[i])));
    let mut out = Vec::new();
    for sz in [1.0, -1.0] {
        for sy in [1.0, -1.0] {
            for sx in [1.0, -1.0] {
                let sign = DVec3::new(sx, sy, sz);
                let (cp, w): (Vec<DVec3>, Vec<f64>) = (0..16)
                    .map(|k| {
                        let h = cols[k % 4][k / 4];
                        (centre + h.truncate() / h.w * sign * radius, h.w)
                    })
                    .unzip();
                out.push(Patch {
                    net: PatchNet::new(cp.try_into().unwrap(), w.try_into().unwrap()),
                    material: 0,
                    flip_normal: sx * sy * sz < 0.0,
                    two_sided: true,
                    primvars: None,
                    displacement: None,
                    motion: None,
                    trim: None,
                    source: PatchSource {
                        file: "rational_sphere".into(),
                        line: 0,
                        index: out.len() as u32,
                    },
                });
            }
        }
    }
    out
}

/// The text of `scenes/closed_blob.rib`.
pub fn closed_blob_rib() -> String {
    let mut s = String::from(
        "# closed_blob.rib: a closed, watertight surface for coverage and pinhole tests.\n\
         # Six bicubic Bezier patches: the faces of the cube [-1,1]^3, each a 4x4 control grid\n\
         # at -1, -1/3, 1/3, 1, every grid point p mapped by g(p) = p / |p|^0.5. Faces that\n\
         # share a cube edge have identical boundary control points (same text), and\n\
         # dPdu x dPdv points outward on every face (default orientation, no mirroring).\n\
         # Camera: blob centred at z = 6, turned so that three faces (+x, +y, -z) are seen.\n\
         # Generated by reyes::reference::closed::closed_blob_rib (keep them in step).\n\
         Format 320 240 1\n\
         Projection \"perspective\" \"fov\" [40]\n\
         Translate 0 0 6\n\
         Rotate -30 1 0 0\n\
         Rotate 40 0 1 0\n\
         WorldBegin\n\
         LightSource \"ambientlight\" 1 \"intensity\" [0.15]\n\
         LightSource \"distantlight\" 2 \"intensity\" [1] \"from\" [-1 2 -3] \"to\" [0 0 0]\n\
         Surface \"plastic\"\n\
         Color [0.8 0.55 0.3]\n",
    );
    for cp in blob_patches() {
        s += "Patch \"bicubic\" \"P\" [\n";
        for row in cp.chunks(4) {
            let nums: Vec<String> = row
                .iter()
                .flat_map(|p| p.to_array())
                .map(|v| format!("{v:.9}"))
                .collect();
            s += &format!("  {}\n", nums.join(" "));
        }
        s += "]\n";
    }
    s += "WorldEnd\n";
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::reference::exact::{coverage, pinholes};
    use crate::scene::{Scene, eval_bezier, load};
    use std::path::PathBuf;

    fn blob_path() -> PathBuf {
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenes/closed_blob.rib")
    }

    fn blob() -> Scene {
        load(&blob_path()).unwrap()
    }

    /// Centre of the blob in camera space: the mean of all control points (the control
    /// point set is symmetric about it).
    fn centre(s: &Scene) -> DVec3 {
        let pts: Vec<DVec3> = s.patches.iter().flat_map(|p| p.cp()).collect();
        pts.iter().sum::<DVec3>() / pts.len() as f64
    }

    #[test]
    fn shipped_file_matches_generator() {
        let text = std::fs::read_to_string(blob_path()).unwrap();
        assert!(
            text == closed_blob_rib(),
            "scenes/closed_blob.rib differs from closed_blob_rib(); run regenerate_closed_blob"
        );
        let s = blob();
        assert_eq!(s.patches.len(), 6);
        assert_eq!((s.width, s.height), (320, 240));
        assert_eq!(s.camera.fov_deg, 40.0);
        assert_eq!(s.lights.len(), 2);
        assert!(s.warnings.is_empty(), "{:?}", s.warnings);
        assert!(centre(&s).distance(DVec3::new(0.0, 0.0, 6.0)) < 1e-9);
    }

    /// Rewrites the shipped file from the generator:
    /// `cargo test -p reyes --lib regenerate_closed_blob -- --ignored`.
    #[test]
    #[ignore = "writes scenes/closed_blob.rib"]
    fn regenerate_closed_blob() {
        std::fs::write(blob_path(), closed_blob_rib()).unwrap();
    }

    #[test]
    fn shared_edges_are_identical() {
        let s = blob();
        let edges: Vec<(usize, [DVec3; 4])> = s
            .patches
            .iter()
            .enumerate()
            .flat_map(|(i, p)| {
                let c = |k: [usize; 4]| (i, k.map(|k| p.cp()[k]));
                [
                    c([0, 1, 2, 3]),
                    c([12, 13, 14, 15]),
                    c([0, 4, 8, 12]),
                    c([3, 7, 11, 15]),
                ]
            })
            .collect();
        for (i, e) in &edges {
            let mut rev = *e;
            rev.reverse();
            let twins = edges
                .iter()
                .filter(|(j, f)| j != i && (f == e || *f == rev))
                .count();
            assert_eq!(twins, 1, "patch {i} edge {e:?}");
        }
    }

    /// Outside normals (after `flip_normal`) point away from the centre everywhere, and
    /// exactly three faces face the camera.
    #[test]
    fn normals_point_outward() {
        let s = blob();
        let c = centre(&s);
        let mut facing = 0;
        for (k, p) in s.patches.iter().enumerate() {
            assert!(!p.flip_normal);
            for a in 0..=8 {
                for b in 0..=8 {
                    let (u, v) = (a as f64 / 8.0, b as f64 / 8.0);
                    let (pos, du, dv) = eval_bezier(&p.cp(), u, v);
                    let n = du.cross(dv);
                    let n = if p.flip_normal { -n } else { n };
                    let out = n.normalize().dot((pos - c).normalize());
                    assert!(out > 0.3, "patch {k} at ({u}, {v}): {out}");
                }
            }
            let (pos, du, dv) = eval_bezier(&p.cp(), 0.5, 0.5);
            if du.cross(dv).dot(pos) < 0.0 {
                facing += 1;
            }
        }
        assert_eq!(facing, 3);
    }

    #[test]
    fn coverage_is_solid_and_sized() {
        let s = blob();
        let (w, h) = (64, 48);
        let cov = coverage(&s, w, h, 4);
        let fine = coverage(&s, w, h, 8);
        let area = cov.area();
        assert!(area > 0.0);
        let interior = fine.interior().iter().filter(|&&b| b).count();
        assert!(interior > 200, "{interior} interior pixels");
        assert_eq!(pinholes(&cov.frac, &fine), 0);
        assert!((area - fine.area()).abs() < 0.01 * area);

        // Between the projected discs of an inscribed and a circumscribed sphere (the blob
        // is star-shaped about its centre, which lies on the optical axis).
        let c = centre(&s);
        let outer = s
            .patches
            .iter()
            .flat_map(|p| p.cp())
            .map(|p| p.distance(c))
            .fold(0.0, f64::max);
        let inner = s
            .patches
            .iter()
            .flat_map(|p| {
                (0..=40 * 40).map(|k| {
                    let (u, v) = ((k % 41) as f64 / 40.0, (k / 41) as f64 / 40.0);
                    eval_bezier(&p.cp(), u, v).0.distance(c)
                })
            })
            .fold(f64::INFINITY, f64::min)
            * 0.99;
        let f = (w.min(h) as f64 / 2.0) / (s.camera.fov_deg.to_radians() / 2.0).tan();
        let disc = |r: f64| {
            let rp = f * r / (c.z * c.z - r * r).sqrt();
            std::f64::consts::PI * rp * rp
        };
        let (lo, hi) = (disc(inner), disc(outer));
        assert!(
            0.98 * lo < area && area < 1.02 * hi,
            "area {area} not in [{lo}, {hi}]"
        );
        eprintln!("closed blob: area {area:.1} px^2, spheres {lo:.1}..{hi:.1}");
    }
}
