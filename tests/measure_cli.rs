//! The `measure` command end to end: the built binary runs its `trees` suite, shrunk (`--size
//! small --runs 1`, the binary tree only), with the built `schedbench` beside it on the adapter
//! from the environment (lavapipe in CI), and prints a table whose rows are verified; usage
//! errors exit 2, a missing binary names itself. It checks results and files, never speed.

use std::process::{Command, Output, Stdio};

fn measure(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_measure"))
        .args(args)
        .output()
        .expect("measure runs")
}

#[test]
fn the_trees_suite_prints_a_verified_row_per_strategy() {
    let out = tempfile::tempdir().unwrap();
    let dir = out.path().to_str().unwrap();
    let o = measure(&[
        "trees", "--size", "small", "--runs", "1", "--only", "binary", "--out", dir,
    ]);
    let stdout = String::from_utf8_lossy(&o.stdout);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{}\n{stdout}\n{stderr}", o.status);
    let rows: Vec<Vec<&str>> = stdout
        .lines()
        .filter(|l| l.starts_with("trees "))
        .map(|l| l.split_whitespace().collect())
        .collect();
    let strategies: Vec<&str> = rows.iter().map(|r| r[2]).collect();
    for s in [
        "megakernel",
        "multipass",
        "multipass-host",
        "cpu",
        "megakernel-fifo",
    ] {
        assert!(strategies.contains(&s), "no {s} row in:\n{stdout}");
    }
    for r in &rows {
        assert_eq!(r[1], "binary", "{stdout}");
        // ... runs, verified (the last column without notes).
        assert_eq!(r.last(), Some(&"yes"), "{stdout}");
        assert_eq!(r[r.len() - 2], "1", "{stdout}");
    }
    assert!(stdout.starts_with("adapter: "), "{stdout}");
    let table = std::fs::read_to_string(out.path().join("table.md")).unwrap();
    assert!(table.contains("| trees | binary | megakernel |"), "{table}");
    let commands = std::fs::read_to_string(out.path().join("commands.txt")).unwrap();
    assert!(
        commands.contains("--workload tree --preset binary --roots 8 --depth 8"),
        "{commands}"
    );
}

#[test]
fn an_unknown_suite_is_a_usage_error() {
    let o = measure(&["sort"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("sort"));
    let o = measure(&["suite", "--size", "small"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("--out"));
}

#[test]
fn a_missing_binary_is_named() {
    let empty = tempfile::tempdir().unwrap();
    let o = measure(&["trees", "--bin", empty.path().to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(1));
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(e.contains("no `schedbench` in"), "{e}");
}

/// A reader that left before the table came (`measure ... | head -0`, the pipe closed) ends
/// the output only: the status is the runs' (0, every row verified) and `--out` has the table.
#[test]
fn a_closed_pipe_keeps_the_runs_status_and_files() {
    let out = tempfile::tempdir().unwrap();
    let mut child = Command::new(env!("CARGO_BIN_EXE_measure"))
        .args([
            "trees", "--size", "small", "--runs", "1", "--only", "binary",
        ])
        .arg("--out")
        .arg(out.path())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("measure runs");
    drop(child.stdout.take());
    let o = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(0), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    let table = std::fs::read_to_string(out.path().join("table.md")).unwrap();
    assert!(table.contains("| trees | binary | megakernel |"), "{table}");
}
