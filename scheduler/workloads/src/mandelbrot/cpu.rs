//! The CPU side of the Mandelbrot workload: the escape iteration (the WGSL's twin), the
//! brute-force reference image and the Mariani-Silver subdivision (the multi-threaded CPU
//! baseline), both with rayon.

use rayon::prelude::*;

use super::{MandelCfg, MandelImage, MandelParams, MandelRect, MandelResult, MsWork};

/// The escape count of pixel `(px, py)`: iterations of `z <- z² + c` from `z = 0` before
/// `|z|² > 4`, or `max_iterations`. Same operations, same order, as WGSL `ms_dwell`, with WGSL's
/// `fma(a, b, c)` computed fused (`FUSED`) or as `a * b + c` rounded twice.
pub fn dwell<const FUSED: bool>(cfg: &MandelCfg, px: u32, py: u32) -> u32 {
    let fma = |a: f32, b: f32, c: f32| if FUSED { a.mul_add(b, c) } else { a * b + c };
    let cr = fma(px as f32 - cfg.half_w, cfg.scale, cfg.centre_re);
    let ci = fma(cfg.half_h - py as f32, cfg.scale, cfg.centre_im);
    let (mut x, mut y) = (0.0f32, 0.0f32);
    for n in 0..cfg.max_iterations {
        if fma(x, x, y * y) > 4.0 {
            return n;
        }
        let nx = fma(x, x, fma(-y, y, cr));
        y = fma(x + x, y, ci);
        x = nx;
    }
    cfg.max_iterations
}

/// [`dwell`] in the arithmetic `fused` names.
fn dwell_as(fused: bool) -> fn(&MandelCfg, u32, u32) -> u32 {
    if fused { dwell::<true> } else { dwell::<false> }
}

/// Border pixels of a `w × h` rectangle (each once).
fn border_count(w: u32, h: u32) -> u32 {
    match (w, h) {
        (0, _) | (_, 0) => 0,
        (_, 1) => w,
        (1, _) => h,
        _ => 2 * w + 2 * h - 4,
    }
}

/// The `i`-th border pixel: top row, bottom row, left column, right column.
fn border_pixel(r: &MandelRect, i: u32) -> (u32, u32) {
    if r.h == 1 {
        return (r.x + i, r.y);
    }
    if r.w == 1 {
        return (r.x, r.y + i);
    }
    if i < r.w {
        return (r.x + i, r.y);
    }
    if i < 2 * r.w {
        return (r.x + i - r.w, r.y + r.h - 1);
    }
    let j = i - 2 * r.w;
    if j < r.h - 2 {
        (r.x, r.y + 1 + j)
    } else {
        (r.x + r.w - 1, r.y + 1 + j - (r.h - 2))
    }
}

/// The interior's quadrants (the empty ones left out), as `ms_rect` splits them.
fn quadrants(inner: &MandelRect) -> impl Iterator<Item = MandelRect> + '_ {
    let (w0, h0) = (inner.w / 2, inner.h / 2);
    let xs = [(inner.x, w0), (inner.x + w0, inner.w - w0)];
    let ys = [(inner.y, h0), (inner.y + h0, inner.h - h0)];
    ys.into_iter().flat_map(move |(y, h)| {
        xs.into_iter()
            .filter(move |&(_, w)| w > 0 && h > 0)
            .map(move |(x, w)| MandelRect {
                x,
                y,
                w,
                h,
                dwell: 0,
            })
    })
}

impl MandelParams {
    /// The CPU reference: every pixel iterated (rayon over rows).
    pub fn reference(&self) -> MandelImage {
        let (cfg, dwell) = (self.cfg(), dwell_as(self.fused_fma));
        let mut img = vec![0u32; self.width as usize * self.height as usize];
        img.par_chunks_mut(self.width as usize)
            .enumerate()
            .for_each(|(py, row)| {
                for (px, d) in row.iter_mut().enumerate() {
                    *d = dwell(&cfg, px as u32, py as u32);
                }
            });
        MandelImage {
            width: self.width,
            height: self.height,
            dwell: img,
        }
    }

    /// Mariani-Silver on the CPU, the multi-threaded baseline: rayon over tiles, each tile
    /// subdivided exactly as the GPU procedures do (so `work` equals the GPU's counts).
    pub fn mariani_silver(&self) -> MandelResult {
        let cfg = self.cfg();
        let tiles = self.tiles();
        let done: Vec<(Vec<u32>, MsWork)> = tiles
            .par_iter()
            .map(|t| {
                let mut buf = vec![0u32; t.w as usize * t.h as usize];
                let work = ms_tile(&cfg, dwell_as(self.fused_fma), t, &mut buf);
                (buf, work)
            })
            .collect();
        let mut img = vec![0u32; self.width as usize * self.height as usize];
        let mut work = MsWork::default();
        for (t, (buf, w)) in tiles.iter().zip(done) {
            work = work.add(w);
            for (r, src) in buf.chunks(t.w as usize).enumerate() {
                let at = (t.y as usize + r) * self.width as usize + t.x as usize;
                img[at..at + t.w as usize].copy_from_slice(src);
            }
        }
        MandelResult {
            image: MandelImage {
                width: self.width,
                height: self.height,
                dwell: img,
            },
            work,
        }
    }
}

/// One tile's subdivision into `buf` (the tile's own pixels, row-major).
fn ms_tile(
    cfg: &MandelCfg,
    dwell: fn(&MandelCfg, u32, u32) -> u32,
    tile: &MandelRect,
    buf: &mut [u32],
) -> MsWork {
    let mut put = |x: u32, y: u32, d: u32| {
        buf[((y - tile.y) * tile.w + (x - tile.x)) as usize] = d;
    };
    let mut work = MsWork::default();
    let mut stack = vec![*tile];
    while let Some(r) = stack.pop() {
        work.rects += 1;
        let nb = border_count(r.w, r.h);
        let (mut lo, mut hi) = (u32::MAX, 0);
        for i in 0..nb {
            let (x, y) = border_pixel(&r, i);
            let d = dwell(cfg, x, y);
            put(x, y, d);
            lo = lo.min(d);
            hi = hi.max(d);
        }
        work.computed_pixels += nb as u64;
        if r.w <= 2 || r.h <= 2 {
            continue;
        }
        let inner = MandelRect {
            x: r.x + 1,
            y: r.y + 1,
            w: r.w - 2,
            h: r.h - 2,
            dwell: lo,
        };
        let area = inner.w as u64 * inner.h as u64;
        if lo == hi {
            work.fills += 1;
            work.filled_pixels += area;
            for y in inner.y..inner.y + inner.h {
                for x in inner.x..inner.x + inner.w {
                    put(x, y, lo);
                }
            }
        } else if r.w.min(r.h) <= cfg.min_side {
            work.pixel_rects += 1;
            work.computed_pixels += area;
            for y in inner.y..inner.y + inner.h {
                for x in inner.x..inner.x + inner.w {
                    put(x, y, dwell(cfg, x, y));
                }
            }
        } else {
            stack.extend(quadrants(&inner));
        }
    }
    work
}

#[cfg(test)]
mod tests {
    use super::*;

    fn small(w: u32, h: u32) -> MandelParams {
        MandelParams {
            width: w,
            height: h,
            max_iterations: 256,
            tile: 32,
            min_side: 6,
            ..MandelParams::whole_set(w)
        }
    }

    #[test]
    fn borders_visit_each_border_pixel_once() {
        for (w, h) in [(1, 1), (1, 5), (5, 1), (2, 2), (2, 7), (7, 3), (9, 9)] {
            let r = MandelRect {
                x: 3,
                y: 4,
                w,
                h,
                dwell: 0,
            };
            let mut seen: Vec<_> = (0..border_count(w, h))
                .map(|i| border_pixel(&r, i))
                .collect();
            seen.sort();
            seen.dedup();
            let expect = (0..h)
                .flat_map(|y| (0..w).map(move |x| (x, y)))
                .filter(|&(x, y)| x == 0 || y == 0 || x == w - 1 || y == h - 1)
                .count();
            assert_eq!(seen.len(), expect, "{w}x{h}");
            assert_eq!(border_count(w, h) as usize, expect, "{w}x{h}");
            assert!(
                seen.iter()
                    .all(|&(x, y)| x >= 3 && y >= 4 && x < 3 + w && y < 4 + h)
            );
        }
    }

    #[test]
    fn mariani_silver_equals_brute_force_on_the_cpu_in_both_arithmetics() {
        for p in [
            small(200, 150),
            small(97, 131),
            MandelParams::whole_set(256),
            MandelParams::seahorse(128),
        ]
        .into_iter()
        .flat_map(|p| {
            [
                p.clone(),
                MandelParams {
                    fused_fma: false,
                    ..p
                },
            ]
        }) {
            let ms = p.mariani_silver();
            let bf = p.reference();
            assert_eq!(ms.image.differing_pixels(&bf), 0, "{}", p.describe());
            let w = ms.work;
            assert_eq!(
                w.filled_pixels + w.computed_pixels,
                p.width as u64 * p.height as u64
            );
            assert!(w.fills > 0 && w.pixel_rects > 0 && w.rects > p.tiles().len() as u64);
        }
    }

    #[test]
    fn the_two_arithmetics_give_different_images() {
        let fused = small(100, 70);
        let unfused = MandelParams {
            fused_fma: false,
            ..fused.clone()
        };
        let d = fused.reference().differing_pixels(&unfused.reference());
        assert!(d > 0 && d < 100, "{d}");
    }

    #[test]
    fn every_pixel_is_written_once_whatever_the_tiling() {
        // min_side 3 and odd tiles: thin interiors, one-pixel quadrants and clipped tiles.
        let p = MandelParams {
            min_side: 3,
            tile: 37,
            ..small(101, 75)
        };
        let w = p.mariani_silver().work;
        assert_eq!(w.filled_pixels + w.computed_pixels, 101 * 75);
    }
}
