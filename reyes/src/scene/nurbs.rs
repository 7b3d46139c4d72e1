//! `NuPatch` of order 4 (bicubic, non-rational) to Bezier patches.
//!
//! Each non-empty knot span inside [min, max] becomes one Bezier patch. The Bezier points
//! of a span [a, b] are what Boehm knot insertion yields after inserting a and b until each
//! has multiplicity 3; we compute them directly and locally per span as the blossom values
//! f(a,a,a), f(a,a,b), f(a,b,b), f(b,b,b) (the de Boor triangle with the three insertion
//! parameters), so no global knot vector is rebuilt and zero-length spans are simply skipped.

use glam::DVec3;

/// The only order supported: cubic.
pub const ORDER: usize = 4;

/// A non-rational NURBS surface of order 4 in both directions.
pub struct NuSurface<'a> {
    pub nu: usize,
    pub nv: usize,
    pub uknot: &'a [f64],
    pub vknot: &'a [f64],
    pub urange: (f64, f64),
    pub vrange: (f64, f64),
    /// nu * nv points, u varying fastest.
    pub points: &'a [DVec3],
}

/// A parameter span [a, b] over knot interval i (t_i <= a < b <= t_{i+1}).
#[derive(Clone, Copy, Debug, PartialEq)]
struct Span {
    i: usize,
    a: f64,
    b: f64,
}

/// Checks a knot vector and range (RenderMan rules: non-decreasing, length n + order,
/// t[order-1] <= min < max <= t[n]) and lists the non-empty spans inside the range.
fn spans(dir: char, n: usize, knots: &[f64], (min, max): (f64, f64)) -> Result<Vec<Span>, String> {
    if n < ORDER {
        return Err(format!("n{dir} = {n} is less than the order {ORDER}"));
    }
    if knots.len() != n + ORDER {
        return Err(format!(
            "{dir} knot vector has {} values, expected n{dir} + order = {}",
            knots.len(),
            n + ORDER
        ));
    }
    if let Some(k) = knots.iter().position(|k| !k.is_finite()) {
        return Err(format!("{dir} knot {k} is not finite"));
    }
    if knots.windows(2).any(|w| w[1] < w[0]) {
        return Err(format!("{dir} knot vector is decreasing somewhere"));
    }
    let (lo, hi) = (knots[ORDER - 1], knots[n]);
    if !(min.is_finite() && max.is_finite() && lo <= min && min < max && max <= hi) {
        return Err(format!(
            "{dir} range [{min}, {max}] is not within the knot range [{lo}, {hi}] \
             (need {dir}min < {dir}max)"
        ));
    }
    let mut out = Vec::new();
    for i in ORDER - 1..n {
        let a = knots[i].max(min);
        let b = knots[i + 1].min(max);
        if a < b {
            out.push(Span { i, a, b });
        }
    }
    Ok(out)
}

/// The blossom of the curve segment over knot interval `i` (control points p[0..4] =
/// P[i-3..=i]) at arguments x: three rounds of de Boor / Boehm insertion.
fn blossom(knots: &[f64], mut q: [DVec3; 4], i: usize, x: [f64; 3]) -> DVec3 {
    for r in 1..=3 {
        for j in (i + r - 3..=i).rev() {
            let k = j + 3 - i;
            let alpha = (x[r - 1] - knots[j]) / (knots[j + 4 - r] - knots[j]);
            q[k] = q[k - 1] * (1.0 - alpha) + q[k] * alpha;
        }
    }
    q[3]
}

/// The 4 Bezier control points of one span of a curve.
fn span_to_bezier(knots: &[f64], pts: [DVec3; 4], s: Span) -> [DVec3; 4] {
    let (a, b) = (s.a, s.b);
    [
        blossom(knots, pts, s.i, [a, a, a]),
        blossom(knots, pts, s.i, [a, a, b]),
        blossom(knots, pts, s.i, [a, b, b]),
        blossom(knots, pts, s.i, [b, b, b]),
    ]
}

/// Number of Bezier patches the surface will produce (nonempty u spans x v spans).
pub fn span_count(s: &NuSurface) -> Result<usize, String> {
    Ok(spans('u', s.nu, s.uknot, s.urange)?.len() * spans('v', s.nv, s.vknot, s.vrange)?.len())
}

/// Converts the surface to Bezier patches (cp[4*v + u]), ordered v-span major, u-span minor.
pub fn to_bezier(s: &NuSurface) -> Result<Vec<[DVec3; 16]>, String> {
    let us = spans('u', s.nu, s.uknot, s.urange)?;
    let vs = spans('v', s.nv, s.vknot, s.vrange)?;
    if s.points.len() != s.nu * s.nv {
        return Err(format!(
            "has {} control points, expected nu * nv = {}",
            s.points.len(),
            s.nu * s.nv
        ));
    }
    // Pass 1 (u): every row of control points becomes 4 Bezier points per u span.
    let width = 4 * us.len();
    let mut rows = vec![DVec3::ZERO; width * s.nv];
    for r in 0..s.nv {
        let row = &s.points[r * s.nu..(r + 1) * s.nu];
        for (si, sp) in us.iter().enumerate() {
            let pts = std::array::from_fn(|k| row[sp.i - 3 + k]);
            let bz = span_to_bezier(s.uknot, pts, *sp);
            rows[r * width + 4 * si..r * width + 4 * si + 4].copy_from_slice(&bz);
        }
    }
    // Pass 2 (v): every column of that grid becomes 4 Bezier points per v span.
    let mut out = vec![[DVec3::ZERO; 16]; us.len() * vs.len()];
    for c in 0..width {
        let (su, k) = (c / 4, c % 4);
        for (sv, sp) in vs.iter().enumerate() {
            let pts = std::array::from_fn(|m| rows[(sp.i - 3 + m) * width + c]);
            let bz = span_to_bezier(s.vknot, pts, *sp);
            let patch = &mut out[sv * us.len() + su];
            for (l, p) in bz.into_iter().enumerate() {
                patch[4 * l + k] = p;
            }
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::eval_bezier;

    /// Cox-de Boor basis function N_{j,p}(t) on knot interval `span` (the degree-0 function
    /// is 1 on that interval only, so t may sit on either end of it). Independent of the
    /// blossom code.
    fn basis(knots: &[f64], j: usize, p: usize, t: f64, span: usize) -> f64 {
        if p == 0 {
            return if j == span { 1.0 } else { 0.0 };
        }
        let mut v = 0.0;
        let d1 = knots[j + p] - knots[j];
        if d1 > 0.0 {
            v += (t - knots[j]) / d1 * basis(knots, j, p - 1, t, span);
        }
        let d2 = knots[j + p + 1] - knots[j + 1];
        if d2 > 0.0 {
            v += (knots[j + p + 1] - t) / d2 * basis(knots, j + 1, p - 1, t, span);
        }
        v
    }

    /// Direct evaluation sum_ij N_i(u) N_j(v) P_ij with u in knot interval iu, v in iv.
    fn de_boor_eval(s: &NuSurface, u: f64, v: f64, iu: usize, iv: usize) -> DVec3 {
        let mut p = DVec3::ZERO;
        for r in 0..s.nv {
            let wv = basis(s.vknot, r, 3, v, iv);
            for c in 0..s.nu {
                p += s.points[r * s.nu + c] * (basis(s.uknot, c, 3, u, iu) * wv);
            }
        }
        p
    }

    fn grid(nu: usize, nv: usize) -> Vec<DVec3> {
        (0..nu * nv)
            .map(|k| {
                let (c, r) = ((k % nu) as f64, (k / nu) as f64);
                DVec3::new(
                    c + 0.2 * (r * 1.3).sin(),
                    r + 0.1 * c * c,
                    (c * 0.7).cos() * (r * 0.4).sin(),
                )
            })
            .collect()
    }

    /// Bezier patch (su, sv) evaluated at local (s, t) equals the NURBS at the mapped (u, v).
    fn check(s: &NuSurface) {
        let us = spans('u', s.nu, s.uknot, s.urange).unwrap();
        let vs = spans('v', s.nv, s.vknot, s.vrange).unwrap();
        let patches = to_bezier(s).unwrap();
        assert_eq!(patches.len(), us.len() * vs.len());
        assert_eq!(span_count(s).unwrap(), patches.len());
        for (sv, vsp) in vs.iter().enumerate() {
            for (su, usp) in us.iter().enumerate() {
                let patch = &patches[sv * us.len() + su];
                for (a, b) in [(0.0, 0.0), (0.3, 0.6), (1.0, 0.5), (0.8, 1.0), (1.0, 1.0)] {
                    let u = usp.a + a * (usp.b - usp.a);
                    let v = vsp.a + b * (vsp.b - vsp.a);
                    let want = de_boor_eval(s, u, v, usp.i, vsp.i);
                    let got = eval_bezier(patch, a, b).0;
                    assert!(
                        want.distance(got) < 1e-11,
                        "span ({su},{sv}) at ({u},{v}): {want} vs {got}"
                    );
                }
            }
        }
    }

    #[test]
    fn clamped_uniform_matches_de_boor() {
        let pts = grid(5, 7);
        let uk = [0.0, 0.0, 0.0, 0.0, 1.0, 2.0, 2.0, 2.0, 2.0];
        let vk = [0.0, 0.0, 0.0, 0.0, 1.0, 2.0, 3.0, 4.0, 4.0, 4.0, 4.0];
        let s = NuSurface {
            nu: 5,
            nv: 7,
            uknot: &uk,
            vknot: &vk,
            urange: (0.0, 2.0),
            vrange: (0.0, 4.0),
            points: &pts,
        };
        assert_eq!(span_count(&s).unwrap(), 8);
        check(&s);
    }

    #[test]
    fn nonuniform_repeated_and_unclamped_knots() {
        let pts = grid(8, 6);
        // Repeated interior knot (a zero-length span, skipped), uneven spacing, unclamped.
        let uk = [
            -1.0, -0.5, 0.0, 0.5, 1.25, 1.25, 2.0, 3.5, 4.0, 4.5, 5.0, 6.0,
        ];
        let vk = [0.0, 0.0, 0.0, 0.0, 0.3, 0.3, 1.0, 1.0, 1.0, 1.0];
        let s = NuSurface {
            nu: 8,
            nv: 6,
            uknot: &uk,
            vknot: &vk,
            urange: (0.5, 4.0),
            vrange: (0.0, 1.0),
            points: &pts,
        };
        // u spans: [0.5,1.25], [1.25,2], [2,3.5], [3.5,4]; v spans: [0,0.3], [0.3,1].
        assert_eq!(span_count(&s).unwrap(), 8);
        check(&s);
    }

    #[test]
    fn sub_range_cuts_spans() {
        let pts = grid(6, 4);
        let uk = [0.0, 0.0, 0.0, 0.0, 1.0, 2.0, 3.0, 3.0, 3.0, 3.0];
        let vk = [0.0, 0.0, 0.0, 0.0, 1.0, 1.0, 1.0, 1.0];
        let s = NuSurface {
            nu: 6,
            nv: 4,
            uknot: &uk,
            vknot: &vk,
            urange: (0.5, 2.5),
            vrange: (0.25, 0.75),
            points: &pts,
        };
        assert_eq!(span_count(&s).unwrap(), 3);
        check(&s);
    }

    #[test]
    fn bad_knots_and_ranges() {
        let pts = grid(4, 4);
        let vk = [0.0, 0.0, 0.0, 0.0, 1.0, 1.0, 1.0, 1.0];
        let err = |uk: &[f64], urange, points: &[DVec3]| {
            to_bezier(&NuSurface {
                nu: 4,
                nv: 4,
                uknot: uk,
                vknot: &vk,
                urange,
                vrange: (0.0, 1.0),
                points,
            })
            .map(|p| p.len())
        };
        assert_eq!(err(&vk, (0.0, 1.0), &pts), Ok(1));
        let short = [0.0, 0.0, 0.0, 1.0, 1.0, 1.0, 1.0];
        assert!(
            err(&short, (0.0, 1.0), &pts)
                .unwrap_err()
                .contains("7 values")
        );
        let down = [0.0, 0.0, 0.0, 0.0, 1.0, 0.5, 1.0, 1.0];
        assert!(
            err(&down, (0.0, 1.0), &pts)
                .unwrap_err()
                .contains("decreasing")
        );
        assert!(err(&vk, (0.0, 2.0), &pts).unwrap_err().contains("range"));
        assert!(err(&vk, (0.5, 0.5), &pts).unwrap_err().contains("range"));
        assert!(
            err(&vk, (0.0, 1.0), &pts[..15])
                .unwrap_err()
                .contains("control points")
        );
        let nan = [0.0, 0.0, 0.0, 0.0, f64::NAN, 1.0, 1.0, 1.0];
        assert!(
            err(&nan, (0.0, 1.0), &pts)
                .unwrap_err()
                .contains("not finite")
        );
    }
}
