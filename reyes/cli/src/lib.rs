//! What the project's command-line tools (`reyes`, `schedbench`) share and a library user does
//! not need: progress bars on a terminal ([`progress`]), the logger that writes above them
//! ([`logging`]) and standard output that a closed pipe does not turn into a panic
//! ([`stdout`]). The `reyes` command itself is this package's binary (`src/main.rs`).
#![warn(missing_docs)]

pub mod logging;
pub mod progress;
pub mod stdout;
