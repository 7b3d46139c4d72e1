//! Syntax errors, skipped requests, truncated and malformed input.

use super::*;
use glam::DVec3;

#[test]
fn one_warning_per_skipped_request_kind() {
    let s = parse(&format!(
        "set -x\nHider \"hidden\"\nHider \"zbuffer\"\nOption \"x\" \"y\" [1]\n{}",
        world(
            "Attribute \"a\" \"b\" [1]\nAttribute \"a\" \"d\" [2]\nPatch \"bilinear\" \"P\" [0 0 0 1 0 0 0 1 0 1 1 0] \"N\" [0 0 1 0 0 1 0 0 1 0 0 1]"
        )
    ));
    assert_eq!(
        s.warnings,
        vec![
            "t.rib:1: skipped unsupported request `set`",
            "t.rib:2: skipped unsupported request `Hider`",
            "t.rib:4: skipped unsupported request `Option`",
            "t.rib:6: skipped unsupported attribute \"a\"",
            "t.rib:8: ignored parameter \"N\" of `Patch`",
        ]
    );
    assert_eq!(s.patches.len(), 1);
}

#[test]
fn object_and_motion_blocks() {
    let s = parse(&world(&format!(
        "ObjectBegin 1\n{QUAD}\nObjectEnd\nMotionBegin [0 1]\nTranslate 1 0 0\nTranslate 5 0 0\nMotionEnd\n{QUAD}"
    )));
    assert_eq!(s.patches.len(), 1);
    assert!(close(s.patches[0].cp()[0], DVec3::X));
    // Shutter 0 0 (the default): the transform at time 0, no motion.
    assert!(s.patches[0].motion.is_none());
    // The object is defined, not drawn (no `ObjectInstance`): nothing is skipped.
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    assert!(err(&world("ObjectBegin 1")).contains("inside `ObjectBegin`"));
}

#[test]
fn truncated_files() {
    let full = world(&format!("AttributeBegin\n{QUAD}\nAttributeEnd"));
    let e = err(&full[..full.find("AttributeEnd").unwrap()]);
    assert_eq!(
        e,
        "t.rib:3: unexpected end of file inside `AttributeBegin` (line 2)"
    );
    let e = err(&full[..full.find(" 1 1 0]").unwrap()]);
    assert_eq!(
        e,
        "t.rib:3: unexpected end of file inside the array opened at line 3"
    );
    let e = err("WorldBegin\nDisplay \"x");
    assert_eq!(e, "t.rib:2: unterminated string");
    let e = err("Format 640 480 1\n");
    assert_eq!(
        e,
        "t.rib:1: no `WorldBegin` ... `WorldEnd` block in the file"
    );
}

#[test]
fn wrong_value_counts() {
    let (_, nums) = grid_numbers(4, 4);
    let short: Vec<&str> = nums.split(' ').collect();
    let e = err(&world(&format!(
        "\nPatch \"bicubic\" \"P\" [{}]",
        short[..47].join(" ")
    )));
    assert_eq!(
        e,
        "t.rib:3: `Patch`: \"P\" needs 48 numbers (16 points), found 47"
    );
    assert_eq!(
        err(&world("Translate 1 2")),
        "t.rib:2: `Translate`: expected 3 numbers for the offset, found 2"
    );
    assert_eq!(
        err("Format 1 2 3 4 WorldBegin WorldEnd"),
        "t.rib:1: `Format`: unexpected extra argument: number 4"
    );
    assert!(err(&world("Patch \"bicubic\"")).contains("missing the \"P\" parameter"));
    assert!(err(&world("Patch \"bicubic\" \"P\"")).contains("parameter \"P\" has no value"));
    assert!(err(&world("Patch \"biquadratic\" \"P\" [0 0 0]")).contains("\"biquadratic\""));
}

#[test]
fn non_numbers_where_numbers_are_expected() {
    assert_eq!(
        err(&world("Translate 1 \"a\" 3")),
        "t.rib:2: `Translate`: expected a number for the offset, found string \"a\""
    );
    assert_eq!(
        err(&world("Translate 1 2 3x")),
        "t.rib:2: `Translate`: unexpected `3x` (not a number or string)"
    );
    assert_eq!(
        err(&world(
            "Patch \"bilinear\" \"P\" [0 0 0 1 0 zero 0 1 0 1 1 0]"
        )),
        "t.rib:2: unexpected `zero` inside an array (not a number or string)"
    );
    assert_eq!(
        err(&world("Color [1 \"x\" 0]")),
        "t.rib:2: array mixes numbers and strings"
    );
    // A file must start with a request name (see `not_rib_is_refused_at_its_first_token`).
    assert!(err("42 WorldBegin WorldEnd").starts_with("t.rib:1: t.rib is not RIB"));
    assert_eq!(err("WorldBegin ] WorldEnd"), "t.rib:1: unexpected `]`");
    assert!(err(&world("Translate 1 2 3 -x")).contains("unexpected `-x`"));
}

#[test]
fn nan_and_inf_name_the_patch() {
    let e = err(&world(
        "Patch \"bilinear\" \"P\" [0 0 0 1 0 0 0 1 nan 1 1 0]",
    ));
    let p = DVec3::new(0.0, 1.0, f64::NAN);
    assert_eq!(
        e,
        format!("t.rib:2: `Patch`: patch 0: point 2 of \"P\" is NaN ({p})")
    );
    let (_, nums) = grid_numbers(7, 4);
    let mut v: Vec<String> = nums.split(' ').map(String::from).collect();
    v[3 * 5 + 2] = "inf".into(); // point (5, 0): in the second patch only
    let e = err(&world(&format!(
        "PatchMesh \"bicubic\" 7 \"nonperiodic\" 4 \"nonperiodic\" \"P\" [{}]",
        v.join(" ")
    )));
    assert!(
        e.starts_with("t.rib:2: `PatchMesh`: patch 1: point 5 of \"P\" is infinite ("),
        "{e}"
    );
    let e = err(&world(
        "Patch \"bilinear\" \"P\" [0 0 0 1 0 0 0 1 1e999 1 1 0]",
    ));
    assert!(e.contains("patch 0: point 2 of \"P\" is infinite"), "{e}");
    // Overflow on the way to camera space is caught as well.
    let e = err(&world(
        "Scale 1e300 1e300 1e300 Patch \"bilinear\" \"P\" [0 0 0 1e300 0 0 0 1 0 1 1 0]",
    ));
    assert!(e.contains("in camera space"), "{e}");
    // Non-finite transform arguments are rejected where they are given.
    assert!(err(&world("Translate nan 0 0")).contains("non-finite"));
}

#[test]
fn unbalanced_blocks() {
    assert_eq!(
        err("AttributeEnd\nWorldBegin WorldEnd"),
        "t.rib:1: `AttributeEnd` without a matching `AttributeBegin`"
    );
    assert_eq!(
        err(&world("AttributeEnd")),
        "t.rib:2: `AttributeEnd` does not match `WorldBegin` at line 1"
    );
    assert_eq!(
        err("WorldBegin\nAttributeBegin\nWorldEnd\n"),
        "t.rib:3: `WorldEnd` does not match `AttributeBegin` at line 2"
    );
    assert_eq!(
        err("WorldEnd"),
        "t.rib:1: `WorldEnd` without a matching `WorldBegin`"
    );
    assert!(
        err("TransformEnd WorldBegin WorldEnd").contains("without a matching `TransformBegin`")
    );
    assert!(
        err(&world("TransformBegin AttributeEnd"))
            .contains("`AttributeEnd` does not match `TransformBegin`")
    );
    assert!(err("FrameBegin 1 WorldBegin WorldEnd").contains("inside `FrameBegin`"));
    assert!(err(&world("WorldBegin")).contains("world blocks do not nest"));
    assert!(
        err("FrameBegin 1 WorldBegin WorldEnd WorldBegin WorldEnd FrameEnd")
            .contains("frame 1 already has a world block")
    );
    assert!(err("FrameBegin 1 FrameBegin 2").contains("frames do not nest"));
    assert!(err("WorldBegin FrameBegin 2").contains("not allowed inside `WorldBegin`"));
    assert!(err("FrameEnd").contains("without a matching `FrameBegin`"));
    assert!(err(QUAD).contains("outside `WorldBegin`"));
    assert!(err(&world("MotionEnd")).contains("without a matching `MotionBegin`"));
}

/// Mutated and truncated inputs never panic.
#[test]
fn no_panics_on_garbage() {
    let base = format!(
        "Format 64 48 1\nProjection \"perspective\" \"fov\" [30]\nTranslate 0 0 5\nScale 1 1 -1\n{}",
        world(&format!(
            "AttributeBegin\nBasis \"b-spline\" 1 \"catmull-rom\" 1\nColor [1 .5 .2]\nSurface \"plastic\"\n\
             LightSource \"distantlight\" 1 \"from\" [0 1 0] \"to\" [0 0 0]\n{QUAD}\n\
             PatchMesh \"bicubic\" 4 \"periodic\" 4 \"nonperiodic\" \"P\" [{}]\n{}\nAttributeEnd",
            grid_numbers(4, 4).1,
            super::patches::nu_patch(true, 1.0)
                .replace("WorldBegin", "")
                .replace("WorldEnd", "")
        ))
    );
    assert!(parse_rib(&base, "t.rib").is_ok());
    let bytes = base.as_bytes();
    let mut seed = 0x2545_f491_4f6c_dd1du64;
    let mut rnd = move || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        seed
    };
    let junk: &[&[u8]] = &[
        b"[",
        b"]",
        b"\"",
        b"-",
        b"nan",
        b"1e999",
        b"0",
        b"-1",
        b"AttributeEnd",
        b"#",
        b"\xff",
        b"Scale 0 0 0",
        b"999999999",
    ];
    for _ in 0..3000 {
        let mut m = bytes.to_vec();
        for _ in 0..1 + rnd() % 4 {
            let at = (rnd() as usize) % m.len();
            match rnd() % 3 {
                0 => m.truncate(at),
                1 => {
                    let j = junk[(rnd() as usize) % junk.len()];
                    m.splice(at..at, j.iter().copied());
                }
                _ => {
                    let n = ((rnd() % 8) as usize).min(m.len() - at);
                    m.drain(at..at + n);
                }
            }
            if m.is_empty() {
                break;
            }
        }
        let text = String::from_utf8_lossy(&m);
        let _ = parse_rib(&text, "fuzz.rib");
    }
}
