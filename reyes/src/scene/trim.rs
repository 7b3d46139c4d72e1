//! Trim curves (RIB `TrimCurve`; RenderMan Interface Specification 3.2, section 5.5.2): loops
//! of NURBS curves in the (u, v) parameter space of the `NuPatch` surfaces that follow, which
//! keep the part of each surface inside the loops.
//!
//! Each curve is a rational NURBS curve of any order from 2 to [`MAX_TRIM_ORDER`] with
//! homogeneous control points `(u, v, w)` (the point is `(u / w, v / w)`), drawn over its
//! parameter range `[min, max]`. The loops are flattened once, on the host, into closed
//! polylines ([`TrimLoops`]) whose chords stay within [`TRIM_FLATNESS`] of the loops' extent
//! of the curves; the stages test points and parameter rectangles against those polylines
//! (`shaders/reyes/trim.wgsl`, twin `crate::stages::trim`).
//!
//! Which side is kept: a point is inside when a ray from it crosses the loops an odd number of
//! times (the even-odd rule); RenderMan keeps the inside (`Attribute "trimcurve" "sense"
//! "inside"`, the default) or, with `"outside"`, the rest of the surface. A loop is closed by
//! a chord from its last point to its first when the curves do not meet exactly.

use glam::DVec2;
use std::sync::Arc;

/// Highest curve order read (degree 7): the de Boor evaluation below takes any order; the cap
/// only bounds a hostile file's work per point.
pub const MAX_TRIM_ORDER: usize = 8;

/// Chord tolerance of the flattened loops, as a fraction of the largest side of the box of
/// their control points: 1/4096, so on a patch spanning 1000 pixels of the image a trimmed
/// edge lies within 0.25 px of the exact curve.
pub const TRIM_FLATNESS: f64 = 1.0 / 4096.0;

/// Most polyline edges one `TrimCurve` may make (each is one 16-byte table entry on the GPU
/// and is tested, per micropolygon of a trimmed grid, in DiceShade).
pub const MAX_TRIM_EDGES: usize = 1 << 16;

/// Halvings of a knot span at most while flattening (2^10 chords per span).
const MAX_FLATTEN_DEPTH: u32 = 10;
/// Halvings of a knot span at least (4 chords per span), so that a curve whose midpoint happens
/// to lie on its chord is still followed.
const MIN_FLATTEN_DEPTH: u32 = 2;

/// The flattened loops of one `TrimCurve` request: closed polylines in the NURBS surface's
/// parameter space (the last point of each joins its first).
#[derive(Clone, Debug, PartialEq)]
pub struct TrimLoops {
    /// The loops' points, in order.
    pub loops: Vec<Vec<DVec2>>,
}

impl TrimLoops {
    /// Every edge of every loop, the closing one included, as (start, end).
    pub fn edges(&self) -> impl Iterator<Item = (DVec2, DVec2)> + '_ {
        self.loops
            .iter()
            .flat_map(|l| (0..l.len()).map(move |k| (l[k], l[(k + 1) % l.len()])))
    }

    /// Number of [`Self::edges`].
    pub fn edge_count(&self) -> usize {
        self.loops.iter().map(|l| l.len()).sum()
    }

    /// The even-odd rule in f64 (the reference of the stages' f32 test): true when a ray from
    /// `p` towards +u crosses the loops an odd number of times (edges half-open in v).
    pub fn contains(&self, p: DVec2) -> bool {
        let mut odd = false;
        for (a, b) in self.edges() {
            if (a.y > p.y) != (b.y > p.y) {
                let x = a.x + (p.y - a.y) / (b.y - a.y) * (b.x - a.x);
                if p.x < x {
                    odd = !odd;
                }
            }
        }
        odd
    }
}

/// The trimming of one patch of a trimmed `NuPatch`: the request's loops, the kept side, and
/// the patch's own span of the surface's parameter space (patch (u, v) in [0, 1]^2 is surface
/// parameter (u0 + (u1 - u0) u, v0 + (v1 - v0) v)).
#[derive(Clone, Debug, PartialEq)]
pub struct PatchTrim {
    /// The loops, shared by every patch of the surface.
    pub loops: Arc<TrimLoops>,
    /// `Attribute "trimcurve" "sense" "outside"`: keep what lies outside the loops.
    pub outside: bool,
    /// The patch's u span (u0, u1) in the surface's parameter space.
    pub u: (f64, f64),
    /// The patch's v span (v0, v1).
    pub v: (f64, f64),
}

impl PatchTrim {
    /// Whether the surface is kept at (u, v) of this patch (f64 reference).
    pub fn keeps(&self, u: f64, v: f64) -> bool {
        let p = DVec2::new(
            self.u.0 + (self.u.1 - self.u.0) * u,
            self.v.0 + (self.v.1 - self.v.0) * v,
        );
        self.loops.contains(p) != self.outside
    }
}

/// The arguments of a `TrimCurve` request, as RIB gives them: per loop its number of curves;
/// per curve its order, knots, parameter range, and number of control points; the control
/// points' homogeneous u, v, w.
pub struct TrimCurveArgs<'a> {
    /// Curves per loop (`ncurves`), one entry per loop.
    pub ncurves: &'a [f64],
    /// Order of each curve.
    pub order: &'a [f64],
    /// Every curve's knots, concatenated (n + order per curve).
    pub knot: &'a [f64],
    /// Start of each curve's parameter range.
    pub min: &'a [f64],
    /// End of each curve's parameter range.
    pub max: &'a [f64],
    /// Control points per curve.
    pub n: &'a [f64],
    /// Homogeneous u of every control point, concatenated.
    pub u: &'a [f64],
    /// Homogeneous v of every control point.
    pub v: &'a [f64],
    /// Weight of every control point (positive).
    pub w: &'a [f64],
}

/// A count argument: a whole number in `lo..=hi`.
fn count(x: f64, what: &str, lo: usize, hi: usize) -> Result<usize, String> {
    if x.fract() == 0.0 && x >= lo as f64 && x <= hi as f64 {
        Ok(x as usize)
    } else {
        Err(format!("{what} {x} is not a whole number in {lo}..={hi}"))
    }
}

/// One curve: order, its knots, range and homogeneous points.
struct Curve<'a> {
    order: usize,
    knots: &'a [f64],
    range: (f64, f64),
    pts: Vec<glam::DVec3>,
}

impl Curve<'_> {
    /// The point at t in [min, max]: de Boor's algorithm on the homogeneous points, divided by
    /// the weight (Piegl & Tiller, *The NURBS Book*, algorithm A4.1).
    fn eval(&self, t: f64) -> DVec2 {
        let p = self.order - 1;
        let n = self.pts.len();
        // The knot interval [t_i, t_i+1) holding t, i in p..n (the last non-empty one at max).
        let mut i = p;
        while i + 1 < n && self.knots[i + 1] <= t {
            i += 1;
        }
        while i > p && self.knots[i] >= self.knots[i + 1] {
            i -= 1;
        }
        let mut d: Vec<glam::DVec3> = (0..=p).map(|j| self.pts[i - p + j]).collect();
        for r in 1..=p {
            for j in (r..=p).rev() {
                let k = i - p + j;
                let den = self.knots[k + p + 1 - r] - self.knots[k];
                let alpha = if den > 0.0 {
                    (t - self.knots[k]) / den
                } else {
                    0.0
                };
                d[j] = d[j - 1] * (1.0 - alpha) + d[j] * alpha;
            }
        }
        DVec2::new(d[p].x / d[p].z, d[p].y / d[p].z)
    }
}

/// Reads, checks and flattens a `TrimCurve` request (errors are messages without a location;
/// the caller adds it). `None` when it has no loops (trimming off, as RenderMan reads
/// `TrimCurve` with nloops 0).
pub fn trim_loops(a: &TrimCurveArgs) -> Result<Option<TrimLoops>, String> {
    if a.ncurves.is_empty() {
        return Ok(None);
    }
    let mut per_loop = Vec::with_capacity(a.ncurves.len());
    let mut total = 0usize;
    for (k, &c) in a.ncurves.iter().enumerate() {
        let c = count(c, &format!("loop {k}: ncurves"), 1, MAX_TRIM_EDGES)?;
        total += c;
        per_loop.push(c);
    }
    for (name, v) in [
        ("order", a.order),
        ("min", a.min),
        ("max", a.max),
        ("n", a.n),
    ] {
        if v.len() != total {
            return Err(format!(
                "\"{name}\" has {} values, expected one per curve ({total})",
                v.len()
            ));
        }
    }
    let mut knots_needed = 0usize;
    let mut points_needed = 0usize;
    let mut shapes = Vec::with_capacity(total);
    for c in 0..total {
        let order = count(a.order[c], &format!("curve {c}: order"), 2, MAX_TRIM_ORDER)?;
        let n = count(a.n[c], &format!("curve {c}: n"), order, MAX_TRIM_EDGES)?;
        shapes.push((order, n));
        knots_needed += n + order;
        points_needed += n;
    }
    if a.knot.len() != knots_needed {
        return Err(format!(
            "\"knot\" has {} values, expected n + order per curve ({knots_needed})",
            a.knot.len()
        ));
    }
    for (name, v) in [("u", a.u), ("v", a.v), ("w", a.w)] {
        if v.len() != points_needed {
            return Err(format!(
                "\"{name}\" has {} values, expected one per control point ({points_needed})",
                v.len()
            ));
        }
    }
    if let Some(k) =
        (a.u.iter()
            .chain(a.v)
            .chain(a.knot)
            .chain(a.min)
            .chain(a.max))
        .position(|x| !x.is_finite())
    {
        return Err(format!("value {k} of the curves' numbers is not finite"));
    }
    if let Some(k) = a.w.iter().position(|w| !(*w > 0.0 && w.is_finite())) {
        return Err(format!(
            "control point {k} has weight w = {}: weights must be positive and finite",
            a.w[k]
        ));
    }
    // The curves, and the box of their Euclidean control points (the tolerance's scale).
    let (mut ko, mut po) = (0, 0);
    let mut curves = Vec::with_capacity(total);
    let (mut lo, mut hi) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
    for (c, &(order, n)) in shapes.iter().enumerate() {
        let knots = &a.knot[ko..ko + n + order];
        ko += n + order;
        if knots.windows(2).any(|w| w[1] < w[0]) {
            return Err(format!(
                "curve {c}: the knot vector is decreasing somewhere"
            ));
        }
        let (t0, t1) = (knots[order - 1], knots[n]);
        let range = (a.min[c], a.max[c]);
        if !(t0 <= range.0 && range.0 < range.1 && range.1 <= t1) {
            return Err(format!(
                "curve {c}: the range [{}, {}] is not within the knot range [{t0}, {t1}] (need \
                 min < max)",
                range.0, range.1
            ));
        }
        let pts: Vec<glam::DVec3> = (po..po + n)
            .map(|k| glam::DVec3::new(a.u[k], a.v[k], a.w[k]))
            .collect();
        po += n;
        for p in &pts {
            let e = DVec2::new(p.x / p.z, p.y / p.z);
            lo = lo.min(e);
            hi = hi.max(e);
        }
        curves.push(Curve {
            order,
            knots,
            range,
            pts,
        });
    }
    let extent = (hi - lo).max_element();
    let tol = if extent > 0.0 {
        extent * TRIM_FLATNESS
    } else {
        f64::MIN_POSITIVE
    };
    let mut loops = Vec::with_capacity(per_loop.len());
    let mut edges = 0usize;
    let mut next = curves.iter();
    for &c in &per_loop {
        let mut pts: Vec<DVec2> = Vec::new();
        for curve in next.by_ref().take(c) {
            flatten(curve, tol, &mut pts);
            if edges + pts.len() > MAX_TRIM_EDGES {
                return Err(format!(
                    "the loops flatten to more than {MAX_TRIM_EDGES} edges (the renderer's \
                     limit per `TrimCurve`)"
                ));
            }
        }
        // Curves meet head to tail: drop a point repeating the one before, and the last when
        // it closes the loop onto the first.
        pts.dedup();
        if pts.len() > 1 && pts.first() == pts.last() {
            pts.pop();
        }
        edges += pts.len();
        if pts.len() >= 2 {
            loops.push(pts);
        }
    }
    Ok(Some(TrimLoops { loops }))
}

/// Appends the polyline of `c` over its range: each knot span inside the range halved until
/// the curve's midpoint lies within `tol` of the chord (at least [`MIN_FLATTEN_DEPTH`], at
/// most [`MAX_FLATTEN_DEPTH`] halvings); the first point included.
fn flatten(c: &Curve, tol: f64, out: &mut Vec<DVec2>) {
    let (t0, t1) = c.range;
    let mut breaks = vec![t0];
    breaks.extend(c.knots.iter().copied().filter(|&k| k > t0 && k < t1));
    breaks.push(t1);
    breaks.dedup();
    out.push(c.eval(t0));
    for w in breaks.windows(2) {
        let (a, b) = (w[0], w[1]);
        let (pa, pb) = (c.eval(a), c.eval(b));
        subdivide(c, tol, (a, pa), (b, pb), 0, out);
    }
}

fn subdivide(
    c: &Curve,
    tol: f64,
    (a, pa): (f64, DVec2),
    (b, pb): (f64, DVec2),
    depth: u32,
    out: &mut Vec<DVec2>,
) {
    let m = 0.5 * (a + b);
    let pm = c.eval(m);
    let chord = pb - pa;
    let off = if chord.length_squared() > 0.0 {
        (pm - pa).perp_dot(chord).abs() / chord.length()
    } else {
        (pm - pa).length()
    };
    if depth < MIN_FLATTEN_DEPTH || (off > tol && depth < MAX_FLATTEN_DEPTH) {
        subdivide(c, tol, (a, pa), (m, pm), depth + 1, out);
        subdivide(c, tol, (m, pm), (b, pb), depth + 1, out);
    } else {
        out.push(pb);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The field file's loop: a rational quadratic circle of radius 0.5 about (0.5, 0.5),
    /// homogeneous u, v.
    fn circle() -> TrimLoops {
        let s = std::f64::consts::FRAC_1_SQRT_2;
        let knot = [
            0.0, 0.0, 0.0, 0.25, 0.25, 0.5, 0.5, 0.75, 0.75, 1.0, 1.0, 1.0,
        ];
        let u = [0.5, 0.0, 0.0, 0.0, 0.5, s, 1.0, s, 0.5];
        let v = [1.0, s, 0.5, 0.0, 0.0, 0.0, 0.5, s, 1.0];
        let w = [1.0, s, 1.0, s, 1.0, s, 1.0, s, 1.0];
        trim_loops(&TrimCurveArgs {
            ncurves: &[1.0],
            order: &[3.0],
            knot: &knot,
            min: &[0.0],
            max: &[1.0],
            n: &[9.0],
            u: &u,
            v: &v,
            w: &w,
        })
        .unwrap()
        .unwrap()
    }

    /// Every flattened point lies on the exact circle, and every chord's midpoint within the
    /// stated tolerance of it (1/4096 of the extent 1).
    #[test]
    fn a_rational_circle_flattens_within_the_tolerance() {
        let l = circle();
        assert_eq!(l.loops.len(), 1);
        let c = DVec2::splat(0.5);
        for p in &l.loops[0] {
            assert!(((*p - c).length() - 0.5).abs() < 1e-12, "{p}");
        }
        for (a, b) in l.edges() {
            let sag = 0.5 - ((a + b) * 0.5 - c).length();
            assert!((0.0..=TRIM_FLATNESS).contains(&sag), "sag {sag}");
        }
        assert!(
            l.edge_count() >= 16 && l.edge_count() <= 1024,
            "{}",
            l.edge_count()
        );
    }

    /// The even-odd rule: the centre is inside, the square's corners outside; "outside"
    /// keeps the opposite.
    #[test]
    fn inside_and_outside() {
        let loops = Arc::new(circle());
        assert!(loops.contains(DVec2::splat(0.5)));
        for p in [[0.02, 0.02], [0.98, 0.02], [0.02, 0.98], [0.98, 0.98]] {
            assert!(!loops.contains(DVec2::from(p)), "{p:?}");
        }
        let t = PatchTrim {
            loops,
            outside: true,
            u: (0.0, 1.0),
            v: (0.0, 1.0),
        };
        assert!(!t.keeps(0.5, 0.5) && t.keeps(0.01, 0.01));
        // A hole: a second loop inside the first is outside again.
        let mut two = circle();
        let inner: Vec<DVec2> = two.loops[0]
            .iter()
            .map(|p| (*p - 0.5) * 0.5 + 0.5)
            .collect();
        two.loops.push(inner);
        assert!(!two.contains(DVec2::splat(0.5)) && two.contains(DVec2::new(0.5, 0.1)));
    }

    #[test]
    fn bad_counts_are_named() {
        let e = trim_loops(&TrimCurveArgs {
            ncurves: &[1.0],
            order: &[3.0],
            knot: &[0.0; 5],
            min: &[0.0],
            max: &[1.0],
            n: &[3.0],
            u: &[0.0; 3],
            v: &[0.0; 3],
            w: &[1.0; 3],
        })
        .unwrap_err();
        assert!(e.contains("\"knot\" has 5 values"), "{e}");
        let e = trim_loops(&TrimCurveArgs {
            ncurves: &[1.0],
            order: &[2.0],
            knot: &[0.0, 0.0, 1.0, 1.0],
            min: &[0.0],
            max: &[1.0],
            n: &[2.0],
            u: &[0.0; 2],
            v: &[0.0; 2],
            w: &[1.0, 0.0],
        })
        .unwrap_err();
        assert!(e.contains("weight"), "{e}");
        assert_eq!(
            trim_loops(&TrimCurveArgs {
                ncurves: &[],
                order: &[],
                knot: &[],
                min: &[],
                max: &[],
                n: &[],
                u: &[],
                v: &[],
                w: &[],
            }),
            Ok(None)
        );
    }
}
