//! NuPatch of orders 2 to 4, rational "Pw", subranges: the patches the reader makes against
//! direct B-spline evaluation (de Boor's algorithm, written here independently of the
//! reader's blossoms), and the field file's rational sphere.

use super::*;
use crate::scene::eval_rational_bezier;
use glam::DVec4;

/// De Boor's algorithm: the point at t of the curve of the given order over `knots` with
/// homogeneous control points `pts`, in knot interval k (t_k <= t <= t_{k+1}).
fn de_boor(knots: &[f64], pts: &[DVec4], order: usize, k: usize, t: f64) -> DVec4 {
    let p = order - 1;
    let mut d: Vec<DVec4> = (0..=p).map(|j| pts[j + k - p]).collect();
    for r in 1..=p {
        for j in (r..=p).rev() {
            let i = j + k - p;
            let alpha = (t - knots[i]) / (knots[i + 1 + p - r] - knots[i]);
            d[j] = d[j - 1] * (1.0 - alpha) + d[j] * alpha;
        }
    }
    d[p]
}

/// The knot intervals [a, b] (with their index) of the range [min, max].
fn spans(knots: &[f64], n: usize, order: usize, (min, max): (f64, f64)) -> Vec<(usize, f64, f64)> {
    (order - 1..n)
        .filter_map(|i| {
            let (a, b) = (knots[i].max(min), knots[i + 1].min(max));
            (a < b).then_some((i, a, b))
        })
        .collect()
}

/// A NuPatch request and its homogeneous points: a wavy nu x nv grid, weights varied when
/// `rational` (and then given as "Pw").
struct Nurbs {
    nu: usize,
    nv: usize,
    uorder: usize,
    vorder: usize,
    uknot: Vec<f64>,
    vknot: Vec<f64>,
    urange: (f64, f64),
    vrange: (f64, f64),
    rational: bool,
}

impl Nurbs {
    fn points(&self) -> Vec<DVec4> {
        (0..self.nu * self.nv)
            .map(|k| {
                let (c, r) = ((k % self.nu) as f64, (k / self.nu) as f64);
                let p = DVec3::new(c, r + 0.2 * c, (c * 0.9).sin() * (r * 0.7 + 0.3).cos());
                let w = if self.rational {
                    1.2 + (k as f64 * 1.7).sin()
                } else {
                    1.0
                };
                (p * w).extend(w)
            })
            .collect()
    }

    fn rib(&self) -> String {
        let list = |v: &[f64]| v.iter().map(f64::to_string).collect::<Vec<_>>().join(" ");
        let (name, nums): (&str, Vec<f64>) = if self.rational {
            (
                "Pw",
                self.points().iter().flat_map(|p| p.to_array()).collect(),
            )
        } else {
            (
                "P",
                self.points()
                    .iter()
                    .flat_map(|p| p.truncate().to_array())
                    .collect(),
            )
        };
        world(&format!(
            "NuPatch {} {} [{}] {} {} {} {} [{}] {} {} \"{name}\" [{}]",
            self.nu,
            self.uorder,
            list(&self.uknot),
            self.urange.0,
            self.urange.1,
            self.nv,
            self.vorder,
            list(&self.vknot),
            self.vrange.0,
            self.vrange.1,
            list(&nums)
        ))
    }

    /// The surface point at (u, v) in knot intervals (ku, kv), directly.
    fn eval(&self, ku: usize, u: f64, kv: usize, v: f64) -> DVec3 {
        let pts = self.points();
        let column: Vec<DVec4> = (0..self.nv)
            .map(|r| {
                de_boor(
                    &self.uknot,
                    &pts[r * self.nu..(r + 1) * self.nu],
                    self.uorder,
                    ku,
                    u,
                )
            })
            .collect();
        let h = de_boor(&self.vknot, &column, self.vorder, kv, v);
        h.truncate() / h.w
    }

    /// Parses the request and compares every patch with direct evaluation on a grid.
    fn check(&self) {
        let s = parse(&self.rib());
        let us = spans(&self.uknot, self.nu, self.uorder, self.urange);
        let vs = spans(&self.vknot, self.nv, self.vorder, self.vrange);
        assert_eq!(s.patches.len(), us.len() * vs.len());
        for (j, &(kv, v0, v1)) in vs.iter().enumerate() {
            for (i, &(ku, u0, u1)) in us.iter().enumerate() {
                let p = &s.patches[j * us.len() + i];
                assert_eq!(p.source.index as usize, j * us.len() + i);
                assert_eq!(p.is_rational(), self.rational);
                for a in 0..=8 {
                    for b in 0..=8 {
                        let (a, b) = (a as f64 / 8.0, b as f64 / 8.0);
                        let want = self.eval(ku, u0 + a * (u1 - u0), kv, v0 + b * (v1 - v0));
                        let got = eval_rational_bezier(&p.cp(), &p.w(), a, b).0;
                        assert!(
                            want.distance(got) < 1e-11,
                            "orders {}x{} patch ({i},{j}) at ({a},{b}): {want} vs {got}",
                            self.uorder,
                            self.vorder
                        );
                    }
                }
            }
        }
    }
}

#[test]
fn every_order_pair_matches_de_boor() {
    for rational in [false, true] {
        for uorder in 2..=4 {
            for vorder in 2..=4 {
                let (nu, nv) = (uorder + 2, vorder + 3);
                // Clamped, uneven interior knots, one of them doubled in v.
                let clamped = |n: usize, o: usize, doubled: bool| {
                    let mut k = vec![0.0; o];
                    let mut inner: Vec<f64> = (1..=n - o)
                        .map(|j| j as f64 * 0.7 + 0.1 * (j * j) as f64)
                        .collect();
                    if doubled && inner.len() > 1 {
                        inner[1] = inner[0];
                    }
                    let end = inner.last().copied().unwrap_or(0.0) + 1.0;
                    k.extend(inner);
                    k.extend(std::iter::repeat_n(end, o));
                    k
                };
                let (uknot, vknot) = (clamped(nu, uorder, false), clamped(nv, vorder, true));
                Nurbs {
                    nu,
                    nv,
                    uorder,
                    vorder,
                    urange: (uknot[uorder - 1], uknot[nu]),
                    vrange: (vknot[vorder - 1], vknot[nv]),
                    uknot,
                    vknot,
                    rational,
                }
                .check();
            }
        }
    }
}

#[test]
fn bilinear_and_cubic_nupatch_subranges() {
    // Order 2 (bilinear) in both directions, uniform unclamped knots, a subrange cutting
    // spans at both ends.
    let bilinear = Nurbs {
        nu: 5,
        nv: 4,
        uorder: 2,
        vorder: 2,
        uknot: (0..7).map(f64::from).collect(),
        vknot: (0..6).map(f64::from).collect(),
        urange: (1.25, 3.5),
        vrange: (1.0, 3.75),
        rational: false,
    };
    bilinear.check();
    let s = parse(&bilinear.rib());
    // A bilinear span is the bilinear interpolation of its four points.
    assert_eq!(s.patches.len(), 3 * 3);
    let cubic = Nurbs {
        nu: 6,
        nv: 5,
        uorder: 4,
        vorder: 4,
        uknot: vec![-1.0, -0.5, 0.0, 0.4, 1.0, 1.0, 2.5, 3.0, 3.5, 4.0],
        vknot: vec![0.0, 0.0, 0.0, 0.0, 0.3, 1.0, 1.0, 1.0, 1.0],
        urange: (0.5, 2.0),
        vrange: (0.1, 0.9),
        rational: false,
    };
    cubic.check();
    let rational = Nurbs {
        rational: true,
        uorder: 3,
        uknot: cubic.uknot[..9].to_vec(),
        urange: (0.0, 1.0),
        ..cubic
    };
    rational.check();
}

/// The field file: a unit sphere as an order-3 rational NuPatch, 4 units in front of the eye.
#[test]
fn field_rational_sphere_lies_on_the_unit_sphere() {
    let s = crate::scene::load(&crate::shared_data_dir().join("field/nurbs-sphere-order3.rib"))
        .unwrap();
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    // 4 u spans x 2 v spans.
    assert_eq!(s.patches.len(), 8);
    let centre = DVec3::new(0.0, 0.0, 4.0);
    let mut samples = Vec::new();
    let mut outward = [0usize; 2];
    for p in &s.patches {
        assert!(p.is_rational());
        for a in 0..=24 {
            for b in 0..=24 {
                let (pos, du, dv) =
                    eval_rational_bezier(&p.cp(), &p.w(), a as f64 / 24.0, b as f64 / 24.0);
                // The file gives sqrt(1/2) to 9 digits: the sphere is exact to about 1e-9.
                let r = pos.distance(centre);
                assert!((r - 1.0).abs() < 1e-8, "radius {r} at {pos}");
                samples.push(pos);
                let n = du.cross(dv);
                if n.length() > 1e-6 {
                    outward[(n.dot(pos - centre) > 0.0) as usize] += 1;
                }
            }
        }
    }
    // Every patch turns the same way (whichever the file chose).
    assert!(outward[0] == 0 || outward[1] == 0, "{outward:?}");
    // The whole sphere: every direction is reached.
    for k in 0..300 {
        let z = 1.0 - 2.0 * (k as f64 + 0.5) / 300.0;
        let phi = k as f64 * 2.399963229728653;
        let d = DVec3::new(
            (1.0 - z * z).sqrt() * phi.cos(),
            (1.0 - z * z).sqrt() * phi.sin(),
            z,
        );
        let near = samples
            .iter()
            .map(|p| p.distance(centre + d))
            .fold(f64::MAX, f64::min);
        assert!(near < 0.08, "direction {d} not covered ({near})");
    }
}

#[test]
fn rational_nupatch_follows_the_transform() {
    // A quarter circle of radius 1 in x-y (order 3, weights 1, sqrt(1/2), 1) extruded along z
    // by a linear v, then scaled by 2 and moved: every point at distance 2 from the moved
    // axis.
    let h = std::f64::consts::FRAC_1_SQRT_2;
    let rib = world(&format!(
        "Translate 1 2 3\nScale 2 2 2\nNuPatch 3 3 [0 0 0 1 1 1] 0 1 2 2 [0 0 1 1] 0 1 \"Pw\" \
         [1 0 0 1  {h} {h} 0 {h}  0 1 0 1  1 0 1 1  {h} {h} {h} {h}  0 1 1 1]"
    ));
    let s = parse(&rib);
    assert_eq!(s.patches.len(), 1);
    let p = &s.patches[0];
    for a in 0..=10 {
        for b in 0..=10 {
            let pos = eval_rational_bezier(&p.cp(), &p.w(), a as f64 / 10.0, b as f64 / 10.0).0;
            let radial = (pos - DVec3::new(1.0, 2.0, 0.0)).truncate().length();
            assert!((radial - 2.0).abs() < 1e-12, "{pos}");
            assert!(pos.z >= 3.0 - 1e-12 && pos.z <= 5.0 + 1e-12);
        }
    }
}

#[test]
fn nupatch_count_errors_name_the_line() {
    let n = Nurbs {
        nu: 3,
        nv: 2,
        uorder: 3,
        vorder: 2,
        uknot: vec![0.0, 0.0, 0.0, 1.0, 1.0, 1.0],
        vknot: vec![0.0, 0.0, 1.0, 1.0],
        urange: (0.0, 1.0),
        vrange: (0.0, 1.0),
        rational: true,
    };
    assert_eq!(parse(&n.rib()).patches.len(), 1);
    // "Pw" needs 4 numbers a point.
    let three = n.rib().replace("\"Pw\"", "\"P\"");
    let e = err(&three);
    assert_eq!(
        e,
        "t.rib:2: `NuPatch`: \"P\" needs 18 numbers (6 points), found 24"
    );
    let e = err(&n
        .rib()
        .replace("NuPatch 3 3 [0 0 0 1 1 1]", "NuPatch 3 3 [0 0 0 1 1]"));
    assert_eq!(
        e,
        "t.rib:2: `NuPatch`: u knot vector has 5 values, expected nu + order = 6"
    );
}
