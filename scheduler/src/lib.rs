//! Whippletree-style scheduling of irregular GPU work from on-device queues.
//!
//! Users describe each kind of work once as a [`Procedure`] (item type, threads per item, WGSL
//! body that may `enqueue_<other>(item)`), register procedures into a [`Program`], and run it to
//! completion with either strategy built from the same sources:
//! - [`Megakernel`]: one persistent dispatch pulling batches from per-procedure queues;
//! - [`Multipass`]: the Patney & Owens baseline, rounds of dispatches with scan/compact,
//!   planned on the device with indirect dispatches;
//! - [`HostMultipass`]: the same baseline driven by the host as its authors ran it: exactly
//!   sized direct dispatches per round, compaction fused into the producing pass.
//!
//! The queue protocol and its correctness argument are in `docs/scheduler.md`.

pub mod clocks;
pub mod error;
pub mod gpu;
pub mod growth;
pub mod hash;
pub mod megakernel;
pub mod multipass;
pub mod pipeline;
pub mod procedure;
pub mod program;
pub mod queue_layout;
pub mod readback;
pub mod stats;
pub mod strategy;
pub mod timing;
pub mod wgsl;
pub mod workloads;

pub use error::RunError;
pub use gpu::Gpu;
pub use megakernel::{Megakernel, MegakernelConfig, QueuePolicy, Workgroups};
pub use multipass::host::{HostMultipass, HostMultipassConfig};
pub use multipass::{Multipass, MultipassConfig};
pub use procedure::{ItemType, Procedure};
pub use program::{Program, Seed, UserBindings};
pub use stats::RunStats;
pub use strategy::{Scheduler, StrategyKind};
