//! Hostile input: deep nesting, values beyond f32, range checks with their line, huge tokens.

use super::*;
use crate::scene::load;
use crate::scene::rib::state::MAX_NESTING;

fn field(name: &str) -> std::path::PathBuf {
    let p = crate::shared_data_dir().join("field/hostile").join(name);
    assert!(p.is_file(), "{} is missing", p.display());
    p
}

/// Millions of unclosed `AttributeBegin`: an error at the bound, read as a stream. The text
/// here has 10x the bound; the field generator's 4,000,000 levels fail the same way.
#[test]
fn deep_nesting_fails_at_a_bounded_depth() {
    let n = 10 * MAX_NESTING;
    let text = format!("WorldBegin\n{}", "AttributeBegin\n".repeat(n));
    let e = err(&text);
    let line = MAX_NESTING + 1; // WorldBegin is the first block
    assert_eq!(
        e,
        format!(
            "t.rib:{line}: `AttributeBegin`: blocks nested deeper than {} (the reader's limit; \
             is an `AttributeEnd` missing?)",
            MAX_NESTING
        )
    );
    // Balanced nesting up to the bound is fine.
    let depth = MAX_NESTING - 1;
    let ok = format!(
        "WorldBegin\n{}{QUAD}\n{}WorldEnd\n",
        "TransformBegin\n".repeat(depth),
        "TransformEnd\n".repeat(depth)
    );
    assert_eq!(parse(&ok).patches.len(), 1);
}

#[test]
fn values_beyond_f32_in_camera_space_name_the_patch_line() {
    let e = load(&field("f32-overflow.rib")).unwrap_err().to_string();
    assert!(e.contains("f32-overflow.rib:4: `Patch`: patch 0: control point 0 is [-1e200, -1e200, 5] in camera space, beyond the f32 range"), "{e}");
    // Just inside the range is accepted; the line is the primitive's.
    assert!(
        parse(&world(&format!("Scale 1e37 1e37 1e37\n{QUAD}")))
            .patches
            .len()
            == 1
    );
    let e = err(&world(&format!(
        "Scale 1e37 1e37 1e37\nScale 100 1 1\n\n{QUAD}"
    )));
    assert!(
        e.starts_with("t.rib:5: `Patch`: patch 0: control point 2"),
        "{e}"
    );
    // Colours and lights go to the GPU as f32 too.
    assert!(err(&world("Color [1e39 0 0]")).contains("beyond the f32 range"));
    assert!(
        err(&world("LightSource \"pointlight\" 1 \"from\" [1e39 0 0]"))
            .contains("beyond the f32 range")
    );
    assert!(err(&world("Surface \"plastic\" \"Ks\" 1e300")).contains("beyond the f32 range"));
}

#[test]
fn range_checks_name_the_file_and_line() {
    let e = load(&field("pixelsamples-17.rib")).unwrap_err().to_string();
    assert!(
        e.ends_with(
            "pixelsamples-17.rib:1: `PixelSamples`: sample count 17 is not in (0, 16] (the renderer's limit)"
        ),
        "{e}"
    );
    let side = crate::scene::MAX_IMAGE_SIDE;
    assert_eq!(
        err(&format!("\nFormat {} 10 1\n{}", side + 1, world(""))),
        format!(
            "t.rib:2: `Format`: the x resolution must be an integer in 1..={side}, found {}",
            side + 1
        )
    );
    assert!(parse(&format!("Format {side} 10 1\n{}", world(""))).width == side);
    assert!(
        err(&format!("Format 10 10 0\n{}", world(""))).contains("aspect ratio must be positive")
    );
    assert_eq!(
        err(&format!("\n\nClipping 0 10\n{}", world(""))),
        "t.rib:3: `Clipping`: need 1e-10 <= near < far, found near 0 far 10"
    );
    assert!(err(&format!("Clipping 1e-11 10\n{}", world(""))).contains("near < far"));
}

/// A 100 kB word: the warning quotes its first 64 characters and its length.
#[test]
fn huge_tokens_are_quoted_short() {
    let s = load(&field("huge-token.rib")).unwrap();
    let w = s.warnings.join("\n");
    assert!(w.len() < 300, "{w}");
    assert!(
        w.contains(&format!("skipped unsupported request `{}…", "A".repeat(64))),
        "{w}"
    );
    assert!(w.contains("bytes)`"), "{w}");
    let long = "x".repeat(10_000);
    for text in [
        world(&format!("Surface \"{long}\"")),
        format!("Projection \"{long}\" WorldBegin WorldEnd"),
        world(&format!("Translate 1 2 -{long}")),
        world(&format!("\"{long}\"")),
    ] {
        let msg = match parse_rib(&text, "t.rib") {
            Ok(s) => s.warnings.join("\n"),
            Err(e) => e.to_string(),
        };
        assert!(msg.len() < 300 && msg.contains("bytes)"), "{msg}");
    }
}
