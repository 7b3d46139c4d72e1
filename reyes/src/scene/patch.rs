//! A scene's patch as the host keeps it: [`Patch`], its control net [`PatchNet`] and its
//! origin [`PatchSource`].
//!
//! Memory per patch matters: a scene may hold millions (issue 24: 10 million identical
//! bilinear patches once took 4 GB, about 600 bytes each). The net keeps what the input gave:
//! a bilinear patch as its 4 object-space corners and a transform shared by the patches under
//! it, a bicubic one as its 16 camera-space points, weights only for a rational one. The 16
//! camera-space points are formed when asked for ([`Patch::cp`]), by the same f64 arithmetic
//! the reader used to do up front, so they are the same bits.

use std::sync::Arc;

use glam::{DMat4, DVec3};

use super::{Displacement, Primvars};

/// One bicubic Bezier patch.
#[derive(Clone, Debug, PartialEq)]
pub struct Patch {
    /// The control net: 16 control points (camera space, [`Patch::cp`]) and their weights
    /// ([`Patch::w`]). Built with [`PatchNet::new`] from the 16 points and weights.
    pub net: PatchNet,
    /// Index into [`Scene::materials`](super::Scene::materials).
    pub material: u32,
    /// True when the camera-space geometric normal dPdu x dPdv must be negated to get the
    /// surface's OUTSIDE normal as RenderMan defines it (`Orientation`/`ReverseOrientation`
    /// versus the handedness of the current transform; see `rib/mod.rs` for the derivation).
    pub flip_normal: bool,
    /// `Sides 2` (the default): both sides visible. `Sides 1`: back-facing parts are culled.
    pub two_sided: bool,
    /// The patch's own `"Cs"` / `"Os"` over its parameter square; `None` (no cost) when the
    /// material's `Color` and `Opacity` apply everywhere. Shared by the instances of an
    /// object (`ObjectInstance`), and written to the GPU's tables once per allocation.
    pub primvars: Option<Arc<Primvars>>,
    /// Displacement along the normal in DiceShade (RIB `Displacement`); `None` (no cost) for
    /// the undisplaced surface. Shared by the patches of one request.
    pub displacement: Option<Arc<Displacement>>,
    /// Motion over the shutter (RIB `MotionBegin` around transforms): the camera-space
    /// affine map taking the patch at shutter open (`cp`) to the patch at shutter close; a
    /// point at shutter fraction t is the linear interpolation of the two (docs/reyes.md,
    /// "Motion blur and depth of field"). `None` for a patch that does not move.
    pub motion: Option<Box<DMat4>>,
    /// Trimming (RIB `TrimCurve` before a `NuPatch`): the loops that keep part of the patch,
    /// and the patch's span of the surface's parameter space; `None` (no cost) when untrimmed.
    pub trim: Option<Arc<super::trim::PatchTrim>>,
    /// Where the patch came from, for error messages.
    pub source: PatchSource,
}

impl Patch {
    /// Weights of a polynomial (non-rational) patch.
    pub const POLYNOMIAL: [f64; 16] = [1.0; 16];

    /// A patch of control points `cp` (camera space, `cp[4*v + u]`) and weights `w`
    /// ([`PatchNet::new`]), from `source`, with the defaults of everything else: material 0,
    /// not flipped, two-sided, no primitive variables, displacement, motion or trim. Set the other
    /// fields with struct update syntax: `Patch { material: 2, ..Patch::new(cp, w, source) }`.
    pub fn new(cp: [DVec3; 16], w: [f64; 16], source: PatchSource) -> Patch {
        Patch {
            net: PatchNet::new(cp, w),
            material: 0,
            flip_normal: false,
            two_sided: true,
            primvars: None,
            displacement: None,
            motion: None,
            trim: None,
            source,
        }
    }

    /// The 16 control points, row-major: `cp[4*v + u]`, u varies fastest (RenderMan order);
    /// camera space, Euclidean (already divided by their weight when the patch is rational).
    /// Formed from the net ([`PatchNet::points`]), so take them once per use.
    pub fn cp(&self) -> [DVec3; 16] {
        self.net.points()
    }

    /// The control points to change in place (the net is kept as 16 points from then on).
    pub fn cp_mut(&mut self) -> &mut [DVec3; 16] {
        self.net.points_mut()
    }

    /// The weight of each control point, same order: the patch is the rational Bezier surface
    /// sum(B_i B_j w_ij P_ij) / sum(B_i B_j w_ij). All 1.0 for a polynomial patch (every loader
    /// but rational `NuPatch` "Pw" and the quadrics); always finite and positive.
    pub fn w(&self) -> [f64; 16] {
        self.net.weights().copied().unwrap_or(Self::POLYNOMIAL)
    }

    /// The weights to change in place (the net then holds 16 points and 16 weights).
    pub fn w_mut(&mut self) -> &mut [f64; 16] {
        self.net.weights_mut()
    }

    /// True when some weight differs from 1 (the patch needs homogeneous arithmetic).
    pub fn is_rational(&self) -> bool {
        self.net.weights().is_some_and(|w| *w != Self::POLYNOMIAL)
    }

    /// Bytes the host holds for this patch: the struct and what it owns alone (its net's and
    /// motion's heap parts, its primitive variables unless another patch shares them), not
    /// what it shares with other patches (the file name, a bilinear net's transform, a
    /// displacement, an instanced object's fields and weights).
    pub fn host_bytes(&self) -> usize {
        std::mem::size_of::<Patch>()
            + self.net.heap_bytes()
            + self
                .motion
                .as_ref()
                .map_or(0, |_| std::mem::size_of::<DMat4>())
            + self.primvars.as_ref().map_or(0, |v| {
                (Arc::strong_count(v) == 1) as usize * std::mem::size_of::<Primvars>()
            })
    }
}

/// Origin of a patch: file, line of the request, and index of the patch within that request
/// (0-based; for meshes and NURBS, the index of the sub-patch or span).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PatchSource {
    /// The scene file, as named to the loader; one allocation shared by the patches of a
    /// file (`"a.rib".into()` makes one).
    pub file: Arc<str>,
    /// Line of the request in that file.
    pub line: u64,
    /// Index of the patch within the request.
    pub index: u32,
}

/// How a bilinear patch's 4 corners become 16 Bezier control points (both exact: a bilinear
/// patch is a bicubic one; they differ in the last bit of some points).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum BilinearForm {
    /// `Patch "bilinear"`, `PatchMesh "bilinear"`: each point the bilinear map at (i/3, j/3)
    /// ([`bilinear_to_bezier`]).
    Patch,
    /// Polygons: the edges' points from the lexicographically smaller corner, so neighbours
    /// share them bit for bit (`polygon::bilinear_patch`).
    Polygon,
}

/// A patch's control net as the host keeps it. Equal nets have equal points and weights,
/// whatever their form.
#[derive(Clone, Debug)]
pub struct PatchNet(Net);

#[derive(Clone, Debug)]
enum Net {
    /// A bilinear patch: its object-space corners (0,0), (1,0), (0,1), (1,1) and the
    /// object-to-camera transform, shared by the patches under it. The 16 points are the
    /// corners elevated to bicubic as `form` says, then transformed (`project_point3`), as
    /// the reader did before nets were compact. 112 bytes against 16 points' 384 on the heap.
    Bilinear {
        corners: [DVec3; 4],
        to_camera: Arc<DMat4>,
        form: BilinearForm,
    },
    /// 16 camera-space points, and the weights of a rational patch.
    Bicubic(Box<BicubicNet>),
}

#[derive(Clone, Debug)]
struct BicubicNet {
    cp: [DVec3; 16],
    /// Shared by the instances of an object (the weights do not depend on the placement).
    w: Option<Arc<[f64; 16]>>,
}

impl PatchNet {
    /// The net of 16 camera-space control points (`cp[4*v + u]`) with weights `w`; weights
    /// that are all 1 ([`Patch::POLYNOMIAL`]) are not stored.
    pub fn new(cp: [DVec3; 16], w: [f64; 16]) -> PatchNet {
        let w = (w != Patch::POLYNOMIAL).then(|| Arc::new(w));
        PatchNet(Net::Bicubic(Box::new(BicubicNet { cp, w })))
    }

    /// [`PatchNet::new`] with weights another net holds already (an instance of an object
    /// shares its weights with the object's other instances); `None` for all 1.
    pub(crate) fn with_shared_weights(cp: [DVec3; 16], w: Option<Arc<[f64; 16]>>) -> PatchNet {
        PatchNet(Net::Bicubic(Box::new(BicubicNet { cp, w })))
    }

    /// The weights as the net holds them: one allocation that instances share ([`Arc`]),
    /// `None` when all are 1. The GPU's weight table has one entry per allocation.
    pub fn shared_weights(&self) -> Option<&Arc<[f64; 16]>> {
        match &self.0 {
            Net::Bilinear { .. } => None,
            Net::Bicubic(b) => b.w.as_ref(),
        }
    }

    /// The net of a bilinear patch of object-space `corners` under `to_camera` (affine),
    /// elevated to bicubic as `form` says when its points are asked for.
    pub(crate) fn bilinear(
        corners: [DVec3; 4],
        to_camera: Arc<DMat4>,
        form: BilinearForm,
    ) -> PatchNet {
        PatchNet(Net::Bilinear {
            corners,
            to_camera,
            form,
        })
    }

    /// The 16 camera-space control points (Euclidean), `[4*v + u]`.
    pub fn points(&self) -> [DVec3; 16] {
        match &self.0 {
            Net::Bilinear {
                corners,
                to_camera,
                form,
            } => {
                let object = match form {
                    BilinearForm::Patch => bilinear_to_bezier(*corners),
                    BilinearForm::Polygon => super::polygon::bilinear_patch(*corners),
                };
                object.map(|p| to_camera.project_point3(p))
            }
            Net::Bicubic(b) => b.cp,
        }
    }

    /// The weights of a net that has them (rational input); `None` when all are 1.
    pub fn weights(&self) -> Option<&[f64; 16]> {
        match &self.0 {
            Net::Bilinear { .. } => None,
            Net::Bicubic(b) => b.w.as_deref(),
        }
    }

    /// The net as 16 stored points and weights (a bilinear net is expanded).
    fn bicubic(&mut self) -> &mut BicubicNet {
        if let Net::Bilinear { .. } = self.0 {
            let cp = self.points();
            self.0 = Net::Bicubic(Box::new(BicubicNet { cp, w: None }));
        }
        match &mut self.0 {
            Net::Bicubic(b) => b,
            Net::Bilinear { .. } => unreachable!("expanded above"),
        }
    }

    /// The 16 points to change in place.
    pub fn points_mut(&mut self) -> &mut [DVec3; 16] {
        &mut self.bicubic().cp
    }

    /// The 16 weights to change in place (stored from then on, all 1 at first).
    pub fn weights_mut(&mut self) -> &mut [f64; 16] {
        Arc::make_mut(
            self.bicubic()
                .w
                .get_or_insert_with(|| Arc::new(Patch::POLYNOMIAL)),
        )
    }

    /// Bytes the net owns on the heap (0 for a bilinear net, whose transform is shared;
    /// weights only when no other net shares them).
    pub fn heap_bytes(&self) -> usize {
        match &self.0 {
            Net::Bilinear { .. } => 0,
            Net::Bicubic(b) => {
                std::mem::size_of::<BicubicNet>()
                    + b.w.as_ref().map_or(0, |w| {
                        (Arc::strong_count(w) == 1) as usize * std::mem::size_of::<[f64; 16]>()
                    })
            }
        }
    }
}

/// Elevates a bilinear patch (corners (0,0), (1,0), (0,1), (1,1)) to bicubic Bezier: each
/// point the bilinear map at (i/3, j/3).
pub(crate) fn bilinear_to_bezier(c: [DVec3; 4]) -> [DVec3; 16] {
    std::array::from_fn(|k| {
        let (u, v) = ((k % 4) as f64 / 3.0, (k / 4) as f64 / 3.0);
        c[0].lerp(c[1], u).lerp(c[2].lerp(c[3], u), v)
    })
}

impl PartialEq for PatchNet {
    fn eq(&self, o: &PatchNet) -> bool {
        let ones = |n: &PatchNet| n.weights().copied().unwrap_or(Patch::POLYNOMIAL);
        self.points() == o.points() && ones(self) == ones(o)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn corners() -> [DVec3; 4] {
        [
            DVec3::new(-1.0, -1.0, 0.1),
            DVec3::new(1.0, -1.0, 0.3),
            DVec3::new(-1.0, 1.0, 0.7),
            DVec3::new(1.0, 1.0, 0.0),
        ]
    }

    fn to_camera() -> Arc<DMat4> {
        Arc::new(
            DMat4::from_translation(DVec3::new(0.1, 0.2, 5.0))
                * DMat4::from_axis_angle(DVec3::new(1.0, 2.0, 3.0).normalize(), 0.7),
        )
    }

    /// A bilinear net's points are the reader's old arithmetic (elevate in object space,
    /// then transform) bit for bit, in either form; expanding it in place keeps them.
    #[test]
    fn bilinear_nets_give_the_points_the_reader_formed() {
        let (c, m) = (corners(), to_camera());
        for (form, elevate) in [
            (
                BilinearForm::Patch,
                bilinear_to_bezier as fn([DVec3; 4]) -> [DVec3; 16],
            ),
            (BilinearForm::Polygon, super::super::polygon::bilinear_patch),
        ] {
            let want = elevate(c).map(|p| m.project_point3(p));
            let mut net = PatchNet::bilinear(c, m.clone(), form);
            assert_eq!(net.points(), want);
            assert!(net.weights().is_none());
            assert_eq!(net, PatchNet::new(want, Patch::POLYNOMIAL));
            assert_eq!(net.heap_bytes(), 0);
            net.points_mut()[0].x += 1.0;
            assert_eq!(net.points()[1..], want[1..]);
            assert_ne!(net.points()[0], want[0]);
        }
    }

    /// Weights are stored for rational nets only, and read back as given.
    #[test]
    fn weights_are_kept_for_rational_nets_only() {
        let cp: [DVec3; 16] = std::array::from_fn(|k| DVec3::new(k as f64, 1.0, 2.0));
        let source = PatchSource {
            file: "t.rib".into(),
            line: 3,
            index: 0,
        };
        let mut p = Patch::new(cp, Patch::POLYNOMIAL, source);
        assert!(!p.is_rational() && p.net.weights().is_none());
        assert_eq!((p.cp(), p.w()), (cp, Patch::POLYNOMIAL));
        p.w_mut()[6] = 4.0;
        assert!(p.is_rational());
        let mut w = Patch::POLYNOMIAL;
        w[6] = 4.0;
        assert_eq!(p.w(), w);
        assert_eq!(p.net, PatchNet::new(cp, w));
        assert!(p.host_bytes() > std::mem::size_of::<Patch>() + 16 * 24 + 16 * 8);
    }

    /// The common case stays small: a bilinear patch (the struct, nothing owned on the heap)
    /// under 180 bytes, against about 600 with 16 f64 points and weights and an owned file
    /// name (issue 24). docs/reyes.md, *Limits*, quotes these sizes.
    #[test]
    fn a_bilinear_patch_is_small() {
        let p = Patch {
            net: PatchNet::bilinear(corners(), to_camera(), BilinearForm::Patch),
            ..Patch::new(
                [DVec3::ZERO; 16],
                Patch::POLYNOMIAL,
                PatchSource {
                    file: "t.rib".into(),
                    line: 1,
                    index: 0,
                },
            )
        };
        assert_eq!(p.host_bytes(), std::mem::size_of::<Patch>());
        assert!(p.host_bytes() <= 184, "{} bytes", p.host_bytes());
    }
}
