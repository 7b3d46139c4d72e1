// Device-driven multi-pass (Patney & Owens 2008, without their read-back per round): rounds of
// one indirect dispatch per dispatch group (each procedure alone; all of them, fused rounds,
// `mp_round` below; or the producers and the sinks apart, `mp_group_<g>`),
// every round of a submission recorded up front and sized on the device. Compaction is fused
// into the producing pass, as in the host-driven variant (`multipass_host.wgsl`): `enqueue_<t>`
// appends the item straight into queue t's region of the next round's input buffer with one
// atomicAdd on t's count, so a round has no flags, no scan and no scatter. The plan
// (`plan_round`) turns the previous round's counts into this round's dispatch sizes: for a
// chunk's first round a one-thread dispatch (`mp_plan`), for every other round the last
// workgroup of the round before, when it finishes. An empty queue gets 0 workgroups; an empty
// round is never planned, so it and every round after it in the chunk keep the zeroed
// arguments the host cleared. Order within a queue is not kept.
// Generated before this file: tables, procedures, `mp_in_*` / `mp_out_*` accessors,
// `sched_execute`, `mp_execute` (item i of queue q's region) and `mp_word_at` (word w of it),
// both in the run's item layout (scheduler/src/item_layout.rs), `enqueue_*`, and the
// per-procedure entry points, each with its own copy of `run_procedure` (multipass_run.wgsl).

// ---- mp_ctrl layout; host twin: scheduler/src/multipass/layout.rs ----
const CSTRIDE: u32 = 8u;
const C_COUNT: u32 = 0u;  // inputs of the current round
const C_PEAK: u32 = 1u;
const C_EXEC: u32 = 2u;
const C_EMITS: u32 = 3u;  // worst-case outputs of this round for this target
const C_NEXT: u32 = 4u;   // carried inputs + appended outputs = inputs of the next round
const C_RUN: u32 = 5u;    // inputs this round runs (all but in a partial round)
const C_KEEP: u32 = 6u;   // inputs this round carries, unrun, to the front of the next
const C_WGS: u32 = 7u;    // this procedure's workgroups in its dispatch group's dispatch
fn cw(q: u32, i: u32) -> u32 { return q * CSTRIDE + i; }
fn gw(i: u32) -> u32 { return NQ * CSTRIDE + i; }
const G_ROUNDS: u32 = 0u;
const G_ERROR: u32 = 1u;
const G_ERR_A: u32 = 2u;
const G_ERR_B: u32 = 3u;
const G_HALT: u32 = 4u;
const G_PLANNED: u32 = 5u; // plans that let their round run, for the host's parity
const G_PARTIAL: u32 = 6u; // partial rounds (scheduler/src/multipass/partial.rs)
const G_DONE: u32 = 7u;    // workgroups of the current round that have finished
const G_WGS: u32 = 8u;     // workgroups the current round dispatched, all procedures together
const G_K: u32 = 9u;       // the current round's index within the chunk
const G_CHUNK: u32 = 10u;  // rounds in the chunk (the host's): round G_CHUNK is not planned

const ERR_EMIT: u32 = 1u;
const ERR_OVERFLOW: u32 = 2u;
const ERR_ROOM: u32 = 3u; // an append past a capacity: the plan's room check failed (a bug)

// ---- params; host twin: Multipass::device_rounds ----
fn q_cap(q: u32) -> u32 { return params[q * 4u]; }
fn q_base(q: u32) -> u32 { return params[q * 4u + 1u]; }
// 1 when queue q is at its capacity limit: a round it cannot hold runs in part instead of
// halting for growth.
fn q_at_limit(q: u32) -> bool { return params[q * 4u + 2u] != 0u; }

@group(0) @binding(0) var<storage, read_write> mp_ctrl: array<atomic<u32>>;
@group(0) @binding(1) var<storage, read_write> items_in: array<vec4<u32>>;
@group(0) @binding(2) var<storage, read_write> items_out: array<vec4<u32>>;
@group(0) @binding(3) var<storage, read> params: array<u32>;
// Group 2: the arguments of the rounds the bound dispatch may plan, round k's dispatch group
// g's at slot (k / 2) x NQ + g of buffer k % 2. Round k's dispatches read theirs from buffer k % 2 and have
// buffer (k + 1) % 2 bound here, so no dispatch reads its own arguments as storage.
@group(2) @binding(0) var<storage, read_write> indirect: array<u32>;

// This workgroup's copy of what the plan wrote for its round (R_* entries): its procedure's
// inputs, inputs run and workgroups, then the round's workgroups (all procedures), the round's
// index in the chunk and the chunk's length. Read once at the start by parallel lanes
// (`mp_round_inputs`; the fused round reads every procedure's at once), so no workgroup's start
// or end waits on a chain of global loads, and `finish_workgroup` compares its count with the
// round's own G_WGS, which the next round's plan may overwrite while this workgroup finishes.
const R_COUNT: u32 = 0u;
const R_RUN: u32 = 1u;
const R_WGS: u32 = 2u;
const R_ALL: u32 = 3u;
const R_K: u32 = 4u;
const R_CHUNK: u32 = 5u;
const R_WORDS: u32 = 6u;
var<workgroup> wg_round: array<u32, R_WORDS>;
var<workgroup> wg_item_emits: array<atomic<u32>, 256u * NQ>;
var<workgroup> wg_last: u32;
var<private> sched_proc: u32;
var<private> sched_slot: u32;
var<private> sched_active: bool;

fn sched_raise(code: u32, a: u32, b: u32) {
    if atomicExchange(&mp_ctrl[gw(G_ERROR)], code) == 0u {
        atomicStore(&mp_ctrl[gw(G_ERR_A)], a);
        atomicStore(&mp_ctrl[gw(G_ERR_B)], b);
    }
    atomicStore(&mp_ctrl[gw(G_HALT)], 1u);
}

// The slot (index within queue t's region of items_out) of this item's next item to t, or
// 0xffffffff after raising ERR_EMIT when the item emits more than it declared: the append is
// refused, so the round's appends never pass its worst case, which the plan made room for.
fn sched_append_slot(t: u32) -> u32 {
    let j = atomicAdd(&wg_item_emits[sched_slot * NQ + t], 1u);
    if j >= EMITS[sched_proc * NQ + t] {
        sched_raise(ERR_EMIT, sched_proc, t);
        return 0xffffffffu;
    }
    let at = atomicAdd(&mp_ctrl[cw(t, C_NEXT)], 1u);
    if at >= q_cap(t) {
        sched_raise(ERR_ROOM, t, at);
        return 0xffffffffu;
    }
    return at;
}

// The mp_ctrl word of entry j of procedure q's round copy (`wg_round`).
fn round_word(q: u32, j: u32) -> u32 {
    switch j {
        case 0u: { return cw(q, C_COUNT); }
        case 1u: { return cw(q, C_RUN); }
        case 2u: { return cw(q, C_WGS); }
        case 3u: { return gw(G_WGS); }
        case 4u: { return gw(G_K); }
        default: { return gw(G_CHUNK); }
    }
}

// Procedure q's round copy: one load per lane, unless the round's dispatch read it already
// (`loaded`: a fused round's or a dispatch group's `mp_pick`).
fn mp_round_inputs(q: u32, lid: u32, loaded: bool) -> array<u32, R_WORDS> {
    if !loaded && lid < R_WORDS { wg_round[lid] = atomicLoad(&mp_ctrl[round_word(q, lid)]); }
    return workgroupUniformLoad(&wg_round);
}

fn set_args(slot: u32, x: u32) {
    indirect[slot * 3u] = x;
    indirect[slot * 3u + 1u] = 1u;
    indirect[slot * 3u + 2u] = 1u;
}

// The first round of a chunk (its index 0): planned by one thread before it.
@compute @workgroup_size(1)
fn mp_plan() { plan_round(0u); }

// One thread: takes the previous round's carried and appended counts as this round's inputs
// and writes every dispatch size of the round (at most 65,535: grid-stride past that, so every
// argument is valid with wgpu's indirect validation off). When a target cannot hold the
// round's worst case: halts (nothing run, inputs intact) for the host to grow it, or, when it
// is at its limit, runs only part of the inputs (partial.rs, the host twin) and carries the
// rest; halts with ERR_OVERFLOW when not one input fits. A halted or empty round dispatches
// nothing, so nothing plans the rounds after it: they keep their zeroed arguments. `k`: the
// round's index within the chunk.
// Its loads are independent and issued before any store, and the counts stay in `cnt`, so the
// plan, which the whole next round waits for, costs about one round trip to memory, not one
// per queue.
fn plan_round(k: u32) {
    var total = 0u;
    var cnt: array<u32, NQ>;
    for (var q = 0u; q < NQ; q++) { cnt[q] = atomicLoad(&mp_ctrl[cw(q, C_NEXT)]); }
    var ok = atomicLoad(&mp_ctrl[gw(G_HALT)]) == 0u;
    for (var q = 0u; q < NQ; q++) {
        atomicStore(&mp_ctrl[cw(q, C_COUNT)], cnt[q]);
        total += cnt[q];
    }
    var run = cnt;
    var partial = false;
    var over_t = 0u;
    var over_m = 0u;
    for (var t = 0u; t < NQ; t++) {
        var m = 0u;
        for (var p = 0u; p < NQ; p++) { m += run[p] * EMITS[p * NQ + t]; }
        atomicStore(&mp_ctrl[cw(t, C_EMITS)], m);
        if q_at_limit(t) && m > q_cap(t) / 2u {
            if !partial || m > over_m { over_t = t; over_m = m; }
            partial = true;
        } else if m > q_cap(t) {
            if ok {
                ok = false;
                if atomicExchange(&mp_ctrl[gw(G_ERROR)], ERR_OVERFLOW) == 0u {
                    atomicStore(&mp_ctrl[gw(G_ERR_A)], t);
                    atomicStore(&mp_ctrl[gw(G_ERR_B)], m);
                }
                atomicStore(&mp_ctrl[gw(G_HALT)], 1u);
            }
        }
    }
    if ok && partial {
        // Last procedure first: each runs as many inputs as keep every target within half its
        // capacity, and at least one when one fits (partial.rs says why).
        var used: array<u32, NQ>;
        for (var t = 0u; t < NQ; t++) { used[t] = run[t]; }
        var any = false;
        for (var i = 0u; i < NQ; i++) {
            let p = NQ - 1u - i;
            var hard = run[p];
            var soft = run[p];
            for (var t = 0u; t < NQ; t++) {
                let grow = EMITS[p * NQ + t];
                let shrink = select(0u, 1u, t == p);
                if grow > shrink {
                    hard = min(hard, (q_cap(t) - used[t]) / (grow - shrink));
                    let half = q_cap(t) / 2u;
                    soft = min(soft, select(0u, half - used[t], half > used[t]) / (grow - shrink));
                }
            }
            let r = max(soft, min(hard, 1u));
            run[p] = r;
            for (var t = 0u; t < NQ; t++) { used[t] += r * EMITS[p * NQ + t]; }
            used[p] -= r;
            any = any || r > 0u;
        }
        if any {
            atomicAdd(&mp_ctrl[gw(G_PARTIAL)], 1u);
        } else {
            ok = false;
            if atomicExchange(&mp_ctrl[gw(G_ERROR)], ERR_OVERFLOW) == 0u {
                atomicStore(&mp_ctrl[gw(G_ERR_A)], over_t);
                atomicStore(&mp_ctrl[gw(G_ERR_B)], over_m);
            }
            atomicStore(&mp_ctrl[gw(G_HALT)], 1u);
        }
    }
    if ok {
        for (var t = 0u; t < NQ; t++) {
            var m = 0u;
            for (var p = 0u; p < NQ; p++) { m += run[p] * EMITS[p * NQ + t]; }
            atomicStore(&mp_ctrl[cw(t, C_EMITS)], m);
        }
    }
    // A halted round leaves the whole round's worst case in C_EMITS, for the host's growth.
    // A round is one indirect dispatch per dispatch group (GROUP[q], NG groups: every
    // procedure alone, all together with fused rounds, or the sinks apart; `Multipass::new`),
    // so each procedure gets at most its share of its group's dispatch's 65,535.
    var all_wgs = 0u;
    var group_wgs: array<u32, NQ>;
    for (var q = 0u; q < NQ; q++) {
        let n = cnt[q];
        let per_step = 256u / THREADS[q];
        let max_wgs = 65535u / GROUP_LEN[q];
        // Every input is visited: run, or copied to the front of the next round's inputs.
        let wgs = select(0u, min((n + per_step - 1u) / per_step, max_wgs), ok);
        group_wgs[GROUP[q]] += wgs;
        all_wgs += wgs;
        if ok {
            atomicStore(&mp_ctrl[cw(q, C_WGS)], wgs);
            atomicMax(&mp_ctrl[cw(q, C_PEAK)], n);
            atomicAdd(&mp_ctrl[cw(q, C_EXEC)], run[q]);
            atomicStore(&mp_ctrl[cw(q, C_RUN)], run[q]);
            atomicStore(&mp_ctrl[cw(q, C_KEEP)], n - run[q]);
            // The carried inputs lead the next round; the round's appends go after them.
            atomicStore(&mp_ctrl[cw(q, C_NEXT)], n - run[q]);
        }
    }
    for (var g = 0u; g < NG; g++) { set_args((k / 2u) * NQ + g, group_wgs[g]); }
    if ok { atomicAdd(&mp_ctrl[gw(G_PLANNED)], 1u); }
    if ok && total > 0u { atomicAdd(&mp_ctrl[gw(G_ROUNDS)], 1u); }
    atomicStore(&mp_ctrl[gw(G_DONE)], 0u);
    atomicStore(&mp_ctrl[gw(G_WGS)], all_wgs);
    atomicStore(&mp_ctrl[gw(G_K)], k);
}

// After a workgroup's last step: the round's last workgroup to finish plans the next round,
// unless the chunk ends here (the next submission's mp_plan plans it then). Every append of
// the round precedes the plan: each workgroup's storageBarrier (naga: a device-scope
// acquire-release fence on Vulkan) comes before its count of finished workgroups, and the last
// one's after it (docs/scheduler.md 5.1). `round`: the workgroup's copy of the plan's words,
// read when it started (the round's G_WGS, G_K, G_CHUNK).
fn finish_workgroup(lid: u32, round: array<u32, R_WORDS>) {
    storageBarrier();
    if lid == 0u {
        let done = atomicAdd(&mp_ctrl[gw(G_DONE)], 1u) + 1u;
        wg_last = select(0u, 1u, done == round[R_ALL]);
    }
    if workgroupUniformLoad(&wg_last) == 0u { return; }
    storageBarrier();
    let k = round[R_K] + 1u;
    if lid == 0u && k < round[R_CHUNK] { plan_round(k); }
}

// A round's dispatch of several procedures (dispatch group g): every procedure's workgroups of
// the group (C_WGS of each), in the group's order (ORDER: procedure order, or the sinks first),
// so the round costs one indirect dispatch for them instead of one each. Lanes read every
// procedure's round words and the round's own at once (one round trip), then lane 0 finds this
// workgroup's procedure among the group's in workgroup memory and leaves its round copy in
// `wg_round`. Returns the procedure and the workgroup's index among that procedure's workgroups.
var<workgroup> wg_pick: vec2<u32>;
var<workgroup> wg_rounds: array<u32, 3u * NQ + 3u>;
fn mp_pick(lid: u32, w: u32, g: u32) -> vec2<u32> {
    if lid < 3u * NQ + 3u {
        // R_COUNT, R_RUN, R_WGS of procedure lid / 3, then the round's R_ALL, R_K, R_CHUNK.
        let q = min(lid / 3u, NQ - 1u);
        let j = select(lid % 3u, lid - 3u * NQ + R_ALL, lid >= 3u * NQ);
        wg_rounds[lid] = atomicLoad(&mp_ctrl[round_word(q, j)]);
    }
    workgroupBarrier();
    if lid == 0u {
        var first = 0u;
        var pick = NQ;
        var last = 0u;
        for (var i = 0u; i < NQ; i++) {
            let q = ORDER[i];
            if GROUP[q] != g { continue; }
            last = q;
            let n = wg_rounds[3u * q + R_WGS];
            if w < first + n { pick = q; break; }
            first += n;
        }
        // A workgroup past the group's workgroups (none: the dispatch's size and C_WGS come
        // from the same plan) runs no input of its group's last procedure but still counts
        // itself finished, so the round still ends and is planned.
        let found = pick < NQ;
        let q = select(last, pick, found);
        wg_pick = vec2<u32>(q, select(0u, w - first, found));
        for (var j = 0u; j < R_ALL; j++) { wg_round[j] = wg_rounds[3u * q + j]; }
        for (var j = R_ALL; j < R_WORDS; j++) { wg_round[j] = wg_rounds[3u * NQ + j - R_ALL]; }
        if !found {
            wg_round[R_COUNT] = 0u;
            wg_round[R_RUN] = 0u;
        }
    }
    return workgroupUniformLoad(&wg_pick);
}

// Fused rounds (`MultipassConfig::fused_rounds`): every procedure in one dispatch group, run
// through `sched_execute`'s switch. Other groups of several procedures have an entry point
// `mp_group_<g>` each (generated, scheduler/src/multipass/wgsl.rs) that reaches only its own
// procedures' bodies, so the driver sizes its registers for them alone.
@compute @workgroup_size(256)
fn mp_round(@builtin(local_invocation_index) lid: u32, @builtin(workgroup_id) wid: vec3<u32>) {
    let pick = mp_pick(lid, wid.x, 0u);
    run_procedure(pick.x, lid, pick.y, true);
}
