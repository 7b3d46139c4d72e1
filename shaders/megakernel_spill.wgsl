// Persistent megakernel, part 4 of 6 (order: megakernel_state.wgsl): the spill of held items
// (local queues, docs/scheduler.md 2.7). Host twin: scheduler/src/megakernel/local.rs.

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
