//! `ObjectBegin` / `ObjectEnd` / `ObjectInstance`: each instance is the object's geometry
//! under the instance's transform and attributes.

use super::*;
use std::sync::Arc;

fn centre(p: &crate::scene::Patch) -> DVec3 {
    p.cp().iter().sum::<DVec3>() / 16.0
}

#[test]
fn numbered_and_named_objects_are_instanced_under_their_own_transforms() {
    for h in ["1", "\"thing\""] {
        let s = parse(&format!(
            "ObjectBegin {h}\n Translate 0 0 1\n {QUAD}\nObjectEnd\n\
             WorldBegin\n\
             AttributeBegin Translate 10 0 0 Color 1 0 0 ObjectInstance {h} AttributeEnd\n\
             AttributeBegin Translate -10 0 0 ObjectInstance {h} AttributeEnd\n\
             ObjectInstance {h}\n\
             WorldEnd\n"
        ));
        assert_eq!(s.patches.len(), 3, "{h}");
        let c: Vec<DVec3> = s.patches.iter().map(centre).collect();
        assert!(close(c[0], DVec3::new(10.5, 0.5, 1.0)), "{c:?}");
        assert!(close(c[1], DVec3::new(-9.5, 0.5, 1.0)), "{c:?}");
        // The object's own Translate does not leak out of the instance.
        assert!(close(c[2], DVec3::new(0.5, 0.5, 1.0)), "{c:?}");
        let color = |p: &crate::scene::Patch| s.materials[p.material as usize].color;
        assert_eq!(color(&s.patches[0]), DVec3::X);
        assert_eq!(color(&s.patches[1]), DVec3::ONE);
        assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    }
}

#[test]
fn objects_may_instance_objects_and_are_defined_inside_the_world_too() {
    let s = parse(&world(&format!(
        "ObjectBegin 1 {QUAD} ObjectEnd\n\
         ObjectBegin 2 ObjectInstance 1 Translate 5 0 0 ObjectInstance 1 ObjectEnd\n\
         ObjectInstance 2"
    )));
    assert_eq!(s.patches.len(), 2);
    assert!(close(centre(&s.patches[1]), DVec3::new(5.5, 0.5, 0.0)));
}

#[test]
fn object_errors_name_the_line() {
    let e = err(&world("ObjectInstance 7"));
    assert!(
        e.contains("t.rib:2:") && e.contains("no object \"7\""),
        "{e}"
    );
    let e = err("ObjectBegin 1\nObjectBegin 2\nObjectEnd\n");
    assert!(e.contains("t.rib:2:") && e.contains("do not nest"), "{e}");
    let e = err("ObjectBegin 1\nPatch \"bilinear\" \"P\" [0 0 0 1 0 0 0 1 0 1 1 0]\n");
    assert!(e.contains("inside `ObjectBegin` (line 1)"), "{e}");
    let e = err("ObjectBegin 1\nWorldBegin\nWorldEnd\nObjectEnd\n");
    assert!(
        e.contains("t.rib:2:") && e.contains("not allowed inside"),
        "{e}"
    );
    // An object that instances itself (through a redefinition) stops at a bounded depth.
    let e = err(&world(
        "ObjectBegin 1 ObjectEnd ObjectBegin 1 ObjectInstance 1 ObjectEnd ObjectInstance 1",
    ));
    assert!(e.contains("nested deeper"), "{e}");
}

/// The exporters' file: two spheres, one instanced on either side of the origin.
#[test]
fn exporters_object_instance() {
    let path = crate::shared_data_dir().join("field/exporters/object-instance.rib");
    let s = crate::scene::load(&path).unwrap_or_else(|e| panic!("{e}"));
    let one = parse(&world("Sphere 5 5 -5 360")).patches.len();
    assert!(one > 0);
    assert_eq!(s.patches.len(), 2 * one);
    assert!(
        !s.warnings.iter().any(|w| w.contains("Object")),
        "{:?}",
        s.warnings
    );
}

/// An object of every kind of primitive that instances place (a bilinear patch coloured per
/// corner under a colour of its own, a bicubic patch through the current basis, a partial
/// sphere, a trimmed rational NuPatch, a subdivided cube with face-varying colours, a
/// coloured polygon) and two that are built at each replay (a mesh with normals, a curve).
pub(crate) const OBJECT: &str = "\
AttributeBegin Color 0 1 0 Patch \"bilinear\" \"P\" [0 0 0 1 0 0 0 1 0 1 1 0] \
 \"varying color Cs\" [1 0 0 0 1 0 0 0 1 1 1 1] AttributeEnd
Patch \"bicubic\" \"P\" [0 0 0 1 0 0.5 2 0 0 3 0 0  0 1 0 1 1 1 2 1 1 3 1 0 \
 0 2 0 1 2 1 2 2 1 3 2 0  0 3 0 1 3 0 2 3 0.5 3 3 0]
Translate 0 0 1
Sphere 0.5 -0.5 0.5 300
TrimCurve [1] [3] [0 0 0 0.25 0.25 0.5 0.5 0.75 0.75 1 1 1] [0] [1] [9] \
 [0.5 0 0 0 0.5 0.707107 1 0.707107 0.5] [1 0.707107 0.5 0 0 0 0.5 0.707107 1] \
 [1 0.707107 1 0.707107 1 0.707107 1 0.707107 1]
NuPatch 3 3 [0 0 0 1 1 1] 0 1 2 2 [0 0 1 1] 0 1 \"Pw\" [0 0 0 1  0.5 0.5 0 0.5  1 0 0 1 \
 0 0 1 1  0.5 0.5 0.5 0.5  1 0 1 1] \"vertex color Cs\" [1 0 0 0 1 0 0 0 1 1 1 0 0 1 1 1 0 1]
Attribute \"trimcurve\" \"sense\" \"outside\"
SubdivisionMesh \"catmull-clark\" [4 4 4 4 4 4] [0 1 3 2 2 3 5 4 4 5 7 6 6 7 1 0 1 7 5 3 6 0 2 4] \
 \"P\" [-1 -1 1 1 -1 1 -1 1 1 1 1 1 -1 1 -1 1 1 -1 -1 -1 -1 1 -1 -1] \
 \"facevarying color Cs\" [1 0 0 1 0 0 1 0 0 1 0 0  0 1 0 0 1 0 0 1 0 0 1 0 \
 0 0 1 0 0 1 0 0 1 0 0 1  1 1 0 1 1 0 1 1 0 1 1 0  0 1 1 0 1 1 0 1 1 0 1 1 1 0 1 1 0 1 1 0 1 1 0 1]
Polygon \"P\" [0 0 0 1 0 0 1.2 1 0.2 0.5 1.5 0.1 -0.3 0.8 0] \"Cs\" [1 0 0 0 1 0 0 0 1 1 1 0 0 1 1]
PointsPolygons [3] [0 1 2] \"P\" [0 0 2 1 0 2 0 1 2] \"N\" [0 0 1 0 0.2 1 0.2 0 1]
Curves \"linear\" [2] \"nonperiodic\" \"P\" [0 0 0 1 1 1] \"constantwidth\" 0.05
";

/// The instances' transforms and attributes: a colour, a mirror (the orientation flips),
/// `ReverseOrientation` and `Sides 1`, another basis (the bicubic patch is built again),
/// a displacement, a non-uniform scale.
pub(crate) const PLACEMENTS: &[&str] = &[
    "Translate -2 0 0 Color 1 0 0",
    "Translate 2 1 0 Rotate 30 0 1 0 Scale 1 -1 1",
    "ReverseOrientation Sides 1 Translate 0 -2 0 Scale 2 2 2",
    "Basis \"b-spline\" 1 \"b-spline\" 1 Translate 0 2 0 Rotate 70 1 1 0",
    "Displacement \"bumps\" \"Km\" 0.05 Translate 1 1 1 Scale 0.5 1 3",
];

/// The scene of `object` at each of `placements`: as `ObjectInstance`s, or with the object's
/// requests written out in an attribute block where each instance stands (what an instance
/// means).
pub(crate) fn placed(object: &str, placements: &[&str], instanced: bool) -> String {
    let mut s = String::from("Translate 0 0 12\nWorldBegin\n");
    if instanced {
        s += &format!("ObjectBegin 1\n{object}ObjectEnd\n");
    }
    for p in placements {
        let body = if instanced {
            "ObjectInstance 1".to_string()
        } else {
            format!("AttributeBegin\n{object}AttributeEnd")
        };
        s += &format!("AttributeBegin\n{p}\n{body}\nAttributeEnd\n");
    }
    s + "WorldEnd\n"
}

/// Everything the renderer reads of two scenes' patches is equal (the patches' sources
/// differ in their lines only).
fn assert_same_patches(a: &crate::scene::Scene, b: &crate::scene::Scene) {
    assert_eq!(a.patches.len(), b.patches.len());
    assert_eq!(a.materials, b.materials);
    for (k, (p, q)) in a.patches.iter().zip(&b.patches).enumerate() {
        let r = crate::scene::Patch {
            source: p.source.clone(),
            ..q.clone()
        };
        assert_eq!(*p, r, "patch {k}");
        assert_eq!(p.cp(), q.cp(), "patch {k}: bit for bit");
        assert_eq!(p.source.index, q.source.index, "patch {k}");
    }
}

/// Instances are placed from one build of each primitive, and are bit for bit the patches
/// the object's requests give written out at each instance: the attributes set inside the
/// object win, the instance's apply otherwise, the orientation follows a mirroring instance,
/// a changed basis builds again. The placed patches share their fields, weights and trims.
#[test]
fn instances_are_the_written_out_requests_bit_for_bit() {
    let inst = parse(&placed(OBJECT, PLACEMENTS, true));
    let inline = parse(&placed(OBJECT, PLACEMENTS, false));
    assert_same_patches(&inst, &inline);
    let per = inst.patches.len() / PLACEMENTS.len();
    assert_eq!(per * PLACEMENTS.len(), inst.patches.len());
    let (a, b) = (&inst.patches[..per], &inst.patches[per..2 * per]);
    let mut shared = [0usize; 3];
    for (p, q) in a.iter().zip(b) {
        if let (Some(x), Some(y)) = (&p.primvars, &q.primvars) {
            if x.n.is_none() {
                assert!(Arc::ptr_eq(x, y), "fields shared");
                shared[0] += 1;
            } else {
                assert!(
                    !Arc::ptr_eq(x, y),
                    "camera-space normals are each instance's"
                );
            }
        }
        if let (Some(x), Some(y)) = (p.net.shared_weights(), q.net.shared_weights()) {
            assert!(Arc::ptr_eq(x, y), "weights shared");
            shared[1] += 1;
        }
        if let (Some(x), Some(y)) = (&p.trim, &q.trim) {
            assert!(Arc::ptr_eq(x, y), "trims shared");
            shared[2] += 1;
        }
    }
    assert!(shared.iter().all(|&n| n > 0), "{shared:?}");
    // The written-out scene shares nothing between its copies.
    let (p, q) = (&inline.patches[0], &inline.patches[per]);
    assert!(!Arc::ptr_eq(
        p.primvars.as_ref().unwrap(),
        q.primvars.as_ref().unwrap()
    ));
}

/// Nested instances (an object of instances of an object) are placed as written out, and
/// the inner object's fields are shared through every level.
#[test]
fn nested_instances_are_the_written_out_requests() {
    let outer = "AttributeBegin Translate 3 0 0 ObjectInstance 1 AttributeEnd\n\
                 Color 0 0 1 Rotate 45 0 0 1 ObjectInstance 1\n";
    let inst = {
        let mut s = String::from("Translate 0 0 12\nWorldBegin\n");
        s += &format!("ObjectBegin 1\n{OBJECT}ObjectEnd\nObjectBegin 2\n{outer}ObjectEnd\n");
        for p in PLACEMENTS {
            s += &format!("AttributeBegin\n{p}\nObjectInstance 2\nAttributeEnd\n");
        }
        parse(&(s + "WorldEnd\n"))
    };
    let written = outer.replace(
        "ObjectInstance 1",
        &format!("AttributeBegin\n{OBJECT}AttributeEnd"),
    );
    let inline = parse(&placed(&written, PLACEMENTS, false));
    assert_same_patches(&inst, &inline);
    let per = inst.patches.len() / (2 * PLACEMENTS.len());
    let (p, q) = (&inst.patches[0], &inst.patches[3 * per]);
    assert!(Arc::ptr_eq(
        p.primvars.as_ref().unwrap(),
        q.primvars.as_ref().unwrap()
    ));
}

/// A redefined object is built again, and another object's definition keeps the builds of
/// the others; a `Declare` between instances builds again (it may change how the
/// primitive's parameters read).
#[test]
fn redefinitions_and_declarations_build_again() {
    let s = parse(&world(&format!(
        "ObjectBegin 1 {QUAD} ObjectEnd ObjectInstance 1\n\
         ObjectBegin 1 Translate 0 0 2 {QUAD} ObjectEnd ObjectInstance 1\n\
         ObjectBegin 2 Polygon \"P\" [0 0 0 1 0 0 1 1 0] \"Cs\" [1 0 0 0 1 0 0 0 1] ObjectEnd\n\
         ObjectInstance 2 ObjectBegin 3 {QUAD} ObjectEnd ObjectInstance 2\n\
         Declare \"Cs\" \"vertex color\" ObjectInstance 2"
    )));
    assert_eq!(s.patches.len(), 5);
    assert!(close(centre(&s.patches[1]), DVec3::new(0.5, 0.5, 2.0)));
    let fields = |k: usize| s.patches[k].primvars.as_ref().unwrap();
    assert!(Arc::ptr_eq(fields(2), fields(3)));
    assert!(!Arc::ptr_eq(fields(3), fields(4)));
    assert_eq!(fields(3), fields(4));
}

/// The frame tables of N instances: one copy of the object's fields, weights, trims and
/// displacement, and per instance only its root items (224 bytes), patch infos (32) and the
/// camera-space normal fields of its polygons with `"N"` (4 entries of 16 bytes each).
#[test]
fn frame_tables_hold_the_shared_data_once() {
    use crate::frame::{FrameData, RenderOptions};
    // No curves (their fields are made at each replay) or rotations (a rotation may round a
    // displacement's bound apart).
    let object: String = (OBJECT.lines())
        .filter(|l| !l.starts_with("Curves"))
        .map(|l| format!("{l}\n"))
        .collect();
    let at = |n: usize| -> Vec<String> {
        (0..n)
            .map(|i| format!("Displacement \"bumps\" \"Km\" 0.05 Translate {} 0 0", i * 3))
            .collect()
    };
    let data = |n: usize, instanced: bool| {
        let p = at(n);
        let p: Vec<&str> = p.iter().map(String::as_str).collect();
        FrameData::new(
            &parse(&placed(&object, &p, instanced)),
            &RenderOptions::default(),
        )
        .unwrap()
    };
    let one = data(1, true);
    let per = one.items.len();
    let with_normals = (parse(&placed(&object, &["Translate 0 0 0"], true))
        .patches
        .iter())
    .filter(|p| p.primvars.as_ref().is_some_and(|v| v.n.is_some()))
    .count();
    assert!(per > 0 && with_normals == 1 && !one.primvars.is_empty());
    for n in [2, 7] {
        let d = data(n, true);
        assert_eq!(d.items.len(), n * per);
        assert_eq!(
            d.primvars.len(),
            one.primvars.len() + (n - 1) * with_normals * 4,
            "{n} instances: one copy of the shared data"
        );
        assert_eq!(
            d.table_bytes(),
            one.table_bytes() + (n as u64 - 1) * (per as u64 * (224 + 32) + 64),
            "{n} instances"
        );
        let written = data(n, false);
        assert_eq!(written.items, d.items);
        assert!(written.primvars.len() > d.primvars.len());
    }
}

/// A placement checks what a build checks: normals that leave the f32 range under the
/// instance's transform fail the instance, as the written-out requests fail.
#[test]
fn a_placement_fails_where_the_written_out_requests_fail() {
    let mesh =
        "PointsPolygons [3] [0 1 2] \"P\" [0 0 2 1 0 2 0 1 2] \"N\" [0 0 1 0 0.2 1 0.2 0 1]\n";
    for instanced in [true, false] {
        let e = err(&placed(
            mesh,
            &["Translate 1 0 0", "Scale 1e-40 1 1"],
            instanced,
        ));
        assert!(e.contains("\"N\" is not finite in camera space"), "{e}");
    }
}
