//! Polygon meshes through the whole pipeline: a planar mesh of quads, triangles, a six-sided
//! face, a face with a hole and the polygon filling that hole covers exactly the square it
//! tiles (no pinhole along any shared edge, coverage as the exact reference and as the
//! square's own projected area), every strategy gives the same image and the CPU twin
//! agrees. Runs on lavapipe in CI.

use reyes::frame::{FrameData, RenderOptions};
use reyes::scene::{self, Scene};

mod common;
use common::render_everywhere;

/// A 4 x 4 grid of points over [-1.5, 1.5]² at depth 4 (fov 45, 160 x 120), tiled by faces of
/// every kind; colours per point (vertex class) so the twin comparison sees interpolation.
fn mesh_rib() -> String {
    let p = |i: usize, j: usize| j * 4 + i;
    let mut faces: Vec<Vec<usize>> = Vec::new();
    for i in 0..3 {
        faces.push(vec![p(i, 0), p(i + 1, 0), p(i + 1, 1), p(i, 1)]);
    }
    faces.push(vec![p(0, 1), p(1, 1), p(1, 2)]);
    faces.push(vec![p(0, 1), p(1, 2), p(0, 2)]);
    // The other winding.
    faces.push(vec![p(1, 1), p(1, 2), p(2, 2), p(2, 1)]);
    faces.push(vec![p(2, 1), p(3, 1), p(3, 2), p(2, 2)]);
    // Two cells as one six-sided face (collinear corners).
    faces.push(vec![p(0, 2), p(1, 2), p(2, 2), p(2, 3), p(1, 3), p(0, 3)]);
    let nverts: Vec<String> = faces.iter().map(|f| f.len().to_string()).collect();
    let verts: Vec<String> = faces.iter().flatten().map(|k| k.to_string()).collect();
    let mut pts = String::new();
    let mut cs = String::new();
    // Point (3, 3), the corner of the cell drawn separately, is not in the mesh: the mesh's
    // points are its largest index + 1 = 15.
    for j in 0..4 {
        for i in 0..4 {
            if (i, j) == (3, 3) {
                continue;
            }
            pts += &format!("{} {} 0  ", i as f64 - 1.5, j as f64 - 1.5);
            cs += &format!(
                "{} {} {}  ",
                i as f64 / 3.0,
                j as f64 / 3.0,
                1.0 - i as f64 / 6.0
            );
        }
    }
    // The last cell, [0.5, 1.5]²: a face with a square hole, and the hole's own polygon.
    format!(
        "Format 160 120 1\nProjection \"perspective\" \"fov\" 45\nPixelSamples 4 4\n\
         WorldBegin\nTranslate 0 0 4\nSurface \"constant\"\n\
         PointsPolygons [{}] [{}] \"P\" [{pts}] \"Cs\" [{cs}]\n\
         Color 1 0 0\n\
         GeneralPolygon [4 4] \"P\" [0.5 0.5 0  1.5 0.5 0  1.5 1.5 0  0.5 1.5 0  \
                                     0.8 0.8 0  0.8 1.2 0  1.2 1.2 0  1.2 0.8 0]\n\
         Color 0 0 1\n\
         Polygon \"P\" [0.8 0.8 0  1.2 0.8 0  1.2 1.2 0  0.8 1.2 0]\n\
         WorldEnd\n",
        nverts.join(" "),
        verts.join(" ")
    )
}

fn parse(text: &str) -> Scene {
    scene::parse_rib(text, "mesh.rib").unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn a_polygon_mesh_covers_its_square_without_pinholes() {
    let s = parse(&mesh_rib());
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    let (w, h) = (160, 120);
    let exact = reyes::reference::coverage(&s, w, h, 8);
    // The square's own area in pixels: side 3 at depth 4, focal 60 / tan(22.5°); and the
    // area its 8x8 samples per pixel see (sample m of a row at (m + 0.5) / 8), which the exact
    // reference must match to the sample.
    let focal = 60.0 / 22.5f64.to_radians().tan();
    let half = 1.5 * focal / 4.0;
    let square = (2.0 * half).powi(2);
    let seen = |c: f64| {
        let (lo, hi) = (
            ((c - half) * 8.0 - 0.5).ceil(),
            ((c + half) * 8.0 - 0.5).floor(),
        );
        (hi - lo + 1.0) / 8.0
    };
    let sampled = seen(80.0) * seen(60.0);
    assert_eq!(
        exact.area(),
        sampled,
        "exact coverage against the square's samples"
    );
    assert!((sampled - square).abs() < 0.005 * square);
    // Coarse dicing too: neighbouring faces' grids meet at different rates.
    for mp_size in [1.0, 6.0] {
        let o = RenderOptions {
            mp_size,
            ..common::small(w, h)
        };
        let data = FrameData::new(&s, &o).unwrap();
        let g = render_everywhere(&data);
        let alpha: Vec<f32> = g.image.rgba.iter().map(|p| p[3]).collect();
        assert_eq!(
            reyes::reference::pinholes(&alpha, &exact),
            0,
            "pinholes at mp_size {mp_size}"
        );
        // Coverage: the crack dilation grows the silhouette by a fraction of a pixel.
        let area: f64 = alpha.iter().map(|&a| a as f64).sum();
        eprintln!("mp_size {mp_size}: covered {area} px, exact {sampled}");
        assert!(
            (area - sampled).abs() < 0.01 * sampled,
            "mp_size {mp_size}: covered {area} px against {sampled}"
        );
        // The hole's polygon is blue, the holed face around it red.
        let px = |x: f64, y: f64| {
            let (cx, cy) = (80.0 + focal * x / 4.0, 60.0 - focal * y / 4.0);
            g.image.rgba[cy as usize * w as usize + cx as usize]
        };
        let centre = px(1.0, 1.0);
        assert!(centre[2] > 0.9 && centre[0] < 0.1, "{centre:?}");
        let ring = px(0.65, 1.0);
        assert!(ring[0] > 0.9 && ring[2] < 0.1, "{ring:?}");
    }
}

/// The exporters' file: a white square, the archive's red triangle, a smaller yellow square.
#[test]
fn exporters_polygons_render_as_the_file_says() {
    let path = reyes::shared_data_dir().join("field/exporters/polygons/readarchive.rib");
    let s = scene::load(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let data = FrameData::new(&s, &RenderOptions::default()).unwrap();
    let g = render_everywhere(&data);
    let (w, h) = (s.width as usize, s.height as usize);
    let at = |x: usize, y: usize| g.image.rgba[y * w + x];
    // The centre is the yellow square (drawn last, in front at the same depth or not: the
    // squares are at z = 0.5 and 0.3 in front of the triangle at z = 1).
    let c = at(w / 2, h / 2);
    assert!(
        c[3] > 0.99 && c[0] > 0.9 && c[1] > 0.9 && c[2] < 0.1,
        "yellow: {c:?}"
    );
    let alpha: f64 = g.image.rgba.iter().map(|p| p[3] as f64).sum();
    assert!(
        alpha > 0.1 * (w * h) as f64,
        "almost nothing drawn: {alpha}"
    );
}

/// `"N"` shades in place of the surface's normal: a flat square facing the eye, lit head-on
/// by a distant light, is as bright as cos(angle) of its given normals (matte, Kd 1).
#[test]
fn vertex_normals_shade_the_polygon() {
    let square = |n: &str| {
        format!(
            "Format 64 64 1\nProjection \"perspective\" \"fov\" 30\nWorldBegin\n\
             LightSource \"distantlight\" 1 \"from\" [0 0 0] \"to\" [0 0 1]\n\
             Surface \"matte\" \"Ka\" 0 \"Kd\" 1\nTranslate 0 0 5\n\
             Polygon \"P\" [-1 -1 0  1 -1 0  1 1 0  -1 1 0] {n}\nWorldEnd\n"
        )
    };
    let centre = |text: &str| {
        let s = parse(text);
        assert!(s.warnings.is_empty(), "{:?}", s.warnings);
        let data = FrameData::new(&s, &RenderOptions::default()).unwrap();
        let g = render_everywhere(&data);
        g.image.rgba[32 * 64 + 32]
    };
    let plain = centre(&square(""));
    let (c, s) = (60f64.to_radians().cos(), 60f64.to_radians().sin());
    let tilted = centre(&square(&format!(
        "\"N\" [{s} 0 {c}  {s} 0 {c}  {s} 0 {c}  {s} 0 {c}]"
    )));
    // 10-bit colour packing: within 0.005.
    assert!((plain[0] - 1.0).abs() < 0.005, "{plain:?}");
    assert!((tilted[0] - 0.5).abs() < 0.005, "{tilted:?}");
}
