//! Frame sequences: FrameBegin/FrameEnd, several worlds, Display, shadow passes.

use super::*;
use crate::scene::{FrameSequence, parse_rib_frames};

fn frames(s: &str) -> FrameSequence {
    parse_rib_frames(s, "t.rib").unwrap_or_else(|e| panic!("unexpected error: {e}"))
}

/// The field file: three frames of a turntable, a Display each, options set before the
/// first frame shared by all, the camera transform set inside each frame.
#[test]
fn three_frames_rib() {
    let path = crate::shared_data_dir().join("field/three-frames.rib");
    assert!(path.is_file(), "{} is missing", path.display());
    let seq = crate::scene::load_frames(&path).unwrap();
    assert_eq!(seq.frames.len(), 3);
    for (k, f) in seq.frames.iter().enumerate() {
        let n = k as u32 + 1;
        assert_eq!(f.number, n);
        let d = f.display.as_ref().unwrap();
        assert_eq!(
            (d.name.as_str(), d.kind.as_str(), d.mode.as_str()),
            (format!("teapot.000{n}.png").as_str(), "file", "rgba")
        );
        assert!(f.unsupported.is_none());
        assert_eq!((f.scene.width, f.scene.height), (320, 200));
        assert_eq!(f.scene.pixel_samples, (2, 2));
        assert_eq!(f.scene.camera.fov_deg, 25.0);
        assert_eq!(f.scene.patches.len(), 32);
        assert_eq!(f.scene.lights.len(), 2);
        assert!(f.scene.warnings.is_empty());
    }
    // The same teapot, turned 30 degrees more about the world z axis in each frame: the
    // camera-space distance between corresponding points of frames 1 and 2 equals the one
    // between frames 2 and 3, and is not zero.
    let p = |f: usize| seq.frames[f].scene.patches[0].cp[0];
    let (d12, d23) = (p(0).distance(p(1)), p(1).distance(p(2)));
    assert!(d12 > 1.0 && (d12 - d23).abs() < 1e-9, "{d12} {d23}");
    // A single-image consumer takes frame 1 and is told.
    let s = seq.into_scene();
    assert!(
        s.warnings
            .iter()
            .any(|w| w.contains("3 frames: using frame 1")),
        "{:?}",
        s.warnings
    );
}

#[test]
fn frame_blocks_save_and_restore_options_and_attributes() {
    let seq = frames(&format!(
        "Format 100 50 1\nTranslate 0 0 5\nColor [1 0 0]\n\
         FrameBegin 7\nFormat 30 20 1\nDisplay \"a.tif\" \"file\" \"rgb\"\nTranslate 1 0 0\n{}FrameEnd\n\
         FrameBegin 9\n{}FrameEnd\n",
        world(QUAD),
        world(QUAD)
    ));
    let [a, b] = [&seq.frames[0], &seq.frames[1]];
    assert_eq!((a.number, b.number), (7, 9));
    assert_eq!((a.scene.width, a.scene.height), (30, 20));
    assert_eq!(
        (b.scene.width, b.scene.height),
        (100, 50),
        "FrameEnd restores the options"
    );
    assert_eq!(a.display.as_ref().unwrap().name, "a.tif");
    assert!(b.display.is_none(), "a frame's Display stays in it");
    assert!(close(a.scene.patches[0].cp[0], DVec3::new(1.0, 0.0, 5.0)));
    assert!(
        close(b.scene.patches[0].cp[0], DVec3::new(0.0, 0.0, 5.0)),
        "FrameEnd restores the transform"
    );
    // Attributes set before the frames apply to both; materials are per frame.
    for f in [a, b] {
        assert_eq!(f.scene.materials.len(), 1);
        assert_eq!(f.scene.materials[0].color, DVec3::new(1.0, 0.0, 0.0));
        assert_eq!(f.scene.patches[0].material, 0);
    }
}

#[test]
fn worlds_outside_frames_are_frames_numbered_on() {
    let seq = frames(&format!(
        "Display \"x.png\" \"file\" \"rgb\"\n{}FrameBegin 5\n{}FrameEnd\n{}",
        world(QUAD),
        world(""),
        world(&format!("{QUAD}\n{QUAD}"))
    ));
    let numbers: Vec<u32> = seq.frames.iter().map(|f| f.number).collect();
    assert_eq!(numbers, [1, 5, 6]);
    let patches: Vec<usize> = seq.frames.iter().map(|f| f.scene.patches.len()).collect();
    assert_eq!(patches, [1, 0, 2]);
    assert!(
        seq.frames
            .iter()
            .all(|f| f.display.as_ref().unwrap().name == "x.png")
    );
}

#[test]
fn shadow_passes_are_marked_not_rendered() {
    let seq = frames(&format!(
        "FrameBegin 1\nDisplay \"s.z\" \"zfile\" \"z\"\n{}FrameEnd\n\
         FrameBegin 2\nDisplay \"m.shd\" \"shadow\" \"z\"\n{}FrameEnd\n\
         FrameBegin 3\n{}\nMakeShadow \"a.z\" \"a.shd\"\nFrameEnd\n\
         FrameBegin 4\nDisplay \"+extra.tif\" \"file\" \"rgb\"\n{}FrameEnd\n",
        world(QUAD),
        world(QUAD),
        world(QUAD),
        world(QUAD)
    ));
    let why: Vec<Option<&str>> = seq
        .frames
        .iter()
        .map(|f| f.unsupported.as_deref())
        .collect();
    assert!(
        why[0].unwrap().contains("`Display` type \"zfile\""),
        "{why:?}"
    );
    assert!(why[1].unwrap().contains("\"shadow\""), "{why:?}");
    assert!(why[2].unwrap().contains("`MakeShadow` at line"), "{why:?}");
    assert_eq!(why[3], None);
    assert!(
        seq.frames[3].display.is_none(),
        "a + display adds, not replaces"
    );
    assert!(
        seq.warnings
            .iter()
            .any(|w| w.contains("skipped an additional `Display`"))
    );
    // A single-image consumer takes the first frame that can be rendered.
    let s = seq.into_scene();
    assert!(s.warnings.iter().any(|w| w.contains("using frame 4")));
}

#[test]
fn frame_errors() {
    assert!(err("FrameBegin 1.5 WorldBegin WorldEnd FrameEnd").contains("integer"));
    assert!(err("FrameBegin -1 WorldBegin WorldEnd FrameEnd").contains("integer"));
    assert_eq!(
        err("FrameBegin 1\nWorldBegin\nWorldEnd\n"),
        "t.rib:3: unexpected end of file inside `FrameBegin` (line 1)"
    );
    assert_eq!(
        err("FrameBegin 1\nFrameEnd\n"),
        "t.rib:2: no `WorldBegin` ... `WorldEnd` block in the file"
    );
    assert!(err("Display \"x\" \"file\" WorldBegin WorldEnd").contains("missing the display mode"));
}
