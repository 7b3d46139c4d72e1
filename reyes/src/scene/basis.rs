//! Bicubic patch bases (RenderMan `Basis`) and their conversion to Bezier form.
//!
//! A basis matrix M (rows for t^3, t^2, t, 1) defines the curve P(t) = [t^3 t^2 t 1] M G.
//! The same curve in Bezier form has control points Mbez^-1 M G, so a 4x4 block of control
//! points G[v][u] becomes (Mbez^-1 Mv) G (Mbez^-1 Mu)^T: the renderer only ever sees Bezier
//! patches.

use glam::DVec3;

/// A 4x4 matrix as rows, in RenderMan's `RtBasis` layout.
pub type Mat4x4 = [[f64; 4]; 4];

/// A cubic basis: its matrix and the step (in control points) between successive patches of
/// a `PatchMesh`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Basis {
    /// The basis matrix, rows for t^3, t^2, t, 1.
    pub matrix: Mat4x4,
    /// Control points from one patch of a `PatchMesh` to the next.
    pub step: u32,
}

const BEZIER: Mat4x4 = [
    [-1.0, 3.0, -3.0, 1.0],
    [3.0, -6.0, 3.0, 0.0],
    [-3.0, 3.0, 0.0, 0.0],
    [1.0, 0.0, 0.0, 0.0],
];

const S6: f64 = 1.0 / 6.0;
const B_SPLINE: Mat4x4 = [
    [-S6, 3.0 * S6, -3.0 * S6, S6],
    [3.0 * S6, -6.0 * S6, 3.0 * S6, 0.0],
    [-3.0 * S6, 0.0, 3.0 * S6, 0.0],
    [S6, 4.0 * S6, S6, 0.0],
];

const CATMULL_ROM: Mat4x4 = [
    [-0.5, 1.5, -1.5, 0.5],
    [1.0, -2.5, 2.0, -0.5],
    [-0.5, 0.0, 0.5, 0.0],
    [0.0, 1.0, 0.0, 0.0],
];

/// Geometry order (point0, vector0, point1, vector1), as RenderMan defines it.
const HERMITE: Mat4x4 = [
    [2.0, 1.0, -2.0, 1.0],
    [-3.0, -2.0, 3.0, -1.0],
    [0.0, 1.0, 0.0, 0.0],
    [1.0, 0.0, 0.0, 0.0],
];

const POWER: Mat4x4 = [
    [1.0, 0.0, 0.0, 0.0],
    [0.0, 1.0, 0.0, 0.0],
    [0.0, 0.0, 1.0, 0.0],
    [0.0, 0.0, 0.0, 1.0],
];

/// Inverse of the Bezier matrix: maps power coefficients to Bezier control points.
const BEZIER_INV: Mat4x4 = [
    [0.0, 0.0, 0.0, 1.0],
    [0.0, 0.0, 1.0 / 3.0, 1.0],
    [0.0, 1.0 / 3.0, 2.0 / 3.0, 1.0],
    [1.0, 1.0, 1.0, 1.0],
];

impl Basis {
    /// `"bezier"`, step 3.
    pub const BEZIER: Basis = Basis {
        matrix: BEZIER,
        step: 3,
    };
    /// `"b-spline"` (uniform cubic B-spline), step 1.
    pub const B_SPLINE: Basis = Basis {
        matrix: B_SPLINE,
        step: 1,
    };
    /// `"catmull-rom"`, step 1.
    pub const CATMULL_ROM: Basis = Basis {
        matrix: CATMULL_ROM,
        step: 1,
    };
    /// `"hermite"`: control points alternate positions and tangents, step 2.
    pub const HERMITE: Basis = Basis {
        matrix: HERMITE,
        step: 2,
    };
    /// `"power"`: the control points are the polynomial's coefficients, step 4.
    pub const POWER: Basis = Basis {
        matrix: POWER,
        step: 4,
    };

    /// A standard basis by its RIB name, with its standard step.
    pub fn by_name(name: &str) -> Option<Basis> {
        Some(match name {
            "bezier" => Basis::BEZIER,
            "b-spline" => Basis::B_SPLINE,
            "catmull-rom" => Basis::CATMULL_ROM,
            "hermite" => Basis::HERMITE,
            "power" => Basis::POWER,
            _ => return None,
        })
    }

    pub(crate) fn is_bezier(&self) -> bool {
        self.matrix == BEZIER
    }

    /// The matrix C with bezier_points = C * points of this basis.
    pub fn to_bezier(&self) -> Mat4x4 {
        mul(&BEZIER_INV, &self.matrix)
    }
}

fn mul(a: &Mat4x4, b: &Mat4x4) -> Mat4x4 {
    std::array::from_fn(|i| std::array::from_fn(|j| (0..4).map(|k| a[i][k] * b[k][j]).sum()))
}

/// Converts a 4x4 block of control points (g[4*v + u]) in bases (`ub`, `vb`) to Bezier:
/// H = Cv G Cu^T with C = Mbez^-1 M.
pub fn block_to_bezier(g: &[DVec3; 16], ub: &Basis, vb: &Basis) -> [DVec3; 16] {
    if ub.is_bezier() && vb.is_bezier() {
        return *g;
    }
    let cu = ub.to_bezier();
    let cv = vb.to_bezier();
    // Rows first (u direction): T[v][i] = sum_j Cu[i][j] G[v][j].
    let mut t = [DVec3::ZERO; 16];
    for v in 0..4 {
        for i in 0..4 {
            t[4 * v + i] = (0..4).map(|j| g[4 * v + j] * cu[i][j]).sum();
        }
    }
    // Then columns (v direction): H[k][u] = sum_v Cv[k][v] T[v][u].
    std::array::from_fn(|idx| {
        let (k, u) = (idx / 4, idx % 4);
        (0..4).map(|v| t[4 * v + u] * cv[k][v]).sum()
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Evaluates a patch in its own basis: [u^3 u^2 u 1] M G... summed as a tensor product.
    fn eval_in_basis(g: &[DVec3; 16], ub: &Basis, vb: &Basis, u: f64, v: f64) -> DVec3 {
        let w = |m: &Mat4x4, t: f64| -> [f64; 4] {
            let tt = [t * t * t, t * t, t, 1.0];
            std::array::from_fn(|j| (0..4).map(|k| tt[k] * m[k][j]).sum())
        };
        let (wu, wv) = (w(&ub.matrix, u), w(&vb.matrix, v));
        let mut p = DVec3::ZERO;
        for j in 0..4 {
            for i in 0..4 {
                p += g[4 * j + i] * (wu[i] * wv[j]);
            }
        }
        p
    }

    fn sample_block() -> [DVec3; 16] {
        std::array::from_fn(|k| {
            let (u, v) = ((k % 4) as f64, (k / 4) as f64);
            DVec3::new(
                u + 0.3 * v * v,
                v - 0.2 * u * v,
                (u * 1.7).sin() + (v * 0.9).cos(),
            )
        })
    }

    #[test]
    fn bezier_inverse_is_inverse() {
        let p = mul(&BEZIER, &BEZIER_INV);
        for (i, row) in p.iter().enumerate() {
            for (j, x) in row.iter().enumerate() {
                assert!((x - if i == j { 1.0 } else { 0.0 }).abs() < 1e-15);
            }
        }
    }

    #[test]
    fn every_basis_converts_to_the_same_surface() {
        let g = sample_block();
        let all = [
            Basis::BEZIER,
            Basis::B_SPLINE,
            Basis::CATMULL_ROM,
            Basis::HERMITE,
            Basis::POWER,
        ];
        for ub in &all {
            for vb in &all {
                let h = block_to_bezier(&g, ub, vb);
                for (u, v) in [(0.0, 0.0), (0.25, 0.5), (1.0, 0.3), (0.7, 1.0), (0.5, 0.5)] {
                    let a = eval_in_basis(&g, ub, vb, u, v);
                    let b = super::super::eval_bezier(&h, u, v).0;
                    assert!(
                        a.distance(b) < 1e-12,
                        "{ub:?} {vb:?} at ({u},{v}): {a} vs {b}"
                    );
                }
            }
        }
    }

    #[test]
    fn b_spline_block_to_bezier_known_values() {
        // A uniform cubic B-spline segment over points 0,1,2,3 (on a line) starts at 1 and
        // ends at 2, with Bezier inner points at 4/3 and 5/3.
        let g: [DVec3; 16] = std::array::from_fn(|k| DVec3::new((k % 4) as f64, 0.0, 0.0));
        let h = block_to_bezier(&g, &Basis::B_SPLINE, &Basis::B_SPLINE);
        for (i, x) in [1.0, 4.0 / 3.0, 5.0 / 3.0, 2.0].iter().enumerate() {
            assert!((h[i].x - x).abs() < 1e-14);
        }
    }

    #[test]
    fn names_and_steps() {
        assert_eq!(Basis::by_name("bezier").unwrap().step, 3);
        assert_eq!(Basis::by_name("b-spline").unwrap().step, 1);
        assert_eq!(Basis::by_name("catmull-rom").unwrap().step, 1);
        assert_eq!(Basis::by_name("hermite").unwrap().step, 2);
        assert_eq!(Basis::by_name("power").unwrap().step, 4);
        assert!(Basis::by_name("nurbs").is_none());
    }
}
