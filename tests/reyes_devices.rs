//! Several devices in one process (`reyes render --devices`, `reyes bench --devices`,
//! `reyes devices`), on the one lavapipe adapter of the test machine: `--devices 0,0` opens
//! two logical devices on adapter 0 (each its own device and queue). The images must equal
//! one device's bit for bit (PNG bytes: the encoder is deterministic, so equal files mean
//! equal 8-bit pixels; the float EXR is compared too for the split frame), and the
//! statistics must show that both devices rendered (per-device frame and bucket counts).

mod cli;

use cli::reyes_in as reyes;
use std::path::{Path, PathBuf};

fn scratch(name: &str) -> PathBuf {
    cli::scratch("devices", name)
}

fn json(p: &Path) -> serde_json::Value {
    let text = std::fs::read_to_string(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
    serde_json::from_str(&text).unwrap()
}

fn bytes(p: &Path) -> Vec<u8> {
    std::fs::read(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

/// A four-frame RIB of teapot-free quads, each frame's quad elsewhere.
fn sequence(dir: &Path) -> &'static str {
    let quad = |x: f64| {
        format!(
            "Patch \"bicubic\" \"P\" [{a} -1 5 {b} -1 5 {c} -1 6 {d} -1 6  {a} -0.3 5 {b} -0.3 4 {c} -0.3 4 {d} -0.3 6  \
             {a} 0.3 5 {b} 0.3 4 {c} 0.3 4 {d} 0.3 6  {a} 1 5 {b} 1 5 {c} 1 6 {d} 1 6]",
            a = x - 1.0,
            b = x - 0.3,
            c = x + 0.3,
            d = x + 1.0
        )
    };
    let frames: String = (1..=4)
        .map(|n| {
            format!(
                "FrameBegin {n}\nWorldBegin\n{}\nWorldEnd\nFrameEnd\n",
                quad(-0.6 + 0.4 * n as f64)
            )
        })
        .collect();
    std::fs::write(dir.join("seq.rib"), format!("Format 48 32 1\n{frames}")).unwrap();
    "seq.rib"
}

#[test]
fn devices_lists_the_adapter_that_can_render() {
    let dir = scratch("list");
    let (code, out, err) = reyes(&dir, &["devices"]);
    assert_eq!(code, 0, "{err}");
    assert!(
        out.lines()
            .any(|l| l.starts_with("0: ") && l.ends_with("can render")),
        "{out}"
    );
    assert!(out.contains("--devices all: "), "{out}");
    let (code, _, err) = reyes(&dir, &["render", "--devices", "0,x"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("not an adapter index"), "{err}");
    let (code, _, err) = reyes(&dir, &["render", "--devices", "99", "-o", "x.png"]);
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("no adapter 99"), "{err}");
    assert!(!dir.join("x.png").exists());
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The frames of a sequence spread over two devices: each image equals the one-device
/// render, each frame's statistics name the device that rendered it, and both rendered.
#[test]
fn a_sequence_on_two_devices_equals_one_device_and_uses_both() {
    let dir = scratch("sequence");
    let scene = sequence(&dir);
    let one = [scene, "--gpu", "-o", "one.####.png"];
    let (code, _, err) = reyes(&dir, &[&["render"][..], &one].concat());
    assert_eq!(code, 0, "{err}");
    let two = [
        "render",
        scene,
        "--devices",
        "0,0",
        "-o",
        "two.####.png",
        "--stats",
        "two.####.json",
    ];
    let (code, _, err) = reyes(&dir, &two);
    assert_eq!(code, 0, "{err}");
    let mut slots = Vec::new();
    for n in 1..=4 {
        let name = |s: &str, ext: &str| dir.join(format!("{s}.000{n}.{ext}"));
        assert!(
            bytes(&name("one", "png")) == bytes(&name("two", "png")),
            "frame {n}"
        );
        let stats = json(&name("two", "json"));
        let devices = stats["devices"].as_array().expect("devices in --stats");
        assert_eq!(
            devices.len(),
            1,
            "frame {n}: one device renders a frame of a sequence"
        );
        assert_eq!(devices[0]["frames"], 1);
        slots.push(devices[0]["slot"].as_u64().unwrap());
    }
    slots.sort();
    slots.dedup();
    assert_eq!(slots, [0, 1], "both devices took frames");
    // Skip-existing is unchanged: a second run with --frames renders nothing.
    let again = [&two[..], &["--frames", "1-4"]].concat();
    let (code, _, err) = reyes(&dir, &again);
    assert_eq!(code, 0, "{err}");
    assert_eq!(err.matches("skipped").count(), 4, "{err}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// One frame split into buckets over two devices: the image (PNG and float EXR) equals one
/// device's bit for bit, and both devices rendered buckets that add up to the frame's.
#[test]
fn a_frame_split_over_two_devices_equals_one_device() {
    let dir = scratch("split");
    let size = ["--width", "160", "--height", "120"];
    let one = [
        &[
            "render", "teapot", "--gpu", "-o", "one.png", "--exr", "one.exr",
        ][..],
        &size,
    ]
    .concat();
    let (code, _, err) = reyes(&dir, &one);
    assert_eq!(code, 0, "{err}");
    let two = [
        &[
            "render",
            "teapot",
            "--devices",
            "0,0",
            "-o",
            "two.png",
            "--exr",
            "two.exr",
        ][..],
        &["--stats", "two.json"],
        &size,
    ]
    .concat();
    let (code, _, err) = reyes(&dir, &two);
    assert_eq!(code, 0, "{err}");
    assert!(bytes(&dir.join("one.png")) == bytes(&dir.join("two.png")));
    assert!(bytes(&dir.join("one.exr")) == bytes(&dir.join("two.exr")));
    let stats = json(&dir.join("two.json"));
    let devices = stats["devices"].as_array().expect("devices in --stats");
    assert_eq!(devices.len(), 2);
    let buckets: Vec<u64> = devices
        .iter()
        .map(|d| d["buckets"].as_u64().unwrap())
        .collect();
    assert!(
        buckets.iter().all(|&b| b > 0),
        "both devices rendered buckets: {buckets:?}"
    );
    assert_eq!(
        buckets.iter().sum::<u64>(),
        stats["buckets"].as_u64().unwrap()
    );
    // 120 rows in strips of 16 (four per device wanted: 15 rows, rounded up to 16): 8.
    assert_eq!(stats["buckets"], 8);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `reyes bench --devices 0,0`: every timed frame rendered once, shared between the devices.
#[test]
fn bench_on_two_devices_reports_each_device() {
    let dir = scratch("bench");
    let args = [
        "bench",
        "teapot",
        "--devices",
        "0,0",
        "--frames",
        "8",
        "--warmup",
        "1",
        "--turntable",
        "--width",
        "64",
        "--height",
        "48",
        "--json",
    ];
    let (code, out, err) = reyes(&dir, &args);
    assert_eq!(code, 0, "{err}");
    let report: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(report["frames"], 8);
    let devices = report["devices"].as_array().expect("devices in the report");
    assert_eq!(devices.len(), 2);
    let frames: u64 = devices.iter().map(|d| d["frames"].as_u64().unwrap()).sum();
    assert_eq!(frames, 8);
    assert!(report["fps"].as_f64().unwrap() > 0.0);
    let angles: Vec<f64> = (report["per_frame"].as_array().unwrap().iter())
        .map(|f| f["angle_deg"].as_f64().unwrap())
        .collect();
    let want: Vec<f64> = (0..8).map(|i| 45.0 * i as f64).collect();
    assert!(
        angles.iter().zip(&want).all(|(a, b)| (a - b).abs() < 1e-9),
        "{angles:?}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}
