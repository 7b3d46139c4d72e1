//! Rational bicubic Bezier patches in f64, exactly: homogeneous control nets `(x w, y w, z w, w)`,
//! their evaluation with exact derivatives, and de Casteljau halving (exact subdivision of a
//! rational patch when done on the homogeneous points; Farin, *Curves and Surfaces for CAGD*,
//! ch. 13). For a polynomial patch (all w = 1) every function here does, bit for bit, the
//! Euclidean arithmetic it replaces: `w` stays exactly 1 and `x / 1 = x`.

use crate::scene::{Patch, eval_bezier};
use glam::{DVec3, DVec4};

/// A homogeneous control net, `cp[4*v + u] = (x w, y w, z w, w)`.
pub type HomNet = [DVec4; 16];

/// The homogeneous net of `p` (its Euclidean `cp` times its weights `w`).
pub fn homogeneous(p: &Patch) -> HomNet {
    let (cp, w) = (p.cp(), p.w());
    std::array::from_fn(|k| (cp[k] * w[k]).extend(w[k]))
}

/// The Euclidean point of a homogeneous one: xyz / w.
pub fn euclidean(h: DVec4) -> DVec3 {
    h.truncate() / h.w
}

/// The Euclidean control points of a homogeneous net.
pub fn euclidean_net(h: &HomNet) -> [DVec3; 16] {
    h.map(euclidean)
}

/// Point, d/du and d/dv of the rational patch with homogeneous net `h` at (u, v)
/// (`scene::rational::eval_homogeneous`).
pub fn eval_rational(h: &HomNet, u: f64, v: f64) -> (DVec3, DVec3, DVec3) {
    crate::scene::rational::eval_homogeneous(h, u, v)
}

/// Point, d/du and d/dv of patch `p` at (u, v): [`eval_bezier`] for a polynomial patch (no
/// division by a weight of 1 in its numbers), [`eval_rational`] otherwise.
pub fn eval_patch(p: &Patch, u: f64, v: f64) -> (DVec3, DVec3, DVec3) {
    if p.is_rational() {
        eval_rational(&homogeneous(p), u, v)
    } else {
        eval_bezier(&p.cp(), u, v)
    }
}

/// Point, d/du and d/dv at (u, v) of the patch with homogeneous net `h`: [`eval_rational`]
/// when `rational`, else [`eval_bezier`] on the net's points (all w = 1), as [`eval_patch`]
/// chooses.
pub fn eval_net(h: &HomNet, rational: bool, u: f64, v: f64) -> (DVec3, DVec3, DVec3) {
    if rational {
        eval_rational(h, u, v)
    } else {
        eval_bezier(&euclidean_net(h), u, v)
    }
}

/// De Casteljau halving of a homogeneous cubic at t = 1/2. Every step is (a + b) * 0.5, so
/// halving the reversed curve gives bit-identical (reversed) halves: shared curves split the
/// same from both sides.
pub fn split_curve(p: [DVec4; 4]) -> ([DVec4; 4], [DVec4; 4]) {
    let mid = |a: DVec4, b: DVec4| (a + b) * 0.5;
    let (m01, m12, m23) = (mid(p[0], p[1]), mid(p[1], p[2]), mid(p[2], p[3]));
    let (n0, n1) = (mid(m01, m12), mid(m12, m23));
    let c = mid(n0, n1);
    ([p[0], m01, n0, c], [c, n1, m23, p[3]])
}

/// Halves a net in u (each row split as a curve): the halves u in [0, 1/2] and [1/2, 1].
pub fn split_u(cp: &HomNet) -> (HomNet, HomNet) {
    let (mut a, mut b) = ([DVec4::ZERO; 16], [DVec4::ZERO; 16]);
    for r in 0..4 {
        let (l, h) = split_curve([cp[4 * r], cp[4 * r + 1], cp[4 * r + 2], cp[4 * r + 3]]);
        a[4 * r..4 * r + 4].copy_from_slice(&l);
        b[4 * r..4 * r + 4].copy_from_slice(&h);
    }
    (a, b)
}

/// Halves a net in v (each column split as a curve).
pub fn split_v(cp: &HomNet) -> (HomNet, HomNet) {
    let (mut a, mut b) = ([DVec4::ZERO; 16], [DVec4::ZERO; 16]);
    for c in 0..4 {
        let (l, h) = split_curve([cp[c], cp[c + 4], cp[c + 8], cp[c + 12]]);
        for k in 0..4 {
            a[4 * k + c] = l[k];
            b[4 * k + c] = h[k];
        }
    }
    (a, b)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::reference::closed::rational_sphere;

    /// The sphere's octants are exact: points on the sphere, derivatives that match finite
    /// differences, and d/du x d/dv along the outward radius (after `flip_normal`).
    #[test]
    fn rational_octants_lie_on_the_sphere_with_exact_derivatives() {
        let (c, r) = (DVec3::new(0.3, -0.2, 5.0), 1.7);
        let h = 1.0e-6;
        for p in rational_sphere(c, r) {
            assert!(p.is_rational());
            for k in 0..=20 * 20 {
                let (u, v) = ((k % 21) as f64 / 20.0, (k / 21) as f64 / 20.0);
                let (pos, du, dv) = eval_patch(&p, u, v);
                assert!((pos.distance(c) - r).abs() < 1e-13, "{pos} at ({u}, {v})");
                if !(0.01..0.99).contains(&u) || !(0.01..0.99).contains(&v) {
                    continue;
                }
                let fu = (eval_patch(&p, u + h, v).0 - eval_patch(&p, u - h, v).0) / (2.0 * h);
                let fv = (eval_patch(&p, u, v + h).0 - eval_patch(&p, u, v - h).0) / (2.0 * h);
                assert!(du.distance(fu) < 1e-7 * r, "{du} vs {fu}");
                assert!(dv.distance(fv) < 1e-7 * r, "{dv} vs {fv}");
                let n = du.cross(dv) * if p.flip_normal { -1.0 } else { 1.0 };
                let radial = (pos - c).normalize();
                assert!(n.normalize().dot(radial) > 1.0 - 1e-12, "{n} vs {radial}");
            }
        }
    }

    /// Split halves (f64, homogeneous) evaluate to the parent's surface at the mapped
    /// parameters, along random paths of 12 splits; for a polynomial patch the homogeneous
    /// split is the Euclidean one bit for bit.
    #[test]
    fn split_halves_are_the_parent_surface() {
        let mut seed = 0x9e37_79b9u32;
        let mut rnd = || {
            seed = scheduler::hash::lowbias32(seed);
            seed
        };
        for p in rational_sphere(DVec3::new(0.0, 0.0, 4.0), 1.0) {
            let root = homogeneous(&p);
            let (mut net, mut uv) = (root, [0.0, 1.0, 0.0, 1.0]);
            for _ in 0..12 {
                let r = rnd();
                let (along_u, second) = (r & 1 != 0, r & 2 != 0);
                let (a, b) = if along_u {
                    split_u(&net)
                } else {
                    split_v(&net)
                };
                net = if second { b } else { a };
                let (lo, hi) = if along_u { (0, 1) } else { (2, 3) };
                let m = (uv[lo] + uv[hi]) * 0.5;
                if second {
                    uv[lo] = m
                } else {
                    uv[hi] = m
                }
                for (s, t) in [(0.0, 0.0), (0.25, 0.75), (0.5, 0.5), (1.0, 0.3), (1.0, 1.0)] {
                    let sub = eval_rational(&net, s, t).0;
                    let (pu, pv) = (uv[0] + s * (uv[1] - uv[0]), uv[2] + t * (uv[3] - uv[2]));
                    let whole = eval_rational(&root, pu, pv).0;
                    assert!(sub.distance(whole) < 1e-13, "{sub} vs {whole}");
                }
            }
        }
        let teapot = &crate::scene::builtin_teapot().patches[7];
        let (a, b) = split_u(&homogeneous(teapot));
        for (k, q) in a.iter().chain(&b).enumerate() {
            assert_eq!(q.w, 1.0, "point {k}");
        }
        assert_eq!(euclidean_net(&a)[0], teapot.cp()[0]);
        let e = euclidean_net(&b);
        assert_eq!(e[3], teapot.cp()[3]);
        assert_eq!(
            eval_patch(teapot, 0.3, 0.6),
            eval_bezier(&teapot.cp(), 0.3, 0.6)
        );
    }
}
