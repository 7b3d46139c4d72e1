//! How far the drawn micropolygons are from the exact surface, and how big they are, in
//! pixels.
//!
//! The grids come from the CPU twin of the pipeline (`cpu_render::diced_items` and
//! `stages::dice_shade::dice`), which makes the GPU's decisions and grid points with the same
//! f32 operations (the GPU tests check that the counts match exactly), so these are the GPU's
//! micropolygons without reading them back.
//!
//! What is drawn of a micropolygon is two triangles, (a, b, c) and (a, c, d) of its corners
//! a = (i, j), b = (i+1, j), c = (i+1, j+1), d = (i, j+1), with screen positions interpolated
//! linearly. At seven points of each, the midpoints of its four sides and of the diagonal and
//! the two triangles' centroids (the chord error of an edge peaks at its midpoint), the drawn
//! position is compared with the exact f64 surface of the original patch at the same (u, v),
//! projected. That is a distance at equal parameters, so it also counts error along the
//! surface: an upper bound of the distance to the surface. Only micropolygons that are drawn
//! count: on screen, not culled as back-facing, in front of the near plane.

use super::parallel::in_chunks;
use super::surface::eval;
use glam::DVec2;
use reyes::cpu_render::diced_items;
use reyes::frame::{FrameData, PatchItem};
use reyes::reference::project;
use reyes::scene::Scene;
use reyes::stages::dice_shade::dice;

/// Geometric accuracy of a frame's micropolygons against the exact surfaces, in pixels.
#[derive(Clone, Debug, PartialEq)]
pub struct GeometryStats {
    /// Micropolygons measured (drawn ones, see the module doc).
    pub micropolygons: u64,
    /// Largest screen distance between a drawn point and the exact surface at its (u, v).
    pub err_max_px: f64,
    /// 99th percentile over micropolygons of each one's largest distance.
    pub err_p99_px: f64,
    /// Longest micropolygon side on screen.
    pub edge_max_px: f64,
    /// Mean screen area of a micropolygon (its two triangles).
    pub area_mean_px: f64,
}

/// Points (s, t) inside a micropolygon, in its own parameters.
const POINTS: [(f64, f64); 7] = [
    (0.5, 0.0),
    (1.0, 0.5),
    (0.5, 1.0),
    (0.0, 0.5),
    (0.5, 0.5),
    (2.0 / 3.0, 1.0 / 3.0),
    (1.0 / 3.0, 2.0 / 3.0),
];

/// Measures the micropolygons `data` dices for `scene` (the scene `data` was made from).
pub fn geometry(scene: &Scene, data: &FrameData) -> GeometryStats {
    // Grids crossing the near plane keep camera-space points and are clipped when sampled;
    // the metric measures projected micropolygons, which they do not have.
    let items: Vec<PatchItem> = diced_items(data)
        .into_iter()
        .filter(|i| i.rates & reyes::stages::NEAR_CLIP_GRID == 0)
        .collect();
    let threads = rayon::current_num_threads();
    let parts = in_chunks(items.len(), items.len().div_ceil(threads * 16), |range| {
        let mut part = Part::default();
        for item in &items[range] {
            measure_item(scene, data, item, &mut part);
        }
        part
    });
    let mut errs: Vec<f64> = Vec::new();
    let (mut edge_max, mut area_sum): (f64, f64) = (0.0, 0.0);
    for (_, p) in parts {
        errs.extend(p.errs);
        edge_max = edge_max.max(p.edge_max);
        area_sum += p.area_sum;
    }
    let n = errs.len();
    let err_max = errs.iter().copied().fold(0.0, f64::max);
    let err_p99 = if n == 0 {
        0.0
    } else {
        let k = ((n as f64 * 0.99).ceil() as usize).clamp(1, n) - 1;
        *errs.select_nth_unstable_by(k, f64::total_cmp).1
    };
    GeometryStats {
        micropolygons: n as u64,
        err_max_px: err_max,
        err_p99_px: err_p99,
        edge_max_px: edge_max,
        area_mean_px: if n == 0 { 0.0 } else { area_sum / n as f64 },
    }
}

/// One chunk's results.
#[derive(Default)]
struct Part {
    /// Largest error of each micropolygon.
    errs: Vec<f64>,
    edge_max: f64,
    area_sum: f64,
}

fn measure_item(scene: &Scene, data: &FrameData, item: &PatchItem, part: &mut Part) {
    let f = &data.frame;
    let (nu, nv, grid) = dice(item, data);
    let patch = &scene.patches[item.patch_id as usize];
    let two_sided = patch.two_sided;
    let [u0, u1, v0, v1] = item.uv.map(|x| x as f64);
    let cols = (nu + 1) as usize;
    let (w, h) = (f.width as f64, f.height as f64);
    for j in 0..nv as usize {
        for i in 0..nu as usize {
            let g = |di: usize, dj: usize| grid[(j + dj) * cols + i + di];
            let corners = [g(0, 0), g(1, 0), g(1, 1), g(0, 1)];
            // Back-face culling works on the bit the shader packs with the colour.
            let back = corners.iter().all(|c| c[3].to_bits() & (1 << 30) != 0);
            if !two_sided && back {
                continue;
            }
            let [a, b, c, d] = corners.map(|c| DVec2::new(c[0] as f64, c[1] as f64));
            let lo = a.min(b).min(c.min(d));
            let hi = a.max(b).max(c.max(d));
            if hi.x < 0.0 || hi.y < 0.0 || lo.x > w || lo.y > h {
                continue;
            }
            let mut worst: f64 = 0.0;
            let mut in_front = true;
            for (s, t) in POINTS {
                let drawn = if s >= t {
                    a + (b - a) * s + (c - b) * t
                } else {
                    a + (d - a) * t + (c - d) * s
                };
                let u = u0 + (u1 - u0) * (i as f64 + s) / nu as f64;
                let v = v0 + (v1 - v0) * (j as f64 + t) / nv as f64;
                let p = eval(patch, u, v).p;
                if p.z < scene.camera.near {
                    in_front = false;
                    break;
                }
                let exact = project(scene, f.width, f.height, p).expect("z > 0");
                worst = worst.max(drawn.distance(exact));
            }
            if !in_front {
                continue;
            }
            part.errs.push(worst);
            let sides = [a.distance(b), b.distance(c), c.distance(d), d.distance(a)];
            part.edge_max = sides.iter().copied().fold(part.edge_max, f64::max);
            part.area_sum += ((b - a).perp_dot(c - a).abs() + (c - a).perp_dot(d - a).abs()) / 2.0;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use reyes::frame::RenderOptions;
    use reyes::scene::builtin_teapot;

    fn stats(mp_size: f32, bound_px: Option<f32>) -> GeometryStats {
        let o = RenderOptions {
            width: Some(96),
            height: Some(72),
            mp_size,
            bound_px,
            ..Default::default()
        };
        let s = builtin_teapot();
        geometry(&s, &FrameData::new(&s, &o).unwrap())
    }

    /// Default settings are sub-pixel accurate, and coarser dicing is measured as worse.
    #[test]
    fn error_is_subpixel_by_default_and_grows_with_the_micropolygon_size() {
        let fine = stats(1.0, None);
        assert!(fine.micropolygons > 1000, "{fine:?}");
        assert!(fine.err_max_px < 0.5, "{fine:?}");
        assert!(fine.err_p99_px <= fine.err_max_px);
        // Rates bound the control polygon's length, not each step's: a step of a cubic is at
        // most 3x its control polygon's longest leg per step, so sides reach ~3x mp_size.
        assert!(fine.edge_max_px > 0.5 && fine.edge_max_px < 3.3, "{fine:?}");
        let coarse = stats(4.0, None);
        assert!(coarse.err_max_px > 2.0 * fine.err_max_px, "{coarse:?}");
        assert!(coarse.err_p99_px > 2.0 * fine.err_p99_px, "{coarse:?}");
        assert!(coarse.area_mean_px > 4.0 * fine.area_mean_px, "{coarse:?}");
        assert!(coarse.micropolygons < fine.micropolygons / 4);
    }

    /// A single flat, uniformly parametrised square facing the camera is diced exactly: the
    /// error is rounding only, and the sizes are what the dicing rates say.
    #[test]
    fn flat_square_is_exact() {
        let mut s = builtin_teapot();
        let o = RenderOptions {
            width: Some(64),
            height: Some(64),
            mp_size: 2.0,
            ..Default::default()
        };
        // About 30 px across: split once each way, then diced 8 x 8.
        let focal = FrameData::new(&s, &o).unwrap().frame.focal as f64;
        let half = 1.0;
        let z = 2.0 * half * focal / 30.2;
        s.patches.truncate(1);
        *s.patches[0].cp_mut() = std::array::from_fn(|k| {
            let (x, y) = ((k % 4) as f64 / 3.0, (k / 4) as f64 / 3.0);
            glam::DVec3::new((2.0 * x - 1.0) * half, (2.0 * y - 1.0) * half, z)
        });
        let data = FrameData::new(&s, &o).unwrap();
        let g = geometry(&s, &data);
        assert_eq!(g.micropolygons, 256);
        assert!(g.err_max_px < 1e-3, "{g:?}");
        let side = data.frame.focal as f64 * 2.0 * half / z;
        let n = g.micropolygons as f64;
        assert!((g.area_mean_px * n - side * side).abs() < 1e-3 * side * side);
        let per = side / n.sqrt();
        assert!((g.edge_max_px - per).abs() < 1e-3 * per, "{g:?} {per}");
    }

    /// A one-pixel offset is measured as one pixel: the exact surface is taken from a copy of
    /// the scene sheared so that every point projects exactly 1 px further right
    /// (x += z / f), against the grids diced from the original.
    #[test]
    fn a_known_offset_is_measured() {
        let s = builtin_teapot();
        let o = RenderOptions {
            width: Some(80),
            height: Some(60),
            ..Default::default()
        };
        let data = FrameData::new(&s, &o).unwrap();
        let f = data.frame.focal as f64;
        let mut moved = s.clone();
        for p in &mut moved.patches {
            for c in p.cp_mut() {
                c.x += c.z / f;
            }
        }
        let base = geometry(&s, &data);
        let off = geometry(&moved, &data);
        assert!(base.err_max_px < 0.5);
        let tol = base.err_max_px + 1e-3;
        assert!((off.err_p99_px - 1.0).abs() <= tol, "{off:?} {base:?}");
        assert!((off.err_max_px - 1.0).abs() <= tol, "{off:?} {base:?}");
    }
}
