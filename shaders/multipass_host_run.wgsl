// The host-driven multi-pass's loop over one procedure's round inputs (multipass_host.wgsl).
// Instantiated by scheduler/src/multipass/wgsl.rs (`rounds_source`): once per procedure t as
// `run_procedure_<t>` with `mp_execute_<t>`, which calls t's body alone, for t's entry point;
// the host-driven multi-pass has no fused round, so no generic copy.
// An entry point that reached every body through sched_execute's switch would get the driver's
// register allocation and workgroup memory for all of them (on the H200, the host-driven
// DiceShade took 122 registers instead of 80 when Bound's workgroup memory grew:
// docs/scheduler.md 4).

// Runs procedure q over this round's counts_in[q] inputs, grid-stride, items_per_step items per
// step (the host dispatches min(ceil(n / items_per_step), 65535) workgroups).
fn RUN_PROCEDURE(q: u32, lid: u32, wid: u32, nwg: u32) {
    if lid == 0u { wg_n = counts_in[q]; }
    let n = workgroupUniformLoad(&wg_n);
    let skip = counts_in[H_SKIP + q];
    let per_step = 256u / sched_threads(q);
    let slot = lid / sched_threads(q);
    let thread = lid % sched_threads(q);
    for (var first = wid * per_step; first < n; first += nwg * per_step) {
        let idx = first + slot;
        let live = idx < n;
        for (var t = thread; t < NQ; t += sched_threads(q)) { atomicStore(&wg_item_emits[slot * NQ + t], 0u); }
        workgroupBarrier();
        sched_proc = q;
        sched_slot = slot;
        sched_active = live;
        MP_EXECUTE(q, skip + idx, Invocation(thread, slot, live, sched_threads(q)));
        workgroupBarrier();
    }
}
