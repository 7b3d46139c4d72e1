// Persistent megakernel, part 5 of 6 (order: megakernel_state.wgsl): the turn's probe of the
// queue counts and the co-residency probe of a probing launch (docs/scheduler.md 2.3).

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
