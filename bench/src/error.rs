//! `schedbench`'s errors: one enum, [`Error`], with a variant per kind of failure (a failed
//! GPU run, a scene or frame the renderer library refuses, an input that cannot be read or
//! generated, a report file that cannot be written, a plot that cannot be drawn). A failure
//! of one run is recorded in the report (its text in `runs.jsonl`) and the suite goes on;
//! the others end the command with `schedbench: ` and the message (exit 1).

use reyes::scene::SceneError;
use scheduler::RunError;
use std::path::PathBuf;

/// What can make a run, a workload or the whole command fail.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A GPU run that failed (no adapter, a device error, a timeout, a queue overflow; an
    /// overflow's advice names schedbench's options).
    #[error("{}", run_message(.0))]
    Run(#[from] RunError),
    /// The renderer library's error: a frame's options out of range.
    #[error(transparent)]
    Reyes(#[from] reyes::Error),
    /// A scene file that could not be read or parsed (the reader's error names the file and
    /// line).
    #[error("{source}")]
    SceneFile {
        /// The scene's file.
        path: PathBuf,
        /// The reader's error.
        source: SceneError,
    },
    /// A scene of the shared data (`killeroo`) that is not where `reyes::shared_data_dir`
    /// looks.
    #[error(
        "{}: the shared scene is missing; set REYES_SHARED_DATA to the shared data folder \
         (by default `shared/data` beside the repository)",
        .0.display()
    )]
    SharedScene(PathBuf),
    /// An R-MAT graph that could not be generated.
    #[error("R-MAT scale {scale}: {source}")]
    Graph {
        /// The graph's scale (log2 of its vertices).
        scale: u32,
        /// The generator's error.
        source: RunError,
    },
    /// A baseline strategy asked of the Reyes workload, which has none.
    #[error("Reyes has no baseline `{0}`")]
    NoReyesBaseline(String),
    /// The warm-up run did not match the CPU reference.
    #[error("warm-up run: {0}")]
    WarmUpMismatch(String),
    /// A report file or folder that could not be made or written.
    #[error("{}: {source}", path.display())]
    File {
        /// The file or folder.
        path: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
    /// A line of a suite's `runs.jsonl` that is not a run record (`--replot`).
    #[error("{}:{line}: not a run record: {message}", path.display())]
    Record {
        /// The records' file.
        path: PathBuf,
        /// Its line, from 1.
        line: usize,
        /// The parser's error.
        message: String,
    },
    /// A suite's `runs.jsonl` without a run record (`--replot`).
    #[error("{}: no run records to plot", .0.display())]
    NoRecords(PathBuf),
    /// A plot the plotting backend could not draw.
    #[error("plot {workload}: {message}")]
    Plot {
        /// The plot's workload.
        workload: String,
        /// The backend's error, as text (its type depends on the backend).
        message: String,
    },
    /// A drawn plot whose buffer is not the plot's size.
    #[error("plot buffer size")]
    PlotBufferSize,
    /// A plot that could not be encoded as PNG.
    #[error(transparent)]
    Encode(#[from] image::ImageError),
}

/// A run error's message; a queue overflow's advice in schedbench's terms: its queues grow
/// to the device's largest storage binding (or the strategy's limit), so what makes room is
/// fewer items alive at once (at most the whole tree) or smaller ones.
fn run_message(e: &RunError) -> String {
    match e {
        RunError::QueueOverflow {
            queue,
            capacity,
            needed_more_than,
        } => format!(
            "queue `{queue}` overflowed: capacity {capacity} items, live work needs more than \
             {needed_more_than}; no item was lost (make room with a larger --max-capacity where \
             one was given, a smaller --payload, or a smaller tree, fewer items alive at once: \
             fewer --roots, a lower --depth, a smaller --fanout)"
        ),
        other => other.to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::CommandFactory;

    /// A queue overflow's advice names only options schedbench has (not the library's "memory
    /// budget" or its config field `max_capacity`, which schedbench sets as `--max-capacity`).
    #[test]
    fn overflow_advice_names_existing_options() {
        let e = Error::Run(RunError::QueueOverflow {
            queue: "branch".into(),
            capacity: 65535,
            needed_more_than: 65535,
        });
        let text = e.to_string();
        assert!(
            text.starts_with("queue `branch` overflowed: capacity 65535"),
            "{text}"
        );
        let cmd = crate::cli::Cli::command();
        let named: Vec<&str> = text
            .split(|c: char| !(c.is_ascii_alphanumeric() || c == '-'))
            .filter_map(|w| w.strip_prefix("--"))
            .collect();
        assert!(named.len() >= 3, "{text}");
        for flag in named {
            assert!(
                cmd.get_arguments().any(|a| a.get_long() == Some(flag)),
                "--{flag} is no schedbench option: {text}"
            );
        }
        assert!(
            !text.contains("max_capacity") && !text.contains("memory budget"),
            "{text}"
        );
    }
}
