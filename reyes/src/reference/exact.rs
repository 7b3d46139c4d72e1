//! Exact (f64) sample coverage of a scene's patches: the ground truth that GPU output is
//! judged against.
//!
//! Method. Each patch is split recursively (de Casteljau halving of its control net, so every
//! cell corner is an exact surface point) until the cell's projected control net is smaller
//! than `SIZE_PX` (0.25 px) and within `FLAT_PX` (0.02 px) of the bilinear map of its projected corners (a
//! bound on the brief's "centre versus bilinear corners" test that also catches curved
//! edges and folds). Cells whose projected control net (a conservative bound: the surface
//! lies in the net's convex hull, and a perspective projection keeps hulls) holds no sample
//! are dropped, which culls off-screen geometry early.
//!
//! A leaf covers the samples inside its projected boundary loop (non-zero winding, boundary
//! inclusive). The loop is the cell's four boundary curves, each refined by halving wherever
//! a sample lies inside the projected hull of the piece, until the piece is straight to
//! `EDGE_EPS_PX` (1e-7 px). That rule depends only on the piece itself and on the global sample grid,
//! and halving is bit-exact in either direction, so two cells sharing a curve (within a
//! patch, or across patches whose boundary control points are bit-identical) classify every
//! sample identically on both sides: the result is watertight, with no T-junction cracks.
//!
//! Cells straddling the near or far plane are split further (their bound is the projection
//! of the control hull clipped to the z slab) and, once tiny, their corner quad is clipped
//! to the slab in 3D and filled.
//!
//! Rational patches: cells are homogeneous nets halved exactly (`homogeneous::split_u`); every
//! test above uses the cell's Euclidean control points, whose hull holds a rational patch
//! with positive weights as it holds a polynomial one, and a curve's projection (a rational
//! curve with weights w z > 0) stays in the hull of its projected control points. Polynomial
//! patches (w = 1) give the same numbers as Euclidean nets.

use super::homogeneous::{HomNet, euclidean, homogeneous, split_curve, split_u, split_v};
use super::polygon::{bounds, clip_z, covers, curve_deviation, cut_at_z};
use crate::scene::Scene;
use glam::{DVec2, DVec3, DVec4};
use rayon::prelude::*;
use std::ops::RangeInclusive;

/// A leaf cell's projected control net must fit in a box this big (pixels).
const SIZE_PX: f64 = 0.25;
/// ... and lie within this distance (pixels) of the bilinear map of its projected corners.
const FLAT_PX: f64 = 0.02;
/// Cells straddling a clipping plane stop splitting once their visible bound is this small.
const CLIP_PX: f64 = 0.02;
/// Boundary curve pieces with a sample in their hull are refined until this straight.
const EDGE_EPS_PX: f64 = 1e-7;
/// Split depth caps (each split halves one parameter direction).
const MAX_DEPTH: u32 = 60;
const EDGE_MAX_DEPTH: u32 = 40;
/// Bounding boxes are widened by this much (pixels) before the sample query, to absorb
/// rounding in the projection of split control points.
const BOX_SLACK: f64 = 1e-9;

/// Per-pixel covered fraction of a regular sub-sample grid.
#[derive(Clone, Debug, PartialEq)]
pub struct Coverage {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Row-major, `frac[y * width + x]`, in [0, 1].
    pub frac: Vec<f32>,
}

impl Coverage {
    /// Covered fraction of pixel (x, y).
    pub fn at(&self, x: u32, y: u32) -> f32 {
        self.frac[(y * self.width + x) as usize]
    }

    /// Covered area in square pixels.
    pub fn area(&self) -> f64 {
        self.frac.iter().map(|&f| f as f64).sum()
    }

    /// Pixels whose whole 3x3 neighbourhood is fully covered (pixels outside the image
    /// count as uncovered). Such pixels must be fully covered by any correct renderer,
    /// whatever its sample pattern: a robust "must be solid" mask for pinhole checks.
    pub fn interior(&self) -> Vec<bool> {
        let (w, h) = (self.width as i64, self.height as i64);
        let full = |x: i64, y: i64| {
            (0..w).contains(&x) && (0..h).contains(&y) && self.frac[(y * w + x) as usize] >= 1.0
        };
        (0..h)
            .flat_map(|y| (0..w).map(move |x| (x, y)))
            .map(|(x, y)| (-1..=1).all(|dy| (-1..=1).all(|dx| full(x + dx, y + dy))))
            .collect()
    }
}

/// Pinholes: pixels in `reference.interior()` whose `alpha` (row-major, same size) is below
/// 1 by more than 8-bit quantisation (1/512) allows.
pub fn pinholes(alpha: &[f32], reference: &Coverage) -> usize {
    assert_eq!(
        alpha.len(),
        reference.frac.len(),
        "alpha and reference differ in size"
    );
    reference
        .interior()
        .iter()
        .zip(alpha)
        .filter(|(inside, a)| **inside && **a < 1.0 - 1.0 / 512.0)
        .count()
}

/// The renderer's projection to pixel coordinates (y down); `None` when `p.z <= 0`.
/// Ignores the near and far planes: callers decide visibility.
pub fn project(scene: &Scene, width: u32, height: u32, p: DVec3) -> Option<DVec2> {
    (p.z > 0.0).then(|| Proj::new(scene, width, height).apply(p))
}

/// Camera constants of [`project`], plus the clipping slab.
#[derive(Clone, Copy, Debug)]
struct Proj {
    half_w: f64,
    half_h: f64,
    f: f64,
    near: f64,
    far: f64,
}

impl Proj {
    fn new(scene: &Scene, width: u32, height: u32) -> Proj {
        let short = width.min(height) as f64;
        Proj {
            half_w: width as f64 / 2.0,
            half_h: height as f64 / 2.0,
            f: short / 2.0 / (scene.camera.fov_deg.to_radians() / 2.0).tan(),
            near: scene.camera.near,
            far: scene.camera.far,
        }
    }

    /// px = W/2 + f x / z, py = H/2 - f y / z. Only for z > 0.
    fn apply(&self, p: DVec3) -> DVec2 {
        DVec2::new(
            self.half_w + self.f * p.x / p.z,
            self.half_h - self.f * p.y / p.z,
        )
    }

    fn visible_z(&self, z: f64) -> bool {
        self.near <= z && z <= self.far
    }
}

/// The global sub-sample grid: sample (kx, ky) sits at pixel kx / n plus (kx % n + 0.5) / n.
#[derive(Clone, Copy, Debug)]
struct Grid {
    n: u32,
    /// Samples per row and per column.
    sw: usize,
    sh: usize,
    /// Sample rows taken into account, `first..end` (all of them: `0..sh`).
    rows: (usize, usize),
}

impl Grid {
    fn coord(&self, k: usize) -> f64 {
        let n = self.n as usize;
        (k / n) as f64 + ((k % n) as f64 + 0.5) / self.n as f64
    }

    fn pos(&self, kx: usize, ky: usize) -> DVec2 {
        DVec2::new(self.coord(kx), self.coord(ky))
    }

    /// Sample indices in [lo, hi] along one axis, among `first..end` (widened by BOX_SLACK).
    fn axis(&self, lo: f64, hi: f64, first: usize, end: usize) -> Option<RangeInclusive<usize>> {
        let n = self.n as f64;
        let a = ((lo - BOX_SLACK) * n - 0.5).ceil().max(first as f64);
        let b = ((hi + BOX_SLACK) * n - 0.5).floor().min(end as f64 - 1.0);
        // Written so that NaN bounds give None.
        if a <= b {
            Some(a as usize..=b as usize)
        } else {
            None
        }
    }

    /// Samples inside the box [lo, hi], or None when there are none.
    fn range(
        &self,
        (lo, hi): (DVec2, DVec2),
    ) -> Option<(RangeInclusive<usize>, RangeInclusive<usize>)> {
        Some((
            self.axis(lo.x, hi.x, 0, self.sw)?,
            self.axis(lo.y, hi.y, self.rows.0, self.rows.1)?,
        ))
    }
}

/// Fraction of each pixel's `samples_per_axis`^2 regular sub-samples covered by any patch of
/// `scene` (depth ignored; near/far clipping applied), seen by `scene.camera` at
/// `width` x `height`. Patches are spread over all available threads.
pub fn coverage(scene: &Scene, width: u32, height: u32, samples_per_axis: u32) -> Coverage {
    coverage_with(scene, width, height, samples_per_axis, SIZE_PX, FLAT_PX)
}

/// [`coverage`] with the leaf tolerances as parameters (tests use coarse ones to show that
/// flat geometry comes out exact whatever the cell size).
fn coverage_with(
    scene: &Scene,
    width: u32,
    height: u32,
    samples_per_axis: u32,
    size_px: f64,
    flat_px: f64,
) -> Coverage {
    assert!(samples_per_axis > 0, "samples_per_axis must be positive");
    let n = samples_per_axis as usize;
    let grid = Grid {
        n: samples_per_axis,
        sw: width as usize * n,
        sh: height as usize * n,
        rows: (0, height as usize * n),
    };
    let proj = Proj::new(scene, width, height);
    // Each of rayon's threads rasterizes its share of the patches into its own bit set; the
    // sets are OR-ed together (at most one share per thread, so as many sets as threads).
    let words = (grid.sw * grid.sh).div_ceil(64);
    let share = scene
        .patches
        .len()
        .div_ceil(rayon::current_num_threads())
        .max(1);
    let bits = (scene.patches.par_iter().enumerate())
        .with_min_len(share)
        .fold(
            || vec![0u64; words],
            |mut bits, (i, p)| {
                Raster::new(proj, grid, size_px, flat_px, |_: &Leaf, [kx, ky], _| {
                    let k = ky * grid.sw + kx;
                    bits[k / 64] |= 1 << (k % 64);
                })
                .patch(i, &homogeneous(p));
                bits
            },
        )
        .reduce(
            || vec![0u64; words],
            |mut all, b| {
                for (a, b) in all.iter_mut().zip(b) {
                    *a |= b;
                }
                all
            },
        );
    let frac = (0..height as usize)
        .flat_map(|y| (0..width as usize).map(move |x| (x, y)))
        .map(|(x, y)| {
            let hits: u32 = (y * n..(y + 1) * n)
                .map(|ky| {
                    let row = ky * grid.sw;
                    (x * n..(x + 1) * n)
                        .filter(|kx| bits[(row + kx) / 64] >> ((row + kx) % 64) & 1 == 1)
                        .count() as u32
                })
                .sum();
            hits as f32 / (n * n) as f32
        })
        .collect();
    Coverage {
        width,
        height,
        frac,
    }
}

/// A leaf cell of the traversal, as passed to [`for_each_covered_sample`]'s visitor.
#[derive(Clone, Copy, Debug)]
pub struct Leaf<'a> {
    /// Index of the patch in `scene.patches`.
    pub patch: usize,
    /// Parameter range of the cell in that patch: u0, u1, v0, v1.
    pub uv: [f64; 4],
    /// The cell's own control net (camera space, homogeneous `(x w, y w, z w, w)`), from
    /// exact de Casteljau halving.
    pub cp: &'a HomNet,
    /// The cell straddled a clipping plane and was filled as its clipped corner quad.
    pub clipped: bool,
}

/// Calls `visit(leaf, [kx, ky], position)` for every sample of the regular
/// `samples_per_axis`^2-per-pixel grid in sample rows `rows` (of `height * samples_per_axis`)
/// that a leaf cell covers, in no particular order; a sample covered by several surfaces (or
/// by two leaves on a shared boundary) is visited once per leaf. Single-threaded: callers
/// split the rows between threads, which keeps each thread's per-sample state small. The
/// result on any sample does not depend on `rows` (see the module doc: a curve piece whose
/// box holds no sample cannot change the winding about a sample).
pub fn for_each_covered_sample(
    scene: &Scene,
    width: u32,
    height: u32,
    samples_per_axis: u32,
    rows: std::ops::Range<usize>,
    visit: impl FnMut(&Leaf, [usize; 2], DVec2),
) {
    assert!(samples_per_axis > 0, "samples_per_axis must be positive");
    let n = samples_per_axis as usize;
    let sh = height as usize * n;
    let grid = Grid {
        n: samples_per_axis,
        sw: width as usize * n,
        sh,
        rows: (rows.start.min(sh), rows.end.min(sh)),
    };
    let mut r = Raster::new(
        Proj::new(scene, width, height),
        grid,
        SIZE_PX,
        FLAT_PX,
        visit,
    );
    for (i, p) in scene.patches.iter().enumerate() {
        r.patch(i, &homogeneous(p));
    }
}

/// One thread's state: the camera, the sample grid, what to do with a covered sample, and
/// the current patch, leaf and scratch polygon.
struct Raster<V> {
    proj: Proj,
    grid: Grid,
    /// Leaf tolerances (pixels): box size and control-net flatness.
    size_px: f64,
    flat_px: f64,
    visit: V,
    patch: usize,
    leaf_cp: HomNet,
    leaf_uv: [f64; 4],
    leaf_clipped: bool,
    poly: Vec<DVec2>,
}

impl<V: FnMut(&Leaf, [usize; 2], DVec2)> Raster<V> {
    fn new(proj: Proj, grid: Grid, size_px: f64, flat_px: f64, visit: V) -> Raster<V> {
        Raster {
            proj,
            grid,
            size_px,
            flat_px,
            visit,
            patch: 0,
            leaf_cp: [DVec4::ZERO; 16],
            leaf_uv: [0.0; 4],
            leaf_clipped: false,
            poly: Vec::new(),
        }
    }

    /// Traverses patch number `index` (its homogeneous net).
    fn patch(&mut self, index: usize, cp: &HomNet) {
        self.patch = index;
        self.cell(cp, [0.0, 1.0, 0.0, 1.0], 0);
    }

    /// Culls, splits or fills one cell (a sub-patch, as its own Bezier control net, covering
    /// parameters `uv` = u0, u1, v0, v1 of its patch).
    fn cell(&mut self, h: &HomNet, uv: [f64; 4], depth: u32) {
        let cp = &h.map(euclidean);
        let (zmin, zmax) = cp
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| {
                (a.min(p.z), b.max(p.z))
            });
        if zmax < self.proj.near || zmin > self.proj.far {
            return;
        }
        if !(self.proj.visible_z(zmin) && self.proj.visible_z(zmax)) {
            return self.straddling(h, cp, uv, depth);
        }
        let q = cp.map(|p| self.proj.apply(p));
        let bbox = bounds(&q);
        if self.grid.range(bbox).is_none() {
            return;
        }
        let size = (bbox.1 - bbox.0).max_element();
        if depth >= MAX_DEPTH || (size < self.size_px && net_flatness(&q) < self.flat_px) {
            return self.leaf(h, uv);
        }
        self.split(h, uv, depth, net_extent_u(&q) >= net_extent_v(&q));
    }

    /// Halves a cell along u (else v) and goes on with both halves.
    fn split(&mut self, cp: &HomNet, uv: [f64; 4], depth: u32, along_u: bool) {
        let [u0, u1, v0, v1] = uv;
        let (a, b, ua, ub) = if along_u {
            let (a, b) = split_u(cp);
            let um = (u0 + u1) * 0.5;
            (a, b, [u0, um, v0, v1], [um, u1, v0, v1])
        } else {
            let (a, b) = split_v(cp);
            let vm = (v0 + v1) * 0.5;
            (a, b, [u0, u1, v0, vm], [u0, u1, vm, v1])
        };
        self.cell(&a, ua, depth + 1);
        self.cell(&b, ub, depth + 1);
    }

    /// A cell partly outside the near..far slab: split until its visible bound is tiny,
    /// then fill its corner quad clipped to the slab. `cp` is `h` made Euclidean.
    fn straddling(&mut self, h: &HomNet, cp: &[DVec3; 16], uv: [f64; 4], depth: u32) {
        let Some(bbox) = self.clipped_bounds(cp) else {
            return;
        };
        if self.grid.range(bbox).is_none() {
            return;
        }
        if depth >= MAX_DEPTH || (bbox.1 - bbox.0).max_element() < CLIP_PX {
            let quad = [cp[0], cp[3], cp[15], cp[12]];
            let clipped = clip_z(&clip_z(&quad, self.proj.near, true), self.proj.far, false);
            self.poly.clear();
            self.poly
                .extend(clipped.iter().map(|&p| self.proj.apply(p)));
            self.set_leaf(h, uv, true);
            return self.fill();
        }
        // Alternate directions by depth: the parameter extent is what must shrink here.
        self.split(h, uv, depth, depth.is_multiple_of(2));
    }

    /// Screen bound of the control hull clipped to the z slab: the hull's clipped vertices
    /// are control points inside the slab or points where hull edges (segments between
    /// control points) cross a clipping plane. None when nothing is inside.
    fn clipped_bounds(&self, cp: &[DVec3; 16]) -> Option<(DVec2, DVec2)> {
        let mut pts: Vec<DVec2> = Vec::with_capacity(64);
        for (i, &a) in cp.iter().enumerate() {
            if self.proj.visible_z(a.z) {
                pts.push(self.proj.apply(a));
            }
            for &b in &cp[i + 1..] {
                for plane in [self.proj.near, self.proj.far] {
                    if (a.z - plane) * (b.z - plane) < 0.0 {
                        pts.push(self.proj.apply(cut_at_z(a, b, plane)));
                    }
                }
            }
        }
        (!pts.is_empty()).then(|| bounds(&pts))
    }

    /// Fills a leaf cell: its boundary loop (bottom, right, top, left curves, refined near
    /// samples) is the polygon.
    fn leaf(&mut self, cp: &HomNet, uv: [f64; 4]) {
        self.set_leaf(cp, uv, false);
        self.poly.clear();
        let c = |i: [usize; 4]| i.map(|k| cp[k]);
        self.edge(c([0, 1, 2, 3]), 0);
        self.edge(c([3, 7, 11, 15]), 0);
        self.edge(c([15, 14, 13, 12]), 0);
        self.edge(c([12, 8, 4, 0]), 0);
        self.fill();
    }

    /// Appends a boundary curve to the polygon (all its points but the last). A piece is
    /// halved while a sample lies in its projected hull's box and it is not yet straight:
    /// a rule that sees only the piece, so neighbours sharing it build the same polyline.
    fn edge(&mut self, c: [DVec4; 4], depth: u32) {
        let q = c.map(|p| self.proj.apply(euclidean(p)));
        let refine = depth < EDGE_MAX_DEPTH
            && self.grid.range(bounds(&q)).is_some()
            && curve_deviation(&q) > EDGE_EPS_PX;
        if refine {
            let (a, b) = split_curve(c);
            self.edge(a, depth + 1);
            self.edge(b, depth + 1);
        } else {
            self.poly.push(q[0]);
        }
    }

    fn set_leaf(&mut self, cp: &HomNet, uv: [f64; 4], clipped: bool) {
        self.leaf_cp = *cp;
        self.leaf_uv = uv;
        self.leaf_clipped = clipped;
    }

    /// Visits the samples inside `self.poly` (non-zero winding, boundary inclusive).
    fn fill(&mut self) {
        if self.poly.len() < 3 {
            return;
        }
        let Some((xs, ys)) = self.grid.range(bounds(&self.poly)) else {
            return;
        };
        let leaf = Leaf {
            patch: self.patch,
            uv: self.leaf_uv,
            cp: &self.leaf_cp,
            clipped: self.leaf_clipped,
        };
        for ky in ys {
            for kx in xs.clone() {
                let s = self.grid.pos(kx, ky);
                if covers(&self.poly, s) {
                    (self.visit)(&leaf, [kx, ky], s);
                }
            }
        }
    }
}

/// Largest distance of a projected control point from the bilinear map of the projected
/// corners at its Greville parameters (i/3, j/3). For an affine view this bounds how far the
/// surface strays from its bilinear approximation; it is zero for a uniformly parametrised
/// flat quad.
fn net_flatness(q: &[DVec2; 16]) -> f64 {
    let (c00, c10, c01, c11) = (q[0], q[3], q[12], q[15]);
    let mut worst: f64 = 0.0;
    for j in 0..4 {
        let t = j as f64 / 3.0;
        for i in 0..4 {
            let s = i as f64 / 3.0;
            let bil = (c00 * (1.0 - s) + c10 * s) * (1.0 - t) + (c01 * (1.0 - s) + c11 * s) * t;
            worst = worst.max(q[4 * j + i].distance(bil));
        }
    }
    worst
}

/// Longest projected control polygon along u (over the four rows).
fn net_extent_u(q: &[DVec2; 16]) -> f64 {
    (0..4)
        .map(|r| {
            (0..3)
                .map(|i| q[4 * r + i].distance(q[4 * r + i + 1]))
                .sum::<f64>()
        })
        .fold(0.0, f64::max)
}

/// Longest projected control polygon along v (over the four columns).
fn net_extent_v(q: &[DVec2; 16]) -> f64 {
    (0..4)
        .map(|c| {
            (0..3)
                .map(|j| q[4 * j + c].distance(q[4 * j + c + 4]))
                .sum::<f64>()
        })
        .fold(0.0, f64::max)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{Camera, Patch, PatchNet, PatchSource, builtin_teapot};

    /// A scene of bilinear-flat quads (corners c00, c10, c01, c11, uniformly parametrised).
    fn quad_scene(quads: &[[DVec3; 4]], fov_deg: f64, near: f64, far: f64) -> Scene {
        let patches = quads
            .iter()
            .enumerate()
            .map(|(i, c)| {
                let cp = std::array::from_fn(|k| {
                    let (s, t) = ((k % 4) as f64 / 3.0, (k / 4) as f64 / 3.0);
                    (c[0] * (1.0 - s) + c[1] * s) * (1.0 - t) + (c[2] * (1.0 - s) + c[3] * s) * t
                });
                let source = PatchSource {
                    file: "test".into(),
                    line: 0,
                    index: i as u32,
                };
                Patch::new(cp, Patch::POLYNOMIAL, source)
            })
            .collect();
        Scene {
            camera: Camera {
                fov_deg,
                near,
                far,
                ..Camera::default()
            },
            patches,
            ..Scene::default()
        }
    }

    /// Analytic coverage of a planar convex quad: clip it to the slab in 3D, project (a
    /// plane's projection is exact), count samples inside the convex polygon.
    fn analytic(scene: &Scene, quad: [DVec3; 4], w: u32, h: u32, n: u32) -> Vec<f32> {
        let loop3 = [quad[0], quad[1], quad[3], quad[2]];
        let c = &scene.camera;
        let clipped = clip_z(&clip_z(&loop3, c.near, true), c.far, false);
        let poly: Vec<DVec2> = clipped
            .iter()
            .map(|&p| project(scene, w, h, p).unwrap())
            .collect();
        let grid = Grid {
            n,
            sw: (w * n) as usize,
            sh: (h * n) as usize,
            rows: (0, (h * n) as usize),
        };
        let inside = |s: DVec2| {
            let sides: Vec<f64> = (0..poly.len())
                .map(|k| (poly[(k + 1) % poly.len()] - poly[k]).perp_dot(s - poly[k]))
                .collect();
            sides.iter().all(|&d| d >= 0.0) || sides.iter().all(|&d| d <= 0.0)
        };
        let n = n as usize;
        (0..h as usize)
            .flat_map(|y| (0..w as usize).map(move |x| (x, y)))
            .map(|(x, y)| {
                let hits = (y * n..(y + 1) * n)
                    .flat_map(|ky| (x * n..(x + 1) * n).map(move |kx| (kx, ky)))
                    .filter(|&(kx, ky)| inside(grid.pos(kx, ky)))
                    .count();
                hits as f32 / (n * n) as f32
            })
            .collect()
    }

    /// Sum over pixels of |a - b|, in samples.
    fn sample_mismatch(a: &[f32], b: &[f32], n: u32) -> f64 {
        let per = (n * n) as f64;
        a.iter()
            .zip(b)
            .map(|(x, y)| (x - y).abs() as f64 * per)
            .sum()
    }

    #[test]
    fn projection_convention() {
        let s = quad_scene(&[], 40.0, 1e-3, 1e3);
        let c = project(&s, 80, 60, DVec3::new(0.0, 0.0, 5.0)).unwrap();
        assert_eq!(c, DVec2::new(40.0, 30.0));
        // The fov spans the shorter side (60 px): a point at the half angle hits its edge.
        let t = 20f64.to_radians().tan();
        let p = project(&s, 80, 60, DVec3::new(0.0, 5.0 * t, 5.0)).unwrap();
        assert!((p.y - 0.0).abs() < 1e-12 && p.x == 40.0, "{p}");
        let p = project(&s, 60, 80, DVec3::new(5.0 * t, 0.0, 5.0)).unwrap();
        assert!((p.x - 60.0).abs() < 1e-12, "{p}");
        assert!(project(&s, 80, 60, DVec3::new(1.0, 1.0, 0.0)).is_none());
    }

    /// A flat square facing the camera (rotated in the image plane, off centre): every pixel
    /// matches the analytic sample count, and the area matches the projected area.
    #[test]
    fn flat_square_is_exact() {
        let (w, h, n) = (80, 60, 8);
        let (a, b) = (17f64.to_radians().cos(), 17f64.to_radians().sin());
        let z = 4.0;
        let half = 0.6;
        let centre = DVec3::new(0.137, -0.089, z);
        let corner = |s: f64, t: f64| centre + DVec3::new(a * s - b * t, b * s + a * t, 0.0) * half;
        let quad = [
            corner(-1.0, -1.0),
            corner(1.0, -1.0),
            corner(-1.0, 1.0),
            corner(1.0, 1.0),
        ];
        let s = quad_scene(&[quad], 40.0, 0.01, 100.0);
        let cov = coverage(&s, w, h, n);
        let exact = analytic(&s, quad, w, h, n);
        assert!(sample_mismatch(&cov.frac, &exact, n) <= 1.0);
        let f = 30.0 / 20f64.to_radians().tan();
        let side = f * 2.0 * half / z;
        let area = cov.area();
        assert!(
            (area - side * side).abs() < 0.01 * side * side,
            "area {area} vs analytic {}",
            side * side
        );
    }

    /// A tilted square cut by the near plane: the clipped part matches the analytic
    /// polygon.
    #[test]
    fn near_plane_clips_exactly() {
        let (w, h, n) = (64, 48, 4);
        let (c, u, v) = (
            DVec3::new(0.1, 0.05, 2.0),
            DVec3::new(1.5, 0.0, 0.0),
            DVec3::new(0.0, 0.6, 1.8),
        );
        let quad = [c - u - v, c + u - v, c - u + v, c + u + v];
        let s = quad_scene(&[quad], 60.0, 1.0, 3.5);
        let cov = coverage(&s, w, h, n);
        let exact = analytic(&s, quad, w, h, n);
        let total: f64 = exact.iter().map(|&f| f as f64).sum();
        assert!(total > 100.0, "degenerate test: {total}");
        let miss = sample_mismatch(&cov.frac, &exact, n);
        assert!(miss <= 2.0, "{miss} samples differ");
    }

    /// A flat patch with curved edges, facing the camera (one layer, no folds), and the same
    /// patch cut by de Casteljau into pieces that meet at T-junctions: the pieces must cover
    /// exactly the same samples (no cracks along the cuts, no overlap beyond the patch).
    #[test]
    fn t_junctions_leave_no_cracks() {
        let bump = [0.0, 0.35, 0.35, 0.0];
        let cp: [DVec3; 16] = std::array::from_fn(|k| {
            let (i, j) = (k % 4, k / 4);
            let (x, y) = (i as f64 / 1.5 - 1.0, j as f64 / 1.5 - 1.0);
            // Bulge every edge outward, more along x than along y, plus a shear.
            let x = x * (1.0 + bump[j]) + 0.2 * y * y;
            let y = y * (1.0 + 0.6 * bump[i]);
            DVec3::new(0.9 * x + 0.05, 0.9 * y - 0.03, 4.0)
        });
        let (l, r) = split_u(&cp.map(|p| p.extend(1.0)));
        let (lb, lt) = split_v(&l);
        let (lbl, lbr) = split_u(&lb);
        let (lbl_b, lbl_t) = split_v(&lbl);
        let pieces = [lbl_b, lbl_t, lbr, lt, r].map(|h| h.map(euclidean));
        let scene = |cps: &[[DVec3; 16]]| Scene {
            patches: cps
                .iter()
                .map(|cp| Patch {
                    net: PatchNet::new(*cp, Patch::POLYNOMIAL),
                    ..quad_scene(&[[DVec3::Z; 4]], 40.0, 0.01, 100.0).patches[0].clone()
                })
                .collect(),
            ..quad_scene(&[], 40.0, 0.01, 100.0)
        };
        let (w, h, n) = (64, 48, 4);
        let whole = coverage(&scene(&[cp]), w, h, n);
        assert!(whole.area() > 1000.0, "{}", whole.area());
        // Huge leaves (no size or flatness limit): only the sample-driven refinement of the
        // boundary curves keeps the result exact and crack-free.
        for cps in [&[cp][..], &pieces[..]] {
            let coarse = coverage_with(&scene(cps), w, h, n, f64::INFINITY, f64::INFINITY);
            let miss = sample_mismatch(&whole.frac, &coarse.frac, n);
            assert_eq!(miss, 0.0, "{} pieces: {miss} samples differ", cps.len());
        }
        let cut = coverage(&scene(&pieces), w, h, n);
        assert_eq!(sample_mismatch(&whole.frac, &cut.frac, n), 0.0);
    }

    #[test]
    fn teapot_coverage_plausible() {
        let (w, h) = (80, 60);
        let cov = coverage(&builtin_teapot(), w, h, 3);
        let frac = cov.area() / (w * h) as f64;
        assert!((0.1..0.6).contains(&frac), "covered fraction {frac}");
        assert_eq!(cov.at(w / 2, h / 2), 1.0, "centre");
        for (x, y) in [(0, 0), (w - 1, 0), (0, h - 1), (w - 1, h - 1)] {
            assert_eq!(cov.at(x, y), 0.0, "corner {x},{y}");
        }
        // The ground truth has no holes: the 3x3-sample result is solid wherever a finer one
        // says the neighbourhood is.
        let fine = coverage(&builtin_teapot(), w, h, 6);
        assert!(fine.interior().iter().filter(|&&b| b).count() > 200);
        assert_eq!(pinholes(&cov.frac, &fine), 0);
    }

    #[test]
    fn pinholes_counts_interior_gaps() {
        let mut full = Coverage {
            width: 5,
            height: 5,
            frac: vec![1.0; 25],
        };
        assert_eq!(full.interior().iter().filter(|&&b| b).count(), 9);
        let mut alpha = vec![1.0; 25];
        alpha[12] = 0.9;
        alpha[0] = 0.0; // not interior: ignored
        assert_eq!(pinholes(&alpha, &full), 1);
        full.frac[0] = 0.5;
        assert_eq!(full.interior().iter().filter(|&&b| b).count(), 8);
    }

    /// Times `coverage` on killeroo.rib at 200x130 with 4x4 samples. Run with
    /// `cargo test -p reyes --release --lib reference::exact::tests::killeroo_timing --
    /// --ignored --nocapture`.
    #[test]
    #[ignore = "timing, not a check; needs the shared data"]
    fn killeroo_timing() {
        let path = crate::shared_data_dir().join("rib/killeroo.rib");
        let scene = crate::scene::load(&path).unwrap();
        let t = std::time::Instant::now();
        let cov = coverage(&scene, 200, 130, 4);
        let dt = t.elapsed();
        let area = cov.area();
        eprintln!(
            "killeroo 200x130 4x4: {dt:?}, covered {area:.1} px^2 ({:.1}%)",
            100.0 * area / (200.0 * 130.0)
        );
        assert!(area > 0.05 * 200.0 * 130.0);
    }
}
