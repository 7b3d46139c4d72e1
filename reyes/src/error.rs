//! The renderer library's errors: one enum, [`Error`], with a variant per kind of failure (a
//! scene that cannot be read, options out of range, a frame beyond what a device binding holds,
//! an output that cannot be written, an image that cannot be read, a failed GPU run). Each
//! variant's message is the whole sentence a command line prints; the underlying cause, where
//! there is one (an I/O, image or OpenEXR error, the scheduler's [`RunError`]), is kept as the
//! error's source.

use scheduler::RunError;
use std::fmt;
use std::path::PathBuf;

/// What can go wrong in the renderer library. Messages name what failed and why (the option
/// and its range, the file and the cause), in the words the command line prints.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A scene file that could not be read or parsed, at a file and line.
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// A surface that cannot become Bezier patches: a NURBS surface's orders, knots, ranges or
    /// point count, a quadric's parameters. The message has no location: the scene reader
    /// reports it as a [`SceneError`] at the request's line.
    #[error("{0}")]
    InvalidSurface(String),
    /// A primitive variable's declaration (`[class] type[n]`) that does not parse. No location,
    /// as for [`Error::InvalidSurface`].
    #[error("{0}")]
    InvalidDeclaration(String),
    /// A displacement map whose image could not be read.
    #[error("cannot read the displacement map {}: {source}", path.display())]
    DisplacementMapUnreadable {
        /// The map's file.
        path: PathBuf,
        /// Why the `image` crate could not read it.
        source: image::ImageError,
    },
    /// A displacement map named by a path that is not a regular file (a FIFO, a device, a
    /// folder): reading one could block forever or never end.
    #[error("the displacement map {} is not a regular file", path.display())]
    DisplacementMapNotAFile {
        /// The map's path.
        path: PathBuf,
    },
    /// A displacement map with a NaN texel: it would displace points to NaN, which the
    /// renderer drops without a word.
    #[error(
        "the displacement map {} has a NaN texel at ({x}, {y}) (texels must be numbers)",
        path.display()
    )]
    DisplacementMapNaN {
        /// The map's file.
        path: PathBuf,
        /// The first NaN texel's column.
        x: u32,
        /// Its row.
        y: u32,
    },
    /// A displacement map of a size the GPU table does not take.
    #[error(
        "the displacement map {} is {width}x{height}: each side must be 1..={max_side} and \
         the texels at most {max_texels} (4096x4096); sample it down",
        path.display()
    )]
    DisplacementMapSize {
        /// The map's file.
        path: PathBuf,
        /// Its width in texels.
        width: u32,
        /// Its height in texels.
        height: u32,
        /// The longest side taken ([`crate::scene::MAX_MAP_SIDE`]).
        max_side: u32,
        /// The most texels taken ([`crate::scene::MAX_MAP_TEXELS`]).
        max_texels: u64,
    },
    /// A turn of the scene about its vertical axis by an angle that is not finite.
    #[error("spin {degrees} degrees: must be finite")]
    NonFiniteSpin {
        /// The angle asked for, in degrees.
        degrees: f64,
    },
    /// A turn of the scene about the world's z axis when that axis is degenerate in camera
    /// space.
    #[error("the world's z axis is degenerate in camera space: cannot spin about it")]
    DegenerateSpinAxis,
    /// A frame selection (`N`, `A-B`, comma-separated lists of them) that does not parse or
    /// selects an empty range; the message names the bad part.
    #[error("{0}")]
    InvalidFrameRanges(String),
    /// Render options out of the supported ranges (image size, pixel samples, micropolygon
    /// size, screen bound, interleaving); the message names the option and its range.
    #[error("{0}")]
    InvalidOptions(String),
    /// A frame whose buffers would not fit a device binding (more sub-samples than a 32-bit
    /// index reaches, an image or sample buffer over 4 GiB); the message says what to change.
    #[error("{0}")]
    FrameTooLarge(String),
    /// The frame's per-patch table (primitive variables, weights, motion, displacements)
    /// would outgrow what one GPU binding holds.
    #[error("the patches' {what} need more than the {limit} bytes a GPU table may hold")]
    TablesTooLarge {
        /// What the table was holding when it ran out, e.g. `"motion and primitive variables"`.
        what: &'static str,
        /// The most bytes the table may hold ([`crate::frame::MAX_FRAME_BUFFER_BYTES`]).
        limit: u64,
    },
    /// An output file that could not be written (a missing or read-only folder, a full disk).
    #[error("{}: {source}", path.display())]
    Write {
        /// The file being written.
        path: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
    /// An output path that names no file (e.g. `..` or a root).
    #[error("{}: not a file name", path.display())]
    NotAFileName {
        /// The path given.
        path: PathBuf,
    },
    /// An image that could not be encoded (PNG, through the `image` crate).
    #[error(transparent)]
    Encode(#[from] image::ImageError),
    /// An image whose pixel buffer does not have width x height pixels.
    #[error("image buffer size mismatch")]
    BufferSizeMismatch,
    /// An image that could not be encoded as OpenEXR.
    #[error("OpenEXR: {0}")]
    EncodeExr(#[source] exr::error::Error),
    /// An OpenEXR image that could not be read.
    #[error("{}: {source}", path.display())]
    ReadExr {
        /// The image's file.
        path: PathBuf,
        /// The OpenEXR reader's error.
        source: exr::error::Error,
    },
    /// An image that was read but lacks what the renderer needs (a layer, a channel).
    #[error("{}: {what}", path.display())]
    ImageContent {
        /// The image's file.
        path: PathBuf,
        /// What is missing, e.g. `"no A channel"`.
        what: String,
    },
    /// A GPU run that failed (no adapter, a device error, a timeout, a queue overflow).
    #[error(transparent)]
    Run(#[from] RunError),
}

/// An input error of a scene file, located at a file and line (line 0: the file as a whole,
/// e.g. when it cannot be read). Shown as `file:line: message` (`file: message` for line 0).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SceneError {
    /// The file as given (an archive's own name for errors inside it).
    pub file: String,
    /// The 1-based line of the request at fault, or 0 for the file as a whole.
    pub line: u64,
    /// What is wrong, without the location.
    pub message: String,
}

impl SceneError {
    /// The error `message` at `line` of `file`.
    pub fn new(file: &str, line: u64, message: impl Into<String>) -> SceneError {
        SceneError {
            file: file.to_string(),
            line,
            message: message.into(),
        }
    }
}

impl fmt::Display for SceneError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        // Line 0: the error is about the whole file (it cannot be read), not a line of it.
        match self.line {
            0 => write!(f, "{}: {}", self.file, self.message),
            line => write!(f, "{}:{line}: {}", self.file, self.message),
        }
    }
}

impl std::error::Error for SceneError {}
