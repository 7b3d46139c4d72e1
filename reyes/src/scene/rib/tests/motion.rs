//! `Shutter`, `DepthOfField` and motion blocks (`motion.rs`).

use super::*;
use crate::scene::DepthOfField;

/// A patch emitted after a moving transform keeps its shutter-open points and the map to
/// its shutter-close points; later transforms apply at both times.
#[test]
fn motion_blocks_move_transforms() {
    let s = parse(&format!(
        "Shutter 0 1\n{}",
        world(&format!(
            "MotionBegin [0 1]\nTranslate 0 0 0\nTranslate 2 0 0\nMotionEnd\nScale 2 2 2\n{QUAD}"
        ))
    ));
    let p = &s.patches[0];
    assert!(close(p.cp()[15], DVec3::new(2.0, 2.0, 0.0)));
    let m = p.motion.as_deref().expect("moving");
    assert!(close(
        m.transform_point3(p.cp()[15]),
        DVec3::new(4.0, 2.0, 0.0)
    ));
    // The shutter half open: half way.
    let s = parse(&format!(
        "Shutter 0 0.5\n{}",
        world(&format!(
            "MotionBegin [0 1]\nTranslate 0 0 0\nTranslate 2 0 0\nMotionEnd\n{QUAD}"
        ))
    ));
    let m = s.patches[0].motion.as_deref().expect("moving");
    assert!(close(m.transform_point3(DVec3::ZERO), DVec3::X));
    // The shutter closed (the default, 0 0): the first time, no motion; and a block closed
    // by `TransformEnd` stops moving what follows.
    let s = parse(&world(&format!(
        "MotionBegin [0 1]\nTranslate 0 0 0\nTranslate 2 0 0\nMotionEnd\n{QUAD}"
    )));
    assert!(s.patches[0].motion.is_none());
    let s = parse(&format!(
        "Shutter 0 1\n{}",
        world(&format!(
            "TransformBegin\nMotionBegin [0 1]\nRotate 0 0 0 1\nRotate 90 0 0 1\nMotionEnd\n\
             {QUAD}\nTransformEnd\n{QUAD}"
        ))
    ));
    assert!(s.patches[0].motion.is_some() && s.patches[1].motion.is_none());
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
}

#[test]
fn motion_block_errors_name_the_line() {
    let block = |body: &str| err(&format!("Shutter 0 1\n{}", world(body)));
    let e = block("MotionBegin [0 1]\nTranslate 1 0 0\nMotionEnd");
    assert_eq!(
        e,
        "t.rib:5: `MotionEnd`: the motion block (`MotionBegin` at line 3) has 2 time(s) but 1 \
         request(s)"
    );
    let e =
        block("MotionBegin [0 1]\nTranslate 1 0 0\nTranslate 2 0 0\nTranslate 3 0 0\nMotionEnd");
    assert!(
        e.starts_with("t.rib:6:") && e.contains("has 2 time(s) and more"),
        "{e}"
    );
    let e = block("MotionBegin [0 1]\nTranslate 1 0 0\nScale 2 2 2\nMotionEnd");
    assert!(
        e.contains("one kind of request: `Scale` after `Translate`"),
        "{e}"
    );
    assert!(block("MotionBegin [1 0]\nMotionEnd").contains("the times must increase"));
    assert!(block("MotionBegin [0 1]\nMotionBegin [0 1]").contains("nested `MotionBegin`"));
    assert!(block("MotionEnd").contains("without a matching `MotionBegin`"));
    let e = err("Shutter 0 1\nWorldBegin\nMotionBegin [0 1]\nTranslate 1 0 0\n");
    assert!(
        e.contains("unexpected end of file inside `MotionBegin` (line 3)"),
        "{e}"
    );
}

/// Motion of anything but transforms keeps the first time, with a warning; camera motion (a
/// block before `WorldBegin`) moves every object by the camera's motion, in camera space.
#[test]
fn unsupported_motion_warns_and_keeps_the_first_time() {
    let s = parse(&format!(
        "Shutter 0 1\nMotionBegin [0 1]\nTranslate 0 0 1\nTranslate 0 0 2\nMotionEnd\n{}",
        world(&format!(
            "MotionBegin [0 1]\nColor 1 0 0\nColor 0 1 0\nMotionEnd\n{QUAD}"
        ))
    ));
    assert!(close(s.patches[0].cp()[0], DVec3::new(0.0, 0.0, 1.0)));
    let m = s.patches[0].motion.as_deref().expect("the camera's motion");
    assert!(close(
        m.transform_point3(s.patches[0].cp()[0]),
        DVec3::new(0.0, 0.0, 2.0)
    ));
    assert_eq!(s.warnings.len(), 1, "{:?}", s.warnings);
    assert!(s.warnings[0].contains("motion of `Color` is not supported"));
    // "world" space under a moving camera moves with the world.
    let s = parse(&format!(
        "Shutter 0 1\nMotionBegin [0 1]\nTranslate 0 0 1\nTranslate 0 0 2\nMotionEnd\n{}",
        world(&format!("CoordSysTransform \"world\"\n{QUAD}"))
    ));
    assert!(s.patches[0].motion.is_some());
}

#[test]
fn shutter_and_depth_of_field_options() {
    let s = parse(&format!(
        "Shutter 0.25 0.75\nDepthOfField 2.8 0.05 4\n{}",
        world("")
    ));
    assert_eq!(s.camera.shutter, (0.25, 0.75));
    assert_eq!(
        s.camera.depth_of_field,
        Some(DepthOfField {
            fstop: 2.8,
            focal_length: 0.05,
            focal_distance: 4.0
        })
    );
    let s = parse(&format!("DepthOfField 2 1 3\nDepthOfField\n{}", world("")));
    assert_eq!(s.camera.depth_of_field, None);
    assert_eq!(
        err("DepthOfField 2 0 4"),
        "t.rib:1: `DepthOfField`: the focal length must be positive and finite, found 0"
    );
    assert!(err("DepthOfField -1 1 4").contains("the f-stop must be positive"));
    assert!(err("DepthOfField 2 1 -4").contains("the focal distance must be positive"));
    assert!(err("DepthOfField 2 1").contains("the focal distance"));
    assert!(err("Shutter 1 0").contains("open <= close, found open 1 close 0"));
    assert!(err(&world("Shutter 0 1")).contains("not allowed inside `WorldBegin`"));
}
