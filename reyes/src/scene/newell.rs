//! Newell's indexed teapot format: the patch count; per patch one line of 16 one-based
//! vertex indices (comma- or space-separated, u varying fastest); the vertex count; one
//! "x,y,z" line per vertex.

use super::{ObjectPatch, PatchSource, SceneError};
use glam::DVec3;

/// Whitespace/comma separated fields with their line numbers, shared with the BPT reader.
pub(crate) struct Fields<'a> {
    file: &'a str,
    fields: Vec<(&'a str, u64)>,
    pos: usize,
    last_line: u64,
}

impl<'a> Fields<'a> {
    pub(crate) fn new(text: &'a str, file: &'a str, commas: bool) -> Fields<'a> {
        let mut fields = Vec::new();
        let mut last_line = 1;
        for (n, line) in text.lines().enumerate() {
            let line_no = n as u64 + 1;
            last_line = line_no;
            let parts = line.split(|c: char| c.is_whitespace() || (commas && c == ','));
            fields.extend(parts.filter(|f| !f.is_empty()).map(|f| (f, line_no)));
        }
        Fields {
            file,
            fields,
            pos: 0,
            last_line,
        }
    }

    pub(crate) fn err(&self, line: u64, msg: impl Into<String>) -> SceneError {
        SceneError::new(self.file, line, msg)
    }

    fn next(&mut self, what: &str) -> Result<(&'a str, u64), SceneError> {
        let f = self.fields.get(self.pos).copied().ok_or_else(|| {
            self.err(
                self.last_line,
                format!("unexpected end of file: expected {what}"),
            )
        })?;
        self.pos += 1;
        Ok(f)
    }

    /// A non-negative integer; returns it with its line.
    pub(crate) fn int(&mut self, what: &str) -> Result<(u64, u64), SceneError> {
        let (f, line) = self.next(what)?;
        let v = f
            .parse::<u64>()
            .map_err(|_| self.err(line, format!("expected {what} (an integer), found `{f}`")))?;
        Ok((v, line))
    }

    /// A finite number; returns it with its line.
    pub(crate) fn float(&mut self, what: &str) -> Result<(f64, u64), SceneError> {
        let (f, line) = self.next(what)?;
        let v = f
            .parse::<f64>()
            .map_err(|_| self.err(line, format!("expected {what} (a number), found `{f}`")))?;
        if !v.is_finite() {
            return Err(self.err(line, format!("{what} is not finite (`{f}`)")));
        }
        Ok((v, line))
    }

    pub(crate) fn point(&mut self, what: &str) -> Result<(DVec3, u64), SceneError> {
        let (x, line) = self.float(what)?;
        let (y, _) = self.float(what)?;
        let (z, _) = self.float(what)?;
        Ok((DVec3::new(x, y, z), line))
    }

    pub(crate) fn finish(&self) -> Result<(), SceneError> {
        match self.fields.get(self.pos) {
            Some((f, line)) => Err(self.err(*line, format!("unexpected trailing data `{f}`"))),
            None => Ok(()),
        }
    }
}

/// Parses Newell's format into object-space Bezier patches.
pub fn parse_newell(text: &str, file: &str) -> Result<Vec<ObjectPatch>, SceneError> {
    let mut r = Fields::new(text, file, true);
    let (count, _) = r.int("the patch count")?;
    let mut indices = Vec::with_capacity(count.min(1 << 16) as usize);
    for p in 0..count {
        let mut idx = [0u64; 16];
        let mut line = 0;
        for (k, slot) in idx.iter_mut().enumerate() {
            let (v, l) = r.int(&format!("vertex index {k} of patch {p}"))?;
            if k == 0 {
                line = l;
            }
            *slot = v;
        }
        indices.push((idx, line));
    }
    let (nverts, _) = r.int("the vertex count")?;
    let mut verts = Vec::with_capacity(nverts.min(1 << 20) as usize);
    for v in 0..nverts {
        verts.push(r.point(&format!("coordinate of vertex {}", v + 1))?.0);
    }
    r.finish()?;
    let shared: std::sync::Arc<str> = file.into();
    indices
        .into_iter()
        .enumerate()
        .map(|(p, (idx, line))| {
            let mut cp = [DVec3::ZERO; 16];
            for (c, &i) in cp.iter_mut().zip(&idx) {
                if i == 0 || i > nverts {
                    return Err(r.err(
                        line,
                        format!("patch {p}: vertex index {i} is out of range 1..={nverts}"),
                    ));
                }
                *c = verts[i as usize - 1];
            }
            let src = PatchSource {
                file: shared.clone(),
                line,
                index: p as u32,
            };
            Ok((cp, src))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    const ONE: &str = "1\n1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16\n16\n\
        0,0,0\n1,0,0\n2,0,0\n3,0,0\n0,1,0\n1,1,1\n2,1,1\n3,1,0\n\
        0,2,0\n1,2,1\n2,2,1\n3,2,0\n0,3,0\n1,3,0\n2,3,0\n3,3,0\n";

    #[test]
    fn parses_indices_and_vertices() {
        let p = parse_newell(ONE, "one").unwrap();
        assert_eq!(p.len(), 1);
        assert_eq!(p[0].0[5], DVec3::new(1.0, 1.0, 1.0));
        assert_eq!(p[0].0[15], DVec3::new(3.0, 3.0, 0.0));
        assert_eq!(p[0].1.line, 2);
        // Spaces instead of commas work as well.
        let spaced = ONE.replace(',', " ");
        assert_eq!(parse_newell(&spaced, "one").unwrap()[0].0, p[0].0);
    }

    #[test]
    fn errors_name_file_and_line() {
        let e = parse_newell(&ONE.replace("1, 2, 3", "1, 2, 17"), "t").unwrap_err();
        assert_eq!(
            e.to_string(),
            "t:2: patch 0: vertex index 17 is out of range 1..=16"
        );
        let e = parse_newell(&ONE.replace("1, 2, 3", "1, 0, 3"), "t").unwrap_err();
        assert!(e.to_string().starts_with("t:2: patch 0: vertex index 0"));
        let e = parse_newell(&ONE.replace("2,1,1", "2,x,1"), "t").unwrap_err();
        assert_eq!(
            e.to_string(),
            "t:10: expected coordinate of vertex 7 (a number), found `x`"
        );
        let e = parse_newell(&ONE.replace("2,1,1", "2,nan,1"), "t").unwrap_err();
        assert!(
            e.to_string()
                .starts_with("t:10: coordinate of vertex 7 is not finite")
        );
        let truncated = &ONE[..ONE.len() - 8];
        let e = parse_newell(truncated, "t").unwrap_err();
        assert!(e.to_string().contains("unexpected end of file"), "{e}");
        let e = parse_newell(&format!("{ONE}7\n"), "t").unwrap_err();
        assert_eq!(e.to_string(), "t:20: unexpected trailing data `7`");
        assert!(parse_newell("", "t").is_err());
    }
}
