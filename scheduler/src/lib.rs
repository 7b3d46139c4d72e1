//! Whippletree-style scheduling of irregular GPU work from on-device queues.
//!
//! Users describe each kind of work once as a [`Procedure`] (item type, threads per item, WGSL
//! body that may `enqueue_<other>(item)`), register procedures into a [`Program`], and run it to
//! completion with either strategy built from the same sources:
//! - [`Megakernel`]: one persistent dispatch pulling batches from per-procedure queues;
//! - [`Multipass`]: the Patney & Owens baseline, rounds of dispatches with scan/compact.
//!
//! The queue protocol and its correctness argument are in `docs/scheduler.md`.

pub mod clocks;
pub mod error;
pub mod gpu;
pub mod megakernel;
pub mod multipass;
pub mod pipeline;
pub mod procedure;
pub mod program;
pub mod queue_layout;
pub mod stats;
pub mod strategy;
pub mod timing;
pub mod wgsl;
pub mod workloads;

pub use error::RunError;
pub use gpu::Gpu;
pub use megakernel::{Megakernel, MegakernelConfig, QueuePolicy, Workgroups};
pub use multipass::{Multipass, MultipassConfig};
pub use procedure::{ItemType, Procedure};
pub use program::{Program, Seed, UserBindings};
pub use stats::RunStats;
pub use strategy::{Scheduler, StrategyKind};
