//! The reference render: what the renderer's image should converge to, computed from the exact
//! f64 surfaces with many samples per pixel.
//!
//! Coverage comes from `reference::exact` (recursive de Casteljau to cells under 0.25 px,
//! boundaries refined to 1e-7 px, watertight across shared edges) on a regular grid of
//! `n` x `n` samples per pixel. At every sample a covering leaf cell is found for, the surface
//! point under the sample is solved for by Newton's method on the original patch (projection
//! of the exact surface equal to the sample position), evaluated exactly (`surface::eval`),
//! depth-tested by camera-space z against the other surfaces there, culled when seen from its
//! back on a `Sides 1` patch, and shaded in f64 (`surface::shade`, with the patch's `"Cs"`
//! where it has one), clamped to [0, 1] as the renderer's colour encoding does. Opacity is not
//! modelled: every surface is opaque here. A pixel is the box-filtered mean of its covered samples
//! (straight colour, alpha = covered fraction), as the renderer's resolve pass does.
//!
//! Its own accuracy: coverage is exact at the sample points; the sample's surface point is
//! found to 1e-6 px where Newton converges (the count where it does not, e.g. exactly on a
//! silhouette fold, is reported: those samples use the best iterate, which lies within the
//! 0.25 px cell); shading is then exact. What remains is the n x n point-sampling of the box
//! filter: on an edge pixel the covered fraction is off by at most about 1/(2n) (axis-aligned
//! edge), 1/16 at the default n = 8, and smaller for slanted edges.

use super::parallel::in_chunks;
use super::surface::{back_facing, eval, scene_lights, shade};
use glam::{DVec2, DVec3};
use reyes::image::FrameImage;
use reyes::progress::Progress;
use reyes::reference::exact::{Coverage, Leaf, for_each_covered_sample};
use reyes::scene::Scene;

/// Samples per pixel axis of the reference unless told otherwise (64 per pixel).
pub const DEFAULT_SAMPLES_PER_AXIS: u32 = 8;

/// Pixel rows a thread renders at a time.
const BAND_ROWS: usize = 4;
/// Newton stops below this residual (pixels) or after this many steps.
const NEWTON_TOL_PX: f64 = 1.0e-6;
const NEWTON_STEPS: usize = 12;

/// The reference render of a frame ([`render_reference`]) and what it cost.
pub struct ReferenceImage {
    /// Straight linear colour, alpha = covered fraction, nearest camera-space depth.
    pub image: FrameImage,
    /// The same covered fractions, for `reference::pinholes`.
    pub coverage: Coverage,
    /// Samples per pixel along each axis (`n`; `n * n` per pixel).
    pub samples_per_axis: u32,
    /// Covered samples whose surface point Newton did not pin down to `NEWTON_TOL_PX` (1e-6 px).
    pub unconverged_samples: u64,
    /// Samples a surface covers.
    pub covered_samples: u64,
    /// Host time of the render, milliseconds.
    pub cpu_ms: f64,
}

/// Nearest surface point found so far at one sample.
#[derive(Clone, Copy)]
struct Hit {
    z: f64,
    patch: u32,
    u: f64,
    v: f64,
    converged: bool,
}

const NO_HIT: Hit = Hit {
    z: f64::INFINITY,
    patch: u32::MAX,
    u: 0.0,
    v: 0.0,
    converged: true,
};

/// Renders the reference of `scene` at `width` x `height` with `samples_per_axis`^2 samples
/// per pixel, on all cores (bands of rows handed out one at a time); `progress` advances by
/// each band's pixel rows as it is done (`height` in all).
pub fn render_reference(
    scene: &Scene,
    width: u32,
    height: u32,
    samples_per_axis: u32,
    progress: &dyn Progress,
) -> ReferenceImage {
    let start = std::time::Instant::now();
    let (w, h, n) = (width as usize, height as usize, samples_per_axis as usize);
    let lights = scene_lights(scene);
    let bands = in_chunks(h, BAND_ROWS, |rows| {
        let b = band(scene, &lights, width, height, n, rows.start, rows.end);
        progress.advance(rows.len() as u64);
        b
    });
    let mut rgba = vec![[0f32; 4]; w * h];
    let mut depth = vec![3.0e38f32; w * h];
    let (mut unconverged, mut covered) = (0, 0);
    for (_, (y0, c, d, un, cov)) in bands {
        rgba[y0 * w..y0 * w + c.len()].copy_from_slice(&c);
        depth[y0 * w..y0 * w + d.len()].copy_from_slice(&d);
        unconverged += un;
        covered += cov;
    }
    let frac = rgba.iter().map(|p| p[3]).collect();
    ReferenceImage {
        image: FrameImage {
            width,
            height,
            rgba,
            depth,
        },
        coverage: Coverage {
            width,
            height,
            frac,
        },
        samples_per_axis,
        unconverged_samples: unconverged,
        covered_samples: covered,
        cpu_ms: start.elapsed().as_secs_f64() * 1e3,
    }
}

/// Pixel rows `y0..y1`: (y0, pixels, depths, unconverged samples, covered samples).
fn band(
    scene: &Scene,
    lights: &[reyes::scene::Light],
    width: u32,
    height: u32,
    n: usize,
    y0: usize,
    y1: usize,
) -> (usize, Vec<[f32; 4]>, Vec<f32>, u64, u64) {
    let sw = width as usize * n;
    let first = y0 * n;
    let mut hits = vec![NO_HIT; (y1 - y0) * n * sw];
    let cam = Camera::new(scene, width, height);
    for_each_covered_sample(
        scene,
        width,
        height,
        n as u32,
        first..y1 * n,
        |leaf, k, s| {
            let Some(hit) = locate(scene, &cam, leaf, s) else {
                return;
            };
            let slot = &mut hits[(k[1] - first) * sw + k[0]];
            if hit.z < slot.z {
                *slot = hit;
            }
        },
    );
    let (mut unconverged, mut covered) = (0, 0);
    let mut pixels = Vec::with_capacity((y1 - y0) * width as usize);
    let mut depths = Vec::with_capacity(pixels.capacity());
    for py in 0..y1 - y0 {
        for px in 0..width as usize {
            let (mut sum, mut count, mut zmin) = (DVec3::ZERO, 0u32, f64::INFINITY);
            for sy in 0..n {
                for sx in 0..n {
                    let hit = hits[(py * n + sy) * sw + px * n + sx];
                    if hit.patch == u32::MAX {
                        continue;
                    }
                    let patch = &scene.patches[hit.patch as usize];
                    let e = eval(patch, hit.u, hit.v);
                    let mut m =
                        std::borrow::Cow::Borrowed(&scene.materials[patch.material as usize]);
                    if let Some(cs) = patch.primvars.as_ref().and_then(|p| p.cs.as_ref()) {
                        m.to_mut().color = cs.eval(hit.u, hit.v);
                    }
                    sum += shade(e.p, e.n, &m, lights).clamp(DVec3::ZERO, DVec3::ONE);
                    count += 1;
                    zmin = zmin.min(hit.z);
                    unconverged += !hit.converged as u64;
                }
            }
            covered += count as u64;
            let c = if count > 0 {
                sum / count as f64
            } else {
                DVec3::ZERO
            };
            pixels.push([
                c.x as f32,
                c.y as f32,
                c.z as f32,
                count as f32 / (n * n) as f32,
            ]);
            depths.push(if count > 0 { zmin as f32 } else { 3.0e38 });
        }
    }
    (y0, pixels, depths, unconverged, covered)
}

/// The renderer's pinhole camera in f64 (the convention of `reference::project`), with the
/// derivative of the projection.
struct Camera {
    half: DVec2,
    f: f64,
    near: f64,
    far: f64,
}

impl Camera {
    fn new(scene: &Scene, width: u32, height: u32) -> Camera {
        Camera {
            half: DVec2::new(width as f64, height as f64) / 2.0,
            f: width.min(height) as f64 / 2.0 / (scene.camera.fov_deg.to_radians() / 2.0).tan(),
            near: scene.camera.near,
            far: scene.camera.far,
        }
    }

    fn project(&self, p: DVec3) -> DVec2 {
        self.half + DVec2::new(self.f * p.x / p.z, -self.f * p.y / p.z)
    }

    /// Screen-space change of the projection along camera-space direction `d` at `p`.
    fn project_dir(&self, p: DVec3, d: DVec3) -> DVec2 {
        let iz = 1.0 / p.z;
        DVec2::new(
            self.f * (d.x - p.x * iz * d.z) * iz,
            -self.f * (d.y - p.y * iz * d.z) * iz,
        )
    }
}

/// The surface point of `leaf` under sample position `s`, or None where it is clipped away or
/// culled as back-facing.
fn locate(scene: &Scene, cam: &Camera, leaf: &Leaf, s: DVec2) -> Option<Hit> {
    let patch = &scene.patches[leaf.patch];
    let [u0, u1, v0, v1] = leaf.uv;
    let (du, dv) = (u1 - u0, v1 - v0);
    let (mut a, mut b) = (0.5, 0.5);
    let mut converged = false;
    for _ in 0..NEWTON_STEPS {
        let e = eval(patch, u0 + a * du, v0 + b * dv);
        if !(e.p.z > 0.0) {
            break;
        }
        let r = cam.project(e.p) - s;
        if r.length() < NEWTON_TOL_PX {
            converged = true;
            break;
        }
        let ja = cam.project_dir(e.p, e.dpdu * du);
        let jb = cam.project_dir(e.p, e.dpdv * dv);
        let det = ja.perp_dot(jb);
        if !(det.abs() > 1e-300) {
            break;
        }
        // Solve [ja jb] (da, db) = -r by Cramer's rule; stay near the cell.
        let da = -r.perp_dot(jb) / det;
        let db = -ja.perp_dot(r) / det;
        a = (a + da).clamp(-0.5, 1.5);
        b = (b + db).clamp(-0.5, 1.5);
    }
    if !converged {
        // The sample is covered by this cell, so its surface point lies in it.
        a = a.clamp(0.0, 1.0);
        b = b.clamp(0.0, 1.0);
    }
    let (u, v) = (u0 + a * du, v0 + b * dv);
    let e = eval(patch, u, v);
    if leaf.clipped && !(cam.near <= e.p.z && e.p.z <= cam.far) {
        return None;
    }
    if !patch.two_sided && back_facing(&e) {
        return None;
    }
    Some(Hit {
        z: e.p.z,
        patch: leaf.patch as u32,
        u,
        v,
        converged,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use reyes::progress::NoProgress;
    use reyes::reference::{closed::blob_patches, coverage, project};
    use reyes::scene::builtin_teapot;

    fn blob() -> Scene {
        reyes::scene::load(std::path::Path::new(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../scenes/closed_blob.rib"
        )))
        .unwrap()
    }

    /// Rendering in bands gives exactly the coverage the whole-image traversal gives; the
    /// progress counts every row once.
    #[test]
    fn coverage_matches_the_exact_reference() {
        for s in [builtin_teapot(), blob()] {
            let rows = std::sync::atomic::AtomicU64::new(0);
            let count = |n| {
                rows.fetch_add(n, std::sync::atomic::Ordering::Relaxed);
            };
            let r = render_reference(&s, 48, 36, 4, &count);
            assert_eq!(rows.into_inner(), 36);
            let c = coverage(&s, 48, 36, 4);
            assert_eq!(r.coverage, c);
            assert!(r.covered_samples > 1000);
            // Almost every sample's surface point is pinned down by Newton.
            assert!(
                r.unconverged_samples * 1000 < r.covered_samples,
                "{} of {} unconverged",
                r.unconverged_samples,
                r.covered_samples
            );
        }
    }

    /// Depth is the nearest exact surface point: the blob's visible depth at the image
    /// centre is the front of the blob, never its back.
    #[test]
    fn nearest_surface_wins_and_shading_is_exact_there() {
        let s = blob();
        let (w, h) = (40, 30);
        // One sample per pixel, at its centre: the pixel is that sample's shading.
        let r = render_reference(&s, w, h, 1, &NoProgress);
        // Centre pixel: nearer than the blob's centre (z = 6).
        let c = (h / 2 * w + w / 2) as usize;
        assert!(r.image.depth[c] < 6.0 - 0.5, "{}", r.image.depth[c]);
        assert_eq!(r.image.rgba[c][3], 1.0);
        // Brute force: the nearest of a fine parameter grid's points that project within
        // 0.05 px of the pixel centre.
        let lights = scene_lights(&s);
        let m = &s.materials[0];
        let centre = DVec2::new(w as f64 / 2.0 + 0.5, h as f64 / 2.0 + 0.5);
        let mut best: Option<(f64, DVec3)> = None;
        for (i, _) in blob_patches().iter().enumerate() {
            let p = &s.patches[i];
            for k in 0..=400 * 400 {
                let (u, v) = ((k % 401) as f64 / 400.0, (k / 401) as f64 / 400.0);
                let e = eval(p, u, v);
                let q = project(&s, w, h, e.p).unwrap();
                if q.distance(centre) < 0.05 && best.is_none_or(|b| e.p.z < b.0) {
                    best = Some((e.p.z, shade(e.p, e.n, m, &lights)));
                }
            }
        }
        let (z, colour) = best.unwrap();
        assert!((r.image.depth[c] as f64 - z).abs() < 0.01, "{z}");
        let got = DVec3::new(
            r.image.rgba[c][0] as f64,
            r.image.rgba[c][1] as f64,
            r.image.rgba[c][2] as f64,
        );
        assert!(
            got.distance(colour.clamp(DVec3::ZERO, DVec3::ONE)) < 0.01,
            "{got} vs {colour}"
        );
    }
}
