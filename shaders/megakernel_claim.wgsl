// Persistent megakernel, part 3 of 6 (order: megakernel_state.wgsl): the leader's claim of a
// batch and its decision for the turn. Host twin: scheduler/src/megakernel/claim.rs.

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
