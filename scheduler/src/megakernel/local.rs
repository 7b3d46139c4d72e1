//! Local queues: where a workgroup keeps the items its batches emit to a target declared with
//! [`crate::Procedure::local`], in its own workgroup memory, to run them as its next batch
//! (Whippletree's shared-memory queues, Steinberger et al. 2014, section 4). This module sizes
//! the regions from the workgroup memory the rest of the kernel leaves and writes their WGSL
//! constants; the protocol is in `shaders/megakernel.wgsl` (`LOCAL`) and docs/scheduler.md 2.7.

use crate::error::RunError;
use crate::program::Program;

/// Most bytes of workgroup memory the local regions and the input buffer take together, so that
/// a workgroup's memory does not cut how many workgroups an SM holds at once (the H200 gives
/// 228 KiB per SM, at most 48 KiB per workgroup under Vulkan).
pub const LOCAL_MAX_BYTES: u32 = 16 * 1024;

/// Where each target's items stay in a workgroup: `cap[t]` items of queue `t` in the words
/// `off[t]..off[t] + cap[t] * words[t]` of `wg_local_out` (0 items: `t` is nobody's local
/// target, or its item does not fit), and `wg_local_in`, the batch being run, as large as the
/// largest region.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct LocalPlan {
    pub cap: Vec<u32>,
    pub off: Vec<u32>,
    pub out_words: u32,
    pub in_words: u32,
}

impl LocalPlan {
    /// No local queue: every constant that keeps the template compiling, arrays of one word.
    pub fn none(nq: usize) -> LocalPlan {
        LocalPlan {
            cap: vec![0; nq],
            off: vec![0; nq],
            out_words: 1,
            in_words: 1,
        }
    }

    /// Regions for the program's local targets within `bytes` of workgroup memory: half for the
    /// regions (split evenly between the targets), half for the input buffer.
    pub fn new(program: &Program, bytes: u32) -> LocalPlan {
        let nq = program.queue_count();
        let targets: Vec<usize> = (0..nq)
            .filter(|&t| program.procs.iter().any(|p| p.local[t]))
            .collect();
        let mut plan = LocalPlan::none(nq);
        if targets.is_empty() {
            return plan;
        }
        let region_words = bytes / 8 / targets.len() as u32;
        let mut off = 0;
        for &t in &targets {
            let words = program.procs[t].words();
            // At most one batch of t: more would never run as one batch.
            let cap = (region_words / words).min(crate::megakernel::layout::MAX_BATCH);
            plan.cap[t] = cap;
            plan.off[t] = off;
            off += cap * words;
            plan.in_words = plan.in_words.max(cap * words);
        }
        plan.out_words = off.max(1);
        plan
    }

    /// True when some target has room for an item.
    pub fn active(&self) -> bool {
        self.cap.iter().any(|&c| c > 0)
    }

    /// Bytes of workgroup memory the plan takes.
    pub fn bytes(&self) -> u32 {
        (self.out_words + self.in_words) * 4
    }

    /// Its WGSL constants and workgroup arrays; `edge[q * NQ + t]` from the program.
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
        format!(
            "const LOCAL: bool = {on};\n\
             // LOCAL_EDGE[q * NQ + t]: 1 when q's emits to t may stay in the workgroup\n\
             const LOCAL_EDGE: array<u32, {n2}> = array<u32, {n2}>({});\n\
             // Items of queue t its local region holds, and the region's first word\n\
             const LOCAL_CAP: array<u32, {nq}> = array<u32, {nq}>({});\n\
             const LOCAL_OFF: array<u32, {nq}> = array<u32, {nq}>({});\n\
             var<workgroup> wg_local_out: array<u32, {}>;\n\
             var<workgroup> wg_local_in: array<u32, {}>;\n",
            list(&edge),
            list(&self.cap),
            list(&self.off),
            self.out_words,
            self.in_words,
            n2 = nq * nq,
        )
    }
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
        let plan = LocalPlan::new(&p, 8192);
        // Half of 8 KiB for the one region: 1024 words of 4-word items.
        assert_eq!(plan.cap, vec![256, 0]);
        assert_eq!(plan.out_words, 1024);
        assert_eq!(plan.in_words, 1024);
        assert!(plan.bytes() <= 8192);
        assert!(
            plan.wgsl(&p)
                .contains("LOCAL_EDGE: array<u32, 4> = array<u32, 4>(1u, 0u, 0u, 0u)")
        );
        assert!(!LocalPlan::none(2).active());
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
