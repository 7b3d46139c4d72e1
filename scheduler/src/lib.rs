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
//! [`RecordedRun`] records a run of fixed sizes into the caller's encoder without host waits,
//! for frames pipelined on the GPU.
//!
//! The queue protocol and its correctness argument are in `docs/scheduler.md`.
#![warn(missing_docs)]

pub mod bindings;
pub mod clocks;
pub mod error;
pub mod gpu;
mod growth;
pub mod hash;
pub mod item_layout;
pub mod megakernel;
pub mod multipass;
mod pipeline;
pub mod procedure;
pub mod program;
mod queue_layout;
pub mod readback;
pub mod recorded_run;
pub mod stats;
pub mod strategy;
pub mod timing;
pub mod wgsl;

/// The bytemuck this crate is built against: `#[derive(Pod, Zeroable)]` host twins of item
/// structs go through it ([`Seed::new`], [`Gpu::upload`]).
pub use bytemuck;
/// The wgpu this crate is built against (30.x). Use `scheduler::wgpu::...` for the buffers and
/// bind groups a run takes, so the versions always match without a dependency of your own.
pub use wgpu;

pub use bindings::{UserBindings, storage_entry};
pub use error::RunError;
pub use gpu::Gpu;
pub use item_layout::ItemLayout;
pub use megakernel::{Megakernel, MegakernelConfig, QueuePolicy, Workgroups};
pub use multipass::host::{HostMultipass, HostMultipassConfig};
pub use multipass::{Multipass, MultipassConfig};
pub use procedure::{ItemType, Procedure};
pub use program::{Program, Seed};
pub use readback::ReadRange;
pub use recorded_run::{DeviceSeeds, RecordedRun, RecordedSize};
pub use stats::{Outcome, RunStats};
pub use strategy::{Scheduler, StrategyKind};
