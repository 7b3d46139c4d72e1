// Device-driven multi-pass (Patney & Owens 2008, without their read-back per round): rounds of
// one indirect dispatch per dispatch group (each procedure alone; all of them, fused rounds,
// `mp_round` below; or the producers and the sinks apart, `mp_group_<g>`),
// every round of a submission recorded up front and sized on the device. Compaction is fused
// into the producing pass, as in the host-driven variant (`multipass_host.wgsl`): `enqueue_<t>`
// appends the item straight into queue t's region of the next round's input buffer with one
// atomicAdd on t's count, so a round has no flags, no scan and no scatter.
// No workgroup waits for the others: a round's appends size the next round's dispatch as they
// go (an append that begins a new step of items adds one workgroup to the next round's
// indirect arguments), and every workgroup of a round computes the round's plan itself from
// the counts its round starts with (`mp_begin`), which no workgroup of the round changes: the
// round's inputs are in one of three count windows, its appends go to the next, and it clears
// the one after. So a workgroup ends when its items do, with no fence and no count of finished
// workgroups (docs/scheduler.md 5.1). A chunk's first round is sized by `mp_plan`. An empty
// queue gets 0 workgroups; a round with no inputs dispatches nothing, so it and every round
// after it in the chunk run nothing. Order within a queue is not kept.
// Generated before this file: tables, procedures, `mp_in_*` / `mp_out_*` accessors,
// `sched_execute`, `mp_execute` (item i of queue q's region) and `mp_word_at` (word w of it),
// both in the run's item layout (scheduler/src/item_layout.rs), `enqueue_*`, and the
// per-procedure entry points, each with its own copy of `run_procedure` (multipass_run.wgsl).

// ---- mp_ctrl layout; host twin: scheduler/src/multipass/layout.rs ----
const CSTRIDE: u32 = 9u;
const C_PEAK: u32 = 0u;
const C_EXEC: u32 = 1u;
const C_EMITS: u32 = 2u;  // worst-case outputs for this target of the round that halted
const C_APPEND: u32 = 3u; // + window (0, 1, 2): items appended to the window's inputs
const C_CARRY: u32 = 6u;  // + window: inputs carried, unrun, to the front of the window's inputs
fn cw(q: u32, i: u32) -> u32 { return q * CSTRIDE + i; }
fn gw(i: u32) -> u32 { return NQ * CSTRIDE + i; }
const G_ROUNDS: u32 = 0u;
const G_ERROR: u32 = 1u;
const G_ERR_A: u32 = 2u;
const G_ERR_B: u32 = 3u;
const G_HALT: u32 = 4u;
const G_PARTIAL: u32 = 5u; // partial rounds (scheduler/src/multipass/partial.rs)
const G_RAN: u32 = 6u;     // rounds of the chunk that ran: round G_RAN's inputs are pending
const G_BASE: u32 = 7u;    // the count window of the chunk's first round's inputs
const G_CHUNK: u32 = 8u;   // rounds in the chunk (the host's): round G_CHUNK is not sized

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
// Group 2: the arguments of the next round, round k's dispatch group g's at slot
// (k / 2) x NQ + g of buffer k % 2. Round k's dispatches read theirs from buffer k % 2 and have
// buffer (k + 1) % 2 bound here, so no dispatch reads its own arguments as storage. `mp_k.x`:
// the round's index within its chunk (a dynamic offset per round).
@group(2) @binding(0) var<storage, read_write> indirect: array<atomic<u32>>;
@group(2) @binding(1) var<uniform> mp_k: vec4<u32>;

// Workgroups of procedure q in a round of n inputs: one per step of items (2^STEP_SHIFT[q]), at
// most its share of its group's dispatch (MAX_WGS[q]; past that, grid-stride), so every
// argument is valid with wgpu's indirect validation off.
fn wgs_for(q: u32, n: u32) -> u32 {
    return min((n + (1u << STEP_SHIFT[q]) - 1u) >> STEP_SHIFT[q], MAX_WGS[q]);
}
fn args_x(k: u32, g: u32) -> u32 { return ((k / 2u) * NQ + g) * 3u; }

// What this workgroup runs (`mp_begin`): its procedure, its index among that procedure's
// workgroups, the procedure's inputs this round (0: nothing to run), how many of the oldest of
// them are carried unrun, and its workgroups.
struct Pick {
    proc: u32,
    index: u32,
    count: u32,
    keep: u32,
    wgs: u32,
}
var<workgroup> wg_pick: Pick;
// What the appends of this workgroup need: per target t its carried inputs (`W_KEEP + t`, the
// front of its next-round region), then the next round's window, index and the chunk's length.
const W_KEEP: u32 = 0u;
const W_WIN: u32 = NQ;
const W_K: u32 = NQ + 1u;
const W_CHUNK: u32 = NQ + 2u;
var<workgroup> wg_plan: array<u32, NQ + 3u>;
// The words every workgroup loads at its start: per queue its three windows' appends and
// carries, then G_HALT, G_BASE, G_CHUNK.
var<workgroup> wg_words: array<u32, 6u * NQ + 3u>;
var<workgroup> wg_item_emits: array<atomic<u32>, 256u * NQ>;
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
// Slots start after the inputs the round carries to the front of t's next inputs. An append
// that begins a step of t's items (every 256 / sched_threads(t)-th slot) adds a workgroup to t's
// dispatch group in the next round's arguments, so the next round is sized when this one ends.
fn sched_append_slot(t: u32) -> u32 {
    let j = atomicAdd(&wg_item_emits[sched_slot * NQ + t], 1u);
    if j >= sched_emits(sched_proc * NQ + t) {
        sched_raise(ERR_EMIT, sched_proc, t);
        return 0xffffffffu;
    }
    let at = wg_plan[W_KEEP + t] + atomicAdd(&mp_ctrl[cw(t, C_APPEND + wg_plan[W_WIN])], 1u);
    if at >= q_cap(t) {
        sched_raise(ERR_ROOM, t, at);
        return 0xffffffffu;
    }
    let k = wg_plan[W_K];
    let step = at >> STEP_SHIFT[t];
    if at == step << STEP_SHIFT[t] && step < MAX_WGS[t] && k < wg_plan[W_CHUNK] {
        atomicAdd(&indirect[args_x(k, GROUP[t])], 1u);
    }
    return at;
}

// The first round of a chunk (its index 0), sized by one thread before it from its inputs'
// window (G_BASE); it clears the window the round appends to.
@compute @workgroup_size(1)
fn mp_plan() {
    let win = atomicLoad(&mp_ctrl[gw(G_BASE)]);
    var group_wgs: array<u32, NQ>;
    for (var q = 0u; q < NQ; q++) {
        let n = atomicLoad(&mp_ctrl[cw(q, C_APPEND + win)]) + atomicLoad(&mp_ctrl[cw(q, C_CARRY + win)]);
        group_wgs[GROUP[q]] += wgs_for(q, n);
        atomicStore(&mp_ctrl[cw(q, C_APPEND + (win + 1u) % 3u)], 0u);
    }
    for (var g = 0u; g < NG; g++) {
        atomicStore(&indirect[args_x(0u, g)], group_wgs[g]);
        atomicStore(&indirect[args_x(0u, g) + 1u], 1u);
        atomicStore(&indirect[args_x(0u, g) + 2u], 1u);
    }
}

// The round's plan, the same in every workgroup of the round: each computes it from the words
// its round starts with (`mp_begin`), which no workgroup of the round changes. The round's
// inputs are in its window; when a target cannot hold the round's worst case the round halts
// (nothing run, inputs intact) for the host to grow it, or, when the target is at its limit,
// runs only part of the inputs (partial.rs, the host twin) and carries the rest;
// ERR_OVERFLOW when not one input fits. Lanes q < NQ work out queue q's inputs, workgroups
// (`wgs_for`: the sizes the round before gave this dispatch) and worst case as a target (each
// from every queue's inputs, so no barrier between), and flag a partial round (1) or an
// overflow (2); lane 0 then plans (`plan_round`).
var<workgroup> wg_cnt: array<u32, NQ>;
var<workgroup> wg_wgs: array<u32, NQ>;
var<workgroup> wg_worst: array<u32, NQ>;
var<workgroup> wg_flags: atomic<u32>;
// Lane 0's plan: the inputs each queue runs this round (its count, or fewer in a partial
// round), and a partial round's room used per target. In workgroup memory, not in lane 0's
// private arrays: the driver sized every kernel's registers for the plan's unrolled loops
// (DiceShade's entry point 124 registers with it, 64 without; docs/results.md, 2026-12-05
// (sixth session)), though the plan runs once per workgroup in one lane.
var<workgroup> wg_run: array<u32, NQ>;
var<workgroup> wg_used: array<u32, NQ>;

// Lane 0: the round's plan from `wg_cnt`, `wg_worst` and `flags` (the serial part only when a
// round is partial or refused), then workgroup `w` of dispatch group `g`'s procedure (the
// group's procedures in ORDER, each with its workgroups). Workgroup 0 of the round's first
// dispatch group with workgroups keeps the round's books: statistics, the next round's
// carried counts and arguments' other words, the window after next cleared, or, for a round
// that halts, the error and every target's worst case for the host's growth.
fn plan_round(w: u32, g: u32, flags: u32) {
    let halt = wg_words[6u * NQ];
    let base = wg_words[6u * NQ + 1u];
    let chunk = wg_words[6u * NQ + 2u];
    let k = mp_k.x;
    let win = (base + k) % 3u;
    var total = 0u;
    for (var q = 0u; q < NQ; q++) { total += wg_cnt[q]; }
    var ok = halt == 0u;
    let partial = (flags & 1u) != 0u;
    var over = (flags & 2u) != 0u;
    // The overflow to report: the first target that cannot grow its way out, else, when no
    // input fits a partial round, the at-limit target with the largest worst case.
    var over_t = 0u;
    var over_m = 0u;
    if ok && over {
        for (var t = 0u; t < NQ; t++) {
            let m = wg_worst[t];
            if !(q_at_limit(t) && m > q_cap(t) / 2u) && m > q_cap(t) {
                over_t = t;
                over_m = m;
                break;
            }
        }
    }
    if ok && !over && partial {
        for (var t = 0u; t < NQ; t++) {
            let m = wg_worst[t];
            if q_at_limit(t) && m > q_cap(t) / 2u && m > over_m {
                over_t = t;
                over_m = m;
            }
        }
        // Last procedure first: each runs as many inputs as keep every target within half its
        // capacity, and at least one when one fits (partial.rs says why).
        for (var t = 0u; t < NQ; t++) { wg_used[t] = wg_run[t]; }
        var any = false;
        for (var i = 0u; i < NQ; i++) {
            let p = NQ - 1u - i;
            var hard = wg_run[p];
            var soft = wg_run[p];
            for (var t = 0u; t < NQ; t++) {
                let grow = sched_emits(p * NQ + t);
                let shrink = select(0u, 1u, t == p);
                if grow > shrink {
                    hard = min(hard, (q_cap(t) - wg_used[t]) / (grow - shrink));
                    let half = q_cap(t) / 2u;
                    soft = min(soft, select(0u, half - wg_used[t], half > wg_used[t]) / (grow - shrink));
                }
            }
            let r = max(soft, min(hard, 1u));
            wg_run[p] = r;
            for (var t = 0u; t < NQ; t++) { wg_used[t] += r * sched_emits(p * NQ + t); }
            wg_used[p] -= r;
            any = any || r > 0u;
        }
        over = !any;
    }
    // Halts for growth (or fails) on an overflow, unless an error has halted the run already.
    let refused = ok && over;
    ok = ok && !over;
    // This workgroup's procedure: the group's procedures in ORDER, each with its workgroups.
    var first = 0u;
    var pick = NQ;
    var book_g = NG;
    for (var i = 0u; i < NQ; i++) {
        let q = ORDER[i];
        let n = wg_wgs[q];
        if n > 0u && book_g == NG { book_g = GROUP[q]; }
        if GROUP[q] != g || pick < NQ { continue; }
        if w < first + n { pick = q; } else { first += n; }
    }
    let nk = k + 1u;
    let next = (win + 1u) % 3u;
    if w == 0u && g == book_g {
        if refused {
            if atomicExchange(&mp_ctrl[gw(G_ERROR)], ERR_OVERFLOW) == 0u {
                atomicStore(&mp_ctrl[gw(G_ERR_A)], over_t);
                atomicStore(&mp_ctrl[gw(G_ERR_B)], over_m);
            }
            atomicStore(&mp_ctrl[gw(G_HALT)], 1u);
            // The whole round's worst case, for the host's growth.
            for (var t = 0u; t < NQ; t++) { atomicStore(&mp_ctrl[cw(t, C_EMITS)], wg_worst[t]); }
        }
        if ok {
            for (var q = 0u; q < NQ; q++) {
                atomicMax(&mp_ctrl[cw(q, C_PEAK)], wg_cnt[q]);
                atomicAdd(&mp_ctrl[cw(q, C_EXEC)], wg_run[q]);
                let keep = wg_cnt[q] - wg_run[q];
                // The carried inputs lead the next round's; its appends go after them.
                atomicStore(&mp_ctrl[cw(q, C_CARRY + next)], keep);
                atomicStore(&mp_ctrl[cw(q, C_APPEND + (win + 2u) % 3u)], 0u);
                if keep > 0u && nk < chunk {
                    atomicAdd(&indirect[args_x(nk, GROUP[q])], wgs_for(q, keep));
                }
            }
            if nk < chunk {
                for (var h = 0u; h < NG; h++) {
                    atomicStore(&indirect[args_x(nk, h) + 1u], 1u);
                    atomicStore(&indirect[args_x(nk, h) + 2u], 1u);
                }
            }
            if partial { atomicAdd(&mp_ctrl[gw(G_PARTIAL)], 1u); }
            if total > 0u { atomicAdd(&mp_ctrl[gw(G_ROUNDS)], 1u); }
            atomicMax(&mp_ctrl[gw(G_RAN)], nk);
        }
    }
    for (var t = 0u; t < NQ; t++) { wg_plan[W_KEEP + t] = wg_cnt[t] - wg_run[t]; }
    wg_plan[W_WIN] = next;
    wg_plan[W_K] = nk;
    wg_plan[W_CHUNK] = chunk;
    // A workgroup with nothing to run (a refused round, or past its group's workgroups, which
    // the sizes rule out) gets its group's last procedure with no inputs.
    let found = ok && pick < NQ;
    let q = select(min(pick, NQ - 1u), pick, found);
    wg_pick = Pick(q, w - first, select(0u, wg_cnt[q], found), wg_cnt[q] - wg_run[q], wg_wgs[q]);
}

// The start of every workgroup of a round: lanes load the round's words at once (one round
// trip), work out each queue's share in parallel, lane 0 plans (`plan_round`), and every lane
// gets the workgroup's `Pick`.
fn mp_begin(lid: u32, w: u32, g: u32) -> Pick {
    if lid < 6u * NQ {
        // Queue lid / 6's appends (j < 3) and carries (j >= 3) of window j % 3.
        wg_words[lid] = atomicLoad(&mp_ctrl[cw(lid / 6u, C_APPEND + lid % 6u)]);
    } else if lid < 6u * NQ + 3u {
        let j = lid - 6u * NQ;
        wg_words[lid] = atomicLoad(&mp_ctrl[gw(select(select(G_CHUNK, G_BASE, j == 1u), G_HALT, j == 0u))]);
    } else if lid == 255u {
        atomicStore(&wg_flags, 0u);
    }
    workgroupBarrier();
    if lid < NQ {
        // Every queue's inputs (for the worst case), this one's kept.
        let win = (wg_words[6u * NQ + 1u] + mp_k.x) % 3u;
        var m = 0u;
        for (var p = 0u; p < NQ; p++) {
            let n = wg_words[p * 6u + win] + wg_words[p * 6u + 3u + win];
            m += n * sched_emits(p * NQ + lid);
            if p == lid {
                wg_cnt[lid] = n;
                wg_run[lid] = n;
                wg_wgs[lid] = wgs_for(lid, n);
            }
        }
        wg_worst[lid] = m;
        if q_at_limit(lid) && m > q_cap(lid) / 2u {
            atomicOr(&wg_flags, 1u);
        } else if m > q_cap(lid) {
            atomicOr(&wg_flags, 2u);
        }
    }
    workgroupBarrier();
    if lid == 0u { plan_round(w, g, atomicLoad(&wg_flags)); }
    return workgroupUniformLoad(&wg_pick);
}

// Fused rounds (`MultipassConfig::fused_rounds`): every procedure in one dispatch group, run
// through `sched_execute`'s switch. Other groups of several procedures have an entry point
// `mp_group_<g>` each (generated, scheduler/src/multipass/wgsl.rs) that reaches only its own
// procedures' bodies, so the driver sizes its registers for them alone.
@compute @workgroup_size(256)
fn mp_round(@builtin(local_invocation_index) lid: u32, @builtin(workgroup_id) wid: vec3<u32>) {
    let pick = mp_begin(lid, wid.x, 0u);
    run_procedure(pick.proc, pick, lid);
}
