//! The command line (clap derive): flags, defaults, ranges. Usage errors exit with status 2 and
//! name the flag; `--help` exits 0 and shows the defaults.

use crate::catalog::WorkloadName;
use crate::scale::Scale;
use crate::strategy::{GpuConfig, Policy};
use clap::error::ErrorKind;
use clap::{CommandFactory, Parser, value_parser};
use scheduler::ItemLayout;
use std::path::PathBuf;
use workloads::tree::{ChildEnqueue, Fanout, TreeParams, TreePreset};

const EXAMPLES: &str = "Examples:
  schedbench --workload tree --strategy all --runs 10
  schedbench --workload tree --preset deep --strategy megakernel --json
  schedbench --workload tree --preset large-payload --strategy all --child-enqueue whole
  schedbench --workload reyes --scene killeroo --width 398 --height 258
  schedbench --workload mandelbrot --size-px 4096
  schedbench --workload bfs --scale 22 --strategy frontier
  schedbench --suite --size small --out report/
  schedbench --suite --size small --workload tree --out report/
  schedbench --replot report/";

/// Runs workloads under the scheduler's strategies (and their CPU implementations), checks every
/// run against the CPU reference, and prints a table of medians (or JSON lines); `--suite`
/// runs everything and writes a report.
#[derive(Debug, Parser)]
#[command(name = "schedbench", after_help = EXAMPLES)]
pub struct Cli {
    /// Run the suite: every workload x strategy x problem size. Writes runs.jsonl, summary.md
    /// and a PNG per workload into --out.
    #[arg(long, requires = "out")]
    pub suite: bool,

    /// The suite's output folder (created if missing).
    #[arg(long, value_name = "DIR", requires = "suite")]
    pub out: Option<PathBuf>,

    /// Draw a suite's plots again from DIR/runs.jsonl, into DIR, and run nothing (e.g. for a
    /// suite whose plots a remote machine could not send back); takes no other option.
    #[arg(long, value_name = "DIR", exclusive = true)]
    pub replot: Option<PathBuf>,

    /// The suite's problem sizes: `small` runs in minutes on lavapipe, `full` is for a GPU.
    #[arg(long, value_enum, default_value_t = Scale::Full, requires = "suite")]
    pub size: Scale,

    /// The workload to run [default: tree]; with --suite, the only one to run.
    #[arg(long, value_enum)]
    pub workload: Option<WorkloadName>,

    /// megakernel, megakernel-fifo, multipass, multipass-host (rounds planned by the host
    /// from read-back queue counts), cpu (the workload's rayon implementation), a workload's
    /// own baseline (e.g. bfs's frontier), or all (all of these but megakernel-fifo and
    /// multipass-floor; the megakernel under --policy); or a comma-separated list of them
    /// (e.g. all,multipass-floor). multipass-floor is a reference: its untimed warm-up is a
    /// host-driven run that keeps the items it executed, and each timed run replays them in
    /// one round, one dispatch per procedure (the bodies' work without the rounds' cost: what
    /// no multi-pass can beat; docs/scheduler.md 5.4).
    #[arg(long, default_value = "all", conflicts_with = "suite")]
    pub strategy: String,

    /// Print one JSON object per run instead of the table.
    #[arg(long, conflicts_with = "suite")]
    pub json: bool,

    /// Timed runs per strategy (and size), after one untimed warm-up run
    /// [default: 5; with --suite: 2 small, 10 full].
    #[arg(long, value_parser = value_parser!(u32).range(1..))]
    pub runs: Option<u32>,

    /// The tree the other tree options change: binary (64 roots, depth 14), irregular,
    /// deep, large-payload or heavy-work.
    #[arg(long, value_parser = parse_preset, default_value = "binary", help_heading = "Tree")]
    pub preset: TreePreset,

    /// Root nodes. The tree (roots x fanout^depth; for uniform:K the mean K/2) may have at
    /// most 2^30 nodes, and nodes x (1 + work) at most 2^36 hash rounds: a larger tree is
    /// refused (exit 2) before it runs.
    #[arg(long, help_heading = "Tree")]
    pub roots: Option<u32>,

    /// Depth of the deepest nodes (roots are at depth 0); within the tree's size limit
    /// (--roots).
    #[arg(long, help_heading = "Tree")]
    pub depth: Option<u32>,

    /// Children per inner node: fixed:K (exactly K) or uniform:K (0..=K from a hash), K in 1..=16.
    #[arg(long, value_parser = parse_fanout, help_heading = "Tree")]
    pub fanout: Option<Fanout>,

    /// Hash rounds per inner node (work per item), 0..=65536; within the tree's work limit
    /// (--roots).
    #[arg(long, value_parser = value_parser!(u32).range(0..=65536), help_heading = "Tree")]
    pub work: Option<u32>,

    /// Payload words per item (item = 2 + payload words).
    #[arg(long, value_name = "WORDS", value_parser = value_parser!(u32).range(1..=254),
          help_heading = "Tree")]
    pub payload: Option<u32>,

    /// Seed of the tree's hashes.
    #[arg(long, help_heading = "Tree")]
    pub seed: Option<u32>,

    /// How a branch hands its children to the queues: whole (built, then `enqueue_<t>`), words
    /// (`reserve_<t>`, then `store_word` as each word is computed) or by-strategy (each strategy's
    /// faster form: words, but whole in the multi-passes for items of 16 words or more, and
    /// whole everywhere for those on a CPU adapter) [default: by-strategy].
    #[arg(long, value_name = "FORM", value_parser = parse_child_enqueue, help_heading = "Tree")]
    pub child_enqueue: Option<ChildEnqueue>,

    /// Scene: teapot (built in), killeroo (the shared data's), or a RIB/Newell/BPT file.
    #[arg(long, default_value = "teapot", help_heading = "Reyes")]
    pub scene: String,

    /// Image width [default: the scene's].
    #[arg(long, value_parser = value_parser!(u32).range(1..=16384), help_heading = "Reyes")]
    pub width: Option<u32>,

    /// Image height [default: the scene's].
    #[arg(long, value_parser = value_parser!(u32).range(1..=16384), help_heading = "Reyes")]
    pub height: Option<u32>,

    /// Image side in pixels: the whole set at `side x side`, 1,024 iterations. Its
    /// Mariani-Silver image is exact (checked) at 256, 1024 and 4096; other sides may differ
    /// from the brute-force reference in a few pixels, which shows as unverified runs
    /// [default: 1024].
    #[arg(long, value_name = "PIXELS", value_parser = value_parser!(u32).range(1..=16384),
          help_heading = "Mandelbrot")]
    pub size_px: Option<u32>,

    /// Graph500 R-MAT scale: 2^scale vertices, 16 edges per vertex, seed 1 [default: 20].
    #[arg(long, value_parser = value_parser!(u32).range(1..=26), help_heading = "BFS")]
    pub scale: Option<u32>,

    /// Megakernel workgroups [default: probe how many run at once].
    #[arg(long, value_parser = value_parser!(u32).range(1..=65535), help_heading = "Scheduler")]
    pub workgroups: Option<u32>,

    /// Launch this share of the probed megakernel workgroups (for --strategy megakernel and
    /// all), `A/B` with 0 < A <= B, or `1` for all, rounded down and at least one
    /// (`Workgroups::ProbeShare`; the `queues:` line and the records' `probed_workgroups` give
    /// what the probe found); not with --workgroups [default: the workload's: on GPUs for
    /// trees whose mean fan-out is at most one and that have at most 65,536 roots, 1/2 with
    /// the local area in workgroup memory and 1/5 without it, one workgroup per SM on the
    /// H100 (`TreeParams::megakernel_workgroup_share`), else all].
    #[arg(long, value_name = "A/B", value_parser = parse_share, conflicts_with = "workgroups",
          help_heading = "Scheduler")]
    pub workgroup_share: Option<(u32, u32)>,

    /// Threads per megakernel workgroup (for --strategy megakernel and all): 256, 512, 768 or
    /// 1024, within the adapter's limit. Larger workgroups limit the registers each thread may
    /// use (on NVIDIA 80 at 768 threads, 64 at 1024); measured, no workload's default ran
    /// faster with them (docs/scheduler.md 4) [default: 256].
    #[arg(long, value_name = "THREADS", value_parser = parse_workgroup_size, help_heading = "Scheduler")]
    pub workgroup_size: Option<u32>,

    /// The megakernel's queue policy (for --strategy megakernel and all).
    #[arg(long, value_enum, default_value_t = Policy::Priority, help_heading = "Scheduler")]
    pub policy: Policy,

    /// The megakernel's queue order under --policy priority (for --strategy megakernel and all):
    /// procedure names, highest first, comma-separated; those not named follow, later ones first
    /// (`QueuePolicy::Priority`; the records' `queue_order` gives the order run). Names as for
    /// --procedure-steps. E.g. `dicesmall,diceshade` runs Reyes later stages first
    /// [default: the workload's: Reyes frames on a GPU breadth first, as `reyes render` runs
    /// them, bound,splitu,splitv,diceshade,dicesmall (`reyes::gpu_render::megakernel_priority`);
    /// else later procedures first, which keeps queues short: tree leaf,branch; reyes on
    /// lavapipe dicesmall,diceshade,splitv,splitu,bound].
    #[arg(
        long,
        value_delimiter = ',',
        value_name = "NAMES",
        help_heading = "Scheduler"
    )]
    pub priority: Vec<String>,

    /// Megakernel workgroup steps per claimed batch [default: the workload's: 2 for Reyes frames
    /// on a GPU, as `reyes render` runs them (`reyes::gpu_render::megakernel_batch_steps`), else 1].
    #[arg(long, value_parser = value_parser!(u32).range(1..=64), help_heading = "Scheduler")]
    pub batch_steps: Option<u32>,

    /// Megakernel steps per batch of named procedures, overriding --batch-steps for them:
    /// `NAME=STEPS`, repeated or comma-separated, e.g. `leaf=4` (tree: branch, leaf; bfs:
    /// bfs_vertex, bfs_edges; mandelbrot: ms_rect, ms_fill, ms_pixels; reyes: bound, splitu,
    /// splitv, diceshade, dicesmall) [default: the workload's on GPUs: leaf=4 for the tree, 16
    /// for both BFS procedures, 8 for diceshade and dicesmall; none on lavapipe].
    #[arg(long, value_delimiter = ',', value_parser = parse_procedure_steps,
          help_heading = "Scheduler")]
    pub procedure_steps: Vec<(String, u32)>,

    /// Longest pause of an idle megakernel workgroup between polls, in trips of a chain of
    /// dependent loads (0: none; lavapipe always runs 0, whatever is given).
    #[arg(long, default_value_t = scheduler::MegakernelConfig::default().idle_backoff,
          value_parser = value_parser!(u32).range(0..=30000), help_heading = "Scheduler")]
    pub idle_backoff: u32,

    /// How the megakernel's and multipass-host's queues hold items: `interleaved` (item after
    /// item) or `planar` (word k of every item together: coalesced, faster for large one-thread
    /// items on GPUs) [default: planar on a GPU for one-thread items of 16+ words, else
    /// interleaved].
    #[arg(long, value_parser = parse_item_layout, help_heading = "Scheduler")]
    pub item_layout: Option<ItemLayout>,

    /// The megakernel enqueues straight into the target queue's slots (`direct`, when a batch's
    /// worst case fits a ticket list in workgroup memory) or through a per-workgroup outbox
    /// copied out after each batch (`outbox`) [default: direct wherever a batch's tickets fit].
    #[arg(long, value_enum, help_heading = "Scheduler")]
    pub enqueue: Option<Enqueue>,

    /// Queue slots at the start of a run [default: from the problem size].
    #[arg(long, value_name = "SLOTS", value_parser = value_parser!(u32).range(1..),
          help_heading = "Scheduler")]
    pub capacity: Option<u32>,

    /// Most slots a queue may grow to, on every strategy (`max_capacity` of their configs):
    /// under such a limit the multi-passes run partial rounds and the megakernel parks work on
    /// the host, going depth first, and the records count both (`partial_rounds`,
    /// `parked_items`); a run overflows only when not one item more can run [default: the
    /// library's, 2^26 slots or the largest binding].
    #[arg(long, value_name = "SLOTS", value_parser = value_parser!(u32).range(1..),
          help_heading = "Scheduler")]
    pub max_capacity: Option<u32>,

    /// Count what the megakernel's loop turns spend per phase (claim, wait for flags, execute,
    /// enqueue, reserve, copy, publish) and print the table after the runs (`MegakernelConfig::turn_anatomy`).
    #[arg(long, help_heading = "Scheduler")]
    pub turn_anatomy: bool,

    /// The megakernel takes enqueue tickets once per subgroup where the adapter has wgpu's
    /// `SUBGROUP` operations (by default one atomic per item: `MegakernelConfig::subgroups`).
    #[arg(long, help_heading = "Scheduler")]
    pub subgroups: bool,

    /// The megakernel keeps the emits a workload declares local (the tree's children, Reyes'
    /// Bound and Split pieces) in its workgroup's area of the queue buffer and runs them next on
    /// the same workgroup (`MegakernelConfig::local_queues`). Default: the workload's choice, on
    /// for trees that do not die out (a fixed fan-out, or a random one of mean 1 or more), off
    /// elsewhere (docs/scheduler.md 2.7).
    #[arg(long, help_heading = "Scheduler", conflicts_with = "no_local_queues")]
    pub local_queues: bool,

    /// The megakernel runs without local queues, whatever the workload would choose.
    #[arg(long, help_heading = "Scheduler")]
    pub no_local_queues: bool,

    /// With local queues, held items of a procedure that emits nothing run in their priority
    /// turn instead of waiting for other held work (`MegakernelConfig::defer_local_sinks`
    /// off): the A/B of the deferral.
    #[arg(long, help_heading = "Scheduler")]
    pub no_defer_local_sinks: bool,

    /// Megakernel claims take at most the workgroup's share of the pending items,
    /// ceil(pending / workgroups), one step's worth at least: guided self-scheduling
    /// (`MegakernelConfig::guided_claims`). Default: the workload's choice, on a GPU on for
    /// Reyes frames, as `reyes render` runs them (`reyes::gpu_render::megakernel_guided_claims`),
    /// and for BFS (`workloads::bfs::megakernel_guided_claims`); off elsewhere and on CPU
    /// adapters.
    #[arg(long, help_heading = "Scheduler", conflicts_with = "no_guided_claims")]
    pub guided_claims: bool,

    /// Megakernel claims take whole batches, whatever the workload would choose.
    #[arg(long, help_heading = "Scheduler")]
    pub no_guided_claims: bool,

    /// With local queues: most bytes of one megakernel workgroup's local area, in global memory,
    /// once per workgroup (`MegakernelConfig::local_bytes`; default 1 MiB: a full batch per
    /// buffer of every local target where it fits). A size too small for one item of any local
    /// target runs without local queues, with a warning.
    #[arg(long, value_name = "BYTES", help_heading = "Scheduler")]
    pub local_bytes: Option<u32>,

    /// With local queues: keep the local area in workgroup memory, at most this many bytes of
    /// it (`MegakernelConfig::local_workgroup_bytes`; 0: the slots buffer) [default: the
    /// workload's: 12288 on GPUs for trees of mean fan-out one, at most 65,536 roots and one
    /// payload word at 256 threads a workgroup (`TreeParams::megakernel_local_workgroup_bytes`),
    /// else 0]. Local batches then read held items from workgroup memory, and one that emitted
    /// only held items skips the release fence. On the H100 2 KiB or more cost co-resident
    /// workgroups, which only the narrow trees can spare, and an area whose buffers hold less
    /// than a step (under 12 KiB for the binary tree) makes part-empty local batches (a
    /// warning says so).
    #[arg(long, value_name = "BYTES", help_heading = "Scheduler")]
    pub local_workgroup_bytes: Option<u32>,

    /// How the device-driven multi-pass dispatches a round (`MultipassConfig::fused_rounds`):
    /// `on`, one indirect dispatch of every procedure's workgroups; `off`, one per procedure;
    /// `sinks-apart`, one for the producers and one for the sinks
    /// (`MultipassConfig::fused_sinks_apart`); `sinks-first`, one with the sinks' workgroups
    /// before the producers' (`MultipassConfig::fused_sinks_first`); `auto`, on for GPUs and off for CPU adapters
    /// such as lavapipe (docs/scheduler.md 5.1).
    #[arg(long, value_enum, default_value = "auto", help_heading = "Scheduler")]
    pub fused_rounds: FusedRounds,

    /// Most workgroups of a procedure in one round of the device-driven multi-pass
    /// (`MultipassConfig::max_workgroups`); past it the workgroups take the items grid-stride.
    /// Default: 528 on GPUs, no cap on CPU adapters such as lavapipe (docs/scheduler.md 5.1).
    #[arg(long, value_name = "WORKGROUPS", help_heading = "Scheduler", value_parser = clap::value_parser!(u32).range(1..))]
    pub max_workgroups: Option<u32>,
}

/// `--fused-rounds`: how the device-driven multi-pass dispatches a round.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum FusedRounds {
    /// On for GPUs, off for CPU adapters.
    Auto,
    /// One indirect dispatch of every procedure's workgroups.
    On,
    /// One indirect dispatch per procedure.
    Off,
    /// One indirect dispatch for the procedures that emit, one for those that do not.
    SinksApart,
    /// One indirect dispatch, the workgroups of the procedures that emit nothing first.
    SinksFirst,
}

/// `--enqueue`: how megakernel items reach their queue.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Enqueue {
    /// Straight into the slots (a ticket per item).
    Direct,
    /// Through the workgroup's outbox.
    Outbox,
}

// The value parsers below return `Result<T, String>`: that is clap's contract for a
// `value_parser` function (the text becomes the usage error, exit 2), not the command's error
// type (`crate::error::Error`).

fn parse_child_enqueue(s: &str) -> Result<ChildEnqueue, String> {
    ChildEnqueue::parse(s)
        .ok_or_else(|| format!("unknown child enqueue `{s}` (known: whole, words, by-strategy)"))
}

fn parse_item_layout(s: &str) -> Result<ItemLayout, String> {
    ItemLayout::parse(s)
        .ok_or_else(|| format!("unknown item layout `{s}` (known: interleaved, planar)"))
}

fn parse_workgroup_size(s: &str) -> Result<u32, String> {
    match s.parse::<u32>() {
        Ok(n @ (256 | 512 | 768 | 1024)) => Ok(n),
        _ => Err(format!(
            "`{s}` is not a megakernel workgroup size (use 256, 512, 768 or 1024)"
        )),
    }
}

/// `A/B`, 0 < A <= B (or `1`, all).
fn parse_share(s: &str) -> Result<(u32, u32), String> {
    let bad = || format!("`{s}` is not a share A/B with 0 < A <= B (e.g. 2/5), or 1 (all)");
    let (a, b) = s.split_once('/').unwrap_or((s, "1"));
    let (a, b) = (a.trim().parse::<u32>(), b.trim().parse::<u32>());
    match (a, b) {
        (Ok(a), Ok(b)) if a > 0 && a <= b => Ok((a, b)),
        _ => Err(bad()),
    }
}

fn parse_preset(s: &str) -> Result<TreePreset, String> {
    TreePreset::parse(s).ok_or_else(|| {
        let names: Vec<_> = TreePreset::ALL.iter().map(|p| p.name()).collect();
        format!("unknown preset `{s}` (known: {})", names.join(", "))
    })
}

/// `fixed:K` or `uniform:K` (also `uniform:0..K`), K in 1..=16.
pub fn parse_fanout(s: &str) -> Result<Fanout, String> {
    let (kind, k) = s
        .split_once(':')
        .ok_or(format!("`{s}` is not fixed:K or uniform:K"))?;
    let k: u32 = k
        .trim_start_matches("0..")
        .parse()
        .map_err(|e| format!("`{s}`: {e}"))?;
    if !(1..=16).contains(&k) {
        return Err(format!("`{s}`: K must be 1..=16"));
    }
    match kind {
        "fixed" => Ok(Fanout::Fixed(k)),
        "uniform" => Ok(Fanout::Uniform(k)),
        _ => Err(format!("`{s}` is not fixed:K or uniform:K")),
    }
}

impl Cli {
    /// Exits with status 2 naming `flag` (clap's usage error).
    pub fn usage_error(kind: ErrorKind, msg: String) -> ! {
        Cli::command().error(kind, msg).exit()
    }

    /// Checks what clap's attributes cannot say: options of one workload with another.
    pub fn check(&self) {
        let workload = self.workload.unwrap_or(WorkloadName::Tree);
        // --preset and --scene have defaults: another value is what counts as given.
        let tree_flags = [
            ("--preset", self.preset != TreePreset::Binary),
            ("--roots", self.roots.is_some()),
            ("--depth", self.depth.is_some()),
            ("--fanout", self.fanout.is_some()),
            ("--work", self.work.is_some()),
            ("--payload", self.payload.is_some()),
            ("--seed", self.seed.is_some()),
            ("--child-enqueue", self.child_enqueue.is_some()),
        ];
        let reyes_flags = [
            ("--scene", self.scene != "teapot"),
            ("--width", self.width.is_some()),
            ("--height", self.height.is_some()),
        ];
        let own_flags = [
            (
                "--size-px",
                self.size_px.is_some(),
                WorkloadName::Mandelbrot,
            ),
            ("--scale", self.scale.is_some(), WorkloadName::Bfs),
        ];
        for (flag, given, w) in own_flags {
            if given && (self.suite || workload != w) {
                Self::usage_error(
                    ErrorKind::ArgumentConflict,
                    format!("{flag} applies to --workload {} without --suite", w.name()),
                );
            }
        }
        for (flag, given) in tree_flags {
            if given && (self.suite || workload != WorkloadName::Tree) {
                Self::usage_error(
                    ErrorKind::ArgumentConflict,
                    format!("{flag} applies to --workload tree without --suite"),
                );
            }
        }
        if workload == WorkloadName::Tree
            && !self.suite
            && let Some(why) = self.tree().too_large()
        {
            let given: Vec<&str> = tree_flags
                .iter()
                .filter(|(f, given)| {
                    *given && !["--preset", "--payload", "--seed", "--child-enqueue"].contains(f)
                })
                .map(|(f, _)| *f)
                .collect();
            let flags = if given.is_empty() {
                "--preset".to_string()
            } else {
                given.join(", ")
            };
            Self::usage_error(
                ErrorKind::ValueValidation,
                format!("{flags}: {why} (see --help, Tree)"),
            );
        }
        for (flag, given) in reyes_flags {
            if given && (self.suite || workload != WorkloadName::Reyes) {
                Self::usage_error(
                    ErrorKind::ArgumentConflict,
                    format!("{flag} applies to --workload reyes without --suite"),
                );
            }
        }
        if !self.priority.is_empty()
            && (self.policy != Policy::Priority
                || self
                    .strategy
                    .split(',')
                    .any(|s| s.trim() == "megakernel-fifo"))
        {
            Self::usage_error(
                ErrorKind::ArgumentConflict,
                "--priority orders the queues of the priority policy, not FIFO's".into(),
            );
        }
        if self.priority.iter().any(|n| n.trim().is_empty()) {
            Self::usage_error(
                ErrorKind::ValueValidation,
                "--priority: an empty name (names are separated by commas alone)".into(),
            );
        }
        // Procedure names are the workload's: checked here, before anything runs.
        self.check_procedure_names("--priority", &self.priority, workload);
        let steps: Vec<String> = self
            .procedure_steps
            .iter()
            .map(|(n, _)| n.clone())
            .collect();
        self.check_procedure_names("--procedure-steps", &steps, workload);
    }

    /// `names`, given to `flag`: each a procedure of `workload`, none twice, and with --suite
    /// only beside --workload; else a usage error (exit 2) naming the flag and the procedures.
    fn check_procedure_names(&self, flag: &str, names: &[String], workload: WorkloadName) {
        if names.is_empty() {
            return;
        }
        if self.suite && self.workload.is_none() {
            Self::usage_error(
                ErrorKind::ArgumentConflict,
                format!("{flag} with --suite needs --workload (procedures are a workload's)"),
            );
        }
        let known = workload.procedures();
        for (i, name) in names.iter().enumerate() {
            if !known.contains(&name.as_str()) {
                Self::usage_error(
                    ErrorKind::ValueValidation,
                    format!(
                        "{flag}: `{name}` is no procedure of --workload {} (its procedures: {})",
                        workload.name(),
                        known.join(", ")
                    ),
                );
            }
            if names[..i].contains(name) {
                Self::usage_error(
                    ErrorKind::ValueValidation,
                    format!("{flag}: `{name}` given twice"),
                );
            }
        }
    }

    /// The tree: the preset, changed by the tree options.
    pub fn tree(&self) -> TreeParams {
        let p = self.preset.params();
        TreeParams {
            roots: self.roots.unwrap_or(p.roots),
            max_depth: self.depth.unwrap_or(p.max_depth),
            fanout: self.fanout.unwrap_or(p.fanout),
            work: self.work.unwrap_or(p.work),
            payload_words: self.payload.unwrap_or(p.payload_words),
            seed: self.seed.unwrap_or(p.seed),
            children: self.child_enqueue.unwrap_or(p.children),
        }
    }

    pub fn gpu_config(&self) -> GpuConfig {
        GpuConfig {
            workgroups: self.workgroups,
            workgroup_share: self.workgroup_share,
            workgroup_size: self.workgroup_size,
            batch_steps: self.batch_steps,
            procedure_steps: (!self.procedure_steps.is_empty())
                .then(|| self.procedure_steps.clone()),
            idle_backoff: self.idle_backoff,
            priority: self.priority.clone(),
            guided_claims: match (self.guided_claims, self.no_guided_claims) {
                (true, _) => Some(true),
                (_, true) => Some(false),
                _ => None,
            },
            capacity: self.capacity,
            max_capacity: self.max_capacity,
            turn_anatomy: self.turn_anatomy,
            subgroups: match self.subgroups {
                true => None,
                false => Some(false),
            },
            item_layout: self.item_layout,
            direct_enqueue: self.enqueue.map(|e| e == Enqueue::Direct),
            local_queues: match (self.local_queues, self.no_local_queues) {
                (true, _) => Some(true),
                (_, true) => Some(false),
                _ => None,
            },
            local_bytes: self.local_bytes,
            local_workgroup_bytes: self.local_workgroup_bytes,
            defer_local_sinks: !self.no_defer_local_sinks,
            fused_rounds: match self.fused_rounds {
                FusedRounds::Auto => None,
                FusedRounds::On | FusedRounds::SinksApart | FusedRounds::SinksFirst => Some(true),
                FusedRounds::Off => Some(false),
            },
            fused_sinks_apart: self.fused_rounds == FusedRounds::SinksApart,
            fused_sinks_first: self.fused_rounds == FusedRounds::SinksFirst,
            max_workgroups: self.max_workgroups,
        }
    }
}

/// `NAME=STEPS` of `--procedure-steps`: a procedure name and its steps per batch (1..=64).
fn parse_procedure_steps(s: &str) -> Result<(String, u32), String> {
    let (name, steps) = s
        .split_once('=')
        .ok_or_else(|| format!("`{s}`: expected NAME=STEPS, e.g. diceshade=4"))?;
    let steps: u32 = steps
        .parse()
        .map_err(|e| format!("`{s}`: steps `{steps}` is not a number ({e})"))?;
    if !(1..=64).contains(&steps) || name.is_empty() {
        return Err(format!(
            "`{s}`: expected a procedure name and steps in 1..=64"
        ));
    }
    Ok((name.to_string(), steps))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(args: &[&str]) -> Result<Cli, clap::Error> {
        Cli::try_parse_from(std::iter::once("schedbench").chain(args.iter().copied()))
    }

    #[test]
    fn procedure_steps_parse_name_and_steps() {
        assert_eq!(
            parse_procedure_steps("diceshade=8"),
            Ok(("diceshade".to_string(), 8))
        );
        for bad in ["diceshade", "=4", "leaf=0", "leaf=65", "leaf=x"] {
            assert!(parse_procedure_steps(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn a_workgroup_share_parses_as_a_fraction_of_at_most_one() {
        assert_eq!(parse_share("2/5"), Ok((2, 5)));
        assert_eq!(parse_share("1"), Ok((1, 1)));
        for bad in ["0/5", "6/5", "2/0", "x/5", "2/", "/5", "-1/5"] {
            assert!(parse_share(bad).is_err(), "{bad}");
        }
        let cli = parse(&["--workgroup-share", "2/5"]).unwrap();
        assert_eq!(cli.gpu_config().workgroup_share, Some((2, 5)));
    }

    #[test]
    fn ranges_and_names_are_checked() {
        for bad in [
            &["--workgroups", "0"][..],
            &["--workgroup-share", "3/2"],
            &["--workgroups", "64", "--workgroup-share", "1/2"],
            &["--batch-steps", "0"],
            &["--workgroup-size", "384"],
            &["--workgroup-size", "2048"],
            &["--runs", "0"],
            &["--payload", "0"],
            &["--fanout", "fixed:0"],
            &["--fanout", "binary:2"],
            &["--preset", "huge"],
            &["--workload", "sort"],
            &["--scale", "27"],
            &["--size-px", "0"],
            &["--suite"],
            &["--out", "x"],
            &["--suite", "--out", "x", "--json"],
        ] {
            let e = parse(bad).expect_err(&format!("{bad:?} accepted"));
            assert_eq!(e.exit_code(), 2, "{bad:?}");
        }
        let e = parse(&["--workgroups", "0"]).unwrap_err().to_string();
        assert!(e.contains("--workgroups"), "{e}");
        let c = parse(&["--workgroup-size", "768"]).unwrap();
        assert_eq!(c.gpu_config().workgroup_size, Some(768));
        assert_eq!(parse(&["--help"]).unwrap_err().exit_code(), 0);
    }

    /// `--strategy`'s help names every strategy every workload has (a new user missed
    /// multipass-host there).
    #[test]
    fn strategy_help_names_every_strategy() {
        let cmd = Cli::command();
        let arg = cmd
            .get_arguments()
            .find(|a| a.get_id() == "strategy")
            .unwrap();
        let help = arg.get_long_help().or(arg.get_help()).unwrap().to_string();
        for s in crate::strategy::Strategy::all_for(&[]) {
            assert!(
                help.contains(&s.name()),
                "{} missing from: {help}",
                s.name()
            );
        }
    }

    #[test]
    fn the_tree_is_the_preset_changed_by_its_options() {
        let c = parse(&[
            "--preset",
            "deep",
            "--roots",
            "7",
            "--fanout",
            "uniform:0..3",
        ])
        .unwrap();
        let t = c.tree();
        assert_eq!(
            (t.roots, t.max_depth, t.fanout),
            (7, 200, Fanout::Uniform(3))
        );
        assert_eq!(parse(&[]).unwrap().tree(), TreeParams::binary_benchmark());
        let s = parse(&["--suite", "--out", "d", "--size", "small"]).unwrap();
        assert_eq!((s.size, s.out), (Scale::Small, Some(PathBuf::from("d"))));
    }
}
