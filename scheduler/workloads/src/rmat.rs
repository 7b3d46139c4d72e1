//! R-MAT graphs (Chakrabarti, Zhan & Faloutsos, "R-MAT: A Recursive Model for Graph Mining",
//! SDM 2004) with the Graph500 Kronecker generator's parameters (a = 0.57, b = 0.19, c = 0.19,
//! d = 0.05, edge factor 16; Graph500 specification, section 3), stored as CSR on the host.
//!
//! Each of the `edge_factor × 2^scale` edges picks, `scale` times, one quadrant of the adjacency
//! matrix with probabilities a, b, c, d (top-left, top-right, bottom-left, bottom-right); the
//! choices are the bits of its endpoints, most significant first. Like Graph500, vertex ids are
//! then permuted (optional), the graph is undirected (both directions stored), self-loops are
//! dropped and duplicate edges kept. Random numbers come from SplitMix64 keyed by the seed and
//! the edge index, so a graph is the same whatever the thread count.

use rayon::prelude::*;

use scheduler::error::RunError;

/// Generator parameters. `d = 1 - a - b - c`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RmatParams {
    /// `2^scale` vertices.
    pub scale: u32,
    /// Undirected edges generated per vertex.
    pub edge_factor: u32,
    /// Probability of the top-left quadrant at each recursion (Chakrabarti, Zhan & Faloutsos 2004).
    pub a: f64,
    /// Probability of the top-right quadrant.
    pub b: f64,
    /// Probability of the bottom-left quadrant.
    pub c: f64,
    /// Seed of the [`SplitMix64`] stream; the same seed gives the same graph.
    pub seed: u64,
    /// Relabel vertices by a random permutation (as Graph500 does), so that vertex 0 is not the
    /// largest hub.
    pub permute: bool,
}

impl RmatParams {
    /// Graph500's generator: a = 0.57, b = c = 0.19, edge factor 16, permuted labels.
    pub fn graph500(scale: u32, seed: u64) -> Self {
        RmatParams {
            scale,
            edge_factor: 16,
            a: 0.57,
            b: 0.19,
            c: 0.19,
            seed,
            permute: true,
        }
    }

    /// `2^scale`.
    pub fn vertices(&self) -> u64 {
        1 << self.scale
    }

    /// Undirected edges generated (self-loops included; they are dropped from the CSR).
    pub fn generated_edges(&self) -> u64 {
        self.edge_factor as u64 * self.vertices()
    }
}

/// SplitMix64 (Steele, Lea & Flood 2014): one 64-bit output per call.
pub struct SplitMix64(pub u64);

impl SplitMix64 {
    /// The next 64 bits (the state advances by the golden-ratio increment).
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// Uniform in `[0, 1)` (53 bits).
    pub fn next_f64(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }
}

/// An undirected graph in compressed sparse rows: the neighbours of `v` are
/// `col[row[v]..row[v + 1]]`, sorted; every edge appears in both directions.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Csr {
    /// `vertices + 1` offsets into `col`.
    pub row: Vec<u32>,
    /// Neighbour lists back to back (duplicates kept).
    pub col: Vec<u32>,
    /// Generated edges that were self-loops (not stored).
    pub self_loops: u64,
}

impl Csr {
    /// Vertex count.
    pub fn vertices(&self) -> u32 {
        (self.row.len() - 1) as u32
    }

    /// Stored directed edges: twice the undirected edges kept.
    pub fn directed_edges(&self) -> u64 {
        self.col.len() as u64
    }

    /// Length of `v`'s neighbour list.
    pub fn degree(&self, v: u32) -> u32 {
        self.row[v as usize + 1] - self.row[v as usize]
    }

    /// `v`'s neighbours, sorted.
    pub fn neighbours(&self, v: u32) -> &[u32] {
        &self.col[self.row[v as usize] as usize..self.row[v as usize + 1] as usize]
    }

    /// Builds CSR from directed `(source, target)` pairs on `vertices` vertices.
    pub fn from_directed(vertices: u32, mut edges: Vec<(u32, u32)>) -> Csr {
        edges.par_sort_unstable();
        let mut row = vec![0u32; vertices as usize + 1];
        for &(u, _) in &edges {
            row[u as usize + 1] += 1;
        }
        for v in 0..vertices as usize {
            row[v + 1] += row[v];
        }
        Csr {
            row,
            col: edges.into_par_iter().map(|(_, v)| v).collect(),
            self_loops: 0,
        }
    }

    /// Graph500's traversed edges of a BFS: the undirected input edges in the source's connected
    /// component (duplicates counted, self-loops not), i.e. half the degree sum of the reached
    /// vertices. `levels[v] == u32::MAX` marks an unreached vertex. GTEPS = this / seconds / 1e9.
    pub fn traversed_edges(&self, levels: &[u32]) -> u64 {
        levels
            .par_iter()
            .enumerate()
            .filter(|(_, l)| **l != u32::MAX)
            .map(|(v, _)| self.degree(v as u32) as u64)
            .sum::<u64>()
            / 2
    }
}

/// Generates the R-MAT graph. Errors when ids or edge offsets would not fit in u32 (the GPU
/// code indexes with u32): `2^scale` vertices need `scale <= 31` and the `2 × edge_factor ×
/// 2^scale` directed edges must stay below 2^32 (scale 26 at edge factor 16).
pub fn generate(p: &RmatParams) -> Result<Csr, RunError> {
    let directed = 2 * p.generated_edges() as u128;
    if p.scale > 31 || directed >= 1 << 32 {
        return Err(RunError::Program(format!(
            "R-MAT scale {} with edge factor {}: {} directed edges do not fit u32 indexes",
            p.scale, p.edge_factor, directed
        )));
    }
    let (ab, abc) = (p.a + p.b, p.a + p.b + p.c);
    if !(p.a >= 0.0 && p.b >= 0.0 && p.c >= 0.0 && abc <= 1.0) {
        return Err(RunError::Program(format!(
            "R-MAT probabilities a={} b={} c={} must be non-negative with a + b + c <= 1",
            p.a, p.b, p.c
        )));
    }
    let n = p.vertices() as u32;
    let key = p.seed.wrapping_mul(0x2545_f491_4f6c_dd1d);
    let perm: Vec<u32> = if p.permute {
        let mut perm: Vec<u32> = (0..n).collect();
        let mut rng = SplitMix64(key ^ 0x5851_f42d_4c95_7f2d);
        for i in (1..n as usize).rev() {
            let j = (rng.next_u64() % (i as u64 + 1)) as usize;
            perm.swap(i, j);
        }
        perm
    } else {
        Vec::new()
    };
    let label = |v: u32| if p.permute { perm[v as usize] } else { v };
    let pairs: Vec<(u32, u32)> = (0..p.generated_edges())
        .into_par_iter()
        .map(|e| {
            let mut rng = SplitMix64(key ^ e.wrapping_mul(0xd605_bbb5_8c8a_bbd5));
            let (mut u, mut v) = (0u32, 0u32);
            for _ in 0..p.scale {
                let r = rng.next_f64();
                let (bu, bv) = if r < p.a {
                    (0, 0)
                } else if r < ab {
                    (0, 1)
                } else if r < abc {
                    (1, 0)
                } else {
                    (1, 1)
                };
                u = (u << 1) | bu;
                v = (v << 1) | bv;
            }
            (label(u), label(v))
        })
        .collect();
    let self_loops = pairs.par_iter().filter(|(u, v)| u == v).count() as u64;
    let directed: Vec<(u32, u32)> = pairs
        .into_par_iter()
        .filter(|(u, v)| u != v)
        .flat_map_iter(|(u, v)| [(u, v), (v, u)])
        .collect();
    let mut g = Csr::from_directed(n, directed);
    g.self_loops = self_loops;
    Ok(g)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn edge_counts_add_up() {
        let p = RmatParams::graph500(10, 1);
        let g = generate(&p).unwrap();
        assert_eq!(g.vertices(), 1024);
        assert_eq!(g.row.len(), 1025);
        assert_eq!(*g.row.last().unwrap() as usize, g.col.len());
        assert_eq!(
            g.directed_edges(),
            2 * (p.generated_edges() - g.self_loops),
            "both directions of every non-loop edge"
        );
        assert!(g.self_loops > 0, "R-MAT at a = 0.57 makes some self-loops");
        for v in 0..g.vertices() {
            assert!(g.neighbours(v).iter().all(|&u| u != v && u < 1024));
            assert!(g.neighbours(v).windows(2).all(|w| w[0] <= w[1]));
        }
        let deg_sum: u64 = (0..g.vertices()).map(|v| g.degree(v) as u64).sum();
        assert_eq!(deg_sum, g.directed_edges());
        // Symmetric: u lists v as often as v lists u.
        for v in 0..g.vertices() {
            for &u in g.neighbours(v) {
                let a = g.neighbours(v).iter().filter(|&&x| x == u).count();
                let b = g.neighbours(u).iter().filter(|&&x| x == v).count();
                assert_eq!(a, b);
            }
        }
    }

    #[test]
    fn unpermuted_rmat_is_skewed_towards_vertex_zero() {
        let p = RmatParams {
            permute: false,
            ..RmatParams::graph500(12, 3)
        };
        let g = generate(&p).unwrap();
        let max = (0..g.vertices()).map(|v| g.degree(v)).max().unwrap();
        assert_eq!(g.degree(0), max, "vertex 0 has a^scale odds on each edge");
        // The top bit of each endpoint is the first quadrant choice: u is in the upper half with
        // probability c + d = 0.24, v with b + d = 0.24, so 24% of the directed edges start there
        // (65,536 edges: 0.01 is about six standard deviations).
        let high = g.row[g.vertices() as usize] - g.row[g.vertices() as usize / 2];
        let frac = high as f64 / g.directed_edges() as f64;
        assert!((frac - 0.24).abs() < 0.01, "{frac}");
        // Permutation relabels without changing the degree distribution.
        let q = generate(&RmatParams { permute: true, ..p }).unwrap();
        let mut d1: Vec<u32> = (0..g.vertices()).map(|v| g.degree(v)).collect();
        let mut d2: Vec<u32> = (0..q.vertices()).map(|v| q.degree(v)).collect();
        assert_ne!(d1, d2);
        d1.sort();
        d2.sort();
        assert_eq!(d1, d2);
    }

    #[test]
    fn the_seed_decides_the_graph() {
        let a = generate(&RmatParams::graph500(8, 1)).unwrap();
        assert_eq!(a, generate(&RmatParams::graph500(8, 1)).unwrap());
        assert_ne!(a, generate(&RmatParams::graph500(8, 2)).unwrap());
    }

    #[test]
    fn too_large_graphs_are_refused() {
        assert!(generate(&RmatParams::graph500(27, 1)).is_err());
    }
}
