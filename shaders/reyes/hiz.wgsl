// The depth pyramid (Hi-Z) of one bucket's samples, built between scheduler runs: a plain
// compute pass per level. Level 0: per tile of `tile_px` x `tile_px` pixels, the largest depth
// bits of its sub-samples (the complement of a key's high word; an empty sample, key 0, reads
// 0xffffffff: deeper than anything, never an occluder). Each level above: the largest of the
// (up to) 2x2 tiles below. Bound reads it (hiz_occluded in bound.wgsl).
// Rust twin: reyes/src/stages/hiz.rs (`build`).

struct HizParams {
    // The bucket, pixels, and its sub-samples a pixel (level 0 only).
    width: u32,
    height: u32,
    spp: u32,
    tile_px: u32,
    // The level below (tiles across, down, first word); level 0 reads the samples instead.
    src_w: u32,
    src_h: u32,
    src_off: u32,
    // This level (first word, tiles across, down).
    dst_off: u32,
    dst_w: u32,
    dst_h: u32,
    pad0: u32,
    pad1: u32,
}

@group(0) @binding(0) var<storage, read> hiz_params: HizParams;
// The sample keys as (low, high) words.
@group(0) @binding(1) var<storage, read> hiz_keys: array<vec2<u32>>;
@group(0) @binding(2) var<storage, read_write> hiz_out: array<u32>;

@compute @workgroup_size(8, 8)
fn hiz_level0(@builtin(global_invocation_id) id: vec3<u32>) {
    let p = hiz_params;
    if id.x >= p.dst_w || id.y >= p.dst_h { return; }
    let x0 = id.x * p.tile_px;
    let y0 = id.y * p.tile_px;
    var m = 0u;
    for (var y = y0; y < min(y0 + p.tile_px, p.height); y++) {
        for (var x = x0; x < min(x0 + p.tile_px, p.width); x++) {
            let base = (y * p.width + x) * p.spp;
            for (var s = 0u; s < p.spp; s++) { m = max(m, ~hiz_keys[base + s].y); }
        }
    }
    hiz_out[p.dst_off + id.y * p.dst_w + id.x] = m;
}

@compute @workgroup_size(8, 8)
fn hiz_reduce(@builtin(global_invocation_id) id: vec3<u32>) {
    let p = hiz_params;
    if id.x >= p.dst_w || id.y >= p.dst_h { return; }
    var m = 0u;
    for (var y = 2u * id.y; y < min(2u * id.y + 2u, p.src_h); y++) {
        for (var x = 2u * id.x; x < min(2u * id.x + 2u, p.src_w); x++) {
            m = max(m, hiz_out[p.src_off + y * p.src_w + x]);
        }
    }
    hiz_out[p.dst_off + id.y * p.dst_w + id.x] = m;
}
