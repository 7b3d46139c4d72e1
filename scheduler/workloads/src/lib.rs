//! Demonstration and benchmark workloads for the `scheduler` crate, built only from its public
//! API: what `schedbench`, the scheduler's GPU tests and its benchmark run. They live apart from
//! the scheduler so that a program using the scheduler does not compile them (nor rayon, which
//! their CPU references use).
//!
//! Each has a `*Params` type with
//! `reference()` (the CPU result), `program()` and `seeds()`, and a `*Run` that owns the user
//! buffers and bind group, with `run(gpu, &Scheduler) -> (RunStats, result)`; a run's result
//! compares equal (`==`) to the reference exactly when the GPU got it right.
//!
//! - [`tree`]: a synthetic split tree (fan-out, payload, work per item).
//! - [`mandelbrot`]: adaptive Mariani-Silver Mandelbrot (subdivision, 32-thread items, shared
//!   memory reductions).
//! - [`bfs`] on [`rmat`] graphs: label-correcting BFS with hub lists cut into chunk items;
//!   [`frontier_bfs`] is its plain-wgpu level-synchronous baseline.
#![warn(missing_docs)]

pub mod bfs;
pub mod frontier_bfs;
pub mod mandelbrot;
pub mod rmat;
pub mod tree;
