//! What the farm tests share (`farm_slurm.rs`, `farm_openjd.rs`): the three-frame shot they
//! submit (the field scene `three-frames.rib`, and a copy whose frame 2 is broken), its
//! reference images from one `reyes render --frames 1-3` process, bounded runs of outside
//! commands, and the checks on what a farm run wrote.
//!
//! Every render uses the CPU twin (`--cpu`): the farm tests check how frames are handed out
//! and resubmitted, not the GPU, and the twin renders a 320x200 teapot frame in a fraction of a
//! second where lavapipe takes seconds.

#![allow(dead_code)] // each test binary uses its own subset

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

pub use crate::cli::{mtime, png};
use std::time::{Duration, Instant};

/// The repository's root (the job script and template are found from it).
pub fn repo_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .canonicalize()
        .unwrap()
}

/// The `reyes` binary Cargo built for this test.
pub fn reyes_bin() -> &'static str {
    env!("CARGO_BIN_EXE_reyes")
}

/// The three-frame turntable of the field scenes (a `Display` per frame, 320x200).
fn field_shot() -> PathBuf {
    let p = reyes::shared_data_dir()
        .join("field")
        .join("three-frames.rib");
    assert!(p.is_file(), "{} is missing", p.display());
    p
}

/// Writes the shot to `dir/shot.rib`: the field scene as it is, or with frame 2 broken (a
/// bilinear patch of one point after its `WorldBegin`, an error the reader names with its line).
pub fn write_shot(dir: &Path, broken_frame_2: bool) -> PathBuf {
    let mut text = std::fs::read_to_string(field_shot()).unwrap();
    if broken_frame_2 {
        let frame2 = text
            .find("FrameBegin 2")
            .expect("three-frames.rib has a frame 2");
        let world = frame2 + text[frame2..].find("WorldBegin\n").unwrap() + "WorldBegin\n".len();
        text.insert_str(world, "Patch \"bilinear\" \"P\" [0 0 5]\n");
    }
    let p = dir.join("shot.rib");
    std::fs::write(&p, text).unwrap();
    p
}

/// Runs `cmd` for at most `limit`; the output, or a panic naming `what` when it runs over (it
/// is killed) or cannot start. `context` is called for more to print on a panic (daemon logs).
pub fn run_bounded(
    what: &str,
    cmd: &mut Command,
    limit: Duration,
    context: &dyn Fn() -> String,
) -> Output {
    let mut child = cmd
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap_or_else(|e| panic!("{what}: cannot start: {e}\n{}", context()));
    let start = Instant::now();
    loop {
        if child.try_wait().unwrap().is_some() {
            return child.wait_with_output().unwrap();
        }
        if start.elapsed() > limit {
            child.kill().ok();
            let out = child.wait_with_output().unwrap();
            panic!(
                "{what}: still running after {} s, killed\nstdout: {}\nstderr: {}\n{}",
                limit.as_secs(),
                String::from_utf8_lossy(&out.stdout),
                String::from_utf8_lossy(&out.stderr),
                context()
            );
        }
        std::thread::sleep(Duration::from_millis(100));
    }
}

/// stdout and stderr of `out`, for messages.
pub fn text(out: &Output) -> String {
    format!(
        "exit {:?}\nstdout: {}\nstderr: {}",
        out.status.code(),
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    )
}

/// Renders the shot's three frames in one process into `dir/ref.0001.png` ..; the images the
/// farm runs must reproduce.
pub fn reference_images(dir: &Path, shot: &Path) -> Vec<image::RgbaImage> {
    let out = run_bounded(
        "reyes render --frames 1-3",
        Command::new(reyes_bin())
            .args(["render", "--cpu", "--frames", "1-3", "-o", "ref.%04d.png"])
            .arg(shot)
            .current_dir(dir)
            .env("XDG_RUNTIME_DIR", dir),
        Duration::from_secs(120),
        &String::new,
    );
    assert!(out.status.success(), "{}", text(&out));
    (1..=3)
        .map(|n| png(&dir.join(format!("ref.{n:04}.png"))))
        .collect()
}

/// Asserts that `dir/PREFIX.000N.png` holds exactly the reference image N for N in `frames`
/// (the same binary and the CPU twin: bit-identical pixels, no tolerance).
pub fn assert_frames_match(dir: &Path, prefix: &str, frames: &[u32], refs: &[image::RgbaImage]) {
    for &n in frames {
        let p = dir.join(format!("{prefix}.{n:04}.png"));
        assert!(p.is_file(), "{} was not written", p.display());
        assert!(
            png(&p) == refs[n as usize - 1],
            "{} differs from frame {n} of `reyes render --frames 1-3`",
            p.display()
        );
    }
}

/// The names of the files in `dir` that hold `needle` (leftovers of a failed frame: its image
/// or a temporary file).
pub fn files_named_with(dir: &Path, needle: &str) -> Vec<String> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.contains(needle))
        .collect()
}
