//! `measure`'s errors: one enum, [`Error`], with a variant per kind of failure (a scene that
//! cannot be found or made, a program missing from a build, a folder or file that cannot be
//! made, read or written, an output that does not parse). A case whose output cannot be read
//! is a failed row of the table (the message in its notes); the others end the command with
//! `measure: ` and the message (exit 1).

use std::path::PathBuf;

/// What can make `measure`, or the reading of one case's output, fail.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A scene named by a suite or `--scene` that is none of the places looked at.
    #[error(
        "scene `{name}` not found (looked for {looked}; set REYES_SHARED_DATA or give --data DIR)"
    )]
    SceneNotFound {
        /// The scene's name.
        name: String,
        /// The places looked at, comma-separated.
        looked: String,
    },
    /// A scene file whose displacement shader is not there to replace.
    #[error("{} has no `{shader}` to replace by the built-in bumps", path.display())]
    NoShaderToReplace {
        /// The scene's file.
        path: PathBuf,
        /// The shader statement looked for.
        shader: &'static str,
    },
    /// A file that could not be read.
    #[error("reading {}: {source}", path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
    /// A JSON output that does not parse.
    #[error("reading {}: {source}", path.display())]
    ParseJson {
        /// The output's file.
        path: PathBuf,
        /// The parser's error.
        source: serde_json::Error,
    },
    /// `reyes bench --json`'s output that does not parse.
    #[error("reading reyes bench --json: {0}")]
    ParseBenchJson(#[source] serde_json::Error),
    /// A file that could not be written.
    #[error("writing {}: {source}", path.display())]
    Write {
        /// The file.
        path: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
    /// A folder that could not be made.
    #[error("creating {}: {source}", path.display())]
    CreateFolder {
        /// The folder.
        path: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
    /// The temporary folder for generated inputs could not be made.
    #[error("creating a scratch folder: {0}")]
    ScratchFolder(#[source] std::io::Error),
    /// The temporary folder for outputs (no `--out`) could not be made.
    #[error("creating a work folder: {0}")]
    WorkFolder(#[source] std::io::Error),
    /// The folder of this executable (the default build) is unknown.
    #[error("finding this executable's folder: {0}")]
    CurrentExe(#[source] std::io::Error),
    /// A command a case runs is missing from a build.
    #[error(
        "no `{program}` in {} (cargo build --release --bin {program}; or give {flag} DIR)",
        dir.display()
    )]
    MissingProgram {
        /// The program's name.
        program: String,
        /// The build's folder.
        dir: PathBuf,
        /// The flag that names that build's folder.
        flag: &'static str,
    },
    /// None of the GPU test binaries is in any build.
    #[error(
        "gpu-tests: none of the test binaries {tests} in {dirs} (as NAME or deps/NAME-HASH: \
         cargo test --release --no-run)"
    )]
    NoTestBinaries {
        /// The test binaries looked for, comma-separated.
        tests: String,
        /// The builds' folders, joined by " or ".
        dirs: String,
    },
}
