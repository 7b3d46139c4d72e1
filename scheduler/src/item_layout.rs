//! How a queue region holds its items' words: interleaved (item after item, the layout of an
//! `array<T>`) or planar (word `k` of every item together, structure of arrays). Planar lets
//! the threads of a warp, which run consecutive items, read and write consecutive addresses for
//! every word of their items, so each access is one full memory transaction whatever the item's
//! size; interleaved touches one sector per thread per access, but moves an item whose size is
//! a whole number of `vec4`s 16 bytes at a time (docs/scheduler.md, "Item layout").

use crate::gpu::{Gpu, MAX_WORKGROUPS_PER_DIMENSION};
use crate::program::Program;
use crate::queue_layout::QueueLayout;
use crate::wgsl::{StructLayout, cast_in, cast_out, load_store_fns};

/// Where word `k` of item `i` of a queue region lives (in u32 words from the region's start,
/// `capacity` slots).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum ItemLayout {
    /// `i × words + k`: items back to back (an `array<T>`); items that are a whole number of
    /// `vec4<u32>` move 16 bytes at a time.
    #[default]
    Interleaved,
    /// `k × capacity + i`: one plane per word (structure of arrays). Coalesced for one-thread
    /// items of any size; a queue that grows is copied plane by plane.
    Planar,
}

impl ItemLayout {
    /// The command-line name: `interleaved` or `planar`.
    pub fn name(self) -> &'static str {
        match self {
            ItemLayout::Interleaved => "interleaved",
            ItemLayout::Planar => "planar",
        }
    }

    /// The layout of a command-line name; `None` for an unknown name.
    pub fn parse(s: &str) -> Option<ItemLayout> {
        [ItemLayout::Interleaved, ItemLayout::Planar]
            .into_iter()
            .find(|l| l.name() == s)
    }

    /// Smallest item, in words, for which [`ItemLayout::for_program`] picks planar queues.
    pub const PLANAR_MIN_WORDS: u32 = 16;

    /// The faster layout for `program` on `gpu`, as measured on the H200 (docs/results.md,
    /// "Planar (structure-of-arrays) queues"): planar when every procedure runs one thread per item and the largest item
    /// has at least [`Self::PLANAR_MIN_WORDS`] words (the tree of 64-word items: host-driven
    /// multi-pass 1.10 -> 0.76 ms, megakernel 1.30 -> 1.17; of 16-word items 0.53 -> 0.49),
    /// interleaved otherwise: for 3-word items planar was up to 10% slower (the megakernel
    /// copies them out a word at a time), and for Reyes, whose multi-thread items are read by
    /// every thread of the item, 5-10% slower (a vec4 load serves all the item's threads at
    /// once). Interleaved on CPU adapters such as lavapipe, whose caches favour an item's words
    /// together (planar was 3x slower there on the 64-word tree).
    pub fn for_program(gpu: &Gpu, program: &Program) -> ItemLayout {
        Self::choose(gpu.is_cpu_adapter(), program)
    }

    /// [`ItemLayout::for_program`] on a CPU adapter (`cpu`) or a GPU.
    fn choose(cpu: bool, program: &Program) -> ItemLayout {
        let one_thread = program.procs.iter().all(|p| p.proc.threads_per_item == 1);
        let largest = program.procs.iter().map(|p| p.words()).max().unwrap_or(0);
        if !cpu && one_thread && largest >= Self::PLANAR_MIN_WORDS {
            ItemLayout::Planar
        } else {
            ItemLayout::Interleaved
        }
    }

    /// `fn sched_execute(q, base, inv)` for `program`'s queues laid out this way: loads the
    /// item at word `base` with `{prefix}_load_*` (only for active invocations) and calls the
    /// body of procedure `q`. With [`ItemLayout::Planar`] it is `sched_execute(q, base, stride,
    /// inv)` (word `k` of the item at `base + k × stride`).
    pub(crate) fn execute_switch(self, program: &Program, prefix: &str) -> String {
        let planar = self == ItemLayout::Planar;
        let mut s = self.typed_fns(program, prefix);
        let (stride_param, stride) = if planar {
            ("stride: u32, ", ", stride")
        } else {
            ("", "")
        };
        s += &format!(
            "fn sched_execute(q: u32, base: u32, {stride_param}inv: Invocation) {{\n    switch q {{\n"
        );
        // One case, and one call, per execute function (Procedure::execute_of).
        let mut done = Vec::new();
        for p in &program.procs {
            let f = p.proc.execute_fn();
            if done.contains(&f) {
                continue;
            }
            let qs: Vec<String> = (program.procs.iter().enumerate())
                .filter(|(_, o)| o.proc.execute_fn() == f)
                .map(|(i, _)| format!("{i}u"))
                .collect();
            s += &format!(
                "        case {qs}: {{ {} }}\n",
                run_item(&p.layout.name, prefix, &format!("base{stride}"), &f),
                qs = qs.join(", "),
            );
            done.push(f);
        }
        s += "        default: {}\n    }\n}\n";
        s
    }

    /// `{prefix}_load_<T>` and `{prefix}_store_<T>` in this layout, once per item type of
    /// `program`'s procedures.
    pub(crate) fn typed_fns(self, program: &Program, prefix: &str) -> String {
        let mut s = String::new();
        let mut seen = Vec::new();
        for p in &program.procs {
            if !seen.contains(&p.layout.name) {
                seen.push(p.layout.name.clone());
                s += &match self {
                    ItemLayout::Interleaved => load_store_fns(&p.layout, prefix),
                    ItemLayout::Planar => planar_load_store_fns(&p.layout, prefix),
                };
            }
        }
        s
    }

    /// Word ranges `(from_word, to_word, words)` that copy items `0..n` of queue `q` from a
    /// buffer laid out by `from` to one laid out by `to` (the same queue's region, capacities may
    /// differ): one range when interleaved, one per item word when planar.
    pub(crate) fn copy_ranges(
        self,
        from: &QueueLayout,
        to: &QueueLayout,
        q: usize,
        n: u32,
    ) -> Vec<(u64, u64, u64)> {
        let (a, b, w) = (
            from.slot_base[q] as u64,
            to.slot_base[q] as u64,
            from.words[q] as u64,
        );
        if n == 0 {
            return Vec::new();
        }
        match self {
            ItemLayout::Interleaved => vec![(a, b, n as u64 * w)],
            ItemLayout::Planar => (0..w)
                .map(|k| {
                    (
                        a + k * from.capacity[q] as u64,
                        b + k * to.capacity[q] as u64,
                        n as u64,
                    )
                })
                .collect(),
        }
    }

    /// Encodes [`ItemLayout::copy_ranges`] as buffer copies from `src` to `dst`.
    pub(crate) fn encode_copy(
        self,
        enc: &mut wgpu::CommandEncoder,
        (src, from): (&wgpu::Buffer, &QueueLayout),
        (dst, to): (&wgpu::Buffer, &QueueLayout),
        q: usize,
        n: u32,
    ) {
        for (a, b, len) in self.copy_ranges(from, to, q, n) {
            enc.copy_buffer_to_buffer(src, a * 4, dst, b * 4, len * 4);
        }
    }

    /// Writes `items` (words back to back, as seeds hold them) into the first slots of queue
    /// `q` of `buf`, a buffer of `layout`.
    pub(crate) fn write_items(
        self,
        queue: &wgpu::Queue,
        buf: &wgpu::Buffer,
        layout: &QueueLayout,
        q: usize,
        items: &[u32],
    ) {
        if items.is_empty() {
            return;
        }
        let base = layout.slot_base[q] as u64;
        match self {
            ItemLayout::Interleaved => {
                queue.write_buffer(buf, base * 4, bytemuck::cast_slice(items))
            }
            ItemLayout::Planar => {
                let w = layout.words[q] as usize;
                for k in 0..w {
                    let plane: Vec<u32> = items.iter().skip(k).step_by(w).copied().collect();
                    let at = base + k as u64 * layout.capacity[q] as u64;
                    queue.write_buffer(buf, at * 4, bytemuck::cast_slice(&plane));
                }
            }
        }
    }
}

/// Device copies of items that lie back to back in a buffer (seeds of a recorded run) into the
/// planar regions of a queue buffer: `shaders/planar_scatter.wgsl`. Bind groups are made once
/// per (queue, source buffer) and kept, so recording the same seeds again allocates nothing.
pub(crate) struct PlanarScatter {
    device: wgpu::Device,
    pipeline: wgpu::ComputePipeline,
    /// Per queue: words per item, seed count, first word of its region, capacity.
    params: Vec<wgpu::Buffer>,
    count: Vec<u32>,
    words: Vec<u32>,
    bound: std::sync::Mutex<Vec<((usize, wgpu::Buffer), wgpu::BindGroup)>>,
}

impl PlanarScatter {
    /// For queues of `layout` seeded with `seeded[q]` items each. Errors: pipeline or buffer
    /// creation ([`crate::RunError::Device`]).
    pub fn new(
        gpu: &Gpu,
        layout: &QueueLayout,
        seeded: &[u32],
    ) -> Result<PlanarScatter, crate::RunError> {
        const SOURCE: &str = include_str!("../../shaders/planar_scatter.wgsl");
        let pipeline = gpu.compute_pipeline("planar scatter", SOURCE, "scatter")?;
        let params = (0..seeded.len())
            .map(|q| {
                gpu.upload(
                    "planar scatter params",
                    &[
                        layout.words[q],
                        seeded[q],
                        layout.slot_base[q],
                        layout.capacity[q],
                    ],
                )
            })
            .collect::<Result<_, _>>()?;
        Ok(PlanarScatter {
            device: gpu.device.clone(),
            pipeline,
            params,
            count: seeded.to_vec(),
            words: layout.words.clone(),
            bound: Default::default(),
        })
    }

    /// Records the copy of each `(queue, buffer, count)` seed buffer (its items back to back)
    /// into `slots`; `count` must be the one given to [`PlanarScatter::new`].
    pub fn record(
        &self,
        enc: &mut wgpu::CommandEncoder,
        seeds: &[(usize, &wgpu::Buffer, u32)],
        slots: &wgpu::Buffer,
    ) {
        let mut bound = self.bound.lock().unwrap();
        let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("planar scatter"),
            timestamp_writes: None,
        });
        pass.set_pipeline(&self.pipeline);
        for &(q, buf, n) in seeds.iter().filter(|s| s.2 > 0) {
            debug_assert_eq!(n, self.count[q]);
            let key = (q, buf.clone());
            let at = match bound.iter().position(|(k, _)| *k == key) {
                Some(at) => at,
                None => {
                    let bind = crate::gpu::bind_buffers(
                        &self.device,
                        "planar scatter",
                        &self.pipeline.get_bind_group_layout(0),
                        &[buf, slots, &self.params[q]],
                    );
                    bound.push((key, bind));
                    bound.len() - 1
                }
            };
            pass.set_bind_group(0, &bound[at].1, &[]);
            let words = n as u64 * self.words[q] as u64;
            let wgs = words
                .div_ceil(256)
                .clamp(1, MAX_WORKGROUPS_PER_DIMENSION.into());
            pass.dispatch_workgroups(wgs as u32, 1, 1);
        }
    }
}

/// WGSL statements that run body `f` on an item of type `ty`, loaded with
/// `{prefix}_load_<ty>({at})` for active invocations only (`at`: the item's first word, and in
/// the planar layout its stride): one case of `sched_execute`, or a multi-pass entry point's
/// `mp_execute_<t>`.
pub(crate) fn run_item(ty: &str, prefix: &str, at: &str, f: &str) -> String {
    format!("var it: {ty}; if inv.live {{ it = {prefix}_load_{ty}({at}); }} {f}(it, inv);")
}

/// Generates `fn {prefix}_load_{T}(base: u32, stride: u32) -> T` and
/// `fn {prefix}_store_{T}(base: u32, stride: u32, v: T)` for the planar layout: word `k` of the
/// item at `base + k × stride` (`stride` = the region's capacity), over the word accessors
/// `{prefix}_load_word` / `{prefix}_store_word`. Padding words are not stored.
pub(crate) fn planar_load_store_fns(layout: &StructLayout, prefix: &str) -> String {
    let t = &layout.name;
    let mut s =
        format!("fn {prefix}_load_{t}(base: u32, stride: u32) -> {t} {{\n    var v: {t};\n");
    for l in &layout.leaves {
        let w = format!("{prefix}_load_word(base + {}u * stride)", l.word);
        s += &format!("    v{} = {};\n", l.path, cast_in(l, w));
    }
    s += "    return v;\n}\n";
    s += &format!("fn {prefix}_store_{t}(base: u32, stride: u32, v: {t}) {{\n");
    for l in &layout.leaves {
        s += &format!(
            "    {prefix}_store_word(base + {}u * stride, {});\n",
            l.word,
            cast_out(l)
        );
    }
    s += "}\n";
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn planar_copies_go_plane_by_plane_between_capacities() {
        // Two queues of 3 and 2 words; the second grows from 8 to 32 slots.
        let mk = |caps: Vec<u32>| QueueLayout {
            words: vec![3, 2],
            slot_base: vec![0, 3 * caps[0]],
            flag_base: vec![0, caps[0]],
            total_words: (3 * caps[0] + 2 * caps[1]) as u64,
            total_slots: (caps[0] + caps[1]) as u64,
            capacity: caps,
        };
        let (a, b) = (mk(vec![4, 8]), mk(vec![4, 32]));
        assert_eq!(
            ItemLayout::Planar.copy_ranges(&a, &b, 1, 5),
            vec![(12, 12, 5), (20, 44, 5)]
        );
        assert_eq!(
            ItemLayout::Interleaved.copy_ranges(&a, &b, 1, 5),
            vec![(12, 12, 10)]
        );
        assert!(ItemLayout::Planar.copy_ranges(&a, &b, 0, 0).is_empty());
    }

    #[test]
    fn planar_accessors_are_valid_wgsl() {
        let src = "struct Item { id: u32, p: array<vec4<f32>, 2>, k: i32 }";
        let l = crate::wgsl::struct_layout(src, "Item").unwrap();
        let fns = planar_load_store_fns(&l, "q");
        assert!(fns.contains("q_load_word(base + 4u * stride)"), "{fns}");
        let full = format!(
            "{src}\n@group(0) @binding(0) var<storage, read_write> buf: array<vec4<u32>>;\n{}{fns}\n\
             @compute @workgroup_size(1) fn main() {{ q_store_Item(1u, 64u, q_load_Item(0u, 64u)); }}",
            crate::wgsl::vec4_word_accessors("q", "buf")
        );
        crate::wgsl::validate("test", &full).unwrap();
    }

    #[test]
    fn planar_is_chosen_for_large_one_thread_items_on_gpus_only() {
        // A node procedure and a leaf procedure of one thread per item each, as in a split
        // tree, on items of `words` words.
        let one_thread = |words: u32| {
            let item =
                crate::ItemType::new("Node", &format!("struct Node {{ w: array<u32, {words}> }}"));
            let node = crate::Procedure::new("node", item.clone(), 1)
                .emits("leaf", 2)
                .body("fn node_execute(item: Node, inv: Invocation) { enqueue_leaf(item); }");
            let leaf = crate::Procedure::new("leaf", item, 1)
                .body("fn leaf_execute(item: Node, inv: Invocation) {}");
            crate::Program::new(vec![node, leaf], crate::UserBindings::none()).unwrap()
        };
        // 64-word and 16-word items: planar on a GPU, interleaved on a CPU adapter.
        assert_eq!(
            ItemLayout::choose(false, &one_thread(64)),
            ItemLayout::Planar
        );
        assert_eq!(
            ItemLayout::choose(false, &one_thread(16)),
            ItemLayout::Planar
        );
        assert_eq!(
            ItemLayout::choose(true, &one_thread(64)),
            ItemLayout::Interleaved
        );
        // 15-word items, and items read by several threads each.
        assert_eq!(
            ItemLayout::choose(false, &one_thread(15)),
            ItemLayout::Interleaved
        );
        let wide = crate::ItemType::new("Wide", "struct Wide { w: array<u32, 32> }");
        let multi = crate::Procedure::new("multi", wide, 4)
            .body("fn multi_execute(item: Wide, inv: Invocation) {}");
        let program = crate::Program::new(vec![multi], crate::UserBindings::none()).unwrap();
        assert_eq!(ItemLayout::choose(false, &program), ItemLayout::Interleaved);
    }

    #[test]
    fn names_round_trip() {
        for l in [ItemLayout::Interleaved, ItemLayout::Planar] {
            assert_eq!(ItemLayout::parse(l.name()), Some(l));
        }
        assert_eq!(ItemLayout::parse("soa"), None);
    }
}
