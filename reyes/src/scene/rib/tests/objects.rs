//! `ObjectBegin` / `ObjectEnd` / `ObjectInstance`: each instance is the object's geometry
//! under the instance's transform and attributes.

use super::*;

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
