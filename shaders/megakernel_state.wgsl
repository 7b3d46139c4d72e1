// Persistent megakernel, part 1 of 6: the state. Every workgroup loops, claiming a batch from
// one procedure queue, running it, and publishing what it emitted, until no work is left in
// this launch. The protocol and why it is correct under WGSL's relaxed atomics:
// docs/scheduler.md. The parts, concatenated in this order (scheduler/src/megakernel/wgsl.rs,
// TEMPLATE): megakernel_state.wgsl (ctrl and params layouts, workgroup and lane state; host
// twin: scheduler/src/megakernel/layout.rs), megakernel_enqueue.wgsl (where an emit goes),
// megakernel_claim.wgsl (the leader's claim and decision; scheduler/src/megakernel/claim.rs),
// megakernel_spill.wgsl (held items to the global queues; scheduler/src/megakernel/local.rs),
// megakernel_probe.wgsl (the turn's probe and the co-residency probe) and megakernel.wgsl (the
// loop).
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
