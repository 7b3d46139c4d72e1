//! Everything a run can report instead of a result. No variant is ever swallowed: a run either
//! returns complete statistics or one of these.

use std::fmt;

/// Why a program could not be built or a run did not complete (which variant each step can
/// return is listed in `docs/scheduler.md`, section 6).
#[derive(Debug, Clone, PartialEq)]
pub enum RunError {
    /// No adapter or device could be opened; the message says what to install.
    NoAdapter(String),
    /// A program is malformed (unknown target procedure, bad threads per item, bad WGSL, ...),
    /// a configuration is out of range, or seeds or bind groups do not fit the program. WGSL
    /// errors found by [`crate::Program::new`] name the procedure and the line of its body.
    Program(String),
    /// A bounded wait for the GPU ran out ([`crate::Gpu::timeout`]).
    Timeout {
        /// What was being waited for.
        what: String,
        /// The bound that ran out, in seconds.
        seconds: f64,
    },
    /// The device reported an error.
    Device(String),
    /// A queue could not hold the live work even after growing to its limit. Nothing was lost:
    /// the run stopped with the queues intact.
    QueueOverflow {
        /// The procedure whose queue overflowed.
        queue: String,
        /// Its capacity at the end, in items (slots).
        capacity: u64,
        /// Items it would have had to hold, at least.
        needed_more_than: u64,
    },
    /// A procedure emitted more items to a target than it declared with
    /// [`crate::Procedure::emits`]; the excess was dropped and the run stopped.
    EmitLimit {
        /// The emitting procedure.
        procedure: String,
        /// The target procedure.
        target: String,
        /// Items per executed item it declared for that target.
        declared: u32,
    },
    /// The run needed more launches (megakernel) or rounds (multi-pass) than allowed.
    NoProgress(String),
}

impl fmt::Display for RunError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            RunError::NoAdapter(m) => write!(f, "no GPU adapter: {m}"),
            RunError::Program(m) => write!(f, "invalid program: {m}"),
            RunError::Timeout { what, seconds } => {
                write!(f, "GPU did not finish {what} within {seconds:.1} s")
            }
            RunError::Device(m) => write!(f, "GPU device error: {m}"),
            RunError::QueueOverflow {
                queue,
                capacity,
                needed_more_than,
            } => write!(
                f,
                "queue `{queue}` overflowed: capacity {capacity} items, live work needs more than \
                 {needed_more_than}; no item was lost (more room: a larger memory budget, or the \
                 strategy's max_capacity)"
            ),
            RunError::EmitLimit {
                procedure,
                target,
                declared,
            } => write!(
                f,
                "procedure `{procedure}` emitted more than its declared max_emits ({declared}) \
                 items to `{target}` for one item"
            ),
            RunError::NoProgress(m) => write!(f, "run made no progress: {m}"),
        }
    }
}

impl std::error::Error for RunError {}
