//! `SubdivisionMesh "catmull-clark" nverts vertids [tags nargs intargs floatargs
//! [stringargs]] parameterlist`: the mesh and its tags (`interpolateboundary`, `crease`,
//! `corner`, `hole`; RenderMan Interface Specification 3.2, section 5.6) read here, the
//! limit surface made by `scene::subdiv` and emitted as Bezier patches.
//!
//! Primitive variables: "P"; "Cs" and "Os" constant or uniform (one value per face, every
//! patch of the face gets it), vertex or varying (subdivided with the positions: varying is
//! smoothed like vertex, a choice), or facevarying (one value per face corner, interpolated
//! linearly over each face: bilinearly on a quad, over the n quads of the first subdivision
//! step on another polygon; values differ across faces where they are given so).

use super::lexer::shown;
use super::patches::check_points;
use super::primvars::{Class, ClassCounts};
use super::state::Interp;
use super::syntax::{Arg, Args, Request};
use crate::scene::subdiv::{BoundaryMode, Tags, catmull_clark};
use crate::scene::{ColorField, Patch, SceneError};

/// Integers of a request's integer array (`what` names it in errors), each in `lo..=hi`.
fn ints(a: &Args, v: &[f64], what: &str, lo: usize, hi: usize) -> Result<Vec<usize>, SceneError> {
    v.iter()
        .map(|&x| {
            if x.fract() == 0.0 && x >= lo as f64 && x <= hi as f64 {
                Ok(x as usize)
            } else {
                Err(a.err(format!("{what}: {x} is not an integer in {lo}..={hi}")))
            }
        })
        .collect()
}

impl Interp {
    pub(super) fn subdivision_mesh(
        &mut self,
        req: &Request,
        a: &mut Args,
    ) -> Result<(), SceneError> {
        let scheme = a.string("the subdivision scheme")?;
        if scheme != "catmull-clark" {
            let msg = super::requests::with_suggestion(
                format!(
                    "skipped `SubdivisionMesh` of scheme \"{}\" (only \"catmull-clark\"): the \
                     image lacks that mesh",
                    shown(scheme)
                ),
                scheme,
                &["catmull-clark"],
            );
            self.warn_once(req, &format!("SubdivisionMesh {scheme}"), &msg);
            return Ok(());
        }
        const MAX: usize = 1 << 28;
        let sizes = a.array("nvertices")?;
        let sizes = ints(a, sizes, "nvertices", 3, MAX)?;
        let ids = a.array("vertices")?;
        let ids = ints(a, ids, "vertices", 0, MAX)?;
        let tags = self.subdiv_tags(req, a)?;
        let params = a.params()?;
        let n = match params.iter().find(|p| p.name == "P" || p.name == "Pw") {
            Some(p) => p.nums(a)?.len() / if p.name == "P" { 3 } else { 4 },
            None => return Err(a.err("missing the \"P\" parameter")),
        };
        let pts = self.positions(req, a, &params, n)?;
        let counts = ClassCounts {
            uniform: sizes.len(),
            varying: n,
            vertex: n,
            // One per face corner.
            facevarying: ids.len(),
        };
        let vars = self.color_vars(a, &params, &counts)?;
        let ctm = self.geometry_ctm(a)?;
        check_points(a, 0, &pts, 0..n)?;
        // Channels: positions, then each smoothly varying colour.
        let mut data = vec![pts];
        let mut slot = |v: &Option<super::primvars::ColorVar>| match v {
            Some(c) if matches!(c.class, Class::Vertex | Class::Varying) => {
                data.push(c.values.clone());
                Some(data.len() - 1)
            }
            _ => None,
        };
        let (cs_ch, os_ch) = (slot(&vars.cs), slot(&vars.os));
        // Facevarying colours: channels interpolated linearly over each face.
        fn facevarying(
            v: &Option<super::primvars::ColorVar>,
        ) -> Option<&super::primvars::ColorVar> {
            v.as_ref().filter(|c| c.class == Class::FaceVarying)
        }
        let fv: Vec<&[glam::DVec3]> = [facevarying(&vars.cs), facevarying(&vars.os)]
            .into_iter()
            .flatten()
            .map(|c| c.values.as_slice())
            .collect();
        let cs_fv = facevarying(&vars.cs).map(|_| 0);
        let os_fv = facevarying(&vars.os).map(|_| cs_fv.map_or(0, |_| 1));
        let ids: Vec<u32> = ids.into_iter().map(|i| i as u32).collect();
        let patches = catmull_clark(&sizes, &ids, &tags, data, &fv)
            .map_err(|e| a.err(format!("{e} (faces and vertices count from 0)")))?;
        for (k, p) in patches.into_iter().enumerate() {
            let field = |v: &Option<super::primvars::ColorVar>,
                         ch: Option<usize>,
                         f: Option<usize>| {
                let v = v.as_ref()?;
                Some(match (ch, f, v.class) {
                    (Some(c), _, _) => ColorField::Bezier(p.channels[c]),
                    (None, Some(f), _) => ColorField::Bilinear(p.facevarying[f]),
                    (None, None, Class::Uniform) => ColorField::Flat(v.values[p.origin as usize]),
                    (None, None, _) => ColorField::Flat(v.values[0]),
                })
            };
            let fields = (field(&vars.cs, cs_ch, cs_fv), field(&vars.os, os_ch, os_fv));
            self.emit_with(a, &ctm, k, p.channels[0], Patch::POLYNOMIAL, fields)?;
        }
        Ok(())
    }

    /// The optional tag arrays: tags, nargs (two or three per tag), intargs, floatargs and,
    /// with three counts per tag, stringargs. Unknown tags are skipped with a warning.
    fn subdiv_tags(&mut self, req: &Request, a: &mut Args) -> Result<Tags, SceneError> {
        let mut tags = Tags::default();
        let names: Vec<String> = match a.peek() {
            Some(Arg::Strs(v)) => v.clone(),
            Some(Arg::Nums(v)) if v.is_empty() => Vec::new(),
            _ => return Ok(tags),
        };
        a.pos += 1;
        let nargs = a.array("nargs")?;
        let per = if nargs.len() == 3 * names.len() && !names.is_empty() {
            3
        } else {
            2
        };
        if nargs.len() != per * names.len() {
            return Err(a.err(format!(
                "nargs has {} numbers for {} tags (two per tag)",
                nargs.len(),
                names.len()
            )));
        }
        let nargs = ints(a, nargs, "nargs", 0, 1 << 28)?;
        let intargs = a.array("intargs")?;
        let floatargs = a.array("floatargs")?;
        if per == 3 {
            match a.peek() {
                Some(Arg::Strs(_)) | Some(Arg::Nums(_)) => a.pos += 1,
                _ => return Err(a.err("missing stringargs (nargs gives three counts per tag)")),
            }
        }
        let (ni, nf): (usize, usize) = (0..names.len())
            .map(|t| (nargs[per * t], nargs[per * t + 1]))
            .fold((0, 0), |(x, y), (i, f)| (x + i, y + f));
        if ni != intargs.len() || nf != floatargs.len() {
            return Err(a.err(format!(
                "nargs asks for {ni} integer and {nf} float arguments, found {} and {}",
                intargs.len(),
                floatargs.len()
            )));
        }
        let (mut io, mut fo) = (0, 0);
        for (t, name) in names.iter().enumerate() {
            let (ni, nf) = (nargs[per * t], nargs[per * t + 1]);
            let iv = ints(a, &intargs[io..io + ni], name, 0, 1 << 28)?;
            let fv = &floatargs[fo..fo + nf];
            io += ni;
            fo += nf;
            if let Some(x) = fv.iter().find(|x| x.is_nan()) {
                return Err(a.err(format!("tag \"{}\": sharpness {x}", shown(name))));
            }
            match name.as_str() {
                "interpolateboundary" => {
                    tags.boundary = match iv.first() {
                        Some(0) => BoundaryMode::None,
                        Some(2) => BoundaryMode::EdgesOnly,
                        _ => BoundaryMode::EdgesAndCorners,
                    }
                }
                "crease" if !fv.is_empty() && iv.len() >= 2 => {
                    tags.creases
                        .push((iv.iter().map(|&v| v as u32).collect(), fv[0]));
                }
                "corner" if !fv.is_empty() => {
                    for (k, &v) in iv.iter().enumerate() {
                        tags.corners.push((v as u32, fv[k.min(fv.len() - 1)]));
                    }
                }
                "hole" => tags.holes.extend(iv.iter().map(|&f| f as u32)),
                "crease" | "corner" => {
                    return Err(a.err(format!(
                        "tag \"{name}\" needs vertices and a sharpness, found {ni} integers \
                         and {nf} floats"
                    )));
                }
                other => {
                    let msg = format!(
                        "skipped tag \"{}\" of `SubdivisionMesh` (the surface is drawn \
                         without it)",
                        shown(other)
                    );
                    self.warn_once(req, &format!("SubdivisionMesh tag {other}"), &msg);
                }
            }
        }
        Ok(tags)
    }
}

#[cfg(test)]
mod tests {
    use super::super::tests::{err, parse, world};
    use crate::scene::ColorField;
    use glam::DVec3;

    const TETRA: &str = "SubdivisionMesh \"catmull-clark\" [3 3 3 3] [0 1 3 1 2 3 2 0 3 2 1 0] \
                         \"P\" [1 0 0  -0.5 0.866 0  -0.5 -0.866 0  0 0 1]";

    #[test]
    fn a_tetrahedron_is_read_as_limit_patches() {
        let s = parse(&world(&format!("Translate 0 0 5\n{TETRA}")));
        assert!(s.warnings.is_empty(), "{:?}", s.warnings);
        assert!(s.patches.len() > 100, "{}", s.patches.len());
        assert!(s.patches.iter().all(|p| p.cp().iter().all(|c| c.z > 4.0)));
    }

    #[test]
    fn tags_and_colours_are_read() {
        let quad = "SubdivisionMesh \"catmull-clark\" [4] [0 1 2 3] \
                    [\"interpolateboundary\" \"crease\" \"unknowntag\"] [0 0 2 1 0 0] [0 1] [10] \
                    \"P\" [0 0 0 1 0 0 1 1 0 0 1 0] \"vertex color Cs\" [1 0 0 0 1 0 0 0 1 1 1 1] \
                    \"uniform color Os\" [0.5 0.5 0.5] \"N\" [0 0 1 0 0 1 0 0 1 0 0 1]";
        let s = parse(&world(quad));
        assert!(!s.patches.is_empty());
        let w = s.warnings.join("\n");
        assert!(w.contains("unknowntag") && w.contains("\"N\""), "{w}");
        let pv = s.patches[0].primvars.as_ref().unwrap();
        assert!(matches!(pv.cs, Some(crate::scene::ColorField::Bezier(_))));
        assert!(matches!(pv.os, Some(crate::scene::ColorField::Flat(_))));
    }

    /// Facevarying "Cs" is interpolated linearly over each face: on a flat unit square with
    /// sharp boundaries (whose limit surface is the square, each point where its linear
    /// refinement puts it) every patch corner has the bilinear blend of the four corner
    /// colours at its position; on a cube whose faces each have one colour, every patch has its
    /// face's colour alone (the colour jumps at the edges).
    #[test]
    fn facevarying_colours_are_linear_over_each_face() {
        let quad = "SubdivisionMesh \"catmull-clark\" [4] [0 1 2 3] [\"interpolateboundary\"] \
                    [0 0] [] [] \"P\" [0 0 0 1 0 0 1 1 0 0 1 0] \
                    \"facevarying color Cs\" [1 0 0 0 1 0 0 0 1 1 1 1]";
        let s = parse(&world(quad));
        assert!(s.warnings.is_empty(), "{:?}", s.warnings);
        assert!(s.patches.len() >= 4);
        let corner = [
            DVec3::new(1.0, 0.0, 0.0),
            DVec3::new(0.0, 1.0, 0.0),
            DVec3::new(0.0, 0.0, 1.0),
            DVec3::ONE,
        ];
        let want = |x: f64, y: f64| {
            (corner[0] * (1.0 - x) + corner[1] * x) * (1.0 - y)
                + (corner[3] * (1.0 - x) + corner[2] * x) * y
        };
        for p in &s.patches {
            let cs = p.primvars.as_ref().and_then(|v| v.cs.clone()).unwrap();
            assert!(matches!(cs, ColorField::Bilinear(_)));
            for (u, v, k) in [(0.0, 0.0, 0), (1.0, 0.0, 3), (0.0, 1.0, 12), (1.0, 1.0, 15)] {
                let q = p.cp()[k];
                let d = cs.eval(u, v) - want(q.x, q.y);
                assert!(
                    d.length() < 1e-9,
                    "at {q}: {} vs {}",
                    cs.eval(u, v),
                    want(q.x, q.y)
                );
            }
        }
        let cube = "SubdivisionMesh \"catmull-clark\" [4 4 4 4 4 4] \
                    [0 1 3 2 2 3 5 4 4 5 7 6 6 7 1 0 1 7 5 3 6 0 2 4] \
                    \"P\" [-1 -1 1 1 -1 1 -1 1 1 1 1 1 -1 1 -1 1 1 -1 -1 -1 -1 1 -1 -1] \
                    \"facevarying color Cs\" [1 0 0 1 0 0 1 0 0 1 0 0  0 1 0 0 1 0 0 1 0 0 1 0 \
                    0 0 1 0 0 1 0 0 1 0 0 1  1 1 0 1 1 0 1 1 0 1 1 0  0 1 1 0 1 1 0 1 1 0 1 1 \
                    1 0 1 1 0 1 1 0 1 1 0 1]";
        let s = parse(&world(cube));
        assert!(s.warnings.is_empty(), "{:?}", s.warnings);
        let colours = [
            DVec3::X,
            DVec3::Y,
            DVec3::Z,
            DVec3::new(1.0, 1.0, 0.0),
            DVec3::new(0.0, 1.0, 1.0),
            DVec3::new(1.0, 0.0, 1.0),
        ];
        let mut seen = [0; 6];
        for p in &s.patches {
            let Some(ColorField::Bilinear(c)) = p.primvars.as_ref().and_then(|v| v.cs.clone())
            else {
                panic!("no bilinear Cs");
            };
            let f = colours
                .iter()
                .position(|k| *k == c[0])
                .expect("a face colour");
            assert!(c.iter().all(|x| *x == colours[f]), "{c:?}");
            seen[f] += 1;
        }
        assert!(seen.iter().all(|&n| n > 0), "{seen:?}");
    }

    #[test]
    fn bad_meshes_name_their_fault() {
        let e = err(&world(
            "SubdivisionMesh \"catmull-clark\" [3] [0 1 5] \"P\" [0 0 0 1 0 0 0 1 0]",
        ));
        assert!(
            e.contains("t.rib:2") && e.contains("vertex 5 out of range"),
            "{e}"
        );
        let e = err(&world(
            "SubdivisionMesh \"catmull-clark\" [3 3] [0 1 2 0 1 2] \"P\" [0 0 0 1 0 0 0 1 0]",
        ));
        assert!(e.contains("oriented manifold"), "{e}");
        let e = err(&world(
            "SubdivisionMesh \"catmull-clark\" [2] [0 1] \"P\" [0 0 0 1 0 0]",
        ));
        assert!(e.contains("nvertices"), "{e}");
        let s = parse(&world(
            "SubdivisionMesh \"loop\" [3] [0 1 2] \"P\" [0 0 0 1 0 0 0 1 0]",
        ));
        assert!(s.patches.is_empty() && s.warnings[0].contains("\"loop\""));
    }
}
