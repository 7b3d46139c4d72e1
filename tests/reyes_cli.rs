//! The `reyes` command on bad input: a clear error naming the file and line (or patch), a
//! failing exit status, and no output file left behind. No GPU is needed: these fail first.

use std::path::{Path, PathBuf};
use std::process::Command;

fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("reyes-cli-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Runs `reyes render ARGS` in `dir`; returns (success, stderr).
fn reyes(dir: &Path, args: &[&str]) -> (bool, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_reyes"))
        .arg("render")
        .args(args)
        .current_dir(dir)
        .env("XDG_RUNTIME_DIR", std::env::temp_dir())
        .output()
        .unwrap();
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

fn patch(points: &[&str]) -> String {
    format!(
        "WorldBegin\nPatch \"bicubic\" \"P\" [ {} ]\nWorldEnd\n",
        points.join("  ")
    )
}

#[test]
fn bad_scene_files_name_the_file_and_line_and_write_nothing() {
    let dir = scratch("bad");
    let mut points = vec!["0 0 5"; 16];
    let cases: Vec<(&str, String, &str)> = vec![
        (
            "truncated.rib",
            "WorldBegin\nPatch \"bicubic\" \"P\" [ 0 0 0  1 0 0\n".into(),
            "truncated.rib:2: unexpected end of file",
        ),
        (
            "count.rib",
            patch(&points[..15]),
            "count.rib:2: `Patch`: \"P\" needs 48 numbers (16 points), found 45",
        ),
        (
            "word.rib",
            {
                points[15] = "abc 0 5";
                patch(&points)
            },
            "word.rib:2: unexpected `abc`",
        ),
        (
            "nan.rib",
            {
                points[15] = "nan 0 5";
                patch(&points)
            },
            "nan.rib:2: `Patch`: patch 0: point 15 of \"P\" is NaN",
        ),
        (
            "inf.rib",
            {
                points[15] = "1e999 0 5";
                format!("\n{}", patch(&points))
            },
            "inf.rib:3: `Patch`: patch 0: point 15 of \"P\" is infinite",
        ),
    ];
    for (name, text, expected) in cases {
        std::fs::write(dir.join(name), text).unwrap();
        let (ok, err) = reyes(&dir, &[name, "-o", "out.png", "--stats", "out.json"]);
        assert!(!ok, "{name}: succeeded");
        assert!(
            err.contains(expected),
            "{name}: expected `{expected}` in:\n{err}"
        );
        assert!(!dir.join("out.png").exists() && !dir.join("out.json").exists());
    }
    let (ok, err) = reyes(&dir, &["missing.rib"]);
    assert!(
        !ok && err.contains("missing.rib") && err.contains("cannot read"),
        "{err}"
    );
}

#[test]
fn bad_options_are_clear_errors() {
    let dir = scratch("options");
    for (args, expected) in [
        (&["--width", "0"][..], "image size 0x"),
        (
            &["--width", "wide"][..],
            "--width: `wide` is not a valid number",
        ),
        (&["--memory-budget", "lots"][..], "--memory-budget: `lots`"),
        (&["--samples", "0"][..], "pixel samples 0x0"),
        (&["--strategy", "magic"][..], "unknown strategy `magic`"),
        (&["--frobnicate"][..], "unknown option `--frobnicate`"),
    ] {
        let (ok, err) = reyes(&dir, args);
        assert!(!ok, "{args:?} succeeded");
        assert!(
            err.contains(expected),
            "{args:?}: expected `{expected}` in:\n{err}"
        );
    }
    assert!(!dir.join("teapot.png").exists());
}

/// The field input `empty-world.rib` (a world with nothing drawable): every way of rendering it
/// writes an image of the requested size with alpha 0, warns that nothing was drawn, and exits
/// 0. It used to panic in wgpu's validation on both GPU strategies. Needs the GPU (lavapipe).
#[test]
fn an_empty_world_renders_an_empty_image_with_a_warning() {
    let scene = reyes::shared_data_dir().join("field/empty-world.rib");
    assert!(scene.is_file(), "{} is missing", scene.display());
    let dir = scratch("empty");
    let scene = scene.to_str().unwrap();
    for way in [
        &["--strategy", "megakernel"][..],
        &["--strategy", "multipass"],
        &["--memory-budget", "64K"],
        &["--cpu"],
    ] {
        let out = dir.join("empty.png");
        let _ = std::fs::remove_file(&out);
        let mut args = vec![scene, "-o", "empty.png"];
        args.extend_from_slice(way);
        let (ok, err) = reyes(&dir, &args);
        assert!(ok, "{way:?}: {err}");
        assert!(err.contains("nothing was drawn"), "{way:?}: {err}");
        let img = image::open(&out).unwrap().to_rgba8();
        assert_eq!(img.dimensions(), (320, 240), "{way:?}");
        assert!(img.pixels().all(|p| p[3] == 0), "{way:?}: not transparent");
    }
}
