//! `Curves` and `Points` through the whole pipeline: ribbons and discs cover what RenderMan's
//! definitions say (a straight ribbon its width times its length, a disc pi d^2 / 4, a bending
//! cubic ribbon the area between its exact edges, every curve point under the ribbon's
//! centre), every strategy gives the same image and the CPU twin agrees; the exporters' files
//! render without a skipped-primitive warning. Runs on lavapipe in CI.

use glam::DVec3;
use reyes::frame::{FrameData, RenderOptions};
use reyes::gpu_render::GpuFrame;
use reyes::scene::{self, Scene};

mod common;
use common::render_everywhere;

fn parse(text: &str) -> Scene {
    let s = scene::parse_rib(text, "curves.rib").unwrap_or_else(|e| panic!("{e}"));
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    s
}

fn alpha_sum(g: &GpuFrame) -> f64 {
    g.image.rgba.iter().map(|p| p[3] as f64).sum()
}

/// 160 x 120, fov 90: the focal length is 60 px, so at depth 6 a unit is 10 px.
const HEAD: &str = "Format 160 120 1\nProjection \"perspective\" \"fov\" 90\nPixelSamples 4 4\n\
                    WorldBegin\nSurface \"constant\"\n";

/// Raster position of a camera-space point in a scene of `HEAD`'s camera (`f` px focal).
fn raster(p: DVec3, f: f64, w: f64, h: f64) -> (f64, f64) {
    (w / 2.0 + f * p.x / p.z, h / 2.0 - f * p.y / p.z)
}

/// The area of a closed polygon (shoelace).
fn polygon_area(pts: &[(f64, f64)]) -> f64 {
    let n = pts.len();
    0.5 * (0..n)
        .map(|k| {
            let (a, b) = (pts[k], pts[(k + 1) % n]);
            a.0 * b.1 - b.0 * a.1
        })
        .sum::<f64>()
        .abs()
}

#[test]
fn straight_ribbons_cover_width_times_length() {
    // A horizontal ribbon along y = 0 (x from -7 to -1, width 0.4) and a vertical one along
    // x = 0 (y from 1 to 5, width 0.6): through the view axis each is a rectangle facing the
    // eye, 60 x 4 and 6 x 40 px, their edges on pixel boundaries.
    let s = parse(&format!(
        "{HEAD}Curves \"linear\" [2 2] \"nonperiodic\" \"P\" [-7 0 6  -1 0 6  0 1 6  0 5 6] \
         \"uniform float width\" [0.4 0.6]\nWorldEnd\n"
    ));
    let want = 60.0 * 4.0 + 6.0 * 40.0;
    // The exact reference samples pixels at (m + 0.5) / 8: no sample lies on an edge.
    let exact = reyes::reference::coverage(&s, 160, 120, 8);
    assert_eq!(exact.area(), want);
    let data = FrameData::new(&s, &RenderOptions::default()).unwrap();
    let g = render_everywhere(&data);
    let area = alpha_sum(&g);
    eprintln!("straight ribbons: covered {area} px, want {want}");
    // Edges on pixel boundaries (to f32 rounding): only samples on them or within the 1e-3
    // px edge tolerance of a micropolygon can differ, a few percent of the ~1700 samples in
    // the pixels along the edges (measured: 481.9 px): within 1%.
    assert!(
        (area - want).abs() <= 0.01 * want,
        "covered {area} px, want {want}"
    );
    // Inside: full; beside: empty.
    let at = |x: usize, y: usize| g.image.rgba[y * 160 + x][3];
    assert_eq!((at(40, 59), at(40, 60), at(80, 30)), (1.0, 1.0, 1.0));
    assert_eq!(
        (at(40, 57), at(40, 62), at(76, 30), at(83, 30)),
        (0.0, 0.0, 0.0, 0.0)
    );
}

#[test]
fn discs_cover_their_projected_area() {
    // One disc on the axis (diameter 4 at depth 6: 40 px, pi 400 px²) and one off the axis,
    // whose exact outline is the projection of its rim circle (a conic), summed as a polygon
    // of 20000 rim points.
    let (c2, r2) = (DVec3::new(3.0, 2.0, 6.0), 1.0);
    let s = parse(&format!(
        "{HEAD}Color 1 0 0\nPoints \"P\" [0 0 6  {} {} {}] \"width\" [4 {}]\nWorldEnd\n",
        c2.x,
        c2.y,
        c2.z,
        2.0 * r2
    ));
    let axis = std::f64::consts::PI * 400.0;
    let n = -c2.normalize();
    let a = n.any_orthonormal_vector();
    let b = n.cross(a);
    let rim: Vec<(f64, f64)> = (0..20000)
        .map(|k| {
            let phi = std::f64::consts::TAU * k as f64 / 20000.0;
            raster(
                c2 + (a * phi.cos() + b * phi.sin()) * r2,
                60.0,
                160.0,
                120.0,
            )
        })
        .collect();
    let off = polygon_area(&rim);
    let want = axis + off;
    let data = FrameData::new(&s, &RenderOptions::default()).unwrap();
    let g = render_everywhere(&data);
    let area = alpha_sum(&g);
    eprintln!("discs: covered {area} px, want {want}");
    // 4x4 jittered samples along ~190 px of outline (a few px either way), and the rim diced
    // into chords (inside the circle, by under 0.03 px at 1 px micropolygons): within 1%.
    assert!(
        (area - want).abs() < 0.01 * want,
        "covered {area} px, want {want} ({axis} + {off})"
    );
    // Red, flat: the centre of the disc.
    let c = g.image.rgba[60 * 160 + 80];
    assert!(
        c[0] > 0.99 && c[1] < 0.01 && c[2] < 0.01 && c[3] == 1.0,
        "{c:?}"
    );
}

/// A cubic Bezier ribbon bending across the view (depth 6 to 8, width 0.5): its coverage is the
/// area between its exact edges C(t) +- h d(t) (d across the tangent and the view, RenderMan's
/// definition, evaluated here at 4000 points per edge), and every curve point's pixel is
/// covered.
#[test]
fn a_cubic_ribbon_covers_the_area_between_its_exact_edges() {
    let cp = [
        DVec3::new(-5.0, -2.0, 6.0),
        DVec3::new(-2.0, 5.0, 8.0),
        DVec3::new(2.0, -5.0, 8.0),
        DVec3::new(5.0, 2.0, 6.0),
    ];
    let h = 0.25;
    let nums: Vec<String> = cp
        .iter()
        .map(|p| format!("{} {} {}", p.x, p.y, p.z))
        .collect();
    let s = parse(&format!(
        "{HEAD}Curves \"cubic\" [4] \"nonperiodic\" \"P\" [{}] \"constantwidth\" {}\nWorldEnd\n",
        nums.join("  "),
        2.0 * h
    ));
    let bez = |t: f64| {
        let s = 1.0 - t;
        cp[0] * (s * s * s)
            + cp[1] * (3.0 * t * s * s)
            + cp[2] * (3.0 * t * t * s)
            + cp[3] * (t * t * t)
    };
    let tangent = |t: f64| {
        let s = 1.0 - t;
        (cp[1] - cp[0]) * (s * s) + (cp[2] - cp[1]) * (2.0 * t * s) + (cp[3] - cp[2]) * (t * t)
    };
    let edge = |t: f64, side: f64| {
        let c = bez(t);
        let d = c.cross(tangent(t)).normalize();
        raster(c + d * (h * side), 60.0, 160.0, 120.0)
    };
    let n = 4000;
    let mut outline: Vec<(f64, f64)> = (0..=n).map(|k| edge(k as f64 / n as f64, 1.0)).collect();
    outline.extend((0..=n).rev().map(|k| edge(k as f64 / n as f64, -1.0)));
    let want = polygon_area(&outline);
    let data = FrameData::new(&s, &RenderOptions::default()).unwrap();
    let g = render_everywhere(&data);
    let area = alpha_sum(&g);
    eprintln!("cubic ribbon: covered {area} px, want {want}");
    // 4x4 jittered samples along ~330 px of edges, the ribbon's offset fit (0.5% of the half
    // width) and the edges diced into chords: within 1.5%.
    assert!(
        (area - want).abs() < 0.015 * want,
        "covered {area} px, want {want}"
    );
    // The ribbon is 5 to 2.5 px wide: the pixel under each curve point is fully covered.
    for k in 1..20 {
        let (x, y) = raster(bez(k as f64 / 20.0), 60.0, 160.0, 120.0);
        let a = g.image.rgba[y as usize * 160 + x as usize][3];
        assert!(a > 0.99, "t {}: alpha {a} at ({x}, {y})", k as f64 / 20.0);
    }
}

/// The exporters' files: what was skipped is drawn, the same on every strategy and the CPU
/// twin, covering what its patches cover exactly.
#[test]
fn exporters_curves_and_points_render() {
    for file in ["curves-linear.rib", "points.rib"] {
        let path = reyes::shared_data_dir().join("field/exporters").join(file);
        let s = scene::load(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        let w = s.warnings.join("\n");
        assert!(
            !w.contains("Curves") && !w.contains("Points"),
            "{file}: {w}"
        );
        let o = RenderOptions {
            pixel_samples: Some((4, 4)),
            ..Default::default()
        };
        let data = FrameData::new(&s, &o).unwrap();
        let g = render_everywhere(&data);
        let area = alpha_sum(&g);
        let exact = reyes::reference::coverage(&s, s.width, s.height, 8).area();
        assert!(exact > 100.0, "{file}: {exact}");
        let o = RenderOptions {
            crack_dilation: false,
            ..o
        };
        let bare = alpha_sum(&render_everywhere(&FrameData::new(&s, &o).unwrap()));
        eprintln!("{file}: covered {area} px ({bare} without crack dilation), exact {exact}");
        // Without the crack dilation: thin ribbons and small discs are mostly edge pixels,
        // each within about 1/16 (4x4 jittered samples): within 3%.
        assert!(
            (bare - exact).abs() < 0.03 * exact,
            "{file}: covered {bare} px without crack dilation, exact {exact}"
        );
        // The crack dilation (on by default) only grows: the discs of points.rib, 2 to 4 px
        // across, by 6% (its boundary bound is the chord deviation times a conservative
        // camera-to-pixel factor, issue 23 item 6); the ribbons by 0.2%.
        assert!(
            area >= bare - 0.005 * exact && area < 1.12 * exact,
            "{file}: covered {area} px with crack dilation, {bare} without, exact {exact}"
        );
    }
}
