//! `reyes render` on frame sequences: the files each frame writes, decided frame by frame as
//! the frames stream in. Pure functions of the frame and the command line, so the naming
//! rules are tested without rendering.
//!
//! Output names, per frame:
//! - a name with a frame-number pattern (`-o out.####.png` or `out.%04d.png`, also `--stats`,
//!   `--float`, `--depth`, `--exr`): the number, zero-padded to the run of `#` (to N for
//!   `%0Nd`; `%d`: not padded);
//! - a file of one frame, or one frame selected (`--frame N`): `-o` as given, else `SCENE.png`
//!   (as before sequences existed);
//! - a sequence: the frame's `Display` name in `-o`'s folder (its file name only: a scene
//!   file does not choose folders), with the extension `.png`; without a `Display`,
//!   `STEM.NNNN.png` where STEM is `-o`'s stem or the scene's.
//!
//! Several frames are rendered when the file has several and the selection is not one frame
//! number: then `--stats` (etc.) need a pattern. Two frames writing one file is an error of
//! the later frame. Frames the renderer cannot make (shadow-map passes) are skipped with a
//! warning.

use crate::error::CliError;
use reyes::scene::SceneFrame;
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// The files one frame writes.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Outputs {
    pub image: PathBuf,
    pub stats: Option<PathBuf>,
    pub float: Option<PathBuf>,
    pub depth: Option<PathBuf>,
    pub exr: Option<PathBuf>,
}

impl Outputs {
    /// Every file the frame writes: the image, and on the GPU path (`cpu` false) the others.
    pub fn files(&self, cpu: bool) -> Vec<&Path> {
        let mut v = vec![self.image.as_path()];
        if !cpu {
            let rest = [&self.stats, &self.float, &self.depth, &self.exr];
            v.extend(rest.into_iter().flatten().map(PathBuf::as_path));
        }
        v
    }
}

/// Where the command line says outputs go.
pub struct Requested<'a> {
    pub out: Option<&'a Path>,
    pub stats: Option<&'a Path>,
    pub float: Option<&'a Path>,
    pub depth: Option<&'a Path>,
    pub exr: Option<&'a Path>,
    /// The scene's stem ("teapot" for teapot.rib), for default names.
    pub stem: &'a str,
}

/// Names each frame's outputs as the frames come, remembering the images named so far.
pub struct Namer<'a> {
    req: &'a Requested<'a>,
    /// The file has several frames.
    sequence: bool,
    /// Several frames may be rendered.
    several: bool,
    /// Images named so far, with their frame.
    named: HashMap<PathBuf, u32>,
    /// The output folders were checked (they are the same for every frame).
    checked: bool,
}

impl<'a> Namer<'a> {
    /// The naming of a file of several frames (`sequence`) or one, of which several may be
    /// rendered (`several`). Errors: a `--stats` (etc.) name without a pattern when several
    /// are.
    pub fn new(
        req: &'a Requested<'a>,
        sequence: bool,
        several: bool,
    ) -> Result<Namer<'a>, CliError> {
        let sides = [
            (req.stats, "--stats"),
            (req.float, "--float"),
            (req.depth, "--depth"),
            (req.exr, "--exr"),
        ];
        for (p, flag) in sides {
            if several && p.is_some_and(|p| !has_pattern(p)) {
                return Err(CliError::UnnumberedOutput { flag });
            }
        }
        if let Some(out) = req.out.filter(|o| sequence && several && !has_pattern(o)) {
            log::warn!(
                "-o {}: several frames are rendered, so each is written under its `Display` \
                 name in that folder (give -o NAME.####.png for numbered names)",
                out.display()
            );
        }
        Ok(Namer {
            req,
            sequence,
            several,
            named: HashMap::new(),
            checked: false,
        })
    }

    /// The files `frame` writes. Errors: an output folder that does not exist (checked with
    /// the first frame: every frame's outputs share their folders), an image an earlier
    /// frame writes ([`CliError::SameOutput`]).
    pub fn outputs(&mut self, frame: &SceneFrame) -> Result<Outputs, CliError> {
        let (req, n) = (self.req, frame.number);
        let side = |p: Option<&Path>| match p {
            Some(p) if has_pattern(p) => Some(numbered(p, n)),
            p => p.map(Path::to_path_buf),
        };
        let outputs = Outputs {
            image: image_path(frame, req, self.sequence, self.several),
            stats: side(req.stats),
            float: side(req.float),
            depth: side(req.depth),
            exr: side(req.exr),
        };
        check_names(frame, &outputs, self.sequence)?;
        if !self.checked {
            check_folders(&outputs)?;
            self.checked = true;
        }
        if let Some(&first) = self.named.get(&outputs.image) {
            return Err(CliError::SameOutput {
                first,
                second: n,
                path: outputs.image,
            });
        }
        self.named.insert(outputs.image.clone(), n);
        Ok(outputs)
    }
}

/// The longest file name (one path component) written, in bytes: `NAME_MAX` of Linux's file
/// systems (and of macOS's and Windows', in their units).
pub const MAX_NAME_BYTES: usize = 255;

/// The longest output path, in bytes (Linux's `PATH_MAX` less its NUL).
pub const MAX_PATH_BYTES: usize = 4095;

/// Every output's name is one the file system can hold: no NUL, no component longer than
/// [`MAX_NAME_BYTES`], no path longer than [`MAX_PATH_BYTES`]; checked for each frame before it
/// renders, so that no render is wasted on a name that cannot be written (a 300-character
/// `Display` name would fail only after rendering). An image named by the frame's
/// `Display` is blamed on it.
fn check_names(frame: &SceneFrame, o: &Outputs, sequence: bool) -> Result<(), CliError> {
    for (i, p) in o.files(false).into_iter().enumerate() {
        let Some(why) = bad_name(p) else { continue };
        let display = frame.display.as_ref().filter(|_| sequence && i == 0);
        let what = match display.filter(|d| bad_name(Path::new(&d.name)).is_some()) {
            Some(d) => format!(
                "the Display name \"{}\" ({} bytes)",
                shown(&d.name),
                d.name.len()
            ),
            None => format!("output {}", shown(&p.to_string_lossy())),
        };
        return Err(CliError::BadOutputName { what, why });
    }
    Ok(())
}

/// Why the file system cannot hold `p`, if it cannot.
fn bad_name(p: &Path) -> Option<String> {
    let bytes = p.as_os_str().as_encoded_bytes();
    if bytes.contains(&0) {
        return Some("a file name cannot hold a NUL byte".into());
    }
    if let Some(c) = p
        .components()
        .find(|c| c.as_os_str().len() > MAX_NAME_BYTES)
    {
        return Some(format!(
            "the file name \"{}\" is {} bytes, more than the {MAX_NAME_BYTES} a file name may have",
            shown(&c.as_os_str().to_string_lossy()),
            c.as_os_str().len()
        ));
    }
    if bytes.len() > MAX_PATH_BYTES {
        return Some(format!(
            "the path is {} bytes, more than the {MAX_PATH_BYTES} a path may have",
            bytes.len()
        ));
    }
    None
}

/// `s` as messages quote it: control characters escaped, cut after 40 characters.
fn shown(s: &str) -> String {
    let mut out: String = s.chars().take(40).flat_map(char::escape_debug).collect();
    if s.chars().count() > 40 {
        out.push_str("...");
    }
    out
}

/// Every output's folder exists, so that a frame never fails after rendering (or after an
/// earlier frame was written) for want of one.
fn check_folders(o: &Outputs) -> Result<(), CliError> {
    for p in o.files(false) {
        let dir = p.parent().filter(|d| !d.as_os_str().is_empty());
        if let Some(d) = dir
            && !d.is_dir()
        {
            return Err(CliError::MissingFolder {
                path: p.to_path_buf(),
                folder: d.to_path_buf(),
            });
        }
    }
    Ok(())
}

/// Whether the file name of `p` holds a frame-number pattern: a run of `#`, `%d` or `%0Nd`.
pub fn has_pattern(p: &Path) -> bool {
    p.file_name()
        .is_some_and(|n| pattern(&n.to_string_lossy()).is_some())
}

/// The first frame-number pattern of `name`: its byte range and padding (`####`: 4,
/// `%04d`: 4, `%d`: 0).
fn pattern(name: &str) -> Option<(usize, usize, usize)> {
    let hash = name.find('#').map(|start| {
        let len = name[start..].chars().take_while(|&c| c == '#').count();
        (start, start + len, len)
    });
    let printf = name.match_indices('%').find_map(|(start, _)| {
        let rest = &name[start + 1..];
        let digits = rest.chars().take_while(char::is_ascii_digit).count();
        if !rest[digits..].starts_with('d') || (digits > 0 && !rest.starts_with('0')) {
            return None;
        }
        let pad = if digits > 0 {
            rest[..digits].parse().ok()?
        } else {
            0
        };
        Some((start, start + 1 + digits + 1, pad))
    });
    match (hash, printf) {
        (Some(h), Some(p)) => Some(if h.0 < p.0 { h } else { p }),
        (h, p) => h.or(p),
    }
}

/// `p` with the first frame-number pattern in its file name replaced by `n`, zero-padded to
/// the pattern's width (`out.####.png` or `out.%04d.png`, 7: `out.0007.png`; `out.%d.png`:
/// `out.7.png`).
pub fn numbered(p: &Path, n: u32) -> PathBuf {
    let name = p.file_name().unwrap_or_default().to_string_lossy();
    let Some((start, end, pad)) = pattern(&name) else {
        return p.to_path_buf();
    };
    let name = format!("{}{n:0pad$}{}", &name[..start], &name[end..]);
    p.with_file_name(name)
}

/// True when `-o` names a folder: it ends with a separator or is an existing folder.
fn is_folder(p: &Path) -> bool {
    p.as_os_str()
        .to_string_lossy()
        .ends_with(std::path::MAIN_SEPARATOR)
        || p.is_dir()
}

/// The image of `frame`: `-o`'s pattern numbered; `-o`'s name when one frame is rendered;
/// else, in `-o`'s folder (`-o` itself when it names one), the frame's `Display` name or
/// `<stem>.<frame>.png`.
fn image_path(frame: &SceneFrame, req: &Requested, sequence: bool, several: bool) -> PathBuf {
    if let Some(out) = req.out.filter(|p| has_pattern(p)) {
        return numbered(out, frame.number);
    }
    let folder = req.out.filter(|p| is_folder(p));
    let file = req.out.filter(|_| folder.is_none());
    if let Some(out) = file.filter(|_| !several) {
        return out.to_path_buf();
    }
    if !sequence && folder.is_none() {
        return PathBuf::from(format!("{}.png", req.stem));
    }
    let dir = match (folder, file) {
        (Some(f), _) => f.to_path_buf(),
        (None, Some(out)) => out.parent().map(Path::to_path_buf).unwrap_or_default(),
        (None, None) => PathBuf::new(),
    };
    let from_display = (frame.display.as_ref())
        .filter(|_| sequence)
        .and_then(|d| Path::new(&d.name).file_name())
        .map(|n| as_png(Path::new(n)));
    let name = from_display.unwrap_or_else(|| match (file, sequence) {
        (Some(out), _) => {
            let stem = out.file_stem().map(|s| s.to_string_lossy().into_owned());
            let stem = stem.unwrap_or_else(|| req.stem.to_string());
            PathBuf::from(format!("{stem}.{:04}.png", frame.number))
        }
        (None, true) => PathBuf::from(format!("{}.{:04}.png", req.stem, frame.number)),
        (None, false) => PathBuf::from(format!("{}.png", req.stem)),
    });
    dir.join(name)
}

/// `name` with the extension `png`: an image extension is replaced (`a.0001.tif`), a frame
/// number or nothing is kept (`a.0001`, `a`: `.png` is added).
fn as_png(name: &Path) -> PathBuf {
    match name.extension().map(|e| e.to_string_lossy()) {
        Some(e) if !e.is_empty() && !e.chars().all(|c| c.is_ascii_digit()) => {
            name.with_extension("png")
        }
        _ => PathBuf::from(format!("{}.png", name.display())),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use reyes::scene::{Display, FrameRanges, FrameSequence, Scene};

    /// The frames rendered (indices) with their outputs, and the skipped frames' warnings.
    type Plan = (Vec<(usize, Outputs)>, Vec<String>);

    /// What `reyes render` names for the frames of `seq` (selected by `selection`) as they
    /// stream: the frames rendered with their outputs, the skipped frames' warnings; the first
    /// error.
    fn plan(
        seq: &FrameSequence,
        selection: Option<&FrameRanges>,
        req: &Requested,
    ) -> Result<Plan, CliError> {
        let sequence = seq.frames.len() > 1;
        let several = sequence && selection.is_none_or(|s| s.single().is_none());
        let mut namer = Namer::new(req, sequence, several)?;
        let (mut jobs, mut warnings) = (Vec::new(), Vec::new());
        for (i, f) in seq.frames.iter().enumerate() {
            if selection.is_some_and(|s| !s.contains(f.number)) {
                continue;
            }
            match &f.unsupported {
                Some(why) => warnings.push(format!("skipped frame {}: {why}", f.number)),
                None => jobs.push((i, namer.outputs(f)?)),
            }
        }
        Ok((jobs, warnings))
    }

    fn seq(frames: &[(u32, Option<&str>, Option<&str>)]) -> FrameSequence {
        FrameSequence {
            frames: frames
                .iter()
                .map(|&(number, display, unsupported)| SceneFrame {
                    number,
                    display: display.map(|d| Display {
                        name: d.into(),
                        kind: "file".into(),
                        mode: "rgba".into(),
                    }),
                    unsupported: unsupported.map(String::from),
                    scene: Scene::default(),
                })
                .collect(),
            warnings: vec![],
        }
    }

    fn req<'a>(out: Option<&'a str>, stats: Option<&'a str>) -> Requested<'a> {
        Requested {
            out: out.map(Path::new),
            stats: stats.map(Path::new),
            float: None,
            depth: None,
            exr: None,
            stem: "scene",
        }
    }

    fn images(s: &FrameSequence, sel: Option<&str>, r: &Requested) -> Vec<String> {
        let sel = sel.map(|s| FrameRanges::parse(s).unwrap());
        plan(s, sel.as_ref(), r)
            .unwrap()
            .0
            .into_iter()
            .map(|(_, o)| o.image.display().to_string())
            .collect()
    }

    #[test]
    fn numbered_names() {
        assert_eq!(
            numbered(Path::new("d/o.####.png"), 7),
            Path::new("d/o.0007.png")
        );
        assert_eq!(numbered(Path::new("o#.png"), 12), Path::new("o12.png"));
        assert_eq!(numbered(Path::new("o.##.png"), 123), Path::new("o.123.png"));
        assert_eq!(
            numbered(Path::new("d/shot.%04d.png"), 7),
            Path::new("d/shot.0007.png")
        );
        assert_eq!(numbered(Path::new("s.%d.png"), 12), Path::new("s.12.png"));
        assert_eq!(
            numbered(Path::new("s_%02d_#.png"), 3),
            Path::new("s_03_#.png")
        );
        assert!(has_pattern(Path::new("a.%04d.exr")) && has_pattern(Path::new("a%d")));
        for plain in ["a.png", "a%.png", "a.%4d.png", "a.%x.png", "d%04d/a.png"] {
            assert!(!has_pattern(Path::new(plain)), "{plain}");
        }
    }

    #[test]
    fn display_names_in_the_output_folder() {
        let s = seq(&[
            (1, Some("teapot.0001.png"), None),
            (2, Some("/etc/teapot.0002.tif"), None),
            (3, Some("teapot.0003"), None),
        ]);
        let dir = std::env::temp_dir();
        let out = dir.join("x.png");
        let got = images(&s, None, &req(out.to_str(), None));
        let want: Vec<String> = (1..=3)
            .map(|n| dir.join(format!("teapot.000{n}.png")).display().to_string())
            .collect();
        assert_eq!(got, want);
        let e = plan(&s, None, &req(Some("/nonexistent/d/x.png"), None))
            .unwrap_err()
            .to_string();
        assert_eq!(
            e,
            "/nonexistent/d/teapot.0001.png: the folder /nonexistent/d does not exist"
        );
        let e = plan(&s, None, &req(None, Some("/nonexistent/s.####.json")))
            .unwrap_err()
            .to_string();
        assert!(e.contains("the folder /nonexistent does not exist"), "{e}");
        assert_eq!(
            images(&s, None, &req(None, None)),
            ["teapot.0001.png", "teapot.0002.png", "teapot.0003.png"]
        );
        assert_eq!(
            images(&s, Some("2-3"), &req(Some("f.####.png"), None)),
            ["f.0002.png", "f.0003.png"]
        );
        assert_eq!(images(&s, Some("1,3"), &req(None, None)).len(), 2);
    }

    #[test]
    fn sequences_without_display_and_single_frames() {
        let s = seq(&[(1, None, None), (2, None, None)]);
        assert_eq!(
            images(&s, None, &req(Some("x.png"), None)),
            ["x.0001.png", "x.0002.png"]
        );
        assert_eq!(
            images(&s, None, &req(None, None)),
            ["scene.0001.png", "scene.0002.png"]
        );
        // One frame: as before sequences, Display or not.
        let one = seq(&[(1, Some("elsewhere.tif"), None)]);
        assert_eq!(images(&one, None, &req(Some("x.png"), None)), ["x.png"]);
        assert_eq!(images(&one, None, &req(None, None)), ["scene.png"]);
    }

    #[test]
    fn skipped_frames_and_errors() {
        let s = seq(&[
            (1, Some("a.png"), Some("a shadow-map pass")),
            (2, Some("b.png"), None),
        ]);
        // A sequence: --stats needs a pattern unless one frame is selected.
        let e = plan(&s, None, &req(None, Some("s.json"))).unwrap_err();
        assert!(e.to_string().contains("--stats: several frames"), "{e}");
        let two = FrameRanges::parse("2").unwrap();
        let (jobs, warnings) = plan(&s, Some(&two), &req(None, Some("s.json"))).unwrap();
        assert_eq!(jobs.len(), 1);
        assert_eq!(jobs[0].1.stats.as_deref(), Some(Path::new("s.json")));
        assert!(warnings.is_empty());
        let (_, warnings) = plan(&s, None, &req(None, Some("s.#.json"))).unwrap();
        assert_eq!(warnings, ["skipped frame 1: a shadow-map pass"]);
        let two = seq(&[(1, None, None), (2, None, None)]);
        let e = plan(&two, None, &req(None, Some("s.json")))
            .unwrap_err()
            .to_string();
        assert!(e.contains("--stats: several frames"), "{e}");
        let (jobs, _) = plan(&two, None, &req(None, Some("s.####.json"))).unwrap();
        assert_eq!(jobs[1].1.stats.as_deref(), Some(Path::new("s.0002.json")));
        // Names the file system cannot hold fail their frame before it renders, blaming the
        // Display name, rather than rendering and then failing with "File name too long".
        let long = "d".repeat(300);
        let bad = seq(&[(1, Some("a.png"), None), (2, Some(&long), None)]);
        let r = req(None, None);
        let mut namer = Namer::new(&r, true, true).unwrap();
        assert!(namer.outputs(&bad.frames[0]).is_ok());
        let e = namer.outputs(&bad.frames[1]).unwrap_err().to_string();
        assert!(
            e.starts_with("the Display name \"dddd") && e.contains("(300 bytes)"),
            "{e}"
        );
        assert!(e.contains("304 bytes, more than the 255"), "{e}");
        let nul = seq(&[(1, Some("a\0b.png"), None), (2, None, None)]);
        let e = plan(&nul, None, &req(None, None)).unwrap_err().to_string();
        assert!(e.contains("a\\0b.png") && e.contains("NUL"), "{e}");
        let e = plan(&two, None, &req(Some(&format!("{long}.####.png")), None))
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("output dddd"), "{e}");
        let same = seq(&[(1, Some("x.png"), None), (2, Some("x.tif"), None)]);
        let e = plan(&same, None, &req(None, None)).unwrap_err().to_string();
        assert_eq!(e, "frames 1 and 2 would both write x.png");
    }
}
