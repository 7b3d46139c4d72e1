//! A property test over mutated RIB files (the reader's fuzz target): the field files
//! (`field/**/*.rib` of the shared data) and the repository's scenes (`reyes/scenes/`), each
//! mutated a few ways at once (bytes changed, ranges deleted or repeated, hostile tokens
//! inserted, the end cut off), read through the whole stream of frames. Whatever the input,
//! the reader must not panic, must end, and every error and warning must name the file and a
//! line of it in a bounded message.
//!
//! The cases come from a fixed seed, so a failure repeats; their number (`CASES`, or
//! `REYES_FUZZ_CASES` for a longer run) keeps the test to seconds. Every input is at most
//! twice its file plus 64 KiB, and the reader's limits (docs/reyes.md, "Limits") bound what
//! one input can make it hold.

use crate::scene::rib::RibFrames;
use crate::scene::rib::input::Reader;
use std::path::{Path, PathBuf};

/// Cases of a test run (each a mutated file read to its end).
const CASES: usize = 4000;

/// Longest diagnostic allowed: the location, a sentence and a quoted token (cut at 64
/// characters) fit well within it.
const MAX_MESSAGE: usize = 600;

/// Tokens and fragments a mutation inserts: limits, non-numbers, block structure, requests
/// that read files or allocate.
const DICTIONARY: &[&str] = &[
    "1e308",
    "-1e38",
    "3.4e38",
    "1e-45",
    "nan",
    "inf",
    "-inf",
    "4294967296",
    "-1",
    "0",
    "65536",
    "[",
    "]",
    "\"",
    "\\",
    "#",
    "\n",
    "[]",
    "[1 2 3]",
    "[\"a\"]",
    "\"\"",
    "AttributeBegin",
    "AttributeEnd",
    "WorldBegin",
    "WorldEnd",
    "FrameBegin 1",
    "FrameEnd",
    "TransformBegin",
    "MotionBegin [0 1]",
    "MotionEnd",
    "ObjectBegin 1",
    "ObjectEnd",
    "ReadArchive \"read-archive.rib\"",
    "ReadArchive \"/etc/passwd\"",
    "Format 16384 16384 1",
    "PixelSamples 1024 1024",
    "Sphere 1e25 -1e25 1e25 360",
    "Scale 1e200 1 1",
    "Displacement \"bumps\" \"Km\" 1e30",
    "DepthOfField 1e-15 1 5",
    "Attribute \"displacementbound\" \"sphere\" [1e30]",
    "Basis \"bspline\" 1 \"bezier\" 3",
    "NuPatch 4 4 [0 0 0 0 1 1 1 1] 0 1 4 4 [0 0 0 0 1 1 1 1] 0 1",
    "Declare \"x\" \"varying float[99999999]\"",
    "Patch \"bicubic\" \"P\"",
    "PatchMesh \"bilinear\" 2 \"periodic\" 2 \"periodic\" \"P\"",
    "Shutter 0 1",
];

/// xorshift64*: small, deterministic, good enough to pick mutations.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }

    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

/// The RIB files under `dir`, recursively, in a fixed order.
fn rib_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    let mut paths: Vec<PathBuf> = entries.filter_map(|e| e.ok().map(|e| e.path())).collect();
    paths.sort();
    for p in paths {
        if p.is_dir() {
            rib_files(&p, out);
        } else if p.extension().is_some_and(|e| e == "rib") {
            out.push(p);
        }
    }
}

/// `text` changed one to four ways; at most twice as long plus 64 KiB.
fn mutate(text: &[u8], rng: &mut Rng) -> Vec<u8> {
    let mut t = text.to_vec();
    let limit = 2 * text.len() + (64 << 10);
    for _ in 0..1 + rng.below(4) {
        let at = rng.below(t.len() + 1);
        match rng.below(6) {
            // One byte, to a delimiter, a digit, a letter or any byte.
            0 if !t.is_empty() => {
                let bytes = b"[]\"#\n\\ 0919e.-+aZ\x00\x7f\xff";
                let at = at.min(t.len() - 1);
                t[at] = if rng.below(4) == 0 {
                    rng.next() as u8
                } else {
                    bytes[rng.below(bytes.len())]
                };
            }
            // A range deleted.
            1 => {
                let end = (at + 1 + rng.below(200)).min(t.len());
                t.drain(at.min(end)..end);
            }
            // A range repeated (a block or a request many times over).
            2 => {
                let end = (at + 1 + rng.below(400)).min(t.len());
                let piece = t[at.min(end)..end].to_vec();
                for _ in 0..1 + rng.below(50) {
                    if t.len() + piece.len() > limit {
                        break;
                    }
                    t.splice(at..at, piece.iter().copied());
                }
            }
            // The end cut off (inside a string, an array or a block).
            3 => t.truncate(at),
            // A hostile token, spaced as a token.
            _ => {
                let word = DICTIONARY[rng.below(DICTIONARY.len())];
                let piece = format!(" {word} ");
                if t.len() + piece.len() <= limit {
                    t.splice(at..at, piece.bytes());
                }
            }
        }
    }
    t
}

/// Checks one diagnostic (an error or a warning): bounded, and located at a file and line, a
/// line of the input (of `lines`) when the file is the input `file`.
fn check_message(case: &str, msg: &str, file: &str, lines: u64) {
    assert!(
        msg.len() <= MAX_MESSAGE,
        "{case}: a diagnostic of {} bytes: {}…",
        msg.len(),
        &msg[..msg.char_indices().nth(200).map_or(msg.len(), |(i, _)| i)]
    );
    // "FILE:LINE: message"; FILE is the input or an archive it read (by its own path).
    let (place, _) = msg
        .split_once(": ")
        .unwrap_or_else(|| panic!("{case}: no location: {msg}"));
    let (name, line) = place
        .rsplit_once(':')
        .unwrap_or_else(|| panic!("{case}: no line: {msg}"));
    let line: u64 = line
        .parse()
        .unwrap_or_else(|_| panic!("{case}: no line number: {msg}"));
    assert!(line >= 1, "{case}: line 0: {msg}");
    if name == file {
        assert!(
            line <= lines.max(1),
            "{case}: line {line} of an input of {lines} lines: {msg}"
        );
    }
}

/// Reads `bytes` as the file `path` (archives looked up beside it) through every frame;
/// asserts the properties above.
fn read_all(case: &str, path: &Path, bytes: Vec<u8>) {
    let file = path.display().to_string();
    let lines = bytes.split(|&b| b == b'\n').count() as u64;
    let result = std::panic::catch_unwind(|| {
        let mut out = Vec::new();
        let mut frames = RibFrames::new(Reader::new(Box::new(&bytes[..]), &file, Some(path)));
        for f in frames.by_ref() {
            match f {
                Ok(frame) => out.push(Ok(frame.scene.patches.len())),
                Err(e) => out.push(Err(e.error.to_string())),
            }
        }
        (out, frames.take_warnings())
    });
    let (out, warnings) = result.unwrap_or_else(|_| panic!("{case}: the reader panicked"));
    for r in &out {
        if let Err(msg) = r {
            check_message(case, msg, &file, lines);
        }
    }
    for w in &warnings {
        check_message(case, w, &file, lines);
    }
}

#[test]
fn mutated_field_files_never_panic_and_errors_name_file_and_line() {
    let mut files = Vec::new();
    rib_files(&crate::shared_data_dir().join("field"), &mut files);
    let field = files.len();
    rib_files(
        &Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes"),
        &mut files,
    );
    assert!(
        field >= 20 && files.len() > field,
        "{field} field files, {} in all: is REYES_SHARED_DATA set?",
        files.len()
    );
    let texts: Vec<Vec<u8>> = files.iter().map(|p| std::fs::read(p).unwrap()).collect();
    // The files as they are first (each must read without a panic too).
    for (p, t) in files.iter().zip(&texts) {
        read_all(&p.display().to_string(), p, t.clone());
    }
    let cases = std::env::var("REYES_FUZZ_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(CASES);
    let mut rng = Rng(0x5eed_1234_abcd_0001);
    for case in 0..cases {
        let k = rng.below(files.len());
        let bytes = mutate(&texts[k], &mut rng);
        let name = format!("case {case} ({})", files[k].display());
        read_all(&name, &files[k], bytes);
    }
}
