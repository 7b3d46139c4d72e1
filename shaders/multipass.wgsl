// Multi-pass baseline (Patney & Owens 2008): rounds of one dispatch per procedure with input;
// each input item owns fixed output slots per target, flagged when used; a prefix sum over the
// flags compacts them into the next round's inputs. Rounds are planned on the device (indirect
// dispatch); an empty round dispatches zero workgroups.
// Generated before this file: tables, procedures, `mp_in_*` / `mp_emit_*` accessors,
// `sched_execute`, `enqueue_*`, and the per-procedure / per-target entry points.

// ---- mp_ctrl layout; host twin: scheduler/src/multipass/layout.rs ----
const CSTRIDE: u32 = 8u;
const C_COUNT: u32 = 0u;  // inputs of the current round
const C_PEAK: u32 = 1u;
const C_EXEC: u32 = 2u;
const C_EMITS: u32 = 3u;  // output slots of this round for this target
const C_NEXT: u32 = 4u;   // carried inputs + compacted outputs = inputs of the next round
const C_RUN: u32 = 5u;    // inputs this round runs (all but in a partial round)
const C_KEEP: u32 = 6u;   // inputs this round carries, unrun, to the front of the next
fn cw(q: u32, i: u32) -> u32 { return q * CSTRIDE + i; }
fn gw(i: u32) -> u32 { return NQ * CSTRIDE + i; }
const G_ROUNDS: u32 = 0u;
const G_ERROR: u32 = 1u;
const G_ERR_A: u32 = 2u;
const G_ERR_B: u32 = 3u;
const G_HALT: u32 = 4u;
const G_PLANNED: u32 = 5u; // plans that let their round run, for the host's parity
const G_PARTIAL: u32 = 6u; // partial rounds (scheduler/src/multipass/partial.rs)
fn off_w(p: u32, t: u32) -> u32 { return NQ * CSTRIDE + 8u + p * NQ + t; }

const ERR_EMIT: u32 = 1u;
const ERR_OVERFLOW: u32 = 2u;

// ---- params; host twin: MultipassParams ----
fn q_cap(q: u32) -> u32 { return params[8u + q * 8u]; }
fn q_in_base(q: u32) -> u32 { return params[9u + q * 8u]; }
fn q_emit_base(q: u32) -> u32 { return params[10u + q * 8u]; }
fn q_eflag_base(q: u32) -> u32 { return params[11u + q * 8u]; }
fn q_sum_base(q: u32) -> u32 { return params[12u + q * 8u]; }
// 1 when queue q is at its capacity limit: a round it cannot hold runs in part instead of
// halting for growth.
fn q_at_limit(q: u32) -> bool { return params[13u + q * 8u] != 0u; }

const SCAN_BLOCK: u32 = 1024u; // flags per scan workgroup: 256 threads x 4

@group(0) @binding(0) var<storage, read_write> mp_ctrl: array<atomic<u32>>;
@group(0) @binding(1) var<storage, read_write> items_in: array<vec4<u32>>;
@group(0) @binding(2) var<storage, read_write> items_out: array<vec4<u32>>;
@group(0) @binding(3) var<storage, read_write> emit: array<vec4<u32>>;
@group(0) @binding(4) var<storage, read_write> emit_flags: array<u32>;
@group(0) @binding(5) var<storage, read_write> sums: array<u32>;
@group(0) @binding(6) var<storage, read> params: array<u32>;
// Group 2: bound only to mp_plan, so no dispatch reads its own arguments as storage.
@group(2) @binding(0) var<storage, read_write> indirect: array<u32>;


var<workgroup> wg_n: u32;
var<workgroup> wg_k: u32;
var<workgroup> wg_item_emits: array<atomic<u32>, 256u * NQ>;
var<workgroup> wg_sum: array<u32, 256>;
var<private> sched_proc: u32;
var<private> sched_item: u32;
var<private> sched_slot: u32;
var<private> sched_active: bool;

fn sched_raise(code: u32, a: u32, b: u32) {
    if atomicExchange(&mp_ctrl[gw(G_ERROR)], code) == 0u {
        atomicStore(&mp_ctrl[gw(G_ERR_A)], a);
        atomicStore(&mp_ctrl[gw(G_ERR_B)], b);
    }
    atomicStore(&mp_ctrl[gw(G_HALT)], 1u);
}

// The output slot (index within target t's emit region) for this item's next item to t.
fn sched_emit_slot(t: u32) -> u32 {
    let e = EMITS[sched_proc * NQ + t];
    let j = atomicAdd(&wg_item_emits[sched_slot * NQ + t], 1u);
    if j >= e {
        sched_raise(ERR_EMIT, sched_proc, t);
        return 0xffffffffu;
    }
    return atomicLoad(&mp_ctrl[off_w(sched_proc, t)]) + sched_item * e + j;
}

fn set_args(slot: u32, x: u32) {
    indirect[slot * 3u] = x;
    indirect[slot * 3u + 1u] = 1u;
    indirect[slot * 3u + 2u] = 1u;
}

// One thread: takes the previous round's carried and compacted counts as this round's inputs,
// lays out the output slots, and writes every dispatch size of the round. When a target cannot
// hold the round's worst case: halts (nothing run, inputs intact) for the host to grow it, or,
// when it is at its limit, runs only part of the inputs (partial.rs, the host twin) and carries
// the rest; halts with ERR_OVERFLOW when not one input fits.
@compute @workgroup_size(1)
fn mp_plan() {
    var total = 0u;
    var run: array<u32, NQ>;
    for (var q = 0u; q < NQ; q++) {
        let n = atomicLoad(&mp_ctrl[cw(q, C_NEXT)]);
        atomicStore(&mp_ctrl[cw(q, C_COUNT)], n);
        run[q] = n;
        total += n;
    }
    var ok = atomicLoad(&mp_ctrl[gw(G_HALT)]) == 0u;
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
    for (var t = 0u; t < NQ; t++) {
        var m = 0u;
        for (var p = 0u; p < NQ; p++) {
            atomicStore(&mp_ctrl[off_w(p, t)], m);
            m += run[p] * EMITS[p * NQ + t];
        }
        // A halted round leaves the whole round's worst case here, for the host's growth.
        if ok { atomicStore(&mp_ctrl[cw(t, C_EMITS)], m); }
    }
    for (var q = 0u; q < NQ; q++) {
        let n = atomicLoad(&mp_ctrl[cw(q, C_COUNT)]);
        let per_step = 256u / THREADS[q];
        let m = atomicLoad(&mp_ctrl[cw(q, C_EMITS)]);
        // Every input is visited: run, or copied to the front of the next round's inputs.
        set_args(q, select(0u, min((n + per_step - 1u) / per_step, 65535u), ok));
        set_args(NQ + q, select(0u, (m + SCAN_BLOCK - 1u) / SCAN_BLOCK, ok));
        set_args(2u * NQ + q, select(0u, 1u, ok && m > 0u));
        if ok {
            atomicMax(&mp_ctrl[cw(q, C_PEAK)], n);
            atomicAdd(&mp_ctrl[cw(q, C_EXEC)], run[q]);
            atomicStore(&mp_ctrl[cw(q, C_RUN)], run[q]);
            atomicStore(&mp_ctrl[cw(q, C_KEEP)], n - run[q]);
            // The carried inputs lead the next round; the scan of the round adds its outputs.
            atomicStore(&mp_ctrl[cw(q, C_NEXT)], n - run[q]);
        }
    }
    if ok { atomicAdd(&mp_ctrl[gw(G_PLANNED)], 1u); }
    if ok && total > 0u { atomicAdd(&mp_ctrl[gw(G_ROUNDS)], 1u); }
}

// Runs procedure q over this round's inputs, grid-stride, items_per_step items per step.
// Only the newest C_RUN inputs run (the outputs of the last rounds, so a partial round goes
// depth first and its live work stays bounded); the older ones are copied, in place, to the
// front of the next round's inputs.
fn run_procedure(q: u32, lid: u32, wid: u32, nwg: u32) {
    if lid == 0u { wg_n = atomicLoad(&mp_ctrl[cw(q, C_COUNT)]); }
    let n = workgroupUniformLoad(&wg_n);
    if lid == 0u { wg_k = atomicLoad(&mp_ctrl[cw(q, C_RUN)]); }
    let k = workgroupUniformLoad(&wg_k);
    let per_step = 256u / THREADS[q];
    let slot = lid / THREADS[q];
    let thread = lid % THREADS[q];
    for (var first = wid * per_step; first < n; first += nwg * per_step) {
        let idx = first + slot;
        let keep = n - k;
        let live = idx >= keep && idx < n;
        if idx < keep {
            let at = q_in_base(q) + idx * WORDS[q];
            for (var w = thread; w < WORDS[q]; w += THREADS[q]) { mp_out_store_word(at + w, mp_in_load_word(at + w)); }
        }
        for (var t = thread; t < NQ; t += THREADS[q]) { atomicStore(&wg_item_emits[slot * NQ + t], 0u); }
        if live {
            // Clear this item's output flags before anything is emitted.
            for (var t = 0u; t < NQ; t++) {
                let e = EMITS[q * NQ + t];
                let first_slot = atomicLoad(&mp_ctrl[off_w(q, t)]) + (idx - keep) * e;
                for (var j = thread; j < e; j += THREADS[q]) { emit_flags[q_eflag_base(t) + first_slot + j] = 0u; }
            }
        }
        workgroupBarrier();
        storageBarrier();
        sched_proc = q;
        sched_item = idx - keep;
        sched_slot = slot;
        sched_active = live;
        sched_execute(q, q_in_base(q) + idx * WORDS[q], Invocation(thread, slot, live, THREADS[q]));
        workgroupBarrier();
    }
}

// Exclusive-scan machinery over target t's output flags, in blocks of SCAN_BLOCK.
fn flags4(t: u32, i: u32, m: u32) -> vec4<u32> {
    var f = vec4<u32>(0u);
    for (var k = 0u; k < 4u; k++) {
        if i + k < m { f[k] = emit_flags[q_eflag_base(t) + i + k]; }
    }
    return f;
}

// Inclusive scan of wg_sum across the workgroup (Hillis-Steele); returns this thread's value.
fn workgroup_inclusive_scan(lid: u32, v: u32) -> u32 {
    wg_sum[lid] = v;
    workgroupBarrier();
    var acc = v;
    for (var d = 1u; d < 256u; d <<= 1u) {
        var add = 0u;
        if lid >= d { add = wg_sum[lid - d]; }
        workgroupBarrier();
        acc += add;
        wg_sum[lid] = acc;
        workgroupBarrier();
    }
    return acc;
}

fn scan_reduce(t: u32, lid: u32, b: u32) {
    let m = atomicLoad(&mp_ctrl[cw(t, C_EMITS)]);
    let f = flags4(t, b * SCAN_BLOCK + lid * 4u, m);
    let total = workgroup_inclusive_scan(lid, f.x + f.y + f.z + f.w);
    if lid == 255u { sums[q_sum_base(t) + b] = total; }
}

fn scan_blocks(t: u32, lid: u32) {
    let m = atomicLoad(&mp_ctrl[cw(t, C_EMITS)]);
    let nb = (m + SCAN_BLOCK - 1u) / SCAN_BLOCK;
    var carry = 0u;
    for (var c = 0u; c < nb; c += 256u) {
        var v = 0u;
        if c + lid < nb { v = sums[q_sum_base(t) + c + lid]; }
        let inc = workgroup_inclusive_scan(lid, v);
        if c + lid < nb { sums[q_sum_base(t) + c + lid] = carry + inc - v; }
        carry += wg_sum[255];
        workgroupBarrier();
    }
    if lid == 0u { atomicStore(&mp_ctrl[cw(t, C_NEXT)], atomicLoad(&mp_ctrl[cw(t, C_KEEP)]) + carry); }
}

fn scan_scatter(t: u32, lid: u32, b: u32) {
    let m = atomicLoad(&mp_ctrl[cw(t, C_EMITS)]);
    let i = b * SCAN_BLOCK + lid * 4u;
    let f = flags4(t, i, m);
    let own = f.x + f.y + f.z + f.w;
    let keep = atomicLoad(&mp_ctrl[cw(t, C_KEEP)]);
    var dst = keep + sums[q_sum_base(t) + b] + workgroup_inclusive_scan(lid, own) - own;
    for (var k = 0u; k < 4u; k++) {
        if f[k] != 0u {
            let src = q_emit_base(t) + (i + k) * WORDS[t];
            let to = q_in_base(t) + dst * WORDS[t];
            if WORDS[t] % 4u == 0u {
                for (var w = 0u; w < WORDS[t]; w += 4u) { mp_out_store_vec4(to + w, mp_emit_load_vec4(src + w)); }
            } else {
                for (var w = 0u; w < WORDS[t]; w++) { mp_out_store_word(to + w, mp_emit_load_word(src + w)); }
            }
            dst += 1u;
        }
    }
}
