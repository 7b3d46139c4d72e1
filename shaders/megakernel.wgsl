// Persistent megakernel, part 6 of 6 (order: megakernel_state.wgsl): the loop, one turn per
// batch (docs/scheduler.md 2.2).

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
        // workgroup's lanes only, which its barriers order (docs/scheduler.md 2.7). Every
        // batch takes the same barriers: the branch is on a constant only. Taken in a branch on
        // `from_local` (a uniform load in one arm, a barrier in the other), the skip left the
        // one-item chain's local turn at 2.32 us on the H100, against 1.96 in this form
        // (docs/results.md, 2026-12-06 (fourteenth session)).
        var publishes = true;
        if LOCAL_IN_WG {
            let emit_n = workgroupUniformLoad(&wg_emit_n);
            var sum = 0u;
            for (var t = 0u; t < NQ; t++) { sum += emit_n[t]; }
            publishes = !from_local || sum > 0u;
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
