//! The small benchmark suite end to end: the built `schedbench --suite --size small` on the
//! adapter from the environment (lavapipe in CI; none is a failure, as in every GPU test).
//! Every run must be verified, every workload x strategy x size present, and the report files
//! complete. It checks results and files, never speed.

use serde_json::Value;
use std::collections::BTreeSet;
use std::io::{BufRead, BufReader};
use std::process::{Command, Stdio};

/// Strategies every workload runs under (scheduler strategies with the megakernel once per
/// queue policy, and the CPU implementation); `--strategy` names as in the records.
const STRATEGIES: [&str; 4] = ["megakernel", "megakernel-fifo", "multipass", "cpu"];
const WORKLOADS: [&str; 9] = [
    "tree-binary",
    "tree-irregular",
    "tree-deep",
    "tree-large-payload",
    "tree-heavy-work",
    "reyes-teapot",
    "reyes-killeroo",
    "mandelbrot",
    "bfs",
];
const RUNS: usize = 2;

#[test]
fn small_suite_verifies_every_run_and_writes_its_report() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("report");
    let status = Command::new(env!("CARGO_BIN_EXE_schedbench"))
        .args(["--suite", "--size", "small", "--runs", &RUNS.to_string()])
        .arg("--out")
        .arg(&out)
        .status()
        .expect("schedbench runs");
    assert!(status.success(), "schedbench --suite failed: {status}");

    let text = std::fs::read_to_string(out.join("runs.jsonl")).unwrap();
    let records: Vec<Value> = text
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    let mut seen = BTreeSet::new();
    for r in &records {
        let (w, s, size) = (
            r["workload"].as_str().unwrap(),
            r["strategy"].as_str().unwrap(),
            r["size"].as_str().unwrap(),
        );
        assert_eq!(r["verified"], true, "{w} {s} {size}: {}", r["error"]);
        for field in [
            "params",
            "adapter",
            "items",
            "gpu_ms",
            "wall_ms",
            "rounds",
            "launches",
            "spin_wait_us",
        ] {
            assert!(r.get(field).is_some(), "{w} {s}: no `{field}`");
        }
        assert!(r["wall_ms"].as_f64().unwrap() > 0.0);
        assert!(r["items"].as_u64().unwrap() > 0, "{w} {s} {size}: no items");
        if w == "bfs" {
            // Graph runs give GTEPS (the Graph500 traversed edges over the run's time).
            assert!(r["gteps"].as_f64().unwrap() > 0.0, "{s} {size}: no gteps");
        }
        // The megakernel's records say what it ran with; the multi-passes' do not.
        if s.starts_with("megakernel") {
            assert_eq!(r["workgroup_size"], 256, "{w} {s} {size}");
            // Local queues where the workload chose them: the trees that do not die out.
            let local = matches!(
                w,
                "tree-binary"
                    | "tree-irregular"
                    | "tree-deep"
                    | "tree-large-payload"
                    | "tree-heavy-work"
            );
            assert_eq!(r["local_queues"], local, "{w} {s} {size}");
        } else {
            assert!(r.get("workgroup_size").is_none(), "{w} {s} {size}");
            assert!(r.get("local_queues").is_none(), "{w} {s} {size}");
        }
        if s == "multipass" && w.starts_with("tree") {
            assert!(r["rounds"].as_u64().unwrap() > 0, "{w} {size}: no rounds");
        }
        seen.insert((w.to_string(), s.to_string(), size.to_string()));
    }
    for w in WORKLOADS {
        let sizes: BTreeSet<&str> = seen
            .iter()
            .filter(|k| k.0 == w)
            .map(|k| k.2.as_str())
            .collect();
        let want = if w.starts_with("reyes") { 1 } else { 2 };
        assert!(sizes.len() >= want, "{w}: sizes {sizes:?}");
        for s in STRATEGIES {
            let of_s: BTreeSet<&str> = seen
                .iter()
                .filter(|k| k.0 == w && k.1 == s)
                .map(|k| k.2.as_str())
                .collect();
            assert_eq!(of_s, sizes, "{w} x {s}");
        }
    }
    // BFS also runs its hand-written frontier baseline, at every size.
    let frontier = seen
        .iter()
        .filter(|k| k.0 == "bfs" && k.1 == "frontier")
        .count();
    assert_eq!(frontier, 2, "bfs x frontier");
    let per_combination = records.len() / seen.len();
    assert_eq!((per_combination, records.len() % seen.len()), (RUNS, 0));

    let summary = std::fs::read_to_string(out.join("summary.md")).unwrap();
    for w in WORKLOADS {
        assert!(summary.contains(&format!("## {w}")), "summary lacks {w}");
        let png = std::fs::read(out.join(format!("{w}.png"))).unwrap();
        assert!(png.starts_with(b"\x89PNG") && png.len() > 10_000, "{w}.png");
    }
    assert!(summary.contains("1 (best)"));
    // `--replot` draws the same plots again from the records alone.
    let drawn: Vec<Vec<u8>> = (WORKLOADS.iter())
        .map(|w| std::fs::read(out.join(format!("{w}.png"))).unwrap())
        .collect();
    for w in WORKLOADS {
        std::fs::remove_file(out.join(format!("{w}.png"))).unwrap();
    }
    let replot = Command::new(env!("CARGO_BIN_EXE_schedbench"))
        .arg("--replot")
        .arg(&out)
        .output()
        .expect("schedbench runs");
    assert!(replot.status.success(), "{replot:?}");
    for (w, png) in WORKLOADS.iter().zip(&drawn) {
        let again = std::fs::read(out.join(format!("{w}.png"))).unwrap();
        assert!(&again == png, "{w}.png drawn differently from the records");
    }
    // Nothing half-written is left behind.
    for e in std::fs::read_dir(&out).unwrap() {
        let name = e.unwrap().file_name().into_string().unwrap();
        assert!(!name.starts_with('.'), "temporary file {name} left");
    }
}

/// Trees that would abort allocating, take 4 GB or never end are refused before any
/// GPU work: exit 2, naming the flags that made them too large; `--help` states the limits.
#[test]
fn trees_too_large_to_run_are_refused_naming_their_flags() {
    for (args, flags) in [
        (&["--roots", "4294967295"][..], &["--roots"][..]),
        (&["--depth", "4294967295"], &["--depth"]),
        (&["--depth", "40"], &["--depth"]),
        (
            &["--fanout", "fixed:16", "--depth", "12"],
            &["--depth", "--fanout"],
        ),
        (&["--work", "4294967295"], &["--work"]),
        (
            &["--work", "65536", "--roots", "64"],
            &["--roots", "--work"],
        ),
        (&["--preset", "deep", "--depth", "4294967295"], &["--depth"]),
    ] {
        let out = Command::new(env!("CARGO_BIN_EXE_schedbench"))
            .args(["--workload", "tree", "--strategy", "cpu"])
            .args(args)
            .output()
            .expect("schedbench runs");
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        for flag in flags {
            assert!(err.contains(flag), "{args:?}: no {flag} in {err}");
        }
    }
    let help = Command::new(env!("CARGO_BIN_EXE_schedbench"))
        .arg("--help")
        .output()
        .unwrap();
    let help = String::from_utf8_lossy(&help.stdout);
    assert!(
        help.contains("2^30 nodes") && help.contains("0..=65536"),
        "{help}"
    );
}

/// `--procedure-steps` names the workload's procedures: another workload's name, or one given
/// twice, is a usage error (exit 2) before anything runs, listing the workload's procedures.
#[test]
fn procedure_steps_name_the_workloads_procedures() {
    for (args, expected) in [
        (
            &["--workload", "bfs", "--procedure-steps", "leaf=4"][..],
            "bfs_vertex, bfs_edges",
        ),
        (
            &["--workload", "tree", "--procedure-steps", "leaf=4,leaf=2"],
            "given twice",
        ),
        (&["--procedure-steps", "diceshade=8"], "branch, leaf"),
    ] {
        assert_usage_error(args, expected);
    }
}

/// `--priority` names the workload's procedures, each once and none empty, and orders the
/// priority policy's queues: a FIFO megakernel, or a suite without a workload, is a usage error
/// (exit 2) before anything runs. The order reaches the scheduler: on one workgroup (the run is
/// then deterministic) the tree's branches first hold more leaves waiting than the default,
/// leaves first, and each record's `queue_order` is the order asked for, completed.
#[test]
fn priority_orders_the_workloads_procedures() {
    let dir = tempfile::tempdir().unwrap();
    let suite = dir.path().join("suite");
    let suite = suite.to_str().unwrap();
    for (args, expected) in [
        (&["--priority", "bound"][..], "its procedures: branch, leaf"),
        (&["--priority", "leaf,leaf"], "given twice"),
        (&["--priority", "leaf,"], "an empty name"),
        (&["--priority", "leaf", "--policy", "fifo"], "not FIFO's"),
        (
            &["--priority", "leaf", "--strategy", "megakernel-fifo"],
            "not FIFO's",
        ),
        (
            &[
                "--suite",
                "--size",
                "small",
                "--priority",
                "leaf",
                "--out",
                suite,
            ],
            "--priority with --suite needs --workload",
        ),
    ] {
        assert_exits_2(args, expected);
    }
    assert!(
        !dir.path().join("suite").exists(),
        "a refused suite writes nothing"
    );
    let run = |order: &[&str]| {
        let tree = ["--roots", "2", "--depth", "10", "--workgroups", "1"];
        let r = first_json_record(&[&tree[..], &["--no-local-queues"], order].concat());
        let leaves_waiting = r["peak_occupancy"][1].as_u64().unwrap();
        (r["queue_order"].clone(), leaves_waiting)
    };
    let (default_order, default_peak) = run(&[]);
    let (branch_order, branch_peak) = run(&["--priority", "branch"]);
    assert_eq!(default_order, serde_json::json!(["leaf", "branch"]));
    assert_eq!(branch_order, serde_json::json!(["branch", "leaf"]));
    assert!(
        branch_peak > default_peak,
        "{branch_peak} <= {default_peak}"
    );
}

/// `--guided-claims` and `--no-guided-claims` reach the megakernel and its records say which
/// ran (`guided_claims`); the tree's default is off; both at once are a usage error.
#[test]
fn guided_claims_are_asked_for_and_recorded() {
    assert_exits_2(
        &[
            "--workload",
            "tree",
            "--guided-claims",
            "--no-guided-claims",
        ],
        "cannot be used with",
    );
    let guided = |flag: &[&str]| {
        let tree = ["--roots", "2", "--depth", "8", "--workgroups", "3"];
        first_json_record(&[&tree[..], flag].concat())["guided_claims"].clone()
    };
    assert_eq!(guided(&[]), serde_json::json!(false));
    assert_eq!(guided(&["--guided-claims"]), serde_json::json!(true));
    assert_eq!(guided(&["--no-guided-claims"]), serde_json::json!(false));
}

/// `--local-workgroup-bytes` reaches the megakernel: its records give the area's bytes in
/// workgroup memory (at most those asked for; absent by default), the run stays exact, and
/// with local queues off the option does nothing and says so.
#[test]
fn a_local_area_in_workgroup_memory_is_asked_for_and_recorded() {
    let tree = ["--roots", "2", "--depth", "8", "--workgroups", "3"];
    let area = |flag: &[&str]| {
        first_json_record(&[&tree[..], flag].concat())["local_workgroup_bytes"].clone()
    };
    assert_eq!(area(&[]), serde_json::Value::Null);
    let bytes = area(&["--local-workgroup-bytes", "2048"]).as_u64().unwrap();
    assert!(bytes > 0 && bytes <= 2048, "{bytes}");
    let out = Command::new(env!("CARGO_BIN_EXE_schedbench"))
        .args(ONE_MEGAKERNEL_TREE)
        .args(tree)
        .args(["--no-local-queues", "--local-workgroup-bytes", "2048"])
        .output()
        .expect("schedbench runs");
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{err}");
    assert!(
        err.contains("local queues are off: it has no effect"),
        "{err}"
    );
}

/// `--max-capacity` bounds every strategy's queues: a tree whose breadth passes the limit
/// still runs exactly on each, the multi-passes in partial rounds and the megakernel with
/// work parked on the host, and the records count both.
#[test]
fn a_queue_limit_runs_every_strategy_depth_first_and_is_recorded() {
    let records = json_records(&[
        "--workload",
        "tree",
        "--roots",
        "2",
        "--depth",
        "9",
        "--fanout",
        "fixed:2",
        "--payload",
        "2",
        "--max-capacity",
        "32",
        "--strategy",
        "all",
        "--runs",
        "1",
    ]);
    let by = |name: &str| {
        let r = records.iter().find(|r| r["strategy"] == name);
        r.unwrap_or_else(|| panic!("no {name} record: {records:?}"))
            .clone()
    };
    for r in &records {
        assert_eq!(r["verified"], true, "{r}");
    }
    assert!(
        by("megakernel")["parked_items"].as_u64().unwrap() > 0,
        "{records:?}"
    );
    for mp in ["multipass", "multipass-host"] {
        assert!(
            by(mp)["partial_rounds"].as_u64().unwrap() > 0,
            "{records:?}"
        );
    }
}

/// `--replot` takes no other option (exit 2), and a folder without records is an error naming
/// the file (exit 1), not "0 plots".
#[test]
fn replot_takes_no_other_option_and_needs_records() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path().to_str().unwrap();
    assert_exits_2(&["--replot", d, "--json"], "cannot be used with");
    for contents in [None, Some("")] {
        if let Some(c) = contents {
            std::fs::write(dir.path().join("runs.jsonl"), c).unwrap();
        }
        let out = Command::new(env!("CARGO_BIN_EXE_schedbench"))
            .args(["--replot", d])
            .output()
            .expect("schedbench runs");
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{err}");
        assert!(err.contains("runs.jsonl"), "{err}");
    }
}

/// `--child-enqueue` builds the tree's program with that form, which the record's params
/// name; the default (by strategy) adds nothing to them.
#[test]
fn the_child_enqueue_form_is_asked_for_and_recorded() {
    let small = ["--preset", "large-payload", "--roots", "1", "--depth", "4"];
    for form in ["whole", "words"] {
        let r = first_json_record(&[&small[..], &["--child-enqueue", form]].concat());
        let params = r["params"].as_str().unwrap();
        assert!(params.ends_with(&format!(" children={form}")), "{params}");
    }
    let r = first_json_record(&small);
    assert!(!r["params"].as_str().unwrap().contains("children"), "{r}");
    assert_exits_2(&["--child-enqueue", "half"], "unknown child enqueue `half`");
    assert_exits_2(
        &["--workload", "bfs", "--child-enqueue", "words"],
        "--child-enqueue applies to --workload tree",
    );
}

/// `--strategy multipass-floor` is named, not part of `all`: its warm-up keeps the tree's
/// items, and every timed run replays them in one round, one launch per procedure, verified
/// against the CPU reference. A comma-separated list runs each named strategy once, in order.
/// BFS, whose bodies emit more when every level runs at once, replays verified too (room for
/// the round's worst case), and an unknown name lists the floor among the known ones.
#[test]
fn the_multipass_floor_is_named_and_replays_in_one_round() {
    let records = |args: &[&str]| json_records(&[args, &["--runs", "2"]].concat());
    let tree = [
        "--workload",
        "tree",
        "--preset",
        "binary",
        "--roots",
        "2",
        "--depth",
        "6",
    ];
    let rs = records(
        &[
            &tree[..],
            &[
                "--strategy",
                "multipass-floor,multipass-host,multipass-floor",
            ],
        ]
        .concat(),
    );
    let names: Vec<&str> = rs.iter().map(|r| r["strategy"].as_str().unwrap()).collect();
    assert_eq!(
        names,
        [
            "multipass-floor",
            "multipass-floor",
            "multipass-host",
            "multipass-host"
        ]
    );
    for r in &rs {
        assert_eq!(r["verified"], true, "{r}");
    }
    for r in &rs[..2] {
        assert_eq!(r["rounds"], 1, "{r}");
        assert_eq!(r["launches"], 2, "branch and leaf: {r}");
    }
    assert!(rs[2]["rounds"].as_u64().unwrap() > 1, "{}", rs[2]);
    for r in records(&[
        "--workload",
        "bfs",
        "--scale",
        "8",
        "--strategy",
        "multipass-floor",
    ]) {
        assert_eq!(r["verified"], true, "{r}");
        assert_eq!(r["rounds"], 1, "{r}");
    }
    assert_exits_2(
        &["--strategy", "nope"],
        "multipass-host, cpu, multipass-floor)",
    );
}

/// One timed megakernel run of a tree (the command line's tree options follow).
const ONE_MEGAKERNEL_TREE: [&str; 6] = [
    "--workload",
    "tree",
    "--strategy",
    "megakernel",
    "--runs",
    "1",
];

/// The first JSON record of `schedbench --workload tree --strategy megakernel --runs 1 --json
/// ARGS`, which must exit 0 with a verified run.
fn first_json_record(args: &[&str]) -> serde_json::Value {
    let r = json_records(&[&ONE_MEGAKERNEL_TREE[..], args].concat()).remove(0);
    assert_eq!(r["verified"], true, "{r}");
    r
}

/// The records of `schedbench ARGS --json`, which must exit 0, one per line of its output.
fn json_records(args: &[&str]) -> Vec<serde_json::Value> {
    let out = Command::new(env!("CARGO_BIN_EXE_schedbench"))
        .args(args)
        .arg("--json")
        .output()
        .expect("schedbench runs");
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{args:?}: {err}");
    let stdout = String::from_utf8_lossy(&out.stdout);
    let records: Vec<serde_json::Value> = stdout
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert!(!records.is_empty(), "{args:?}: no records: {err}");
    records
}

/// `schedbench --strategy cpu ARGS` exits 2 (a usage error) with `expected` in its message.
fn assert_usage_error(args: &[&str], expected: &str) {
    assert_exits_2(&[&["--strategy", "cpu"][..], args].concat(), expected);
}

/// `schedbench ARGS` exits 2 (a usage error) with `expected` in its message.
fn assert_exits_2(args: &[&str], expected: &str) {
    let out = Command::new(env!("CARGO_BIN_EXE_schedbench"))
        .args(args)
        .output()
        .expect("schedbench runs");
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
    assert!(err.contains(expected), "{args:?}: {err}");
}

/// A scene file that cannot be read is an input error, not a usage error: exit 1, the file
/// named once.
#[test]
fn an_unreadable_scene_names_its_file_once_and_exits_1() {
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("absent.rib");
    reyes_scene_error(missing.to_str().unwrap(), None, &missing);
}

/// The shared Killeroo missing where `REYES_SHARED_DATA` points: exit 1, the path named once,
/// and the variable named as the way to point at the data.
#[test]
fn a_missing_shared_scene_names_the_variable_that_finds_it() {
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("rib/killeroo.rib");
    let err = reyes_scene_error("killeroo", Some(dir.path()), &missing);
    assert!(err.contains("REYES_SHARED_DATA"), "{err}");
}

/// `schedbench --workload reyes --strategy cpu --scene SCENE` (with `REYES_SHARED_DATA` set to
/// `data` if given) exits 1 and names `missing` once; returns its error output.
fn reyes_scene_error(
    scene: &str,
    data: Option<&std::path::Path>,
    missing: &std::path::Path,
) -> String {
    let mut c = Command::new(env!("CARGO_BIN_EXE_schedbench"));
    c.args(["--workload", "reyes", "--strategy", "cpu", "--scene", scene]);
    if let Some(d) = data {
        c.env("REYES_SHARED_DATA", d);
    }
    let out = c.output().expect("schedbench runs");
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    assert_eq!(out.status.code(), Some(1), "{err}");
    let name = missing.display().to_string();
    assert_eq!(err.matches(&name).count(), 1, "{err}");
    err
}

/// The device-driven records say whether wgpu's indirect-call validation was on: off by
/// default, on with `WGPU_VALIDATION_INDIRECT_CALL=1`; other strategies' records leave it out.
#[test]
fn device_driven_records_say_whether_indirect_calls_were_validated() {
    let record = |strategy: &str, env: Option<&str>| {
        let mut c = Command::new(env!("CARGO_BIN_EXE_schedbench"));
        c.args(["--workload", "tree", "--roots", "2", "--depth", "6"])
            .args(["--strategy", strategy, "--runs", "1", "--json"])
            .env_remove("WGPU_VALIDATION_INDIRECT_CALL");
        if let Some(v) = env {
            c.env("WGPU_VALIDATION_INDIRECT_CALL", v);
        }
        let out = c.output().expect("schedbench runs");
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(0), "{strategy}: {err}");
        let stdout = String::from_utf8_lossy(&out.stdout);
        let r: serde_json::Value = serde_json::from_str(stdout.lines().next().unwrap()).unwrap();
        assert_eq!(r["verified"], true, "{r}");
        r["indirect_validation"].clone()
    };
    assert_eq!(record("multipass", None), serde_json::json!(false));
    assert_eq!(record("multipass", Some("1")), serde_json::json!(true));
    assert_eq!(record("multipass", Some("0")), serde_json::json!(false));
    assert_eq!(record("multipass-host", Some("1")), serde_json::Value::Null);
}

/// An option of one workload given to another is a usage error (exit 2) naming the option and
/// its workload, never silently ignored; `--preset` and `--scene`, which have defaults, count as
/// given when they name something else.
#[test]
fn another_workloads_option_is_a_usage_error() {
    for (args, expected) in [
        (
            &["--workload", "bfs", "--preset", "deep"][..],
            "--preset applies to --workload tree",
        ),
        (
            &["--workload", "tree", "--scene", "killeroo"],
            "--scene applies to --workload reyes",
        ),
        (
            &["--workload", "tree", "--scale", "12"],
            "--scale applies to --workload bfs",
        ),
    ] {
        assert_usage_error(args, expected);
    }
}

/// `SCHED_DUMP_WGSL` writes every module the scheduler compiles, whole: each dumped file is a
/// complete WGSL module that naga validates on its own (what `pipestats` is given).
#[test]
fn dumped_wgsl_modules_are_whole() {
    let dir = tempfile::tempdir().unwrap();
    let status = Command::new(env!("CARGO_BIN_EXE_schedbench"))
        .args([
            "--workload",
            "tree",
            "--roots",
            "4",
            "--depth",
            "4",
            "--runs",
            "1",
        ])
        .args(["--strategy", "megakernel", "--workgroups", "2"])
        .env(scheduler::gpu::DUMP_WGSL_ENV, dir.path())
        .status()
        .expect("schedbench runs");
    assert!(status.success(), "schedbench failed: {status}");
    let mut names = Vec::new();
    for entry in std::fs::read_dir(dir.path()).unwrap() {
        let path = entry.unwrap().path();
        let source = std::fs::read_to_string(&path).unwrap();
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        scheduler::wgsl::validate(&name, &source).unwrap_or_else(|e| panic!("{name}: {e}"));
        names.push(name);
    }
    assert!(
        names.iter().any(|n| n == "megakernel.wgsl"),
        "dumped: {names:?}"
    );
}

/// A reader that leaves early (`schedbench ... --json | head -1`) closes the pipe: the output
/// ends there, but the runs go on to their end and the exit status is theirs (0: every run
/// verified), not a panic's 101. 2,000 records are far more than a pipe's buffer holds, so
/// schedbench writes into the closed pipe.
#[test]
fn a_closed_pipe_ends_the_output_not_the_run() {
    let mut child = Command::new(env!("CARGO_BIN_EXE_schedbench"))
        .args(["--workload", "tree", "--strategy", "cpu", "--roots", "1"])
        .args(["--depth", "3", "--runs", "2000", "--json"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("schedbench runs");
    let mut first = String::new();
    let mut reader = BufReader::new(child.stdout.take().unwrap());
    reader.read_line(&mut first).unwrap();
    let r: Value = serde_json::from_str(&first).unwrap();
    assert_eq!(r["verified"], true, "{first}");
    drop(reader);
    let out = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{err}");
    assert!(!err.contains("panicked"), "{err}");
}

/// A write to standard output that fails for another reason than a closed pipe (a full disk:
/// Linux's `/dev/full`) loses output, so the run fails: exit 1 and one line naming standard
/// output, no panic.
#[test]
fn a_failed_write_to_standard_output_exits_1() {
    let full = std::fs::OpenOptions::new()
        .write(true)
        .open("/dev/full")
        .expect("/dev/full (Linux)");
    let out = Command::new(env!("CARGO_BIN_EXE_schedbench"))
        .args(["--workload", "tree", "--strategy", "cpu", "--roots", "1"])
        .args(["--depth", "3", "--runs", "3", "--json"])
        .stdout(full)
        .output()
        .expect("schedbench runs");
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert_eq!(err.matches("standard output").count(), 1, "{err}");
    assert!(!err.contains("panicked"), "{err}");
}
