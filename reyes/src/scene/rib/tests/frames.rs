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
    let p = |f: usize| seq.frames[f].scene.patches[0].cp()[0];
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
    assert!(close(a.scene.patches[0].cp()[0], DVec3::new(1.0, 0.0, 5.0)));
    assert!(
        close(b.scene.patches[0].cp()[0], DVec3::new(0.0, 0.0, 5.0)),
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

/// The frames of `text` as a stream.
fn stream(text: &str) -> crate::scene::RibFrames<'_> {
    super::super::RibFrames::new(super::super::Reader::new(
        Box::new(text.as_bytes()),
        "t.rib",
        None,
    ))
}

const FARM_QUAD: &str = "Patch \"bilinear\" \"P\" [-1 -1 5  1 -1 5  -1 1 5  1 1 5]";

/// An error inside a frame block is that frame's: the frames after it still come, with the
/// options the file set before the frames (not those the broken frame set).
#[test]
fn a_frame_after_a_broken_one_is_still_delivered() {
    let text = format!(
        "Format 32 24 1\nFrameBegin 1\nWorldBegin\n{FARM_QUAD}\nWorldEnd\nFrameEnd\n\
         FrameBegin 2\nFormat 64 48 1\nWorldBegin\nAttributeBegin\nPatch \"bilinear\" \"P\" [1 2]\n\
         AttributeEnd\nWorldEnd\nFrameEnd\n\
         FrameBegin 3\nWorldBegin\n{FARM_QUAD}\nWorldEnd\nFrameEnd\n"
    );
    let items: Vec<_> = stream(&text).collect();
    assert_eq!(items.len(), 3);
    let one = items[0].as_ref().unwrap();
    assert_eq!((one.number, one.scene.patches.len()), (1, 1));
    let e = items[1].as_ref().unwrap_err();
    assert_eq!(e.number, Some(2));
    assert_eq!(e.error.line, 11);
    assert!(e.to_string().starts_with("frame 2: t.rib:11: "), "{e}");
    let three = items[2].as_ref().unwrap();
    assert_eq!(three.number, 3);
    assert_eq!((three.scene.width, three.scene.height), (32, 24));
    assert_eq!(three.scene.patches.len(), 1);
    // The whole-sequence reader still fails on the first error.
    let e = parse_rib_frames(&text, "t.rib").unwrap_err();
    assert_eq!(e.line, 11);
    // An error at `FrameEnd` itself skips nothing after it; one outside a frame block ends
    // the stream.
    let text = format!(
        "FrameBegin 1\nWorldBegin\n{FARM_QUAD}\nFrameEnd\nFrameBegin 2\nWorldBegin\n{FARM_QUAD}\nWorldEnd\nFrameEnd\n"
    );
    let items: Vec<_> = stream(&text).collect();
    assert_eq!(items[0].as_ref().unwrap_err().number, Some(1));
    assert_eq!(items[1].as_ref().unwrap().number, 2);
    let items: Vec<_> = stream(&format!(
        "AttributeEnd\nWorldBegin\n{FARM_QUAD}\nWorldEnd\n"
    ))
    .collect();
    assert_eq!(items.len(), 1);
    assert_eq!(items[0].as_ref().unwrap_err().number, None);
}

/// A stream reads only as far as the frame it delivers and holds no frame once it has
/// handed it over: the frames of an endless input come one by one, each dropped by the
/// caller, however many are read.
#[test]
fn frames_stream_one_at_a_time() {
    /// Frame after frame, without end.
    struct Endless {
        next: u32,
        buf: Vec<u8>,
        at: usize,
    }
    impl std::io::Read for Endless {
        fn read(&mut self, out: &mut [u8]) -> std::io::Result<usize> {
            if self.at == self.buf.len() {
                self.next += 1;
                self.buf = format!(
                    "FrameBegin {}\nDisplay \"f.{:04}.tif\" \"file\" \"rgba\"\nWorldBegin\n{FARM_QUAD}\nWorldEnd\nFrameEnd\n",
                    self.next, self.next
                )
                .into_bytes();
                self.at = 0;
            }
            let n = out.len().min(self.buf.len() - self.at);
            out[..n].copy_from_slice(&self.buf[self.at..self.at + n]);
            self.at += n;
            Ok(n)
        }
    }
    let src = Endless {
        next: 0,
        buf: Vec::new(),
        at: 0,
    };
    let mut s =
        super::super::RibFrames::new(super::super::Reader::new(Box::new(src), "e.rib", None));
    let selected = 500;
    let mut kept = None;
    for item in s.by_ref().take(selected as usize) {
        let f = item.unwrap();
        if f.number == selected {
            kept = Some(f);
        }
    }
    assert_eq!(s.held(), 0);
    let f = kept.unwrap();
    assert_eq!(f.display.unwrap().name, "f.0500.tif");
    assert_eq!(f.scene.patches.len(), 1);
}
