//! Instances (`ObjectBegin` / `ObjectInstance`) through the whole pipeline: an instanced
//! scene renders, on every strategy and the CPU twin, the image of the same scene with the
//! object's requests written out at each instance, bit for bit (the reader places each
//! instance from one build through the arithmetic a build uses, so the patches are the same
//! bits; docs/reyes.md, *Instances*), from smaller tables. Runs on lavapipe in CI.

use reyes::cpu_render::render_cpu;
use reyes::frame::FrameData;
use reyes::scene::{self, Scene};

mod common;
use common::{render_everywhere, small};

/// A coloured bilinear patch, a sphere, a trimmed rational NuPatch with vertex colours, a
/// subdivided cube with face-varying colours and a polygon mesh with normals.
const OBJECT: &str = "\
AttributeBegin Color 0 1 0 Patch \"bilinear\" \"P\" [-1 -1 0 1 -1 0 -1 1 0 1 1 0] \
 \"varying color Cs\" [1 0 0 0 1 0 0 0 1 1 1 1] AttributeEnd
Translate 0 0 -1
Sphere 0.6 -0.6 0.6 360
TrimCurve [1] [3] [0 0 0 0.25 0.25 0.5 0.5 0.75 0.75 1 1 1] [0] [1] [9] \
 [0.5 0 0 0 0.5 0.707107 1 0.707107 0.5] [1 0.707107 0.5 0 0 0 0.5 0.707107 1] \
 [1 0.707107 1 0.707107 1 0.707107 1 0.707107 1]
NuPatch 3 3 [0 0 0 1 1 1] 0 1 2 2 [0 0 1 1] 0 1 \"Pw\" [-1 -1 0 1  0 -0.5 0 0.5  1 -1 0 1 \
 -1 1 -0.5 1  0 0.5 -0.25 0.5  1 1 -0.5 1] \"vertex color Cs\" [1 0 0 0 1 0 0 0 1 1 1 0 0 1 1 1 0 1]
Translate 0 1.5 0 Scale 0.4 0.4 0.4
SubdivisionMesh \"catmull-clark\" [4 4 4 4 4 4] [0 1 3 2 2 3 5 4 4 5 7 6 6 7 1 0 1 7 5 3 6 0 2 4] \
 \"P\" [-1 -1 1 1 -1 1 -1 1 1 1 1 1 -1 1 -1 1 1 -1 -1 -1 -1 1 -1 -1] \
 \"facevarying color Cs\" [1 0 0 1 0 0 1 0 0 1 0 0  0 1 0 0 1 0 0 1 0 0 1 0 \
 0 0 1 0 0 1 0 0 1 0 0 1  1 1 0 1 1 0 1 1 0 1 1 0  0 1 1 0 1 1 0 1 1 0 1 1 1 0 1 1 0 1 1 0 1 1 0 1]
PointsPolygons [4 3] [0 1 2 3 1 4 2] \"P\" [-2 -3 1.5  2 -3 1.5  2 -2 1.5  -2 -2 1.5  3 -3 1.5] \
 \"N\" [0 -0.5 1  0 -0.5 1  0.5 0 1  -0.5 0 1  1 0 1]
";

/// Four instances: coloured, mirrored and turned, one-sided and reversed, scaled.
const PLACEMENTS: &[&str] = &[
    "Translate -2.2 -1.2 0 Color 1 0.5 0.2",
    "Translate 2.2 -1.2 0 Rotate 40 0 1 0 Scale -1 1 1",
    "ReverseOrientation Sides 1 Translate -2.2 1.6 0 Rotate 30 1 0 0",
    "Surface \"plastic\" Translate 2.2 1.6 0 Scale 1.3 0.8 1",
];

/// The scene: the object at each placement, instanced or written out.
fn scene(instanced: bool) -> Scene {
    let mut s = String::from(
        "Format 96 72 1\nPixelSamples 2 2\nProjection \"perspective\" \"fov\" 50\n\
         Translate 0 0 8\nWorldBegin\nLightSource \"distantlight\" 1 \"from\" [0 0 0] \
         \"to\" [0.3 -0.4 1]\n",
    );
    if instanced {
        s += &format!("ObjectBegin \"thing\"\n{OBJECT}ObjectEnd\n");
    }
    for p in PLACEMENTS {
        let body = if instanced {
            "ObjectInstance \"thing\"".to_string()
        } else {
            format!("AttributeBegin\n{OBJECT}AttributeEnd")
        };
        s += &format!("AttributeBegin\n{p}\n{body}\nAttributeEnd\n");
    }
    scene::parse_rib(&(s + "WorldEnd\n"), "instances.rib").unwrap_or_else(|e| panic!("{e}"))
}

/// Every strategy and the CPU twin draw the instanced scene as the written-out one, bit for
/// bit, from smaller tables (one copy of the object's fields, weights and trims).
#[test]
fn instances_render_as_their_requests_written_out() {
    let o = small(96, 72);
    let inst = FrameData::new(&scene(true), &o).unwrap();
    let written = FrameData::new(&scene(false), &o).unwrap();
    assert_eq!(inst.items, written.items);
    assert!(
        inst.table_bytes() < written.table_bytes(),
        "{} against {}",
        inst.table_bytes(),
        written.table_bytes()
    );
    let a = render_everywhere(&inst).image;
    let b = render_everywhere(&written).image;
    assert!(a.covered_pixels() > 1500, "{}", a.covered_pixels());
    assert!(
        a == b,
        "GPU: the instanced image differs from the written-out one"
    );
    let (ca, cb) = (render_cpu(&inst).image, render_cpu(&written).image);
    assert!(ca == cb, "CPU twin: the instanced image differs");
}

/// The exporters' file (one sphere object, instanced on either side of the origin) still
/// renders both spheres, as its object written out at each instance does.
#[test]
fn the_exporters_instanced_spheres_render() {
    let path = reyes::shared_data_dir().join("field/exporters/object-instance.rib");
    let text = std::fs::read_to_string(&path).unwrap();
    let inst = scene::parse_rib(&text, "object-instance.rib").unwrap_or_else(|e| panic!("{e}"));
    let (begin, end) = (
        text.find("ObjectBegin 1").unwrap(),
        text.find("ObjectEnd").unwrap(),
    );
    let body = &text[begin + "ObjectBegin 1".len()..end];
    let written = text[..begin].to_string() + &text[end + "ObjectEnd".len()..];
    let written = written.replace(
        "ObjectInstance 1",
        &format!("AttributeBegin\n{body}\nAttributeEnd"),
    );
    let written = scene::parse_rib(&written, "written.rib").unwrap_or_else(|e| panic!("{e}"));
    let o = small(80, 60);
    let (a, b) = (
        FrameData::new(&inst, &o).unwrap(),
        FrameData::new(&written, &o).unwrap(),
    );
    assert_eq!(a.items, b.items);
    let image = render_everywhere(&a).image;
    assert!(image == render_everywhere(&b).image);
    // Two spheres: two separate runs of columns with coverage.
    let covered: Vec<bool> = (0..image.width as usize)
        .map(|x| {
            (0..image.height as usize).any(|y| image.rgba[y * image.width as usize + x][3] > 0.0)
        })
        .collect();
    let runs = covered.windows(2).filter(|w| !w[0] && w[1]).count() + covered[0] as usize;
    assert_eq!(runs, 2, "{covered:?}");
}
