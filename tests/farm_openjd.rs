//! `farm/openjd/render.yaml` and `render-chunked.yaml` run by Open Job Description's reference
//! runner (`openjd run`, from PyPI's `openjd-cli`): a job of three frames writes the images
//! that one `reyes render --frames 1-3` writes; with frame 2 broken the job fails at that task
//! (the runner stops a session at its first failed task), and the job run again renders only
//! the missing frames; the chunked template renders two frames in one task.
//!
//! `openjd` is found on PATH, or as the environment's `OPENJD`; `./run-tests` installs it
//! (scripts/ensure-openjd.sh). A missing runner is a failure, never a skip.

mod cli;
mod farm;

use farm::{
    assert_frames_match, files_named_with, mtime, reference_images, repo_root, reyes_bin,
    run_bounded, text, write_shot,
};
use std::path::Path;
use std::process::{Command, Output};
use std::time::Duration;

/// `openjd run farm/openjd/TEMPLATE` with the shot of `work`, the CPU twin and `params` more.
fn openjd_run(work: &Path, template: &str, out: &str, params: &[&str]) -> Output {
    let openjd = std::env::var("OPENJD").unwrap_or_else(|_| "openjd".into());
    let mut cmd = Command::new(&openjd);
    cmd.arg("run")
        .arg(repo_root().join("farm/openjd").join(template))
        .arg("-p")
        .arg(format!("SceneFile={}", work.join("shot.rib").display()))
        .arg("-p")
        .arg(format!("OutputPattern={}", work.join(out).display()))
        .args(["-p", "Frames=1-3", "-p", "Device=cpu"])
        .arg("-p")
        .arg(format!("ReyesCommand={}", reyes_bin()));
    for p in params {
        cmd.args(["-p", p]);
    }
    cmd.current_dir(work).env("XDG_RUNTIME_DIR", work);
    run_bounded(
        &format!("{openjd} run {template} (scripts/ensure-openjd.sh installs openjd-cli)"),
        &mut cmd,
        Duration::from_secs(180),
        &String::new,
    )
}

#[test]
fn a_job_renders_the_frames_and_a_rerun_only_the_missing_ones() {
    let tmp = tempfile::Builder::new()
        .prefix("farm-openjd")
        .tempdir()
        .unwrap();
    let work = tmp.path();
    let out = work.join("out");
    std::fs::create_dir_all(&out).unwrap();
    let shot = write_shot(work, false);
    let refs = reference_images(work, &shot);

    // One task per frame: the images of one `reyes render --frames 1-3`.
    let run = openjd_run(work, "render.yaml", "out/shot.%04d.png", &[]);
    let log = text(&run);
    assert!(run.status.success(), "{log}");
    assert!(log.contains("Chunks run: 3"), "{log}");
    assert_frames_match(&out, "shot", &[1, 2, 3], &refs);

    // Frame 2 broken: its task fails naming the frame and line, and leaves no file; frame 1
    // is written, and the runner stops the session there (frame 3 is not run).
    for n in 1..=3 {
        std::fs::remove_file(out.join(format!("shot.{n:04}.png"))).unwrap();
    }
    write_shot(work, true);
    let run = openjd_run(work, "render.yaml", "out/shot.%04d.png", &[]);
    let log = text(&run);
    assert!(!run.status.success(), "{log}");
    assert!(
        log.contains("reyes render: frame 2: ") && log.contains("shot.rib:"),
        "{log}"
    );
    assert!(log.contains("exited with code: 1 "), "{log}");
    assert_frames_match(&out, "shot", &[1], &refs);
    assert!(files_named_with(&out, "0002").is_empty(), "{log}");
    assert!(files_named_with(&out, "0003").is_empty(), "{log}");
    let t1 = mtime(&out.join("shot.0001.png"));

    // Fixed and run again as it was: frame 1 is skipped, 2 and 3 render.
    write_shot(work, false);
    let run = openjd_run(work, "render.yaml", "out/shot.%04d.png", &[]);
    let log = text(&run);
    assert!(run.status.success(), "{log}");
    assert!(log.contains("frame 1: skipped,"), "{log}");
    assert_eq!(log.matches("wrote ").count(), 2, "{log}");
    assert_eq!(mtime(&out.join("shot.0001.png")), t1);
    assert_frames_match(&out, "shot", &[1, 2, 3], &refs);
    let hidden: Vec<String> = files_named_with(&out, "")
        .into_iter()
        .filter(|n| n.starts_with('.'))
        .collect();
    assert!(hidden.is_empty(), "temporary files left: {hidden:?}");

    // Chunks of two frames (TASK_CHUNKING): two tasks, 1-2 and 3-3.
    let run = openjd_run(
        work,
        "render-chunked.yaml",
        "out/chunk.%04d.png",
        &["ChunkSize=2"],
    );
    let log = text(&run);
    assert!(run.status.success(), "{log}");
    assert!(
        log.contains("Frame(CHUNK[INT]) = 1-2") && log.contains("Chunks run: 2"),
        "{log}"
    );
    assert_frames_match(&out, "chunk", &[1, 2, 3], &refs);
}
