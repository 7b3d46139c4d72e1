//! `reyes render` on frame sequences: which frames to render (`--frames`) and the files each
//! writes. Pure functions of the sequence and the command line, so the naming rules are
//! tested without rendering.
//!
//! Output names, per frame:
//! - a name with a run of `#` (`-o out.####.png`, also `--stats`, `--float`, `--depth`, `--exr`): the
//!   run becomes the frame number, zero-padded to its length;
//! - a file of one frame: `-o` as given, else `SCENE.png` (as before sequences existed);
//! - a sequence: the frame's `Display` name in `-o`'s folder (its file name only: a scene
//!   file does not choose folders), with the extension `.png`; without a `Display`,
//!   `STEM.NNNN.png` where STEM is `-o`'s stem or the scene's.
//!
//! Frames the renderer cannot make (shadow-map passes) are skipped with a warning.

use crate::error::CliError;
use reyes::scene::{FrameRanges, FrameSequence, SceneFrame};
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

/// The frames to render (indices into `seq.frames`) with their outputs, and warnings for the
/// selected frames that are skipped.
pub type Plan = (Vec<(usize, Outputs)>, Vec<String>);

/// The frames to render (indices into `seq.frames`) with their outputs, and warnings for the
/// selected frames that are skipped ([`Plan`]). Errors: a selection that matches no frame, a `--stats`
/// (etc.) name without `#` when several frames are rendered, two frames writing one file.
pub fn plan(
    seq: &FrameSequence,
    selection: Option<&FrameRanges>,
    req: &Requested,
) -> Result<Plan, CliError> {
    let selected: Vec<usize> = (0..seq.frames.len())
        .filter(|&i| selection.is_none_or(|s| s.contains(seq.frames[i].number)))
        .collect();
    if selected.is_empty() {
        let numbers: Vec<String> = seq.frames.iter().map(|f| f.number.to_string()).collect();
        return Err(CliError::NoFrameSelected {
            numbers: numbers.join(", "),
        });
    }
    let mut warnings = Vec::new();
    let mut jobs = Vec::new();
    for i in selected {
        let frame = &seq.frames[i];
        match &frame.unsupported {
            Some(why) => warnings.push(format!("skipped frame {}: {why}", frame.number)),
            None => jobs.push(i),
        }
    }
    let several = jobs.len() > 1;
    let sequence = seq.frames.len() > 1;
    let side =
        |p: Option<&Path>, flag: &'static str, n: u32| -> Result<Option<PathBuf>, CliError> {
            match p {
                None => Ok(None),
                Some(p) if has_pattern(p) => Ok(Some(numbered(p, n))),
                Some(_) if several => Err(CliError::UnnumberedOutput { flag }),
                Some(p) => Ok(Some(p.to_path_buf())),
            }
        };
    let mut out = Vec::new();
    for i in jobs {
        let frame = &seq.frames[i];
        let n = frame.number;
        let outputs = Outputs {
            image: image_path(frame, req, sequence, several),
            stats: side(req.stats, "--stats", n)?,
            float: side(req.float, "--float", n)?,
            depth: side(req.depth, "--depth", n)?,
            exr: side(req.exr, "--exr", n)?,
        };
        if let Some((j, _)) = out
            .iter()
            .find(|(_, o): &&(usize, Outputs)| o.image == outputs.image)
        {
            return Err(CliError::SameOutput {
                first: seq.frames[*j].number,
                second: n,
                path: outputs.image,
            });
        }
        check_folders(&outputs)?;
        out.push((i, outputs));
    }
    Ok((out, warnings))
}

/// Every output's folder exists, so that a frame never fails after rendering (or after an
/// earlier frame was written) for want of one.
fn check_folders(o: &Outputs) -> Result<(), CliError> {
    let paths = [
        Some(&o.image),
        o.stats.as_ref(),
        o.float.as_ref(),
        o.depth.as_ref(),
        o.exr.as_ref(),
    ];
    for p in paths.into_iter().flatten() {
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

/// Whether the file name of `p` holds a `#` run.
fn has_pattern(p: &Path) -> bool {
    p.file_name()
        .is_some_and(|n| n.to_string_lossy().contains('#'))
}

/// `p` with the first run of `#` in its file name replaced by `n`, zero-padded to the run's
/// length (`out.####.png`, 7: `out.0007.png`).
pub fn numbered(p: &Path, n: u32) -> PathBuf {
    let name = p.file_name().unwrap_or_default().to_string_lossy();
    let Some(start) = name.find('#') else {
        return p.to_path_buf();
    };
    let len = name[start..].chars().take_while(|&c| c == '#').count();
    let name = format!(
        "{}{n:0len$}{}",
        &name[..start],
        &name[start + len..],
        len = len
    );
    p.with_file_name(name)
}

/// True when `-o` names a folder: it ends with a separator or is an existing folder.
fn is_folder(p: &Path) -> bool {
    p.as_os_str()
        .to_string_lossy()
        .ends_with(std::path::MAIN_SEPARATOR)
        || p.is_dir()
}

/// The image of `frame`: `-o`'s #### pattern numbered; `-o`'s name when one frame is rendered;
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
    use reyes::scene::{Display, Scene};

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
        let (jobs, warnings) = plan(&s, None, &req(None, Some("s.json"))).unwrap();
        assert_eq!(jobs.len(), 1);
        assert_eq!(jobs[0].1.stats.as_deref(), Some(Path::new("s.json")));
        assert_eq!(warnings, ["skipped frame 1: a shadow-map pass"]);
        let two = seq(&[(1, None, None), (2, None, None)]);
        let e = plan(&two, None, &req(None, Some("s.json")))
            .unwrap_err()
            .to_string();
        assert!(e.contains("--stats: several frames"), "{e}");
        let (jobs, _) = plan(&two, None, &req(None, Some("s.####.json"))).unwrap();
        assert_eq!(jobs[1].1.stats.as_deref(), Some(Path::new("s.0002.json")));
        let sel = FrameRanges::parse("5").unwrap();
        let e = plan(&two, Some(&sel), &req(None, None))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("selects none of the file's frames (1, 2)"),
            "{e}"
        );
        let same = seq(&[(1, Some("x.png"), None), (2, Some("x.tif"), None)]);
        let e = plan(&same, None, &req(None, None)).unwrap_err().to_string();
        assert_eq!(e, "frames 1 and 2 would both write x.png");
    }
}
