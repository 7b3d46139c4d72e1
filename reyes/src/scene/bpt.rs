//! Plain BPT (Bezier patch text): the patch count on the first line, then per patch a line
//! with the degrees "3 3" and 16 lines of "x y z" control points, u varying fastest
//! (the same order as RenderMan's).

use super::newell::Fields;
use super::{ObjectPatch, PatchSource, SceneError};
use glam::DVec3;

/// Parses a BPT file into object-space Bezier patches. Only bicubic ("3 3") patches.
pub fn parse_bpt(text: &str, file: &str) -> Result<Vec<ObjectPatch>, SceneError> {
    let mut r = Fields::new(text, file, false);
    let (count, _) = r.int("the patch count")?;
    let mut out = Vec::with_capacity(count.min(1 << 16) as usize);
    let shared: std::sync::Arc<str> = file.into();
    for p in 0..count {
        let (du, line) = r.int(&format!("the u degree of patch {p}"))?;
        let (dv, _) = r.int(&format!("the v degree of patch {p}"))?;
        if (du, dv) != (3, 3) {
            return Err(r.err(
                line,
                format!("patch {p}: degrees {du} {dv} are not supported (only bicubic, 3 3)"),
            ));
        }
        let mut cp = [DVec3::ZERO; 16];
        for (k, c) in cp.iter_mut().enumerate() {
            *c = r
                .point(&format!("coordinate of control point {k} of patch {p}"))?
                .0;
        }
        let src = PatchSource {
            file: shared.clone(),
            line,
            index: p as u32,
        };
        out.push((cp, src));
    }
    r.finish()?;
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn one_patch() -> String {
        let mut s = String::from("1\n3 3\n");
        for k in 0..16 {
            s += &format!("{} {} {}\n", k % 4, k / 4, (k % 3) as f64 * 0.5);
        }
        s
    }

    #[test]
    fn parses_one_patch() {
        let p = parse_bpt(&one_patch(), "a.bpt").unwrap();
        assert_eq!(p.len(), 1);
        assert_eq!(p[0].0[6], DVec3::new(2.0, 1.0, 0.0));
        assert_eq!(p[0].1.line, 2);
    }

    #[test]
    fn errors_name_file_and_line() {
        let e = parse_bpt(&one_patch().replace("3 3", "2 3"), "a.bpt").unwrap_err();
        assert_eq!(
            e.to_string(),
            "a.bpt:2: patch 0: degrees 2 3 are not supported (only bicubic, 3 3)"
        );
        let e = parse_bpt(&one_patch().replace("0 1 0.5", "0 1 inf"), "a.bpt").unwrap_err();
        let want = "a.bpt:7: coordinate of control point 4 of patch 0 is not finite";
        assert!(e.to_string().starts_with(want), "{e}");
        let e = parse_bpt(&one_patch().replace("1\n3 3", "2\n3 3"), "a.bpt").unwrap_err();
        assert!(e.to_string().contains("unexpected end of file"), "{e}");
        let e = parse_bpt("x\n", "a.bpt").unwrap_err();
        assert_eq!(
            e.to_string(),
            "a.bpt:1: expected the patch count (an integer), found `x`"
        );
    }
}
