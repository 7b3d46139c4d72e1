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
        parse(&world(&format!("Scale 1e12 1e12 1e12\n{QUAD}")))
            .patches
            .len()
            == 1
    );
    let e = err(&world(&format!(
        "Scale 1e12 1e12 1e12\nScale 100 1 1\n\n{QUAD}"
    )));
    assert!(
        e.starts_with("t.rib:5: `Patch`: patch 0: control point 1"),
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

/// `Sphere 1e25 -1e25 1e25 360` around the camera (and `Hyperboloid 1e30 ...`) passed the f32
/// range check and never finished: the bound arithmetic squares and cubes coordinates. Now
/// every camera-space coordinate is at most `MAX_COORD`, checked at the primitive's line.
#[test]
fn coordinates_whose_squares_overflow_are_refused_at_the_line() {
    use crate::scene::rib::patches::MAX_COORD;
    assert_eq!(MAX_COORD, 1e12);
    assert!(((MAX_COORD * MAX_COORD * MAX_COORD * 3.0) as f32).is_finite());
    let e = err(&world("Sphere 1e25 -1e25 1e25 360"));
    assert!(
        e.starts_with("t.rib:2: `Sphere`: patch 0: control point ")
            && e.contains("coordinates at most ±1e12"),
        "{e}"
    );
    let e = err(&world("\nHyperboloid 1e30 0 -1 1e30 0 1 360"));
    assert!(e.starts_with("t.rib:3: `Hyperboloid`: patch 0:"), "{e}");
    // A large sphere inside the limit is fine.
    assert_eq!(parse(&world("Sphere 1e11 -1e11 1e11 360")).patches.len(), 8);
}

/// `DepthOfField 1e-15 1 5`: a lens radius of 5e14 made f32 rounding at the focal plane a
/// circle of confusion over the whole image (every pixel white). Refused at its line.
#[test]
fn a_lens_wider_than_the_limit_is_refused_at_its_line() {
    use crate::scene::rib::motion::MAX_LENS_RATIO;
    let e = err(&format!("\nDepthOfField 1e-15 1 5\n{}", world(QUAD)));
    assert!(
        e.starts_with("t.rib:2: `DepthOfField`: the lens radius")
            && e.contains(&format!("at most {MAX_LENS_RATIO}")),
        "{e}"
    );
    // The limit itself is taken: a lens radius of 100 focal distances.
    let s = parse(&format!("DepthOfField 0.005 1 1\n{}", world(QUAD)));
    assert!(s.camera.depth_of_field.is_some());
    assert!(err(&format!("DepthOfField 0.0049 1 1\n{}", world(QUAD))).contains("lens radius"));
}

/// A FIFO (or a folder) named as a displacement map blocked forever; only regular files are
/// read, and the error names the map and the line.
#[test]
fn a_map_that_is_not_a_regular_file_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::create_dir(dir.path().join("folder.png")).unwrap();
    let fifo = dir.path().join("fifo.png");
    let made_fifo = std::process::Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .is_ok_and(|s| s.success());
    let rib = dir.path().join("scene.rib");
    let mut names = vec!["folder.png"];
    if made_fifo {
        names.push("fifo.png");
    }
    for name in names {
        let text = world(&format!(
            "Displacement \"mapped\" \"mapname\" \"{name}\"\n{QUAD}"
        ));
        let e = parse_rib(&text, rib.to_str().unwrap())
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with(&format!("{}:2: `Displacement`:", rib.display()))
                && e.contains(&format!("{name} is not a regular file")),
            "{e}"
        );
    }
}

/// An EXR map with NaN texels drew 8 of ~1,500 pixels with no warning: it is refused, naming
/// the map, the first NaN texel and the line.
#[test]
fn a_map_with_nan_texels_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let exr = dir.path().join("nan.exr");
    let img = image::Rgb32FImage::from_fn(8, 8, |x, y| {
        image::Rgb(
            [if (x, y) == (3, 2) || y == 6 {
                f32::NAN
            } else {
                0.5
            }; 3],
        )
    });
    img.save(&exr).unwrap();
    let rib = dir.path().join("scene.rib");
    let text = world(&format!(
        "Displacement \"mapped\" \"mapname\" \"nan.exr\"\n{QUAD}"
    ));
    let e = parse_rib(&text, rib.to_str().unwrap())
        .unwrap_err()
        .to_string();
    assert!(
        e.starts_with(&format!("{}:2: `Displacement`:", rib.display()))
            && e.contains("nan.exr has a NaN texel at (3, 2)"),
        "{e}"
    );
}

/// `ReadArchive "/etc/shadow"` rendered and printed the start of every line as a warning. A
/// file whose first token is not a request name is refused with one error quoting none of it;
/// a skipped request is named alone, without its arguments.
#[test]
fn a_file_that_is_not_rib_is_refused_at_its_first_token() {
    let dir = tempfile::tempdir().unwrap();
    let secret = dir.path().join("shadow");
    std::fs::write(
        &secret,
        "root:*:19000:0:99999:7:::\ndaemon:*:19000:0:99999:7:::\n",
    )
    .unwrap();
    let rib = dir.path().join("scene.rib");
    std::fs::write(&rib, world("ReadArchive \"shadow\"")).unwrap();
    let e = load(&rib).unwrap_err().to_string();
    assert_eq!(
        e,
        format!(
            "{s}:1: {s} is not RIB: it does not start with a request name (a RIB file starts \
             with a request such as `version`, `Display` or `WorldBegin`, or a `#` comment)",
            s = secret.display()
        )
    );
    assert!(!e.contains("root") && !e.contains("daemon"), "{e}");
    // The scene file itself, and numbers or strings first, the same.
    let e = load(&secret).unwrap_err().to_string();
    assert!(e.contains("is not RIB") && !e.contains("root"), "{e}");
    assert!(err("\"secret\" WorldBegin").starts_with("t.rib:1: t.rib is not RIB"));
    // A request name is letters, digits and `_`: `a:b` is not one, anywhere.
    let e = err("WorldBegin\nWorldEnd\nroot:x");
    assert_eq!(
        e,
        "t.rib:3: `WorldEnd`: unexpected `root:x` (not a number or string)"
    );
    // An unknown request is named alone, not with its arguments or the rest of its line.
    let s = parse(&format!(
        "Frobnicate \"secret\" [1 2] -x junk:words\n{}",
        world("")
    ));
    assert_eq!(
        s.warnings,
        vec!["t.rib:1: skipped unsupported request `Frobnicate`"]
    );
}

/// Exporters' boilerplate: `version` says nothing; `ShadingRate`'s warning says what sets the
/// micropolygon size instead.
#[test]
fn version_is_silent_and_shading_rate_says_what_applies() {
    let s = crate::scene::parse_rib(
        "version 3.04\nShadingRate 4\nWorldBegin\nPatch \"bilinear\" \"P\" [0 0 5 1 0 5 0 1 5 1 1 5]\nWorldEnd\n",
        "boiler.rib",
    )
    .unwrap();
    assert_eq!(s.warnings.len(), 1, "{:?}", s.warnings);
    assert!(
        s.warnings[0].contains("boiler.rib:2") && s.warnings[0].contains("--mp-size"),
        "{:?}",
        s.warnings
    );
}

/// A misspelt request is still skipped with a warning, which names the request it was close to.
#[test]
fn a_misspelt_request_names_the_one_meant() {
    let s = crate::scene::parse_rib(
        "WorldBegin\nNuPach 2 2 [0 0 1 1] 0 1 2 2 [0 0 1 1] 0 1 \"P\" [0 0 5 1 0 5 0 1 5 1 1 5]\nHider \"hidden\"\nWorldEnd\n",
        "typo.rib",
    )
    .unwrap();
    assert!(
        s.warnings
            .iter()
            .any(|w| w.contains("typo.rib:2") && w.contains("did you mean `NuPatch`?")),
        "{:?}",
        s.warnings
    );
    assert!(
        s.warnings
            .iter()
            .all(|w| !w.contains("Hider") || !w.contains("did you mean")),
        "{:?}",
        s.warnings
    );
}

/// A misspelt shader or subdivision scheme is skipped with a warning that names the one meant;
/// an unknown name far from every known one gets no suggestion.
#[test]
fn misspelt_shader_and_scheme_names_suggest_the_one_meant() {
    let s = crate::scene::parse_rib(
        "WorldBegin\nSurface \"plastik\"\nDisplacement \"bumbs\"\nSurface \"wood\"\n\
         SubdivisionMesh \"catmul-clark\" [3] [0 1 2] [] [] [] [] \"P\" [0 0 5 1 0 5 0 1 5]\n\
         WorldEnd\n",
        "typo.rib",
    )
    .unwrap();
    for (line, meant) in [(2, "plastic"), (3, "bumps"), (5, "catmull-clark")] {
        assert!(
            s.warnings
                .iter()
                .any(|w| w.contains(&format!("typo.rib:{line}"))
                    && w.contains(&format!("did you mean \"{meant}\"?"))),
            "{meant}: {:?}",
            s.warnings
        );
    }
    assert!(
        s.warnings
            .iter()
            .any(|w| w.contains("typo.rib:4") && !w.contains("did you mean")),
        "{:?}",
        s.warnings
    );
}
