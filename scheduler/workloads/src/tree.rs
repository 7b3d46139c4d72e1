//! A synthetic split tree: the first workload the scheduler is proven on. Each node's child count
//! comes from a hash of its id (fixed `k`, or uniform in `0..=k`), nodes carry a payload that
//! children derive from their parent's (so a word lost or misplaced in a queue changes the
//! result), and leaves fold an order-independent checksum. Inner nodes run `branch`, childless
//! nodes run `leaf`. A CPU reference gives exact item counts and the checksum.

use rayon::prelude::*;
use scheduler::bindings::UserBindings;
use scheduler::error::RunError;
use scheduler::gpu::Gpu;
use scheduler::hash::{lowbias32 as hash, lowbias32_wgsl};
use scheduler::procedure::{ItemType, Procedure};
use scheduler::program::{Program, Seed};
use scheduler::stats::RunStats;
use scheduler::strategy::Scheduler;

/// How many children an inner node has.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Fanout {
    /// Every inner node has exactly k children.
    Fixed(u32),
    /// 0..=k children, uniformly, from the node id.
    Uniform(u32),
}

/// The shape of one synthetic tree.
#[derive(Debug, Clone, PartialEq)]
pub struct TreeParams {
    /// Root nodes (the seeds).
    pub roots: u32,
    /// Nodes at this depth have no children (roots are at depth 0).
    pub max_depth: u32,
    /// Children per inner node.
    pub fanout: Fanout,
    /// Hash rounds per inner node: the per-item work cost.
    pub work: u32,
    /// Payload words per item (item size = 2 + payload words).
    pub payload_words: u32,
    /// Varies the root ids and, with [`Fanout::Uniform`], every node's child count.
    pub seed: u32,
    /// How `branch` hands its children to the queues (the program only; the tree and its
    /// result are the same either way).
    pub children: ChildEnqueue,
}

/// How the `branch` body hands a child to its queue (docs/scheduler.md 1, "Large items word by
/// word").
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum ChildEnqueue {
    /// Builds the child whole, then `enqueue_<t>(child)`: the child's words sit in registers
    /// beside the parent's.
    Whole,
    /// `reserve_<t>()`, then `store_word` of each word as it is computed.
    Words,
    /// Each strategy's faster form: words, but whole in the multi-passes for items of
    /// [`WHOLE_IN_MULTIPASS_MIN_WORDS`] or more (the body branches on `SCHED_MEGAKERNEL`), and
    /// whole in every strategy for those on a CPU adapter, where lavapipe's megakernel ran the
    /// 64-word tree of one root 1.7x slower by words (53 against 31 ms). On the H100
    /// (docs/results.md, 2026-12-06 (fifteenth session)) words took the 64-root large-payload
    /// tree's megakernel from 177 registers to 112 and from 0.538 to 0.449 ms, and every other
    /// preset's by up to 3%; the multi-passes ran the 3-word items of the other presets 0-2%
    /// faster by words, but the 64-word ones 2-16% slower (device-driven 0.593 -> 0.645 ms at
    /// 64 roots, with 128 registers whole and 80 by words).
    #[default]
    ByStrategy,
}

impl ChildEnqueue {
    /// The command-line name: `whole`, `words` or `by-strategy`.
    pub fn name(self) -> &'static str {
        match self {
            ChildEnqueue::Whole => "whole",
            ChildEnqueue::Words => "words",
            ChildEnqueue::ByStrategy => "by-strategy",
        }
    }

    /// The form of a command-line name; `None` for an unknown name.
    pub fn parse(s: &str) -> Option<ChildEnqueue> {
        [
            ChildEnqueue::Whole,
            ChildEnqueue::Words,
            ChildEnqueue::ByStrategy,
        ]
        .into_iter()
        .find(|c| c.name() == s)
    }
}

/// The named trees of the benchmark suite (`schedbench --preset NAME`, `schedbench --suite`):
/// each stresses one thing a scheduler must handle. All start from
/// [`TreeParams::binary_benchmark`] and change what their name says.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TreePreset {
    /// 64 roots, binary, depth 14: 2,097,088 items in 15 levels, trivial work (the default).
    Binary,
    /// 0..=3 children per node (mean 1.5), depth 20, 64 roots: ragged levels and leaves at
    /// every depth.
    Irregular,
    /// 0..=2 children per node (mean 1, a critical branching process), depth 200, 20,000
    /// roots: narrow, long-lived work (multi-pass needs up to 200 rounds).
    Deep,
    /// The binary tree with 62 payload words (256-byte items): queue bandwidth.
    LargePayload,
    /// The binary tree with 64 hash rounds per inner node: compute-bound items.
    HeavyWork,
}

impl TreePreset {
    /// Every preset, in the order the benchmark lists them.
    pub const ALL: [TreePreset; 5] = [
        TreePreset::Binary,
        TreePreset::Irregular,
        TreePreset::Deep,
        TreePreset::LargePayload,
        TreePreset::HeavyWork,
    ];

    /// The command-line name: `binary`, `irregular`, `deep`, `large-payload`, `heavy-work`.
    pub fn name(self) -> &'static str {
        match self {
            TreePreset::Binary => "binary",
            TreePreset::Irregular => "irregular",
            TreePreset::Deep => "deep",
            TreePreset::LargePayload => "large-payload",
            TreePreset::HeavyWork => "heavy-work",
        }
    }

    /// The preset of a command-line name; `None` for an unknown name.
    pub fn parse(s: &str) -> Option<TreePreset> {
        Self::ALL.into_iter().find(|p| p.name() == s)
    }

    /// The tree the preset names: the benchmark's trees, sized as those of the reference
    /// figures for Whippletree and a plain CUDA multi-pass that docs/results.md sets the
    /// strategies beside.
    pub fn params(self) -> TreeParams {
        let binary = TreeParams::binary_benchmark();
        match self {
            TreePreset::Binary => binary,
            TreePreset::Irregular => TreeParams {
                fanout: Fanout::Uniform(3),
                max_depth: 20,
                roots: 64,
                ..binary
            },
            TreePreset::Deep => TreeParams {
                fanout: Fanout::Uniform(2),
                max_depth: 200,
                roots: 20_000,
                ..binary
            },
            TreePreset::LargePayload => TreeParams {
                payload_words: 62,
                ..binary
            },
            TreePreset::HeavyWork => TreeParams { work: 64, ..binary },
        }
    }
}

impl TreeParams {
    /// The benchmark tree: 64 roots, binary, depth 14 = 2,097,088 items, trivial work.
    pub fn binary_benchmark() -> Self {
        TreeParams {
            roots: 64,
            max_depth: 14,
            fanout: Fanout::Fixed(2),
            work: 0,
            payload_words: 1,
            seed: 1,
            children: ChildEnqueue::ByStrategy,
        }
    }

    fn max_children(&self) -> u32 {
        match self.fanout {
            Fanout::Fixed(k) | Fanout::Uniform(k) => k,
        }
    }

    /// Children per inner node on average: K for [`Fanout::Fixed`], K/2 for
    /// [`Fanout::Uniform`] (exact in an f64).
    fn mean_fanout(&self) -> f64 {
        match self.fanout {
            Fanout::Fixed(k) => k as f64,
            Fanout::Uniform(k) => k as f64 / 2.0,
        }
    }

    /// Nodes the tree is expected to have, computed without walking it: with
    /// [`Fanout::Fixed`] (K) exactly `roots * (1 + K + ... + K^depth)`; with
    /// [`Fanout::Uniform`] (0..=K from a hash, mean K/2) the same sum with K/2, the mean over
    /// seeds. Infinite where it does not fit an f64. What a caller checks before a run that
    /// might never end ([`TreeParams::MAX_ITEMS`]).
    pub fn expected_items(&self) -> f64 {
        let m = self.mean_fanout();
        if self.roots == 0 {
            return 0.0;
        }
        let levels = self.max_depth as f64 + 1.0;
        let per_root = if (m - 1.0).abs() < 1e-12 {
            levels
        } else {
            (m.powf(levels) - 1.0) / (m - 1.0)
        };
        self.roots as f64 * per_root
    }

    /// The most nodes a tree may be expected to have ([`TreeParams::expected_items`]): the
    /// GPU strategies count executed items per procedure in 32-bit words, and a tree past
    /// 2^30 nodes takes minutes to hours on a CPU adapter. The benchmark's largest tree has
    /// 8.4M.
    pub const MAX_ITEMS: f64 = (1u64 << 30) as f64;

    /// The most hash rounds over the whole tree: nodes times (1 + `work`).
    pub const MAX_WORK: f64 = (1u64 << 36) as f64;

    /// The most hash rounds per inner node (`work`): one GPU thread runs them all.
    pub const MAX_WORK_PER_ITEM: u32 = 1 << 16;

    /// Why this tree cannot run in bounded time and memory, or `None` when it can: more
    /// nodes than [`TreeParams::MAX_ITEMS`], more work per node than
    /// [`TreeParams::MAX_WORK_PER_ITEM`], or more hash rounds than [`TreeParams::MAX_WORK`].
    pub fn too_large(&self) -> Option<String> {
        let items = self.expected_items();
        if items > Self::MAX_ITEMS {
            return Some(format!(
                "the tree would have about {items:.3e} nodes (roots {} x fanout {}^depth {}), \
                 more than the {} that can run",
                self.roots,
                self.max_children(),
                self.max_depth,
                Self::MAX_ITEMS
            ));
        }
        if self.work > Self::MAX_WORK_PER_ITEM {
            return Some(format!(
                "{} hash rounds per node is more than the {} one GPU thread may run",
                self.work,
                Self::MAX_WORK_PER_ITEM
            ));
        }
        let rounds = items * (1.0 + self.work as f64);
        if rounds > Self::MAX_WORK {
            return Some(format!(
                "about {items:.3e} nodes x {} hash rounds each is {rounds:.3e} rounds, more \
                 than the {} that can run",
                self.work,
                Self::MAX_WORK
            ));
        }
        None
    }

    /// One line of every parameter, for reports.
    pub fn describe(&self) -> String {
        let f = match self.fanout {
            Fanout::Fixed(k) => format!("fixed:{k}"),
            Fanout::Uniform(k) => format!("uniform:0..{k}"),
        };
        let children = match self.children {
            ChildEnqueue::ByStrategy => String::new(),
            c => format!(" children={}", c.name()),
        };
        format!(
            "roots={} depth={} fanout={f} work={} payload={} seed={}{children}",
            self.roots, self.max_depth, self.work, self.payload_words, self.seed
        )
    }
}

/// What a run of the tree produced: items per procedure and the leaf checksum.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct TreeResult {
    /// Inner nodes executed (`branch` items).
    pub branches: u64,
    /// Leaves executed (`leaf` items).
    pub leaves: u64,
    /// Leaves that reached the output buckets (must equal `leaves`).
    pub leaves_folded: u64,
    /// Wrapping sum of every leaf's hash.
    pub leaf_sum: u32,
    /// Xor of `hash(h)` over every leaf's hash `h`.
    pub leaf_xor: u32,
}

impl TreeResult {
    /// Every node of the tree (branches and leaves).
    pub fn items(&self) -> u64 {
        self.branches + self.leaves
    }

    fn add_leaf(&mut self, id: u32, depth: u32, payload: &[u32]) {
        let h = TreeParams::leaf_hash(id, depth, payload);
        self.leaves += 1;
        self.leaves_folded += 1;
        self.leaf_sum = self.leaf_sum.wrapping_add(h);
        self.leaf_xor ^= hash(h);
    }

    /// The result of two disjoint parts of a tree: counts and sums add, xors combine.
    fn merge(self, o: TreeResult) -> TreeResult {
        TreeResult {
            branches: self.branches + o.branches,
            leaves: self.leaves + o.leaves,
            leaves_folded: self.leaves_folded + o.leaves_folded,
            leaf_sum: self.leaf_sum.wrapping_add(o.leaf_sum),
            leaf_xor: self.leaf_xor ^ o.leaf_xor,
        }
    }
}

/// Subtrees the parallel CPU walk aims to hand out per rayon thread (it expands the top of
/// the tree breadth-first until it has them, so a few roots still spread over every core).
const SUBTREES_PER_THREAD: usize = 64;

const BUCKETS: u32 = 256;

/// The host twin of the WGSL `TreeNode` with `payload_words` payload words.
fn node_words(id: u32, depth: u32, payload: &[u32]) -> Vec<u32> {
    let mut w = vec![id, depth];
    w.extend_from_slice(payload);
    w
}

impl TreeParams {
    fn children(&self, id: u32, depth: u32) -> u32 {
        if depth >= self.max_depth {
            return 0;
        }
        match self.fanout {
            Fanout::Fixed(k) => k,
            Fanout::Uniform(k) => hash(id ^ self.seed.wrapping_mul(0x9e37_79b9)) % (k + 1),
        }
    }

    fn root(&self, i: u32) -> (u32, Vec<u32>) {
        let id = hash(i.wrapping_add(self.seed.wrapping_mul(0x632b_e5ab)));
        let payload = (0..self.payload_words)
            .map(|w| hash(id ^ w.wrapping_mul(0x85eb_ca6b)))
            .collect();
        (id, payload)
    }

    fn child(&self, id: u32, payload: &[u32], work: u32, j: u32) -> (u32, Vec<u32>) {
        let mut p = Vec::with_capacity(payload.len());
        let cid = Self::child_into(id, payload, work, j, &mut p);
        (cid, p)
    }

    /// Child `j` of node `id`: returns its id and appends its payload words to `out`.
    fn child_into(id: u32, payload: &[u32], work: u32, j: u32, out: &mut Vec<u32>) -> u32 {
        let cid = hash(id.wrapping_mul(0x9e37_79b9).wrapping_add(j + 1));
        let at = out.len();
        out.extend(
            payload
                .iter()
                .enumerate()
                .map(|(w, &x)| hash(x ^ cid ^ (w as u32).wrapping_mul(0x85eb_ca6b))),
        );
        out[at] ^= work;
        cid
    }

    fn work_of(&self, id: u32) -> u32 {
        let mut x = id;
        for i in 0..self.work {
            x = hash(x.wrapping_add(i));
        }
        x
    }

    fn leaf_hash(id: u32, depth: u32, payload: &[u32]) -> u32 {
        let mut h = hash(id ^ (depth << 24));
        for &x in payload {
            h = hash(h ^ x);
        }
        h
    }

    /// The CPU reference: walks the whole tree.
    pub fn reference(&self) -> TreeResult {
        let mut r = TreeResult {
            branches: 0,
            leaves: 0,
            leaves_folded: 0,
            leaf_sum: 0,
            leaf_xor: 0,
        };
        let mut stack: Vec<(u32, u32, Vec<u32>)> = (0..self.roots)
            .map(|i| {
                let (id, p) = self.root(i);
                (id, 0, p)
            })
            .collect();
        while let Some((id, depth, payload)) = stack.pop() {
            let c = self.children(id, depth);
            if c == 0 {
                r.add_leaf(id, depth, &payload);
            } else {
                r.branches += 1;
                let work = self.work_of(id);
                for j in 0..c {
                    let (cid, p) = self.child(id, &payload, work, j);
                    stack.push((cid, depth + 1, p));
                }
            }
        }
        r
    }

    /// [`TreeParams::reference`] on every core (rayon): the same [`TreeResult`], the CPU floor a
    /// GPU result must beat. The top of the tree is expanded breadth-first on the calling
    /// thread until there are `SUBTREES_PER_THREAD` subtrees per rayon thread (or the tree
    /// ends); rayon then walks the subtrees depth-first, each with a flat stack of payload
    /// words, so no node allocates. Children's order differs from the reference's, which
    /// cannot change the result: every fold is commutative.
    pub fn cpu_parallel(&self) -> TreeResult {
        let p = self.payload_words as usize;
        let mut done = TreeResult::default();
        // The frontier: node ids and depths, and their payloads back to back.
        let (mut nodes, mut words) = (Vec::new(), Vec::new());
        for i in 0..self.roots {
            let (id, payload) = self.root(i);
            nodes.push((id, 0));
            words.extend(payload);
        }
        let want = SUBTREES_PER_THREAD * rayon::current_num_threads();
        while !nodes.is_empty() && nodes.len() < want {
            let (mut next, mut next_words) = (Vec::new(), Vec::new());
            for (i, &(id, depth)) in nodes.iter().enumerate() {
                let payload = &words[i * p..(i + 1) * p];
                let c = self.children(id, depth);
                if c == 0 {
                    done.add_leaf(id, depth, payload);
                    continue;
                }
                done.branches += 1;
                let work = self.work_of(id);
                for j in 0..c {
                    let cid = Self::child_into(id, payload, work, j, &mut next_words);
                    next.push((cid, depth + 1));
                }
            }
            (nodes, words) = (next, next_words);
        }
        nodes
            .par_iter()
            .enumerate()
            .fold(
                || (TreeResult::default(), Vec::new(), Vec::new(), vec![0; p]),
                |(mut r, mut stack, mut stack_words, mut parent), (i, &(id, depth))| {
                    stack.push((id, depth));
                    stack_words.extend_from_slice(&words[i * p..(i + 1) * p]);
                    while let Some((id, depth)) = stack.pop() {
                        let at = stack_words.len() - p;
                        parent.copy_from_slice(&stack_words[at..]);
                        stack_words.truncate(at);
                        let c = self.children(id, depth);
                        if c == 0 {
                            r.add_leaf(id, depth, &parent);
                            continue;
                        }
                        r.branches += 1;
                        let work = self.work_of(id);
                        for j in 0..c {
                            let cid = Self::child_into(id, &parent, work, j, &mut stack_words);
                            stack.push((cid, depth + 1));
                        }
                    }
                    (r, stack, stack_words, parent)
                },
            )
            .map(|(r, ..)| r)
            .reduce(TreeResult::default, TreeResult::merge)
            .merge(done)
    }

    /// The program for a GPU: `branch` (emits up to the fan-out to `branch` and to `leaf`) and
    /// `leaf`, with the output buckets and run-time shape as user bindings. Errors:
    /// [`RunError::Program`] for a payload outside `1..=254` words.
    pub fn program(&self) -> Result<Program, RunError> {
        self.program_on(false)
    }

    /// [`TreeParams::program`] for a CPU adapter (`cpu`, such as lavapipe) or a GPU: they
    /// differ only in the form [`ChildEnqueue::ByStrategy`] picks.
    pub fn program_on(&self, cpu: bool) -> Result<Program, RunError> {
        let p = self.payload_words;
        if p == 0 || p > 254 {
            return Err(RunError::Program("payload words must be 1..=254".into()));
        }
        let item = ItemType::new(
            "TreeNode",
            &format!("struct TreeNode {{ id: u32, depth: u32, payload: array<u32, {p}> }}"),
        );
        let k = self.max_children();
        let user = UserBindings {
            wgsl: format!(
                "@group(1) @binding(0) var<storage, read_write> tree_out: array<atomic<u32>>;\n\
                 // Tree shape at run time, so one compiled program serves every tree of this payload size.\n\
                 @group(1) @binding(1) var<storage, read> tree_cfg: array<u32, 5>;\n\
                 const TREE_P: u32 = {p}u;\n{}{}",
                lowbias32_wgsl("tree_hash"),
                TREE_WGSL
            ),
            layout: vec![
                scheduler::storage_entry(0, false),
                scheduler::storage_entry(1, true),
            ],
        };
        let branch = Procedure::new("branch", item.clone(), 1)
            .emits("branch", k)
            .emits("leaf", k)
            // A node's children run next on its workgroup while they fit (docs/scheduler.md 2.7).
            .local("branch")
            .local("leaf")
            .body(&unrolled(&branch_body(self.children, p, cpu), p));
        let leaf = Procedure::new("leaf", item, 1).body(&unrolled(LEAF_WGSL, p));
        Program::new(vec![branch, leaf], user)
    }

    /// The roots, as seeds of `branch` (roots with children) and `leaf` (the others).
    pub fn seeds(&self) -> Vec<Seed> {
        let (mut branch, mut leaf) = (Vec::new(), Vec::new());
        for i in 0..self.roots {
            let (id, payload) = self.root(i);
            let words = node_words(id, 0, &payload);
            if self.children(id, 0) > 0 {
                branch.extend(words)
            } else {
                leaf.extend(words)
            }
        }
        vec![
            Seed {
                procedure: "branch".into(),
                words: branch,
            },
            Seed {
                procedure: "leaf".into(),
                words: leaf,
            },
        ]
    }
}

/// The tree program's procedures, in registration order (`--procedure-steps` names).
pub const PROCEDURES: [&str; 2] = ["branch", "leaf"];

// `tree_hash` is `scheduler::hash::lowbias32_wgsl`, the twin of the CPU reference's hash.
const TREE_WGSL: &str = r#"
fn tree_children(id: u32, depth: u32) -> u32 {
    if depth >= tree_cfg[0] { return 0u; }
    if tree_cfg[2] == 1u { return tree_hash(id ^ tree_cfg[3]) % (tree_cfg[1] + 1u); }
    return tree_cfg[1];
}
"#;

// The bodies as written: loops over the payload. `TreeParams::program` unrolls them (`unrolled`)
// for the program's payload size, as a CUDA compiler unrolls loops of constant trip count; the
// Vulkan driver keeps such a loop, and with it the payload in local memory instead of
// registers (1.6x the GPU time of the large-payload tree on the H200: docs/results.md, "Large
// items: how they are copied"). Both copy the item into a `var` first: indexing the `item` parameter (a value)
// with a run-time index makes naga's SPIR-V copy the whole array to a temporary at every access
// (`Program::new` warns of it; docs/scheduler.md, "Writing fast procedures").
const BRANCH_WGSL: &str = r#"
fn branch_execute(item_value: TreeNode, inv: Invocation) {
    var item = item_value;
    var x = item.id;
    for (var i = 0u; i < tree_cfg[4]; i++) { x = tree_hash(x + i); }
    let c = tree_children(item.id, item.depth);
    for (var j = 0u; j < c; j++) {
        let id = tree_hash(item.id * 0x9e3779b9u + j + 1u);
        let depth = item.depth + 1u;
        CHILD
    }
}
"#;

// A child built whole, then enqueued.
const CHILD_WHOLE_WGSL: &str = r#"
        var child: TreeNode;
        child.id = id;
        child.depth = depth;
        for (var w = 0u; w < TREE_P; w++) {
            child.payload[w] = tree_hash(item.payload[w] ^ child.id ^ (w * 0x85ebca6bu));
        }
        child.payload[0] ^= x;
        if tree_children(child.id, child.depth) > 0u { enqueue_branch(child); } else { enqueue_leaf(child); }
"#;

// The same child stored word by word into its reserved slot as each word is computed, so that
// it never sits whole in registers beside its parent. One `slot_reserved` test guards all the
// stores: on the H100, stores left to `store_word`'s own test of every word made the 4-root
// large-payload tree's megakernel 13% slower (0.158 -> 0.180 ms; docs/results.md, fifteenth
// session).
const CHILD_WORDS_WGSL: &str = r#"
        var slot: ItemSlot;
        if tree_children(id, depth) > 0u { slot = reserve_branch(); } else { slot = reserve_leaf(); }
        if slot_reserved(slot) {
            store_word(slot, TreeNode_id_word, id);
            store_word(slot, TreeNode_depth_word, depth);
            for (var w = 0u; w < TREE_P; w++) { store_word(slot, TreeNode_payload_word + (w * 1u), tree_hash(item.payload[w] ^ id ^ (w * 0x85ebca6bu)) ^ select(0u, x, (w * 1u) == 0u)); }
        }
"#;

/// Smallest item, in words, that [`ChildEnqueue::ByStrategy`] enqueues whole in the
/// multi-passes. Measured at 3 words (words faster) and 64 (whole faster); 16 is where
/// [`scheduler::ItemLayout::for_program`] turns to planar queues, a word a plane.
pub const WHOLE_IN_MULTIPASS_MIN_WORDS: u32 = 16;

/// The `branch` body (payload loops not yet unrolled) for `children`, items of
/// `payload_words + 2` words, and a CPU adapter (`cpu`) or a GPU.
fn branch_body(children: ChildEnqueue, payload_words: u32, cpu: bool) -> String {
    let large = payload_words + 2 >= WHOLE_IN_MULTIPASS_MIN_WORDS;
    let child = match children {
        ChildEnqueue::Whole => CHILD_WHOLE_WGSL.to_string(),
        ChildEnqueue::Words => CHILD_WORDS_WGSL.to_string(),
        ChildEnqueue::ByStrategy if !large => CHILD_WORDS_WGSL.to_string(),
        ChildEnqueue::ByStrategy if cpu => CHILD_WHOLE_WGSL.to_string(),
        ChildEnqueue::ByStrategy => format!(
            "if SCHED_MEGAKERNEL {{{CHILD_WORDS_WGSL}        }} else {{{CHILD_WHOLE_WGSL}        }}"
        ),
    };
    BRANCH_WGSL.replace("CHILD", child.trim())
}

// Leaves fold in two levels: into the workgroup's accumulators (workgroup atomics), then, once
// per workgroup step, slot 0 folds those into one of the 256 output buckets: a global atomic
// triple per 256 leaves instead of per leaf (on the H200 the binary tree's million leaves went
// from 3 million global atomics on 768 words to 12 thousand). The body is called by every thread
// of the step in uniform control flow (docs/scheduler.md, section 1), so it may use barriers.
const LEAF_WGSL: &str = r#"
var<workgroup> tree_fold: array<atomic<u32>, 3>;
fn leaf_execute(item_value: TreeNode, inv: Invocation) {
    if inv.slot == 0u {
        atomicStore(&tree_fold[0], 0u);
        atomicStore(&tree_fold[1], 0u);
        atomicStore(&tree_fold[2], 0u);
    }
    workgroupBarrier();
    if inv.live {
        var item = item_value;
        var h = tree_hash(item.id ^ (item.depth << 24u));
        for (var w = 0u; w < TREE_P; w++) { h = tree_hash(h ^ item.payload[w]); }
        atomicAdd(&tree_fold[0], 1u);
        atomicAdd(&tree_fold[1], h);
        atomicXor(&tree_fold[2], tree_hash(h));
    }
    workgroupBarrier();
    if inv.slot == 0u {
        let n = atomicLoad(&tree_fold[0]);
        if n > 0u {
            // Spread over buckets: one counter for every step would serialise the GPU.
            let x = atomicLoad(&tree_fold[2]);
            let b = (x & 255u) * 4u;
            atomicAdd(&tree_out[b], n);
            atomicAdd(&tree_out[b + 1u], atomicLoad(&tree_fold[1]));
            atomicXor(&tree_out[b + 2u], x);
        }
    }
}
"#;

/// `body` with its payload loops (`for (var w = 0u; w < TREE_P; w++) { ... }`, one statement
/// each, no nested braces) unrolled for `p` payload words.
fn unrolled(body: &str, p: u32) -> String {
    let head = "for (var w = 0u; w < TREE_P; w++) {";
    let mut out = String::new();
    let mut rest = body;
    while let Some(at) = rest.find(head) {
        out += &rest[..at];
        let after = &rest[at + head.len()..];
        let end = after.find('}').expect("a one-statement payload loop");
        let stmt = after[..end].trim();
        for w in 0..p {
            out += &stmt
                .replace("[w]", &format!("[{w}u]"))
                .replace("(w *", &format!("({w}u *"));
            out += " ";
        }
        rest = &after[end + 1..];
    }
    out + rest
}

/// The tree's GPU resources: its output buckets and their bind group.
pub struct TreeRun {
    /// The tree the next run walks ([`TreeRun::params`]; changed by [`TreeRun::set_params`]).
    params: TreeParams,
    /// Its roots as the runs' seeds, made once: 0.1-0.2 us a root on the host, which every
    /// run's wall time paid before (20,000 roots: about 2 ms against a 1.4 ms GPU run).
    seeds: Vec<Seed>,
    /// Its program ([`TreeParams::program`]).
    pub program: Program,
    out: wgpu::Buffer,
    cfg: wgpu::Buffer,
    bind: wgpu::BindGroup,
    /// The fan-out the program declared in its max_emits.
    declared_children: u32,
}

impl TreeRun {
    /// Builds the program and the output buffers. Errors: [`RunError::Program`] (see
    /// [`TreeParams::program`]), [`RunError::Device`] if a buffer cannot be made.
    pub fn new(gpu: &Gpu, params: TreeParams) -> Result<TreeRun, RunError> {
        let program = params.program_on(gpu.is_cpu_adapter())?;
        let out = gpu.storage_buffer("tree out", (BUCKETS * 4) as u64)?;
        let cfg = gpu.storage_buffer("tree cfg", 5)?;
        let bind = program.user.bind_group(gpu, &[&out, &cfg])?;
        Ok(TreeRun {
            declared_children: params.max_children(),
            seeds: params.seeds(),
            params,
            program,
            out,
            cfg,
            bind,
        })
    }

    /// Another tree of the same payload size: same compiled program, new shape.
    pub fn set_params(&mut self, params: TreeParams) -> Result<(), RunError> {
        if params.payload_words != self.params.payload_words
            || params.children != self.params.children
            || params.max_children() > self.declared_children
        {
            return Err(RunError::Program(
                "a tree of another payload size, child enqueue or larger fan-out needs its own \
                 program"
                    .into(),
            ));
        }
        self.seeds = params.seeds();
        self.params = params;
        Ok(())
    }

    /// The tree the next run walks.
    pub fn params(&self) -> &TreeParams {
        &self.params
    }

    /// Runs once and reads the result back.
    pub fn run(
        &self,
        gpu: &Gpu,
        scheduler: &Scheduler,
    ) -> Result<(RunStats, TreeResult), RunError> {
        self.run_within(gpu, scheduler, None)
    }

    /// [`TreeRun::run`] with the queue storage bounded (see [`Scheduler::run_within`]).
    pub fn run_within(
        &self,
        gpu: &Gpu,
        scheduler: &Scheduler,
        max_queue_bytes: Option<u64>,
    ) -> Result<(RunStats, TreeResult), RunError> {
        // Zeroed by a queue write (4 KiB), which lands with the run's first submission: no
        // submission of its own.
        let zeros = [0u32; (BUCKETS * 4) as usize];
        gpu.queue
            .write_buffer(&self.out, 0, bytemuck::cast_slice(&zeros));
        let p = &self.params;
        let cfg = [
            p.max_depth,
            p.max_children(),
            matches!(p.fanout, Fanout::Uniform(_)) as u32,
            p.seed.wrapping_mul(0x9e37_79b9),
            p.work,
        ];
        gpu.queue
            .write_buffer(&self.cfg, 0, bytemuck::cast_slice(&cfg));
        // The folds come back with the run's last read-back: no round trip of their own.
        let out = [(&self.out, 0, (BUCKETS * 4) as u64)];
        let (stats, mut words) =
            scheduler.run_reading(gpu, &self.seeds, Some(&self.bind), max_queue_bytes, &out)?;
        let words = words.pop().expect("the folds' range");
        let mut r = TreeResult {
            branches: stats.executed[0],
            leaves: stats.executed[1],
            leaves_folded: 0,
            leaf_sum: 0,
            leaf_xor: 0,
        };
        for b in words.chunks(4) {
            r.leaves_folded += b[0] as u64;
            r.leaf_sum = r.leaf_sum.wrapping_add(b[1]);
            r.leaf_xor ^= b[2];
        }
        Ok((stats, r))
    }
}

/// Megakernel steps per batch of the tree's procedures on `gpu`
/// (`MegakernelConfig::procedure_batch_steps`): 4 for `leaf`, whose items emit nothing, so a
/// larger batch holds no child back; `branch` keeps the configured steps, publishing children
/// early. H200, median of 10 (docs/results.md, 2026-12-02, "Batch steps per procedure"): binary
/// 0.239 -> 0.226 ms, large-payload 0.759 -> 0.686, heavy-work 0.325 -> 0.290, deep and
/// irregular within 1%. None on lavapipe, whose loop limiter counts a batch's steps.
pub fn megakernel_procedure_steps(gpu: &scheduler::Gpu) -> Vec<(String, u32)> {
    if gpu.is_lavapipe() {
        return Vec::new();
    }
    vec![("leaf".into(), 4)]
}

/// Most roots of a tree that [`TreeParams::megakernel_workgroup_share`] calls narrow: levels of
/// about this many items fill under half of the H100's 169K lanes at its probed width (660
/// workgroups of 256), so fewer workgroups lose them no parallelism.
pub const NARROW_ROOTS: u32 = 65_536;

/// Local area in workgroup memory of a narrow tree's megakernel
/// ([`TreeParams::megakernel_local_workgroup_bytes`]): a full step (256 items of 3 words) per
/// buffer of both local targets.
pub const NARROW_LOCAL_WORKGROUP_BYTES: u32 = 12 * 1024;

/// Least `max_compute_workgroup_storage_size` for which a narrow tree takes the local area in
/// workgroup memory: the area, the kernel's own 8 KiB, and room to spare.
pub const NARROW_MIN_WORKGROUP_STORAGE: u32 = 32 * 1024;

impl TreeParams {
    /// Whether the megakernel should keep a workgroup's children local
    /// (`MegakernelConfig::local_queues`; the program declares them local): wherever the tree
    /// does not die out, a fixed fan-out of one or more or a random one of mean one or more
    /// (0..=k children, k >= 2). A batch's children fill the workgroup's next steps and skip the
    /// global queue's round trips. Where the mean is one (deep: 0..=2) a workgroup's lineages
    /// thin out, and its leaves, a few a level, took every other local turn until held leaves
    /// waited for held branches (`LOCAL_DEFER`, docs/scheduler.md 2.7); since then local queues
    /// pay there too. H200, GPU ms median of 10, without / with local queues (docs/results.md,
    /// 2026-12-04 (fourth session)): deep 20,000 roots 1.344 / 1.11-1.16, 5,000 roots 1.304 /
    /// 1.08-1.12, 1,250 roots 1.29 / 1.00-1.02. Earlier, for the other presets (2026-12-04, "A
    /// local batch without barriers of its own"): binary 0.160 -> 0.122 ms, heavy work 0.184 ->
    /// 0.164, large-payload 0.567 -> 0.534, irregular 0.183 -> 0.174, the one-item chain on one
    /// workgroup 8.53 -> 5.12 ms. A tree of mean fan-out below one (0..=1) is left without:
    /// not measured.
    pub fn megakernel_local_queues(&self) -> bool {
        self.mean_fanout() >= 1.0
    }

    /// Whether the tree is narrow: a mean fan-out of at most one (one child, or 0..=k children
    /// with k <= 2), whose levels stay near the roots' count, and at most [`NARROW_ROOTS`]
    /// roots.
    fn narrow(&self) -> bool {
        self.mean_fanout() <= 1.0 && self.roots <= NARROW_ROOTS
    }

    /// Bytes of workgroup memory for the megakernel's local area
    /// (`MegakernelConfig::local_workgroup_bytes`) at `workgroup_size` threads a workgroup:
    /// [`NARROW_LOCAL_WORKGROUP_BYTES`] for a narrow tree that keeps its children local and
    /// whose items are at most 3 words (one payload word: a buffer holds a step of 256
    /// threads, the default size and the only one it is taken at), on a GPU whose workgroups
    /// may hold at least [`NARROW_MIN_WORKGROUP_STORAGE`] bytes (the area and the kernel's own
    /// 8 KiB, with room to spare); else 0 (the slots buffer). Its lineages are few and long, so a local turn's cost
    /// is the chain: with the area a local batch that kept all its children skips the
    /// device-scope fence and the publish barrier. H100, GPU ms median of 20 (docs/results.md,
    /// 2026-12-06 (fourteenth session)): the one-item chain 4.761 -> 3.932 ms (2.38 -> 1.97 us
    /// a local turn), deep 0.949 -> 0.916, 1,250 roots 0.914 -> 0.882, 5,000 roots 0.933 ->
    /// 0.898, at 132 workgroups either way; on the H200 the chain's local turn is 1.96 us. Not
    /// on CPU adapters (lavapipe), where it was not measured. Wide trees keep the slots buffer:
    /// the area costs them co-resident workgroups (binary 0.127 -> 0.175 ms, docs/results.md,
    /// 2026-12-06 (eleventh session)).
    pub fn megakernel_local_workgroup_bytes(
        &self,
        gpu: &scheduler::Gpu,
        workgroup_size: u32,
    ) -> u32 {
        let limit = gpu.device.limits().max_compute_workgroup_storage_size;
        self.local_workgroup_bytes_on(gpu.is_cpu_adapter(), limit, workgroup_size)
    }

    /// [`TreeParams::megakernel_local_workgroup_bytes`] on an adapter that is a CPU or not and
    /// whose workgroups may hold `max_storage` bytes.
    fn local_workgroup_bytes_on(&self, cpu_adapter: bool, max_storage: u32, threads: u32) -> u32 {
        // A larger workgroup has larger steps, and its kernel more workgroup memory of its own.
        let step_fits = self.payload_words <= 1
            && threads == scheduler::MegakernelConfig::default().workgroup_size;
        let fits = max_storage >= NARROW_MIN_WORKGROUP_STORAGE;
        match self.narrow() && self.megakernel_local_queues() && step_fits && fits && !cpu_adapter {
            true => NARROW_LOCAL_WORKGROUP_BYTES,
            false => 0,
        }
    }

    /// The share (numerator, denominator) of the probed workgroups the megakernel should
    /// launch (`Workgroups::ProbeShare`) with `local_workgroup_bytes` of local area in
    /// workgroup memory: on a GPU where the tree stays narrow (as for
    /// [`TreeParams::megakernel_local_workgroup_bytes`]) one workgroup per SM on the H100, whose
    /// probe finds five per SM for the deep trees without the area (1/5) and two with
    /// [`NARROW_LOCAL_WORKGROUP_BYTES`] of it (1/2); else all. Its batches then run
    /// faster spread over the SMs than shared (docs/scheduler.md 2.2, "Presence or claims").
    /// H100, GPU ms median of 20 (docs/results.md, 2026-12-06 (eleventh session) and (twelfth
    /// session)), all 660 probed / 396 / 264 / 132: deep 1.15 / 1.03 / 0.99 / -, then 1.117 / - /
    /// 0.981 / 0.954; deep of 1,250 roots 1.00 / 0.94 / 0.93 / -, then 0.981 / - / 0.920 /
    /// 0.912; irregular (mean 1.5, 528 probed) 0.147 / 0.143 at 396 / 0.148 at 264, binary
    /// 0.127 / 0.133 / 0.155. With the area (fourteenth session): deep 0.917 at 132 (1/2),
    /// 0.951 at 264. On CPU adapters (lavapipe), where it was not measured, all.
    pub fn megakernel_workgroup_share(
        &self,
        gpu: &scheduler::Gpu,
        local_workgroup_bytes: u32,
    ) -> (u32, u32) {
        self.workgroup_share_on(gpu.is_cpu_adapter(), local_workgroup_bytes)
    }

    /// [`TreeParams::megakernel_workgroup_share`] on an adapter that is a CPU or not.
    fn workgroup_share_on(&self, cpu_adapter: bool, local_workgroup_bytes: u32) -> (u32, u32) {
        match (self.narrow() && !cpu_adapter, local_workgroup_bytes) {
            (false, _) => (1, 1),
            (true, 0) => (1, 5),
            (true, _) => (1, 2),
        }
    }
}

#[cfg(test)]
mod tests {
    /// Local queues where the tree does not die out: a fixed fan-out of one or more, a random
    /// one whose mean is one or more.
    #[test]
    fn local_queues_only_where_the_tree_does_not_die_out() {
        use super::{Fanout, TreeParams, TreePreset};
        let chosen: Vec<bool> = TreePreset::ALL
            .iter()
            .map(|p| p.params().megakernel_local_queues())
            .collect();
        // binary, irregular, deep, large-payload, heavy work
        assert_eq!(chosen, [true; 5]);
        let with = |fanout| TreeParams {
            fanout,
            ..TreePreset::Binary.params()
        };
        assert!(with(Fanout::Fixed(1)).megakernel_local_queues());
        assert!(!with(Fanout::Fixed(0)).megakernel_local_queues());
        assert!(with(Fanout::Uniform(2)).megakernel_local_queues());
        assert!(!with(Fanout::Uniform(1)).megakernel_local_queues());
        assert!(with(Fanout::Uniform(4)).megakernel_local_queues());
    }

    /// Narrow trees that keep their children local (mean fan-out one, one payload word) take
    /// the local area in workgroup memory on a GPU with room for it, and one workgroup per SM
    /// of the H100 with it (1/2 of the probed count) or without it (1/5); the wide presets,
    /// CPU adapters and small workgroup memories take neither.
    #[test]
    fn narrow_trees_take_the_workgroup_area_and_their_share_on_gpus_only() {
        use super::{
            Fanout, NARROW_LOCAL_WORKGROUP_BYTES as AREA, NARROW_MIN_WORKGROUP_STORAGE as MIN,
            NARROW_ROOTS, TreeParams, TreePreset,
        };
        let deep = TreePreset::Deep.params();
        assert_eq!(deep.local_workgroup_bytes_on(false, MIN, 256), AREA);
        assert_eq!(deep.local_workgroup_bytes_on(false, 48 * 1024, 256), AREA);
        assert_eq!(
            deep.local_workgroup_bytes_on(true, MIN, 256),
            0,
            "CPU adapter"
        );
        assert_eq!(
            deep.local_workgroup_bytes_on(false, MIN - 1, 256),
            0,
            "16 KiB devices"
        );
        assert_eq!(
            deep.local_workgroup_bytes_on(false, MIN, 512),
            0,
            "larger workgroups"
        );
        assert_eq!(deep.workgroup_share_on(false, AREA), (1, 2));
        assert_eq!(deep.workgroup_share_on(false, 0), (1, 5));
        assert_eq!(deep.workgroup_share_on(true, 0), (1, 1));
        let chain = TreeParams {
            fanout: Fanout::Fixed(1),
            roots: 1,
            ..deep.clone()
        };
        assert_eq!(chain.local_workgroup_bytes_on(false, MIN, 256), AREA);
        let heavy_items = TreeParams {
            payload_words: 2,
            ..deep.clone()
        };
        assert_eq!(
            heavy_items.local_workgroup_bytes_on(false, MIN, 256),
            0,
            "a step would not fit"
        );
        let many_roots = TreeParams {
            roots: NARROW_ROOTS + 1,
            ..deep.clone()
        };
        assert_eq!(many_roots.local_workgroup_bytes_on(false, MIN, 256), 0);
        assert_eq!(many_roots.workgroup_share_on(false, 0), (1, 1));
        let dies_out = TreeParams {
            fanout: Fanout::Uniform(1),
            ..deep
        };
        assert_eq!(
            dies_out.local_workgroup_bytes_on(false, MIN, 256),
            0,
            "no local queues"
        );
        for p in [
            TreePreset::Binary,
            TreePreset::Irregular,
            TreePreset::LargePayload,
            TreePreset::HeavyWork,
        ] {
            assert_eq!(
                p.params().local_workgroup_bytes_on(false, MIN, 256),
                0,
                "{}",
                p.name()
            );
            assert_eq!(
                p.params().workgroup_share_on(false, 0),
                (1, 1),
                "{}",
                p.name()
            );
        }
    }

    /// The expected size is the exact count for fixed fanouts, the presets all run, and the
    /// trees of the issue that never ended (or aborted) are refused.
    #[test]
    fn expected_size_refuses_trees_that_cannot_run() {
        for p in TreePreset::ALL {
            assert_eq!(p.params().too_large(), None, "{}", p.name());
        }
        let binary = TreeParams::binary_benchmark();
        assert_eq!(binary.expected_items(), 2_097_088.0);
        let small = TreeParams {
            roots: 3,
            max_depth: 5,
            fanout: Fanout::Fixed(3),
            ..binary.clone()
        };
        let r = small.reference();
        assert_eq!(small.expected_items(), (r.branches + r.leaves) as f64);
        for bad in [
            TreeParams {
                roots: u32::MAX,
                ..binary.clone()
            },
            TreeParams {
                max_depth: u32::MAX,
                ..binary.clone()
            },
            TreeParams {
                max_depth: 40,
                ..binary.clone()
            },
            TreeParams {
                fanout: Fanout::Fixed(16),
                max_depth: 12,
                ..binary.clone()
            },
            TreeParams {
                work: u32::MAX,
                ..binary.clone()
            },
            TreeParams {
                max_depth: u32::MAX,
                ..TreePreset::Deep.params()
            },
        ] {
            assert!(bad.too_large().is_some(), "{}", bad.describe());
        }
        // A dying tree (mean fanout 1/2) is small at any depth.
        let dying = TreeParams {
            fanout: Fanout::Uniform(1),
            max_depth: u32::MAX,
            ..binary
        };
        assert_eq!(dying.too_large(), None);
    }

    #[test]
    fn procedures_are_named_as_listed() {
        let program = TreePreset::Binary.params().program().unwrap();
        let names: Vec<&str> = program.procs.iter().map(|p| p.proc.name.as_str()).collect();
        assert_eq!(names, PROCEDURES);
    }

    #[test]
    fn payload_loops_unroll_to_one_statement_per_word() {
        let whole =
            "child.payload[2u] = tree_hash(item.payload[2u] ^ child.id ^ (2u * 0x85ebca6bu));";
        let words = "store_word(slot, TreeNode_payload_word + (2u * 1u), tree_hash(item.payload[2u] \
                     ^ id ^ (2u * 0x85ebca6bu)) ^ select(0u, x, (2u * 1u) == 0u));";
        for (children, p, line) in [
            (ChildEnqueue::Whole, 3, whole),
            (ChildEnqueue::ByStrategy, 14, whole),
            (ChildEnqueue::Words, 3, words),
            (ChildEnqueue::ByStrategy, 14, words),
        ] {
            let b = super::unrolled(&super::branch_body(children, p, false), p);
            assert!(!b.contains("TREE_P") && b.contains(line), "{line}: {b}");
        }
        for cpu in [false, true] {
            assert!(!super::branch_body(ChildEnqueue::Whole, 62, cpu).contains("store_word"));
            assert!(!super::branch_body(ChildEnqueue::Words, 62, cpu).contains("enqueue_"));
            // By strategy: words everywhere for items under 16 words.
            let small = super::branch_body(ChildEnqueue::ByStrategy, 13, cpu);
            assert!(!small.contains("enqueue_") && !small.contains("SCHED_MEGAKERNEL"));
        }
        // From there, whole in the multi-passes on a GPU, everywhere on a CPU adapter.
        let large = super::branch_body(ChildEnqueue::ByStrategy, 14, false);
        assert!(large.contains("if SCHED_MEGAKERNEL {") && large.contains("enqueue_"));
        let on_cpu = super::branch_body(ChildEnqueue::ByStrategy, 14, true);
        assert!(!on_cpu.contains("store_word") && !on_cpu.contains("SCHED_MEGAKERNEL"));
        let l = super::unrolled(super::LEAF_WGSL, 2);
        assert!(
            l.contains("h = tree_hash(h ^ item.payload[1u]);") && !l.contains("TREE_P"),
            "{l}"
        );
    }

    use super::*;

    #[test]
    fn binary_benchmark_tree_has_the_documented_size() {
        let r = TreeParams {
            work: 0,
            ..TreeParams::binary_benchmark()
        }
        .reference();
        assert_eq!(r.branches + r.leaves, 2_097_088);
        assert_eq!(r.leaves, 64 << 14);
    }

    #[test]
    fn presets_have_their_documented_shape() {
        let names: Vec<_> = TreePreset::ALL.iter().map(|p| p.name()).collect();
        assert_eq!(
            names,
            ["binary", "irregular", "deep", "large-payload", "heavy-work"]
        );
        for p in TreePreset::ALL {
            assert_eq!(TreePreset::parse(p.name()), Some(p));
        }
        assert_eq!(TreePreset::parse("binary-tree"), None);
        assert_eq!(TreePreset::Binary.params(), TreeParams::binary_benchmark());
        let d = TreePreset::Deep.params();
        assert_eq!(
            (d.roots, d.max_depth, d.fanout),
            (20_000, 200, Fanout::Uniform(2))
        );
        let i = TreePreset::Irregular.params();
        assert_eq!(
            (i.roots, i.max_depth, i.fanout),
            (64, 20, Fanout::Uniform(3))
        );
        assert_eq!(TreePreset::LargePayload.params().payload_words, 62);
        assert_eq!(TreePreset::HeavyWork.params().work, 64);
    }

    #[test]
    fn parallel_cpu_walk_matches_the_reference() {
        // Every preset's shape on fewer roots (and the deep one shallower), plus edge cases: no
        // roots, roots that are leaves, fewer subtrees than the parallel walk wants.
        let mut cases: Vec<TreeParams> = TreePreset::ALL
            .iter()
            .map(|p| TreeParams {
                roots: 3,
                max_depth: p.params().max_depth.min(60),
                ..p.params()
            })
            .collect();
        cases.push(TreeParams {
            roots: 0,
            ..TreeParams::binary_benchmark()
        });
        cases.push(TreeParams {
            roots: 5,
            max_depth: 0,
            ..TreeParams::binary_benchmark()
        });
        cases.push(TreeParams {
            roots: 1,
            max_depth: 9,
            fanout: Fanout::Uniform(4),
            work: 3,
            payload_words: 5,
            seed: 7,
            children: Default::default(),
        });
        for p in cases {
            let r = p.reference();
            assert_eq!(p.cpu_parallel(), r, "{}", p.describe());
            assert_eq!(r.leaves, r.leaves_folded);
        }
    }

    #[test]
    fn uniform_fanout_depends_on_seed() {
        let a = TreeParams {
            roots: 8,
            max_depth: 12,
            fanout: Fanout::Uniform(3),
            work: 0,
            payload_words: 3,
            seed: 1,
            children: Default::default(),
        };
        let b = TreeParams {
            seed: 2,
            ..a.clone()
        };
        assert_ne!(a.reference(), b.reference());
    }
}
