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
        // Bounds both render paths share (the CPU twin used to run for minutes, or to
        // allocate tens of GiB).
        (
            &["--cpu", "--mp-size", "1e-30"][..],
            "micropolygon size 1e-30 px is not supported",
        ),
        (&["--mp-size", "1e-30"][..], "micropolygon size 1e-30 px"),
        (
            &["--cpu", "--width", "16384", "--height", "16384"][..],
            "needs 4294967296 bytes of RGBA",
        ),
        (&["--cpu", "--bound-px", "0.01"][..], "screen bound 0.01 px"),
        (
            &["--frames", "3-2"][..],
            "--frames: the range `3-2` is empty",
        ),
        (
            &["--frames", "2"][..],
            "--frames selects none of the file's frames (1)",
        ),
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

fn field(name: &str) -> String {
    let p = reyes::shared_data_dir().join("field").join(name);
    assert!(p.is_file(), "{} is missing", p.display());
    p.to_str().unwrap().to_string()
}

fn png(p: &Path) -> image::RgbaImage {
    image::open(p)
        .unwrap_or_else(|e| panic!("{}: {e}", p.display()))
        .to_rgba8()
}

fn covered(img: &image::RgbaImage) -> usize {
    img.pixels().filter(|p| p[3] > 0).count()
}

/// `three-frames.rib`: each frame writes the file its Display names, into -o's folder; or
/// the names a `####` pattern gives; `--frames` selects. CPU twin: no GPU needed.
#[test]
fn frame_sequences_write_one_image_per_frame() {
    let scene = field("three-frames.rib");
    let dir = scratch("frames");
    std::fs::create_dir_all(dir.join("out")).unwrap();
    let (ok, err) = reyes(&dir, &[&scene, "--cpu", "-o", "out/ignored.png"]);
    assert!(ok, "{err}");
    let imgs: Vec<_> = (1..=3)
        .map(|n| png(&dir.join(format!("out/teapot.000{n}.png"))))
        .collect();
    assert!(!dir.join("out/ignored.png").exists());
    for img in &imgs {
        assert_eq!(img.dimensions(), (320, 200));
        assert!(covered(img) > 5_000, "{}", covered(img));
    }
    // The teapot turns between frames.
    assert!(imgs[0] != imgs[1] && imgs[1] != imgs[2]);
    // A pattern and a selection.
    let (ok, err) = reyes(
        &dir,
        &[&scene, "--cpu", "-o", "f.####.png", "--frames", "1,3"],
    );
    assert!(ok, "{err}");
    assert!(png(&dir.join("f.0001.png")) == imgs[0]);
    assert!(png(&dir.join("f.0003.png")) == imgs[2]);
    assert!(!dir.join("f.0002.png").exists());
    let (ok, err) = reyes(
        &dir,
        &[&scene, "--cpu", "-o", "g.##.png", "--frames", "2-3"],
    );
    assert!(
        ok && dir.join("g.02.png").exists() && dir.join("g.03.png").exists(),
        "{err}"
    );
    // Several frames need a pattern for --stats; a missing folder fails before rendering.
    for (args, expected) in [
        (
            &["--stats", "s.json"][..],
            "--stats: several frames are rendered",
        ),
        (
            &["-o", "nowhere/x.png"][..],
            "the folder nowhere does not exist",
        ),
    ] {
        let mut all = vec![scene.as_str(), "--cpu", "--frames", "1-2"];
        all.extend_from_slice(args);
        let (ok, err) = reyes(&dir, &all);
        assert!(!ok && err.contains(expected), "{args:?}: {err}");
    }
    assert!(!dir.join("s.json").exists() && !dir.join("teapot.0001.png").exists());
}

/// A shadow-map frame is skipped with a warning; the others render.
#[test]
fn shadow_pass_frames_are_skipped_with_a_warning() {
    let dir = scratch("shadow");
    let patch = "Patch \"bilinear\" \"P\" [-1 -1 5  1 -1 5  -1 1 5  1 1 5]";
    std::fs::write(
        dir.join("s.rib"),
        format!(
            "Format 32 24 1\nFrameBegin 1\nDisplay \"map.z\" \"zfile\" \"z\"\n\
             WorldBegin\n{patch}\nWorldEnd\nFrameEnd\n\
             FrameBegin 2\nDisplay \"beauty.0002.tif\" \"file\" \"rgba\"\n\
             WorldBegin\n{patch}\nWorldEnd\nFrameEnd\n"
        ),
    )
    .unwrap();
    let (ok, err) = reyes(&dir, &["s.rib", "--cpu"]);
    assert!(ok, "{err}");
    assert!(
        err.contains("warning: skipped frame 1: a depth-map pass (`Display` type \"zfile\")"),
        "{err}"
    );
    assert!(covered(&png(&dir.join("beauty.0002.png"))) > 0);
    assert!(!dir.join("map.png").exists() && !dir.join("map.z").exists());
}

/// `read-archive.rib` reads the teapot from the gzip archive beside it: the same image as the
/// same file with the archive's text written in place of the request.
#[test]
fn read_archive_renders_as_if_the_archive_were_inline() {
    let scene = field("read-archive.rib");
    let dir = scratch("archive");
    let (ok, err) = reyes(&dir, &[&scene, "--cpu", "-o", "archive.png"]);
    assert!(ok, "{err}");
    assert!(!err.contains("warning"), "{err}");
    let mut inner = String::new();
    std::io::Read::read_to_string(
        &mut flate2::read::GzDecoder::new(
            std::fs::File::open(field("teapot-patches.rib.gz")).unwrap(),
        ),
        &mut inner,
    )
    .unwrap();
    let text = std::fs::read_to_string(&scene)
        .unwrap()
        .replace("ReadArchive \"teapot-patches.rib.gz\"", &inner);
    std::fs::write(dir.join("inline.rib"), text).unwrap();
    let (ok, err) = reyes(&dir, &["inline.rib", "--cpu", "-o", "inline.png"]);
    assert!(ok, "{err}");
    let (a, b) = (png(&dir.join("archive.png")), png(&dir.join("inline.png")));
    assert!(covered(&a) > 5_000, "{}", covered(&a));
    assert!(
        a == b,
        "the archive renders differently from the inline text"
    );
}

/// The hostile field files: a clear error naming the file and line, exit 1, nothing written;
/// or, for the huge token, a warning that quotes a bounded prefix.
#[test]
fn hostile_files_fail_clearly_and_write_nothing() {
    let dir = scratch("hostile");
    let deep = dir.join("deep.rib");
    std::fs::write(
        &deep,
        format!("WorldBegin\n{}", "AttributeBegin\n".repeat(200_000)),
    )
    .unwrap();
    let deep = deep.to_str().unwrap().to_string();
    for (scene, expected) in [
        (
            field("hostile/f32-overflow.rib"),
            "f32-overflow.rib:4: `Patch`: patch 0: control point 0 is [-1e200, -1e200, 5] in \
             camera space, beyond the f32 range",
        ),
        (
            field("hostile/pixelsamples-17.rib"),
            "pixelsamples-17.rib:1: `PixelSamples`: sample count 17 is not in (0, 16]",
        ),
        (
            deep,
            "deep.rib:1025: `AttributeBegin`: blocks nested deeper than 1024",
        ),
    ] {
        for way in [&["--cpu"][..], &[]] {
            let mut args = vec![scene.as_str(), "-o", "out.png", "--stats", "s.json"];
            args.extend_from_slice(way);
            let (ok, err) = reyes(&dir, &args);
            assert!(!ok, "{scene}: succeeded");
            assert!(
                err.contains(expected),
                "{scene}: expected `{expected}` in:\n{err}"
            );
            assert!(!dir.join("out.png").exists() && !dir.join("s.json").exists());
        }
    }
    let (ok, err) = reyes(
        &dir,
        &[&field("hostile/huge-token.rib"), "--cpu", "-o", "h.png"],
    );
    assert!(ok, "{err}");
    assert!(err.len() < 1000, "{} bytes of stderr", err.len());
    assert!(err.contains("… (100001 bytes)`"), "{err}");
}
