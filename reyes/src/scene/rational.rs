//! Rational Bezier building blocks shared by the NURBS and quadric conversions: homogeneous
//! points, exact degree elevation to cubic, the rational quadratic circular arc, the
//! homogeneous-to-[`Patch`](super::Patch) split, and an f64 evaluator of rational bicubic
//! patches (for tests and checks; the renderer has its own).
//!
//! A homogeneous point is a [`DVec4`] `(w x, w y, w z, w)`: the Euclidean point is
//! `(x, y, z)`, the weight `w`. Every operation here (blossoming, elevation, tensor products)
//! is linear in homogeneous coordinates, which is what makes it exact for rational curves
//! (Piegl & Tiller, *The NURBS Book*, 2nd ed., ch. 4 and 5.5).

use glam::{DVec3, DVec4};

/// Raises a Bezier curve of degree `p = pts.len() - 1` (1, 2 or 3) to degree 3, exactly:
/// Q_i = sum_j C(p, j) C(3-p, i-j) / C(3, i) P_j (Piegl & Tiller eq. 5.36), in homogeneous
/// coordinates so that rational curves stay the same curve with the same parametrisation.
///
/// Panics when `pts` has not 2, 3 or 4 points (callers check orders).
pub fn elevate_to_cubic<T>(pts: &[T]) -> [T; 4]
where
    T: Copy + std::ops::Add<Output = T> + std::ops::Mul<f64, Output = T>,
{
    match *pts {
        [a, b] => [
            a,
            a * (2.0 / 3.0) + b * (1.0 / 3.0),
            a * (1.0 / 3.0) + b * (2.0 / 3.0),
            b,
        ],
        [a, b, c] => [
            a,
            a * (1.0 / 3.0) + b * (2.0 / 3.0),
            b * (2.0 / 3.0) + c * (1.0 / 3.0),
            c,
        ],
        [a, b, c, d] => [a, b, c, d],
        _ => panic!(
            "elevate_to_cubic: degree {} is not 1..=3",
            pts.len() as i64 - 1
        ),
    }
}

/// The unit circle arc from angle `a0` to `a1` (radians, either direction, |a1 - a0| at most
/// pi/2 so that the middle weight cos((a1 - a0)/2) stays >= sqrt(1/2)) as a rational quadratic
/// Bezier curve, homogeneous `(w cos, w sin, w)`: end points on the circle with weight 1, the
/// middle point where the end tangents meet, with weight cos of half the sweep (Piegl &
/// Tiller sec. 7.3). The angle is not proportional to the curve parameter (it is at the ends
/// and the middle only).
pub fn arc(a0: f64, a1: f64) -> [DVec3; 3] {
    let half = 0.5 * (a1 - a0);
    let wm = half.cos();
    let am = a0 + half;
    // The middle point is (cos am, sin am) / wm; homogeneous it is (cos am, sin am, wm).
    [
        DVec3::new(a0.cos(), a0.sin(), 1.0),
        DVec3::new(am.cos(), am.sin(), wm),
        DVec3::new(a1.cos(), a1.sin(), 1.0),
    ]
}

/// Splits the sweep from `a0` to `a1` (radians) into the fewest equal pieces of at most a
/// quarter turn: their end angles, first `a0`, last `a1` (just `[a0, a1]` for an empty sweep).
pub fn quarter_turns(a0: f64, a1: f64) -> Vec<f64> {
    let turns = (a1 - a0).abs() / std::f64::consts::FRAC_PI_2;
    // A tolerance so that an exact quarter (or half, ...) turn given in degrees is not split
    // once more for a rounding error.
    let n = ((turns - 1e-9).ceil() as usize).max(1);
    (0..=n)
        .map(|k| match k {
            0 => a0,
            k if k == n => a1,
            k => a0 + (a1 - a0) * (k as f64 / n as f64),
        })
        .collect()
}

/// Splits a homogeneous bicubic patch (cp[4*v + u]) into the Euclidean control points and
/// weights that [`Patch`](super::Patch) holds. When every weight is exactly 1 the points are
/// taken as they are and the weights are [`Patch::POLYNOMIAL`](super::Patch::POLYNOMIAL);
/// otherwise the weights are scaled so that the largest is 1 (the surface does not change;
/// the renderer's f32 sees weights in (0, 1]). Weights must be positive (callers check).
pub fn from_homogeneous(h: &[DVec4; 16]) -> ([DVec3; 16], [f64; 16]) {
    if h.iter().all(|p| p.w == 1.0) {
        return (h.map(|p| p.truncate()), [1.0; 16]);
    }
    let max = h.iter().fold(0.0f64, |m, p| m.max(p.w));
    (h.map(|p| p.truncate() / p.w), h.map(|p| p.w / max))
}

/// Cubic Bernstein weights at t and their derivatives: (B_i(t), B_i'(t)), i = 0..3.
pub fn bernstein3(t: f64) -> ([f64; 4], [f64; 4]) {
    let s = 1.0 - t;
    (
        [s * s * s, 3.0 * t * s * s, 3.0 * t * t * s, t * t * t],
        [
            -3.0 * s * s,
            3.0 * s * s - 6.0 * t * s,
            6.0 * t * s - 3.0 * t * t,
            3.0 * t * t,
        ],
    )
}

/// Point, d/du and d/dv at (u, v) of the rational bicubic patch with homogeneous control net
/// `h[4*j + i] = (x w, y w, z w, w)`: X = sum B_i(u) B_j(v) h_ij in 4D and its partial
/// derivatives, then the quotient rule P = X.xyz / X.w, Pu = (Xu.xyz - Xu.w P) / X.w, likewise
/// Pv.
pub fn eval_homogeneous(h: &[DVec4; 16], u: f64, v: f64) -> (DVec3, DVec3, DVec3) {
    let ((bu, du), (bv, dv)) = (bernstein3(u), bernstein3(v));
    let (mut x, mut xu, mut xv) = (DVec4::ZERO, DVec4::ZERO, DVec4::ZERO);
    for j in 0..4 {
        for i in 0..4 {
            let c = h[4 * j + i];
            x += c * (bu[i] * bv[j]);
            xu += c * (du[i] * bv[j]);
            xv += c * (bu[i] * dv[j]);
        }
    }
    let p = x.truncate() / x.w;
    (
        p,
        (xu.truncate() - xu.w * p) / x.w,
        (xv.truncate() - xv.w * p) / x.w,
    )
}

/// Evaluates the rational bicubic Bezier patch sum(B_i(u) B_j(v) w_ij P_ij) / sum(B_i B_j w_ij)
/// (cp and w indexed [4*j + i], u varies fastest, as in [`Patch`](super::Patch)) at (u, v) in
/// [0, 1]^2: the point and its derivatives dP/du and dP/dv (`eval_homogeneous`). With all
/// weights 1 this is [`eval_bezier`](super::eval_bezier).
pub fn eval_rational_bezier(
    cp: &[DVec3; 16],
    w: &[f64; 16],
    u: f64,
    v: f64,
) -> (DVec3, DVec3, DVec3) {
    eval_homogeneous(&std::array::from_fn(|k| (cp[k] * w[k]).extend(w[k])), u, v)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::eval_bezier;

    /// A rational quadratic (homogeneous 2D) at t.
    fn eval_quadratic(h: &[DVec3; 3], t: f64) -> glam::DVec2 {
        let s = 1.0 - t;
        let p = h[0] * (s * s) + h[1] * (2.0 * s * t) + h[2] * (t * t);
        p.truncate() / p.z
    }

    #[test]
    fn arcs_lie_on_the_unit_circle_and_sweep_monotonically() {
        for (a0, a1) in [
            (0.0, std::f64::consts::FRAC_PI_2),
            (0.3, -1.2),
            (2.0, 2.5),
            (-1.0, -1.0),
        ] {
            let h = arc(a0, a1);
            let mut last = a0;
            for k in 0..=100 {
                let t = k as f64 / 100.0;
                let p = eval_quadratic(&h, t);
                assert!((p.length() - 1.0).abs() < 1e-15, "{a0}..{a1} at {t}: {p}");
                // The angle moves from a0 towards a1 without turning back.
                let a = a0
                    + (p.y.atan2(p.x) - a0 + std::f64::consts::PI)
                        .rem_euclid(std::f64::consts::TAU)
                    - std::f64::consts::PI;
                assert!((a - last) * (a1 - a0) >= -1e-15, "{a0}..{a1} at {t}");
                last = a;
            }
            assert!((last - a1).abs() < 1e-15);
        }
    }

    #[test]
    fn quarter_turn_splits() {
        let pi = std::f64::consts::PI;
        assert_eq!(quarter_turns(0.0, 2.0 * pi).len(), 5);
        assert_eq!(quarter_turns(0.0, 90f64.to_radians()).len(), 2);
        assert_eq!(quarter_turns(0.0, -91f64.to_radians()).len(), 3);
        assert_eq!(quarter_turns(0.0, 200f64.to_radians()).len(), 4);
        assert_eq!(quarter_turns(1.0, 1.0), vec![1.0, 1.0]);
        let s = quarter_turns(0.5, -3.0);
        assert_eq!((s[0], *s.last().unwrap()), (0.5, -3.0));
        assert!(
            s.windows(2)
                .all(|w| (w[1] - w[0]).abs() <= pi / 2.0 + 1e-12)
        );
    }

    #[test]
    fn elevation_keeps_the_curve() {
        let q = [
            DVec4::new(0.0, 1.0, 2.0, 1.0),
            DVec4::new(2.0, -1.0, 0.5, 0.5),
            DVec4::new(3.0, 3.0, 1.0, 2.0),
        ];
        let c = elevate_to_cubic(&q);
        let l = elevate_to_cubic(&q[..2]);
        for k in 0..=10 {
            let t = k as f64 / 10.0;
            let s = 1.0 - t;
            let quad = q[0] * (s * s) + q[1] * (2.0 * s * t) + q[2] * (t * t);
            let lin = q[0] * s + q[1] * t;
            let cub = |c: &[DVec4; 4]| {
                c[0] * (s * s * s)
                    + c[1] * (3.0 * s * s * t)
                    + c[2] * (3.0 * s * t * t)
                    + c[3] * (t * t * t)
            };
            assert!((cub(&c) - quad).length() < 1e-14);
            assert!((cub(&l) - lin).length() < 1e-14);
        }
        assert_eq!(elevate_to_cubic(&[1.0, 1.0, 1.0]), [1.0; 4]);
        assert_eq!(elevate_to_cubic(&[1.0, 1.0]), [1.0; 4]);
    }

    #[test]
    fn rational_evaluator_matches_polynomial_and_finite_differences() {
        let cp: [DVec3; 16] = std::array::from_fn(|k| {
            let (i, j) = ((k % 4) as f64, (k / 4) as f64);
            DVec3::new(i, j, (i * 1.3).sin() + j * j * 0.2)
        });
        for (u, v) in [(0.0, 0.0), (0.3, 0.7), (1.0, 0.5)] {
            let a = eval_rational_bezier(&cp, &[1.0; 16], u, v);
            let b = eval_bezier(&cp, u, v);
            assert!((a.0 - b.0).length() < 1e-14);
            assert!((a.1 - b.1).length() < 1e-13 && (a.2 - b.2).length() < 1e-13);
        }
        // Scaling all weights changes nothing; derivatives match central differences.
        let w: [f64; 16] = std::array::from_fn(|k| 0.5 + (k as f64 * 0.7).sin().abs());
        let w2 = w.map(|x| x * 3.0);
        let h = 1e-6;
        for (u, v) in [(0.2, 0.3), (0.6, 0.9)] {
            let (p, pu, pv) = eval_rational_bezier(&cp, &w, u, v);
            assert!((eval_rational_bezier(&cp, &w2, u, v).0 - p).length() < 1e-14);
            let fu = (eval_rational_bezier(&cp, &w, u + h, v).0
                - eval_rational_bezier(&cp, &w, u - h, v).0)
                / (2.0 * h);
            let fv = (eval_rational_bezier(&cp, &w, u, v + h).0
                - eval_rational_bezier(&cp, &w, u, v - h).0)
                / (2.0 * h);
            assert!((fu - pu).length() < 1e-7 && (fv - pv).length() < 1e-7);
        }
    }

    #[test]
    fn homogeneous_split() {
        let h: [DVec4; 16] = std::array::from_fn(|k| DVec4::new(k as f64, 1.0, 2.0, 1.0));
        let (cp, w) = from_homogeneous(&h);
        assert_eq!(w, [1.0; 16]);
        assert_eq!(cp[5], DVec3::new(5.0, 1.0, 2.0));
        let h: [DVec4; 16] =
            std::array::from_fn(|k| DVec4::new(2.0, 4.0, 6.0, 2.0) * (k + 1) as f64);
        let (cp, w) = from_homogeneous(&h);
        assert!(
            cp.iter()
                .all(|p| (*p - DVec3::new(1.0, 2.0, 3.0)).length() < 1e-15)
        );
        assert_eq!(w[15], 1.0);
        assert!((w[0] - 1.0 / 16.0).abs() < 1e-16);
    }
}
