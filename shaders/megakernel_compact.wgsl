// Device compaction between two megakernel launches, used when queues grow: copies every
// published, unconsumed slot of the old queues into the first slots of the new, larger ones as a
// seed (flag SEED_STAMP), so the items never travel to the host. One workgroup row per queue
// (workgroup_id.y), grid-stride over the old launch's reserved tickets. Slots are appended with an
// atomic counter per queue, so the kept items lose their ticket order (no order is promised).
// Checks for the host, in the new ctrl: Q_KEPT per queue must equal the live count the host
// derived from the old ctrl (reserve - executed), and G_LOST (an EMPTY slot below the reserve,
// i.e. reserved but never published, or more live slots than the new capacity) must stay 0.
// Host twin of the params: scheduler/src/megakernel/compact.rs.

@group(0) @binding(0) var<storage, read> old_slots: array<u32>;
@group(0) @binding(1) var<storage, read> old_flags: array<u32>;
@group(0) @binding(2) var<storage, read_write> new_slots: array<u32>;
@group(0) @binding(3) var<storage, read_write> new_flags: array<u32>;
@group(0) @binding(4) var<storage, read_write> new_ctrl: array<atomic<u32>>;
@group(0) @binding(5) var<storage, read> cp: array<u32>;

const EMPTY: u32 = 0u;
const CONSUMED: u32 = 0xffffffffu;
const SEED_STAMP: u32 = 1u;

// cp[0]: ctrl word of G_LOST; queue q's CP_QUEUE_WORDS words at 8 + CP_QUEUE_WORDS q: reserved
// tickets, old slot base, old flag base, new slot base, new flag base, words per item, new
// capacity, ctrl word of Q_KEPT, old capacity, 1 if items are planar (word w of the item in slot
// i at base + w x capacity + i; else at base + i x words + w: scheduler/src/item_layout.rs).
const CP_QUEUE_WORDS: u32 = 10u;
@compute @workgroup_size(256)
fn compact(@builtin(local_invocation_index) lid: u32, @builtin(workgroup_id) wid: vec3<u32>,
           @builtin(num_workgroups) nwg: vec3<u32>) {
    let e = 8u + wid.y * CP_QUEUE_WORDS;
    let reserve = cp[e];
    let words = cp[e + 5u];
    for (var i = wid.x * 256u + lid; i < reserve; i += nwg.x * 256u) {
        let f = old_flags[cp[e + 2u] + i];
        if f == CONSUMED { continue; }
        if f == EMPTY { atomicAdd(&new_ctrl[cp[0]], 1u); continue; }
        let j = atomicAdd(&new_ctrl[cp[e + 7u]], 1u);
        if j >= cp[e + 6u] { atomicAdd(&new_ctrl[cp[0]], 1u); continue; }
        if cp[e + 9u] != 0u {
            for (var w = 0u; w < words; w++) {
                new_slots[cp[e + 3u] + w * cp[e + 6u] + j] = old_slots[cp[e + 1u] + w * cp[e + 8u] + i];
            }
        } else {
            let src = cp[e + 1u] + i * words;
            let dst = cp[e + 3u] + j * words;
            for (var w = 0u; w < words; w++) { new_slots[dst + w] = old_slots[src + w]; }
        }
        new_flags[cp[e + 4u] + j] = SEED_STAMP;
    }
}
