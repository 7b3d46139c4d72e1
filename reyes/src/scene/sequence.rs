//! Frame sequences: a RIB file of `FrameBegin n` ... `FrameEnd` blocks (or of several world
//! blocks) describes one image per world block, each with its frame number and `Display`.
//! Every loader returns a [`FrameSequence`]; single-image formats give a one-frame sequence.

use super::{Scene, SceneError};
use crate::Error;

/// A frame's `Display name type mode` (RenderMan Interface Specification 3.2, §4.1.6).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Display {
    /// The output name, e.g. "teapot.0001.tif".
    pub name: String,
    /// "file", "framebuffer", "tiff", "shadow", "zfile", ...
    pub kind: String,
    /// "rgb", "rgba", "z", ...
    pub mode: String,
}

impl Display {
    /// A depth-map pass (`Display` type "shadow" or "zfile"): not an image this renderer
    /// makes.
    pub fn is_depth_pass(&self) -> bool {
        matches!(self.kind.as_str(), "shadow" | "zfile")
    }
}

/// One image of a scene file: what a world block renders.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneFrame {
    /// `FrameBegin n`'s number; a world block outside any frame block counts on from the
    /// frame before it (the first is 1).
    pub number: u32,
    /// The `Display` in effect at the frame's `WorldEnd`, if any.
    pub display: Option<Display>,
    /// Why the frame cannot be rendered (a shadow-map pass), as a warning names it; `None`
    /// for a frame to render.
    pub unsupported: Option<String>,
    /// The frame's scene. Its `warnings` are empty: the file's are in
    /// [`FrameSequence::warnings`].
    pub scene: Scene,
}

/// Every frame of a scene file, in file order, and the file's warnings (one per kind of
/// skipped input, as [`Scene::warnings`]).
#[derive(Clone, Debug, PartialEq)]
pub struct FrameSequence {
    /// At least one frame.
    pub frames: Vec<SceneFrame>,
    /// The file's warnings, one per kind of skipped input.
    pub warnings: Vec<String>,
}

impl FrameSequence {
    /// A one-frame sequence (frame 1, no `Display`) of `scene`, whose warnings become the
    /// sequence's.
    pub fn single(mut scene: Scene) -> FrameSequence {
        let warnings = std::mem::take(&mut scene.warnings);
        FrameSequence {
            frames: vec![SceneFrame {
                number: 1,
                display: None,
                unsupported: None,
                scene,
            }],
            warnings,
        }
    }

    /// The first frame that can be rendered (else the first frame) with every warning of the
    /// file, plus one naming the frame when there are several: what a single-image consumer
    /// (`reyes measure`, the tests) takes from a sequence.
    pub fn into_scene(mut self) -> Scene {
        let count = self.frames.len();
        let pick = self
            .frames
            .iter()
            .position(|f| f.unsupported.is_none())
            .unwrap_or(0);
        if pick >= count {
            return Scene {
                warnings: self.warnings,
                ..Scene::default()
            };
        }
        let frame = self.frames.swap_remove(pick);
        let mut scene = frame.scene;
        scene.warnings = self.warnings;
        if count > 1 {
            scene.warnings.push(format!(
                "the file has {count} frames: using frame {} (`reyes render` renders each)",
                frame.number
            ));
        }
        scene
    }
}

/// An error of one frame of a stream of frames (`rib::RibFrames`): the frame's number when
/// the error lies inside its `FrameBegin` ... `FrameEnd` block (the frames after it are still
/// read), `None` for an error of the file outside any frame block (which ends the stream).
/// Shown as `frame N: file:line: message`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct FrameError {
    /// The frame the error belongs to, if any.
    pub number: Option<u32>,
    /// The input error, with its file and line.
    pub error: SceneError,
}

impl std::fmt::Display for FrameError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self.number {
            Some(n) => write!(f, "frame {n}: {}", self.error),
            None => write!(f, "{}", self.error),
        }
    }
}

impl std::error::Error for FrameError {}

/// A `--frames` selection: frame numbers and inclusive ranges, e.g. `2`, `2-3`, `1,3-5`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct FrameRanges(Vec<(u32, u32)>);

impl FrameRanges {
    /// Parses `N`, `A-B` and comma-separated lists of them. Errors
    /// ([`Error::InvalidFrameRanges`]) name the bad part.
    pub fn parse(spec: &str) -> Result<FrameRanges, Error> {
        let num = |s: &str| {
            s.trim().parse::<u32>().map_err(|_| {
                Error::InvalidFrameRanges(format!(
                    "--frames: `{s}` is not a frame number (in `{spec}`)"
                ))
            })
        };
        let mut out = Vec::new();
        for part in spec.split(',') {
            let (a, b) = match part.split_once('-') {
                Some((a, b)) => (num(a)?, num(b)?),
                None => {
                    let n = num(part)?;
                    (n, n)
                }
            };
            if a > b {
                return Err(Error::InvalidFrameRanges(format!(
                    "--frames: the range `{part}` is empty (its start is after its end)"
                )));
            }
            out.push((a, b));
        }
        Ok(FrameRanges(out))
    }

    /// The one frame number selected, when the selection names a single frame.
    pub fn single(&self) -> Option<u32> {
        let (a, b) = *self.0.first()?;
        (a == b && self.0.iter().all(|&r| r == (a, a))).then_some(a)
    }

    /// The selection of the one frame `n` (`--frame N`).
    pub fn one(n: u32) -> FrameRanges {
        FrameRanges(vec![(n, n)])
    }

    /// True when frame `n` lies in one of the ranges (ends included).
    pub fn contains(&self, n: u32) -> bool {
        self.0.iter().any(|&(a, b)| (a..=b).contains(&n))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_ranges() {
        let r = FrameRanges::parse("1,3-5").unwrap();
        let got: Vec<u32> = (0..8).filter(|&n| r.contains(n)).collect();
        assert_eq!(got, vec![1, 3, 4, 5]);
        assert!(FrameRanges::parse("2").unwrap().contains(2));
        assert!(!FrameRanges::parse("2").unwrap().contains(3));
        assert!(
            FrameRanges::parse("3-2")
                .unwrap_err()
                .to_string()
                .contains("`3-2` is empty")
        );
        assert!(
            FrameRanges::parse("1,x")
                .unwrap_err()
                .to_string()
                .contains("`x` is not a frame number")
        );
        assert!(FrameRanges::parse("").is_err());
        assert!(FrameRanges::parse("-3").is_err());
    }

    #[test]
    fn into_scene_takes_the_first_renderable_frame() {
        let frame = |n, unsupported: Option<&str>| SceneFrame {
            number: n,
            display: None,
            unsupported: unsupported.map(String::from),
            scene: Scene {
                width: n,
                ..Scene::default()
            },
        };
        let s = FrameSequence {
            frames: vec![frame(1, Some("shadow")), frame(2, None), frame(3, None)],
            warnings: vec!["w".into()],
        }
        .into_scene();
        assert_eq!(s.width, 2);
        assert_eq!(s.warnings[0], "w");
        assert!(s.warnings[1].contains("3 frames: using frame 2"), "{s:?}");
        let one = FrameSequence::single(Scene {
            warnings: vec!["x".into()],
            ..Scene::default()
        });
        assert_eq!(one.warnings, vec!["x"]);
        assert_eq!(one.into_scene().warnings, vec!["x"]);
    }
}
