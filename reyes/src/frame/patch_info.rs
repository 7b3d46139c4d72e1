//! The per-patch tables the stages read beside the queue items: [`PatchInfo`] (indexed by
//! `PatchItem::patch_id`) and the entries it points into in the primitive-variable table
//! (motion, colour fields, displacement).

#[allow(unused_imports)]
use super::*;

/// What the stages know of an original patch, indexed by `PatchItem::patch_id`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct PatchInfo {
    /// Index into [`FrameData::materials`].
    pub material: u32,
    /// bit 0: flip the normal; bit 1: two-sided; bit 2 ([`PATCH_RATIONAL`]): some weight of
    /// the patch is not 1.
    pub flags: u32,
    /// The patch's `"Cs"` in [`FrameData::primvars`] ([`field_ref`]), 0 for the material's.
    pub cs: u32,
    /// The patch's `"Os"` in [`FrameData::primvars`] ([`field_ref`]), 0 for the material's.
    pub os: u32,
    /// A rational patch's weights: the index of 4 entries of [`FrameData::primvars`], entry
    /// `l` holding the weights of row `v = l` (u = 0..3 in its 4 lanes), as [`root_item`]
    /// scales them (largest 1). 0 for a polynomial patch, read only under [`PATCH_RATIONAL`].
    pub weights: u32,
    /// A displaced patch's displacement ([`PATCH_DISPLACED`]): the index of its entry in
    /// [`FrameData::primvars`] ([`displacement_ref`] gives the layout). 0 when undisplaced.
    pub displacement: u32,
    /// A moving patch's motion ([`PATCH_MOVING`]): the index of 3 entries of
    /// [`FrameData::primvars`], the rows of the camera-space affine map from its points at
    /// shutter open to those at shutter close ([`motion_ref`]). 0 when it does not move.
    pub motion: u32,
    /// The patch's `"N"` (shading normal, camera space) in [`FrameData::primvars`]
    /// ([`field_ref`]), 0 for the surface's own normal. Used by an undisplaced patch only.
    pub normal: u32,
}

/// Bit of [`PatchInfo::flags`] (`PATCH_MOVING` in common.wgsl): the patch moves over the
/// shutter ([`PatchInfo::motion`]).
pub const PATCH_MOVING: u32 = 16;

/// Appends the affine part of the camera-space motion `m` (shutter open to close) to the table
/// as 3 rows `[m_r0, m_r1, m_r2, t_r]` and returns the first entry's index. Errors
/// ([`Error::TablesTooLarge`]) when the table would outgrow what a GPU binding holds.
pub fn motion_ref(table: &mut Vec<[f32; 4]>, m: &glam::DMat4) -> Result<u32, Error> {
    let at = table.len() as u64;
    if (at + 3) * 16 > MAX_FRAME_BUFFER_BYTES {
        return Err(Error::TablesTooLarge {
            what: "motion and primitive variables",
            limit: MAX_FRAME_BUFFER_BYTES,
        });
    }
    table.extend((0..3).map(|r| std::array::from_fn(|c| m.col(c)[r] as f32)));
    Ok(at as u32)
}

/// Shapes of a colour field in the primitive-variable table (the low 2 bits of
/// `PatchInfo::cs` / `os`; `FIELD_*` in common.wgsl): one value, 4 bilinear corners, or 16
/// bicubic Bezier coefficients (`crate::scene::ColorField`).
pub const FIELD_FLAT: u32 = 1;
/// 4 values at the corners (u, v) = (0, 0), (1, 0), (0, 1), (1, 1), interpolated bilinearly.
pub const FIELD_BILINEAR: u32 = 2;
/// 16 bicubic Bezier coefficients, `4*v + u` order.
pub const FIELD_BEZIER: u32 = 3;

/// Appends `field` to the primitive-variable table (one `[r, g, b, 0]` entry per value, in
/// f32) and returns its reference: the entry index shifted left by 2, or-ed with its shape.
/// Errors ([`Error::TablesTooLarge`]) when the table would outgrow what a GPU binding holds.
pub fn field_ref(
    table: &mut Vec<[f32; 4]>,
    field: &crate::scene::ColorField,
) -> Result<u32, Error> {
    use crate::scene::ColorField;
    let shape = match field {
        ColorField::Flat(_) => FIELD_FLAT,
        ColorField::Bilinear(_) => FIELD_BILINEAR,
        ColorField::Bezier(_) => FIELD_BEZIER,
    };
    let at = table.len() as u64;
    let end = at + field.values().len() as u64;
    if end * 16 > MAX_FRAME_BUFFER_BYTES || at >= 1 << 30 {
        return Err(Error::TablesTooLarge {
            what: "primitive variables",
            limit: MAX_FRAME_BUFFER_BYTES,
        });
    }
    table.extend(field.values().iter().map(|c| {
        let c = f3(*c);
        [c[0], c[1], c[2], 0.0]
    }));
    Ok((at as u32) << 2 | shape)
}

/// Bit of [`PatchInfo::flags`] (`PATCH_RATIONAL` in common.wgsl): the patch is rational, so
/// the stages blossom its weights from [`PatchInfo::weights`] and divide by them (homogeneous
/// arithmetic); without it they take an item's control points as the points, read no table
/// and skip that work.
pub const PATCH_RATIONAL: u32 = 4;

/// Bit of [`PatchInfo::flags`] (`PATCH_DISPLACED` in common.wgsl): DiceShade displaces the
/// patch's grid points ([`PatchInfo::displacement`]) and Bound grows its bound.
pub const PATCH_DISPLACED: u32 = 8;

/// Kinds of displacement pattern in a displacement entry (`DISPLACE_*` in common.wgsl).
pub const DISPLACE_BUMPS: u32 = 0;
/// A displacement map's texels ([`crate::scene::DisplacementPattern::Map`]).
pub const DISPLACE_MAP: u32 = 1;

/// Which normal displaced grid points move along (`--displacement-normals`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum DisplacementNormals {
    /// The surface normal from the patch's analytic derivatives (Sattler et al.'s eq. 1):
    /// one direction per point of the original patch, whatever grid computes it, so grids
    /// that share an edge move it alike.
    #[default]
    Exact,
    /// The normal of the grid's own finite differences (central inside, one-sided at its
    /// border): neighbouring grids of other rates move a shared edge differently, which
    /// opens holes. For comparison only.
    Approximate,
}

/// Appends the displacement `d` to the table and returns its entry index
/// ([`PatchInfo::displacement`]): entry `at` = (amount, bound, kind, map entry or bumps
/// frequency) with the last two as `u32` bits. A map's block (shared by every patch that uses the map; `maps`
/// remembers where each went) is one entry (width, height as `u32` bits, 0, 0), then its
/// texels 4 to an entry, row-major from the top row. Errors ([`Error::TablesTooLarge`]) when
/// the table would outgrow what a GPU binding holds.
pub fn displacement_ref(
    table: &mut Vec<[f32; 4]>,
    maps: &mut Vec<(*const crate::scene::DisplacementMap, u32)>,
    d: &crate::scene::Displacement,
) -> Result<u32, Error> {
    use crate::scene::DisplacementPattern;
    let too_big = |end: u64| {
        (end * 16 > MAX_FRAME_BUFFER_BYTES).then_some(Error::TablesTooLarge {
            what: "displacements and primitive variables",
            limit: MAX_FRAME_BUFFER_BYTES,
        })
    };
    let (kind, map_at) = match &d.pattern {
        DisplacementPattern::Bumps { frequency } => (DISPLACE_BUMPS, *frequency),
        DisplacementPattern::Map(m) => {
            let key = std::sync::Arc::as_ptr(m);
            let at = match maps.iter().find(|(k, _)| *k == key) {
                Some((_, at)) => *at,
                None => {
                    let at = table.len() as u64;
                    if let Some(e) = too_big(at + 1 + m.texels.len().div_ceil(4) as u64) {
                        return Err(e);
                    }
                    let size = [m.width, m.height].map(f32::from_bits);
                    table.push([size[0], size[1], 0.0, 0.0]);
                    table.extend(
                        m.texels
                            .chunks(4)
                            .map(|c| std::array::from_fn(|k| c.get(k).copied().unwrap_or(0.0))),
                    );
                    maps.push((key, at as u32));
                    at as u32
                }
            };
            (DISPLACE_MAP, at)
        }
    };
    let at = table.len() as u64;
    if let Some(e) = too_big(at + 1) {
        return Err(e);
    }
    table.push([
        d.amount as f32,
        d.bound as f32,
        f32::from_bits(kind),
        f32::from_bits(map_at),
    ]);
    Ok(at as u32)
}

/// Bit of [`PatchInfo::flags`] (`PATCH_TRIMMED` in common.wgsl): the patch is trimmed
/// (`TrimCurve`); bits [`TRIM_SHIFT`].. of the flags hold the index of its trim header in
/// [`FrameData::primvars`] ([`trim_ref`]). Read only when `SCENE_TRIM`.
pub const PATCH_TRIMMED: u32 = 32;

/// The trim header's entry index sits in the flags from this bit on (24 bits), so that an
/// untrimmed patch pays nothing for trimming: no field, no table entry.
pub const TRIM_SHIFT: u32 = 8;

/// Appends the trimming of one patch to the table and returns the bits to or into its
/// [`PatchInfo::flags`]: [`PATCH_TRIMMED`] and the header's index << [`TRIM_SHIFT`]. The header
/// is 2 entries: (u0, u1 - u0, v0, v1 - v0), the map from the patch's (u, v) to the surface's
/// parameter space, then (first edge entry, edge count, 1 to keep the outside else 0, 0) as
/// `u32` bits. The edges (one entry (ax, ay, bx, by) each, every loop closed) are written once
/// per `TrimCurve` and shared by its patches (`trims` remembers where each went). Errors
/// ([`Error::TablesTooLarge`]) when the table would outgrow what a GPU binding holds, or the
/// header's index its 24 bits.
pub fn trim_ref(
    table: &mut Vec<[f32; 4]>,
    trims: &mut Vec<(*const crate::scene::trim::TrimLoops, u32, u32)>,
    t: &crate::scene::trim::PatchTrim,
) -> Result<u32, Error> {
    let too_big = || Error::TablesTooLarge {
        what: "trim curves and primitive variables",
        limit: MAX_FRAME_BUFFER_BYTES,
    };
    let key = std::sync::Arc::as_ptr(&t.loops);
    let (edges_at, count) = match trims.iter().find(|(k, _, _)| *k == key) {
        Some(&(_, at, n)) => (at, n),
        None => {
            let at = table.len() as u64;
            let n = t.loops.edge_count() as u64;
            if (at + n) * 16 > MAX_FRAME_BUFFER_BYTES {
                return Err(too_big());
            }
            table.extend(
                t.loops
                    .edges()
                    .map(|(a, b)| [a.x as f32, a.y as f32, b.x as f32, b.y as f32]),
            );
            trims.push((key, at as u32, n as u32));
            (at as u32, n as u32)
        }
    };
    let at = table.len() as u64;
    if (at + 2) * 16 > MAX_FRAME_BUFFER_BYTES || at >= 1 << (32 - TRIM_SHIFT) {
        return Err(too_big());
    }
    table.push([
        t.u.0 as f32,
        (t.u.1 - t.u.0) as f32,
        t.v.0 as f32,
        (t.v.1 - t.v.0) as f32,
    ]);
    table.push([
        f32::from_bits(edges_at),
        f32::from_bits(count),
        f32::from_bits(t.outside as u32),
        0.0,
    ]);
    Ok(PATCH_TRIMMED | (at as u32) << TRIM_SHIFT)
}

/// What the patches share ([`std::sync::Arc`]: the instances of an object, the patches of
/// one request) and the table has once: each allocation's entries, by its address. Patches
/// hold their allocations while the table is made, so an address names one allocation.
#[derive(Default)]
pub(super) struct SharedEntries {
    /// Primitive variables: `(cs, os, normal)` references.
    pub(super) primvars: std::collections::HashMap<usize, (u32, u32, u32)>,
    /// Rational weights: the first entry.
    pub(super) weights: std::collections::HashMap<usize, u32>,
    /// Displacements: the entry.
    pub(super) displacements: std::collections::HashMap<usize, u32>,
    /// Trims: the flag bits of the header ([`trim_ref`]).
    pub(super) trims: std::collections::HashMap<usize, u32>,
    /// Displacement maps' blocks ([`displacement_ref`]).
    pub(super) maps: Vec<(*const crate::scene::DisplacementMap, u32)>,
    /// Trim loops' edges ([`trim_ref`]).
    pub(super) loops: Vec<(*const crate::scene::trim::TrimLoops, u32, u32)>,
}

/// The entries of `a` in the table: those `seen` remembers for its allocation, else `make`'s
/// (remembered when another patch holds the allocation too: one the patch holds alone costs
/// no lookup).
pub(super) fn once<T, V: Copy>(
    seen: &mut std::collections::HashMap<usize, V>,
    a: &std::sync::Arc<T>,
    make: impl FnOnce() -> Result<V, Error>,
) -> Result<V, Error> {
    if std::sync::Arc::strong_count(a) == 1 {
        return make();
    }
    let key = std::sync::Arc::as_ptr(a) as usize;
    if let Some(&v) = seen.get(&key) {
        return Ok(v);
    }
    let v = make()?;
    seen.insert(key, v);
    Ok(v)
}
