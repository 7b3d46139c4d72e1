// Persistent megakernel: every workgroup loops, claiming a batch from one procedure queue,
// running it, and publishing what it emitted, until no work is left in this launch.
// The protocol and why it is correct under WGSL's relaxed atomics: docs/scheduler.md.
// Generated code before this file: NQ/THREADS/WORDS/EMITS tables, ITEMS_PLANAR, the
// procedures, the `sched_slot_*` and `sched_ob_*` word and vec4 accessors over `slots` and
// `outbox`, `sched_execute`, `mk_execute` / `mk_outbox_item` / `mk_outbox_stride` (where items
// are in the program's item layout: scheduler/src/item_layout.rs), and `enqueue_*`.

// ---- ctrl layout (u32 words); host twin: scheduler/src/megakernel/layout.rs ----
// Each word that many workgroups touch every turn has a 128-byte L2 line of its own (32 words):
// a queue's reserve, head, count and budget; pending, stop, the FIFO sequence and the idle
// count. Every probe loads the counts and pending, every claim and publish adds to them; on one
// line the atomics queued behind the loads (H200: binary tree 0.222 -> 0.201 ms, deep 2.27 ->
// 1.87; docs/results.md, 2026-12-02, "A cheaper megakernel turn").
const QSTRIDE: u32 = 128u;
const Q_RESERVE: u32 = 0u;   // tickets handed to producers (linear within a launch)
const Q_HEAD: u32 = 32u;   // tickets handed to consumers
const Q_COUNT: u32 = 64u;  // written, unclaimed items (i32; may dip below 0 transiently)
const Q_BUDGET: u32 = 96u; // tickets appended + worst-case tickets promised to running batches
const Q_PEAK: u32 = 97u;   // most items waiting at once
const Q_EXECUTED: u32 = 98u;
const Q_BATCHES: u32 = 99u;
const Q_BLOCKED: u32 = 100u; // 1 when a batch was refused for lack of room in this queue
const Q_DEMAND: u32 = 101u; // largest worst-case output to this queue of a batch refused for room
// Q_KEPT = 102: written only by the device compaction (megakernel_compact.wgsl)
const Q_LOCAL: u32 = 103u; // items run from the workgroup's local queue (never ticketed)
fn gw(i: u32) -> u32 { return NQ * QSTRIDE + i; }
const G_PENDING: u32 = 0u;   // items appended and neither processed nor abandoned in this launch
const G_STOP: u32 = 32u;
const G_ERROR: u32 = 33u;
const G_ERR_A: u32 = 34u;
const G_ERR_B: u32 = 35u;
const G_IDLE: u32 = 36u;
const G_SEQ: u32 = 64u;
const G_ABANDONED: u32 = 37u;
const G_PROBE_STARTED: u32 = 38u;
const G_PROBE_FINISHED: u32 = 39u;
const G_PROBE_RESIDENT: u32 = 40u;
const G_ITER_EXITS: u32 = 41u;
// G_LOST = 42: written only by the device compaction (megakernel_compact.wgsl)
const G_IDLE_NOW: u32 = 96u; // workgroups idle right now (LOCAL only)
// Turn anatomy (TURN_ANATOMY; host twin: scheduler/src/megakernel/anatomy.rs): per phase, the
// leader's (lane 0's) count of global memory operations or loop trips on the turn's critical
// path, kept in lane 0's registers and added once when the workgroup leaves its loop.
const G_AN: u32 = 128u;
const AN_TURNS: u32 = 0u;    // loop turns (batches, idle turns and the exit turn)
const AN_CLAIM: u32 = 1u;    // global atomics of the claim (every turn, idle ones included)
const AN_WAIT: u32 = 2u;     // flag polls of the slowest lane, summed over batches
const AN_EXEC: u32 = 3u;     // workgroup steps of the bodies
const AN_ENQUEUE: u32 = 4u;  // direct enqueue: per-item ticket atomics (all lanes)
const AN_RESERVE: u32 = 5u;  // global atomics after the batch, before the copy
const AN_COPY: u32 = 6u;     // copy loop trips of a lane
const AN_PUBLISH: u32 = 7u;  // flag-store trips of a lane + the leader's global atomics
const AN_WORDS: u32 = 8u;

const ERR_EMIT: u32 = 1u;

// ---- params (read-only words); host twin: MegakernelParams ----
const P_MAX_ITERS: u32 = 0u;
const P_SPIN: u32 = 1u;
const P_PROBE: u32 = 2u;
const P_POLICY: u32 = 3u;      // 0 = priority order, 1 = oldest batch first (FIFO)
const P_OUTBOX_STRIDE: u32 = 4u;
const P_PAUSE_LINK: u32 = 5u;   // always 0: the idle pause's chain of loads (idle_pause)
const P_IDLE_BACKOFF: u32 = 6u; // longest pause of an idle workgroup between polls (load trips)
const P_LOCAL_BASE: u32 = 7u;   // first word of the workgroups' local areas in `slots` (LOCAL)
fn q_cap(q: u32) -> u32 { return params[8u + q * 4u]; }
fn q_slot_base(q: u32) -> u32 { return params[9u + q * 4u]; }
fn q_flag_base(q: u32) -> u32 { return params[10u + q * 4u]; }
fn prio(i: u32) -> u32 { return params[8u + NQ * 4u + i]; }
fn ob_off(q: u32, t: u32) -> u32 { return params[8u + NQ * 5u + q * NQ + t]; }
// Most items a batch of q claims (host twin: `batch_items` in megakernel/claim.rs, steps x
// items per step); the outbox and the queues' slack are sized for it.
fn batch_max(q: u32) -> u32 { return params[11u + q * 4u]; }
// Items the outbox part (q, t) holds: a batch's worst-case output to t.
fn ob_cap(q: u32, t: u32) -> u32 { return batch_max(q) * sched_emits(q * NQ + t); }

const MAX_BATCH: u32 = 1024u;
const EMPTY: u32 = 0u;            // slot flag: not written yet
const CONSUMED: u32 = 0xffffffffu; // slot flag: processed; any other value: ready, = batch stamp

const CMD_IDLE: u32 = 0u;
const CMD_RUN: u32 = 1u;
const CMD_EXIT: u32 = 2u;
const CMD_LOCAL: u32 = 3u;   // run the items of local queue q held in the workgroup; the credit covers their output
const CMD_LOCAL_RESERVE: u32 = 4u; // the same, once the budget has room for what the credit does not cover
// After a local batch, the early probe is read only on every LOCAL_PROBE_EVERY-th turn (LOCAL).
const LOCAL_PROBE_EVERY: u32 = 8u;

@group(0) @binding(0) var<storage, read_write> ctrl: array<atomic<u32>>;
@group(0) @binding(2) var<storage, read_write> flags: array<atomic<u32>>;
@group(0) @binding(3) var<storage, read_write> outbox: array<vec4<u32>>;
@group(0) @binding(4) var<storage, read> params: array<u32>;

// The leader's decision for the turn, read by every lane in one workgroupUniformLoad (each is a
// barrier, a load and a barrier): x the command (CMD_*), y the queue q, z the first ticket h of
// a claimed batch, w its items n.
var<workgroup> wg_turn: vec4<u32>;
var<workgroup> wg_refused: u32;
var<workgroup> wg_stamp: u32;
var<workgroup> wg_ready: array<u32, MAX_BATCH>;
var<workgroup> wg_emit_count: array<atomic<u32>, NQ>;
var<workgroup> wg_emit_base: array<u32, NQ>;
var<workgroup> wg_emit_n: array<u32, NQ>;
var<workgroup> wg_abandoned: atomic<u32>;
var<workgroup> wg_emitted: atomic<u32>;
// The turn's probe, read by lanes in parallel before the leader decides: Q_COUNT of prio(i) in
// wg_avail[i], G_STOP and G_PENDING.
var<workgroup> wg_avail: array<i32, NQ>;
var<workgroup> wg_stop: u32;
var<workgroup> wg_pending: u32;
// Direct enqueue: the tickets this batch took, per target from sched_es_off(q * NQ + t).
var<workgroup> wg_emit_slot: array<u32, EMIT_SLOTS>;
// Local queues (LOCAL; sizes and buffers: scheduler/src/megakernel/local.rs). In the workgroup's
// area of `slots` (past every queue's slots), t's filling buffer (`sched_local_out`) holds
// wg_local_n[t] items of queue t, kept by earlier batches; while a batch runs, its emits to t
// may fill it up to wg_local_lim[t] (the count may pass the limit: the emits past it went to the
// global queue, and the count is cut back after the batch). A local batch of t runs from that
// buffer while t's other one fills (`sched_local_par`). Every held item is pending and insured:
// its room stays reserved in t's budget, so a spill never lacks a ticket.
var<workgroup> wg_local_n: array<atomic<u32>, NQ>;
var<workgroup> wg_local_lim: array<u32, NQ>;
var<workgroup> wg_local_held: array<u32, NQ>;
var<workgroup> wg_idle_now: u32;
var<workgroup> wg_local_fail: atomic<u32>;
// Per queue t (LOCAL): room in t's budget this workgroup reserved and has not promised (what its
// batches left unused), for its next local batches: in a steady run of local batches their
// promises need no budget atomic, and the leader sees whether the credit covers a batch (no
// barrier to ask the lanes). At most LOCAL_CREDIT_MAX[t]; given back at a spill. Written by
// lane t only, read by the leader between the turn's first barrier and its decision's load.
var<workgroup> wg_credit: array<u32, NQ>;

var<private> sched_proc: u32;
var<private> sched_active: bool;
var<private> sched_batch_n: u32;
var<private> sched_outbox: u32;
var<private> sched_workgroups: u32; // of this launch (GUIDED_CLAIMS)
var<private> sched_blocked: bool; // some queue refused this workgroup room in this launch
var<private> sched_pause_sink: u32;
// Statistics of the lane's own queue (lane t < NQ: queue t), added to ctrl once at exit.
var<private> st_peak: u32;
// The last batch's reserve end and head of the lane's queue, not yet folded into st_peak.
var<private> st_peak_end: u32;
var<private> st_peak_head: u32;
var<private> st_executed: u32;
var<private> st_batches: u32;
var<private> st_local: u32;
// The running batch reads its items from a local buffer (a local batch).
var<private> sched_from_local: bool;
// This workgroup's local area in `slots`, and per queue t (bit t) which of t's two buffers fills.
var<private> sched_local_wg: u32;
var<private> sched_local_par: u32;
// The leader counts itself in G_IDLE_NOW.
var<private> sched_idle_reg: bool;
var<private> an: array<u32, AN_WORDS>;
var<workgroup> wg_an_wait: atomic<u32>;

// Items waiting in the lane's queue at its last batch, into the peak.
fn fold_peak() {
    st_peak = max(st_peak, st_peak_end - min(st_peak_head, st_peak_end));
}

// The first word of t's local buffer `b` (0 or 1) in this workgroup's area.
fn sched_local_buffer(t: u32, b: u32) -> u32 {
    return sched_local_wg + LOCAL_OFF[t] + b * LOCAL_STRIDE[t];
}

// t's filling buffer, and the one a local batch of t runs from (the other).
fn sched_local_out(t: u32) -> u32 { return sched_local_buffer(t, (sched_local_par >> t) & 1u); }
fn sched_local_in(t: u32) -> u32 { return sched_local_buffer(t, ((sched_local_par >> t) & 1u) ^ 1u); }

fn an_add(k: u32, v: u32) {
    if TURN_ANATOMY { an[k] += v; }
}

// An idle workgroup's pause before it polls again: `trips` loads of the params word
// P_PAUSE_LINK (always 0), each at an index that adds the last one's value, so each waits for
// the one before (an L1 hit's latency) while its warp issues almost nothing; after the first,
// no L2 line is touched. The pause it replaced, a loop of dependent multiply-adds, likely
// issued an instruction every few clocks on the SM a busy workgroup shares (H200 deep tree
// 1.52 -> 1.35 ms; docs/scheduler.md 2.2).
fn idle_pause(trips: u32) {
    var z = 0u;
    for (var i = 0u; i < trips; i++) { z = params[P_PAUSE_LINK + z]; }
    sched_pause_sink += z;
}

// A pause of `trips` drawn from [trips / 2, trips * 3 / 2], by workgroup and turn: workgroups
// that went idle together would otherwise double their pauses in step and poll in bursts.
// `sched_hash` (generated before this file) is the project's `lowbias32` (scheduler/src/hash.rs).
fn jitter(trips: u32, wg: u32, turn: u32) -> u32 {
    return trips / 2u + sched_hash((wg * 0x9e3779b1u) ^ turn) % (trips + 1u);
}

fn sched_raise(code: u32, a: u32, b: u32) {
    if atomicExchange(&ctrl[gw(G_ERROR)], code) == 0u {
        atomicStore(&ctrl[gw(G_ERR_A)], a);
        atomicStore(&ctrl[gw(G_ERR_B)], b);
    }
    atomicStore(&ctrl[gw(G_STOP)], 1u);
}

// Generated before this file: `sched_take(t, direct) -> vec2<u32>`, the index j of this emit
// among the batch's emits to t and, for direct enqueue, its ticket of queue t (taken only for
// emits within the batch's declared limit): one lane's atomics, or on adapters with subgroups one
// atomic per subgroup (scheduler/src/megakernel/wgsl.rs, MegakernelConfig::subgroups).

// Where enqueue_<t> puts the j-th item emitted to queue t in this batch, or a raised error.
fn sched_outbox_slot(t: u32) -> u32 {
    let j = sched_take(t, false).x;
    if j >= sched_batch_n * sched_emits(sched_proc * NQ + t) {
        sched_raise(ERR_EMIT, sched_proc, t);
        return 0xffffffffu;
    }
    return mk_outbox_item(sched_proc, t, j);
}

// Direct enqueue: a ticket of queue t for the j-th item this batch emits to t, listed for
// publishing, or a raised error. The claim reserved the batch's worst case in t's budget, so the
// ticket is below t's capacity.
fn sched_direct_slot(t: u32) -> u32 {
    let js = sched_take(t, true);
    let j = js.x;
    if j >= sched_batch_n * sched_emits(sched_proc * NQ + t) {
        sched_raise(ERR_EMIT, sched_proc, t);
        return 0xffffffffu;
    }
    let s = js.y;
    wg_emit_slot[sched_es_off(sched_proc * NQ + t) + j] = s;
    return s;
}

// Generated before this file: `reserve_budget(q, n) -> bool`, which reserves room for the
// worst-case output of n items of q in every target queue, or nothing: every target's add is
// issued before any is checked (straight-line code per target, no array: one round trip
// however many targets), a refusal undoes them all, sets Q_BLOCKED of the queues without room
// and raises every target's Q_DEMAND to what the batch needed there. And `sched_refused(q)` /
// `sched_refuse(q)`, the queues that refused this workgroup room in this launch (a bitmask
// in a register where there are at most 32 queues).

// Leader only. Claims up to a batch of written items of q, of which `avail` were seen
// (Q_COUNT, read by the turn's probe), in two round trips: an optimistic decrement of the
// count (the overshoot given back, as when the probe's read is stale); then, issued together,
// the tickets from head and the room for the batch's worst case in every target. Claimed
// tickets were all reserved before, since the count only grows after items are written. A
// batch refused room is abandoned to the next launch (its slots stay published and
// unconsumed, so compaction keeps them; it leaves pending for G_ABANDONED), and this
// workgroup claims from q no more in this launch.
fn try_claim(q: u32, avail: i32) -> bool {
    if avail <= 0 || sched_refused(q) { return false; }
    var want = min(u32(avail), batch_max(q));
    if GUIDED_CLAIMS {
        // Guided self-scheduling: at most this workgroup's share of all that is pending (the
        // probe's G_PENDING, possibly stale: a heuristic only), one step's worth at least.
        let share = wg_pending / sched_workgroups + select(0u, 1u, wg_pending % sched_workgroups != 0u);
        want = min(want, max(share, WG_SIZE / THREADS[q]));
    }
    an_add(AN_CLAIM, 1u);
    let old = bitcast<i32>(atomicSub(&ctrl[q * QSTRIDE + Q_COUNT], want));
    let got = u32(clamp(old, 0, i32(want)));
    if got < want { atomicAdd(&ctrl[q * QSTRIDE + Q_COUNT], want - got); }
    if got == 0u { return false; }
    an_add(AN_CLAIM, 1u); // the head add and the budget adds, one round
    let h = atomicAdd(&ctrl[q * QSTRIDE + Q_HEAD], got);
    if !reserve_budget(q, got) {
        atomicSub(&ctrl[gw(G_PENDING)], got);
        atomicAdd(&ctrl[gw(G_ABANDONED)], got);
        sched_refuse(q);
        sched_blocked = true;
        return false;
    }
    wg_turn.y = q;
    wg_turn.z = h;
    wg_turn.w = got;
    return true;
}

// Leader only: the oldest waiting batch by its stamp, for the FIFO policy.
fn fifo_pick() -> u32 {
    var best = NQ;
    var best_stamp = CONSUMED;
    for (var q = 0u; q < NQ; q++) {
        an_add(AN_CLAIM, 1u);
        if bitcast<i32>(atomicLoad(&ctrl[q * QSTRIDE + Q_COUNT])) <= 0 { continue; }
        an_add(AN_CLAIM, 2u);
        let h = atomicLoad(&ctrl[q * QSTRIDE + Q_HEAD]);
        if h >= q_cap(q) { continue; }
        let f = atomicLoad(&flags[q_flag_base(q) + h]);
        if f != EMPTY && f < best_stamp { best = q; best_stamp = f; }
    }
    return best;
}

// Leader only (LOCAL): how many items of each target t a batch of q may keep, in wg_local_lim[t],
// and how many it holds before the batch, in wg_local_held[t]: a full region while every
// workgroup is busy; one step's worth while some are idle (one step runs them as fast as many
// workgroups would), the rest shared through the global queue. Set before the turn's decision is
// read, so a local batch needs no barrier before its bodies emit.
fn local_limits(q: u32) {
    for (var t = 0u; t < NQ; t++) {
        let held = atomicLoad(&wg_local_n[t]);
        wg_local_held[t] = held;
        var lim = held;
        if LOCAL_EDGE[q * NQ + t] != 0u {
            var want = LOCAL_CAP[t];
            if wg_idle_now != 0u { want = min(want, WG_SIZE / THREADS[t]); }
            lim = max(held, want);
        }
        wg_local_lim[t] = lim;
    }
}

fn leader_decide() -> u32 {
    an_add(AN_TURNS, 1u);
    if wg_stop != 0u { return CMD_EXIT; }
    // Work held in the workgroup runs first, in priority order: no global atomic to claim it.
    // The items are taken from the filling buffer here (put back if their room cannot be
    // reserved). Where the credit covers their worst-case output the batch starts at once;
    // else the lanes reserve the rest of the room first. A queue that emits nothing
    // (LOCAL_DEFER) waits while it holds less than a step (and than its buffer holds) and
    // other held work can run: its items lengthen no chain, and a later turn runs more of them
    // at the same cost (the deep tree's leaves took every other local turn).
    var pick = NQ;
    for (var i = 0u; i < NQ && LOCAL; i++) {
        let q = prio(i);
        let m = atomicLoad(&wg_local_n[q]);
        if m == 0u { continue; }
        if pick == NQ { pick = q; }
        if LOCAL_DEFER[q] == 0u || m >= min(WG_SIZE / THREADS[q], LOCAL_CAP[q]) {
            pick = q;
            break;
        }
    }
    if LOCAL && pick < NQ {
        let m = atomicLoad(&wg_local_n[pick]);
        wg_turn.y = pick;
        wg_turn.z = 0u;
        wg_turn.w = m;
        atomicStore(&wg_local_n[pick], 0u);
        for (var t = 0u; t < NQ; t++) {
            if m * sched_emits(pick * NQ + t) > wg_credit[t] { return CMD_LOCAL_RESERVE; }
        }
        return CMD_LOCAL;
    }
    if params[P_POLICY] == 1u {
        let q = fifo_pick();
        if q < NQ {
            an_add(AN_CLAIM, 1u);
            if try_claim(q, bitcast<i32>(atomicLoad(&ctrl[q * QSTRIDE + Q_COUNT]))) { return CMD_RUN; }
        }
    }
    // The probe read every count at once; only queues seen with work cost atomics.
    for (var i = 0u; i < NQ; i++) {
        if try_claim(prio(i), wg_avail[i]) { return CMD_RUN; }
    }
    // Nothing claimable. Pending counts every item still to run in this launch, including
    // those being produced right now, so zero means this launch is finished. Zero is final (only
    // a running batch adds to it, and a running batch's items are pending), so the probe's read,
    // taken before the claims, decides as well as a fresh one.
    if wg_pending == 0u { return CMD_EXIT; }
    if sched_blocked {
        // A queue refused this workgroup room in this launch (its batch was abandoned) and
        // nothing else is claimable: work waits for room that only growth between launches
        // can give, so end the launch.
        atomicStore(&ctrl[gw(G_STOP)], 1u);
        return CMD_EXIT;
    }
    return CMD_IDLE;
}

// Moves every item held in the workgroup's local queues to the global queues (tickets, copy,
// flags, counts), all lanes together: when the launch ends for this workgroup, or when a local
// batch finds no room for its output. The tickets are below capacity: the held items' room was
// reserved in each queue's budget when they were kept (the insurance above).
fn spill_local(lid: u32) {
    workgroupBarrier();
    if lid < NQ {
        let m = atomicLoad(&wg_local_n[lid]);
        wg_emit_n[lid] = m;
        if m > 0u { wg_emit_base[lid] = atomicAdd(&ctrl[lid * QSTRIDE + Q_RESERVE], m); }
        if wg_credit[lid] > 0u {
            atomicSub(&ctrl[lid * QSTRIDE + Q_BUDGET], wg_credit[lid]);
            wg_credit[lid] = 0u;
        }
    }
    if lid == 0u {
        wg_stamp = 2u;
        if params[P_POLICY] == 1u { wg_stamp = atomicAdd(&ctrl[gw(G_SEQ)], 1u) + 2u; }
    }
    workgroupBarrier();
    for (var t = 0u; t < NQ; t++) {
        let m = wg_emit_n[t];
        let base = wg_emit_base[t];
        let held_at = sched_local_out(t);
        for (var i = lid; i < m * sched_words(t); i += WG_SIZE) {
            if ITEMS_PLANAR {
                let plane = i / m;
                let j = i % m;
                sched_slot_store_word(q_slot_base(t) + plane * q_cap(t) + base + j,
                    sched_slot_load_word(held_at + plane * LOCAL_CAP[t] + j));
            } else {
                sched_slot_store_word(q_slot_base(t) + base * sched_words(t) + i, sched_slot_load_word(held_at + i));
            }
        }
    }
    storageBarrier();
    for (var t = 0u; t < NQ; t++) {
        for (var j = lid; j < wg_emit_n[t]; j += WG_SIZE) {
            atomicStore(&flags[q_flag_base(t) + wg_emit_base[t] + j], wg_stamp);
        }
    }
    storageBarrier();
    if lid < NQ && wg_emit_n[lid] > 0u {
        atomicAdd(&ctrl[lid * QSTRIDE + Q_COUNT], wg_emit_n[lid]);
        atomicStore(&wg_local_n[lid], 0u);
    }
    workgroupBarrier();
}

// The turn's probe, lane by lane, all in one round trip: lane i < NQ loads the count of queue
// prio(i), lane 255 G_STOP, lane 254 G_PENDING, lane 253 G_IDLE_NOW (LOCAL).
fn probe_load(lid: u32) -> u32 {
    if lid < NQ { return atomicLoad(&ctrl[prio(lid) * QSTRIDE + Q_COUNT]); }
    if lid == 255u { return atomicLoad(&ctrl[gw(G_STOP)]); }
    if lid == 254u { return atomicLoad(&ctrl[gw(G_PENDING)]); }
    if LOCAL && lid == 253u { return atomicLoad(&ctrl[gw(G_IDLE_NOW)]); }
    return 0u;
}

// What probe_load read, for the leader's decision; `own`: items of the lane's queue this
// workgroup published after the load (an early probe's), added to the count it saw. A probe read
// during a batch sees G_PENDING before the batch left it, never 0: the workgroup then leaves
// through an idle turn and an exit turn whose fresh probe reads 0.
fn probe_store(lid: u32, v: u32, own: u32) {
    if lid < NQ { wg_avail[lid] = bitcast<i32>(v + own); }
    if lid == 255u { wg_stop = v; }
    if lid == 254u { wg_pending = v; }
    if LOCAL && lid == 253u { wg_idle_now = v; }
}

// Co-residency probe: a workgroup that starts before any workgroup has finished runs at the
// same time as every workgroup that started before it. Every lane waits for lane 0 at the end,
// as in a run, where no warp leaves before its workgroup: a driver may start another workgroup
// in the registers of warps that have left.
fn probe(lid: u32) {
    if lid == 0u {
        let t = atomicAdd(&ctrl[gw(G_PROBE_STARTED)], 1u);
        if atomicLoad(&ctrl[gw(G_PROBE_FINISHED)]) == 0u {
            atomicMax(&ctrl[gw(G_PROBE_RESIDENT)], t + 1u);
        }
        for (var i = 0u; i < params[P_SPIN]; i++) {
            if atomicLoad(&ctrl[gw(G_PROBE_FINISHED)]) != 0u { break; }
        }
        atomicAdd(&ctrl[gw(G_PROBE_FINISHED)], 1u);
    }
    workgroupBarrier();
}

@compute @workgroup_size(WG_SIZE)
fn megakernel(@builtin(local_invocation_index) lid: u32, @builtin(workgroup_id) wid: vec3<u32>,
              @builtin(num_workgroups) nwg: vec3<u32>) {
    if params[P_PROBE] != 0u {
        probe(lid);
        return;
    }
    sched_workgroups = nwg.x;
    sched_outbox = wid.x * params[P_OUTBOX_STRIDE];
    sched_local_wg = params[P_LOCAL_BASE] + wid.x * LOCAL_WG_WORDS;
    if LOCAL && lid < NQ { // ordered by the probe's barrier
        atomicStore(&wg_local_n[lid], 0u);
        wg_credit[lid] = 0u;
    }
    var idle = 0u;
    var streak = 0u;
    var iter = 0u;
    var probed = false;
    // Bounded far below lavapipe's silent 65,535-iteration cut; the host relaunches if needed.
    for (; iter < params[P_MAX_ITERS]; iter++) {
        // The probe: lanes read every queue's count, the stop and pending words in parallel
        // (one round trip instead of one per queue, in turn, on the leader). After a batch it
        // was read during the batch's publish (the `early` load in step 3 below), off the path.
        if !probed {
            probe_store(lid, probe_load(lid), 0u);
            if lid == 0u { an_add(AN_CLAIM, 1u); } // the probe: one round of parallel loads
        }
        probed = false;
        workgroupBarrier();
        if lid == 0u {
            let decided = leader_decide();
            wg_turn.x = decided;
            if LOCAL {
                // Idle right now, for workgroups deciding how much to keep: only changes cost.
                let idle_now = decided == CMD_IDLE;
                if idle_now != sched_idle_reg {
                    if idle_now { atomicAdd(&ctrl[gw(G_IDLE_NOW)], 1u); } else { atomicSub(&ctrl[gw(G_IDLE_NOW)], 1u); }
                    sched_idle_reg = idle_now;
                }
                atomicStore(&wg_local_fail, 0u);
                if decided == CMD_RUN || decided >= CMD_LOCAL { local_limits(wg_turn.y); }
            }
            atomicStore(&wg_abandoned, 0u);
            atomicStore(&wg_emitted, 0u);
            if TURN_ANATOMY { atomicStore(&wg_an_wait, 0u); }
        }
        if lid < NQ { atomicStore(&wg_emit_count[lid], 0u); }
        let turn = workgroupUniformLoad(&wg_turn);
        var cmd = turn.x;
        if cmd == CMD_EXIT { break; }
        if cmd == CMD_IDLE {
            idle++;
            streak = min(streak * 2u + 1u, params[P_IDLE_BACKOFF]);
            // One warp pauses; the other warps run on to the next turn's first barrier (the
            // last one issuing the probe's stop and pending loads, only staler for it) and wait
            // there, issuing nothing. Paused by every lane, the idle workgroups sharing an SM
            // with a busy one took its issue slots (docs/scheduler.md 2.2).
            if lid < 32u { idle_pause(jitter(streak, wid.x, iter)); }
            continue;
        }
        streak = 0u;
        let q = turn.y;
        let h = turn.z;
        let n = turn.w;
        if LOCAL && cmd == CMD_LOCAL_RESERVE {
            // 0. A local batch whose worst-case output the credit does not cover: lanes in
            //    parallel reserve the shortfall in each target's budget; without room, spill
            //    what the workgroup holds and claim as usual.
            var took = 0u;
            if lid < NQ && n * sched_emits(q * NQ + lid) > wg_credit[lid] {
                took = n * sched_emits(q * NQ + lid) - wg_credit[lid];
                let old = atomicAdd(&ctrl[lid * QSTRIDE + Q_BUDGET], took);
                if old + took > q_cap(lid) { atomicStore(&wg_local_fail, 1u); }
            }
            workgroupBarrier();
            if lid == 0u { wg_refused = atomicLoad(&wg_local_fail); }
            if workgroupUniformLoad(&wg_refused) != 0u {
                if took > 0u { atomicSub(&ctrl[lid * QSTRIDE + Q_BUDGET], took); }
                if lid == 0u { atomicStore(&wg_local_n[q], n); } // put back, for the spill
                spill_local(lid);
                continue;
            }
            if lid < NQ { wg_credit[lid] += took; }
            cmd = CMD_LOCAL;
        }
        let from_local = LOCAL && cmd == CMD_LOCAL;
        sched_from_local = from_local;
        if from_local {
            // A local batch: its worst-case output in every target promised from the credit
            // (the leader saw that it covers it). It runs from the buffer it filled
            // (`sched_local_in`), while q's emits fill the other. Each item was written by an
            // emitting batch before that batch's release barrier, which every lane passed (a
            // sink's batch writes none and skips it): visible here.
            if lid < NQ { wg_credit[lid] -= n * sched_emits(q * NQ + lid); }
            sched_local_par ^= 1u << q;
        }

        // 1. Wait, bounded, for each claimed slot's producer to publish it. A slot whose wait
        //    runs out is abandoned to the compaction between launches: never lost.
        var polls = 0u;
        for (var i = lid; i < n && !from_local; i += WG_SIZE) {
            var ok = 0u;
            var s = 0u;
            for (; s < params[P_SPIN]; s++) {
                if atomicLoad(&flags[q_flag_base(q) + h + i]) != EMPTY { ok = 1u; break; }
            }
            polls += min(s + 1u, params[P_SPIN]);
            wg_ready[i] = ok;
            if ok == 0u { atomicAdd(&wg_abandoned, 1u); }
        }
        if TURN_ANATOMY && polls > 0u { atomicMax(&wg_an_wait, polls); }
        if !from_local {
            storageBarrier(); // acquire: flags seen before the payload is read
            // wg_ready is workgroup memory, which storageBarrier does not order: lanes other
            // than the one that waited read it when threads_per_item > 1.
            workgroupBarrier();
        }

        // 2. Run the batch, items_per_step items at a time.
        let per_step = WG_SIZE / THREADS[q];
        let slot = lid / THREADS[q];
        sched_proc = q;
        sched_batch_n = n;
        for (var first = 0u; first < n; first += per_step) {
            let idx = first + slot;
            sched_active = idx < n && (from_local || wg_ready[min(idx, MAX_BATCH - 1u)] != 0u);
            mk_execute(q, h + idx, Invocation(lid % THREADS[q], slot, sched_active, THREADS[q]));
            // The next step may reuse the body's workgroup memory: all threads finish this one first.
            workgroupBarrier();
        }
        // The outbox's writes visible to the whole workgroup, for the copy. Direct enqueue wrote
        // the slots themselves: the release barrier before the flags orders them, and the
        // step's workgroupBarrier above is all the workgroup needs (a device-scope fence less).
        // A sink's batch (q emits nothing) wrote neither outbox nor slots: no fence.
        if !DIRECT_ENQUEUE && !sched_is_sink(q) { storageBarrier(); }

        // 3. Reserve tickets for what was emitted: lane t for target queue t, all in parallel;
        //    lane q counts the batch in its statistics (registers, added to ctrl at exit).
        let abandoned = atomicLoad(&wg_abandoned);
        if lid < NQ {
            let t = lid;
            let promised = n * sched_emits(q * NQ + t);
            // Local emits: the count cut back to the limit; what was kept stays insured.
            var kept_new = 0u;
            if LOCAL {
                let kept = min(atomicLoad(&wg_local_n[t]), wg_local_lim[t]);
                atomicStore(&wg_local_n[t], kept);
                kept_new = kept - wg_local_held[t];
                if kept_new > 0u { atomicAdd(&wg_emitted, kept_new); }
            }
            let k = min(atomicLoad(&wg_emit_count[t]), promised - min(kept_new, promised));
            if kept_new + atomicLoad(&wg_emit_count[t]) > promised { sched_raise(ERR_EMIT, q, t); }
            wg_emit_n[t] = k;
            if k > 0u {
                // Direct enqueue took its tickets item by item; else take k now.
                var end = 0u;
                if DIRECT_ENQUEUE {
                    end = atomicLoad(&ctrl[t * QSTRIDE + Q_RESERVE]);
                } else {
                    let base = atomicAdd(&ctrl[t * QSTRIDE + Q_RESERVE], k);
                    wg_emit_base[t] = base;
                    end = base + k;
                }
                // The peak's loads are folded in at the next batch (or the exit), so that no
                // lane waits for them on the turn's path.
                fold_peak();
                st_peak_end = end;
                st_peak_head = atomicLoad(&ctrl[t * QSTRIDE + Q_HEAD]);
                atomicAdd(&wg_emitted, k);
            }
            // Unused promised room goes back, and a local batch's own insurance.
            var refund = promised - k - min(kept_new, promised - k);
            if from_local && t == q { refund += n; }
            if LOCAL {
                // Kept as credit for the next local batches, up to a cap.
                let credit = wg_credit[t] + refund;
                wg_credit[t] = min(credit, LOCAL_CREDIT_MAX[t]);
                if credit > LOCAL_CREDIT_MAX[t] {
                    atomicSub(&ctrl[t * QSTRIDE + Q_BUDGET], credit - LOCAL_CREDIT_MAX[t]);
                }
            } else if refund > 0u {
                atomicSub(&ctrl[t * QSTRIDE + Q_BUDGET], refund);
            }
            if t == q {
                if from_local { st_local += n; } else { st_executed += n - abandoned; }
                st_batches += 1u;
            }
        }
        if lid == 0u {
            // A stamp that orders batches only where the FIFO policy compares them.
            wg_stamp = 2u;
            if params[P_POLICY] == 1u { wg_stamp = atomicAdd(&ctrl[gw(G_SEQ)], 1u) + 2u; }
            if abandoned > 0u { atomicAdd(&ctrl[gw(G_ABANDONED)], abandoned); }
        }
        // The next turn's probe, issued now: its round trip overlaps the release fence and the
        // publish instead of opening the next turn. Kept in a register until the count adds
        // are issued, then completed with this batch's own published items.
        // After a local batch the next turn most likely runs held work, which the leader takes
        // before it reads any count, so the probe is read on one such turn in LOCAL_PROBE_EVERY
        // only and the others keep the last one's values (H200: the one-item chain 2.44 -> 2.36
        // us a turn, irregular tree 0.167 -> 0.164 ms; docs/results.md, 2026-12-04 (second
        // session)). Every stale value is safe: held work runs first; a stale count only makes
        // the leader try a claim (the overshoot given back), idle one turn, whose probe is
        // fresh, or, once a queue refused this workgroup room, end the launch one relaunch
        // early; a stale pending is never a false 0 (0 is final); a stop is seen within
        // LOCAL_PROBE_EVERY batches; a stale idle count only sets how much a batch keeps
        // (local_limits).
        let fresh = !from_local || iter % LOCAL_PROBE_EVERY == LOCAL_PROBE_EVERY - 1u;
        var early = 0u;
        if fresh { early = probe_load(lid); }
        // Whether the batch published anything to the global queues: always, but for a local
        // batch whose held items live in workgroup memory (LOCAL_IN_WG), where every lane reads
        // the emit counts with the barrier it needs here anyway. Such a batch that emitted
        // only held items has nothing to release or publish: its items are read by this
        // workgroup's lanes only, which its barriers order (docs/scheduler.md 2.7).
        var publishes = true;
        if LOCAL_IN_WG && from_local {
            let emit_n = workgroupUniformLoad(&wg_emit_n);
            var sum = 0u;
            for (var t = 0u; t < NQ; t++) { sum += emit_n[t]; }
            publishes = sum > 0u;
        } else {
            workgroupBarrier();
        }
        if lid == 0u {
            // Pending: + the children, - this batch, in one atomic. The children are counted
            // before they are published (the count adds below, after a storageBarrier), so
            // pending stays above zero until they run; without children it may reach zero now,
            // which is right: nothing of this launch is left to run.
            let emitted = atomicLoad(&wg_emitted);
            if emitted > n {
                atomicAdd(&ctrl[gw(G_PENDING)], emitted - n);
            } else if emitted < n {
                atomicSub(&ctrl[gw(G_PENDING)], n - emitted);
            }
            if TURN_ANATOMY {
                an_add(AN_WAIT, atomicLoad(&wg_an_wait));
                an_add(AN_EXEC, (n + per_step - 1u) / per_step);
                // The longest lane's chain (the outbox's ticket add, a refund of unused room;
                // the peak's loads are folded in at the next batch, off the path); then the
                // pending atomic and, under FIFO, the stamp.
                var chain = 0u;
                for (var t = 0u; t < NQ; t++) {
                    let k = wg_emit_n[t];
                    chain = max(chain, u32(k > 0u && !DIRECT_ENQUEUE) + u32(n * sched_emits(q * NQ + t) > k));
                    if DIRECT_ENQUEUE { an_add(AN_ENQUEUE, k); }
                    if !DIRECT_ENQUEUE {
                        if ITEMS_PLANAR {
                            an_add(AN_COPY, ((k + WG_SIZE - 1u) / WG_SIZE) * sched_words(t));
                        } else if sched_words(t) % 4u == 0u {
                            an_add(AN_COPY, (k * sched_words(t) + 4u * WG_SIZE - 1u) / (4u * WG_SIZE));
                        } else {
                            an_add(AN_COPY, (k * sched_words(t) + WG_SIZE - 1u) / WG_SIZE);
                        }
                    }
                    an_add(AN_PUBLISH, (k + WG_SIZE - 1u) / WG_SIZE);
                }
                an_add(AN_RESERVE, chain + u32(emitted != n) + params[P_POLICY] + u32(abandoned > 0u));
                // Flag stores of the inputs, then one round of parallel count adds.
                an_add(AN_PUBLISH, (n + WG_SIZE - 1u) / WG_SIZE + 1u);
            }
        }

        // 4. Copy the payloads into the reserved slots, coalesced: planar items a plane at a
        //    time; interleaved ones 16 bytes per thread where the item is a whole number of vec4s
        //    (queue regions and outbox parts are 16-byte aligned).
        for (var t = 0u; t < NQ && !DIRECT_ENQUEUE; t++) {
            let k = wg_emit_n[t];
            let words = k * sched_words(t);
            let dst = q_slot_base(t) + wg_emit_base[t] * sched_words(t);
            let src = sched_outbox + ob_off(q, t);
            if ITEMS_PLANAR {
                // Plane by plane, four planes per trip: four independent loads in flight.
                let cap = q_cap(t);
                let ob = ob_cap(q, t);
                let to = q_slot_base(t) + wg_emit_base[t];
                var plane = 0u;
                for (; plane + 4u <= sched_words(t); plane += 4u) {
                    for (var j = lid; j < k; j += WG_SIZE) {
                        let a = sched_ob_load_word(src + plane * ob + j);
                        let b = sched_ob_load_word(src + (plane + 1u) * ob + j);
                        let c = sched_ob_load_word(src + (plane + 2u) * ob + j);
                        let d = sched_ob_load_word(src + (plane + 3u) * ob + j);
                        sched_slot_store_word(to + plane * cap + j, a);
                        sched_slot_store_word(to + (plane + 1u) * cap + j, b);
                        sched_slot_store_word(to + (plane + 2u) * cap + j, c);
                        sched_slot_store_word(to + (plane + 3u) * cap + j, d);
                    }
                }
                for (; plane < sched_words(t); plane++) {
                    for (var j = lid; j < k; j += WG_SIZE) {
                        sched_slot_store_word(to + plane * cap + j, sched_ob_load_word(src + plane * ob + j));
                    }
                }
            } else if sched_words(t) % 4u == 0u {
                for (var w = lid * 4u; w < words; w += 4u * WG_SIZE) {
                    sched_slot_store_vec4(dst + w, sched_ob_load_vec4(src + w));
                }
            } else {
                for (var w = lid; w < words; w += WG_SIZE) {
                    sched_slot_store_word(dst + w, sched_ob_load_word(src + w));
                }
            }
        }
        // Release: payloads (global slots and the workgroup's held items alike) before the
        // flags that publish them and before the next local batch reads them. A sink's batch
        // wrote no item: it has nothing to release (its inputs' CONSUMED marks are read only
        // between launches), so it skips the device-scope fence. Every held item was written
        // by an emitting batch, whose fence still follows it, or lives in workgroup memory
        // (LOCAL_IN_WG), which the workgroup's barriers order: a local batch there that
        // emitted only held items (`publishes` false) skips the fence too.
        if !sched_is_sink(q) && publishes { storageBarrier(); }

        // 5. Publish: flag new slots with the batch stamp, mark processed inputs consumed.
        for (var t = 0u; t < NQ; t++) {
            for (var j = lid; j < wg_emit_n[t]; j += WG_SIZE) {
                var s = wg_emit_base[t] + j;
                if DIRECT_ENQUEUE { s = wg_emit_slot[sched_es_off(q * NQ + t) + j]; }
                atomicStore(&flags[q_flag_base(t) + s], wg_stamp);
            }
        }
        for (var i = lid; i < n && !from_local; i += WG_SIZE) {
            if wg_ready[i] != 0u { atomicStore(&flags[q_flag_base(q) + h + i], CONSUMED); }
        }
        // Every lane's flag stores issued before any count add. No device-scope fence: the count
        // only says how many items to claim; a claimer that sees it before a flag waits for
        // the flag (bounded), and the flag is what orders the payload (the release barrier
        // above, the claimer's acquire barrier after its wait).
        if publishes { workgroupBarrier(); }
        // The new items become claimable: lane t adds target t's, all in parallel.
        if lid < NQ && wg_emit_n[lid] > 0u {
            atomicAdd(&ctrl[lid * QSTRIDE + Q_COUNT], wg_emit_n[lid]);
        }
        var own = 0u;
        if lid < NQ { own = wg_emit_n[prio(lid)]; }
        if fresh { probe_store(lid, early, own); }
        probed = true;
    }
    // Items still held locally go to the global queues for the next launch.
    if LOCAL {
        spill_local(lid);
        if lid == 0u && sched_idle_reg { atomicSub(&ctrl[gw(G_IDLE_NOW)], 1u); }
    }
    // Statistics, once per workgroup and launch. Every exit of the loop passes here, lavapipe's
    // silent loop cut included, so the host's accounting (executed per queue) stays exact.
    if lid < NQ {
        fold_peak();
        if st_local > 0u { atomicAdd(&ctrl[lid * QSTRIDE + Q_LOCAL], st_local); }
        if st_executed > 0u { atomicAdd(&ctrl[lid * QSTRIDE + Q_EXECUTED], st_executed); }
        if st_batches > 0u { atomicAdd(&ctrl[lid * QSTRIDE + Q_BATCHES], st_batches); }
        if st_peak > 0u { atomicMax(&ctrl[lid * QSTRIDE + Q_PEAK], st_peak); }
    }
    if lid == 0u {
        if idle > 0u { atomicAdd(&ctrl[gw(G_IDLE)], idle); }
        if iter >= params[P_MAX_ITERS] { atomicAdd(&ctrl[gw(G_ITER_EXITS)], 1u); }
        // Keeps the pauses from being optimised away (never true in practice).
        if sched_pause_sink == 0x9e3779b9u { atomicAdd(&ctrl[gw(G_IDLE)], 1u); }
        if TURN_ANATOMY {
            for (var k = 0u; k < AN_WORDS; k++) {
                if an[k] > 0u { atomicAdd(&ctrl[gw(G_AN + k)], an[k]); }
            }
        }
    }
}
