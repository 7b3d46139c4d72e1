//! ReadArchive and gzip-compressed RIB.

use super::*;
use crate::scene::{load, load_frames};
use std::io::Write;
use std::path::{Path, PathBuf};

/// A fresh scratch folder for one test.
fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("reyes-rib-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn gzip(text: &str) -> Vec<u8> {
    let mut e = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::default());
    e.write_all(text.as_bytes()).unwrap();
    e.finish().unwrap()
}

fn load_err(p: &Path) -> String {
    load(p).expect_err("expected an error").to_string()
}

/// The field pair: a scene that reads the teapot's patches from a gzip archive beside it
/// gives the same scene as uteapot.rib's patches under the same camera.
#[test]
fn read_archive_rib_reads_the_gzip_archive_beside_it() {
    let field = crate::shared_data_dir().join("field");
    let path = field.join("read-archive.rib");
    assert!(path.is_file(), "{} is missing", path.display());
    let s = load(&path).unwrap();
    assert_eq!(s.patches.len(), 32);
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    let archive = field.join("teapot-patches.rib.gz").display().to_string();
    assert_eq!(*s.patches[5].source.file, archive);
    assert_eq!(s.patches[5].source.line, 7);
    // The archive itself, given as the scene, is read as RIB (a gzip file is never "binary
    // RIB"): its patches are outside a world block, which is what the error says.
    let e = load_err(&field.join("teapot-patches.rib.gz"));
    assert!(
        e.ends_with(
            "teapot-patches.rib.gz:2: `Patch`: geometry outside `WorldBegin` ... `WorldEnd`"
        ),
        "{e}"
    );
    // The same patches inline (uteapot.rib's camera and geometry) give the same points.
    let u = load(&crate::shared_data_dir().join("rib/uteapot.rib")).unwrap();
    assert!(close(s.patches[0].cp()[0], u.patches[0].cp()[0]));
}

#[test]
fn archives_beside_the_including_file_then_the_current_directory() {
    let d = scratch("paths");
    std::fs::create_dir_all(d.join("sub")).unwrap();
    std::fs::write(
        d.join("sub/inner.rib"),
        format!("# inner\nColor [0 1 0]\n{QUAD}\n"),
    )
    .unwrap();
    std::fs::write(
        d.join("sub/middle.rib.gz"),
        gzip("Translate 1 0 0\nReadArchive \"inner.rib\"\n"),
    )
    .unwrap();
    std::fs::write(
        d.join("scene.rib"),
        world(&format!("ReadArchive \"sub/middle.rib.gz\"\n{QUAD}")),
    )
    .unwrap();
    let s = load(&d.join("scene.rib")).unwrap();
    assert_eq!(s.patches.len(), 2);
    // The archive's transform stays in effect after it (an archive is read in place).
    assert!(close(s.patches[0].cp()[0], DVec3::X) && close(s.patches[1].cp()[0], DVec3::X));
    assert_eq!(s.materials[0].color, DVec3::new(0.0, 1.0, 0.0));
    assert!(s.patches[0].source.file.ends_with("sub/inner.rib"));
    assert_eq!(s.patches[0].source.line, 3);
    // A name relative to the current directory works when nothing is beside the file.
    let cwd_name = d.join("sub/inner.rib");
    let text = world(&format!("ReadArchive \"{}\"", cwd_name.display()));
    let s = parse_rib(&text, "nowhere/t.rib").unwrap();
    assert_eq!(s.patches.len(), 1);
    // Missing archives name what was looked for.
    let e = err(&world("\nReadArchive \"missing.rib\""));
    assert!(
        e.starts_with("t.rib:3: `ReadArchive`: cannot find the archive \"missing.rib\""),
        "{e}"
    );
}

#[test]
fn errors_inside_an_archive_name_the_archive_and_its_line() {
    let d = scratch("errors");
    std::fs::write(
        d.join("bad.rib.gz"),
        gzip("Color [1 0 0]\n\nTranslate 1 2\n"),
    )
    .unwrap();
    std::fs::write(d.join("scene.rib"), world("ReadArchive \"bad.rib.gz\"")).unwrap();
    let e = load_err(&d.join("scene.rib"));
    let archive = d.join("bad.rib.gz").display().to_string();
    assert_eq!(
        e,
        format!("{archive}:3: `Translate`: expected 3 numbers for the offset, found 2")
    );
    // An unclosed block in an archive is reported at the scene's end with the archive's line.
    std::fs::write(d.join("open.rib"), "\nAttributeBegin\n").unwrap();
    std::fs::write(d.join("scene2.rib"), world("ReadArchive \"open.rib\"")).unwrap();
    let e = load_err(&d.join("scene2.rib"));
    let open = d.join("open.rib").display().to_string();
    assert!(
        e.ends_with(&format!(
            "`WorldEnd` does not match `AttributeBegin` at {open}:2"
        )),
        "{e}"
    );
    // Binary RIB is still refused as such; corrupt gzip data is a read error, not binary RIB.
    std::fs::write(d.join("binary.rib"), b"WorldBegin \x81\x02").unwrap();
    assert!(load_err(&d.join("binary.rib")).contains("binary RIB is not supported"));
    let mut corrupt = gzip(&world(QUAD));
    corrupt.truncate(corrupt.len() / 2);
    std::fs::write(d.join("corrupt.rib"), corrupt).unwrap();
    let e = load_err(&d.join("corrupt.rib"));
    assert!(e.contains("cannot read") && !e.contains("binary"), "{e}");
}

#[test]
fn archive_cycles_and_depth_are_errors() {
    let d = scratch("cycles");
    std::fs::write(d.join("a.rib"), "ReadArchive \"b.rib\"\n").unwrap();
    std::fs::write(d.join("b.rib"), "\nReadArchive \"a.rib\"\n").unwrap();
    std::fs::write(d.join("scene.rib"), world("ReadArchive \"a.rib\"")).unwrap();
    let e = load_err(&d.join("scene.rib"));
    let (a, b) = (
        d.join("a.rib").display().to_string(),
        d.join("b.rib").display().to_string(),
    );
    assert_eq!(
        e,
        format!(
            "{b}:2: `ReadArchive`: archive cycle: {a} is already being read ({a} reads {b} reads {a})"
        )
    );
    // A file that reads itself.
    std::fs::write(d.join("self.rib"), world("ReadArchive \"self.rib\"")).unwrap();
    assert!(load_err(&d.join("self.rib")).contains("archive cycle"));
    // A chain deeper than the bound (each archive a different file).
    for k in 0..40 {
        std::fs::write(
            d.join(format!("n{k}.rib")),
            format!("ReadArchive \"n{}.rib\"\n", k + 1),
        )
        .unwrap();
    }
    std::fs::write(d.join("deep.rib"), world("ReadArchive \"n0.rib\"")).unwrap();
    let e = load_err(&d.join("deep.rib"));
    assert!(e.contains("archives nested deeper than 32"), "{e}");
    assert!(e.contains("n30.rib:1:"), "{e}");
}

/// Gzip-compressed scene files are read whatever their name, also as sequences.
#[test]
fn gzip_scene_files() {
    let d = scratch("gzip");
    let text = format!(
        "FrameBegin 1\n{}FrameEnd\nFrameBegin 2\n{}FrameEnd\n",
        world(QUAD),
        world(QUAD)
    );
    std::fs::write(d.join("seq.rib.gz"), gzip(&text)).unwrap();
    std::fs::write(d.join("seq.data"), gzip(&text)).unwrap();
    for name in ["seq.rib.gz", "seq.data"] {
        let seq = load_frames(&d.join(name)).unwrap();
        assert_eq!(seq.frames.len(), 2, "{name}");
    }
}
