//! The `reyes` command on bad input: a clear error naming the file and line (or patch), a
//! failing exit status (2 for usage errors, 1 for the others), and no output file left behind.
//! No GPU is needed: these fail first. Also its help and version.

mod cli;

use cli::{mtime, png, reyes_in as reyes_any};
use std::path::{Path, PathBuf};
use std::process::Command;

fn scratch(name: &str) -> PathBuf {
    cli::scratch("cli", name)
}

/// Runs `reyes render ARGS` in `dir`; returns (exit code, stderr).
fn render_code(dir: &Path, args: &[&str]) -> (i32, String) {
    let mut all = vec!["render"];
    all.extend_from_slice(args);
    let (code, _, err) = reyes_any(dir, &all);
    (code, err)
}

/// Runs `reyes render ARGS` in `dir`; returns (success, stderr).
fn reyes(dir: &Path, args: &[&str]) -> (bool, String) {
    let (code, err) = render_code(dir, args);
    (code == 0, err)
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
    // (arguments, expected in stderr, exit code): 2 for usage errors (clap names the flag),
    // 1 for what the renderer refuses.
    for (args, expected, code) in [
        (&["--width", "0"][..], "'--width <PX>'", 2),
        (
            &["--width", "wide"][..],
            "invalid value 'wide' for '--width <PX>'",
            2,
        ),
        (
            &["--memory-budget", "lots"][..],
            "--memory-budget: `lots`",
            2,
        ),
        (&["--samples", "0"][..], "'--samples <N|NxM>'", 2),
        (&["--strategy", "magic"][..], "unknown strategy `magic`", 2),
        (
            &["--frobnicate"][..],
            "unexpected argument '--frobnicate'",
            2,
        ),
        (&["--runs", "0"][..], "'--runs <N>'", 2),
        (&["--bound-px", "0"][..], "'--bound-px <PX>'", 2),
        (&["--mp-size", "inf"][..], "'--mp-size <PX>'", 2),
        // Bounds both render paths share (the CPU twin used to run for minutes, or to
        // allocate tens of GiB).
        (
            &["--cpu", "--mp-size", "1e-30"][..],
            "micropolygon size 1e-30 px is not supported",
            1,
        ),
        (&["--mp-size", "1e-30"][..], "micropolygon size 1e-30 px", 1),
        (
            &["--cpu", "--width", "16384", "--height", "16384"][..],
            "needs 4294967296 bytes of RGBA",
            1,
        ),
        (
            &["--cpu", "--bound-px", "0.01"][..],
            "screen bound 0.01 px",
            1,
        ),
        (
            &["--frames", "3-2"][..],
            "--frames: the range `3-2` is empty",
            2,
        ),
        (
            &["--frames", "2"][..],
            "--frames selects none of the scene's frames (1)",
            2,
        ),
    ] {
        let (got, err) = render_code(&dir, args);
        assert_eq!(got, code, "{args:?}: {err}");
        assert!(
            err.contains(expected),
            "{args:?}: expected `{expected}` in:\n{err}"
        );
    }
    assert!(!dir.join("teapot.png").exists());
}

/// What the CPU twin would ignore is refused, naming both flags; what it uses is taken.
#[test]
fn cpu_refuses_the_gpu_options() {
    let dir = scratch("cpu");
    for flag in [
        &["--runs", "5"][..],
        &["--strategy", "multipass"],
        &["--stage-times"],
        &["--stats", "s.json"],
        &["--float", "f.pfm"],
        &["--depth", "d.pfm"],
        &["--exr", "f.exr"],
    ] {
        let mut args = vec!["--cpu"];
        args.extend_from_slice(flag);
        let (code, err) = render_code(&dir, &args);
        assert_eq!(code, 2, "{args:?}: {err}");
        assert!(
            err.contains("'--cpu'") && err.contains(flag[0]),
            "{args:?}: {err}"
        );
    }
    assert!(!dir.join("teapot.png").exists() && !dir.join("s.json").exists());
    // measure and sweep time the GPU: no --cpu at all.
    for cmd in ["measure", "sweep"] {
        let (code, _, err) = reyes_any(&dir, &[cmd, "--cpu"]);
        assert_eq!(code, 2, "{cmd}: {err}");
        assert!(err.contains("'--cpu'"), "{cmd}: {err}");
    }
}

/// `--help` (top level and each subcommand) and `--version` print to stdout and exit 0; the
/// help shows defaults and units. Without a subcommand: the help on stderr, exit 2.
#[test]
fn help_and_version() {
    let dir = scratch("help");
    let (code, out, err) = reyes_any(&dir, &["--help"]);
    assert_eq!(code, 0, "{err}");
    for cmd in ["render", "measure", "holes", "sweep", "drift"] {
        assert!(out.contains(cmd), "{out}");
    }
    let (code, out, _) = reyes_any(&dir, &["--version"]);
    assert_eq!(code, 0);
    assert_eq!(out.trim(), format!("reyes {}", env!("CARGO_PKG_VERSION")));
    for (cmd, expected) in [
        ("render", "--memory-budget <BYTES[K|M|G]>"),
        ("render", "[default: 1]"),
        ("measure", "--ref-samples <N>"),
        ("render", "--raster <MODE>"),
        ("holes", "--reference <REF>"),
        ("sweep", "[default: 0.5,0.71,1,1.41,2,4]"),
        ("drift", "[default: 1920]"),
    ] {
        let (code, out, err) = reyes_any(&dir, &[cmd, "--help"]);
        assert_eq!(code, 0, "{cmd}: {err}");
        assert!(out.contains(expected), "{cmd}: `{expected}` not in:\n{out}");
    }
    let (code, out, err) = reyes_any(&dir, &[]);
    assert_eq!(code, 2);
    assert!(
        out.is_empty() && err.contains("Usage: reyes <COMMAND>"),
        "{err}"
    );
}

/// A bad value names its flag and exits 2, in every subcommand.
#[test]
fn bad_values_name_their_flag() {
    let dir = scratch("values");
    for args in [
        &["render", "--height", "-3"][..],
        &["render", "--width", "100000"],
        &["render", "--samples", "17"],
        &["bench", "--samples", "4x17"],
        &["measure", "--ref-samples", "65"],
        &["sweep", "--mp-sizes", "1,nan"],
        &["sweep", "--runs", "0"],
        &["drift", "--paths", "many"],
        &["render", "--raster", "round"],
        &["holes", "--reference", "guess"],
    ] {
        let (code, _, err) = reyes_any(&dir, args);
        assert_eq!(code, 2, "{args:?}: {err}");
        let flag = args.iter().find(|a| a.starts_with("--")).unwrap();
        assert!(err.contains(&format!("'{flag} <")), "{args:?}: {err}");
    }
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
        &["--gpu", "--memory-budget", "64K"],
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

/// On a CPU adapter (lavapipe) a plain `reyes render` renders with the CPU reference and says
/// why: the same image as `--cpu`, byte for byte; `--gpu` renders on the adapter (the
/// multi-pass, its default there). Needs the GPU (lavapipe, a CPU adapter).
#[test]
fn a_cpu_adapter_renders_with_the_cpu_reference_unless_told() {
    let dir = scratch("cpu-default");
    let size = ["--width", "64", "--height", "48"];
    let (ok, err) = reyes(&dir, &[&["-o", "default.png"][..], &size].concat());
    assert!(ok, "{err}");
    assert!(
        err.contains("note: rendering with the CPU reference"),
        "{err}"
    );
    assert!(err.contains("the adapter is a CPU"), "{err}");
    let (ok, err) = reyes(&dir, &[&["-o", "cpu.png", "--cpu"][..], &size].concat());
    assert!(ok, "{err}");
    assert_eq!(png(&dir.join("default.png")), png(&dir.join("cpu.png")));
    let (ok, err) = reyes(&dir, &[&["-o", "gpu.png", "--gpu"][..], &size].concat());
    assert!(ok, "{err}");
    assert!(!err.contains("CPU reference"), "{err}");
    assert!(
        err.contains("multipass:") && err.contains("micropolygons"),
        "{err}"
    );
    // GPU-only outputs choose the GPU without --gpu; --cpu and --gpu conflict.
    let (ok, err) = reyes(
        &dir,
        &[&["-o", "s.png", "--stats", "s.json"][..], &size].concat(),
    );
    assert!(ok, "{err}");
    assert!(
        !err.contains("CPU reference") && dir.join("s.json").is_file(),
        "{err}"
    );
    let (code, err) = render_code(&dir, &["--cpu", "--gpu"]);
    assert_eq!(code, 2, "{err}");
}

/// `reyes holes --json`: the teapot at 2 px micropolygons in nearest mode has holes against
/// the exact coverage and against a bbox render alike; in bbox mode it has none. Needs the GPU
/// (lavapipe).
#[test]
fn holes_reports_what_nearest_mode_leaves_empty() {
    let dir = scratch("holes");
    let run = |extra: &[&str]| -> serde_json::Value {
        let mut args = vec![
            "holes",
            "teapot",
            "--width",
            "64",
            "--height",
            "48",
            "--mp-size",
            "2",
            "--strategy",
            "multipass",
            "--ref-samples",
            "2",
            "--json",
        ];
        args.extend_from_slice(extra);
        let (code, out, err) = reyes_any(&dir, &args);
        assert_eq!(code, 0, "{extra:?}: {err}");
        serde_json::from_str(out.trim()).unwrap_or_else(|e| panic!("{extra:?}: {e}: {out}"))
    };
    let bbox = run(&["--raster", "bbox"]);
    assert_eq!(bbox["raster"], "bbox");
    assert!(bbox["interior_px"].as_u64().unwrap() > 300, "{bbox}");
    assert_eq!(bbox["hole_px"], 0, "{bbox}");
    for reference in ["exact", "bbox"] {
        let v = run(&["--raster", "nearest", "--reference", reference]);
        assert_eq!(v["reference"], reference);
        assert!(v["hole_sample_share"].as_f64().unwrap() > 0.5, "{v}");
        assert!(v["hole_px"].as_u64().unwrap() > 0, "{v}");
    }
}

/// `reyes holes` without --json prints a header row and its markdown rule over the row (one
/// cell per column), and the row alone with --no-header. Needs the GPU (lavapipe).
#[test]
fn holes_table_has_a_header() {
    let dir = scratch("holes-table");
    let base = [
        "holes",
        "teapot",
        "--width",
        "32",
        "--height",
        "24",
        "--mp-size",
        "2",
        "--strategy",
        "multipass",
        "--ref-samples",
        "1",
    ];
    let (code, out, err) = reyes_any(&dir, &base);
    assert_eq!(code, 0, "{err}");
    let lines: Vec<&str> = out.lines().collect();
    assert_eq!(lines.len(), 3, "{out}");
    assert!(lines[0].starts_with("| scene | raster |"), "{out}");
    assert!(lines[1].starts_with("| --- |"), "{out}");
    assert!(lines[2].starts_with("| teapot | bbox |"), "{out}");
    let cells = |l: &str| l.matches('|').count();
    assert_eq!(cells(lines[0]), cells(lines[1]), "{out}");
    assert_eq!(cells(lines[0]), cells(lines[2]), "{out}");
    let mut args = base.to_vec();
    args.push("--no-header");
    let (code, out, err) = reyes_any(&dir, &args);
    assert_eq!(code, 0, "{err}");
    assert_eq!(out.lines().collect::<Vec<_>>(), [lines[2]], "{out}");
}

fn field(name: &str) -> String {
    let p = reyes::shared_data_dir().join("field").join(name);
    assert!(p.is_file(), "{} is missing", p.display());
    p.to_str().unwrap().to_string()
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
    // `-o` naming a folder: the frames go into it, under their Display names (the trial of
    // 2026-11-30 found them written into its parent, over files there).
    std::fs::create_dir_all(dir.join("into")).unwrap();
    for folder in ["into/", "into"] {
        let (ok, err) = reyes(&dir, &[&scene, "--cpu", "-o", folder]);
        assert!(ok, "{err}");
        for (n, img) in imgs.iter().enumerate() {
            let p = dir.join(format!("into/teapot.000{}.png", n + 1));
            assert!(png(&p) == *img, "{folder}: {}", p.display());
            std::fs::remove_file(p).unwrap();
        }
        assert!(!dir.join("teapot.0001.png").exists(), "{folder}");
    }
    // One frame selected and a plain `-o` name: that name.
    let (ok, err) = reyes(&dir, &[&scene, "--cpu", "-o", "one.png", "--frames", "2"]);
    assert!(ok, "{err}");
    assert!(png(&dir.join("one.png")) == imgs[1]);
    assert!(!dir.join("teapot.0002.png").exists());
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
    // Several frames need a pattern for --stats (which the GPU path writes: both fail before
    // the GPU is opened); a missing folder fails before rendering.
    // The first is a usage error (exit 2, as README says of usage errors), the second not.
    for (args, expected, code) in [
        (
            &["--stats", "s.json"][..],
            "--stats: several frames are rendered",
            2,
        ),
        (
            &["--cpu", "-o", "nowhere/x.png"][..],
            "the folder nowhere does not exist",
            1,
        ),
    ] {
        let mut all = vec![scene.as_str(), "--frames", "1-2"];
        all.extend_from_slice(args);
        let (got, err) = render_code(&dir, &all);
        assert!(
            got == code && err.contains(expected),
            "{args:?}: {got} {err}"
        );
    }
    assert!(!dir.join("s.json").exists() && !dir.join("teapot.0001.png").exists());
}

/// A three-frame RIB of 32x24 quads, one at a different place in each frame (frame 2 broken
/// when `broken`: a patch of too few points).
fn farm_scene(dir: &Path, broken: bool) -> &'static str {
    let quad = |x: f64| {
        format!(
            "Patch \"bilinear\" \"P\" [{} -1 5  {} -1 5  {} 1 5  {} 1 5]",
            x - 1.0,
            x + 1.0,
            x - 1.0,
            x + 1.0
        )
    };
    let two = if broken {
        "Patch \"bilinear\" \"P\" [0 0 5]".to_string()
    } else {
        quad(0.0)
    };
    std::fs::write(
        dir.join("shot.rib"),
        format!(
            "Format 32 24 1\n\
             FrameBegin 1\nWorldBegin\n{}\nWorldEnd\nFrameEnd\n\
             FrameBegin 2\nWorldBegin\n{two}\nWorldEnd\nFrameEnd\n\
             FrameBegin 3\nWorldBegin\n{}\nWorldEnd\nFrameEnd\n",
            quad(-0.5),
            quad(0.5)
        ),
    )
    .unwrap();
    "shot.rib"
}

/// `-o` with a printf-style frame number: `%04d` zero-padded, `%d` not; `--frame N` is
/// `--frames N`, and not both.
#[test]
fn printf_frame_number_patterns_name_the_outputs() {
    let dir = scratch("printf");
    let scene = farm_scene(&dir, false);
    let (ok, err) = reyes(&dir, &[scene, "--cpu", "-o", "shot.%04d.png"]);
    assert!(ok, "{err}");
    for n in 1..=3 {
        assert!(covered(&png(&dir.join(format!("shot.000{n}.png")))) > 0);
    }
    let (ok, err) = reyes(&dir, &[scene, "--cpu", "-o", "s%d.png", "--frame", "2"]);
    assert!(ok, "{err}");
    assert!(png(&dir.join("s2.png")) == png(&dir.join("shot.0002.png")));
    assert!(!dir.join("s1.png").exists() && !dir.join("s3.png").exists());
    let (code, err) = render_code(&dir, &[scene, "--frame", "1", "--frames", "2"]);
    assert_eq!(code, 2, "{err}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The farm contract: with --frames, a frame whose output exists is skipped (one stderr line
/// each) unless --overwrite, so a resubmitted task renders only what is missing.
#[test]
fn existing_frames_are_skipped_unless_overwrite() {
    let dir = scratch("skip");
    let scene = farm_scene(&dir, false);
    let args = [scene, "--cpu", "-o", "f.####.png", "--frames", "1-3"];
    let (ok, err) = reyes(&dir, &args);
    assert!(ok, "{err}");
    let paths: Vec<PathBuf> = (1..=3).map(|n| dir.join(format!("f.000{n}.png"))).collect();
    let before: Vec<_> = paths.iter().map(|p| mtime(p)).collect();
    let image2 = png(&paths[1]);
    // A lost frame (a task killed, a file deleted): only it renders again.
    std::fs::remove_file(&paths[1]).unwrap();
    std::thread::sleep(std::time::Duration::from_millis(20));
    let (ok, err) = reyes(&dir, &args);
    assert!(ok, "{err}");
    for n in [1, 3] {
        assert!(
            err.contains(&format!("frame {n}: skipped, f.000{n}.png exists")),
            "{err}"
        );
    }
    assert_eq!(err.matches("skipped").count(), 2, "{err}");
    assert!(png(&paths[1]) == image2);
    assert_eq!(mtime(&paths[0]), before[0]);
    assert_eq!(mtime(&paths[2]), before[2]);
    // All there: nothing renders, exit 0.
    let (ok, err) = reyes(&dir, &args);
    assert!(
        ok && err.matches("skipped").count() == 3 && !err.contains("wrote"),
        "{err}"
    );
    // --overwrite renders them all again: frame 1's file, emptied (it still exists, so it
    // was skipped above), holds its image again. (Its content, not its mtime: a clock's
    // granularity is no part of the contract.)
    let image1 = png(&paths[0]);
    std::fs::write(&paths[0], b"").unwrap();
    let mut again = args.to_vec();
    again.push("--overwrite");
    let (ok, err) = reyes(&dir, &again);
    assert!(
        ok && !err.contains("skipped") && err.matches("wrote").count() == 3,
        "{err}"
    );
    assert!(png(&paths[0]) == image1);
    // Without a selection, as before: the files are written again.
    let (ok, err) = reyes(&dir, &[scene, "--cpu", "-o", "f.####.png"]);
    assert!(ok && !err.contains("skipped"), "{err}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A broken frame 2 does not fail a task of frame 1; a task of 1-3 writes 1 and 3, names
/// frame 2 (and its file and line), leaves no file for it and exits 1; once frame 2 is
/// fixed, the resubmitted task renders frame 2 only.
#[test]
fn a_broken_frame_fails_alone() {
    let dir = scratch("broken");
    let scene = farm_scene(&dir, true);
    let (ok, err) = reyes(&dir, &[scene, "--cpu", "-o", "b.%04d.png", "--frames", "1"]);
    assert!(ok, "{err}");
    assert!(dir.join("b.0001.png").is_file());
    std::fs::remove_file(dir.join("b.0001.png")).unwrap();
    let args = [scene, "--cpu", "-o", "b.%04d.png", "--frames", "1-3"];
    let (code, err) = render_code(&dir, &args);
    assert_eq!(code, 1, "{err}");
    assert!(
        err.contains("reyes render: frame 2: shot.rib:9: `Patch`"),
        "{err}"
    );
    assert!(err.contains("frame 2 failed"), "{err}");
    assert!(dir.join("b.0001.png").is_file() && dir.join("b.0003.png").is_file());
    let leftovers: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.contains("0002") || n.starts_with('.'))
        .collect();
    assert!(leftovers.is_empty(), "{leftovers:?}");
    let t3 = mtime(&dir.join("b.0003.png"));
    farm_scene(&dir, false);
    let (code, err) = render_code(&dir, &args);
    assert_eq!(code, 0, "{err}");
    assert!(dir.join("b.0002.png").is_file());
    assert_eq!(err.matches("wrote").count(), 1, "{err}");
    assert_eq!(mtime(&dir.join("b.0003.png")), t3);
    // Two frames writing one file: the later one fails.
    std::fs::write(
        dir.join("same.rib"),
        "Format 8 6 1\nFrameBegin 1\nDisplay \"x.tif\" \"file\" \"rgba\"\nWorldBegin\nWorldEnd\nFrameEnd\n\
         FrameBegin 2\nDisplay \"x.png\" \"file\" \"rgba\"\nWorldBegin\nWorldEnd\nFrameEnd\n",
    )
    .unwrap();
    let (code, err) = render_code(&dir, &["same.rib", "--cpu"]);
    assert_eq!(code, 1, "{err}");
    assert!(
        err.contains("frame 2: frames 1 and 2 would both write x.png"),
        "{err}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
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
        // --stats is the GPU path's (--cpu refuses it).
        for way in [&["--cpu"][..], &["--stats", "s.json"]] {
            let mut args = vec![scene.as_str(), "-o", "out.png"];
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

/// `reyes bench` on the built-in teapot prints one JSON object with the documented keys
/// (docs/reyes.md), one row per timed frame; the table names its rows. Needs the GPU (lavapipe).
#[test]
fn bench_prints_its_report_as_json() {
    let dir = scratch("bench");
    let args = [
        "bench",
        "teapot",
        "--frames",
        "3",
        "--json",
        "--width",
        "64",
        "--height",
        "48",
        "--warmup",
        "1",
        "--turntable",
    ];
    let (code, out, err) = reyes_any(&dir, &args);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap_or_else(|e| panic!("{e}: {out}"));
    for key in [
        "scene",
        "adapter",
        "strategy",
        "width",
        "height",
        "samples",
        "frames",
        "turntable",
        "degrees_per_frame",
        "pipelined",
        "not_pipelined",
        "wall_ms",
        "gpu_ms",
        "wall_minus_gpu_ms",
        "fps",
        "micropolygons",
        "occlusion",
        "occluded",
        "rerendered",
        "per_frame",
    ] {
        assert!(v.get(key).is_some(), "no `{key}` in {out}");
    }
    // `--occlusion auto` (the default) does not cull the shallow teapot.
    assert_eq!(v["occlusion"], false);
    assert_eq!(v["occluded"]["max"], 0.0);
    assert_eq!(v["scene"], "teapot");
    // The default strategy is chosen per adapter: multipass on a CPU adapter (lavapipe).
    let cpu = v["adapter"].as_str().unwrap().contains("llvmpipe");
    assert_eq!(v["strategy"], if cpu { "multipass" } else { "megakernel" });
    if cpu {
        assert!(err.contains("note: strategy multipass"), "{err}");
    }
    assert_eq!(
        (v["width"].as_u64(), v["height"].as_u64()),
        (Some(64), Some(48))
    );
    assert_eq!(v["frames"], 3);
    assert_eq!(v["degrees_per_frame"], 120.0);
    assert_eq!(v["pipelined"], true);
    for k in ["median", "p95", "min", "max"] {
        assert!(v["wall_ms"][k].as_f64().unwrap() > 0.0, "wall_ms.{k}");
    }
    assert!(v["gpu_ms"].is_null() || v["gpu_ms"]["median"].as_f64().unwrap() > 0.0);
    assert!(v["fps"].as_f64().unwrap() > 0.0);
    assert!(v["micropolygons"]["median"].as_f64().unwrap() > 100.0);
    let rows = v["per_frame"].as_array().unwrap();
    assert_eq!(rows.len(), 3);
    assert_eq!(rows[1]["angle_deg"], 120.0);
    assert_eq!(rows[1]["occluded"], 0);
    let (code, out, err) = reyes_any(
        &dir,
        &[
            "bench",
            "--frames",
            "2",
            "--warmup",
            "0",
            "--width",
            "32",
            "--height",
            "24",
            "--strategy",
            "multipass",
        ],
    );
    assert_eq!(code, 0, "{err}");
    for label in ["wall ms", "GPU ms", "fps", "re-rendered", "occluded"] {
        assert!(out.contains(label), "no `{label}` in the table: {out}");
    }
    // A stacked scene with --occlusion on and off: every frame, the first included (its
    // history is the single frame's first pass), culls the layers behind the front one, with
    // the same image (tests/reyes_occlusion.rs); off culls nothing.
    let rib = dir.join("stacked.rib");
    std::fs::write(&rib, reyes::scene::stacked::stacked_rib(8, 2, 32, 24)).unwrap();
    for (mode, culls) in [("on", true), ("off", false)] {
        let rib = rib.to_str().unwrap();
        let args = [
            "bench",
            rib,
            "--frames",
            "3",
            "--warmup",
            "0",
            "--json",
            "--occlusion",
        ];
        let (code, out, err) = reyes_any(&dir, &[&args[..], &[mode][..]].concat());
        assert_eq!(code, 0, "{err}");
        let v: serde_json::Value = serde_json::from_str(&out).unwrap();
        assert_eq!(v["occlusion"], culls, "--occlusion {mode}");
        let rows = v["per_frame"].as_array().unwrap();
        for row in [&rows[0], &rows[2]] {
            let culled = row["occluded"].as_u64().unwrap();
            match culls {
                true => assert!(culled >= 7 * 4, "--occlusion on culled {culled}: {out}"),
                false => assert_eq!(culled, 0),
            }
        }
    }
}

/// `reyes bench --peer raster --frames 2` times the raster peer on the same frames and reports
/// both renderers: the peer's timing, MSAA count (4 for the 2x2 pixel samples
/// asked) and its image difference against Reyes on the first and
/// last frame, in the JSON and in the table. Needs the GPU (lavapipe).
#[test]
fn bench_with_the_raster_peer_reports_both() {
    let dir = scratch("bench-peer");
    let common = [
        "bench",
        "--frames",
        "2",
        "--warmup",
        "1",
        "--width",
        "64",
        "--height",
        "48",
        "--samples",
        "2",
        "--turntable",
        "--peer",
        "raster",
    ];
    let (code, out, err) = reyes_any(&dir, &[&common[..], &["--json"]].concat());
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap_or_else(|e| panic!("{e}: {out}"));
    assert_eq!(v["frames"], 2);
    assert!(v["micropolygons"]["median"].as_f64().unwrap() > 100.0);
    let p = &v["peer"];
    assert_eq!(p["peer"], "raster");
    assert_eq!(
        (p["msaa_samples"].as_u64(), p["msaa_wanted"].as_u64()),
        (Some(4), Some(4))
    );
    assert!(p["wall_ms"]["median"].as_f64().unwrap() > 0.0);
    assert!(p["gpu_ms"].is_null() || p["gpu_ms"]["median"].as_f64().unwrap() > 0.0);
    assert!(p["fps"].as_f64().unwrap() > 0.0);
    assert!(p["triangles"]["median"].as_f64().unwrap() > 1000.0);
    assert_eq!(p["per_frame"].as_array().unwrap().len(), 2);
    let d = p["difference"].as_array().unwrap();
    let angles: Vec<f64> = d.iter().map(|x| x["angle_deg"].as_f64().unwrap()).collect();
    assert_eq!(angles, [0.0, 180.0]);
    for x in d {
        // Same frames, same surfaces: most pixels agree (edges differ; tests/reyes_raster.rs).
        assert!(x["psnr_db"].as_f64().unwrap() > 20.0, "{x}");
        assert!(x["over"].as_f64().unwrap() < 0.2, "{x}");
        assert!(x["covered_peer"].as_u64().unwrap() > 300, "{x}");
    }
    let (code, out, err) = reyes_any(&dir, &common);
    assert_eq!(code, 0, "{err}");
    for label in [
        "peer raster: 4x MSAA",
        "triangles",
        "image vs Reyes at 0.0 deg: PSNR",
    ] {
        assert!(out.contains(label), "no `{label}` in the table: {out}");
    }
}

/// Little-endian PFM (`reyes render --float`, `--depth`): width, height, channels and the
/// samples top row first.
fn read_pfm(p: &Path) -> (usize, usize, usize, Vec<f32>) {
    let bytes = std::fs::read(p).unwrap();
    let mut lines = bytes.splitn(4, |&b| b == b'\n');
    let kind = lines.next().unwrap();
    let channels = if kind == b"PF" { 3 } else { 1 };
    let size = String::from_utf8(lines.next().unwrap().to_vec()).unwrap();
    let (w, h) = size.split_once(' ').unwrap();
    let (w, h): (usize, usize) = (w.parse().unwrap(), h.parse().unwrap());
    assert_eq!(lines.next().unwrap(), b"-1.0", "little-endian scale");
    let data = lines.next().unwrap();
    assert_eq!(data.len(), w * h * channels * 4);
    let f: Vec<f32> = data
        .chunks(4)
        .map(|c| f32::from_le_bytes(c.try_into().unwrap()))
        .collect();
    let rows: Vec<&[f32]> = f.chunks(w * channels).rev().collect();
    (w, h, channels, rows.concat())
}

/// `--stats` is `FrameStats` whole (every key documented in docs/reyes.md), and `--exr` holds
/// the rendered frame's colour (premultiplied), alpha and depth exactly: read back with the
/// `exr` crate against the `--float` and `--depth` PFMs and the PNG of the same render. Needs
/// the GPU (lavapipe).
/// `--stats`: a scheduler run timed as one carries the megakernel's note on why its stages are
/// not timed apart only under the megakernel; multi-pass (without --stage-times) has none.
/// Needs the GPU (lavapipe).
#[test]
fn only_megakernel_stats_carry_the_schedule_note() {
    let dir = scratch("stats-note");
    for strategy in ["multipass", "megakernel"] {
        let json = format!("{strategy}.json");
        let (ok, err) = reyes(
            &dir,
            &[
                "teapot",
                "--width",
                "40",
                "--height",
                "30",
                "--gpu",
                "--strategy",
                strategy,
                "-o",
                "f.png",
                "--stats",
                &json,
            ],
        );
        assert!(ok, "{strategy}: {err}");
        let v: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(dir.join(&json)).unwrap()).unwrap();
        let stages = &v["gpu_ms_per_stage"];
        assert!(stages.get("schedule").is_some(), "{strategy}: {stages}");
        let note = stages.get("note").and_then(|n| n.as_str());
        match strategy {
            "megakernel" => assert!(note.unwrap().contains("megakernel"), "{stages}"),
            _ => assert_eq!(note, None, "{strategy}: {stages}"),
        }
    }
}

#[test]
fn stats_and_exr_hold_the_rendered_frame() {
    let dir = scratch("exr");
    let (ok, err) = reyes(
        &dir,
        &[
            "teapot",
            "--width",
            "40",
            "--height",
            "30",
            "--strategy",
            "multipass",
            "--stage-times",
            "--runs",
            "2",
            "-o",
            "f.png",
            "--stats",
            "s.json",
            "--exr",
            "f.exr",
            "--float",
            "f.pfm",
            "--depth",
            "d.pfm",
        ],
    );
    assert!(ok, "{err}");
    let text = std::fs::read_to_string(dir.join("s.json")).unwrap();
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    let typed: reyes::stats::FrameStats = serde_json::from_value(v.clone()).unwrap();
    assert_eq!(
        serde_json::to_value(&typed).unwrap(),
        v,
        "keys beyond FrameStats"
    );
    assert_eq!((typed.width, typed.height), (40, 30));
    assert_eq!(typed.strategy, "multipass");
    assert!(typed.micropolygons > 100 && typed.grids_diced > 0);
    // The teapot's patches have no fields, weights or trims: a root item (224 bytes) and a
    // patch info (32) each.
    assert_eq!(typed.table_bytes, typed.patches_in as u64 * (224 + 32));
    assert_eq!(typed.runs.as_ref().unwrap().count, 2);
    assert_eq!(v["executed"]["bound"], typed.bounds);
    let docs = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../../docs/reyes.md"))
        .unwrap();
    for key in v.as_object().unwrap().keys() {
        assert!(
            docs.contains(&format!("`{key}`")) || docs.contains(&format!("`{key}.")),
            "`{key}` is not in docs/reyes.md"
        );
    }

    let exr = exr::prelude::read_first_flat_layer_from_file(dir.join("f.exr")).unwrap();
    let layer = &exr.layer_data;
    assert_eq!((layer.size.0, layer.size.1), (40, 30));
    let channel = |name: &str| -> Vec<f32> {
        let c = (layer.channel_data.list.iter())
            .find(|c| &c.name == name)
            .unwrap_or_else(|| panic!("no channel {name}"));
        match &c.sample_data {
            exr::prelude::FlatSamples::F32(v) => v.clone(),
            other => panic!("{name} is not f32: {other:?}"),
        }
    };
    let (w, h, n, rgb) = read_pfm(&dir.join("f.pfm"));
    assert_eq!((w, h, n), (40, 30, 3));
    let (_, _, _, depth) = read_pfm(&dir.join("d.pfm"));
    let a = channel("A");
    for (c, name) in ["R", "G", "B"].into_iter().enumerate() {
        let want: Vec<f32> = (0..w * h).map(|p| rgb[p * 3 + c] * a[p]).collect();
        assert_eq!(channel(name), want, "{name}");
    }
    let z = channel("Z");
    assert_eq!(z.len(), depth.len());
    assert!(
        z.iter().zip(&depth).all(|(x, y)| x == y),
        "Z differs from --depth"
    );
    assert!(z.contains(&f32::INFINITY) && z.iter().any(|z| z.is_finite()));
    let img = png(&dir.join("f.png"));
    let alpha8: Vec<u8> = a
        .iter()
        .map(|a| (a.clamp(0.0, 1.0) * 255.0).round() as u8)
        .collect();
    let png_alpha: Vec<u8> = img.pixels().map(|p| p[3]).collect();
    assert_eq!(alpha8, png_alpha);
    assert!(covered(&img) > 50);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Without `XDG_RUNTIME_DIR` (no login session: containers, CI) lavapipe used to print
/// "error: XDG_RUNTIME_DIR is invalid or not set" twice although nothing was wrong; the command
/// now gives the driver a private folder of its own (`reyes::driver_env`) and prints no error.
#[test]
fn no_false_driver_error_without_a_runtime_folder() {
    let dir = tempfile::tempdir().unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_reyes"))
        .current_dir(dir.path())
        .env_remove("XDG_RUNTIME_DIR")
        .args(["render", "--width", "32", "--height", "24", "-o", "t.png"])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert!(!err.contains("XDG_RUNTIME_DIR"), "{err}");
    assert!(!err.contains("error"), "{err}");
}

/// What a progress bar writes: carriage returns, escape codes, the bar and its estimate.
fn progress_marks(text: &str) -> Vec<&'static str> {
    [("\r", "\\r"), ("\x1b", "ESC"), ("ETA", "ETA"), ("[=", "[=")]
        .into_iter()
        .filter(|(mark, _)| text.contains(mark))
        .map(|(_, name)| name)
        .collect()
}

/// With stdout and stderr piped (not terminals) the long commands show no progress bar: a
/// GPU frame sequence with `--runs 2` and a small sweep print their usual lines and nothing of
/// a bar. `--runs` prints the median GPU time of the runs beside the last run's wall time.
/// Needs the GPU (lavapipe).
#[test]
fn progress_is_silent_when_output_is_piped() {
    let scene = field("three-frames.rib");
    let dir = scratch("quiet");
    let args = [
        "render",
        scene.as_str(),
        "--width",
        "48",
        "--height",
        "30",
        "--strategy",
        "multipass",
        "--runs",
        "2",
    ];
    let (code, out, err) = reyes_any(&dir, &args);
    assert_eq!(code, 0, "{err}");
    for n in 1..=3 {
        assert!(dir.join(format!("teapot.000{n}.png")).is_file(), "{err}");
        assert!(err.contains(&format!("frame {n}:\n")), "{err}");
    }
    // One summary per frame: 2 runs, the median GPU ms (lavapipe has timestamps; n/a
    // elsewhere), the last run's wall ms.
    let summaries: Vec<&str> = err
        .lines()
        .filter(|l| l.contains("2 runs: GPU ") && l.contains("last run wall "))
        .collect();
    assert_eq!(summaries.len(), 3, "{err}");
    assert!(
        summaries
            .iter()
            .all(|l| l.contains("(median ± MAD)") || l.contains("GPU n/a")),
        "{err}"
    );
    assert_eq!(progress_marks(&out), Vec::<&str>::new(), "{out:?}");
    assert_eq!(progress_marks(&err), Vec::<&str>::new(), "{err:?}");

    let sweep_out = dir.join("sweep");
    let (code, out, err) = reyes_any(
        &dir,
        &[
            "sweep",
            "--scenes",
            "teapot",
            "--width",
            "32",
            "--height",
            "24",
            "--runs",
            "1",
            "--ref-samples",
            "2",
            "--mp-sizes",
            "2",
            "--bound-px",
            "none",
            "--samples",
            "1",
            "--strategies",
            "multipass",
            "--out",
            sweep_out.to_str().unwrap(),
        ],
    );
    assert_eq!(code, 0, "{err}");
    assert!(sweep_out.join("sweep.csv").is_file());
    assert!(
        err.contains("teapot: reference 32x24") && err.contains("(2 settings, "),
        "{err}"
    );
    assert_eq!(progress_marks(&out), Vec::<&str>::new(), "{out:?}");
    assert_eq!(progress_marks(&err), Vec::<&str>::new(), "{err:?}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Under a pseudo-terminal (util-linux `script`) the same kind of command draws its bar, with
/// the count and the estimate, and its usual lines still come through whole. The CPU twin of
/// a three-frame sequence: no GPU needed.
#[cfg(target_os = "linux")]
#[test]
fn progress_bar_is_drawn_on_a_terminal() {
    let scene = field("three-frames.rib");
    let dir = scratch("tty");
    let command = format!(
        "'{}' render '{scene}' --cpu --width 64 --height 40",
        env!("CARGO_BIN_EXE_reyes")
    );
    let out = Command::new("script")
        .args(["-qec", &command, "/dev/null"])
        .current_dir(&dir)
        .env("XDG_RUNTIME_DIR", std::env::temp_dir())
        .output()
        .expect("util-linux `script` runs the command under a pseudo-terminal");
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{text}");
    assert!(
        text.contains("3/3 ETA ") && text.contains("\r") && text.contains("[===="),
        "no bar in {text:?}"
    );
    // The notes are written above the bar: each starts on a line of its own or one the bar
    // was just cleared from (ESC [2K), never after the bar's text.
    for n in 1..=3 {
        let line = format!("wrote teapot.000{n}.png (");
        let at = text
            .find(&line)
            .unwrap_or_else(|| panic!("no `{line}` in {text:?}"));
        let before = &text[..at];
        assert!(
            before.ends_with('\n') || before.ends_with("\x1b[2K"),
            "{text:?}"
        );
        assert!(dir.join(format!("teapot.000{n}.png")).is_file());
    }
    // Warnings (log records) go above the bar too: two empty frames each warn.
    std::fs::write(
        dir.join("empty.rib"),
        "Format 16 12 1\nFrameBegin 1\nWorldBegin\nWorldEnd\nFrameEnd\n\
         FrameBegin 2\nWorldBegin\nWorldEnd\nFrameEnd\n",
    )
    .unwrap();
    let out = Command::new("script")
        .args([
            "-qec",
            &format!("'{}' render empty.rib --cpu", env!("CARGO_BIN_EXE_reyes")),
            "/dev/null",
        ])
        .current_dir(&dir)
        .env("XDG_RUNTIME_DIR", std::env::temp_dir())
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{text}");
    let warning = "warning: nothing was drawn";
    let parts: Vec<&str> = text.split(warning).collect();
    assert_eq!(parts.len(), 3, "two warnings in {text:?}");
    for before in &parts[..2] {
        assert!(
            before.ends_with('\n') || before.ends_with("\x1b[2K"),
            "{text:?}"
        );
    }
    assert!(text.contains("2/2 ETA "), "no bar in {text:?}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `--spin`, `--dof` and `--sampling` give a frame motion blur and depth of field (its
/// statistics say how it was sampled), and `--compare-to` reports the image error against a
/// reference EXR, in the statistics too; bad values name their flag or file.
#[test]
fn motion_blur_and_depth_of_field_from_the_command_line() {
    let dir = scratch("motion");
    let common = [
        "teapot",
        "--width",
        "40",
        "--height",
        "30",
        "--strategy",
        "multipass",
        "--spin",
        "20",
        "--dof",
        "2,1,5",
        "--sampling",
        "bbox",
    ];
    fn with<'a>(common: &[&'a str], more: &[&'a str]) -> Vec<&'a str> {
        [common, more].concat()
    }
    let with = |more: &[&'static str]| with(&common, more);
    let (ok, err) = reyes(
        &dir,
        &with(&["--samples", "4", "--exr", "ref.exr", "-o", "ref.png"]),
    );
    assert!(ok, "{err}");
    let (ok, err) = reyes(
        &dir,
        &with(&[
            "--samples",
            "1",
            "--compare-to",
            "ref.exr",
            "--stats",
            "s.json",
            "-o",
            "f.png",
        ]),
    );
    assert!(ok, "{err}");
    assert!(err.contains("image error against ref.exr: PSNR"), "{err}");
    let text = std::fs::read_to_string(dir.join("s.json")).unwrap();
    let s: reyes::stats::FrameStats = serde_json::from_str(&text).unwrap();
    let uvt = s.uvt.expect("uvt statistics");
    assert_eq!(uvt.sampling, "bbox");
    assert_eq!(uvt.moving_patches, s.patches_in);
    assert!(uvt.coc_scale_px > 0.0);
    let e = s.image_error.expect("image error statistics");
    assert!(e.psnr_db.is_finite() && e.psnr_db > 10.0, "{e:?}");
    assert!(e.flip_mean > 0.0 && e.flip_mean < 0.5, "{e:?}");
    let docs = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../../docs/reyes.md"))
        .unwrap();
    for key in ["uvt", "image_error"] {
        assert!(
            docs.contains(&format!("`{key}`")),
            "`{key}` is not in docs/reyes.md"
        );
    }
    let (code, err) = render_code(&dir, &with(&["--compare-to", "missing.exr", "-o", "m.png"]));
    assert!(
        code == 1 && err.contains("--compare-to missing.exr"),
        "{code}: {err}"
    );
    let mut small = with(&["--compare-to", "ref.exr", "-o", "m.png"]);
    small[2] = "20";
    let (code, err) = render_code(&dir, &small);
    assert!(
        code == 1 && err.contains("the reference is 40x30, the frame 20x30"),
        "{code}: {err}"
    );
    assert!(!dir.join("m.png").exists());
    for (flag, value) in [
        ("--dof", "2,1"),
        ("--dof", "2,0,4"),
        ("--il-tile", "5"),
        ("--spin", "nan"),
    ] {
        let (code, err) = render_code(&dir, &["teapot", flag, value]);
        assert!(
            code == 2 && err.contains(flag),
            "{flag} {value}: {code}: {err}"
        );
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `--raster nearest` samples no time or lens: with `--spin` or `--dof` it is a usage error
/// (exit 2) naming both flags, on every subcommand that renders, and no image is written.
#[test]
fn nearest_rasterization_with_motion_or_depth_of_field_is_a_usage_error() {
    let dir = scratch("nearest-motion");
    for (cmd, flag) in [
        (
            ["render", "-o", "x.png", "--cpu"].as_slice(),
            ["--spin", "30"],
        ),
        (
            ["render", "-o", "x.png", "--cpu"].as_slice(),
            ["--dof", "2,100,420"],
        ),
        (["bench"].as_slice(), ["--spin", "30"]),
    ] {
        let mut args = cmd.to_vec();
        args.extend(["--raster", "nearest", flag[0], flag[1]]);
        let (code, _, err) = reyes_any(&dir, &args);
        assert_eq!(code, 2, "{args:?}: {err}");
        assert!(
            err.contains("--raster nearest") && err.contains(flag[0]),
            "{err}"
        );
    }
    assert!(!dir.join("x.png").exists());
}

/// The multi-pass floor replays one kept frame's work: `reyes bench` and `reyes view`, whose
/// frames move, refuse it as a usage error (exit 2) that names it and says where it works,
/// before opening a device or a window.
#[test]
fn the_multipass_floor_is_refused_where_frames_move() {
    let dir = scratch("floor-moving");
    for cmd in ["bench", "view"] {
        let args = [cmd, "--strategy", "multipass-floor"];
        let (code, _, err) = reyes_any(&dir, &args);
        assert_eq!(code, 2, "{args:?}: {err}");
        assert!(
            err.contains("multipass-floor") && err.contains("reyes render --runs"),
            "{err}"
        );
    }
}

/// `-o` naming a symbolic link writes the file it points to and keeps the link; naming a FIFO
/// writes the PNG into it, in place: neither becomes a regular file (as root, `-o /dev/null`
/// must not replace /dev/null).
#[cfg(unix)]
#[test]
fn output_through_links_and_into_fifos_never_replaces_them() {
    use std::os::unix::fs::FileTypeExt;
    let dir = scratch("special-out");
    let args = |out: &'static str| {
        [
            "teapot", "--cpu", "--width", "40", "--height", "30", "-o", out,
        ]
    };
    let _ = std::fs::remove_file(dir.join("link.png"));
    std::fs::write(dir.join("real.png"), b"old").unwrap();
    std::os::unix::fs::symlink("real.png", dir.join("link.png")).unwrap();
    let (ok, err) = reyes(&dir, &args("link.png"));
    assert!(ok, "{err}");
    assert!(
        std::fs::symlink_metadata(dir.join("link.png"))
            .unwrap()
            .is_symlink()
    );
    let png = std::fs::read(dir.join("real.png")).unwrap();
    assert!(
        png.starts_with(b"\x89PNG"),
        "the link's file holds the image"
    );

    let fifo = dir.join("pipe.png");
    let _ = std::fs::remove_file(&fifo);
    if Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .is_ok_and(|s| s.success())
    {
        let reader = {
            let fifo = fifo.clone();
            std::thread::spawn(move || std::fs::read(fifo).unwrap())
        };
        let (ok, err) = reyes(&dir, &args("pipe.png"));
        assert!(ok, "{err}");
        assert!(std::fs::metadata(&fifo).unwrap().file_type().is_fifo());
        assert!(reader.join().unwrap().starts_with(b"\x89PNG"));
    }
}

/// `-o` writes PNG: a name with another image format's extension is a usage error naming the
/// flag that writes that format (PNG bytes under `out.exr` would mislead every reader).
#[test]
fn output_names_of_another_format_are_usage_errors() {
    let dir = scratch("out-format");
    for (out, flag) in [
        ("out.exr", "--exr"),
        ("out.pfm", "--float"),
        ("out.jpg", "PNG"),
    ] {
        let (code, err) = render_code(&dir, &["--cpu", "-o", out]);
        assert_eq!(code, 2, "{out}: {err}");
        assert!(
            err.contains("-o writes PNG") && err.contains(flag),
            "{out}: {err}"
        );
        assert!(!dir.join(out).exists());
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// An output that is one of the scene's inputs (the scene file, an archive, a displacement
/// map named by a frame's `Display`) is refused before the frame renders, naming both; the
/// input is untouched and the other frames render.
#[test]
fn outputs_never_overwrite_the_scenes_inputs() {
    let dir = scratch("clobber");
    let mut map = image::GrayImage::new(4, 4);
    map.fill(128);
    map.save(dir.join("bumps.png")).unwrap();
    let quad = "Patch \"bilinear\" \"P\" [-1 -1 5  1 -1 5  -1 1 5  1 1 5]";
    std::fs::write(dir.join("arch.rib"), format!("{quad}\n")).unwrap();
    std::fs::write(
        dir.join("s.rib"),
        format!(
            "Format 8 6 1\n\
             FrameBegin 1\nDisplay \"bumps.tif\" \"file\" \"rgba\"\nWorldBegin\n\
             Displacement \"mapped\" \"mapname\" \"bumps.png\" \"Km\" 0.1\n{quad}\n\
             WorldEnd\nFrameEnd\n\
             FrameBegin 2\nDisplay \"two.png\" \"file\" \"rgba\"\nWorldBegin\n\
             ReadArchive \"arch.rib\"\nWorldEnd\nFrameEnd\n"
        ),
    )
    .unwrap();
    let before = |n: &str| std::fs::read(dir.join(n)).unwrap();
    let (map0, scene0, arch0) = (before("bumps.png"), before("s.rib"), before("arch.rib"));
    let (code, err) = render_code(&dir, &["s.rib", "--cpu"]);
    assert_eq!(code, 1, "{err}");
    assert!(
        err.contains("frame 1: bumps.png would overwrite")
            && err.contains("bumps.png, an input of the scene"),
        "{err}"
    );
    assert!(
        dir.join("two.png").is_file(),
        "frame 2 still renders: {err}"
    );
    assert_eq!(err.matches("wrote").count(), 1, "{err}");
    for (out, frame) in [("s.rib", "1"), ("arch.rib", "2")] {
        let (code, err) = render_code(&dir, &["s.rib", "--cpu", "--frame", frame, "-o", out]);
        assert_eq!(code, 1, "{out}: {err}");
        assert!(
            err.contains(&format!("{out} would overwrite")),
            "{out}: {err}"
        );
        assert!(!err.contains("wrote"), "{out}: {err}");
    }
    assert_eq!(before("bumps.png"), map0);
    assert_eq!(before("s.rib"), scene0);
    assert_eq!(before("arch.rib"), arch0);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A frame whose `Display` name the file system cannot hold (300 bytes, or a NUL) fails
/// before it renders, naming the `Display` name (not after rendering, with "File name too
/// long"); the other frames render.
#[test]
fn display_names_the_file_system_cannot_hold_fail_before_rendering() {
    let dir = scratch("long-names");
    let long = "d".repeat(300);
    let frame = |n: u32, name: &str| {
        format!(
            "FrameBegin {n}\nDisplay \"{name}\" \"file\" \"rgba\"\nWorldBegin\n\
             Patch \"bilinear\" \"P\" [-1 -1 5  1 -1 5  -1 1 5  1 1 5]\nWorldEnd\nFrameEnd\n"
        )
    };
    std::fs::write(
        dir.join("s.rib"),
        format!(
            "Format 8 6 1\n{}{}{}{}",
            frame(1, "one.png"),
            frame(2, &long),
            frame(3, "nul\\000.png"),
            frame(4, "four.png")
        ),
    )
    .unwrap();
    let (code, err) = render_code(&dir, &["s.rib", "--cpu"]);
    assert_eq!(code, 1, "{err}");
    assert!(
        err.contains("frame 2: the Display name \"dddd") && err.contains("more than the 255"),
        "{err}"
    );
    assert!(
        err.contains("frame 3: the Display name \"nul\\0.png\"") && err.contains("NUL byte"),
        "{err}"
    );
    assert!(dir.join("one.png").is_file() && dir.join("four.png").is_file());
    assert_eq!(err.matches("wrote").count(), 2, "{err}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Issue 24: 10 million identical bilinear patches in one frame (a 1.6 MB gzip, written as the
/// field's `hostile/many-patches-memory.gen.py` writes it: one compressed block of 100,000
/// requests repeated) are refused at the patch past the per-frame limit (2^22), at its line,
/// exit 1, nothing written, and `reyes render` holds at most 1 GiB on the way: a bilinear
/// patch is 176 bytes on the host, so the 2^22 patches held at the limit are 738 MB
/// (docs/reyes.md, *Limits*; the command peaked at 4 GB before the limit, ~600 bytes a patch).
#[test]
#[allow(unsafe_code)]
#[allow(clippy::zombie_processes)] // reaped by wait4, which gives its rusage
fn ten_million_patches_stop_at_the_frame_limit_within_a_memory_bound() {
    use flate2::{Compression, write::GzEncoder};
    use std::io::{Read, Write};
    let dir = scratch("ten-million");
    let gz = |s: &str| {
        let mut e = GzEncoder::new(Vec::new(), Compression::best());
        e.write_all(s.as_bytes()).unwrap();
        e.finish().unwrap()
    };
    let head = "Format 64 48 1\nProjection \"perspective\" \"fov\" [40]\nTranslate 0 0 5\n\
                WorldBegin\n";
    let block = gz(&"Patch \"bilinear\" \"P\" [-1 -1 0  1 -1 0  -1 1 0  1 1 0]\n".repeat(100_000));
    let mut file = gz(head);
    for _ in 0..100 {
        file.extend_from_slice(&block);
    }
    file.extend(gz("WorldEnd\n"));
    std::fs::write(dir.join("p.rib.gz"), file).unwrap();
    let mut child = Command::new(env!("CARGO_BIN_EXE_reyes"))
        .args(["render", "p.rib.gz", "--cpu", "-o", "p.png"])
        .current_dir(&dir)
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let mut err = String::new();
    child
        .stderr
        .take()
        .unwrap()
        .read_to_string(&mut err)
        .unwrap();
    // wait4: this child's own rusage (peak resident set in KiB on Linux), where
    // getrusage(RUSAGE_CHILDREN) would mix in the other tests' children.
    // SAFETY: rusage is plain integers (all-zero is valid); wait4 writes only the two
    // locals given, and reaps the child `Child` has not waited for.
    let (mut status, mut usage) = (0, unsafe { std::mem::zeroed::<libc::rusage>() });
    let pid = unsafe { libc::wait4(child.id() as i32, &mut status, 0, &mut usage) };
    assert_eq!(pid, child.id() as i32);
    assert!(libc::WIFEXITED(status), "{err}");
    assert_eq!(libc::WEXITSTATUS(status), 1, "{err}");
    // The header's 4 lines, then patch k (from 1) on line 4 + k: patch 2^22 + 1 on 4194309.
    assert!(
        err.contains("p.rib.gz:4194309: `Patch`: patch 0: more than 4194304 patches in one frame"),
        "{err}"
    );
    assert!(!dir.join("p.png").exists());
    let peak_mib = usage.ru_maxrss / 1024;
    assert!(peak_mib < 1024, "peak resident {peak_mib} MiB");
    eprintln!("10M patches: refused at the limit, peak resident {peak_mib} MiB");
}
