//! Everything a run can report instead of a result. No variant is ever swallowed: a run either
//! returns complete statistics or one of these.

/// Why a program could not be built or a run did not complete (which variant each step can
/// return is listed in `docs/scheduler.md`, section 6).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RunError {
    /// No adapter or device could be opened; the message says what to install.
    #[error("no GPU adapter: {0}")]
    NoAdapter(String),
    /// A program is malformed (unknown target procedure, bad threads per item, bad WGSL, ...),
    /// a configuration is out of range, or seeds or bind groups do not fit the program. WGSL
    /// errors found by [`crate::Program::new`] name the procedure and the line of its body.
    #[error("invalid program: {0}")]
    Program(String),
    /// A bounded wait for the GPU ran out ([`crate::Gpu::timeout`]).
    #[error("GPU did not finish {what} within {seconds:.1} s")]
    Timeout {
        /// What was being waited for.
        what: String,
        /// The bound that ran out, in seconds.
        seconds: f64,
    },
    /// The device reported an error.
    #[error("GPU device error: {0}")]
    Device(String),
    /// A queue could not hold the live work even after growing to its limit: the multi-passes'
    /// partial rounds, or the megakernel's parked work, could not run even one item more.
    /// Nothing was lost: the run stopped with the queues intact.
    #[error(
        "queue `{queue}` overflowed: capacity {capacity} items, live work needs more than \
         {needed_more_than}; no item was lost (more room: a larger `max_capacity` in the \
         strategy's config, or a larger budget given to `run_within`)"
    )]
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
    #[error(
        "procedure `{procedure}` emitted more than its declared max_emits ({declared}) \
         items to `{target}` for one item"
    )]
    EmitLimit {
        /// The emitting procedure.
        procedure: String,
        /// The target procedure.
        target: String,
        /// Items per executed item it declared for that target.
        declared: u32,
    },
    /// The run needed more launches (megakernel) or rounds (multi-pass) than allowed.
    #[error("run made no progress: {0}")]
    NoProgress(String),
}

#[cfg(test)]
mod tests {
    use super::RunError;

    /// The messages callers and scripts see, word for word.
    #[test]
    fn every_variant_displays_its_message() {
        let cases = [
            (RunError::NoAdapter("x".into()), "no GPU adapter: x"),
            (RunError::Program("x".into()), "invalid program: x"),
            (
                RunError::Timeout {
                    what: "a launch".into(),
                    seconds: 12.34,
                },
                "GPU did not finish a launch within 12.3 s",
            ),
            (RunError::Device("x".into()), "GPU device error: x"),
            (
                RunError::QueueOverflow {
                    queue: "leaf".into(),
                    capacity: 16,
                    needed_more_than: 17,
                },
                "queue `leaf` overflowed: capacity 16 items, live work needs more than 17; no \
                 item was lost (more room: a larger `max_capacity` in the strategy's config, \
                 or a larger budget given to `run_within`)",
            ),
            (
                RunError::EmitLimit {
                    procedure: "split".into(),
                    target: "leaf".into(),
                    declared: 4,
                },
                "procedure `split` emitted more than its declared max_emits (4) items to `leaf` \
                 for one item",
            ),
            (RunError::NoProgress("x".into()), "run made no progress: x"),
        ];
        for (e, message) in cases {
            assert_eq!(e.to_string(), message);
        }
    }
}
