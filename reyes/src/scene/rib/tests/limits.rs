//! The reader's limits on what one input may make it hold (docs/reyes.md, "Limits"): array
//! lengths, strings, patches per frame, motion times, map sizes, truncated gzip input. Each
//! refused with an error naming the file and line; large inputs are generated as streams,
//! never stored.

use super::*;
use crate::scene::rib::input::{MAX_REQUEST_STRINGS, MAX_REQUEST_VALUES, Reader};
use crate::scene::rib::patches::TEST_MAX_FRAME_PATCHES;
use crate::scene::rib::{RibFrames, load_rib};
use std::io::Read;

/// A RIB stream of `head`, then `n` copies of `item`, then `tail`, made as it is read.
struct Repeat {
    head: std::io::Cursor<Vec<u8>>,
    item: Vec<u8>,
    left: usize,
    at: usize,
    tail: std::io::Cursor<Vec<u8>>,
}

impl Repeat {
    fn new(head: &str, item: &str, n: usize, tail: &str) -> Repeat {
        Repeat {
            head: std::io::Cursor::new(head.into()),
            item: item.into(),
            left: n,
            at: 0,
            tail: std::io::Cursor::new(tail.into()),
        }
    }
}

impl Read for Repeat {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = self.head.read(buf)?;
        if n > 0 {
            return Ok(n);
        }
        let mut k = 0;
        while self.left > 0 && k < buf.len() {
            let m = (self.item.len() - self.at).min(buf.len() - k);
            buf[k..k + m].copy_from_slice(&self.item[self.at..self.at + m]);
            k += m;
            self.at += m;
            if self.at == self.item.len() {
                self.at = 0;
                self.left -= 1;
            }
        }
        if k > 0 {
            return Ok(k);
        }
        self.tail.read(buf)
    }
}

/// The first error of the stream, as shown.
fn stream_err(src: Repeat) -> String {
    let frames = RibFrames::new(Reader::new(Box::new(src), "big.rib", None));
    frames
        .collect_sequence()
        .expect_err("expected an error")
        .to_string()
}

fn stream_ok(src: Repeat) -> crate::scene::FrameSequence {
    let frames = RibFrames::new(Reader::new(Box::new(src), "big.rib", None));
    frames.collect_sequence().unwrap_or_else(|e| panic!("{e}"))
}

/// One array of more numbers than a request may hold: refused at the line where it crosses
/// the limit, naming the line the array opened at, having held at most the limit.
#[test]
fn an_array_longer_than_the_limit_is_refused_at_its_line() {
    let src = Repeat::new(
        "WorldBegin\nPatchMesh \"bilinear\" 2 \"nonperiodic\" 2 \"nonperiodic\"\n\"P\" [\n",
        "0 0 0 0 0 0 0 0\n",
        MAX_REQUEST_VALUES / 8 + 1,
        "]\nWorldEnd\n",
    );
    let e = stream_err(src);
    // The request's 6 values before the array count too: the limit is crossed on the
    // (MAX / 8)th line of 8 numbers.
    let line = 3 + MAX_REQUEST_VALUES / 8;
    assert_eq!(
        e,
        format!(
            "big.rib:{line}: `PatchMesh`: more than {MAX_REQUEST_VALUES} values in one \
             request's arguments (the limit on array length) (in the array opened at line 3)"
        )
    );
}

/// Strings: a lower limit (each is an allocation), counted over bare strings and arrays.
#[test]
fn more_strings_than_the_limit_are_refused_at_their_line() {
    let src = Repeat::new(
        "WorldBegin\nSurface \"plastic\"\n",
        "\"a\" [\"b\"]\n",
        MAX_REQUEST_STRINGS / 2 + 1,
        "WorldEnd\n",
    );
    let e = stream_err(src);
    let line = 2 + MAX_REQUEST_STRINGS / 2;
    assert!(
        e.starts_with(&format!(
            "big.rib:{line}: `Surface`: more than {MAX_REQUEST_STRINGS} strings in one request's \
             arguments"
        )),
        "{e}"
    );
}

/// An unknown request's arguments are read through, never held: past both limits it is
/// skipped with its one warning, and the scene after it is read.
#[test]
fn unknown_requests_arguments_are_not_held() {
    let n = MAX_REQUEST_VALUES / 8 + 1;
    let src = Repeat::new(
        "Option \"x\" [\n",
        "0 0 0 0 0 0 0 0\n",
        n,
        &format!("] \"y\" 1\nWorldBegin\n{QUAD}\nWorldEnd\n"),
    );
    let seq = stream_ok(src);
    assert_eq!(seq.frames.len(), 1);
    assert_eq!(seq.frames[0].scene.patches.len(), 1);
    assert_eq!(seq.frames[0].scene.patches[0].source.line, n as u64 + 4);
    assert_eq!(
        seq.warnings,
        vec!["big.rib:1: skipped unsupported request `Option`".to_string()]
    );
}

/// The patch past the per-frame limit is refused at its request's line (the limit lowered
/// for the test: 4 million patches would take a minute); frames stream, so the limit is per
/// frame, not per file.
#[test]
fn patches_past_the_frame_limit_are_refused_at_their_line() {
    TEST_MAX_FRAME_PATCHES.with(|m| m.set(5));
    let frame = format!(
        "FrameBegin 1\nWorldBegin\n{}WorldEnd\nFrameEnd\n",
        format!("{QUAD}\n").repeat(5)
    );
    let seq = parse_rib_frames_ok(&frame.repeat(3));
    assert_eq!(seq.frames.len(), 3);
    let e = err(&world(&format!("{QUAD}\n").repeat(6)));
    TEST_MAX_FRAME_PATCHES.with(|m| m.set(crate::scene::rib::patches::MAX_FRAME_PATCHES));
    assert!(
        e.starts_with(
            "t.rib:7: `Patch`: patch 0: more than 5 patches in one frame (the limit on scene size"
        ),
        "{e}"
    );
}

fn parse_rib_frames_ok(text: &str) -> crate::scene::FrameSequence {
    crate::scene::rib::parse_rib_frames(text, "t.rib").unwrap_or_else(|e| panic!("{e}"))
}

/// 200,000 motion times then a smaller one: the error quotes the pair at fault, not the
/// list (it once made a 1.9 MB line).
#[test]
fn decreasing_motion_times_quote_the_pair_at_fault() {
    let times: Vec<String> = (0..200_000)
        .map(|k| k.to_string())
        .chain(["5".into()])
        .collect();
    let e = err(&world(&format!(
        "MotionBegin [{}]\nTranslate 0 0 1\nMotionEnd",
        times.join(" ")
    )));
    assert_eq!(
        e,
        "t.rib:2: `MotionBegin`: the times must increase: time 200001 of 200001 (5) is not \
         after time 200000 (199999)"
    );
}

/// A gzip scene cut short: the error names the line the reader had reached.
#[test]
fn a_truncated_gzip_scene_names_the_line_reached() {
    use std::io::Write;
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("cut.rib.gz");
    let mut text = String::from("WorldBegin\n");
    for k in 0..20_000 {
        text += &format!("Patch \"bilinear\" \"P\" [0 0 {k} 1 0 {k} 0 1 {k} 1 1 {k}]\n");
    }
    text += "WorldEnd\n";
    let mut gz = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
    gz.write_all(text.as_bytes()).unwrap();
    let bytes = gz.finish().unwrap();
    std::fs::write(&path, &bytes[..bytes.len() / 2]).unwrap();
    let e = load_rib(&path)
        .expect_err("a truncated gzip file")
        .to_string();
    let shown = path.display().to_string();
    let rest = e
        .strip_prefix(&format!("{shown}:"))
        .unwrap_or_else(|| panic!("{e}"));
    let (line, msg) = rest.split_once(": ").unwrap();
    let line: u64 = line.parse().unwrap_or_else(|_| panic!("{e}"));
    assert!(line > 100 && line < 20_002, "{e}");
    assert!(msg.starts_with("cannot read"), "{e}");
}

/// A PNG map larger than the texel limit is refused from its header (nothing decoded),
/// naming the map and the `Displacement` line. The PNG is its header and an empty `IDAT`
/// (16384 x 16384, no pixel data): a reader that decoded it would fail differently.
#[test]
fn a_map_over_the_texel_limit_is_refused_from_its_header() {
    let dir = tempfile::tempdir().unwrap();
    let png = dir.path().join("big.png");
    let mut bytes = b"\x89PNG\r\n\x1a\n".to_vec();
    let mut chunk = |kind: &[u8], data: &[u8]| {
        bytes.extend((data.len() as u32).to_be_bytes());
        let mut crc = flate2::Crc::new();
        crc.update(kind);
        crc.update(data);
        bytes.extend(kind);
        bytes.extend(data);
        bytes.extend(crc.sum().to_be_bytes());
    };
    let mut ihdr = 16384u32.to_be_bytes().repeat(2);
    ihdr.extend([8, 0, 0, 0, 0]); // 8-bit grey, deflate, no filter, no interlace
    chunk(b"IHDR", &ihdr);
    chunk(b"IDAT", &[]);
    chunk(b"IEND", &[]);
    std::fs::write(&png, &bytes).unwrap();
    let rib = dir.path().join("s.rib");
    let text = format!(
        "WorldBegin\nSurface \"matte\"\nDisplacement \"mapped\" \"mapname\" \"big.png\" \"Km\" 1\n{QUAD}\nWorldEnd\n"
    );
    std::fs::write(&rib, &text).unwrap();
    let e = load_rib(&rib)
        .expect_err("a map over the limit")
        .to_string();
    assert!(
        e.starts_with(&format!(
            "{}:3: `Displacement`: the displacement map ",
            rib.display()
        )),
        "{e}"
    );
    assert!(
        e.contains("is 16384x16384: each side must be 1..=16384 and the texels at most 16777216"),
        "{e}"
    );
}

/// The limits of docs/reyes.md not tested beside their own code: image size, pixel samples,
/// frame numbers, each refused at its line with the range it must be in.
#[test]
fn image_samples_and_frame_limits_name_file_and_line() {
    let side = crate::scene::MAX_IMAGE_SIDE;
    let cases = [
        (
            format!("Format {} 8 1\n{}", side + 1, world(QUAD)),
            format!("t.rib:1: `Format`: the x resolution must be an integer in 1..={side}"),
        ),
        (
            format!("\nPixelSamples 2 17\n{}", world(QUAD)),
            "t.rib:2: `PixelSamples`".to_string(),
        ),
        (
            format!("FrameBegin 100000000\n{}FrameEnd\n", world(QUAD)),
            "t.rib:1: `FrameBegin`: the frame number must be an integer in 0..=99999999"
                .to_string(),
        ),
    ];
    for (text, want) in cases {
        let e = err(&text);
        assert!(e.starts_with(&want), "{e}\nexpected {want}");
    }
}
