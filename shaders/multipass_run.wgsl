// The device-driven multi-pass's loop over one procedure's round inputs (multipass.wgsl).
// Instantiated by scheduler/src/multipass/wgsl.rs (`rounds_source`): once per procedure t as
// `run_procedure_<t>` with `mp_execute_<t>`, which calls t's body alone, for t's entry point
// and the dispatch groups that hold t (`mp_group_<g>`); and once as `run_procedure` with
// `mp_execute` (any procedure, by q) for the fused round, `mp_round`.
// An entry point that reached every body through sched_execute's switch would get the driver's
// register allocation and workgroup memory for all of them (on the H200, the host-driven
// DiceShade took 122 registers instead of 80 when Bound's workgroup memory grew:
// docs/scheduler.md 4).

// Runs procedure q over this round's inputs as this workgroup's `Pick` (`mp_begin`) gives
// them, grid-stride, items_per_step items per step. The workgroup count comes from the pick,
// not @builtin(num_workgroups), which D3D12 reports as 0 for indirect dispatches when wgpu's
// indirect validation is off. Only the newest inputs run (all but `pick.keep`: the outputs of
// the last rounds, so a partial round goes depth first and its live work stays bounded); the
// older ones are copied, in place, to the front of the next round's inputs.
fn RUN_PROCEDURE(q: u32, pick: Pick, lid: u32) {
    let n = pick.count;
    let keep = pick.keep;
    let nwg = max(pick.wgs, 1u);
    let per_step = 256u / sched_threads(q);
    let slot = lid / sched_threads(q);
    let thread = lid % sched_threads(q);
    for (var first = pick.index * per_step; first < n; first += nwg * per_step) {
        let idx = first + slot;
        let live = idx >= keep && idx < n;
        if idx < keep {
            for (var w = thread; w < sched_words(q); w += sched_threads(q)) {
                let at = mp_word_at(q, idx, w);
                mp_out_store_word(at, mp_in_load_word(at));
            }
        }
        for (var t = thread; t < NQ; t += sched_threads(q)) { atomicStore(&wg_item_emits[slot * NQ + t], 0u); }
        workgroupBarrier();
        sched_proc = q;
        sched_slot = slot;
        sched_active = live;
        MP_EXECUTE(q, idx, Invocation(thread, slot, live, sched_threads(q)));
        workgroupBarrier();
    }
}
