//! The files a scene reads, so that no output overwrites one (`-o SCENE.rib`, or a sequence
//! whose `Display` name is one of its own displacement maps, would replace the input by an
//! image). The scene's inputs are the scene file, the archives it reads (`ReadArchive`,
//! nested) and its displacement maps (`"mapname"`), looked up as the reader looks them up:
//! beside the file that names them, then in the current directory.
//!
//! The reader does not record them, so they are collected here by a light scan of the files'
//! quoted strings (a string after `ReadArchive`, a string after `"mapname"`), and only when
//! needed: an output can only be an input if it exists, so the scan runs once, the first time
//! an output already exists (a render to new names never reads the scene twice).

use crate::error::CliError;
use std::collections::HashSet;
use std::io::{BufReader, Read};
use std::path::{Path, PathBuf};

/// How deep archives are followed (the reader's own limit).
const MAX_DEPTH: usize = 32;
/// Longer quoted strings are not file names worth looking up.
const MAX_NAME: usize = 4096;

/// The scene's inputs, collected on first use.
pub struct SceneInputs {
    /// The scene file (`None`: the built-in teapot, which reads nothing).
    scene: Option<PathBuf>,
    /// Canonical input paths with the name they were found under; `None` until needed.
    found: Option<Vec<(PathBuf, PathBuf)>>,
}

impl SceneInputs {
    /// The inputs of the scene file `scene` (`None` or `teapot`: none).
    pub fn new(scene: Option<&Path>) -> SceneInputs {
        SceneInputs {
            scene: scene
                .filter(|p| p.as_os_str() != "teapot")
                .map(Path::to_path_buf),
            found: None,
        }
    }

    /// Refuses `outputs` when one of them is (by its canonical path, links followed as the
    /// output is written) one of the scene's inputs, naming both
    /// ([`CliError::OutputIsInput`]).
    pub fn check<'p>(
        &mut self,
        outputs: impl IntoIterator<Item = &'p Path>,
    ) -> Result<(), CliError> {
        for out in outputs {
            let Ok(canonical) = std::fs::canonicalize(out) else {
                continue; // not there yet: not an input
            };
            let Some(scene) = &self.scene else {
                return Ok(());
            };
            let found = self.found.get_or_insert_with(|| collect(scene));
            if let Some((_, input)) = found.iter().find(|(c, _)| *c == canonical) {
                return Err(CliError::OutputIsInput {
                    output: out.to_path_buf(),
                    input: input.clone(),
                });
            }
        }
        Ok(())
    }
}

/// The scene file's inputs: (canonical path, the name found) of the file, its archives and
/// its maps. Files that cannot be read are left out (the reader reports them).
pub fn collect(scene: &Path) -> Vec<(PathBuf, PathBuf)> {
    let mut found = Vec::new();
    let mut seen = HashSet::new();
    scan(scene, 0, &mut found, &mut seen);
    found
}

/// Adds `file` and what it reads to `found`.
fn scan(
    file: &Path,
    depth: usize,
    found: &mut Vec<(PathBuf, PathBuf)>,
    seen: &mut HashSet<PathBuf>,
) {
    let Ok(canonical) = std::fs::canonicalize(file) else {
        return;
    };
    if !seen.insert(canonical.clone()) {
        return;
    }
    found.push((canonical, file.to_path_buf()));
    let Ok(src) = reyes::scene::open_rib(file) else {
        return;
    };
    let dir = file.parent().map(Path::to_path_buf).unwrap_or_default();
    let lookup = |name: &str| {
        [dir.join(name), PathBuf::from(name)]
            .into_iter()
            .find(|p| p.is_file())
    };
    for (kind, name) in named_files(src) {
        let Some(path) = lookup(&name) else { continue };
        match kind {
            Named::Archive if depth < MAX_DEPTH => scan(&path, depth + 1, found, seen),
            Named::Archive => {}
            Named::Map => {
                if let Ok(c) = std::fs::canonicalize(&path)
                    && seen.insert(c.clone())
                {
                    found.push((c, path));
                }
            }
        }
    }
}

/// What a quoted string names.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Named {
    Archive,
    Map,
}

/// The strings of a RIB stream that name files: after `ReadArchive`, after `"mapname"`
/// (alone or in brackets). Comments are skipped; other tokens only end what came before.
fn named_files(src: Box<dyn Read>) -> Vec<(Named, String)> {
    let mut out = Vec::new();
    let mut expect: Option<Named> = None;
    let mut bytes = BufReader::with_capacity(64 << 10, src).bytes();
    let mut word = Vec::new();
    let end_word = |word: &mut Vec<u8>, expect: &mut Option<Named>| {
        if !word.is_empty() {
            *expect = (word.as_slice() == b"ReadArchive").then_some(Named::Archive);
            word.clear();
        }
    };
    while let Some(Ok(b)) = bytes.next() {
        match b {
            b'#' => {
                end_word(&mut word, &mut expect);
                for c in bytes.by_ref() {
                    if matches!(c, Ok(b'\n') | Err(_)) {
                        break;
                    }
                }
            }
            b'"' => {
                end_word(&mut word, &mut expect);
                let mut s = Vec::new();
                let mut escaped = false;
                for c in bytes.by_ref() {
                    let Ok(c) = c else { break };
                    if escaped {
                        escaped = false;
                    } else if c == b'\\' {
                        escaped = true;
                        continue;
                    } else if c == b'"' {
                        break;
                    }
                    if s.len() <= MAX_NAME {
                        s.push(c);
                    }
                }
                let s = String::from_utf8_lossy(&s).into_owned();
                if let Some(kind) = expect
                    && s.len() <= MAX_NAME
                {
                    out.push((kind, s.clone()));
                }
                expect = (s == "mapname").then_some(Named::Map);
            }
            b'[' | b']' => end_word(&mut word, &mut expect),
            c if c.is_ascii_whitespace() => end_word(&mut word, &mut expect),
            c if c.is_ascii_alphabetic() || (!word.is_empty() && c.is_ascii_alphanumeric()) => {
                word.push(c)
            }
            _ => {
                // A number (or anything else): not a name's request.
                word.clear();
                expect = None;
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn archives_and_maps_are_found_beside_the_file_that_names_them() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        std::fs::create_dir(d.join("sub")).unwrap();
        std::fs::write(d.join("bumps.png"), b"png").unwrap();
        std::fs::write(d.join("sub/inner.png"), b"png").unwrap();
        std::fs::write(
            d.join("sub/a.rib"),
            "Displacement \"mapped\" \"mapname\" [\"inner.png\"] \"Km\" 1\n",
        )
        .unwrap();
        std::fs::write(
            d.join("s.rib"),
            "# ReadArchive \"commented.rib\"\nDisplay \"bumps.png\" \"file\" \"rgba\"\n\
             ReadArchive \"sub/a.rib\"\nDisplacement \"mapped\" \"mapname\" \"bumps.png\" \
             \"Km\" 1\nReadArchive \"s.rib\"\n",
        )
        .unwrap();
        let names: Vec<PathBuf> = collect(&d.join("s.rib")).into_iter().map(|f| f.1).collect();
        assert_eq!(
            names,
            [
                d.join("s.rib"),
                d.join("sub/a.rib"),
                d.join("sub/inner.png"),
                d.join("bumps.png")
            ]
        );
        let mut inputs = SceneInputs::new(Some(&d.join("s.rib")));
        let new = d.join("new.png");
        assert!(inputs.check([new.as_path()]).is_ok());
        let e = inputs
            .check([new.as_path(), &d.join("sub/../bumps.png")])
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("bumps.png") && e.contains("an input of the scene"),
            "{e}"
        );
        assert!(
            SceneInputs::new(None)
                .check([d.join("s.rib").as_path()])
                .is_ok()
        );
    }
}
