// Copies items that lie back to back in `src` into a planar queue region of `dst` (word w of
// item i at region + w x capacity + i): what a plain buffer copy does for interleaved queues.
// Seeds already on the device reach a planar megakernel's queues this way (recorded runs).
// Host twin: PlanarScatter in scheduler/src/item_layout.rs.

@group(0) @binding(0) var<storage, read> src: array<u32>;
@group(0) @binding(1) var<storage, read_write> dst: array<u32>;
// Words per item, items, first word of the region, its capacity in items.
@group(0) @binding(2) var<storage, read> p: array<u32, 4>;

@compute @workgroup_size(256)
fn scatter(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let words = p[0];
    let total = words * p[1];
    for (var i = gid.x; i < total; i += nwg.x * 256u) {
        let item = i / words;
        let w = i - item * words;
        dst[p[2] + w * p[3] + item] = src[i];
    }
}
