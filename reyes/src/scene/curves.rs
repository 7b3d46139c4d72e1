//! Curves and points as Reyes dices them: RenderMan's `Curves` become camera-facing ribbons
//! and its `Points` camera-facing discs, both as bicubic Bezier patches in camera space that
//! go through Bound, Split and DiceShade like every other patch.
//!
//! **Ribbons** (RI Specification 3.2, section 5.5: a curve is "a flat ribbon ... always
//! oriented towards the camera" unless it has normals). A segment's centre curve C(t) (cubic
//! Bezier, or a line) is the ribbon's middle, its v direction; the width spans u:
//! P(u, t) = C(t) + (2u - 1) O(t), with the offset O(t) = h(t) d(t): h the half width and
//! d(t) the unit vector perpendicular to the tangent C'(t) and to the view direction E(t)
//! (d = E x C' / |E x C'|; E = C(t) from the eye at the origin, or +z for an orthographic
//! camera), so the ribbon's normal is the component of the view direction across the curve:
//! it faces the camera. With `"N"` the ribbon lies perpendicular to N instead
//! (d = C' x N / |C' x N|). The patch is linear in u, so its centre line u = 1/2 is C(t)
//! exactly, and dPdu x dPdv points at the eye (or along N): the outside is the front.
//!
//! O(t) is not a polynomial; each segment is cut into pieces [t0, t1] (halving, at most
//! 2^[`MAX_HALVINGS`]) until O is matched within [`OFFSET_TOLERANCE`] of the half width by a
//! cubic interpolating it at t0, t0 + dt/3, t0 + 2 dt/3, t1 (a line through its end values
//! for linear curves, whose pieces are bilinear patches). The piece's centre curve is C
//! restricted to [t0, t1] (blossoming), its end points and offsets computed once per t, so
//! neighbouring pieces share their edge bit for bit. Where two segments of a linear curve
//! meet at an angle, both use the mitre at the shared vertex (the bisector of the two
//! tangents, the half width divided by the cosine of half the turn, at most [`MITRE_LIMIT`]
//! times), so a polyline's ribbon has no wedge-shaped gap at its corners.
//!
//! Widths are given in object space: a half width h becomes h / |M^-1 d| in camera space (M
//! the object-to-camera transform: the object-space length that maps onto the width
//! direction), which is h times the scale for a uniform scale.
//!
//! **Discs**: one bicubic patch ([`disc`]) bounded by the four quarters of the point's circle,
//! centred on it in the plane perpendicular to the view direction, the outside facing the eye.

use glam::{DMat3, DVec3};

/// The largest error of a piece's offset fit, as a fraction of the segment's largest half
/// width (0.5%: a ribbon 200 px wide is at most 1 px off at its edge).
pub(crate) const OFFSET_TOLERANCE: f64 = 0.005;

/// A segment is halved at most this often (at most 64 pieces).
pub(crate) const MAX_HALVINGS: u32 = 6;

/// A mitre (half width over the cosine of half the turn) is at most this many half widths;
/// sharper corners are cut short (SVG's default miter limit).
pub(crate) const MITRE_LIMIT: f64 = 4.0;

/// Where the camera looks from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum View {
    /// The eye at the origin: the view direction at p is p.
    Perspective,
    /// Parallel rays along +z.
    Orthographic,
}

impl View {
    /// The direction from the eye to `p` (not normalized).
    pub(crate) fn dir(self, p: DVec3) -> DVec3 {
        match self {
            View::Perspective => p,
            View::Orthographic => DVec3::Z,
        }
    }
}

/// A value along one segment: cubic Bezier coefficients in t.
pub(crate) type Along<T> = [T; 4];

/// The cubic Bezier coefficients of the line from `a` (t = 0) to `b` (t = 1).
pub(crate) fn linear<T>(a: T, b: T) -> Along<T>
where
    T: Copy + std::ops::Add<Output = T> + std::ops::Mul<f64, Output = T>,
{
    super::rational::elevate_to_cubic(&[a, b])
}

/// The value at t of cubic Bezier coefficients `c`; exactly c[0] at 0 and c[3] at 1.
pub(crate) fn eval<T>(c: &Along<T>, t: f64) -> T
where
    T: Copy + std::ops::Add<Output = T> + std::ops::Mul<f64, Output = T>,
{
    if t == 0.0 {
        return c[0];
    }
    if t == 1.0 {
        return c[3];
    }
    let s = 1.0 - t;
    c[0] * (s * s * s) + c[1] * (3.0 * t * s * s) + c[2] * (3.0 * t * t * s) + c[3] * (t * t * t)
}

/// The derivative in t of cubic Bezier coefficients `c`.
fn deriv(c: &Along<DVec3>, t: f64) -> DVec3 {
    let s = 1.0 - t;
    ((c[1] - c[0]) * (s * s) + (c[2] - c[1]) * (2.0 * t * s) + (c[3] - c[2]) * (t * t)) * 3.0
}

/// The blossom of the cubic `c` at (x, y, z) (de Casteljau with one argument per level).
fn blossom<T>(c: &Along<T>, args: [f64; 3]) -> T
where
    T: Copy + std::ops::Add<Output = T> + std::ops::Mul<f64, Output = T>,
{
    let mut p = *c;
    for (level, x) in args.into_iter().enumerate() {
        for k in 0..3 - level {
            p[k] = p[k] * (1.0 - x) + p[k + 1] * x;
        }
    }
    p[0]
}

/// The cubic `c` restricted to [a, b], reparametrized to [0, 1] (exact).
pub(crate) fn restrict<T>(c: &Along<T>, a: f64, b: f64) -> Along<T>
where
    T: Copy + std::ops::Add<Output = T> + std::ops::Mul<f64, Output = T>,
{
    if (a, b) == (0.0, 1.0) {
        return *c;
    }
    [
        eval(c, a),
        blossom(c, [a, a, b]),
        blossom(c, [a, b, b]),
        eval(c, b),
    ]
}

/// One segment of a curve, in camera space.
#[derive(Clone, Debug)]
pub(crate) struct Segment {
    /// The centre curve as cubic Bezier coefficients (a line elevated, for linear curves).
    pub(crate) centre: Along<DVec3>,
    /// True for a segment of a `"linear"` curve: its pieces are bilinear patches.
    pub(crate) linear: bool,
    /// The half width along the segment, in object-space units.
    pub(crate) half_width: Along<f64>,
    /// `"N"` along the segment (camera space): the ribbon lies perpendicular to it.
    pub(crate) normal: Option<Along<DVec3>>,
    /// For linear curves: the direction of the segment before (at t = 0) and after (at t = 1)
    /// where the curve goes on there, for the mitre.
    pub(crate) joins: [Option<DVec3>; 2],
}

/// One piece of a ribbon: a bicubic Bezier patch (cp[4*v + u]: v along the curve, u across)
/// and the segment parameters [t0, t1] its v = 0..1 covers.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Piece {
    /// The control points, camera space.
    pub(crate) cp: [DVec3; 16],
    /// The segment's t at v = 0 and v = 1.
    pub(crate) t: (f64, f64),
}

/// How widths scale from object to camera space: `to_object` is the inverse of the
/// object-to-camera linear part, when finite.
#[derive(Clone, Copy, Debug)]
pub(crate) struct WidthScale {
    to_object: Option<DMat3>,
    mean: f64,
}

impl WidthScale {
    /// The scale of the linear map `m` (object to camera).
    pub(crate) fn new(m: DMat3) -> WidthScale {
        let inv = m.inverse();
        let finite = inv.to_cols_array().iter().all(|x| x.is_finite()) && m.determinant() != 0.0;
        WidthScale {
            to_object: finite.then_some(inv),
            mean: (m.x_axis.length() + m.y_axis.length() + m.z_axis.length()) / 3.0,
        }
    }

    /// The camera-space length of an object-space length laid along unit vector `d` (camera
    /// space); a singular transform gives its mean axis scale.
    pub(crate) fn along(&self, d: DVec3) -> f64 {
        match self.to_object {
            Some(inv) => 1.0 / (inv * d).length(),
            None => self.mean,
        }
    }

    /// The mean axis scale (points: a disc's radius).
    pub(crate) fn mean(&self) -> f64 {
        match self.to_object {
            Some(inv) => inv.determinant().abs().recip().cbrt(),
            None => self.mean,
        }
    }
}

impl Segment {
    /// The unit tangent direction at t (robust where C' vanishes: a nearby chord, then the
    /// whole chord, then +x).
    fn tangent(&self, t: f64) -> DVec3 {
        let c = &self.centre;
        if self.linear {
            // The chord itself, as the neighbours' joins give it (the same bits at a vertex).
            return (c[3] - c[0]).try_normalize().unwrap_or(DVec3::X);
        }
        let scale = (c[3] - c[0]).length() + (c[1] - c[0]).length() + (c[2] - c[3]).length();
        let d = deriv(c, t);
        if d.length() > 1e-9 * scale {
            return d.normalize();
        }
        let near = eval(c, (t + 1e-3).min(1.0)) - eval(c, (t - 1e-3).max(0.0));
        if near.length() > 1e-12 * scale {
            return near.normalize();
        }
        (c[3] - c[0]).try_normalize().unwrap_or(DVec3::X)
    }

    /// The unit width direction for tangent `tan` at centre point `p` and parameter t.
    fn across(&self, view: View, p: DVec3, tan: DVec3, t: f64) -> DVec3 {
        if let Some(n) = &self.normal
            && let Some(d) = tan.cross(eval(n, t)).try_normalize()
        {
            return d;
        }
        let e = view.dir(p);
        e.cross(tan).try_normalize().unwrap_or_else(|| {
            e.try_normalize()
                .unwrap_or(DVec3::Z)
                .any_orthonormal_vector()
        })
    }

    /// The exact offset O(t) (module doc), without the mitre.
    fn offset(&self, view: View, scale: &WidthScale, t: f64) -> DVec3 {
        let d = self.across(view, eval(&self.centre, t), self.tangent(t), t);
        d * (eval(&self.half_width, t) * scale.along(d))
    }

    /// O(t) as the ribbon uses it: at an end where a linear curve goes on, the mitre.
    fn offset_at_end(&self, view: View, scale: &WidthScale, t: f64) -> DVec3 {
        let end = match t {
            0.0 => 0,
            1.0 => 1,
            _ => return self.offset(view, scale, t),
        };
        let Some(other) = self.joins[end] else {
            return self.offset(view, scale, t);
        };
        let own = self.tangent(t);
        // The earlier segment's direction first, so that both segments compute the same bits.
        let (a, b) = if end == 0 { (other, own) } else { (own, other) };
        let (Some(a), Some(b)) = (a.try_normalize(), b.try_normalize()) else {
            return self.offset(view, scale, t);
        };
        let bisector = a + b;
        let len = bisector.length();
        if len < 1e-9 {
            return self.offset(view, scale, t);
        }
        let p = eval(&self.centre, t);
        let d = self.across(view, p, bisector / len, t);
        let mitre = (2.0 / len).min(MITRE_LIMIT);
        d * (eval(&self.half_width, t) * scale.along(d) * mitre)
    }

    /// The ribbon's pieces (module doc). A segment of zero width everywhere gives none.
    pub(crate) fn ribbon(&self, view: View, scale: &WidthScale) -> Vec<Piece> {
        if self.half_width.iter().all(|h| *h == 0.0) {
            return Vec::new();
        }
        let hmax = (0..=8)
            .map(|k| self.offset(view, scale, k as f64 / 8.0).length())
            .fold(0.0, f64::max);
        let tol = OFFSET_TOLERANCE * hmax;
        let mut out = Vec::new();
        // Depth-first, first half first: pieces come out in order along the curve.
        let mut todo = vec![(0.0, 1.0, 0u32)];
        while let Some((t0, t1, depth)) = todo.pop() {
            let fit = self.fit(view, scale, t0, t1);
            let dt = t1 - t0;
            let checks: &[f64] = if self.linear {
                &[0.25, 0.5, 0.75]
            } else {
                &[1.0 / 6.0, 0.5, 5.0 / 6.0]
            };
            let off = checks.iter().any(|&s| {
                let exact = self.offset(view, scale, t0 + s * dt);
                (eval(&fit, s) - exact).length() > tol
            });
            if off && depth < MAX_HALVINGS {
                let mid = t0 + 0.5 * dt;
                todo.push((mid, t1, depth + 1));
                todo.push((t0, mid, depth + 1));
                continue;
            }
            // The fit above uses mitre-free ends (to judge the fit); the patch uses the
            // ribbon's own end offsets.
            let (o0, o1) = (
                self.offset_at_end(view, scale, t0),
                self.offset_at_end(view, scale, t1),
            );
            let (c0, c1) = (eval(&self.centre, t0), eval(&self.centre, t1));
            let cp = if self.linear {
                super::polygon::bilinear_patch([c0 - o0, c0 + o0, c1 - o1, c1 + o1])
            } else {
                let mut c = restrict(&self.centre, t0, t1);
                (c[0], c[3]) = (c0, c1);
                let mut o = fit;
                (o[0], o[3]) = (o0, o1);
                std::array::from_fn(|k| {
                    let (i, j) = (k % 4, k / 4);
                    c[j] + o[j] * (2.0 * i as f64 / 3.0 - 1.0)
                })
            };
            out.push(Piece { cp, t: (t0, t1) });
        }
        out
    }

    /// The offset on [t0, t1] as cubic Bezier coefficients in the piece's own parameter: the
    /// line through the end values (linear curves), else the cubic through the values at
    /// thirds (b1 = (-5 f0 + 18 f1 - 9 f2 + 2 f3) / 6 and its mirror image).
    fn fit(&self, view: View, scale: &WidthScale, t0: f64, t1: f64) -> Along<DVec3> {
        let f = |s: f64| self.offset(view, scale, if s == 1.0 { t1 } else { t0 + s * (t1 - t0) });
        if self.linear {
            return linear(f(0.0), f(1.0));
        }
        let [f0, f1, f2, f3] = [0.0, 1.0 / 3.0, 2.0 / 3.0, 1.0].map(f);
        [
            f0,
            (f0 * -5.0 + f1 * 18.0 - f2 * 9.0 + f3 * 2.0) / 6.0,
            (f0 * 2.0 - f1 * 9.0 + f2 * 18.0 - f3 * 5.0) / 6.0,
            f3,
        ]
    }
}

/// The largest distance of [`disc`]'s rim from the exact circle, as a fraction of the radius:
/// the cubic quarter arc with inner points k = 4/3 tan(pi/8) along the end tangents lies
/// outside the circle by at most 2.7e-4 of its radius (Dokken et al. 1990).
#[cfg_attr(not(test), allow(dead_code, reason = "the tests' tolerance"))]
pub(crate) const DISC_RIM_ERROR: f64 = 2.8e-4;

/// The inner control points of [`disc`]'s patch at (±s, ±s) of the radius: every s in
/// [0, 0.45] gives a positive Jacobian inside the square (zero only at its corners); 0.2 gives
/// the most even one (largest over smallest away from the corners).
const DISC_INNER: f64 = 0.2;

/// The bicubic patch (control points; polynomial) of a disc of `radius` centred at `p`
/// (camera space), perpendicular to the view direction there, with dPdu x dPdv pointing at
/// the eye; and that unit normal (towards the eye). A zero radius gives none.
///
/// The patch's four edges are the circle's quarters between 45, 135, 225 and 315 degrees,
/// each the cubic Bezier quarter circle (inner points k = 4/3 tan(pi/8) along the end
/// tangents, within [`DISC_RIM_ERROR`] of the circle), the inner points at
/// ([`DISC_INNER`] r)(±1, ±1): a map of the square onto the disc whose Jacobian is positive
/// inside (tested), so it covers the disc once; at the four corners two edges meet in one
/// tangent direction and the normal is degenerate (the shading normal is given). One patch
/// per point rather than four quarters; polynomial rather than the exact rational `Disk`
/// quadric: the crack bound of a rational quarter circle is 4 times its true curvature
/// (docs/reyes.md, *Rational patches*), which grew discs of a few pixels by a pixel all
/// round.
pub(crate) fn disc(p: DVec3, radius: f64, view: View) -> (Vec<[DVec3; 16]>, DVec3) {
    let towards_eye = -view.dir(p).try_normalize().unwrap_or(DVec3::Z);
    if !(radius > 0.0) {
        return (Vec::new(), towards_eye);
    }
    // Local (x, y), with local +z mapped to `towards_eye`: u runs along +x, v along +y, so
    // dPdu x dPdv = +z.
    let a = towards_eye.any_orthonormal_vector();
    let b = towards_eye.cross(a);
    let k = 4.0 / 3.0 * (std::f64::consts::FRAC_PI_8).tan();
    // The quarter circle counter-clockwise from `deg` degrees.
    let quarter = |deg: f64| {
        let (a0, a1) = (deg.to_radians(), (deg + 90.0).to_radians());
        let (c0, c1) = (
            DVec3::new(a0.cos(), a0.sin(), 0.0),
            DVec3::new(a1.cos(), a1.sin(), 0.0),
        );
        let (t0, t1) = (
            DVec3::new(-a0.sin(), a0.cos(), 0.0),
            DVec3::new(-a1.sin(), a1.cos(), 0.0),
        );
        [c0, c0 + t0 * k, c1 - t1 * k, c1]
    };
    let (bottom, right) = (quarter(225.0), quarter(315.0));
    let (mut top, mut left) = (quarter(45.0), quarter(135.0));
    top.reverse();
    left.reverse();
    let s = DISC_INNER;
    let local: [DVec3; 16] = std::array::from_fn(|m| {
        let (i, j) = (m % 4, m / 4);
        match (i, j) {
            (_, 0) => bottom[i],
            (_, 3) => top[i],
            (0, _) => left[j],
            (3, _) => right[j],
            _ => DVec3::new(
                if i == 1 { -s } else { s },
                if j == 1 { -s } else { s },
                0.0,
            ),
        }
    });
    (
        vec![local.map(|l| p + (a * l.x + b * l.y) * radius)],
        towards_eye,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    const ID: WidthScale = WidthScale {
        to_object: Some(DMat3::IDENTITY),
        mean: 1.0,
    };

    fn seg(centre: Along<DVec3>, linear_: bool, h: [f64; 2]) -> Segment {
        Segment {
            centre,
            linear: linear_,
            half_width: linear(h[0], h[1]),
            normal: None,
            joins: [None, None],
        }
    }

    /// A piece's point at (u, v) and its parameter t on the segment.
    fn at(p: &Piece, u: f64, v: f64) -> (DVec3, f64) {
        let (q, _, _) = crate::scene::eval_bezier(&p.cp, u, v);
        (q, p.t.0 + v * (p.t.1 - p.t.0))
    }

    /// RenderMan's definition checked pointwise on every piece: the centre line is the
    /// curve, the width vector is perpendicular to the tangent and the view, of length 2h.
    fn check_definition(s: &Segment, view: View, pieces: &[Piece]) {
        assert!(!pieces.is_empty());
        let hmax = s.half_width.iter().fold(0.0f64, |m, h| m.max(*h));
        // Each side's fit is within OFFSET_TOLERANCE * hmax (plus the sampling between the
        // checked points: twice that).
        let tol = 2.0 * OFFSET_TOLERANCE * hmax;
        assert_eq!(pieces[0].t.0, 0.0);
        assert_eq!(pieces.last().unwrap().t.1, 1.0);
        for w in pieces.windows(2) {
            assert_eq!(w[0].t.1, w[1].t.0);
            assert_eq!(w[0].cp[12..16], w[1].cp[0..4], "shared edge");
        }
        for p in pieces {
            for k in 0..=10 {
                let v = k as f64 / 10.0;
                let (mid, t) = at(p, 0.5, v);
                let c = eval(&s.centre, t);
                assert!(mid.distance(c) < 1e-9 * (1.0 + c.length()), "{mid} vs {c}");
                let width = at(p, 1.0, v).0 - at(p, 0.0, v).0;
                let h = eval(&s.half_width, t);
                let tan = deriv(&s.centre, t).normalize();
                let e = view.dir(c).normalize();
                assert!(
                    (width.length() - 2.0 * h).abs() < 2.0 * tol,
                    "width {} vs {}",
                    width.length(),
                    2.0 * h
                );
                let wd = width.normalize();
                let angle = tol / h + 1e-9;
                assert!(wd.dot(tan).abs() < angle && wd.dot(e).abs() < angle, "{wd}");
                // Facing the eye: dPdu x dPdv towards -e.
                let (_, du, dv) = crate::scene::eval_bezier(&p.cp, 0.5, v);
                assert!(du.cross(dv).dot(e) < 0.0);
            }
        }
    }

    #[test]
    fn straight_line_facing_the_eye_is_one_rectangle() {
        let s = seg(
            linear(DVec3::new(-5.0, 0.0, 6.0), DVec3::new(5.0, 0.0, 6.0)),
            true,
            [0.2, 0.2],
        );
        let pieces = s.ribbon(View::Perspective, &ID);
        assert_eq!(pieces.len(), 1);
        let cp = &pieces[0].cp;
        assert!(
            cp[0].distance(DVec3::new(-5.0, -0.2, 6.0)) < 1e-12,
            "{}",
            cp[0]
        );
        assert!(
            cp[15].distance(DVec3::new(5.0, 0.2, 6.0)) < 1e-12,
            "{}",
            cp[15]
        );
        check_definition(&s, View::Perspective, &pieces);
    }

    #[test]
    fn cubic_curves_follow_the_definition_in_both_views() {
        let centre = [
            DVec3::new(-3.0, -1.0, 5.0),
            DVec3::new(-1.0, 4.0, 9.0),
            DVec3::new(2.0, -3.0, 4.0),
            DVec3::new(3.0, 2.0, 7.0),
        ];
        for view in [View::Perspective, View::Orthographic] {
            let s = seg(centre, false, [0.05, 0.3]);
            let pieces = s.ribbon(view, &ID);
            assert!(pieces.len() > 1, "a bending curve is cut");
            check_definition(&s, view, &pieces);
        }
    }

    #[test]
    fn long_linear_segment_across_the_view_is_one_flat_piece() {
        // From beside the eye to far away: the view direction turns by nearly 90 degrees, but
        // E x T = p0 x T is the same all along a line (the plane through the eye and the
        // line), so the ribbon is flat and one piece is exact.
        let s = seg(
            linear(DVec3::new(-4.0, 1.0, 0.5), DVec3::new(30.0, -2.0, 40.0)),
            true,
            [0.1, 0.1],
        );
        let pieces = s.ribbon(View::Perspective, &ID);
        assert_eq!(pieces.len(), 1);
        check_definition(&s, View::Perspective, &pieces);
    }

    #[test]
    fn normals_turn_the_ribbon() {
        let mut s = seg(
            linear(DVec3::new(-1.0, 0.0, 5.0), DVec3::new(1.0, 0.0, 5.0)),
            true,
            [0.1, 0.1],
        );
        // N along +y: the ribbon lies in the xz plane, its normal +y.
        s.normal = Some([DVec3::Y; 4]);
        let p = &s.ribbon(View::Perspective, &ID)[0];
        let width = at(p, 1.0, 0.5).0 - at(p, 0.0, 0.5).0;
        assert!(
            width
                .normalize()
                .distance(DVec3::Z)
                .min(width.normalize().distance(-DVec3::Z))
                < 1e-12
        );
        let (_, du, dv) = crate::scene::eval_bezier(&p.cp, 0.5, 0.5);
        assert!(du.cross(dv).normalize().distance(DVec3::Y) < 1e-12);
    }

    #[test]
    fn mitred_corner_is_shared_by_both_segments() {
        let (a, b, c) = (
            DVec3::new(-1.0, 0.0, 5.0),
            DVec3::new(0.0, 0.0, 5.0),
            DVec3::new(0.0, 1.0, 5.0),
        );
        let mut s1 = seg(linear(a, b), true, [0.1, 0.1]);
        let mut s2 = seg(linear(b, c), true, [0.1, 0.1]);
        s1.joins[1] = Some(c - b);
        s2.joins[0] = Some(b - a);
        let p1 = s1.ribbon(View::Perspective, &ID);
        let p2 = s2.ribbon(View::Perspective, &ID);
        let end = &p1.last().unwrap().cp;
        assert_eq!(end[12..16], p2[0].cp[0..4]);
        // The outer corner of a right angle lies sqrt(2) half widths from the vertex.
        let corner = end[12].distance(b).max(end[15].distance(b));
        assert!((corner - 0.1 * 2f64.sqrt()).abs() < 1e-3, "{corner}");
    }

    #[test]
    fn widths_scale_with_the_transform_across_the_curve() {
        // x scaled by 3, y by 0.5: a curve along x is widened in y, so by 0.5.
        let m = DMat3::from_diagonal(DVec3::new(3.0, 0.5, 1.0));
        let scale = WidthScale::new(m);
        assert!((scale.along(DVec3::Y) - 0.5).abs() < 1e-15);
        assert!((scale.along(DVec3::X) - 3.0).abs() < 1e-15);
        assert!(
            (WidthScale::new(DMat3::from_diagonal(DVec3::splat(2.0))).mean() - 2.0).abs() < 1e-12
        );
        let flat = WidthScale::new(DMat3::from_diagonal(DVec3::new(1.0, 1.0, 0.0)));
        assert!((flat.along(DVec3::Y) - 2.0 / 3.0).abs() < 1e-15);
    }

    #[test]
    fn disc_is_round_flat_and_faces_the_eye() {
        let (p, r) = (DVec3::new(1.0, -2.0, 9.0), 0.5);
        for view in [View::Perspective, View::Orthographic] {
            let (patches, n) = disc(p, r, view);
            assert_eq!(patches.len(), 1);
            let cp = &patches[0];
            let e = view.dir(p).normalize();
            assert!(n.distance(-e) < 1e-12);
            let tol = DISC_RIM_ERROR * r;
            // The four edges are the circle.
            for k in 0..=40 {
                let t = k as f64 / 40.0;
                for (u, v) in [(t, 0.0), (t, 1.0), (0.0, t), (1.0, t)] {
                    let q = crate::scene::eval_bezier(cp, u, v).0;
                    assert!(((q - p).length() - r).abs() < tol, "{u} {v}");
                }
            }
            // Inside: in the plane, within the circle, the Jacobian towards the eye (so the
            // square covers the disc once), the area pi r^2 (the rim's error is outward).
            let m = 200;
            let mut area = 0.0;
            for k in 0..m {
                for l in 0..m {
                    let (u, v) = ((k as f64 + 0.5) / m as f64, (l as f64 + 0.5) / m as f64);
                    let (q, du, dv) = crate::scene::eval_bezier(cp, u, v);
                    assert!((q - p).dot(e).abs() < 1e-12, "in the plane");
                    assert!((q - p).length() < r + tol);
                    let j = -du.cross(dv).dot(e);
                    assert!(j > 0.0, "Jacobian {j} at ({u}, {v})");
                    area += j / (m * m) as f64;
                }
            }
            let exact = std::f64::consts::PI * r * r;
            assert!((area - exact).abs() < 1e-3 * exact, "{area} vs {exact}");
        }
        assert!(disc(p, 0.0, View::Perspective).0.is_empty());
    }
}
