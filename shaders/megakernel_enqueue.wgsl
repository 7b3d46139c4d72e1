// Persistent megakernel, part 2 of 6 (order: megakernel_state.wgsl): where an emitted item goes,
// the outbox or (direct enqueue) a ticket of its queue. Host twin: the `enqueue_*` and
// `sched_take` generation in scheduler/src/megakernel/wgsl.rs.

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
