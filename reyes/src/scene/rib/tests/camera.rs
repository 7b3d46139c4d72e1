//! The window requests (`ScreenWindow`, `FrameAspectRatio`, `CropWindow`), orthographic
//! projection, `Format` with pixel aspect -1, camera matrices projective by round-off,
//! `CoordinateSystem` / `CoordSysTransform` and `Imager`: where a camera-space point lands
//! on the image, computed here from RenderMan's definitions.

use super::*;
use crate::scene::{Patch, load};

/// Raster position (pixels, y down) of camera-space `p`, as the renderer projects.
fn raster(s: &Scene, p: DVec3) -> (f64, f64) {
    let (w, h) = (s.width as f64, s.height as f64);
    let f = w.min(h) / 2.0 / (s.camera.fov_deg.to_radians() / 2.0).tan();
    (w / 2.0 + f * p.x / p.z, h / 2.0 - f * p.y / p.z)
}

/// A tiny bilinear patch around `c` (object space): its first corner is `c`.
fn dot_at(c: DVec3) -> String {
    let q = |dx: f64, dy: f64| format!("{} {} {}", c.x + dx, c.y + dy, c.z);
    format!(
        "Patch \"bilinear\" \"P\" [{} {} {} {}]\n",
        q(0.0, 0.0),
        q(0.01, 0.0),
        q(0.0, 0.01),
        q(0.01, 0.01)
    )
}

fn first_corner(p: &Patch) -> DVec3 {
    p.cp()[0]
}

fn near(a: (f64, f64), b: (f64, f64), tol: f64) -> bool {
    (a.0 - b.0).abs() <= tol && (a.1 - b.1).abs() <= tol
}

#[test]
fn k3d_screen_window_frames_like_its_field_of_view() {
    let dir = crate::shared_data_dir().join("field/exporters");
    let a = load(&dir.join("screenwindow-k3d.rib")).unwrap_or_else(|e| panic!("{e}"));
    let b = load(&dir.join("screenwindow-k3d-as-fov.rib")).unwrap_or_else(|e| panic!("{e}"));
    assert!(
        (a.camera.fov_deg - b.camera.fov_deg).abs() < 1e-3,
        "{} vs {}",
        a.camera.fov_deg,
        b.camera.fov_deg
    );
    assert_eq!(a.patches.len(), b.patches.len());
    for (p, q) in a.patches.iter().zip(&b.patches) {
        assert_eq!(p.cp(), q.cp());
    }
    // CropWindow 0 1 0 1 is the whole image; the imager's background is named.
    assert_eq!((a.width, a.height), (320, 240));
    assert!(
        !a.warnings
            .iter()
            .any(|w| w.contains("ScreenWindow") || w.contains("CropWindow"))
    );
    assert!(
        a.warnings
            .iter()
            .any(|w| w.contains("Imager") && w.contains("[1 1 1]")),
        "{:?}",
        a.warnings
    );
    // K-3D's imager "sample_buster" with "bgcolor" [1 1 1] is a background imager under its
    // own name: the image is composited over white, as the field README expects.
    assert_eq!(a.background, Some(DVec3::ONE));
    assert_eq!(b.background, Some(DVec3::ONE));
}

/// An imager shader that is not built in: with a "bgcolor" or "background" colour it is read
/// as the background imager; without one it is skipped and the background stays transparent.
#[test]
fn unknown_imagers_with_a_background_colour_composite_over_it() {
    let scene = |imager: &str| {
        crate::scene::parse_rib(
            &format!(
                "{imager}\nWorldBegin\nPatch \"bilinear\" \"P\" [0 0 5 1 0 5 0 1 5 1 1 5]\nWorldEnd\n"
            ),
            "imager.rib",
        )
        .unwrap()
    };
    let s = scene(r#"Imager "MOSAICbackground" "color bgcolor" [0.2 0.4 0.6]"#);
    assert_eq!(s.background, Some(DVec3::new(0.2, 0.4, 0.6)));
    assert!(
        s.warnings
            .iter()
            .any(|w| w.contains("MOSAICbackground") && w.contains("background imager")),
        "{:?}",
        s.warnings
    );
    let s = scene(r#"Imager "vignette" "float strength" [0.5]"#);
    assert_eq!(s.background, None);
    assert!(
        s.warnings
            .iter()
            .any(|w| w.contains(r#"skipped unsupported request `Imager` "vignette""#)),
        "{:?}",
        s.warnings
    );
}

#[test]
fn off_centre_screen_window_maps_onto_the_image() {
    // Screen window [0, 1] x [0, 1] at fov 90: screen (x/z, y/z) = (0.5, 0.5) is the centre of
    // a 100 x 100 image, (0, 1) its top left corner.
    for (p, want) in [
        (DVec3::new(1.0, 1.0, 2.0), (50.0, 50.0)),
        (DVec3::new(0.0, 3.0, 3.0), (0.0, 0.0)),
        (DVec3::new(2.0, 0.0, 2.0), (100.0, 100.0)),
    ] {
        let s = parse(&format!(
            "Format 100 100 1 Projection \"perspective\" ScreenWindow 0 1 0 1\n{}",
            world(&dot_at(p))
        ));
        let got = raster(&s, first_corner(&s.patches[0]));
        assert!(near(got, want, 1e-9), "{p}: {got:?} vs {want:?}");
        assert!(
            s.warnings.iter().any(|w| w.contains("shading")),
            "{:?}",
            s.warnings
        );
    }
    // FrameAspectRatio 2 on a square image: the default window [-2, 2] x [-1, 1] squeezed in.
    let s = parse(&format!(
        "Format 100 100 1 FrameAspectRatio 2\n{}",
        world(&dot_at(DVec3::new(2.0, 1.0, 1.0)))
    ));
    assert!(near(
        raster(&s, first_corner(&s.patches[0])),
        (100.0, 0.0),
        1e-9
    ));
}

#[test]
fn crop_window_renders_its_part_of_the_image() {
    // Format 200 x 100 at fov 90: screen x in [-2, 2]; the crop keeps x from 0.5 to 1 (pixels
    // 100..199) and y from 0 to 0.5 (rows 0..49).
    let s = parse(&format!(
        "Format 200 100 1 CropWindow 0.5 1 0 0.5\n{}",
        world(&dot_at(DVec3::new(1.0, 0.5, 1.0)))
    ));
    assert_eq!((s.width, s.height), (100, 50));
    // Full image: (100 + 50 * 1, 50 - 50 * 0.5) = (150, 25); cropped: (50, 25).
    assert!(near(
        raster(&s, first_corner(&s.patches[0])),
        (50.0, 25.0),
        1e-9
    ));
    let e = err(&format!("CropWindow 0.5 0.2 0 1\n{}", world("")));
    assert!(
        e.contains("t.rib:1:") && e.contains("0 <= min < max <= 1"),
        "{e}"
    );
}

#[test]
fn orthographic_projection_is_parallel_within_its_tolerance() {
    // Orthographic, default window [-1, 1]^2 on 200 x 200: raster = (100 + 100 x, 100 - 100 y)
    // whatever the depth.
    let dots: String = [(0.5, 0.5, 1.0), (0.5, 0.5, 9.0), (-0.9, 0.2, 5.0)]
        .iter()
        .map(|&(x, y, z)| dot_at(DVec3::new(x, y, z)))
        .collect();
    let s = parse(&format!(
        "Format 200 200 1 Projection \"orthographic\"\n{}",
        world(&dots)
    ));
    for (p, want) in s
        .patches
        .iter()
        .zip([(150.0, 50.0), (150.0, 50.0), (10.0, 80.0)])
    {
        let got = raster(&s, first_corner(p));
        // The module's bound: 1/2000 of the offset from the image centre (here <= 0.05 px).
        assert!(near(got, want, 0.05), "{got:?} vs {want:?}");
        assert!(first_corner(p).z > s.camera.near);
    }
    // The exporters' file renders (its objects are instances, its Cylinders quadrics).
    let path = crate::shared_data_dir().join("field/exporters/orthographic.rib");
    let s = load(&path).unwrap_or_else(|e| panic!("{e}"));
    assert!(!s.patches.is_empty());
    assert!(
        !s.warnings
            .iter()
            .any(|w| w.contains("ObjectBegin") || w.contains("PointsGeneralPolygons")),
        "{:?}",
        s.warnings
    );
}

#[test]
fn format_pixel_aspect_minus_one_is_one() {
    let s = parse(&format!("Format 200 150 -1\n{}", world("")));
    assert_eq!((s.width, s.height), (200, 150));
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    let s = parse(&format!("Format 200 150 2\n{}", world("")));
    assert!(
        s.warnings
            .iter()
            .any(|w| w.contains("pixel aspect ratio 2")),
        "{:?}",
        s.warnings
    );
    let path = crate::shared_data_dir().join("field/exporters/trimcurve-format-minus-one.rib");
    let s = load(&path).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!((s.width, s.height), (200, 150));
    // Its `TrimCurve` trims the NuPatch (tests/reyes_trim_camera.rs renders the disc).
    assert!(
        !s.warnings.iter().any(|w| w.contains("TrimCurve")),
        "{:?}",
        s.warnings
    );
    assert!(s.patches.iter().all(|p| p.trim.is_some()));
}

#[test]
fn camera_matrix_projective_only_by_round_off_is_affine() {
    let m = |e: &str| {
        format!(
            "Transform [1 0 0 {e}  0 1 0 0  0 0 1 0  0 0 5 1]\n{}",
            world(&dot_at(DVec3::ZERO))
        )
    };
    let s = parse(&m("1e-12"));
    assert!(close(
        first_corner(&s.patches[0]),
        DVec3::new(0.0, 0.0, 5.0)
    ));
    let e = err(&m("1e-3"));
    assert!(e.contains("projective"), "{e}");
}

#[test]
fn coordinate_systems_are_named_and_restored() {
    let path = crate::shared_data_dir().join("field/exporters/coordsys.rib");
    let s = load(&path).unwrap_or_else(|e| panic!("{e}"));
    assert!(
        !s.warnings
            .iter()
            .any(|w| w.contains("CoordSys") || w.contains("CoordinateSystem")),
        "{:?}",
        s.warnings
    );
    // Two unit spheres at world x = 2 and 0, then the cylinder in "def" (x = 2): camera z = 5.
    let cyl = s
        .patches
        .iter()
        .filter(|p| p.source.line == s.patches.last().unwrap().source.line);
    let (lo, hi) = cyl
        .flat_map(|p| p.cp())
        .fold((DVec3::MAX, DVec3::MIN), |(lo, hi), p| {
            (lo.min(p), hi.max(p))
        });
    assert!(
        close((lo + hi) / 2.0, DVec3::new(2.0, 0.0, 5.0)),
        "{lo} {hi}"
    );
    // Predefined names, and an unknown one.
    let s = parse(&format!(
        "Translate 0 0 5\n{}",
        world(&format!(
            "Translate 1 0 0 CoordSysTransform \"world\" {}",
            dot_at(DVec3::ZERO)
        ))
    ));
    assert!(close(
        first_corner(&s.patches[0]),
        DVec3::new(0.0, 0.0, 5.0)
    ));
    let e = err(&world("CoordSysTransform \"nowhere\""));
    assert!(
        e.contains("t.rib:2:") && e.contains("no coordinate system \"nowhere\""),
        "{e}"
    );
}

/// Skipped requests that change the picture say what the image lacks.
#[test]
fn skipped_requests_say_what_the_image_lacks() {
    let s = parse(&format!(
        "PixelFilter \"gaussian\" 2 2\nExposure 1 2.2\n{}",
        world("Matte 1\n")
    ));
    let w = s.warnings.join("\n");
    assert!(
        w.contains("`PixelFilter`: each pixel is the plain mean"),
        "{w}"
    );
    assert!(w.contains("`Exposure`: no gain or gamma"), "{w}");
    assert!(
        w.contains("`Matte`: the object is drawn as an ordinary surface"),
        "{w}"
    );
}
