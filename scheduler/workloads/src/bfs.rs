//! Breadth-first search on R-MAT graphs ([`crate::rmat`]) through the scheduler: the Graph500
//! kernel 2 problem (levels instead of a parent tree), solved by label-correcting relaxation.
//!
//! `level[v]` (u32, `u32::MAX` = unreached) starts at 0 for the source. Two procedures,
//! [`BfsParams::threads`] threads per item:
//! - `bfs_vertex { v, level }`: skipped if `level[v]` has since dropped below `level` (a better
//!   path was found and a newer item for `v` exists); otherwise it relaxes `v`'s adjacency list;
//! - `bfs_edges { v, level, begin, end }`: the same for the slice `col[begin..end]` of `v`'s list.
//!
//! Relaxing a list of at most [`BfsParams::chunk_edges`] edges runs `atomicMin(&level[u],
//! level + 1)` per neighbour `u` and emits `bfs_vertex { u, level + 1 }` when that lowered it.
//! A longer list (R-MAT's largest hub has degree 138,923 at scale 20) is cut into at
//! most [`BfsParams::split`] `bfs_edges` items of equal length, which cut again until they are
//! short: so each item's declared worst case stays `chunk_edges` vertices plus `split` slices,
//! whatever the degree. With the megakernel, items of different levels run at once and a vertex
//! may be reached first by a longer path; it is then lowered and emitted again, so the final
//! levels are exact (every improvement is propagated) but some vertex items are redundant.
//!
//! Baselines: [`bfs_levels`] (sequential queue, the reference), [`bfs_levels_rayon`]
//! (level-synchronous, parallel over the frontier), and the plain-wgpu level-synchronous
//! frontier BFS in [`crate::frontier_bfs`].

use std::sync::Arc;
use std::sync::atomic::{AtomicU32, Ordering};

use rayon::prelude::*;

use crate::rmat::{self, Csr, RmatParams};
use scheduler::bindings::UserBindings;
use scheduler::error::RunError;
use scheduler::gpu::Gpu;
use scheduler::procedure::{ItemType, Procedure};
use scheduler::program::{Program, Seed};
use scheduler::stats::RunStats;
use scheduler::strategy::Scheduler;

/// Level of a vertex the search did not reach.
pub const UNREACHED: u32 = u32::MAX;

/// The host twin of WGSL `BfsVertex`.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Eq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct BfsVertex {
    /// The vertex.
    pub v: u32,
    /// Its BFS level when it was emitted (hops from the source).
    pub level: u32,
}

/// The host twin of WGSL `BfsEdges`: the slice `col[begin..end]` of `v`'s adjacency list.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Eq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct BfsEdges {
    /// The vertex whose list is cut.
    pub v: u32,
    /// Its BFS level when the slice was emitted.
    pub level: u32,
    /// First index into the CSR column array.
    pub begin: u32,
    /// One past the last index.
    pub end: u32,
}

/// The BFS program's procedures, in registration order (`--procedure-steps` names).
pub const PROCEDURES: [&str; 2] = ["bfs_vertex", "bfs_edges"];

const VERTEX_WGSL: &str = "struct BfsVertex { v: u32, level: u32 }";
const EDGES_WGSL: &str = "struct BfsEdges { v: u32, level: u32, begin: u32, end: u32 }";

/// A BFS problem: the generated graph (shared, built once by [`BfsParams::new`]), the source,
/// and the shape of the scheduler program.
#[derive(Clone)]
pub struct BfsParams {
    rmat: RmatParams,
    graph: Arc<Csr>,
    /// The search's root. [`BfsParams::new`] picks a vertex with at least one edge.
    pub source: u32,
    /// Longest adjacency slice one item relaxes itself (its `emits` to `bfs_vertex`).
    pub chunk_edges: u32,
    /// Slices a longer list is cut into per item (its `emits` to `bfs_edges`), at least 2.
    pub split: u32,
    /// Threads per item (power of two, at most 256).
    pub threads: u32,
}

impl std::fmt::Debug for BfsParams {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.describe())
    }
}

impl BfsParams {
    /// Generates the graph and picks the source: the first vertex with an edge at or after a
    /// position drawn from the seed (Graph500 draws sources among vertices with edges).
    /// Defaults: 16-edge chunks, split 8, 8 threads per item. Multi-pass reserves
    /// `chunk_edges` output slots per item per round, and one round holds a whole BFS level
    /// (the largest is about a third of the vertices: 337,025 of 2^20 at scale 20, seed 1), so
    /// under its 65,535 × 1,024-slot queue cap chunk 16 fits up to scale 23 and chunk 8 scale
    /// 24; beyond, multi-pass reports [`RunError::QueueOverflow`]. The megakernel reserves
    /// per batch and has no such bound.
    pub fn new(rmat: RmatParams) -> Result<BfsParams, RunError> {
        let graph = Arc::new(rmat::generate(&rmat)?);
        let n = graph.vertices();
        let start =
            (rmat::SplitMix64(rmat.seed ^ 0xb5ad_4ece_da1c_e2a9).next_u64() % n as u64) as u32;
        let source = (0..n)
            .map(|i| (start + i) % n)
            .find(|&v| graph.degree(v) > 0)
            .unwrap_or(0);
        Ok(BfsParams {
            rmat,
            graph,
            source,
            chunk_edges: 16,
            split: 8,
            threads: 8,
        })
    }

    /// Graph500's R-MAT at `scale` (edge factor 16), seed `seed`.
    pub fn graph500(scale: u32, seed: u64) -> Result<BfsParams, RunError> {
        Self::new(RmatParams::graph500(scale, seed))
    }

    /// The graph's generator parameters.
    pub fn rmat(&self) -> &RmatParams {
        &self.rmat
    }

    /// The graph, generated once by [`BfsParams::new`].
    pub fn graph(&self) -> &Csr {
        &self.graph
    }

    /// One line of every parameter, for reports.
    pub fn describe(&self) -> String {
        format!(
            "rmat scale={} edge_factor={} seed={} vertices={} directed_edges={} source={} chunk={} split={} threads={}",
            self.rmat.scale,
            self.rmat.edge_factor,
            self.rmat.seed,
            self.graph.vertices(),
            self.graph.directed_edges(),
            self.source,
            self.chunk_edges,
            self.split,
            self.threads
        )
    }

    /// Checks that the largest array, the adjacency `col` (4 bytes per directed edge), fits a
    /// storage binding of `max_binding_bytes` (see [`Gpu::max_binding_bytes`]); the error names
    /// the scale. At edge factor 16, scale 24 needs 2 GiB, scale 25 4 GiB.
    pub fn fits(&self, max_binding_bytes: u64) -> Result<(), RunError> {
        let need = self.graph.directed_edges() * 4;
        if need > max_binding_bytes {
            return Err(RunError::Device(format!(
                "R-MAT scale {} (edge factor {}): the adjacency array needs {need} bytes, more \
                 than this device's storage binding limit of {max_binding_bytes} bytes; use a \
                 smaller scale",
                self.rmat.scale, self.rmat.edge_factor
            )));
        }
        Ok(())
    }

    /// The CPU reference: [`bfs_levels`] from the source.
    pub fn reference(&self) -> Vec<u32> {
        bfs_levels(&self.graph, self.source)
    }

    /// Graph500's traversed edges for `levels` (see [`Csr::traversed_edges`]).
    pub fn traversed_edges(&self, levels: &[u32]) -> u64 {
        self.graph.traversed_edges(levels)
    }

    /// The program: procedures `bfs_vertex` and `bfs_edges` with the graph and level array as
    /// user bindings. Errors: [`RunError::Program`] for `chunk_edges == 0` or `split < 2`.
    pub fn program(&self) -> Result<Program, RunError> {
        let (t, chunk, split) = (self.threads, self.chunk_edges, self.split);
        if chunk == 0 || split < 2 {
            return Err(RunError::Program(
                "BFS: chunk_edges must be at least 1 and split at least 2".into(),
            ));
        }
        let user = UserBindings {
            wgsl: format!(
                "@group(1) @binding(0) var<storage, read> bfs_row: array<u32>;\n\
                 @group(1) @binding(1) var<storage, read> bfs_col: array<u32>;\n\
                 @group(1) @binding(2) var<storage, read_write> bfs_level: array<atomic<u32>>;\n\
                 const BFS_T: u32 = {t}u;\nconst BFS_CHUNK: u32 = {chunk}u;\n\
                 const BFS_SPLIT: u32 = {split}u;\n{RELAX_WGSL}"
            ),
            layout: vec![
                scheduler::storage_entry(0, true),
                scheduler::storage_entry(1, true),
                scheduler::storage_entry(2, false),
            ],
        };
        let vertex = Procedure::new("bfs_vertex", ItemType::new("BfsVertex", VERTEX_WGSL), t)
            .emits("bfs_vertex", chunk)
            .emits("bfs_edges", split)
            .body(VERTEX_BODY);
        let edges = Procedure::new("bfs_edges", ItemType::new("BfsEdges", EDGES_WGSL), t)
            .emits("bfs_vertex", chunk)
            .emits("bfs_edges", split)
            .body(EDGES_BODY);
        Program::new(vec![vertex, edges], user)
    }

    /// The source at level 0.
    pub fn seeds(&self) -> Vec<Seed> {
        vec![Seed::new(
            "bfs_vertex",
            &[BfsVertex {
                v: self.source,
                level: 0,
            }],
        )]
    }
}

/// Relaxes the slice `col[b..e]` of v's list at `level`, or cuts it into `bfs_edges` items.
const RELAX_WGSL: &str = r#"
fn bfs_relax(v: u32, level: u32, b: u32, e: u32, thread: u32) {
    let len = e - b;
    if len <= BFS_CHUNK {
        let next = level + 1u;
        for (var i = b + thread; i < e; i += BFS_T) {
            let u = bfs_col[i];
            // Plain check first: most neighbours are already as close, and an atomicMin is dearer.
            if atomicLoad(&bfs_level[u]) > next && atomicMin(&bfs_level[u], next) > next {
                enqueue_bfs_vertex(BfsVertex(u, next));
            }
        }
        return;
    }
    let parts = min(BFS_SPLIT, (len + BFS_CHUNK - 1u) / BFS_CHUNK);
    let size = (len + parts - 1u) / parts;
    for (var p = thread; p < parts; p += BFS_T) {
        let pb = b + p * size;
        if pb < e { enqueue_bfs_edges(BfsEdges(v, level, pb, min(pb + size, e))); }
    }
}
"#;

const VERTEX_BODY: &str = r#"
fn bfs_vertex_execute(item: BfsVertex, inv: Invocation) {
    if !inv.live { return; }
    // A newer item carries v at a lower level: this one's work is covered by it.
    if atomicLoad(&bfs_level[item.v]) < item.level { return; }
    bfs_relax(item.v, item.level, bfs_row[item.v], bfs_row[item.v + 1u], inv.thread);
}
"#;

const EDGES_BODY: &str = r#"
fn bfs_edges_execute(item: BfsEdges, inv: Invocation) {
    if !inv.live { return; }
    if atomicLoad(&bfs_level[item.v]) < item.level { return; }
    bfs_relax(item.v, item.level, item.begin, item.end, inv.thread);
}
"#;

/// BFS levels from `source` by a sequential FIFO queue: the reference.
pub fn bfs_levels(g: &Csr, source: u32) -> Vec<u32> {
    let mut level = vec![UNREACHED; g.vertices() as usize];
    let mut queue = std::collections::VecDeque::from([source]);
    level[source as usize] = 0;
    while let Some(v) = queue.pop_front() {
        let next = level[v as usize] + 1;
        for &u in g.neighbours(v) {
            if level[u as usize] == UNREACHED {
                level[u as usize] = next;
                queue.push_back(u);
            }
        }
    }
    level
}

/// Level-synchronous BFS with rayon, the multi-threaded CPU baseline: each level's frontier is
/// expanded in parallel, a vertex claimed by the thread whose compare-exchange moves it from
/// unreached to the next level.
pub fn bfs_levels_rayon(g: &Csr, source: u32) -> Vec<u32> {
    let level: Vec<AtomicU32> = (0..g.vertices())
        .into_par_iter()
        .map(|_| AtomicU32::new(UNREACHED))
        .collect();
    level[source as usize].store(0, Ordering::Relaxed);
    let mut frontier = vec![source];
    let mut depth = 0;
    while !frontier.is_empty() {
        depth += 1;
        frontier = frontier
            .par_iter()
            .flat_map_iter(|&v| {
                g.neighbours(v).iter().copied().filter(|&u| {
                    let l = &level[u as usize];
                    l.load(Ordering::Relaxed) == UNREACHED
                        && l.compare_exchange(
                            UNREACHED,
                            depth,
                            Ordering::Relaxed,
                            Ordering::Relaxed,
                        )
                        .is_ok()
                })
            })
            .collect();
    }
    level.into_iter().map(AtomicU32::into_inner).collect()
}

/// The graph on the GPU: `row` and `col` as storage buffers, checked against the device's
/// binding limit with an error that names the scale.
pub(crate) fn upload_graph(
    gpu: &Gpu,
    params: &BfsParams,
) -> Result<(wgpu::Buffer, wgpu::Buffer), RunError> {
    params.fits(gpu.max_binding_bytes())?;
    let g = params.graph();
    let row = gpu.storage_buffer("bfs row", g.row.len() as u64)?;
    let col = gpu.storage_buffer("bfs col", g.col.len() as u64)?;
    write_words(gpu, &row, &g.row);
    write_words(gpu, &col, &g.col);
    Ok((row, col))
}

/// Writes `words` in pieces of 16 Mi words, so that no single staging copy is gigabytes.
pub(crate) fn write_words(gpu: &Gpu, buf: &wgpu::Buffer, words: &[u32]) {
    for (i, piece) in words.chunks(1 << 24).enumerate() {
        gpu.queue
            .write_buffer(buf, (i as u64) << 26, bytemuck::cast_slice(piece));
    }
}

/// Levels with every vertex unreached but the source (level 0).
pub(crate) fn initial_levels(params: &BfsParams) -> Vec<u32> {
    let mut l = vec![UNREACHED; params.graph().vertices() as usize];
    l[params.source as usize] = 0;
    l
}

/// The BFS workload's GPU resources: the graph, the level array, and their bind group.
pub struct BfsRun {
    /// The search run.
    pub params: BfsParams,
    /// Its program ([`BfsParams::program`]).
    pub program: Program,
    level: wgpu::Buffer,
    bind: wgpu::BindGroup,
    /// Kept alive for the bind group.
    _graph: (wgpu::Buffer, wgpu::Buffer),
}

impl BfsRun {
    /// Uploads the graph and builds the program. Errors: [`RunError::Program`] (see
    /// [`BfsParams::program`]), [`RunError::Device`] when the graph passes the binding limit.
    pub fn new(gpu: &Gpu, params: BfsParams) -> Result<BfsRun, RunError> {
        let program = params.program()?;
        let graph = upload_graph(gpu, &params)?;
        let level = gpu.storage_buffer("bfs level", params.graph().vertices() as u64)?;
        let bind = program
            .user
            .bind_group(gpu, &[&graph.0, &graph.1, &level])?;
        Ok(BfsRun {
            params,
            program,
            level,
            bind,
            _graph: graph,
        })
    }

    /// Runs one search from `params.source` and reads the levels back.
    pub fn run(&self, gpu: &Gpu, scheduler: &Scheduler) -> Result<(RunStats, Vec<u32>), RunError> {
        if self.params.source >= self.params.graph().vertices() {
            return Err(RunError::Program(format!(
                "BFS source {} is not a vertex",
                self.params.source
            )));
        }
        write_words(gpu, &self.level, &initial_levels(&self.params));
        // The levels come back with the run's last read-back.
        let levels = [(&self.level, 0, self.params.graph().vertices() as u64)];
        let (stats, mut words) =
            scheduler.run_reading(gpu, &self.params.seeds(), Some(&self.bind), None, &levels)?;
        Ok((stats, words.pop().expect("the levels' range")))
    }
}

/// Megakernel steps per batch of both BFS procedures on `gpu`
/// (`MegakernelConfig::procedure_batch_steps`): 16, i.e. batches of up to 512 items of 8 threads.
/// A BFS level is wide and its items short, so the turn's claim and publish, not the work, set
/// the pace at one step a batch. H200, scale 22 (docs/results.md, 2026-12-02, "Batch steps per
/// procedure"): 9.19 ms at 1 step, 4.17 at 4, 3.61 at 8, 3.38 at 16 (multipass-host 5.27).
/// None on lavapipe, whose loop limiter counts a batch's steps.
pub fn megakernel_procedure_steps(gpu: &scheduler::Gpu) -> Vec<(String, u32)> {
    if gpu.is_lavapipe() {
        return Vec::new();
    }
    vec![("bfs_vertex".into(), 16), ("bfs_edges".into(), 16)]
}

/// Whether the BFS megakernel's claims are guided by what is pending
/// (`MegakernelConfig::guided_claims`): on GPUs, with [`megakernel_procedure_steps`]' 16-step
/// batches. A level of a small graph has a few thousand items, which full batches of 512 hand
/// to a few dozen workgroups while the rest poll; a claim of at most the workgroup's share of
/// what is pending spreads them, and on a large graph batches stay full. H100, scale 16:
/// 0.317 -> 0.124-0.147 ms (the device-driven multi-pass 0.155); scale 22: 2.28 -> 2.12
/// (docs/results.md, 2026-12-05 (sixth session)). Off on lavapipe (one workgroup).
pub fn megakernel_guided_claims(gpu: &scheduler::Gpu) -> bool {
    !gpu.is_lavapipe()
}

#[cfg(test)]
mod tests {
    use super::*;
    use scheduler::wgsl::struct_layout;

    #[test]
    fn procedures_are_named_as_listed() {
        let program = BfsParams::graph500(8, 1).unwrap().program().unwrap();
        let names: Vec<&str> = program.procs.iter().map(|p| p.proc.name.as_str()).collect();
        assert_eq!(names, PROCEDURES);
    }

    /// 0-1-2-3 path, 1-4 and 4-3 shortcut, 5-6 a separate component, 7 isolated.
    fn hand_made() -> Csr {
        let undirected = [(0, 1), (1, 2), (2, 3), (1, 4), (4, 3), (5, 6), (1, 2)];
        Csr::from_directed(
            8,
            undirected
                .iter()
                .flat_map(|&(u, v)| [(u, v), (v, u)])
                .collect(),
        )
    }

    #[test]
    fn reference_bfs_on_a_hand_made_graph() {
        let g = hand_made();
        let m = UNREACHED;
        assert_eq!(bfs_levels(&g, 0), vec![0, 1, 2, 3, 2, m, m, m]);
        assert_eq!(bfs_levels(&g, 3), vec![3, 2, 1, 0, 1, m, m, m]);
        assert_eq!(bfs_levels(&g, 6), vec![m, m, m, m, m, 1, 0, m]);
        assert_eq!(bfs_levels_rayon(&g, 0), bfs_levels(&g, 0));
        // Component of 0: 6 undirected edges, the duplicate 1-2 included.
        assert_eq!(g.traversed_edges(&bfs_levels(&g, 0)), 6);
        assert_eq!(g.traversed_edges(&bfs_levels(&g, 5)), 1);
        assert_eq!(g.traversed_edges(&bfs_levels(&g, 7)), 0);
    }

    #[test]
    fn rayon_bfs_matches_the_reference_on_rmat() {
        let p = BfsParams::graph500(12, 5).unwrap();
        let r = p.reference();
        assert_eq!(bfs_levels_rayon(p.graph(), p.source), r);
        assert_eq!(r[p.source as usize], 0);
        let reached = r.iter().filter(|&&l| l != UNREACHED).count();
        assert!(reached > 1000, "the giant component: {reached}");
        assert!(p.traversed_edges(&r) <= p.graph().directed_edges() / 2);
    }

    #[test]
    fn items_match_the_wgsl_layout() {
        let v = struct_layout(VERTEX_WGSL, "BfsVertex").unwrap();
        assert_eq!(v.size as usize, size_of::<BfsVertex>());
        let e = struct_layout(EDGES_WGSL, "BfsEdges").unwrap();
        assert_eq!(e.size as usize, size_of::<BfsEdges>());
        assert_eq!(e.members[3], ("end".into(), 12));
    }

    #[test]
    fn a_graph_beyond_the_binding_limit_is_refused_by_scale() {
        let p = BfsParams::graph500(8, 1).unwrap();
        let need = p.graph().directed_edges() * 4;
        assert!(p.fits(need).is_ok());
        let e = p.fits(need - 4).unwrap_err().to_string();
        assert!(e.contains("scale 8"), "{e}");
    }

    #[test]
    fn bad_program_shapes_are_refused() {
        let mut p = BfsParams::graph500(6, 1).unwrap();
        p.split = 1;
        assert!(p.program().is_err());
        p.split = 8;
        p.threads = 3;
        assert!(p.program().is_err());
    }
}
