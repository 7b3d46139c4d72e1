//! Generates the megakernel's WGSL: the program's shared code, queue word accessors (plain
//! `@coherent` loads where the device has them, atomics otherwise), enqueue functions that write
//! to the workgroup's outbox or (direct enqueue) straight into the slots, and the loop in
//! `shaders/megakernel*.wgsl` ([`TEMPLATE`]).

use super::local::LocalPlan;
use crate::item_layout::ItemLayout;
use crate::program::Program;

/// The megakernel's fixed code, one concern per file, concatenated in this order: the state,
/// where an emit goes, the claim, the spill, the probes, and the loop.
pub const TEMPLATE: &str = concat!(
    include_str!("../../../shaders/megakernel_state.wgsl"),
    include_str!("../../../shaders/megakernel_enqueue.wgsl"),
    include_str!("../../../shaders/megakernel_claim.wgsl"),
    include_str!("../../../shaders/megakernel_spill.wgsl"),
    include_str!("../../../shaders/megakernel_probe.wgsl"),
    include_str!("../../../shaders/megakernel.wgsl"),
);

/// Options compiled into the megakernel as constants (each a `MegakernelConfig` field).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Switches {
    /// Count each turn's phases (`MegakernelConfig::turn_anatomy`).
    pub anatomy: bool,
    /// Take enqueue tickets once per subgroup (`MegakernelConfig::subgroups`; the device must
    /// have wgpu's `SUBGROUP`).
    pub subgroups: bool,
    /// Cap each claim at the workgroup's share of the pending items
    /// (`MegakernelConfig::guided_claims`).
    pub guided_claims: bool,
}

/// The megakernel's WGSL for `program` (workgroups of [`Program::workgroup_size`] threads),
/// with `slots` read through `@coherent` loads where the device has them, and queues and
/// outboxes holding items as `items` says. `direct`: enqueue
/// straight into the slots, with the longest ticket list of a batch and each (source, target)
/// part's offset in it (`MegakernelConfig::direct_enqueue`). `switches`: the compiled-in
/// options ([`Switches`]). `local`: the workgroup's local regions
/// (`MegakernelConfig::local_queues`; [`LocalPlan::none`] for none).
pub fn source(
    program: &Program,
    coherent: bool,
    items: ItemLayout,
    direct: Option<(u32, &[u32])>,
    switches: Switches,
    local: &LocalPlan,
) -> String {
    let Switches {
        anatomy,
        subgroups,
        guided_claims,
    } = switches;
    let planar = items == ItemLayout::Planar;
    let mut s = program.tables_wgsl(true);
    s += &format!("const ITEMS_PLANAR: bool = {planar};\n");
    s += &format!("const TURN_ANATOMY: bool = {anatomy};\n");
    s += &format!("const GUIDED_CLAIMS: bool = {guided_claims};\n");
    s += &format!("const WG_SIZE: u32 = {}u;\n", program.workgroup_size());
    let (slots, offsets) = direct.unwrap_or((1, &[]));
    let nq = program.queue_count();
    let es: Vec<u32> = (0..nq * nq)
        .map(|i| offsets.get(i).copied().unwrap_or(0))
        .collect();
    s += &format!(
        "const DIRECT_ENQUEUE: bool = {};\n\
         const EMIT_SLOTS: u32 = {slots}u;\n\
         // sched_es_off(q * NQ + t): where target t's tickets start in a batch of q's ticket list\n\
         {}",
        direct.is_some(),
        crate::wgsl::table_fn("sched_es_off", &es),
    );
    s += &local.wgsl(program);
    s += &program.common_wgsl();
    // The slots buffer's accessors; with the local area in workgroup memory they are the
    // `_g_` ones under accessors that send the area's addresses there.
    let in_wg = local.active() && local.in_workgroup;
    let slot = if in_wg { "sched_slot_g" } else { "sched_slot" };
    if coherent {
        s += "@group(0) @binding(1) @coherent var<storage, read_write> slots: array<vec4<u32>>;\n";
        s += &crate::wgsl::vec4_word_accessors(slot, "slots");
    } else {
        s += &format!(
            "@group(0) @binding(1) var<storage, read_write> slots: array<atomic<u32>>;\n\
             fn {slot}_load_word(i: u32) -> u32 {{ return atomicLoad(&slots[i]); }}\n\
             fn {slot}_store_word(i: u32, w: u32) {{ atomicStore(&slots[i], w); }}\n\
             fn {slot}_load_vec4(i: u32) -> vec4<u32> {{\n    \
                 return vec4<u32>(atomicLoad(&slots[i]), atomicLoad(&slots[i + 1u]), atomicLoad(&slots[i + 2u]), atomicLoad(&slots[i + 3u]));\n}}\n\
             fn {slot}_store_vec4(i: u32, v: vec4<u32>) {{\n    \
                 for (var k = 0u; k < 4u; k++) {{ atomicStore(&slots[i + k], v[k]); }}\n}}\n"
        );
    }
    if in_wg {
        s += &local.workgroup_area_accessors("sched_slot");
    }
    s += &crate::wgsl::vec4_word_accessors("sched_ob", "outbox");
    s += if subgroups { TAKE_SUBGROUP } else { TAKE_ONE };
    s += &crate::hash::lowbias32_wgsl("sched_hash");
    s += &claim_wgsl(nq);
    // Bodies read their items through the slot accessors, a local batch's from its buffer in
    // the workgroup's area of the slots (`mk_execute`); local emits are stored with them too.
    s += &items.execute_switch(program, "sched_slot");
    // Outbox item `j` of part (q, t) and its stride.
    let (ob_at, ob_stride) = if planar {
        ("sched_outbox + ob_off(q, t) + j", "ob_cap(q, t)")
    } else {
        ("sched_outbox + ob_off(q, t) + j * sched_words(t)", "1u")
    };
    // A local batch's item `s` in the buffer it was kept in (planar: stride the buffer's
    // capacity). One call site of `sched_execute` either way (lavapipe inlines it).
    let (base, local_base, stride_arg) = if planar {
        ("q_slot_base(q) + s", "sched_local_in(q) + s", ", stride")
    } else {
        (
            "q_slot_base(q) + s * sched_words(q)",
            "sched_local_in(q) + s * sched_words(q)",
            "",
        )
    };
    s += &format!(
        "fn mk_execute(q: u32, s: u32, inv: Invocation) {{\n    \
             var base = {base};\n    var stride = {};\n    \
             if LOCAL && sched_from_local {{ base = {local_base}; stride = LOCAL_CAP[q]; }}\n    \
             sched_execute(q, base{stride_arg}, inv);\n}}\n",
        if planar { "q_cap(q)" } else { "1u" }
    );
    s += &format!(
        "fn mk_outbox_item(q: u32, t: u32, j: u32) -> u32 {{ return {ob_at}; }}\n\
         fn mk_outbox_stride(q: u32, t: u32) -> u32 {{ return {ob_stride}; }}\n"
    );
    // Typed outbox stores, only where items go through the outbox (direct enqueue and local
    // emits store with the `sched_slot_store_*` that come with `ItemLayout::execute_switch`'s
    // loads).
    if direct.is_none() {
        s += &items.typed_fns(program, "sched_ob");
    }
    for (t, p) in program.procs.iter().enumerate() {
        s += &emit_fns(
            t,
            &p.proc.name,
            &p.layout.name,
            planar,
            local.cap[t] > 0,
            direct.is_some(),
        );
    }
    // Guarded word by word, as `enqueue_<name>` is once: a dropped item's words go nowhere.
    s += "fn store_word(slot: ItemSlot, word: u32, value: u32) {\n    \
              if slot.at == 0xffffffffu { return; }\n    \
              let i = slot.at + word * slot.stride;\n    \
              if slot.outbox != 0u { sched_ob_store_word(i, value); } else { sched_slot_store_word(i, value); }\n}\n";
    s += TEMPLATE;
    s
}

/// `enqueue_<name>(item)` and `reserve_<name>()` for target `t` (item type `ty`): both take the
/// same place for an emit, tried in this order: a slot of t's local buffer where the running
/// procedure keeps its emits to t and the buffer has room this batch (`local`), else a ticket
/// of t's queue (`direct`) or an entry of the workgroup's outbox. `enqueue_` stores the whole
/// item there; `reserve_` returns the place as an `ItemSlot` (first word, stride between words)
/// for `store_word`.
fn emit_fns(t: usize, name: &str, ty: &str, planar: bool, local: bool, direct: bool) -> String {
    // Item `index` of a region at `base` holding `cap` items: its first word and word stride.
    let place = |base: String, index: &str, cap: String| {
        if planar {
            (format!("{base} + {index}"), cap)
        } else {
            (format!("{base} + {index} * sched_words({t}u)"), "1u".into())
        }
    };
    let local_at = place(
        format!("sched_local_out({t}u)"),
        "l",
        format!("LOCAL_CAP[{t}u]"),
    );
    let (global_at, outbox) = if direct {
        (
            place(format!("q_slot_base({t}u)"), "s", format!("q_cap({t}u)")),
            false,
        )
    } else {
        let stride = if planar {
            format!("mk_outbox_stride(sched_proc, {t}u)")
        } else {
            "1u".into()
        };
        (("at".to_string(), stride), true)
    };
    // The typed store's arguments: the first word and, planar, the stride.
    let args = |(at, stride): &(String, String)| match planar {
        true => format!("{at}, {stride}"),
        false => at.clone(),
    };
    let store = if outbox {
        "sched_ob_store"
    } else {
        "sched_slot_store"
    };
    let slot = |(at, stride): &(String, String)| format!("r.at = {at}; r.stride = {stride};");
    // The function's body around what it does at the place: `take_local` (which returns) and
    // `take_global`.
    let body = |take_local: String, take_global: String| {
        let local = if local {
            format!(
                "if LOCAL_EDGE[sched_proc * NQ + {t}u] != 0u {{\n        \
                     let l = atomicAdd(&wg_local_n[{t}u], 1u);\n        \
                     if l < wg_local_lim[{t}u] {{ {take_local} }}\n    }}\n    "
            )
        } else {
            String::new()
        };
        let global = if outbox {
            format!(
                "let at = sched_outbox_slot({t}u);\n    if at != 0xffffffffu {{ {take_global} }}"
            )
        } else {
            format!("let s = sched_direct_slot({t}u);\n    if s != 0xffffffffu {{ {take_global} }}")
        };
        format!("{local}{global}")
    };
    let enqueue = body(
        format!("sched_slot_store_{ty}({}, item); return;", args(&local_at)),
        format!("{store}_{ty}({}, item);", args(&global_at)),
    );
    let reserve = body(
        format!("{} return r;", slot(&local_at)),
        slot(&global_at) + if outbox { " r.outbox = 1u;" } else { "" },
    );
    format!(
        "fn enqueue_{name}(item: {ty}) {{\n    if !sched_active {{ return; }}\n    {enqueue}\n}}\n\
         fn reserve_{name}() -> ItemSlot {{\n    var r = ItemSlot(0xffffffffu, 1u, 0u);\n    \
         if !sched_active {{ return r; }}\n    {reserve}\n    return r;\n}}\n"
    )
}

/// `reserve_budget` and the refused-queue set of `try_claim` (`shaders/megakernel_claim.wgsl`) for
/// `nq` queues, as straight-line code: arrays indexed at run time likely live in local memory,
/// a round trip of their own on every claim (the first version, with such arrays, was slower
/// on the H200; the compiled code could not be read to confirm why). The refused queues are a
/// register bitmask up to 32 queues; past that (no workload has so many) a private array,
/// indexed only when a queue refuses room or a claim checks it.
fn claim_wgsl(nq: usize) -> String {
    let mut s = String::from("fn reserve_budget(q: u32, n: u32) -> bool {\n");
    for t in 0..nq {
        s += &format!(
            "    let e{t} = sched_emits(q * NQ + {t}u) * n;\n    var o{t} = 0u;\n    \
             if e{t} > 0u {{ o{t} = atomicAdd(&ctrl[{t}u * QSTRIDE + Q_BUDGET], e{t}); }}\n"
        );
    }
    s += "    var ok = true;\n";
    for t in 0..nq {
        s += &format!(
            "    if e{t} > 0u && o{t} + e{t} > q_cap({t}u) {{\n        \
             atomicStore(&ctrl[{t}u * QSTRIDE + Q_BLOCKED], 1u);\n        ok = false;\n    }}\n"
        );
    }
    s += "    if ok { return true; }\n";
    for t in 0..nq {
        s += &format!(
            "    if e{t} > 0u {{\n        atomicSub(&ctrl[{t}u * QSTRIDE + Q_BUDGET], e{t});\n        \
             atomicMax(&ctrl[{t}u * QSTRIDE + Q_DEMAND], e{t});\n    }}\n"
        );
    }
    s += "    return false;\n}\n";
    if nq <= 32 {
        s += "var<private> sched_refused_mask: u32;\n\
              fn sched_refused(q: u32) -> bool { return (sched_refused_mask & (1u << q)) != 0u; }\n\
              fn sched_refuse(q: u32) { sched_refused_mask |= 1u << q; }\n";
    } else {
        s += "var<private> sched_refused_set: array<bool, NQ>;\n\
              fn sched_refused(q: u32) -> bool { return sched_refused_set[q]; }\n\
              fn sched_refuse(q: u32) { sched_refused_set[q] = true; }\n";
    }
    s
}

/// `sched_take` (see `shaders/megakernel_enqueue.wgsl`): every emitting lane takes its own index and
/// ticket.
const TAKE_ONE: &str = "\
fn sched_take(t: u32, direct: bool) -> vec2<u32> {
    let j = atomicAdd(&wg_emit_count[t], 1u);
    var s = 0u;
    if direct && j < sched_batch_n * sched_emits(sched_proc * NQ + t) {
        s = atomicAdd(&ctrl[t * QSTRIDE + Q_RESERVE], 1u);
    }
    return vec2<u32>(j, s);
}
";

/// `sched_take` with subgroups: the lanes of a subgroup that emit to `t` at the same call take
/// consecutive indices and tickets with one atomic each (the first such lane's), as
/// Whippletree's warp-aggregated enqueue does with ballot and popc.
const TAKE_SUBGROUP: &str = "\
fn sched_take(t: u32, direct: bool) -> vec2<u32> {
    let rank = subgroupExclusiveAdd(1u);
    let n = subgroupAdd(1u);
    var base = vec2<u32>(0u, 0u);
    if rank == 0u {
        base.x = atomicAdd(&wg_emit_count[t], n);
        if direct {
            // Tickets only for the emits within the batch's declared limit.
            let limit = sched_batch_n * sched_emits(sched_proc * NQ + t);
            let within = min(n, limit - min(limit, base.x));
            if within > 0u { base.y = atomicAdd(&ctrl[t * QSTRIDE + Q_RESERVE], within); }
        }
    }
    base = subgroupBroadcastFirst(base);
    return base + vec2<u32>(rank, rank);
}
";

#[cfg(test)]
mod tests {
    use crate::{ItemLayout, ItemType, Procedure, Program, UserBindings};

    /// The megakernel of `p` with interleaved items, outbox enqueue, no anatomy, subgroups or
    /// local queues.
    fn plain_source(p: &Program) -> String {
        let plan = super::LocalPlan::none(p.queue_count());
        super::source(
            p,
            false,
            ItemLayout::Interleaved,
            None,
            Default::default(),
            &plan,
        )
    }

    /// A body that stores its child a word at a time compiles into every form of the
    /// megakernel (outbox or direct enqueue, interleaved or planar items, with or without a
    /// local buffer for the child), which says it is the megakernel (`SCHED_MEGAKERNEL`).
    #[test]
    fn reserved_slots_compile_into_every_form_of_the_megakernel() {
        let pair = ItemType::new("Pair", "struct Pair { a: u32, b: f32 }");
        let split = Procedure::new("split", pair.clone(), 1)
            .emits("split", 1)
            .local("split")
            .body(
                "fn split_execute(item: Pair, inv: Invocation) {\n    \
                 let slot = reserve_split();\n    \
                 if slot_reserved(slot) {\n        \
                 store_word(slot, Pair_a_word, item.a + 1u);\n        \
                 store_word(slot, Pair_b_word, bitcast<u32>(item.b));\n    }\n}",
            );
        let p = Program::new(vec![split], UserBindings::none()).unwrap();
        for items in [ItemLayout::Interleaved, ItemLayout::Planar] {
            for direct in [None, Some((256u32, &[0u32][..]))] {
                for bytes in [0, 1 << 16] {
                    let plan = super::LocalPlan::new(&p, &[256], bytes);
                    let src = super::source(&p, true, items, direct, Default::default(), &plan);
                    assert!(src.contains("const SCHED_MEGAKERNEL: bool = true;"));
                    assert!(src.contains("fn reserve_split() -> ItemSlot {"));
                    assert!(src.contains("const Pair_b_word: u32 = 1u;"));
                    assert_eq!(src.contains("sched_local_out(0u)"), bytes > 0, "{bytes}");
                    assert_eq!(src.contains("r.outbox = 1u"), direct.is_none());
                    crate::wgsl::validate("megakernel", &src).unwrap();
                }
            }
        }
    }

    /// The megakernel reads threads per item from a `const` array and its other tables through
    /// functions (`Program::tables_wgsl`), and tests for a sink at both release fences (2.2).
    #[test]
    fn the_megakernel_reads_threads_from_an_array_the_rest_through_functions() {
        let src = plain_source(&crate::program::source_to_sink(1, 1));
        assert!(
            src.contains("THREADS[") && !src.contains("fn sched_threads"),
            "{src}"
        );
        for table in ["WORDS", "EMITS", "ES_OFF"] {
            assert!(!src.contains(&format!("{table}[")), "{table}: {src}");
        }
        for f in ["sched_words", "sched_emits", "sched_es_off"] {
            assert!(
                src.contains(&format!("fn {f}(i: u32) -> u32")),
                "{f}: {src}"
            );
        }
        assert!(src.contains("return q == 1u;"), "{src}");
        assert_eq!(
            src.matches("!sched_is_sink(q) { storageBarrier(); }")
                .count(),
            1
        );
        // The release fence: also skipped by a local batch in workgroup memory that published
        // nothing (docs/scheduler.md 2.7).
        assert_eq!(
            src.matches("!sched_is_sink(q) && publishes { storageBarrier(); }")
                .count(),
            1
        );
    }

    #[test]
    fn procedures_sharing_an_execute_function_share_one_call_site() {
        let word = ItemType::new("Word", "struct Word { v: u32 }");
        let one = Procedure::new("one", word.clone(), 4)
            .body("fn one_execute(item: Word, inv: Invocation) { let t = inv.threads; }");
        let sink = Procedure::new("sink", word.clone(), 1)
            .body("fn sink_execute(item: Word, inv: Invocation) {}");
        let two = Procedure::new("two", word, 2).execute_of("one");
        let p = Program::new(vec![one, sink, two], UserBindings::none()).unwrap();
        let src = plain_source(&p);
        assert_eq!(src.matches("one_execute(it, inv)").count(), 1, "{src}");
        assert!(src.contains("case 0u, 2u:"), "{src}");
    }

    #[test]
    fn switches_are_compiled_in_as_constants() {
        let word = ItemType::new("Word", "struct Word { v: u32 }");
        let leaf =
            Procedure::new("leaf", word, 1).body("fn leaf_execute(item: Word, inv: Invocation) {}");
        let p = Program::new(vec![leaf], UserBindings::none()).unwrap();
        let plain = plain_source(&p);
        assert!(
            plain.contains("const GUIDED_CLAIMS: bool = false;"),
            "{plain}"
        );
        let plan = super::LocalPlan::none(p.queue_count());
        let switches = super::Switches {
            guided_claims: true,
            ..Default::default()
        };
        let guided = super::source(&p, false, ItemLayout::Interleaved, None, switches, &plan);
        assert!(
            guided.contains("const GUIDED_CLAIMS: bool = true;"),
            "{guided}"
        );
        assert!(
            guided.contains("const TURN_ANATOMY: bool = false;"),
            "{guided}"
        );
        naga::front::wgsl::parse_str(&guided).unwrap();
    }

    #[test]
    fn a_workgroup_size_scales_items_per_step_and_shared_arrays() {
        let word = ItemType::new("Word", "struct Word { v: u32 }");
        let grid = Procedure::new("grid", word.clone(), 64)
            .shared("vec4<f32>", 3)
            .body("fn grid_execute(item: Word, inv: Invocation) {}");
        let leaf =
            Procedure::new("leaf", word, 1).body("fn leaf_execute(item: Word, inv: Invocation) {}");
        let p = Program::new(vec![grid, leaf], UserBindings::none()).unwrap();
        assert_eq!(p.workgroup_size(), 256);
        assert!(p.with_workgroup_size(384).is_err());
        assert!(p.with_workgroup_size(0).is_err());
        assert!(p.with_workgroup_size(2048).is_err());
        let big = p.with_workgroup_size(768).unwrap();
        let steps: Vec<u32> = big.procs.iter().map(|i| i.items_per_step).collect();
        assert_eq!(steps, [12, 768]);
        // The original keeps its own.
        assert_eq!(p.procs[0].items_per_step, 4);
        let src = plain_source(&big);
        assert!(src.contains("const WG_SIZE: u32 = 768u;"), "{src}");
        assert!(
            src.contains("var<workgroup> grid_shared: array<vec4<f32>, 36>;"),
            "{src}"
        );
        assert!(src.contains("@workgroup_size(WG_SIZE)"), "{src}");
        // Every loop over the workgroup's lanes strides by WG_SIZE, none by a literal size.
        assert!(!src.contains("+= 256u"), "{src}");
        naga::front::wgsl::parse_str(&src).unwrap();
    }
}
