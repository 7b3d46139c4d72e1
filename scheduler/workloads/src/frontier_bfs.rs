//! The BFS workload's own GPU baseline, not through the scheduler: the standard
//! level-synchronous frontier BFS in plain wgpu compute (as in Harish & Narayanan 2007, with the
//! frontier queue and workgroup-level edge gathering of Merrill, Garland & Grimshaw, "Scalable
//! GPU Graph Traversal", PPoPP 2012).
//!
//! Per level, one `expand` dispatch over the frontier `fin`: each workgroup takes 256 frontier
//! vertices at a time, scans their degrees in workgroup memory, and sweeps their combined
//! adjacency lists 256 edges per step (a thread finds its edge's vertex by binary search in the
//! scanned offsets), so a hub's list is spread over the whole workgroup instead of one thread. A
//! neighbour still unreached is claimed with `atomicMin(&level[u], L + 1)` (the one whose
//! `atomicMin` saw `u32::MAX` wins) and appended to `fout`: the workgroup counts its finds with a
//! workgroup atomic and reserves room with one global `atomicAdd` per step. Then a one-thread
//! `plan` dispatch moves the appended count into the next level's frontier size and writes the
//! next `expand`'s indirect dispatch arguments, so no level needs a read-back: levels are
//! encoded 8, 16, 32, ... per submission and the host reads the frontier size only between
//! submissions (an empty frontier dispatches zero workgroups).

use std::time::Instant;

use crate::bfs::{BfsParams, initial_levels, upload_graph, write_words};
use scheduler::error::RunError;
use scheduler::gpu::Gpu;
use scheduler::readback::TimedReadback;

/// What a frontier BFS run did.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct FrontierStats {
    /// Non-empty levels expanded (the source's eccentricity + 1).
    pub levels: u32,
    /// Vertices reached, the source included.
    pub reached: u64,
    /// Submissions (each followed by one read-back of the frontier size).
    pub submits: u32,
    /// GPU time from timestamp queries, when the adapter has them.
    pub gpu_ms: Option<f64>,
    /// Host time from the first submission to the last frontier-size read-back.
    pub wall_ms: f64,
}

/// Control words: frontier size, appended count, frontier level, vertices reached.
const C_N: usize = 0;
const C_LEVEL: usize = 2;
const C_REACHED: usize = 3;

const WGSL: &str = r#"
const INF: u32 = 0xffffffffu;
@group(0) @binding(0) var<storage, read> row: array<u32>;
@group(0) @binding(1) var<storage, read> col: array<u32>;
@group(0) @binding(2) var<storage, read_write> level: array<atomic<u32>>;
@group(0) @binding(3) var<storage, read> fin: array<u32>;
@group(0) @binding(4) var<storage, read_write> fout: array<u32>;
// [0] frontier size, [1] vertices appended to fout, [2] frontier level, [3] vertices reached
@group(0) @binding(5) var<storage, read_write> ctrl: array<atomic<u32>, 4>;
@group(0) @binding(6) var<storage, read_write> args: array<u32, 3>;

var<workgroup> wg_n: u32;
var<workgroup> wg_level: u32;
var<workgroup> wg_total: u32;
var<workgroup> wg_base: u32;
var<workgroup> wg_found: atomic<u32>;
var<workgroup> wg_scan: array<u32, 256>;
var<workgroup> wg_beg: array<u32, 256>;
var<workgroup> wg_off: array<u32, 256>;

// Workgroups of the expansion of a frontier of n vertices, one per 256 within the dispatch
// limit: `plan` writes it as the indirect dispatch and `expand` strides by it, instead of
// reading @builtin(num_workgroups), which D3D12 reports as 0 without wgpu's indirect validation.
fn groups(n: u32) -> u32 { return min((n + 255u) / 256u, 65535u); }

@compute @workgroup_size(256)
fn expand(@builtin(local_invocation_index) lid: u32, @builtin(workgroup_id) wid: vec3<u32>) {
    if lid == 0u {
        wg_n = atomicLoad(&ctrl[0]);
        wg_level = atomicLoad(&ctrl[2]);
    }
    let n = workgroupUniformLoad(&wg_n);
    let next = workgroupUniformLoad(&wg_level) + 1u;
    let stride = groups(n) * 256u;
    for (var seg = wid.x * 256u; seg < n; seg += stride) {
        let i = seg + lid;
        var b = 0u;
        var d = 0u;
        if i < n {
            let v = fin[i];
            b = row[v];
            d = row[v + 1u] - b;
        }
        // Inclusive scan of the degrees (Hillis-Steele).
        wg_scan[lid] = d;
        workgroupBarrier();
        for (var k = 1u; k < 256u; k <<= 1u) {
            var add = 0u;
            if lid >= k { add = wg_scan[lid - k]; }
            workgroupBarrier();
            wg_scan[lid] += add;
            workgroupBarrier();
        }
        wg_beg[lid] = b;
        wg_off[lid] = wg_scan[lid] - d;
        if lid == 255u { wg_total = wg_scan[255]; }
        let total = workgroupUniformLoad(&wg_total);
        for (var base = 0u; base < total; base += 256u) {
            if lid == 0u { atomicStore(&wg_found, 0u); }
            workgroupBarrier();
            let e = base + lid;
            var u = INF;
            var slot = 0u;
            if e < total {
                // The last vertex whose offset is <= e owns edge e (it has a non-zero degree).
                var lo = 0u;
                var hi = 255u;
                while lo < hi {
                    let mid = (lo + hi + 1u) / 2u;
                    if wg_off[mid] <= e { lo = mid; } else { hi = mid - 1u; }
                }
                let w = col[wg_beg[lo] + e - wg_off[lo]];
                if atomicLoad(&level[w]) == INF && atomicMin(&level[w], next) == INF {
                    u = w;
                    slot = atomicAdd(&wg_found, 1u);
                }
            }
            workgroupBarrier();
            if lid == 0u { wg_base = atomicAdd(&ctrl[1], atomicLoad(&wg_found)); }
            let at = workgroupUniformLoad(&wg_base);
            if u != INF { fout[at + slot] = u; }
        }
    }
}

@compute @workgroup_size(1)
fn plan() {
    let n = atomicLoad(&ctrl[1]);
    atomicStore(&ctrl[0], n);
    atomicStore(&ctrl[1], 0u);
    if n > 0u {
        atomicAdd(&ctrl[2], 1u);
        atomicAdd(&ctrl[3], n);
    }
    args[0] = groups(n);
    args[1] = 1u;
    args[2] = 1u;
}
"#;

/// The frontier BFS's pipelines and buffers for one graph.
pub struct FrontierBfs {
    /// The graph and source searched.
    pub params: BfsParams,
    expand: wgpu::ComputePipeline,
    plan: wgpu::ComputePipeline,
    level: wgpu::Buffer,
    ctrl: wgpu::Buffer,
    args: wgpu::Buffer,
    front: [wgpu::Buffer; 2],
    /// `expand` reading `front[p]` and appending to `front[1 - p]`.
    expand_bind: [wgpu::BindGroup; 2],
    plan_bind: wgpu::BindGroup,
    /// Each submission's `ctrl` and GPU time, read back in one wait.
    readback: TimedReadback,
}

impl FrontierBfs {
    /// Uploads the graph (a [`RunError::Device`] naming the scale if it exceeds the device's
    /// binding limit) and compiles the two kernels.
    pub fn new(gpu: &Gpu, params: BfsParams) -> Result<FrontierBfs, RunError> {
        let (row, col) = upload_graph(gpu, &params)?;
        let n = params.graph().vertices() as u64;
        let level = gpu.storage_buffer("frontier bfs level", n)?;
        let front = [
            gpu.storage_buffer("frontier a", n)?,
            gpu.storage_buffer("frontier b", n)?,
        ];
        let ctrl = gpu.storage_buffer("frontier ctrl", 4)?;
        let args = gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("frontier dispatch args"),
            size: 12,
            usage: wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::INDIRECT
                | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let expand = gpu.compute_pipeline("frontier bfs expand", WGSL, "expand")?;
        let plan = gpu.compute_pipeline("frontier bfs plan", WGSL, "plan")?;
        let group = |pipe: &wgpu::ComputePipeline, entries: &[(u32, &wgpu::Buffer)]| {
            let entries: Vec<_> = entries
                .iter()
                .map(|(b, buf)| wgpu::BindGroupEntry {
                    binding: *b,
                    resource: buf.as_entire_binding(),
                })
                .collect();
            gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("frontier bfs"),
                layout: &pipe.get_bind_group_layout(0),
                entries: &entries,
            })
        };
        let expand_bind = [0, 1].map(|p| {
            group(
                &expand,
                &[
                    (0, &row),
                    (1, &col),
                    (2, &level),
                    (3, &front[p]),
                    (4, &front[1 - p]),
                    (5, &ctrl),
                ],
            )
        });
        let plan_bind = group(&plan, &[(5, &ctrl), (6, &args)]);
        Ok(FrontierBfs {
            params,
            expand,
            plan,
            level,
            ctrl,
            args,
            front,
            expand_bind,
            plan_bind,
            readback: TimedReadback::reuse(None, gpu, "frontier bfs read-back", 4, &[]),
        })
    }

    /// One search from `params.source`; returns the levels (`u32::MAX` = unreached).
    pub fn run(&self, gpu: &Gpu) -> Result<(FrontierStats, Vec<u32>), RunError> {
        let p = &self.params;
        let n = p.graph().vertices();
        if p.source >= n {
            return Err(RunError::Program(format!(
                "BFS source {} is not a vertex",
                p.source
            )));
        }
        write_words(gpu, &self.level, &initial_levels(p));
        write_words(gpu, &self.front[0], &[p.source]);
        write_words(gpu, &self.ctrl, &[1, 0, 0, 1]);
        write_words(gpu, &self.args, &[1, 1, 1]);
        let start = Instant::now();
        let mut gpu_ms = gpu.timestamps.then_some(0.0);
        let mut stats = FrontierStats::default();
        let mut encoded = 0u64;
        let mut per_submit = 8u64;
        let ctrl = loop {
            let mut enc = gpu.device.create_command_encoder(&Default::default());
            {
                let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: Some("frontier bfs levels"),
                    timestamp_writes: self.readback.pass_writes(),
                });
                for _ in 0..per_submit {
                    pass.set_pipeline(&self.expand);
                    pass.set_bind_group(0, &self.expand_bind[(encoded % 2) as usize], &[]);
                    pass.dispatch_workgroups_indirect(&self.args, 0);
                    pass.set_pipeline(&self.plan);
                    pass.set_bind_group(0, &self.plan_bind, &[]);
                    pass.dispatch_workgroups(1, 1, 1);
                    encoded += 1;
                }
            }
            // The counters and the GPU time come back in one wait.
            self.readback.copy(&mut enc, Some(&self.ctrl), true, &[]);
            gpu.submit(enc);
            let words = self.readback.read(gpu, &[])?;
            self.readback.add_ms(&words, &mut gpu_ms);
            let ctrl = self.readback.counters(&words).to_vec();
            stats.submits += 1;
            if ctrl[C_N] == 0 {
                break ctrl;
            }
            // Every level reaches at least one new vertex, so n levels always suffice.
            if encoded > n as u64 + 1 {
                return Err(RunError::NoProgress(format!(
                    "frontier BFS: {encoded} levels on {n} vertices"
                )));
            }
            per_submit = (per_submit * 2).min(64);
        };
        stats.wall_ms = start.elapsed().as_secs_f64() * 1e3;
        stats.gpu_ms = gpu_ms;
        stats.levels = ctrl[C_LEVEL] + 1;
        stats.reached = ctrl[C_REACHED] as u64;
        let levels = gpu.read_words(&self.level, 0, n as u64)?;
        Ok((stats, levels))
    }
}
