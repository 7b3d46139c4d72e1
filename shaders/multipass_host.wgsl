// Host-driven multi-pass (Patney & Owens 2008, as they ran it): the host reads each round's
// per-queue counts and launches one exactly sized dispatch per non-empty procedure queue.
// Compaction is fused into the producing pass: `enqueue_<t>` appends the item straight into
// queue t's region of the next round's input buffer with one atomicAdd on t's counter, so there
// is no flag array, no scan and no scatter. The host checks before each round that every target
// can hold the round's worst case (sum over procedures of inputs x declared emits) and grows it
// first if not, so an append never passes the capacity. Order within a queue is not kept.
// Generated before this file: tables, procedures, `mp_in_*` / `mp_out_*` accessors,
// `mp_execute_<t>` (item i of queue t's region, in the program's item layout:
// scheduler/src/item_layout.rs), `enqueue_*`, and one entry point per procedure with its own
// loop (multipass_host_run.wgsl).

// ---- counts buffers; host twin: scheduler/src/multipass/host.rs ----
// counts_in[q]: inputs of queue q this round runs (the previous round's appends, or the host's
// seeds); counts_in[H_SKIP + q]: older inputs before them, carried (multipass/partial.rs).
// counts_out[q]: appends to queue q this round (zeroed by the host before the round, or set to
// the inputs it carried there), then the error words, then the next round's skip words (zero).
const H_ERROR: u32 = 0u;
const H_ERR_A: u32 = 1u;
const H_ERR_B: u32 = 2u;
const H_SKIP: u32 = NQ + 3u;
const ERR_EMIT: u32 = 1u;
const ERR_ROOM: u32 = 2u; // an append past a capacity: the host's room check failed (a bug)

// ---- params: per queue, capacity and first word of its region ----
fn q_cap(q: u32) -> u32 { return params[q * 4u]; }
fn q_base(q: u32) -> u32 { return params[q * 4u + 1u]; }

@group(0) @binding(0) var<storage, read> counts_in: array<u32>;
@group(0) @binding(1) var<storage, read_write> counts_out: array<atomic<u32>>;
@group(0) @binding(2) var<storage, read_write> items_in: array<vec4<u32>>;
@group(0) @binding(3) var<storage, read_write> items_out: array<vec4<u32>>;
@group(0) @binding(4) var<storage, read> params: array<u32>;

var<workgroup> wg_n: u32;
var<workgroup> wg_item_emits: array<atomic<u32>, 256u * NQ>;
var<private> sched_proc: u32;
var<private> sched_slot: u32;
var<private> sched_active: bool;

fn sched_raise(code: u32, a: u32, b: u32) {
    if atomicExchange(&counts_out[NQ + H_ERROR], code) == 0u {
        atomicStore(&counts_out[NQ + H_ERR_A], a);
        atomicStore(&counts_out[NQ + H_ERR_B], b);
    }
}

// The slot (index within queue t's region of items_out) of this item's next item to t, or
// 0xffffffff after raising ERR_EMIT when the item emits more than it declared: the append is
// refused, so the round's appends never pass its worst case, which the host made room for.
fn sched_append_slot(t: u32) -> u32 {
    let j = atomicAdd(&wg_item_emits[sched_slot * NQ + t], 1u);
    if j >= sched_emits(sched_proc * NQ + t) {
        sched_raise(ERR_EMIT, sched_proc, t);
        return 0xffffffffu;
    }
    let at = atomicAdd(&counts_out[t], 1u);
    if at >= q_cap(t) {
        sched_raise(ERR_ROOM, t, at);
        return 0xffffffffu;
    }
    return at;
}

