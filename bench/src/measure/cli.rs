//! `measure`'s command line (clap derive): the suites, the builds to run, where the files go.
//! Usage errors (an unknown suite, a value out of range, `suite` without `--out`) exit with
//! status 2 and name what was wrong; `--help` lists the suites and the defaults.

use clap::error::ErrorKind;
use clap::{CommandFactory, Parser, ValueEnum, value_parser};
use std::path::PathBuf;

const EXAMPLES: &str = "Examples:
  measure trees frames --runs 10                  # the binaries beside this one
  measure frames bench --compare ../prev/release  # A/B: the two builds alternated, ratios
  measure trees --size small --runs 2             # seconds to minutes on lavapipe
  measure suite --out report/                     # schedbench --suite --size full into report/suite
  measure gpu-tests --bin .devbin --adapter H200  # the GPU test binaries found in .devbin

Exit status: 0 when every process succeeded and every checked row was verified, 1 otherwise
(also for a missing binary or scene, named), 2 for usage errors.";

/// Runs named measurement suites with the built `schedbench` and `reyes` commands (and the GPU
/// test binaries) and prints one table: per suite, case, strategy (and build) the GPU ms median
/// ± MAD, the wall ms median, the timed runs and whether the results were verified.
#[derive(Debug, Parser)]
#[command(name = "measure", after_help = EXAMPLES)]
pub struct Cli {
    /// The suites to run, in the order given.
    #[arg(value_enum, required = true, value_name = "SUITE")]
    pub suites: Vec<Suite>,

    /// Timed runs per process: `schedbench --runs`, `reyes render --runs`, `reyes bench
    /// --frames` [default: the suite's, from its measurements in docs/results.md: 10 runs
    /// (overflow 5, many-patches 3, suite 5), 200 bench frames (peer and raster-modes 100);
    /// with --size small: 2 runs, 5 frames, many-patches 1].
    #[arg(long, value_name = "N", value_parser = value_parser!(u32).range(1..))]
    pub runs: Option<u32>,

    /// Problem sizes: `full` (the sizes of docs/results.md, for a GPU) or `small` (the same
    /// cases shrunk to run in seconds to minutes on lavapipe).
    #[arg(long, value_enum, default_value_t = Size::Full)]
    pub size: Size,

    /// The folder of the build to measure: `schedbench`, `reyes` and, for gpu-tests, the test
    /// binaries (also as `deps/NAME-HASH`, cargo's name) [default: the folder of this
    /// executable].
    #[arg(long, value_name = "DIR")]
    pub bin: Option<PathBuf>,

    /// A second build's folder, run as the baseline: each case alternates the baseline and
    /// --bin's build process by process (`base`, `new`), and a ratio column gives new / base.
    #[arg(long, value_name = "DIR")]
    pub compare: Option<PathBuf>,

    /// Processes per build and case, alternated between the builds with --compare
    /// [default: 1; 2 with --compare].
    #[arg(long, value_name = "K", value_parser = value_parser!(u32).range(1..))]
    pub repeats: Option<u32>,

    /// Keep every process's output here (stdout, stderr, --stats JSON, the suite's report)
    /// with the table (`table.txt`, `table.md`); created if missing [default: a temporary
    /// folder, removed at the end].
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,

    /// Keep the rendered images (PNG) in --out; else only their md5 is kept.
    #[arg(long, requires = "out")]
    pub keep_images: bool,

    /// The adapter to run on (a substring of its name), passed on as `WGPU_ADAPTER_NAME`.
    #[arg(long, value_name = "NAME")]
    pub adapter: Option<String>,

    /// The shared scene folder (`rib/killeroo.rib`, `field/...`) [default: REYES_SHARED_DATA,
    /// else `shared/data` beside the repository].
    #[arg(long, value_name = "DIR")]
    pub data: Option<PathBuf>,

    /// A scene of frames, bench, peer and raster-modes (repeatable): `teapot` (built in), a
    /// name of the shared data's `rib/` (`killeroo`, `uteapot`), a path in the shared data
    /// (`field/airplane.rib`) or a file [default: the suite's scenes].
    #[arg(long = "scene", value_name = "SCENE")]
    pub scenes: Vec<String>,

    /// Run only the cases whose name contains TEXT (repeatable: any of them); the effects'
    /// references are kept when a case compares to them.
    #[arg(long, value_name = "TEXT")]
    pub only: Vec<String>,

    /// Longest a process may run before it is stopped and reported as failed, seconds.
    #[arg(long, value_name = "SECONDS", default_value_t = 600,
          value_parser = value_parser!(u64).range(1..))]
    pub timeout: u64,

    /// Print the table as Markdown (as docs/results.md tables it) instead of aligned text.
    #[arg(long)]
    pub markdown: bool,
}

/// A named set of measurements (`measure --help` lists them with these descriptions).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, ValueEnum)]
pub enum Suite {
    /// The tree presets (binary, irregular, deep, large-payload, heavy-work) under every
    /// strategy, and the megakernel with the FIFO policy: `schedbench --workload tree`.
    Trees,
    /// A tree run started with 16 queue slots against one with room enough, every strategy.
    Overflow,
    /// Reyes frames (teapot, Killeroo at 1920x1080) per strategy: `reyes render --runs N`,
    /// and the md5 of each image (verified: every image of a scene the same).
    Frames,
    /// Pipelined frames (teapot, uteapot, Killeroo at 1080p and 4K, turntable): `reyes
    /// bench`, wall and GPU ms per frame, fps.
    Bench,
    /// `reyes bench --peer raster`: the same frames by the raster peer, beside Reyes's two
    /// strategies (the peer's row pools both processes' frames).
    Peer,
    /// `reyes bench --raster bbox|nearest` at micropolygon sizes 1 and 0.5.
    RasterModes,
    /// Killeroo with motion blur (`--spin`), depth of field (`--dof`) and none, every
    /// `--sampling` at 16/25/64 samples, with the image error against a 256-sample reference;
    /// displacement with exact and approximate normals.
    Effects,
    /// 1,000,000 and 2,000,000 tiny patches (a generated RIB) on every strategy and the CPU.
    ManyPatches,
    /// BFS on R-MAT graphs (scales 20 and 22), every strategy.
    Bfs,
    /// Adaptive Mandelbrot (1024 and 4096 pixels a side), every strategy.
    Mandelbrot,
    /// `schedbench --suite` into --out (its runs.jsonl, summary.md and plots), one row per
    /// workload, size and strategy.
    #[value(name = "suite")]
    Report,
    /// The GPU test binaries found in --bin (scheduler_gpu, workloads_gpu, reyes_gpu,
    /// reyes_realtime), one at a time with `--test-threads 1`.
    GpuTests,
}

impl Suite {
    /// The name on the command line and in the table.
    pub fn name(self) -> String {
        self.to_possible_value()
            .expect("no suite is hidden")
            .get_name()
            .to_string()
    }
}

/// `--size`: which problem sizes the suites use.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Size {
    /// Shrunk cases for lavapipe (and for checking the tool itself).
    Small,
    /// The sizes of docs/results.md.
    Full,
}

impl Cli {
    /// Checks what clap's attributes cannot say; exits with status 2 naming the problem.
    pub fn check(&self) {
        if self.suites.contains(&Suite::Report) && self.out.is_none() {
            Cli::command()
                .error(
                    ErrorKind::MissingRequiredArgument,
                    "the suite `suite` writes schedbench's report into --out DIR: give --out",
                )
                .exit();
        }
    }

    /// Processes per build and case.
    pub fn repeats(&self) -> u32 {
        self.repeats
            .unwrap_or(if self.compare.is_some() { 2 } else { 1 })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(args: &[&str]) -> Result<Cli, clap::Error> {
        Cli::try_parse_from(std::iter::once("measure").chain(args.iter().copied()))
    }

    #[test]
    fn suites_are_named_on_the_command_line_and_checked() {
        let c = parse(&["trees", "gpu-tests", "raster-modes", "--runs", "3"]).unwrap();
        assert_eq!(
            c.suites,
            vec![Suite::Trees, Suite::GpuTests, Suite::RasterModes]
        );
        assert_eq!(Suite::ManyPatches.name(), "many-patches");
        for bad in [
            &["sort"][..],
            &[],
            &["trees", "--runs", "0"],
            &["trees", "--size", "huge"],
            &["trees", "--keep-images"],
        ] {
            let e = parse(bad).expect_err(&format!("{bad:?} accepted"));
            assert_eq!(e.exit_code(), 2, "{bad:?}");
        }
        assert!(parse(&["sort"]).unwrap_err().to_string().contains("sort"));
        assert_eq!(parse(&["--help"]).unwrap_err().exit_code(), 0);
    }

    #[test]
    fn a_comparison_repeats_each_build_twice_unless_told() {
        assert_eq!(parse(&["trees"]).unwrap().repeats(), 1);
        assert_eq!(parse(&["trees", "--compare", "d"]).unwrap().repeats(), 2);
        let c = parse(&["trees", "--compare", "d", "--repeats", "3"]).unwrap();
        assert_eq!(c.repeats(), 3);
    }
}
