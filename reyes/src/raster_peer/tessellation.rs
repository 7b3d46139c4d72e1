//! The raster peer's tessellation stage on the host: the structs shared with
//! tessellate.wgsl and raster_resolve.wgsl (layouts checked against naga), and the CPU twins of
//! its rate ([`grid_rate`], [`edge_param`]) and of its grid points ([`tessellate_cpu`]).

use crate::frame::{FrameData, FrameUniforms, root_item};
use crate::scene::Patch;
use crate::stages;
use bytemuck::{Pod, Zeroable};
use glam::{Vec2, Vec3};

/// Most segments per grid side: the hardware tessellator's maximum level (OpenGL's
/// `GL_MAX_TESS_GEN_LEVEL` is at least 64; Direct3D 11's is 64).
pub const MAX_RATE: u32 = 64;

/// The draw's targets and vertex live with the pipelines that use them (`gpu::raster`).
pub use crate::gpu::raster::{COLOR_FORMAT, DEPTH_FORMAT, RasterVertex};

/// Patches the peer accepts: each grid has at most 65 x 65 points, and the GPU counts the
/// frame's points in 32 bits.
pub const MAX_PATCHES: usize = 1_000_000;

/// `TessParams` in tessellate.wgsl.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct TessParams {
    /// Patches in the frame (threads of `tess_rates`).
    pub patches: u32,
    /// Threads per row of `tess_rates`'s 2D dispatch (one thread per patch).
    pub row: u32,
    /// Vertices the vertex buffer holds.
    pub vertex_capacity: u32,
    /// Quads the index buffer holds (6 indices each).
    pub quad_capacity: u32,
    /// Most segments per grid side ([`MAX_RATE`]).
    pub max_rate: u32,
    /// Tiles (64 grid points and quads of one patch) the tile list holds.
    pub tile_capacity: u32,
    /// Padding to a multiple of 16 bytes.
    pub pad: [u32; 2],
}

/// `RasterResolveParams` in raster_resolve.wgsl.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct RasterResolveParams {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Samples of the depth target.
    pub samples: u32,
    /// Threads per row of workgroups.
    pub row: u32,
    /// The near distance (depth = near / z).
    pub near: f32,
    /// Padding to a multiple of 16 bytes.
    pub pad: [u32; 3],
}

/// Words of the tessellation counters (`tess_counts` in tessellate.wgsl): the counts, then
/// at [`DISPATCH_WORD`] the indirect dispatch of the tiles.
pub(crate) const COUNT_WORDS: u64 = 12;

/// Where the tiles' indirect dispatch (x, y, z workgroups) lies in the counters (`T_DISPATCH`).
pub(crate) const DISPATCH_WORD: u64 = 8;

/// Grid points (and quads) per tile: one workgroup of `tess_points` and `tess_quads`
/// (`TESS_TILE` in tessellate.wgsl).
pub const TESS_TILE: u32 = 64;

/// What a frame's tessellation counted (`T_*` in tessellate.wgsl).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TessCounts {
    /// Grid points the frame's patches need (counted whether or not they fit).
    pub vertices: u32,
    /// Quads (two triangles each) the frame's patches need.
    pub quads: u32,
    /// Patches tessellated and drawn.
    pub drawn: u32,
    /// Patches culled by their bound.
    pub culled: u32,
    /// Quads of one-sided patches culled as facing away.
    pub backface: u32,
    /// Patches that did not fit the buffers (the frame is then drawn again).
    pub over: u32,
    /// Tiles of [`TESS_TILE`] grid points (and quads) of one patch: the workgroups of each of
    /// the point and quad dispatches.
    pub tiles: u32,
}

impl TessCounts {
    pub(crate) fn from_words(w: &[u32]) -> TessCounts {
        TessCounts {
            vertices: w[0],
            quads: w[1],
            drawn: w[2],
            culled: w[3],
            backface: w[4],
            over: w[5],
            tiles: w[6],
        }
    }

    /// Triangles drawn, back-facing quads' degenerate pairs not counted.
    pub fn triangles(&self) -> u64 {
        2 * (self.quads as u64 - self.backface as u64)
    }
}

/// A patch's grid (`GridRate` in tessellate.wgsl): `n` = `[nu, nv]` segments (`[0, 0]` when
/// culled) and `edges` the segments of its boundary curves v = 0, v = 1 (along u) and u = 0,
/// u = 1 (along v), each from that curve's own control polygon, so that the two patches
/// sharing a boundary place the same points on it (no T-junction cracks; [`edge_param`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct GridRate {
    /// Segments `[nu, nv]` of the grid's interior; `[0, 0]` when culled.
    pub n: [u32; 2],
    /// Segments of the boundary curves v = 0, v = 1, u = 0, u = 1.
    pub edges: [u32; 4],
}

/// The grid of the patch whose Euclidean camera-space control points are `e` (`e[4*v + u]`);
/// twin of `grid_rate` in tessellate.wgsl (see there). The GPU's `distance` may round
/// differently, so a rate can differ by one.
pub fn grid_rate(f: &FrameUniforms, e: &[Vec3; 16], max_rate: u32) -> GridRate {
    let culled = GridRate {
        n: [0; 2],
        edges: [0; 4],
    };
    let zmin = e.iter().map(|p| p.z).fold(3.0e38f32, f32::min);
    let zmax = e.iter().map(|p| p.z).fold(-3.0e38f32, f32::max);
    if zmax < f.near || zmin > f.far {
        return culled;
    }
    if zmin < f.near {
        return GridRate {
            n: [max_rate; 2],
            edges: [max_rate; 4],
        };
    }
    let s: [Vec2; 16] = std::array::from_fn(|k| Vec2::from(stages::project(f, e[k])));
    let lo = s.iter().fold(Vec2::splat(3.0e38), |a, p| a.min(*p));
    let hi = s.iter().fold(Vec2::splat(-3.0e38), |a, p| a.max(*p));
    if hi.x < 0.0 || hi.y < 0.0 || lo.x > f.width as f32 || lo.y > f.height as f32 {
        return culled;
    }
    let mut len = [Vec2::ZERO; 4];
    for (a, l) in len.iter_mut().enumerate() {
        for b in 0..3 {
            l.x += s[4 * a + b + 1].distance(s[4 * a + b]);
            l.y += s[4 * (b + 1) + a].distance(s[4 * b + a]);
        }
    }
    let segments = |l: Vec2| {
        let n = (l / f.mp_size).ceil().min(Vec2::splat(max_rate as f32));
        let n = n.max(Vec2::ONE);
        [n.x as u32, n.y as u32]
    };
    let n = segments(len[0].max(len[1]).max(len[2].max(len[3])));
    let [e0, e1] = segments(Vec2::new(len[0].x, len[3].x));
    let [e2, e3] = segments(Vec2::new(len[0].y, len[3].y));
    GridRate {
        n,
        edges: [e0, e1, e2, e3],
    }
}

/// `edge_param` in tessellate.wgsl: the parameter of point `i` of `n` along a boundary of
/// `e <= n` segments, round(i e / n) / e in integers.
pub fn edge_param(i: u32, n: u32, e: u32) -> f32 {
    ((2 * i * e + n) / (2 * n)) as f32 / e as f32
}

/// The vertices `tessellate` makes for patch `id` (`patch` in camera space) with grid `rate`,
/// row-major: the CPU twin, evaluated and shaded as DiceShade's twin does
/// ([`stages::dice_shade::dice`]) for the patch's root item at the same (u, v), mapped to the
/// clip position of [`RasterVertex`].
pub fn tessellate_cpu(
    data: &FrameData,
    id: u32,
    patch: &Patch,
    rate: &GridRate,
) -> Vec<RasterVertex> {
    let item = root_item(id, patch);
    let f = &data.frame;
    let [nu, nv] = rate.n;
    let edges = rate.edges;
    let info = data.patch_info[id as usize];
    let m = &data.materials[info.material as usize];
    let weights = stages::item_weights(&item, &info, &data.primvars);
    let scale = Vec2::new(
        2.0 * f.focal / (f.width as f32 * f.near),
        2.0 * f.focal / (f.height as f32 * f.near),
    );
    let mut out = Vec::with_capacity(((nu + 1) * (nv + 1)) as usize);
    for k in 0..(nu + 1) * (nv + 1) {
        let (i, j) = (k % (nu + 1), k / (nu + 1));
        let mut u = i as f32 / nu as f32;
        let mut v = j as f32 / nv as f32;
        if j == 0 {
            u = edge_param(i, nu, edges[0]);
        }
        if j == nv {
            u = edge_param(i, nu, edges[1]);
        }
        if i == 0 {
            v = edge_param(j, nv, edges[2]);
        }
        if i == nu {
            v = edge_param(j, nv, edges[3]);
        }
        let e = stages::dice_shade::eval_surface(&item.cp, weights.as_ref(), u, v);
        let n = stages::dice_shade::patch_normal_at(
            &item.cp,
            weights.as_ref(),
            e,
            u,
            v,
            info.flags & 1 != 0,
        );
        let cs = if info.cs != 0 {
            stages::dice_shade::color_field(&data.primvars, info.cs, u, v)
        } else {
            Vec3::from(m.color)
        };
        let ns = if info.normal != 0 && info.flags & crate::frame::PATCH_DISPLACED == 0 {
            stages::dice_shade::color_field(&data.primvars, info.normal, u, v)
        } else {
            n
        };
        let c = stages::shade::shade(e[0], ns, m, cs, &data.lights);
        let back = n.dot(e[0]) > 0.0;
        out.push(RasterVertex {
            x: e[0].x * scale.x,
            y: e[0].y * scale.y,
            w: e[0].z / f.near,
            color: stages::shade::pack_color(c, back),
        });
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shaders;
    use scheduler::wgsl::struct_layout;

    fn check(src: &str, name: &str, size: usize, fields: &[(&str, usize)]) {
        let l = struct_layout(src, name).unwrap();
        assert_eq!(l.size as usize, size, "{name} size");
        for (field, off) in fields {
            let got = (l.members.iter())
                .find(|(n, _)| n == field)
                .map(|m| m.1 as usize);
            assert_eq!(got, Some(*off), "{name}.{field}");
        }
    }

    #[test]
    fn host_structs_match_their_wgsl_layouts() {
        use std::mem::offset_of;
        let tess = crate::gpu::pipelines::tessellate_source(crate::frame::SceneFeatures::ALL);
        check(
            &tess,
            "TessParams",
            size_of::<TessParams>(),
            &[
                ("patches", offset_of!(TessParams, patches)),
                ("row", offset_of!(TessParams, row)),
                ("vertex_capacity", offset_of!(TessParams, vertex_capacity)),
                ("quad_capacity", offset_of!(TessParams, quad_capacity)),
                ("max_rate", offset_of!(TessParams, max_rate)),
                ("tile_capacity", offset_of!(TessParams, tile_capacity)),
            ],
        );
        check(
            &tess,
            "RasterVertex",
            size_of::<RasterVertex>(),
            &[
                ("x", offset_of!(RasterVertex, x)),
                ("y", offset_of!(RasterVertex, y)),
                ("w", offset_of!(RasterVertex, w)),
                ("color", offset_of!(RasterVertex, color)),
            ],
        );
        let resolve = format!(
            "alias RasterDepth = texture_depth_2d;\n{}",
            shaders::RASTER_RESOLVE
        );
        check(
            &resolve,
            "RasterResolveParams",
            size_of::<RasterResolveParams>(),
            &[
                ("width", offset_of!(RasterResolveParams, width)),
                ("height", offset_of!(RasterResolveParams, height)),
                ("samples", offset_of!(RasterResolveParams, samples)),
                ("row", offset_of!(RasterResolveParams, row)),
                ("near", offset_of!(RasterResolveParams, near)),
            ],
        );
        // The draw stage compiles with resolve.wgsl's decoding.
        scheduler::wgsl::validate(
            "raster draw",
            &[shaders::RESOLVE, shaders::RASTER_DRAW].concat(),
        )
        .unwrap();
    }
    /// The rate: culled behind the eye and off screen, the most segments across the near
    /// plane, and about one segment per mp_size pixels of the projected control polygon.
    #[test]
    fn grid_rate_follows_the_projected_size() {
        let f = FrameUniforms {
            width: 100,
            height: 100,
            focal: 100.0,
            near: 0.1,
            far: 100.0,
            mp_size: 1.0,
            ..FrameUniforms::zeroed()
        };
        // A flat 1 x 1 patch at z = 10 spans 10 x 10 pixels.
        let at = |dx: f32, z: f32| -> [Vec3; 16] {
            std::array::from_fn(|k| {
                Vec3::new(
                    dx + (k % 4) as f32 / 3.0 - 0.5,
                    (k / 4) as f32 / 3.0 - 0.5,
                    z,
                )
            })
        };
        // 10 pixels a side, give or take the rounding of three thirds.
        let r = grid_rate(&f, &at(0.0, 10.0), 64);
        assert!(r.n.iter().all(|n| (10..=11).contains(n)), "{r:?}");
        assert!(r.edges.iter().all(|n| (10..=11).contains(n)), "{r:?}");
        assert_eq!(grid_rate(&f, &at(0.0, 1.0), 64).n, [64, 64]);
        assert_eq!(grid_rate(&f, &at(0.0, -1.0), 64).n, [0, 0]);
        assert_eq!(grid_rate(&f, &at(0.0, 200.0), 64).n, [0, 0]);
        assert_eq!(grid_rate(&f, &at(100.0, 10.0), 64).n, [0, 0]);
        let mut crossing = at(0.0, 10.0);
        crossing[0].z = -1.0;
        assert_eq!(grid_rate(&f, &crossing, 64).n, [64, 64]);
        let coarse = FrameUniforms { mp_size: 4.0, ..f };
        assert_eq!(grid_rate(&coarse, &at(0.0, 10.0), 64).n, [3, 3]);
        // A patch whose row v = 1 is half as long: that boundary gets fewer segments.
        let mut taper = at(0.0, 10.0);
        for p in &mut taper[12..] {
            p.x *= 0.5;
        }
        let r = grid_rate(&coarse, &taper, 64);
        assert_eq!((r.n[0], r.edges[0], r.edges[1]), (3, 3, 2), "{r:?}");
        // Boundary points land on the boundary's own k / e, and the ends stay.
        assert_eq!(
            (0..=3).map(|i| edge_param(i, 3, 2)).collect::<Vec<_>>(),
            [0.0, 0.5, 0.5, 1.0]
        );
        assert_eq!(
            (0..=4).map(|i| edge_param(i, 4, 4)).collect::<Vec<_>>(),
            [0.0, 0.25, 0.5, 0.75, 1.0]
        );
    }
}
