//! Primitive variables a patch carries to its shading: the surface colour `"Cs"` and opacity
//! `"Os"` (and, for polygon meshes, the shading normal `"N"`), each as a field over the
//! patch's own parameter square.
//!
//! The RIB reader turns every storage class of the RenderMan Interface (constant, uniform,
//! varying, vertex; RI Specification 3.2, section 5) into one of three shapes over the
//! emitted Bezier patch's (u, v) in [0, 1]²: one value (constant and uniform), four corners
//! interpolated bilinearly (varying), or 16 bicubic Bezier coefficients (vertex: the values
//! put through the same basis change as the positions, as if they were points). The
//! renderer evaluates the field at a grid point's (u, v) in its ORIGINAL patch, which queue
//! items carry through every split, so a field never needs to be split itself.

use glam::DVec3;

/// How one colour-valued primitive variable varies over one bicubic patch, in the patch's
/// own parameters (u, v) in [0, 1]².
#[derive(Clone, Debug, PartialEq)]
#[allow(
    clippy::large_enum_variant,
    reason = "fields live in a patch's boxed `Primvars`; boxing `Bezier` too would add an allocation per field"
)]
pub enum ColorField {
    /// Class constant or uniform: one value over the whole patch.
    Flat(DVec3),
    /// Class varying: the values at the corners (0,0), (1,0), (0,1), (1,1), interpolated
    /// bilinearly.
    Bilinear([DVec3; 4]),
    /// Class vertex: bicubic Bezier coefficients `c[4*v + u]` (u fastest), evaluated with the
    /// Bernstein polynomials like the positions.
    Bezier([DVec3; 16]),
}

impl ColorField {
    /// The value at (u, v), both in [0, 1].
    pub fn eval(&self, u: f64, v: f64) -> DVec3 {
        match self {
            ColorField::Flat(c) => *c,
            ColorField::Bilinear(c) => {
                let lo = c[0] + (c[1] - c[0]) * u;
                let hi = c[2] + (c[3] - c[2]) * u;
                lo + (hi - lo) * v
            }
            ColorField::Bezier(c) => crate::scene::eval_bezier(c, u, v).0,
        }
    }

    /// The field on the sub-square [u0, u1] x [v0, v1] of the parameter square, reparametrized
    /// to [0, 1]² (what a NURBS span cut by the surface's parameter range needs). Exact for
    /// every shape: a bilinear or bicubic polynomial restricted to a rectangle is again one.
    pub fn restricted(&self, (u0, u1): (f64, f64), (v0, v1): (f64, f64)) -> ColorField {
        match self {
            ColorField::Flat(c) => ColorField::Flat(*c),
            ColorField::Bilinear(_) => ColorField::Bilinear(
                [(u0, v0), (u1, v0), (u0, v1), (u1, v1)].map(|(u, v)| self.eval(u, v)),
            ),
            ColorField::Bezier(c) => {
                // Blossoming: the Bezier points of a cubic on [a, b] are f(a,a,a), f(a,a,b),
                // f(a,b,b), f(b,b,b); rows first, then columns.
                let rows: [DVec3; 16] = std::array::from_fn(|k| {
                    let (i, j) = (k % 4, k / 4);
                    let row = [0, 1, 2, 3].map(|m| c[4 * j + m]);
                    blossom(row, sub_args(u0, u1, i))
                });
                ColorField::Bezier(std::array::from_fn(|k| {
                    let (i, j) = (k % 4, k / 4);
                    let col = [0, 1, 2, 3].map(|m| rows[4 * m + i]);
                    blossom(col, sub_args(v0, v1, j))
                }))
            }
        }
    }

    /// Every value the field is made of (for range checks).
    pub fn values(&self) -> &[DVec3] {
        match self {
            ColorField::Flat(c) => std::slice::from_ref(c),
            ColorField::Bilinear(c) => c,
            ColorField::Bezier(c) => c,
        }
    }
}

/// The blossom arguments of Bezier point `k` of a cubic restricted to [a, b].
fn sub_args(a: f64, b: f64, k: usize) -> [f64; 3] {
    std::array::from_fn(|m| if m < 3 - k { a } else { b })
}

/// The blossom of the cubic Bezier curve `p` at `t` (de Casteljau with one argument per level).
fn blossom(mut p: [DVec3; 4], t: [f64; 3]) -> DVec3 {
    for (level, x) in t.into_iter().enumerate() {
        for k in 0..3 - level {
            p[k] = p[k] + (p[k + 1] - p[k]) * x;
        }
    }
    p[0]
}

/// The colour primitive variables of one patch; `None` fields come from the patch's material
/// (the `Color` and `Opacity` attributes).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Primvars {
    /// `"Cs"`: the surface colour, multiplied into the standard shaders as `Color` is.
    pub cs: Option<ColorField>,
    /// `"Os"`: the surface opacity per channel; the renderer uses the mean of the three
    /// channels as the fraction of samples the surface covers (docs/reyes.md, Opacity).
    pub os: Option<ColorField>,
    /// `"N"`: the shading normal in camera space (a field of vectors: polygon meshes' vertex
    /// or face-varying normals), interpolated, then normalized by the shader; `None`: the
    /// surface's own normal. Shading only: which side faces the eye (`Sides 1`) and the
    /// direction of displacement stay the surface's.
    pub n: Option<ColorField>,
}

impl Primvars {
    /// `Some` when at least one variable is given, else `None` (a patch without primitive
    /// variables costs nothing). One allocation that the instances of an object share.
    pub fn shared(self) -> Option<std::sync::Arc<Primvars>> {
        (self.cs.is_some() || self.os.is_some() || self.n.is_some())
            .then(|| std::sync::Arc::new(self))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn wavy() -> [DVec3; 16] {
        std::array::from_fn(|k| {
            let (i, j) = ((k % 4) as f64, (k / 4) as f64);
            DVec3::new((i * 0.7).sin(), j * 0.3 - i * 0.1, (i + j).cos())
        })
    }

    #[test]
    fn bilinear_field_hits_its_corners_and_blends_between() {
        let f = ColorField::Bilinear([DVec3::X, DVec3::Y, DVec3::Z, DVec3::ONE]);
        assert_eq!(f.eval(0.0, 0.0), DVec3::X);
        assert_eq!(f.eval(1.0, 0.0), DVec3::Y);
        assert_eq!(f.eval(0.0, 1.0), DVec3::Z);
        assert_eq!(f.eval(1.0, 1.0), DVec3::ONE);
        assert!(f.eval(0.5, 0.5).distance(DVec3::splat(0.5)) < 1e-15);
    }

    #[test]
    fn restriction_is_the_same_field_on_the_sub_square() {
        let (u, v) = ((0.2, 0.7), (0.35, 0.9));
        for f in [
            ColorField::Flat(DVec3::new(0.1, 0.2, 0.3)),
            ColorField::Bilinear([DVec3::X, DVec3::Y, DVec3::Z, DVec3::ONE]),
            ColorField::Bezier(wavy()),
        ] {
            let r = f.restricted(u, v);
            for (s, t) in [(0.0, 0.0), (1.0, 1.0), (0.3, 0.8), (0.9, 0.1)] {
                let want = f.eval(u.0 + s * (u.1 - u.0), v.0 + t * (v.1 - v.0));
                assert!(r.eval(s, t).distance(want) < 1e-12, "{f:?} at ({s}, {t})");
            }
        }
    }
}
