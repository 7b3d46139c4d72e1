//! `NuPatch` (orders 2 to 4 in u and v independently, rational or not) to bicubic Bezier
//! patches in homogeneous coordinates.
//!
//! Each non-empty knot span inside [min, max] becomes one Bezier patch. The Bezier points of
//! a span [a, b] of a degree-p direction are what Boehm knot insertion yields after inserting
//! a and b until each has multiplicity p; we compute them directly and locally per span as
//! the blossom values f(a^(p-k) b^k), k = 0..=p (the de Boor triangle with the p insertion
//! parameters), so no global knot vector is rebuilt and zero-length spans are simply skipped
//! (Ramshaw's blossoming; Piegl & Tiller, *The NURBS Book*, sec. 5.3). Degrees 1 and 2 are
//! then raised to 3 exactly ([`elevate_to_cubic`]). Everything is linear in the homogeneous
//! points `(w x, w y, w z, w)`, which is what makes it exact for rational surfaces.

use super::rational::elevate_to_cubic;
use crate::Error;
use glam::DVec4;

/// The lowest order supported (bilinear spans).
pub const MIN_ORDER: usize = 2;
/// The highest order supported (bicubic spans).
pub const MAX_ORDER: usize = 4;

/// A NURBS surface as `NuPatch` gives it.
pub struct NuSurface<'a> {
    pub nu: usize,
    pub nv: usize,
    /// Orders (degree + 1), each in [`MIN_ORDER`]..=[`MAX_ORDER`].
    pub uorder: usize,
    pub vorder: usize,
    /// nu + uorder and nv + vorder knots, non-decreasing.
    pub uknot: &'a [f64],
    pub vknot: &'a [f64],
    pub urange: (f64, f64),
    pub vrange: (f64, f64),
    /// nu * nv homogeneous points `(w x, w y, w z, w)` (RenderMan's "Pw"; w = 1 for "P"),
    /// u varying fastest.
    pub points: &'a [DVec4],
}

/// A parameter span [a, b] over knot interval i (t_i <= a < b <= t_{i+1}).
#[derive(Clone, Copy, Debug, PartialEq)]
struct Span {
    i: usize,
    a: f64,
    b: f64,
}

/// Checks an order, knot vector and range (RenderMan rules: non-decreasing, length n +
/// order, t[order-1] <= min < max <= t[n]) and lists the non-empty spans inside the range.
fn spans(
    dir: char,
    n: usize,
    order: usize,
    knots: &[f64],
    (min, max): (f64, f64),
) -> Result<Vec<Span>, Error> {
    if !(MIN_ORDER..=MAX_ORDER).contains(&order) {
        return Err(Error::InvalidSurface(format!(
            "{dir} order {order} is not supported (orders {MIN_ORDER} to {MAX_ORDER}: \
             linear to cubic)"
        )));
    }
    if n < order {
        return Err(Error::InvalidSurface(format!(
            "n{dir} = {n} is less than the order {order}"
        )));
    }
    if knots.len() != n + order {
        return Err(Error::InvalidSurface(format!(
            "{dir} knot vector has {} values, expected n{dir} + order = {}",
            knots.len(),
            n + order
        )));
    }
    if let Some(k) = knots.iter().position(|k| !k.is_finite()) {
        return Err(Error::InvalidSurface(format!(
            "{dir} knot {k} is not finite"
        )));
    }
    if knots.windows(2).any(|w| w[1] < w[0]) {
        return Err(Error::InvalidSurface(format!(
            "{dir} knot vector is decreasing somewhere"
        )));
    }
    let (lo, hi) = (knots[order - 1], knots[n]);
    if !(min.is_finite() && max.is_finite() && lo <= min && min < max && max <= hi) {
        return Err(Error::InvalidSurface(format!(
            "{dir} range [{min}, {max}] is not within the knot range [{lo}, {hi}] \
             (need {dir}min < {dir}max)"
        )));
    }
    let mut out = Vec::new();
    for i in order - 1..n {
        let a = knots[i].max(min);
        let b = knots[i + 1].min(max);
        if a < b {
            out.push(Span { i, a, b });
        }
    }
    Ok(out)
}

/// The blossom of the degree-p curve segment over knot interval `i` (control points
/// q[0..=p] = P[i-p..=i]) at the p arguments x: p rounds of de Boor / Boehm insertion.
fn blossom(knots: &[f64], mut q: [DVec4; 4], p: usize, i: usize, x: &[f64]) -> DVec4 {
    for r in 1..=p {
        for j in (i + r - p..=i).rev() {
            let k = j + p - i;
            // t_j <= t_i < t_{i+1} <= t_{j+p+1-r}: the denominator is positive.
            let alpha = (x[r - 1] - knots[j]) / (knots[j + p + 1 - r] - knots[j]);
            q[k] = q[k - 1] * (1.0 - alpha) + q[k] * alpha;
        }
    }
    q[p]
}

/// The cubic Bezier control points of one span of a degree-p curve (`pts[0..=p]` are the
/// span's de Boor points), elevated to degree 3.
fn span_to_bezier(knots: &[f64], pts: [DVec4; 4], p: usize, s: Span) -> [DVec4; 4] {
    let mut bz = [DVec4::ZERO; 4];
    for (k, b) in bz.iter_mut().enumerate().take(p + 1) {
        let x: Vec<f64> = (0..p).map(|m| if m < p - k { s.a } else { s.b }).collect();
        *b = blossom(knots, pts, p, s.i, &x);
    }
    elevate_to_cubic(&bz[..=p])
}

/// Number of Bezier patches the surface will produce (nonempty u spans x v spans).
pub fn span_count(s: &NuSurface) -> Result<usize, Error> {
    Ok(spans('u', s.nu, s.uorder, s.uknot, s.urange)?.len()
        * spans('v', s.nv, s.vorder, s.vknot, s.vrange)?.len())
}

/// A span of one direction as (knot interval i, a, b) with t_i <= a < b <= t_{i+1}.
pub type SpanRange = (usize, f64, f64);

/// For each patch [`to_bezier`] makes, in its order: its u and v span (what primitive
/// variables of class uniform and varying are looked up by).
pub fn patch_spans(s: &NuSurface) -> Result<Vec<[SpanRange; 2]>, Error> {
    let us = spans('u', s.nu, s.uorder, s.uknot, s.urange)?;
    let vs = spans('v', s.nv, s.vorder, s.vknot, s.vrange)?;
    Ok((vs.iter())
        .flat_map(|v| us.iter().map(move |u| [(u.i, u.a, u.b), (v.i, v.a, v.b)]))
        .collect())
}

/// Converts the surface to homogeneous bicubic Bezier patches (cp[4*v + u]), ordered v-span
/// major, u-span minor. Errors (orders, knots, ranges, the point count) are messages without
/// a location; the caller adds it.
pub fn to_bezier(s: &NuSurface) -> Result<Vec<[DVec4; 16]>, Error> {
    let us = spans('u', s.nu, s.uorder, s.uknot, s.urange)?;
    let vs = spans('v', s.nv, s.vorder, s.vknot, s.vrange)?;
    if s.points.len() != s.nu * s.nv {
        return Err(Error::InvalidSurface(format!(
            "has {} control points, expected nu * nv = {}",
            s.points.len(),
            s.nu * s.nv
        )));
    }
    let (pu, pv) = (s.uorder - 1, s.vorder - 1);
    // Pass 1 (u): every row of control points becomes 4 Bezier points per u span.
    let width = 4 * us.len();
    let mut rows = vec![DVec4::ZERO; width * s.nv];
    for r in 0..s.nv {
        let row = &s.points[r * s.nu..(r + 1) * s.nu];
        for (si, sp) in us.iter().enumerate() {
            let pts = std::array::from_fn(|k| {
                if k <= pu {
                    row[sp.i - pu + k]
                } else {
                    DVec4::ZERO
                }
            });
            let bz = span_to_bezier(s.uknot, pts, pu, *sp);
            rows[r * width + 4 * si..r * width + 4 * si + 4].copy_from_slice(&bz);
        }
    }
    // Pass 2 (v): every column of that grid becomes 4 Bezier points per v span.
    let mut out = vec![[DVec4::ZERO; 16]; us.len() * vs.len()];
    for c in 0..width {
        let (su, k) = (c / 4, c % 4);
        for (sv, sp) in vs.iter().enumerate() {
            let pts = std::array::from_fn(|m| {
                if m <= pv {
                    rows[(sp.i - pv + m) * width + c]
                } else {
                    DVec4::ZERO
                }
            });
            let bz = span_to_bezier(s.vknot, pts, pv, *sp);
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
    use crate::scene::rational::{eval_rational_bezier, from_homogeneous};
    use glam::DVec3;

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

    /// Direct evaluation sum_ij N_i(u) N_j(v) H_ij (homogeneous), divided by its weight,
    /// with u in knot interval iu, v in iv.
    pub(crate) fn de_boor_eval(s: &NuSurface, u: f64, v: f64, iu: usize, iv: usize) -> DVec3 {
        let mut p = DVec4::ZERO;
        for r in 0..s.nv {
            let wv = basis(s.vknot, r, s.vorder - 1, v, iv);
            for c in 0..s.nu {
                p += s.points[r * s.nu + c] * (basis(s.uknot, c, s.uorder - 1, u, iu) * wv);
            }
        }
        p.truncate() / p.w
    }

    /// A wavy grid of points; weights 1, or varied in (0.3, 2.3) when `rational`.
    fn grid(nu: usize, nv: usize, rational: bool) -> Vec<DVec4> {
        (0..nu * nv)
            .map(|k| {
                let (c, r) = ((k % nu) as f64, (k / nu) as f64);
                let p = DVec3::new(
                    c + 0.2 * (r * 1.3).sin(),
                    r + 0.1 * c * c,
                    (c * 0.7).cos() * (r * 0.4).sin(),
                );
                let w = if rational {
                    1.3 + (k as f64 * 2.1).sin()
                } else {
                    1.0
                };
                (p * w).extend(w)
            })
            .collect()
    }

    /// Bezier patch (su, sv) evaluated at local (s, t) equals the NURBS at the mapped (u, v).
    fn check(s: &NuSurface) {
        let us = spans('u', s.nu, s.uorder, s.uknot, s.urange).unwrap();
        let vs = spans('v', s.nv, s.vorder, s.vknot, s.vrange).unwrap();
        let patches = to_bezier(s).unwrap();
        assert_eq!(patches.len(), us.len() * vs.len());
        assert_eq!(span_count(s).unwrap(), patches.len());
        for (sv, vsp) in vs.iter().enumerate() {
            for (su, usp) in us.iter().enumerate() {
                let (cp, w) = from_homogeneous(&patches[sv * us.len() + su]);
                for a in 0..=6 {
                    for b in 0..=6 {
                        let (a, b) = (a as f64 / 6.0, b as f64 / 6.0);
                        let u = usp.a + a * (usp.b - usp.a);
                        let v = vsp.a + b * (vsp.b - vsp.a);
                        let want = de_boor_eval(s, u, v, usp.i, vsp.i);
                        let got = eval_rational_bezier(&cp, &w, a, b).0;
                        assert!(
                            want.distance(got) < 1e-11,
                            "orders {}x{}, span ({su},{sv}) at ({u},{v}): {want} vs {got}",
                            s.uorder,
                            s.vorder
                        );
                    }
                }
            }
        }
    }

    /// A clamped knot vector of n points and the given order with uneven interior knots.
    fn knots(n: usize, order: usize) -> Vec<f64> {
        let inner = n - order;
        let mut k = vec![0.0; order];
        k.extend((1..=inner).map(|j| j as f64 + 0.3 * (j as f64).sin()));
        k.extend(std::iter::repeat_n(inner as f64 + 1.0, order));
        k
    }

    #[test]
    fn every_order_pair_matches_de_boor_polynomial_and_rational() {
        for rational in [false, true] {
            for uo in MIN_ORDER..=MAX_ORDER {
                for vo in MIN_ORDER..=MAX_ORDER {
                    let (nu, nv) = (uo + 3, vo + 2);
                    let pts = grid(nu, nv, rational);
                    let (uk, vk) = (knots(nu, uo), knots(nv, vo));
                    let s = NuSurface {
                        nu,
                        nv,
                        uorder: uo,
                        vorder: vo,
                        uknot: &uk,
                        vknot: &vk,
                        urange: (uk[uo - 1], uk[nu]),
                        vrange: (vk[vo - 1], vk[nv]),
                        points: &pts,
                    };
                    assert_eq!(span_count(&s).unwrap(), 4 * 3);
                    check(&s);
                    // Polynomial input gives weights exactly 1.
                    if !rational {
                        for p in to_bezier(&s).unwrap() {
                            assert!(p.iter().all(|h| h.w == 1.0));
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn clamped_uniform_matches_de_boor() {
        let pts = grid(5, 7, false);
        let uk = [0.0, 0.0, 0.0, 0.0, 1.0, 2.0, 2.0, 2.0, 2.0];
        let vk = [0.0, 0.0, 0.0, 0.0, 1.0, 2.0, 3.0, 4.0, 4.0, 4.0, 4.0];
        let s = NuSurface {
            nu: 5,
            nv: 7,
            uorder: 4,
            vorder: 4,
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
        for rational in [false, true] {
            let pts = grid(8, 6, rational);
            // Repeated interior knot (a zero-length span, skipped), uneven spacing, unclamped.
            let uk = [
                -1.0, -0.5, 0.0, 0.5, 1.25, 1.25, 2.0, 3.5, 4.0, 4.5, 5.0, 6.0,
            ];
            let vk = [0.0, 0.0, 0.0, 0.0, 0.3, 0.3, 1.0, 1.0, 1.0, 1.0];
            let s = NuSurface {
                nu: 8,
                nv: 6,
                uorder: 4,
                vorder: 4,
                uknot: &uk,
                vknot: &vk,
                urange: (0.5, 4.0),
                vrange: (0.0, 1.0),
                points: &pts,
            };
            // u spans: [0.5,1.25], [1.25,2], [2,3.5], [3.5,4]; v spans: [0,0.3], [0.3,1].
            assert_eq!(span_count(&s).unwrap(), 8);
            check(&s);
            // The same points as order 3 (unclamped, 11 knots) and order 2 in u.
            let uk3 = &uk[..11];
            let s3 = NuSurface {
                uorder: 3,
                uknot: uk3,
                urange: (0.0, 4.0),
                ..s
            };
            check(&s3);
            let uk2 = &uk[..10];
            let s2 = NuSurface {
                uorder: 2,
                uknot: uk2,
                urange: (-0.5, 4.0),
                ..s
            };
            check(&s2);
        }
    }

    #[test]
    fn sub_range_cuts_spans() {
        let pts = grid(6, 4, true);
        let uk = [0.0, 0.0, 0.0, 0.0, 1.0, 2.0, 3.0, 3.0, 3.0, 3.0];
        let vk = [0.0, 0.0, 0.0, 0.0, 1.0, 1.0, 1.0, 1.0];
        let s = NuSurface {
            nu: 6,
            nv: 4,
            uorder: 4,
            vorder: 4,
            uknot: &uk,
            vknot: &vk,
            urange: (0.5, 2.5),
            vrange: (0.25, 0.75),
            points: &pts,
        };
        assert_eq!(span_count(&s).unwrap(), 3);
        check(&s);
        // Order 2 in v over the same 4 rows: 6 knots, spans [1,2] and [2,3] cut to 1.5..2.5.
        let vk2 = [0.0, 1.0, 2.0, 3.0, 4.0, 5.0];
        let s2 = NuSurface {
            vorder: 2,
            vknot: &vk2,
            vrange: (1.5, 2.5),
            ..s
        };
        assert_eq!(span_count(&s2).unwrap(), 6);
        check(&s2);
    }

    #[test]
    fn bad_orders_knots_and_ranges() {
        let pts = grid(4, 4, false);
        let vk = [0.0, 0.0, 0.0, 0.0, 1.0, 1.0, 1.0, 1.0];
        let err = |uorder: usize, uk: &[f64], urange, points: &[DVec4]| {
            to_bezier(&NuSurface {
                nu: 4,
                nv: 4,
                uorder,
                vorder: 4,
                uknot: uk,
                vknot: &vk,
                urange,
                vrange: (0.0, 1.0),
                points,
            })
            .map(|p| p.len())
            .map_err(|e| e.to_string())
        };
        assert_eq!(err(4, &vk, (0.0, 1.0), &pts), Ok(1));
        let short = [0.0, 0.0, 0.0, 1.0, 1.0, 1.0, 1.0];
        assert!(
            err(4, &short, (0.0, 1.0), &pts)
                .unwrap_err()
                .contains("7 values")
        );
        let down = [0.0, 0.0, 0.0, 0.0, 1.0, 0.5, 1.0, 1.0];
        assert!(
            err(4, &down, (0.0, 1.0), &pts)
                .unwrap_err()
                .contains("decreasing")
        );
        assert!(err(4, &vk, (0.0, 2.0), &pts).unwrap_err().contains("range"));
        assert!(err(4, &vk, (0.5, 0.5), &pts).unwrap_err().contains("range"));
        assert!(
            err(4, &vk, (0.0, 1.0), &pts[..15])
                .unwrap_err()
                .contains("control points")
        );
        let nan = [0.0, 0.0, 0.0, 0.0, f64::NAN, 1.0, 1.0, 1.0];
        assert!(
            err(4, &nan, (0.0, 1.0), &pts)
                .unwrap_err()
                .contains("not finite")
        );
        let k9 = [0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 1.0, 1.0, 1.0];
        assert_eq!(
            err(5, &k9, (0.0, 1.0), &pts).unwrap_err(),
            "u order 5 is not supported (orders 2 to 4: linear to cubic)"
        );
        assert!(
            err(1, &vk[..5], (0.0, 1.0), &pts)
                .unwrap_err()
                .contains("order 1")
        );
    }
}
