//! `farm/slurm/render.sbatch` on a real one-node Slurm cluster (munged, slurmctld and slurmd
//! on this machine, started by `farm/slurm/local-cluster.sh` in a temporary folder): a job
//! array of three frames writes the images that one `reyes render --frames 1-3` writes; with
//! frame 2 broken the array fails on that task alone, and the resubmitted array renders only
//! frame 2; a chunked array (`--array=1-3:2`) renders two frames in one task.
//!
//! Needs root and Debian's `slurmd`, `slurmctld`, `slurm-client` and `munge` (`./run-tests`
//! installs them: scripts/ensure-slurm.sh). A cluster that does not start is a failure that
//! prints the daemons' logs, never a skip. The daemons are stopped when the test ends, passed
//! or failed.

mod cli;
mod farm;

use farm::{
    assert_frames_match, mtime, reference_images, repo_root, reyes_bin, run_bounded, text,
    write_shot,
};
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Duration;

/// A running one-node cluster; dropping it stops the daemons.
struct Cluster {
    dir: PathBuf,
    script: PathBuf,
}

impl Cluster {
    /// Starts the daemons in `dir`; a panic with the reason and their logs when they do not
    /// come up.
    fn start(dir: &Path) -> Cluster {
        let script = repo_root().join("farm/slurm/local-cluster.sh");
        let cluster = Cluster {
            dir: dir.to_path_buf(),
            script,
        };
        let out = run_bounded(
            "local-cluster.sh start",
            Command::new("bash")
                .arg(&cluster.script)
                .arg("start")
                .arg(dir),
            Duration::from_secs(90),
            &|| cluster.logs(),
        );
        assert!(
            out.status.success(),
            "the Slurm cluster did not start:\n{}",
            text(&out)
        );
        cluster
    }

    fn conf(&self) -> PathBuf {
        self.dir.join("slurm.conf")
    }

    /// The tails of the daemons' logs and the queue, for failure messages.
    fn logs(&self) -> String {
        let mut s = String::new();
        for name in ["munged.log", "slurmctld.log", "slurmd.log"] {
            let text = std::fs::read_to_string(self.dir.join(name)).unwrap_or_default();
            let lines: Vec<&str> = text.lines().collect();
            s += &format!("---- {name}\n");
            for l in &lines[lines.len().saturating_sub(30)..] {
                s += l;
                s.push('\n');
            }
        }
        if let Ok(out) = Command::new("squeue")
            .arg("--all")
            .env("SLURM_CONF", self.conf())
            .output()
        {
            s += &format!("---- squeue\n{}", String::from_utf8_lossy(&out.stdout));
        }
        s
    }

    /// `sbatch --wait ARGS farm/slurm/render.sbatch shot.rib OUT --cpu` in `work`: the job id
    /// and whether every task exited 0 (sbatch --wait exits with the highest task status).
    fn render(&self, work: &Path, array: &str, out: &str) -> (u32, Option<i32>) {
        let sbatch = repo_root().join("farm/slurm/render.sbatch");
        let run = run_bounded(
            "sbatch --wait",
            Command::new("sbatch")
                .args(["--wait", "--time=5", &format!("--array={array}")])
                .arg(&sbatch)
                .args(["shot.rib", out, "--cpu"])
                .current_dir(work)
                .env("SLURM_CONF", self.conf())
                .env("REYES", reyes_bin())
                .env("XDG_RUNTIME_DIR", work),
            Duration::from_secs(180),
            &|| self.logs(),
        );
        let stdout = String::from_utf8_lossy(&run.stdout);
        let job = stdout
            .split_whitespace()
            .last()
            .and_then(|w| w.parse().ok())
            .unwrap_or_else(|| panic!("no job id from sbatch: {}\n{}", text(&run), self.logs()));
        (job, run.status.code())
    }
}

impl Drop for Cluster {
    fn drop(&mut self) {
        let _ = Command::new("bash")
            .arg(&self.script)
            .arg("stop")
            .arg(&self.dir)
            .status();
    }
}

/// The log of array task `task` of `job` (render.sbatch's `%x-%A_%a.log`).
fn task_log(work: &Path, job: u32, task: u32) -> String {
    let p = work.join(format!("reyes-render-{job}_{task}.log"));
    std::fs::read_to_string(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

#[test]
fn a_job_array_renders_the_frames_and_a_resubmission_only_the_missing_ones() {
    let tmp = tempfile::Builder::new()
        .prefix("farm-slurm")
        .tempdir()
        .unwrap();
    let work = tmp.path().join("work");
    std::fs::create_dir_all(work.join("out")).unwrap();
    let cluster = Cluster::start(&tmp.path().join("cluster"));
    let shot = write_shot(&work, false);
    let refs = reference_images(&work, &shot);

    // One frame per task: the images of one `reyes render --frames 1-3`, a log per task.
    let (job, code) = cluster.render(&work, "1-3", "out/shot.%04d.png");
    assert_eq!(code, Some(0), "job {job}\n{}", cluster.logs());
    assert_frames_match(&work.join("out"), "shot", &[1, 2, 3], &refs);
    for task in 1..=3 {
        let log = task_log(&work, job, task);
        assert!(
            log.contains(&format!("frames {task}-{task} of shot.rib"))
                && log.contains(&format!("wrote out/shot.{task:04}.png")),
            "task {task}: {log}"
        );
    }

    // Frame 2 broken: its task fails alone (exit 1, naming the frame and line, no file for
    // it); tasks 1 and 3 write their frames.
    for n in 1..=3 {
        std::fs::remove_file(work.join(format!("out/shot.{n:04}.png"))).unwrap();
    }
    write_shot(&work, true);
    let (job, code) = cluster.render(&work, "1-3", "out/shot.%04d.png");
    assert_eq!(code, Some(1), "job {job}\n{}", cluster.logs());
    let log2 = task_log(&work, job, 2);
    assert!(
        log2.contains("frame 2: shot.rib:") && log2.contains("frame 2 failed"),
        "{log2}"
    );
    let out = work.join("out");
    // Nothing of frame 2, not even a temporary file.
    let mut written: Vec<String> = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    written.sort();
    assert_eq!(written, ["shot.0001.png", "shot.0003.png"], "{log2}");
    assert_frames_match(&out, "shot", &[1, 3], &refs);
    let before = [
        mtime(&out.join("shot.0001.png")),
        mtime(&out.join("shot.0003.png")),
    ];

    // Fixed and resubmitted as it was: tasks 1 and 3 skip their frames, task 2 renders.
    write_shot(&work, false);
    let (job, code) = cluster.render(&work, "1-3", "out/shot.%04d.png");
    assert_eq!(code, Some(0), "job {job}\n{}", cluster.logs());
    let logs: Vec<String> = (1..=3).map(|t| task_log(&work, job, t)).collect();
    let wrote: usize = logs.iter().map(|l| l.matches("wrote").count()).sum();
    assert_eq!(wrote, 1, "{logs:?}");
    for (t, l) in [(1, &logs[0]), (3, &logs[2])] {
        assert!(
            l.contains(&format!("frame {t}: skipped, out/shot.{t:04}.png exists")),
            "{l}"
        );
    }
    assert!(logs[1].contains("wrote out/shot.0002.png"), "{}", logs[1]);
    assert_eq!(mtime(&out.join("shot.0001.png")), before[0]);
    assert_eq!(mtime(&out.join("shot.0003.png")), before[1]);
    assert_frames_match(&out, "shot", &[1, 2, 3], &refs);

    // A chunk of two frames per task (the array's step): tasks 1 (frames 1-2) and 3 (3-4 of a
    // three-frame file: frame 3).
    let (job, code) = cluster.render(&work, "1-3:2", "out/chunk.%04d.png");
    assert_eq!(code, Some(0), "job {job}\n{}", cluster.logs());
    assert_frames_match(&out, "chunk", &[1, 2, 3], &refs);
    let log1 = task_log(&work, job, 1);
    assert!(
        log1.contains("frames 1-2") && log1.matches("wrote").count() == 2,
        "{log1}"
    );
    assert!(!work.join(format!("reyes-render-{job}_2.log")).exists());
    drop(cluster);
}
