//! Accuracy metrics on the GPU (speed against error): the GPU frame against the exact
//! f64 reference, `reyes measure` and `reyes sweep` end to end. Runs on lavapipe in CI; the
//! adapter comes from the environment and a missing one fails loudly.

use reyes::frame::{FrameData, RenderOptions};
use reyes::progress::NoProgress;
use reyes::scene::{self, Scene};
use reyes::stages::C_MICROPOLYGONS;
use reyes_accuracy::exact_image::render_reference;
use reyes_accuracy::geometry::geometry;
use reyes_accuracy::image_error::image_error;
use reyes_accuracy::measure::pinhole_count;
use scheduler::StrategyKind;
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::Command;

mod common;
use common::{gpu, renderer, small};

const BLOB: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes/closed_blob.rib");

fn blob() -> Scene {
    scene::load(Path::new(BLOB)).unwrap()
}

/// The metrics measure the GPU's micropolygons: the CPU twin's grids, which the geometry
/// metric reads, are as many as the GPU diced (the blob is all on screen and two-sided, so
/// every one is measured). At default settings the closed blob has no pinholes and a
/// sub-pixel geometric error, and more pixel samples bring the image closer to the reference.
#[test]
fn gpu_frame_against_the_exact_reference() {
    let s = blob();
    let (w, h) = (64, 48);
    let reference = render_reference(&s, w, h, 8, &NoProgress);
    let mut psnr = Vec::new();
    for spp in [(1, 1), (4, 4)] {
        let o = RenderOptions {
            pixel_samples: Some(spp),
            ..small(w, h)
        };
        let data = FrameData::new(&s, &o).unwrap();
        let g = renderer(StrategyKind::Megakernel)
            .render(gpu(), &data)
            .unwrap();
        let geom = geometry(&s, &data);
        assert_eq!(geom.micropolygons, g.counters[C_MICROPOLYGONS]);
        assert!(geom.err_max_px < 0.5, "{geom:?}");
        assert_eq!(pinhole_count(&g.image, &reference), 0);
        let e = image_error(&reference.image, &g.image);
        assert!(e.psnr_db.is_finite() && e.psnr_db > 20.0, "{e:?}");
        assert!(e.flip_mean > 0.0 && e.flip_mean < 0.1, "{e:?}");
        psnr.push(e.psnr_db);
    }
    assert!(
        psnr[1] > psnr[0] + 3.0,
        "PSNR 1x1 {} vs 4x4 {}",
        psnr[0],
        psnr[1]
    );
}

/// Pinholes are counted where the render leaves the exact silhouette's interior uncovered.
#[test]
fn a_hole_in_the_render_is_counted() {
    let s = blob();
    let (w, h) = (64, 48);
    let reference = render_reference(&s, w, h, 4, &NoProgress);
    let data = FrameData::new(&s, &small(w, h)).unwrap();
    let mut img = renderer(StrategyKind::Megakernel)
        .render(gpu(), &data)
        .unwrap()
        .image;
    assert_eq!(pinhole_count(&img, &reference), 0);
    let c = (h / 2 * w + w / 2) as usize;
    img.rgba[c][3] = 0.75;
    img.rgba[c + 1][3] = 0.0;
    assert_eq!(pinhole_count(&img, &reference), 2);
}

fn reyes(args: &[&str]) -> (String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_reyes"))
        .args(args)
        .env(
            "XDG_RUNTIME_DIR",
            std::env::var("XDG_RUNTIME_DIR").unwrap_or("/tmp".into()),
        )
        .output()
        .expect("run reyes");
    let (so, se) = (
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    );
    assert!(out.status.success(), "reyes {args:?} failed:\n{se}");
    (so, se)
}

#[test]
fn measure_prints_one_json_object_and_the_blob_has_no_pinholes() {
    let (out, _) = reyes(&[
        "measure",
        BLOB,
        "--width",
        "64",
        "--height",
        "48",
        "--ref-samples",
        "4",
        "--json",
    ]);
    assert_eq!(out.trim().lines().count(), 1, "{out}");
    let v: Value = serde_json::from_str(out.trim()).unwrap();
    assert_eq!(v["pinholes"], 0, "{v}");
    assert_eq!(v["scene"], "closed_blob");
    assert_eq!(v["settings"]["width"], 64);
    assert_eq!(v["settings"]["pixel_samples"], serde_json::json!([2, 2]));
    assert_eq!(
        v["reference"]["samples_per_pixel"],
        serde_json::json!([4, 4])
    );
    let num = |k: &str| {
        v[k].as_f64()
            .unwrap_or_else(|| panic!("{k} is not a number: {v}"))
    };
    assert!(num("geom_err_max_px") < 0.5);
    assert!(num("geom_err_p99_px") <= num("geom_err_max_px"));
    assert!(num("mp_edge_max_px") > 0.0 && num("mp_area_mean_px") > 0.0);
    assert!(num("micropolygons_per_covered_pixel") > 0.5);
    assert!(num("psnr_db") > 20.0);
    assert!((0.0..0.1).contains(&num("flip_mean")));
    assert!(num("wall_ms") > 0.0);
    assert!(v["gpu_ms"].is_null() || num("gpu_ms") > 0.0);
    // The typed report reads it back whole: no key more or less than MeasureReport's.
    let typed: reyes_accuracy::measure::MeasureReport = serde_json::from_value(v.clone()).unwrap();
    assert_eq!(serde_json::to_value(&typed).unwrap(), v);
    assert_eq!(typed.runs, 1);
    // Every key is documented in docs/reyes.md's table.
    let docs = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../../docs/reyes.md"))
        .unwrap();
    for key in v.as_object().unwrap().keys() {
        assert!(
            docs.contains(&format!("`{key}`")) || docs.contains(&format!("`{key}.")),
            "`{key}` is not in docs/reyes.md"
        );
    }
}

#[test]
fn sweep_writes_csv_markdown_and_plot() {
    let dir = std::env::temp_dir().join(format!("reyes-sweep-test-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let dir_s = dir.to_str().unwrap();
    reyes(&[
        "sweep",
        "--scenes",
        &format!("teapot,{BLOB}"),
        "--width",
        "48",
        "--height",
        "36",
        "--runs",
        "1",
        "--ref-samples",
        "4",
        "--mp-sizes",
        "1,4",
        "--samples",
        "1",
        "--out",
        dir_s,
    ]);
    let file = |n: &str| -> PathBuf { dir.join(n) };
    let csv = std::fs::read_to_string(file("sweep.csv")).unwrap();
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    for col in [
        "scene",
        "strategy",
        "mode",
        "mp_size_px",
        "bound_px",
        "pixel_samples",
        "gpu_ms",
        "gpu_ms_mad",
        "wall_ms",
        "geom_err_max_px",
        "geom_err_p99_px",
        "mp_edge_max_px",
        "mp_area_mean_px",
        "micropolygons_per_covered_pixel",
        "psnr_db",
        "flip_mean",
        "pinholes",
        "default",
        "pareto_geom",
        "pareto_flip",
    ] {
        assert!(header.contains(&col), "column {col} missing: {header:?}");
    }
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    // 2 scenes x (2 sizes + the fixed bound) x (1x1 + the scenes' default 2x2) x 2 strategies.
    assert_eq!(rows.len(), 2 * 3 * 2 * 2, "{csv}");
    for scene in ["teapot", "closed_blob"] {
        let mine: Vec<&Vec<&str>> = rows.iter().filter(|r| r[0] == scene).collect();
        let defaults: Vec<_> = mine
            .iter()
            .filter(|r| r[col("default")] == "true")
            .collect();
        assert_eq!(defaults.len(), 1, "{scene}: one default point");
        let d = defaults[0];
        assert_eq!(
            (
                d[col("strategy")],
                d[col("mp_size_px")],
                d[col("pixel_samples")]
            ),
            ("megakernel", "1", "2x2")
        );
        let geom: f64 = d[col("geom_err_max_px")].parse().unwrap();
        assert!(geom < 0.5, "{scene} default geom error {geom}");
        assert!(mine.iter().any(|r| r[col("pareto_geom")] == "true"));
        assert!(mine.iter().any(|r| r[col("pareto_flip")] == "true"));
        // Coarser dicing is less accurate.
        let at = |mp: &str| -> f64 {
            mine.iter()
                .find(|r| r[col("mp_size_px")] == mp)
                .map(|r| r[col("geom_err_max_px")].parse().unwrap())
                .unwrap()
        };
        assert!(at("4") > at("1"), "{scene}: {} vs {}", at("4"), at("1"));
    }
    let md = std::fs::read_to_string(file("sweep.md")).unwrap();
    assert!(md.contains("### teapot") && md.contains("### closed_blob"));
    assert!(md.contains("| strategy | dicing | samples |"));
    let png = image::open(file("sweep.png")).unwrap();
    assert!(png.width() >= 1000 && png.height() >= 800);
    let svg = std::fs::read_to_string(file("sweep.svg")).unwrap();
    assert!(svg.starts_with("<svg") && svg.contains("closed_blob: FLIP mean against time"));
    std::fs::remove_dir_all(&dir).unwrap();
}
