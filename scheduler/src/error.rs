//! Everything a run can report instead of a result. No variant is ever swallowed: a run either
//! returns complete statistics or one of these.

use std::fmt;

#[derive(Debug, Clone, PartialEq)]
pub enum RunError {
    /// No adapter or device could be opened; the message says what to install.
    NoAdapter(String),
    /// A program is malformed (unknown target procedure, bad threads per item, bad WGSL, ...).
    Program(String),
    /// A bounded wait for the GPU ran out.
    Timeout { what: String, seconds: f64 },
    /// The device reported an error.
    Device(String),
    /// A queue could not hold the live work even after growing to its limit. Nothing was lost:
    /// the run stopped with the queues intact.
    QueueOverflow {
        queue: String,
        capacity: u64,
        needed_more_than: u64,
    },
    /// A procedure emitted more items to a target than it declared in `max_emits`.
    EmitLimit {
        procedure: String,
        target: String,
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
                 {needed_more_than}; no item was lost, raise the queue capacity limit"
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
