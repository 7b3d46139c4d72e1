//! Local queues: where a workgroup keeps the items its batches emit to a target declared with
//! [`crate::Procedure::local`], to run them as its next batch (Whippletree's per-block queues,
//! Steinberger et al. 2014, section 4; Micropolis' local bound-and-split, Weber et al. 2015).
//! The items stay in a region of the slots buffer that only this workgroup touches, past the
//! queues' own slots: no workgroup memory (which cost co-resident workgroups, and with them the
//! regions' size, docs/scheduler.md 2.7), no global ticket, no flag, and the bodies read a local
//! batch through the same slot accessors as a claimed one, from another base. This module sizes
//! the regions and writes their WGSL constants; the protocol is in `shaders/megakernel.wgsl`
//! (`LOCAL`: the loop) and `shaders/megakernel_spill.wgsl`.

use super::MegakernelConfig;
use super::claim::worst_batch_output;
use crate::error::RunError;
use crate::program::Program;

/// Default most bytes of one workgroup's local regions (both buffers of every local target):
/// each target gets a full batch of its procedure per buffer where this allows.
pub const LOCAL_MAX_BYTES: u32 = 1 << 20;

/// Where each target's items stay in a workgroup's area of the slots buffer: two buffers of
/// `cap[t]` items of queue `t` each (0: `t` is nobody's local target), from word `off[t]` of the
/// area; the buffer a workgroup fills while the other is the batch being run swap at each local
/// batch of `t`. `wg_words`: the area's words per workgroup (a multiple of 4, so that every
/// area and region starts 16-byte aligned). `credit_max[t]`: most room in `t`'s budget a
/// workgroup keeps reserved for its next local batches, the largest worst-case output of one
/// batch to `t` (queues keep that much slack per workgroup: megakernel/record.rs).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct LocalPlan {
    pub cap: Vec<u32>,
    pub off: Vec<u32>,
    pub wg_words: u32,
    pub credit_max: Vec<u32>,
    /// Held sinks wait for other held work (`MegakernelConfig::defer_local_sinks`).
    pub defer_sinks: bool,
    /// The area lives in workgroup memory (`MegakernelConfig::local_workgroup_bytes`): the
    /// slot accessors send addresses within it there (`workgroup_area_accessors`).
    pub in_workgroup: bool,
}

impl LocalPlan {
    /// No local queue: every constant that keeps the template compiling.
    pub fn none(nq: usize) -> LocalPlan {
        LocalPlan {
            cap: vec![0; nq],
            off: vec![0; nq],
            wg_words: 0,
            credit_max: vec![0; nq],
            defer_sinks: true,
            in_workgroup: false,
        }
    }

    /// The bytes a configuration gives the area: `local_bytes` of the slots buffer, or, with
    /// `local_workgroup_bytes` set, that many bytes of workgroup memory (at most `local_bytes`).
    pub fn bytes_for(config: &MegakernelConfig) -> u32 {
        match config.local_workgroup_bytes {
            0 => config.local_bytes,
            wg => config.local_bytes.min(wg),
        }
    }

    /// The plan a configuration asks for, in [`LocalPlan::bytes_for`] bytes.
    pub fn for_config(program: &Program, batch: &[u32], config: &MegakernelConfig) -> LocalPlan {
        let mut plan = LocalPlan::new(program, batch, LocalPlan::bytes_for(config));
        plan.defer_sinks = config.defer_local_sinks;
        plan.in_workgroup = config.local_workgroup_bytes > 0;
        plan
    }

    /// Regions for the program's local targets: a full batch (`batch[t]` items, megakernel/
    /// claim.rs) per buffer, lowered evenly where the whole area would pass `bytes`.
    pub fn new(program: &Program, batch: &[u32], bytes: u32) -> LocalPlan {
        let nq = program.queue_count();
        let targets = local_targets(program);
        let mut plan = LocalPlan::none(nq);
        if targets.is_empty() {
            return plan;
        }
        // Words of one buffer of each target, at most: a multiple of 4, so that the buffer's
        // rounding up to 16 bytes (`buffer_words`) stays within `bytes`.
        let share = (bytes / 4 / 2 / targets.len() as u32) / 4 * 4;
        let mut off = 0;
        for &t in &targets {
            let words = program.procs[t].words();
            plan.cap[t] = batch[t].min(share / words);
            plan.off[t] = off;
            off += 2 * plan.buffer_words(program, t);
        }
        plan.wg_words = off;
        plan.credit_max = (0..nq)
            .map(|t| worst_batch_output(program, batch, t).min(u32::MAX as u64) as u32)
            .collect();
        plan
    }

    /// Warns where `local_workgroup_bytes` is set but local queues are off: it then does
    /// nothing.
    pub fn warn_unused(config: &MegakernelConfig) {
        if config.local_workgroup_bytes > 0 && !config.local_queues {
            log::warn!(
                "megakernel: local_workgroup_bytes (schedbench --local-workgroup-bytes) is set, \
                 but local queues are off: it has no effect"
            );
        }
    }

    /// The local targets whose buffer holds less than one step of their procedure
    /// (`items_per_step`), as (target, items a buffer, items a step), and the bytes per
    /// workgroup that would give every local target a step. A local batch of such a target
    /// runs a part-empty step: on the H100 the trees ran 1.5-4x slower with areas of 1-4 KiB
    /// (docs/results.md, 2026-12-06, "The local area in workgroup memory at 1-16 KiB").
    pub fn partial_steps(&self, program: &Program) -> (Vec<(usize, u32, u32)>, u32) {
        if !self.active() {
            return (Vec::new(), 0);
        }
        // `new` gives every declared target an even share of words a buffer, a multiple of 4,
        // whether or not the share holds one of its items.
        let targets = local_targets(program);
        let short = targets
            .iter()
            .map(|&t| (t, self.cap[t], program.procs[t].items_per_step))
            .filter(|&(_, cap, step)| cap > 0 && cap < step)
            .collect();
        let share = targets
            .iter()
            .map(|&t| buffer_words_for(program, t, program.procs[t].items_per_step))
            .max()
            .unwrap_or(0);
        (short, share * 4 * 2 * targets.len() as u32)
    }

    /// Warns, once, where a local target's buffer holds less than a step
    /// ([`LocalPlan::partial_steps`]) in the `bytes` given, naming the bytes that hold one and,
    /// where the area is in workgroup memory and those would not fit within the device's
    /// `limit` beside the rest of a kernel of `used` bytes, saying so.
    pub fn warn_partial_steps(&self, program: &Program, bytes: u32, used: u32, limit: u32) {
        let (short, enough) = self.partial_steps(program);
        if short.is_empty() {
            return;
        }
        let others = used - self.workgroup_area_bytes();
        let held: Vec<String> = short
            .iter()
            .map(|&(t, cap, step)| format!("{cap} of `{}`'s {step}", program.procs[t].proc.name))
            .collect();
        let fits = if self.in_workgroup && others.saturating_add(enough) > limit {
            format!(
                "; in workgroup memory that is more than this device's {limit} bytes hold \
                 beside the kernel's {others}: keep the area in the slots buffer \
                 (local_workgroup_bytes 0: the slots buffer)"
            )
        } else {
            String::new()
        };
        log::warn!(
            "megakernel: {bytes} bytes of local area per workgroup hold less than a step per \
             buffer ({}): local batches run part-empty steps, which ran the trees 1.5-4x slower \
             on an H100 (docs/scheduler.md 2.7); {enough} bytes (local_bytes, \
             local_workgroup_bytes; schedbench --local-bytes, --local-workgroup-bytes) hold a \
             step of every local target{fits}",
            held.join(", ")
        );
    }

    /// Bytes of workgroup memory the area takes (0 where it is in the slots buffer or none).
    pub fn workgroup_area_bytes(&self) -> u32 {
        if self.active() && self.in_workgroup {
            self.wg_words * 4
        } else {
            0
        }
    }

    /// Why a kernel of `used` bytes of workgroup memory passes the device's `limit`: where this
    /// plan's area is in workgroup memory, its share and the most that would fit; else the
    /// procedures' `.shared` arrays, which scale with the workgroup size.
    pub fn workgroup_overflow_hint(&self, used: u32, limit: u32) -> String {
        let area = self.workgroup_area_bytes();
        if area == 0 {
            return "the procedures' `.shared` arrays scale with the workgroup size: a smaller \
                    one fits"
                .into();
        }
        let fits = limit.saturating_sub(used - area);
        format!(
            "the local area takes {area} of them: local_workgroup_bytes (schedbench \
             --local-workgroup-bytes) of at most {fits} fits"
        )
    }

    /// True when some target has room for an item.
    pub fn active(&self) -> bool {
        self.cap.iter().any(|&c| c > 0)
    }

    /// Words from target `t`'s first buffer to its second (16-byte aligned).
    pub fn buffer_words(&self, program: &Program, t: usize) -> u32 {
        buffer_words_for(program, t, self.cap[t])
    }

    /// Its WGSL constants; `edge[q * NQ + t]` from the program.
    pub fn wgsl(&self, program: &Program) -> String {
        let nq = program.queue_count();
        let on = self.active();
        let list = |v: &[u32]| {
            v.iter()
                .map(|x| format!("{x}u"))
                .collect::<Vec<_>>()
                .join(", ")
        };
        let edge: Vec<u32> = program
            .procs
            .iter()
            .flat_map(|p| (0..nq).map(|t| (on && p.local[t] && self.cap[t] > 0) as u32))
            .collect();
        let stride: Vec<u32> = (0..nq).map(|t| self.buffer_words(program, t)).collect();
        // A held target that emits nothing runs after other held work until it fills a step.
        let defer: Vec<u32> = (0..nq)
            .map(|t| {
                let sink = program.procs[t].is_sink();
                (self.defer_sinks && on && self.cap[t] > 0 && sink) as u32
            })
            .collect();
        format!(
            "const LOCAL: bool = {on};\n\
             // LOCAL_EDGE[q * NQ + t]: 1 when q's emits to t may stay in the workgroup\n\
             const LOCAL_EDGE: array<u32, {n2}> = array<u32, {n2}>({});\n\
             // Items of queue t one local buffer holds, where t's two buffers start in a\n\
             // workgroup's area, and the words from one buffer to the other\n\
             const LOCAL_CAP: array<u32, {nq}> = array<u32, {nq}>({});\n\
             const LOCAL_OFF: array<u32, {nq}> = array<u32, {nq}>({});\n\
             const LOCAL_STRIDE: array<u32, {nq}> = array<u32, {nq}>({});\n\
             const LOCAL_WG_WORDS: u32 = {}u;\n\
             // The area is in workgroup memory (`wg_held`), not in the slots buffer\n\
             const LOCAL_IN_WG: bool = {in_wg};\n\
             // 1 where queue t emits nothing: its held items wait for other held work until\n\
             // they fill a step\n\
             const LOCAL_DEFER: array<u32, {nq}> = array<u32, {nq}>({});\n\
             // Most unpromised budget room of queue t a workgroup keeps (`wg_credit`)\n\
             const LOCAL_CREDIT_MAX: array<u32, {nq}> = array<u32, {nq}>({});\n",
            list(&edge),
            list(&self.cap),
            list(&self.off),
            list(&stride),
            self.wg_words,
            list(&defer),
            list(&self.credit_max),
            n2 = nq * nq,
            in_wg = on && self.in_workgroup,
        )
    }

    /// The `{prefix}_load_word`, `_store_word`, `_load_vec4` and `_store_vec4` slot accessors
    /// over `{prefix}_g_*` ones (the slots buffer's), sending an address within this
    /// workgroup's area (`sched_local_wg`, `LOCAL_WG_WORDS` words) to `wg_held`, the area in
    /// workgroup memory. Addresses stay those of the slots buffer, so that the bodies, the
    /// held buffers and the spill read and write held items as before; only where they live
    /// changes.
    pub fn workgroup_area_accessors(&self, prefix: &str) -> String {
        format!(
            "var<workgroup> wg_held: array<u32, {words}>;\n\
             fn {prefix}_load_word(i: u32) -> u32 {{\n    \
                 let r = i - sched_local_wg;\n    \
                 if r < LOCAL_WG_WORDS {{ return wg_held[r]; }}\n    \
                 return {prefix}_g_load_word(i);\n}}\n\
             fn {prefix}_store_word(i: u32, w: u32) {{\n    \
                 let r = i - sched_local_wg;\n    \
                 if r < LOCAL_WG_WORDS {{ wg_held[r] = w; }} else {{ {prefix}_g_store_word(i, w); }}\n}}\n\
             fn {prefix}_load_vec4(i: u32) -> vec4<u32> {{\n    \
                 let r = i - sched_local_wg;\n    \
                 if r < LOCAL_WG_WORDS {{\n        \
                     return vec4<u32>(wg_held[r], wg_held[r + 1u], wg_held[r + 2u], wg_held[r + 3u]);\n    }}\n    \
                 return {prefix}_g_load_vec4(i);\n}}\n\
             fn {prefix}_store_vec4(i: u32, v: vec4<u32>) {{\n    \
                 let r = i - sched_local_wg;\n    \
                 if r < LOCAL_WG_WORDS {{\n        \
                     wg_held[r] = v.x;\n        wg_held[r + 1u] = v.y;\n        \
                     wg_held[r + 2u] = v.z;\n        wg_held[r + 3u] = v.w;\n    \
                 }} else {{\n        {prefix}_g_store_vec4(i, v);\n    }}\n}}\n",
            words = self.wg_words.max(4)
        )
    }
}

/// Words of one local buffer of `items` items of target `t`, rounded up to 16 bytes.
fn buffer_words_for(program: &Program, t: usize, items: u32) -> u32 {
    (items * program.procs[t].words()).next_multiple_of(4)
}

/// The queues some procedure keeps local ([`crate::Procedure::local`]), in queue order.
fn local_targets(program: &Program) -> Vec<usize> {
    (0..program.queue_count())
        .filter(|&t| program.procs.iter().any(|p| p.local[t]))
        .collect()
}

/// Bytes of workgroup memory the module declares (naga's layout of every `var<workgroup>`).
pub(crate) fn workgroup_bytes(source: &str) -> Result<u32, RunError> {
    let module = naga::front::wgsl::parse_str(source)
        .map_err(|e| RunError::Program(format!("megakernel: {}", e.emit_to_string(source))))?;
    let mut layouter = naga::proc::Layouter::default();
    layouter
        .update(module.to_ctx())
        .map_err(|e| RunError::Program(format!("megakernel layout: {e}")))?;
    Ok(module
        .global_variables
        .iter()
        .filter(|(_, v)| v.space == naga::AddressSpace::WorkGroup)
        .map(|(_, v)| layouter[v.ty].size)
        .sum())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{ItemType, Procedure, UserBindings};

    fn program() -> Program {
        let node = ItemType::new(
            "Node",
            "struct Node { id: u32, depth: u32, pad: vec2<u32> }",
        );
        let split = Procedure::new("split", node.clone(), 1)
            .emits("split", 2)
            .emits("leaf", 2)
            .local("split")
            .body("fn split_execute(item: Node, inv: Invocation) { enqueue_split(item); enqueue_leaf(item); }");
        let leaf =
            Procedure::new("leaf", node, 1).body("fn leaf_execute(item: Node, inv: Invocation) {}");
        Program::new(vec![split, leaf], UserBindings::none()).unwrap()
    }

    #[test]
    fn regions_fit_the_bytes_given_and_only_local_targets_get_one() {
        let p = program();
        // A full batch per buffer where the bytes allow it.
        let plan = LocalPlan::new(&p, &[256, 1024], 1 << 20);
        assert_eq!(plan.cap, vec![256, 0]);
        assert_eq!(plan.wg_words, 2 * 256 * 4);
        // Fewer where they do not: half of 4 KiB per buffer, 128 items of 4 words.
        let small = LocalPlan::new(&p, &[256, 1024], 4096);
        assert_eq!(small.cap, vec![128, 0]);
        assert!(small.wg_words * 4 <= 4096);
        assert!(
            plan.wgsl(&p)
                .contains("LOCAL_EDGE: array<u32, 4> = array<u32, 4>(1u, 0u, 0u, 0u)")
        );
        assert!(!LocalPlan::none(2).active());
        // Items of 3 words: every size's area stays within its bytes, 16-byte rounding included.
        let node = ItemType::new("Node", "struct Node { id: u32, depth: u32, pad: u32 }");
        let split = Procedure::new("split", node, 1)
            .emits("split", 2)
            .local("split")
            .body("fn split_execute(item: Node, inv: Invocation) { enqueue_split(item); }");
        let odd = Program::new(vec![split], UserBindings::none()).unwrap();
        for bytes in (0..512).step_by(4) {
            let plan = LocalPlan::new(&odd, &[256], bytes);
            assert!(plan.wg_words * 4 <= bytes, "{bytes}: {plan:?}");
            assert_eq!(plan.active(), bytes >= 32, "{bytes}: {plan:?}");
        }
    }

    /// Only a local target that emits nothing is deferred: `leaf` once it is kept local, never
    /// `split`, which emits; and none with the deferral off.
    #[test]
    fn only_local_sinks_are_deferred() {
        let p = program();
        let plan = LocalPlan::new(&p, &[256, 1024], 1 << 20);
        assert!(
            plan.wgsl(&p)
                .contains("LOCAL_DEFER: array<u32, 2> = array<u32, 2>(0u, 0u)")
        );
        let node = ItemType::new("Node", "struct Node { id: u32 }");
        let split = Procedure::new("split", node.clone(), 1)
            .emits("split", 2)
            .emits("leaf", 2)
            .local("split")
            .local("leaf")
            .body("fn split_execute(item: Node, inv: Invocation) { enqueue_split(item); enqueue_leaf(item); }");
        let leaf =
            Procedure::new("leaf", node, 1).body("fn leaf_execute(item: Node, inv: Invocation) {}");
        let both = Program::new(vec![split, leaf], UserBindings::none()).unwrap();
        let mut plan = LocalPlan::new(&both, &[256, 1024], 1 << 20);
        assert!(
            plan.wgsl(&both)
                .contains("LOCAL_DEFER: array<u32, 2> = array<u32, 2>(0u, 1u)")
        );
        plan.defer_sinks = false;
        assert!(
            plan.wgsl(&both)
                .contains("LOCAL_DEFER: array<u32, 2> = array<u32, 2>(0u, 0u)")
        );
        assert!(!LocalPlan::none(2).wgsl(&both).contains("(0u, 1u)"));
    }

    /// The area goes to workgroup memory only where it is asked for and holds an item; its
    /// accessors send the area's addresses to `wg_held`, of the area's size, and the rest to
    /// the slots buffer's.
    #[test]
    fn a_local_area_in_workgroup_memory_is_declared_and_routed() {
        let p = program();
        let mut plan = LocalPlan::new(&p, &[256, 1024], 2048);
        assert!(plan.wgsl(&p).contains("const LOCAL_IN_WG: bool = false;"));
        plan.in_workgroup = true;
        assert!(plan.wgsl(&p).contains("const LOCAL_IN_WG: bool = true;"));
        let acc = plan.workgroup_area_accessors("sched_slot");
        assert!(acc.contains(&format!(
            "var<workgroup> wg_held: array<u32, {}>;",
            plan.wg_words
        )));
        assert!(plan.wg_words * 4 <= 2048);
        for f in ["load_word", "store_word", "load_vec4", "store_vec4"] {
            assert!(acc.contains(&format!("fn sched_slot_{f}(")), "{f}");
            assert!(acc.contains(&format!("sched_slot_g_{f}(i")), "{f}");
        }
        // What a kernel past the device's limit is told: the area's share and what fits.
        assert_eq!(plan.workgroup_area_bytes(), plan.wg_words * 4);
        let hint = plan.workgroup_overflow_hint(17_000, 16_384);
        let fits = 16_384 - (17_000 - plan.wg_words * 4);
        assert!(hint.contains(&format!("of at most {fits} fits")), "{hint}");
        assert!(hint.contains("--local-workgroup-bytes"), "{hint}");
        let mut none = LocalPlan::none(2);
        none.in_workgroup = true;
        assert!(none.wgsl(&p).contains("const LOCAL_IN_WG: bool = false;"));
        assert_eq!(none.workgroup_area_bytes(), 0);
        assert!(
            none.workgroup_overflow_hint(20_000, 16_384)
                .contains(".shared")
        );
    }

    /// A buffer of less than a step is found, with the bytes that hold a step of every local
    /// target: `split`'s 256 one-thread items of 4 words, two buffers, 8 KiB.
    #[test]
    fn a_buffer_of_less_than_a_step_is_found_with_the_bytes_that_hold_one() {
        let p = program();
        assert_eq!(p.procs[0].items_per_step, 256);
        let small = LocalPlan::new(&p, &[256, 1024], 2048);
        assert_eq!(small.partial_steps(&p), (vec![(0, 64, 256)], 8192));
        let enough = LocalPlan::new(&p, &[256, 1024], 8192);
        assert_eq!(enough.cap, vec![256, 0]);
        assert_eq!(enough.partial_steps(&p), (vec![], 8192));
        assert_eq!(LocalPlan::none(2).partial_steps(&p), (vec![], 0));
        // Two local targets, one of 64-word items that 512 bytes give no room: it runs globally
        // (not short), but `new` still gave it a share, so the bytes count both.
        let small = ItemType::new("Small", "struct Small { id: u32 }");
        let big = ItemType::new("Big", "struct Big { w: array<u32, 64> }");
        let a = Procedure::new("a", small, 1)
            .emits("a", 1)
            .emits("b", 1)
            .local("a")
            .local("b")
            .body("fn a_execute(item: Small, inv: Invocation) { enqueue_a(item); var b: Big; enqueue_b(b); }");
        let b = Procedure::new("b", big, 1).body("fn b_execute(item: Big, inv: Invocation) {}");
        let two = Program::new(vec![a, b], UserBindings::none()).unwrap();
        let plan = LocalPlan::new(&two, &[256, 256], 512);
        assert_eq!(plan.cap, vec![32, 0]);
        let step_words = 256 * 64;
        assert_eq!(
            plan.partial_steps(&two),
            (vec![(0, 32, 256)], step_words * 4 * 2 * 2)
        );
    }

    #[test]
    fn a_local_target_must_be_emitted_to() {
        let node = ItemType::new("Node", "struct Node { id: u32 }");
        let a = Procedure::new("a", node, 1)
            .local("a")
            .body("fn a_execute(item: Node, inv: Invocation) {}");
        let e = Program::new(vec![a], UserBindings::none()).unwrap_err();
        assert!(e.to_string().contains("does not emit to `a`"), "{e}");
    }

    #[test]
    fn workgroup_bytes_sums_the_workgroup_arrays() {
        let src = "var<workgroup> a: array<u32, 10>; var<workgroup> b: vec4<f32>; \
                   var<private> c: array<u32, 100>;";
        assert_eq!(workgroup_bytes(src).unwrap(), 56);
    }
}
