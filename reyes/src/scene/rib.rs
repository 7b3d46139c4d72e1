//! The RIB interpreter: a graphics-state stack, transforms, attributes and the patch
//! primitives, turning a RIB stream into a [`Scene`] of camera-space Bezier patches.
//!
//! Conventions (RenderMan Interface Specification 3.2):
//! - Points are row vectors in the spec (`P' = P M`); we hold column-vector glam matrices,
//!   so the 16 numbers of `Transform`/`ConcatTransform` (row-major `M`) read as column-major
//!   give `M^T` directly. Each new transform applies FIRST to points: `CTM = CTM * M`.
//! - The CTM current at `WorldBegin` is world-to-camera; inside the world block the CTM is
//!   object-to-camera. `Identity` and `Transform` inside the world block are relative to
//!   world space (they start again from the camera transform saved at `WorldBegin`).
//! - `Rotate a x y z`: the usual axis-angle matrix (x -> y for +90 about z), which is what
//!   the spec's left-handed rule means numerically (checked against uteapot.rib: upright,
//!   seen from above, in front of the camera).
//! - Orientation: the spec keeps a "current orientation" (lh/rh) that starts left-handed,
//!   flips whenever the handedness of the current coordinate system flips (a transform with
//!   negative determinant, or restoring one), and is set by `Orientation`/
//!   `ReverseOrientation`. The surface normal is dPdu x dPdv in OBJECT space, negated when
//!   the current orientation differs from the object system's handedness. Our patches are
//!   in camera space, where the cross product of transformed tangents is
//!   det(CTM) CTM^-T (dPdu x dPdv): it gains the sign of det(CTM). Both sign changes
//!   together leave exactly one rule: the camera-space dPdu x dPdv must be negated iff the
//!   current orientation is right-handed. That is `Patch::flip_normal`. (By this rule
//!   uteapot.rib's teapot, a mirror image of Newell's data, faces inward; killeroo.rib's
//!   mirroring camera `Transform` makes every patch flip, facing it outward.)

use super::basis::{Basis, block_to_bezier};
use super::nurbs::{self, NuSurface};
use super::rib_lexer::{Tok, Token, tokenize};
use super::{Light, Material, Patch, PatchSource, Scene, SceneError, SurfaceKind};
use glam::{DMat4, DVec3};
use std::collections::{HashMap, HashSet};

/// Requests the interpreter understands; any other name is skipped with one warning.
const KNOWN: &[&str] = &[
    "Format",
    "PixelSamples",
    "Projection",
    "Clipping",
    "Identity",
    "Transform",
    "ConcatTransform",
    "Translate",
    "Rotate",
    "Scale",
    "WorldBegin",
    "WorldEnd",
    "FrameBegin",
    "FrameEnd",
    "AttributeBegin",
    "AttributeEnd",
    "TransformBegin",
    "TransformEnd",
    "Basis",
    "Patch",
    "PatchMesh",
    "NuPatch",
    "Color",
    "Opacity",
    "Surface",
    "LightSource",
    "Sides",
    "Orientation",
    "ReverseOrientation",
    "ObjectBegin",
    "ObjectEnd",
    "MotionBegin",
    "MotionEnd",
];

/// One argument of a request.
#[derive(Clone, Debug, PartialEq)]
enum Arg {
    Num(f64),
    Str(String),
    Nums(Vec<f64>),
    Strs(Vec<String>),
}

impl Arg {
    fn describe(&self) -> String {
        match self {
            Arg::Num(v) => format!("number {v}"),
            Arg::Str(s) => format!("string \"{s}\""),
            Arg::Nums(v) => format!("array of {} numbers", v.len()),
            Arg::Strs(v) => format!("array of {} strings", v.len()),
        }
    }
}

#[derive(Debug)]
struct Request {
    name: String,
    line: u32,
    args: Vec<Arg>,
}

fn is_identifier(w: &str) -> bool {
    w.starts_with(|c: char| c.is_ascii_alphabetic() || c == '_')
}

/// Groups tokens into requests: a bare word followed by its arguments.
struct Reader<'a> {
    file: &'a str,
    toks: std::iter::Peekable<std::vec::IntoIter<Token>>,
    eof_line: u32,
}

impl<'a> Reader<'a> {
    fn err(&self, line: u32, msg: impl Into<String>) -> SceneError {
        SceneError::new(self.file, line, msg)
    }

    fn next_request(&mut self) -> Result<Option<Request>, SceneError> {
        let Some(first) = self.toks.next() else {
            return Ok(None);
        };
        let name = match first.tok {
            Tok::Word(w) if is_identifier(&w) => w,
            Tok::Word(w) => return Err(self.err(first.line, format!("unexpected `{w}`"))),
            Tok::Num(v) => {
                return Err(self.err(first.line, format!("expected a request, found number {v}")));
            }
            Tok::Str(s) => {
                return Err(self.err(
                    first.line,
                    format!("expected a request, found string \"{s}\""),
                ));
            }
            Tok::Open => return Err(self.err(first.line, "expected a request, found `[`")),
            Tok::Close => return Err(self.err(first.line, "unexpected `]`")),
        };
        let known = KNOWN.contains(&name.as_str());
        let mut args = Vec::new();
        while let Some(t) = self.toks.peek() {
            let line = t.line;
            match &t.tok {
                Tok::Word(w) if is_identifier(w) => break,
                // Junk after an unknown request (`set -x`) belongs to it; after a known one
                // it is an error.
                Tok::Word(w) if known => {
                    let msg = format!("`{name}`: unexpected `{w}` (not a number or string)");
                    return Err(self.err(line, msg));
                }
                Tok::Word(_) => {
                    self.toks.next();
                }
                Tok::Num(v) => {
                    args.push(Arg::Num(*v));
                    self.toks.next();
                }
                Tok::Str(s) => {
                    args.push(Arg::Str(s.clone()));
                    self.toks.next();
                }
                Tok::Close => return Err(self.err(line, "unexpected `]`")),
                Tok::Open => {
                    self.toks.next();
                    args.push(self.array(line)?);
                }
            }
        }
        Ok(Some(Request {
            name,
            line: first.line,
            args,
        }))
    }

    fn array(&mut self, open_line: u32) -> Result<Arg, SceneError> {
        let mut nums = Vec::new();
        let mut strs = Vec::new();
        loop {
            let Some(t) = self.toks.next() else {
                return Err(self.err(
                    self.eof_line,
                    format!("unexpected end of file inside the array opened at line {open_line}"),
                ));
            };
            match t.tok {
                Tok::Close => break,
                Tok::Num(v) => nums.push(v),
                Tok::Str(s) => strs.push(s),
                Tok::Open => return Err(self.err(t.line, "unexpected `[` inside an array")),
                Tok::Word(w) => {
                    return Err(self.err(
                        t.line,
                        format!("unexpected `{w}` inside an array (not a number or string)"),
                    ));
                }
            }
            if !nums.is_empty() && !strs.is_empty() {
                return Err(self.err(t.line, "array mixes numbers and strings"));
            }
        }
        Ok(if strs.is_empty() {
            Arg::Nums(nums)
        } else {
            Arg::Strs(strs)
        })
    }
}

/// A parameter of a request's parameter list, name without inline type declaration.
struct Param<'r> {
    name: &'r str,
    value: &'r Arg,
}

/// Cursor over a request's arguments with error messages naming the request and line.
struct Args<'r> {
    req: &'r Request,
    file: &'r str,
    pos: usize,
}

impl<'r> Args<'r> {
    fn err(&self, msg: impl std::fmt::Display) -> SceneError {
        SceneError::new(
            self.file,
            self.req.line,
            format!("`{}`: {msg}", self.req.name),
        )
    }

    fn peek(&self) -> Option<&'r Arg> {
        self.req.args.get(self.pos)
    }

    fn take(&mut self, what: &str) -> Result<&'r Arg, SceneError> {
        let a = self
            .req
            .args
            .get(self.pos)
            .ok_or_else(|| self.err(format!("missing {what}")))?;
        self.pos += 1;
        Ok(a)
    }

    /// A finite number (a bare number or a one-element array).
    fn num(&mut self, what: &str) -> Result<f64, SceneError> {
        let v = match self.take(what)? {
            Arg::Num(v) => *v,
            Arg::Nums(v) if v.len() == 1 => v[0],
            other => {
                return Err(self.err(format!(
                    "expected a number for {what}, found {}",
                    other.describe()
                )));
            }
        };
        if !v.is_finite() {
            return Err(self.err(format!("{what} is not finite ({v})")));
        }
        Ok(v)
    }

    /// An integer-valued number in `lo..=hi`.
    fn int(&mut self, what: &str, lo: usize, hi: usize) -> Result<usize, SceneError> {
        let v = self.num(what)?;
        if v.fract() != 0.0 || v < lo as f64 || v > hi as f64 {
            return Err(self.err(format!(
                "{what} must be an integer in {lo}..={hi}, found {v}"
            )));
        }
        Ok(v as usize)
    }

    fn string(&mut self, what: &str) -> Result<&'r str, SceneError> {
        match self.take(what)? {
            Arg::Str(s) => Ok(s),
            Arg::Strs(v) if v.len() == 1 => Ok(&v[0]),
            other => Err(self.err(format!(
                "expected a string for {what}, found {}",
                other.describe()
            ))),
        }
    }

    fn array(&mut self, what: &str) -> Result<&'r [f64], SceneError> {
        match self.take(what)? {
            Arg::Nums(v) => Ok(v),
            other => Err(self.err(format!(
                "expected an array of numbers for {what}, found {}",
                other.describe()
            ))),
        }
    }

    /// `n` finite numbers, given either bare or as one array.
    fn fixed(&mut self, n: usize, what: &str) -> Result<Vec<f64>, SceneError> {
        let vals = if let Some(Arg::Nums(v)) = self.peek() {
            self.pos += 1;
            if v.len() != n {
                return Err(self.err(format!(
                    "expected {n} numbers for {what}, found {}",
                    v.len()
                )));
            }
            v.clone()
        } else {
            let mut out = Vec::with_capacity(n);
            while out.len() < n {
                match self.peek() {
                    Some(Arg::Num(v)) => {
                        out.push(*v);
                        self.pos += 1;
                    }
                    None => {
                        return Err(self.err(format!(
                            "expected {n} numbers for {what}, found {}",
                            out.len()
                        )));
                    }
                    Some(other) => {
                        return Err(self.err(format!(
                            "expected a number for {what}, found {}",
                            other.describe()
                        )));
                    }
                }
            }
            out
        };
        if let Some(v) = vals.iter().find(|v| !v.is_finite()) {
            return Err(self.err(format!("{what} has a non-finite value ({v})")));
        }
        Ok(vals)
    }

    /// The rest: "name" value pairs.
    fn params(&mut self) -> Result<Vec<Param<'r>>, SceneError> {
        let mut out = Vec::new();
        while let Some(a) = self.peek() {
            let Arg::Str(name) = a else {
                return Err(self.err(format!(
                    "expected a parameter name (a string), found {}",
                    a.describe()
                )));
            };
            self.pos += 1;
            let short = name.split_whitespace().last().unwrap_or("");
            let value = self
                .peek()
                .ok_or_else(|| self.err(format!("parameter \"{short}\" has no value")))?;
            self.pos += 1;
            out.push(Param { name: short, value });
        }
        Ok(out)
    }

    fn done(&self) -> Result<(), SceneError> {
        match self.peek() {
            None => Ok(()),
            Some(a) => Err(self.err(format!("unexpected extra argument: {}", a.describe()))),
        }
    }
}

impl Param<'_> {
    fn num(&self, a: &Args) -> Result<f64, SceneError> {
        match self.value {
            Arg::Num(v) if v.is_finite() => Ok(*v),
            Arg::Nums(v) if v.len() == 1 && v[0].is_finite() => Ok(v[0]),
            other => Err(a.err(format!(
                "parameter \"{}\" needs one finite number, found {}",
                self.name,
                other.describe()
            ))),
        }
    }

    fn vec3(&self, a: &Args) -> Result<DVec3, SceneError> {
        match self.value {
            Arg::Nums(v) if v.len() == 3 && v.iter().all(|x| x.is_finite()) => {
                Ok(DVec3::new(v[0], v[1], v[2]))
            }
            other => Err(a.err(format!(
                "parameter \"{}\" needs 3 finite numbers, found {}",
                self.name,
                other.describe()
            ))),
        }
    }

    fn nums<'a>(&'a self, a: &Args) -> Result<&'a [f64], SceneError> {
        match self.value {
            Arg::Nums(v) => Ok(v),
            Arg::Num(v) => Ok(std::slice::from_ref(v)),
            other => Err(a.err(format!(
                "parameter \"{}\" needs numbers, found {}",
                self.name,
                other.describe()
            ))),
        }
    }
}

/// Attributes saved by `AttributeBegin` (and the other attribute-saving blocks).
#[derive(Clone, Debug)]
struct Attributes {
    /// Object to camera, column-vector convention.
    ctm: DMat4,
    /// RenderMan's current orientation: true = right-handed.
    orientation_rh: bool,
    two_sided: bool,
    color: DVec3,
    opacity: DVec3,
    /// Shader and its parameters; its color/opacity fields are unused (see above).
    surface: Material,
    ubasis: Basis,
    vbasis: Basis,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Block {
    Frame,
    World,
    Attribute,
    Transform,
}

impl Block {
    fn begin(self) -> &'static str {
        match self {
            Block::Frame => "FrameBegin",
            Block::World => "WorldBegin",
            Block::Attribute => "AttributeBegin",
            Block::Transform => "TransformBegin",
        }
    }
}

struct Interp<'a> {
    file: &'a str,
    scene: Scene,
    attrs: Attributes,
    stack: Vec<(Block, u32, Attributes)>,
    /// World-to-camera, saved at `WorldBegin`; `Some` only inside the world block.
    world_to_camera: Option<DMat4>,
    world_seen: bool,
    warned: HashSet<String>,
    materials: HashMap<(SurfaceKind, [u64; 13]), u32>,
    /// Material of the current attributes, once looked up.
    current_material: Option<u32>,
    /// Inside `MotionBegin`: whether the first (used) time sample has been seen.
    motion: Option<bool>,
}

/// Parses RIB text. `file` names the input in errors and warnings.
pub fn parse_rib(text: &str, file: &str) -> Result<Scene, SceneError> {
    let toks = tokenize(text.as_bytes(), file)?;
    let eof_line = text.lines().count().max(1) as u32;
    let mut reader = Reader {
        file,
        toks: toks.into_iter().peekable(),
        eof_line,
    };
    let mut it = Interp {
        file,
        scene: Scene::default(),
        attrs: Attributes {
            ctm: DMat4::IDENTITY,
            orientation_rh: false,
            two_sided: true,
            color: DVec3::ONE,
            opacity: DVec3::ONE,
            surface: Material::standard(SurfaceKind::Matte),
            ubasis: Basis::BEZIER,
            vbasis: Basis::BEZIER,
        },
        stack: Vec::new(),
        world_to_camera: None,
        world_seen: false,
        warned: HashSet::new(),
        materials: HashMap::new(),
        current_material: None,
        motion: None,
    };
    while let Some(req) = reader.next_request()? {
        if req.name == "ObjectBegin" {
            it.warn_once(
                &req,
                "ObjectBegin",
                "skipped `ObjectBegin` ... `ObjectEnd` (retained geometry is not supported)",
            );
            loop {
                match reader.next_request()? {
                    Some(r) if r.name == "ObjectEnd" => break,
                    Some(_) => {}
                    None => {
                        return Err(SceneError::new(
                            file,
                            eof_line,
                            format!(
                                "unexpected end of file inside `ObjectBegin` (line {})",
                                req.line
                            ),
                        ));
                    }
                }
            }
            continue;
        }
        if let Some(first_done) = it.motion {
            if req.name == "MotionEnd" {
                it.motion = None;
                continue;
            }
            if first_done {
                continue;
            }
            it.motion = Some(true);
        }
        it.request(&req)?;
    }
    if let Some((block, line, _)) = it.stack.last() {
        return Err(SceneError::new(
            file,
            eof_line,
            format!(
                "unexpected end of file inside `{}` (line {line})",
                block.begin()
            ),
        ));
    }
    if !it.world_seen {
        return Err(SceneError::new(
            file,
            eof_line,
            "no `WorldBegin` ... `WorldEnd` block in the file",
        ));
    }
    Ok(it.scene)
}

impl Interp<'_> {
    fn warn_once(&mut self, req: &Request, key: &str, msg: &str) {
        if self.warned.insert(key.to_string()) {
            self.scene
                .warnings
                .push(format!("{}:{}: {msg}", self.file, req.line));
        }
    }

    /// Sets the CTM, flipping the current orientation when the handedness flips (spec).
    fn set_ctm(&mut self, m: DMat4) {
        if (self.attrs.ctm.determinant() < 0.0) != (m.determinant() < 0.0) {
            self.attrs.orientation_rh = !self.attrs.orientation_rh;
        }
        self.attrs.ctm = m;
    }

    fn concat(&mut self, m: DMat4) {
        self.set_ctm(self.attrs.ctm * m);
    }

    fn push(&mut self, block: Block, line: u32) {
        self.stack.push((block, line, self.attrs.clone()));
    }

    fn pop(&mut self, block: Block, req: &Request) -> Result<(), SceneError> {
        let Some((top, line, saved)) = self.stack.pop() else {
            return Err(SceneError::new(
                self.file,
                req.line,
                format!("`{}` without a matching `{}`", req.name, block.begin()),
            ));
        };
        if top != block {
            return Err(SceneError::new(
                self.file,
                req.line,
                format!(
                    "`{}` does not match `{}` at line {line}",
                    req.name,
                    top.begin()
                ),
            ));
        }
        if block == Block::Transform {
            self.set_ctm(saved.ctm);
        } else {
            self.attrs = saved;
            self.current_material = None;
        }
        Ok(())
    }

    fn request(&mut self, req: &Request) -> Result<(), SceneError> {
        let mut a = Args {
            req,
            file: self.file,
            pos: 0,
        };
        match req.name.as_str() {
            "Format" => {
                let w = a.int("the x resolution", 1, 1 << 16)?;
                let h = a.int("the y resolution", 1, 1 << 16)?;
                a.num("the pixel aspect ratio")?;
                a.done()?;
                self.scene.width = w as u32;
                self.scene.height = h as u32;
            }
            "PixelSamples" => {
                let mut s = [0u32; 2];
                for (k, slot) in s.iter_mut().enumerate() {
                    let v = a.num(if k == 0 { "xsamples" } else { "ysamples" })?;
                    if !(v > 0.0 && v <= 1024.0) {
                        return Err(a.err(format!("sample count {v} is not in (0, 1024]")));
                    }
                    *slot = v.ceil() as u32;
                }
                a.done()?;
                self.scene.pixel_samples = (s[0], s[1]);
            }
            "Projection" => {
                if self.world_to_camera.is_some() {
                    return Err(a.err("not allowed inside `WorldBegin` ... `WorldEnd`"));
                }
                let name = a.string("the projection type")?;
                if name != "perspective" {
                    return Err(a.err(format!(
                        "projection \"{name}\" is not supported (only \"perspective\")"
                    )));
                }
                for p in a.params()? {
                    match p.name {
                        "fov" => {
                            let fov = p.num(&a)?;
                            if !(fov > 0.0 && fov < 180.0) {
                                return Err(a.err(format!("fov {fov} is not in (0, 180)")));
                            }
                            self.scene.camera.fov_deg = fov;
                        }
                        other => self.ignored_param(req, other),
                    }
                }
                // The spec: the current transformation is reset after the projection.
                self.set_ctm(DMat4::IDENTITY);
            }
            "Clipping" => {
                let near = a.num("near")?;
                let far = a.num("far")?;
                a.done()?;
                if !(near > 0.0 && far > near) {
                    return Err(a.err(format!("need 0 < near < far, found near {near} far {far}")));
                }
                self.scene.camera.near = near;
                self.scene.camera.far = far;
            }
            "Identity" => {
                a.done()?;
                self.set_ctm(self.world_to_camera.unwrap_or(DMat4::IDENTITY));
            }
            "Transform" | "ConcatTransform" => {
                let v = a.fixed(16, "the matrix")?;
                a.done()?;
                // Row-major row-vector matrix == column-major column-vector matrix.
                let m = DMat4::from_cols_slice(&v);
                if req.name == "Transform" {
                    self.set_ctm(self.world_to_camera.unwrap_or(DMat4::IDENTITY) * m);
                } else {
                    self.concat(m);
                }
            }
            "Translate" => {
                let v = a.fixed(3, "the offset")?;
                a.done()?;
                self.concat(DMat4::from_translation(DVec3::from_slice(&v)));
            }
            "Rotate" => {
                let v = a.fixed(4, "angle and axis")?;
                a.done()?;
                let r = super::rotation(v[0], DVec3::new(v[1], v[2], v[3]))
                    .ok_or_else(|| a.err("the rotation axis is zero"))?;
                self.concat(r);
            }
            "Scale" => {
                let v = a.fixed(3, "the scale factors")?;
                a.done()?;
                self.concat(DMat4::from_scale(DVec3::from_slice(&v)));
            }
            "WorldBegin" => {
                a.done()?;
                if self.world_seen {
                    return Err(a.err("only one `WorldBegin` block per file is supported"));
                }
                self.world_seen = true;
                self.push(Block::World, req.line);
                self.world_to_camera = Some(self.attrs.ctm);
            }
            "WorldEnd" => {
                a.done()?;
                self.pop(Block::World, req)?;
                self.world_to_camera = None;
            }
            "FrameBegin" => {
                if a.peek().is_some() {
                    a.num("the frame number")?;
                }
                a.done()?;
                self.push(Block::Frame, req.line);
            }
            "FrameEnd" => {
                a.done()?;
                self.pop(Block::Frame, req)?;
            }
            "AttributeBegin" => {
                a.done()?;
                self.push(Block::Attribute, req.line);
            }
            "AttributeEnd" => {
                a.done()?;
                self.pop(Block::Attribute, req)?;
            }
            "TransformBegin" => {
                a.done()?;
                self.push(Block::Transform, req.line);
            }
            "TransformEnd" => {
                a.done()?;
                self.pop(Block::Transform, req)?;
            }
            "Basis" => {
                let ub = basis_arg(&mut a, "u")?;
                let vb = basis_arg(&mut a, "v")?;
                a.done()?;
                self.attrs.ubasis = ub;
                self.attrs.vbasis = vb;
            }
            "Color" | "Opacity" => {
                let v = a.fixed(3, "the color")?;
                a.done()?;
                let c = DVec3::from_slice(&v);
                if req.name == "Color" {
                    self.attrs.color = c;
                } else {
                    self.attrs.opacity = c;
                }
                self.current_material = None;
            }
            "Surface" => self.surface(req, &mut a)?,
            "LightSource" => self.light(req, &mut a)?,
            "Sides" => {
                let s = a.num("the number of sides")?;
                a.done()?;
                self.attrs.two_sided = match s {
                    1.0 => false,
                    2.0 => true,
                    _ => return Err(a.err(format!("sides must be 1 or 2, found {s}"))),
                };
            }
            "Orientation" => {
                let o = a.string("the orientation")?;
                a.done()?;
                let coordsys_rh = self.attrs.ctm.determinant() < 0.0;
                self.attrs.orientation_rh = match o {
                    "lh" => false,
                    "rh" => true,
                    "outside" => coordsys_rh,
                    "inside" => !coordsys_rh,
                    _ => {
                        return Err(a.err(format!(
                            "orientation \"{o}\" is not one of \"lh\", \"rh\", \"inside\", \"outside\""
                        )));
                    }
                };
            }
            "ReverseOrientation" => {
                a.done()?;
                self.attrs.orientation_rh = !self.attrs.orientation_rh;
            }
            "Patch" => self.patch(req, &mut a)?,
            "PatchMesh" => self.patch_mesh(req, &mut a)?,
            "NuPatch" => self.nu_patch(req, &mut a)?,
            "ObjectEnd" => return Err(a.err("without a matching `ObjectBegin`")),
            "MotionBegin" => {
                if self.motion.is_some() {
                    return Err(a.err("nested `MotionBegin`"));
                }
                self.warn_once(
                    req,
                    "MotionBegin",
                    "motion blocks are not supported: using the first time sample of each",
                );
                self.motion = Some(false);
            }
            "MotionEnd" => return Err(a.err("without a matching `MotionBegin`")),
            _ => {
                let msg = format!("skipped unsupported request `{}`", req.name);
                self.warn_once(req, &req.name, &msg);
            }
        }
        Ok(())
    }

    fn ignored_param(&mut self, req: &Request, name: &str) {
        let key = format!("{} \"{name}\"", req.name);
        let msg = format!("ignored parameter \"{name}\" of `{}`", req.name);
        self.warn_once(req, &key, &msg);
    }

    fn surface(&mut self, req: &Request, a: &mut Args) -> Result<(), SceneError> {
        let name = a.string("the shader name")?;
        let kind = match name {
            "constant" => SurfaceKind::Constant,
            "matte" => SurfaceKind::Matte,
            "plastic" => SurfaceKind::Plastic,
            _ => {
                let msg = format!(
                    "skipped unsupported surface shader \"{name}\" (keeping the previous surface)"
                );
                self.warn_once(req, &format!("Surface \"{name}\""), &msg);
                return Ok(());
            }
        };
        let mut m = Material::standard(kind);
        for p in a.params()? {
            match (kind, p.name) {
                (SurfaceKind::Matte | SurfaceKind::Plastic, "Ka") => m.ka = p.num(a)?,
                (SurfaceKind::Matte | SurfaceKind::Plastic, "Kd") => m.kd = p.num(a)?,
                (SurfaceKind::Plastic, "Ks") => m.ks = p.num(a)?,
                (SurfaceKind::Plastic, "roughness") => m.roughness = p.num(a)?,
                (SurfaceKind::Plastic, "specularcolor") => m.specular_color = p.vec3(a)?,
                (_, other) => self.ignored_param(req, other),
            }
        }
        self.attrs.surface = m;
        self.current_material = None;
        Ok(())
    }

    fn light(&mut self, req: &Request, a: &mut Args) -> Result<(), SceneError> {
        let name = a.string("the shader name")?;
        // The handle: a number, or (RIB 3.04) a string followed by an even-length list.
        match a.peek() {
            Some(Arg::Num(_)) => {
                a.pos += 1;
            }
            Some(Arg::Str(_)) if (req.args.len() - a.pos) % 2 == 1 => {
                a.pos += 1;
            }
            _ => {}
        }
        let params = a.params()?;
        if !matches!(name, "ambientlight" | "distantlight" | "pointlight") {
            let msg = format!("skipped unsupported light shader \"{name}\" (no light added)");
            self.warn_once(req, &format!("LightSource \"{name}\""), &msg);
            return Ok(());
        }
        let mut intensity = 1.0;
        let mut color = DVec3::ONE;
        let mut from = DVec3::ZERO;
        let mut to = DVec3::Z;
        for p in &params {
            match (name, p.name) {
                (_, "intensity") => intensity = p.num(a)?,
                (_, "lightcolor") => color = p.vec3(a)?,
                ("distantlight" | "pointlight", "from") => from = p.vec3(a)?,
                ("distantlight", "to") => to = p.vec3(a)?,
                (_, other) => self.ignored_param(req, other),
            }
        }
        let color = color * intensity;
        let ctm = self.attrs.ctm;
        let light = match name {
            "ambientlight" => Light::Ambient { color },
            "distantlight" => {
                let d = ctm.project_point3(to) - ctm.project_point3(from);
                let dir = d.normalize_or_zero();
                if dir == DVec3::ZERO || !dir.is_finite() {
                    return Err(a.err("\"from\" and \"to\" give no direction"));
                }
                Light::Distant { color, dir }
            }
            _ => {
                let pos = ctm.project_point3(from);
                if !pos.is_finite() {
                    return Err(a.err("the light position is not finite"));
                }
                Light::Point { color, pos }
            }
        };
        self.scene.lights.push(light);
        Ok(())
    }

    fn material(&mut self) -> u32 {
        if let Some(m) = self.current_material {
            return m;
        }
        let m = Material {
            color: self.attrs.color,
            opacity: self.attrs.opacity,
            ..self.attrs.surface.clone()
        };
        let key = (
            m.kind,
            [
                m.color.x,
                m.color.y,
                m.color.z,
                m.opacity.x,
                m.opacity.y,
                m.opacity.z,
                m.ka,
                m.kd,
                m.ks,
                m.roughness,
                m.specular_color.x,
                m.specular_color.y,
                m.specular_color.z,
            ]
            .map(f64::to_bits),
        );
        let next = self.scene.materials.len() as u32;
        let id = *self.materials.entry(key).or_insert(next);
        if id == next {
            self.scene.materials.push(m);
        }
        self.current_material = Some(id);
        id
    }

    /// Checks that geometry may be emitted now; returns the object-to-camera transform.
    fn geometry_ctm(&self, a: &Args) -> Result<DMat4, SceneError> {
        if self.world_to_camera.is_none() {
            return Err(a.err("geometry outside `WorldBegin` ... `WorldEnd`"));
        }
        let m = self.attrs.ctm;
        let affine =
            m.x_axis.w == 0.0 && m.y_axis.w == 0.0 && m.z_axis.w == 0.0 && m.w_axis.w != 0.0;
        if !affine {
            return Err(
                a.err("the current transformation is projective; patches need an affine one")
            );
        }
        Ok(m)
    }

    /// Transforms an object-space Bezier patch to camera space and adds it.
    fn emit(
        &mut self,
        a: &Args,
        ctm: &DMat4,
        index: usize,
        cp: [DVec3; 16],
    ) -> Result<(), SceneError> {
        let bad = |p: &DVec3| {
            if p.is_nan() { "NaN" } else { "infinite" }
        };
        if let Some((k, p)) = cp.iter().enumerate().find(|(_, p)| !p.is_finite()) {
            return Err(a.err(format!(
                "patch {index}: control point {k} is {} ({})",
                bad(p),
                show_point(*p)
            )));
        }
        let cp = cp.map(|p| ctm.project_point3(p));
        if let Some((k, p)) = cp.iter().enumerate().find(|(_, p)| !p.is_finite()) {
            return Err(a.err(format!(
                "patch {index}: control point {k} is {} in camera space ({})",
                bad(p),
                show_point(*p)
            )));
        }
        let material = self.material();
        self.scene.patches.push(Patch {
            cp,
            material,
            flip_normal: self.attrs.orientation_rh,
            two_sided: self.attrs.two_sided,
            source: PatchSource {
                file: self.file.to_string(),
                line: a.req.line,
                index: index as u32,
            },
        });
        Ok(())
    }

    fn patch(&mut self, req: &Request, a: &mut Args) -> Result<(), SceneError> {
        let kind = a.string("the patch type")?;
        let n = patch_points(a, kind)?;
        let params = a.params()?;
        let pts = self.positions(req, a, &params, n)?;
        let ctm = self.geometry_ctm(a)?;
        check_points(a, 0, &pts, 0..n)?;
        let cp = if n == 4 {
            bilinear_to_bezier([pts[0], pts[1], pts[2], pts[3]])
        } else {
            let g: [DVec3; 16] = std::array::from_fn(|k| pts[k]);
            block_to_bezier(&g, &self.attrs.ubasis, &self.attrs.vbasis)
        };
        self.emit(a, &ctm, 0, cp)
    }

    fn patch_mesh(&mut self, req: &Request, a: &mut Args) -> Result<(), SceneError> {
        let kind = a.string("the patch type")?;
        let cubic = patch_points(a, kind)? == 16;
        const MAX: usize = 1 << 24;
        let nu = a.int("nu", 1, MAX)?;
        let uwrap = wrap_arg(a, "uwrap")?;
        let nv = a.int("nv", 1, MAX)?;
        let vwrap = wrap_arg(a, "vwrap")?;
        let params = a.params()?;
        let (ustep, vstep) = if cubic {
            (
                self.attrs.ubasis.step as usize,
                self.attrs.vbasis.step as usize,
            )
        } else {
            (1, 1)
        };
        let order = if cubic { 4 } else { 2 };
        let nup = mesh_patches(a, "u", nu, uwrap, ustep, order)?;
        let nvp = mesh_patches(a, "v", nv, vwrap, vstep, order)?;
        let pts = self.positions(req, a, &params, nu * nv)?;
        let ctm = self.geometry_ctm(a)?;
        let at = |r: usize, c: usize| pts[(r % nv) * nu + (c % nu)];
        let size = if cubic { 4 } else { 2 };
        for pv in 0..nvp {
            for pu in 0..nup {
                let (r0, c0) = (pv * vstep, pu * ustep);
                let used =
                    (0..size * size).map(|k| ((r0 + k / size) % nv) * nu + (c0 + k % size) % nu);
                check_points(a, pv * nup + pu, &pts, used)?;
                let cp = if cubic {
                    let g = std::array::from_fn(|k| at(r0 + k / 4, c0 + k % 4));
                    block_to_bezier(&g, &self.attrs.ubasis, &self.attrs.vbasis)
                } else {
                    bilinear_to_bezier([
                        at(r0, c0),
                        at(r0, c0 + 1),
                        at(r0 + 1, c0),
                        at(r0 + 1, c0 + 1),
                    ])
                };
                self.emit(a, &ctm, pv * nup + pu, cp)?;
            }
        }
        Ok(())
    }

    fn nu_patch(&mut self, req: &Request, a: &mut Args) -> Result<(), SceneError> {
        const MAX: usize = 1 << 24;
        let nu = a.int("nu", 1, MAX)?;
        let uorder = a.int("uorder", 1, MAX)?;
        let uknot = a.array("uknot")?;
        let umin = a.num("umin")?;
        let umax = a.num("umax")?;
        let nv = a.int("nv", 1, MAX)?;
        let vorder = a.int("vorder", 1, MAX)?;
        let vknot = a.array("vknot")?;
        let vmin = a.num("vmin")?;
        let vmax = a.num("vmax")?;
        for o in [uorder, vorder] {
            if o != nurbs::ORDER {
                return Err(a.err(format!(
                    "order {o} is not supported (only order 4, bicubic)"
                )));
            }
        }
        let params = a.params()?;
        let mut surf = NuSurface {
            nu,
            nv,
            uknot,
            vknot,
            urange: (umin, umax),
            vrange: (vmin, vmax),
            points: &[],
        };
        // Knots and ranges first: their errors explain count mismatches best.
        nurbs::span_count(&surf).map_err(|m| a.err(m))?;
        let pts = self.positions(req, a, &params, nu * nv)?;
        let ctm = self.geometry_ctm(a)?;
        surf.points = &pts;
        let patches = nurbs::to_bezier(&surf).map_err(|m| a.err(m))?;
        if let Some(k) = pts.iter().position(|p| !p.is_finite()) {
            // Name the first patch the bad point reaches (conversion spreads it to those).
            return Err(
                match patches
                    .iter()
                    .position(|cp| cp.iter().any(|p| !p.is_finite()))
                {
                    Some(i) => bad_point(a, i, k, pts[k]),
                    None => a.err(format!(
                        "point {k} of \"P\" is {} ({})",
                        nonfinite(pts[k]),
                        show_point(pts[k])
                    )),
                },
            );
        }
        for (i, cp) in patches.into_iter().enumerate() {
            self.emit(a, &ctm, i, cp)?;
        }
        Ok(())
    }

    /// The "P" (or non-rational "Pw") control points of a primitive; other parameters are
    /// ignored with a warning.
    fn positions(
        &mut self,
        req: &Request,
        a: &Args,
        params: &[Param],
        n: usize,
    ) -> Result<Vec<DVec3>, SceneError> {
        let mut pos = None;
        for p in params {
            match p.name {
                "P" | "Pw" if pos.is_some() => {
                    return Err(a.err("more than one position parameter"));
                }
                "P" | "Pw" => pos = Some(p),
                "Pz" => return Err(a.err("\"Pz\" height fields are not supported")),
                other => self.ignored_param(req, other),
            }
        }
        let p = pos.ok_or_else(|| a.err("missing the \"P\" parameter"))?;
        let dim = if p.name == "P" { 3 } else { 4 };
        let v = p.nums(a)?;
        if v.len() != n * dim {
            return Err(a.err(format!(
                "\"{}\" needs {} numbers ({n} points), found {}",
                p.name,
                n * dim,
                v.len()
            )));
        }
        let mut out = Vec::with_capacity(n);
        for (k, c) in v.chunks_exact(dim).enumerate() {
            if dim == 4 && c[3] != 1.0 {
                return Err(a.err(format!(
                    "point {k} of \"Pw\" has w = {}: rational patches are not supported (w must be 1)",
                    c[3]
                )));
            }
            out.push(DVec3::new(c[0], c[1], c[2]));
        }
        Ok(out)
    }
}

/// A point for an error message: `[x, y, z]` as `DVec3` prints it, except that huge
/// coordinates (next to an overflow) are shown in exponent form instead of 300 digits.
fn show_point(p: DVec3) -> String {
    let c = |v: f64| {
        if v.abs() < 1.0e15 || !v.is_finite() {
            format!("{v}")
        } else {
            format!("{v:e}")
        }
    };
    format!("[{}, {}, {}]", c(p.x), c(p.y), c(p.z))
}

fn nonfinite(p: DVec3) -> &'static str {
    if p.is_nan() { "NaN" } else { "infinite" }
}

fn bad_point(a: &Args, patch: usize, k: usize, p: DVec3) -> SceneError {
    a.err(format!(
        "patch {patch}: point {k} of \"P\" is {} ({})",
        nonfinite(p),
        show_point(p)
    ))
}

/// Fails on the first non-finite point among `used`, naming patch `patch`.
fn check_points(
    a: &Args,
    patch: usize,
    pts: &[DVec3],
    used: impl Iterator<Item = usize>,
) -> Result<(), SceneError> {
    for k in used {
        if !pts[k].is_finite() {
            return Err(bad_point(a, patch, k, pts[k]));
        }
    }
    Ok(())
}

/// Number of control points per patch for a `Patch`/`PatchMesh` type.
fn patch_points(a: &Args, kind: &str) -> Result<usize, SceneError> {
    match kind {
        "bicubic" => Ok(16),
        "bilinear" => Ok(4),
        _ => Err(a.err(format!(
            "patch type \"{kind}\" is not \"bicubic\" or \"bilinear\""
        ))),
    }
}

fn wrap_arg(a: &mut Args, what: &str) -> Result<bool, SceneError> {
    match a.string(what)? {
        "periodic" => Ok(true),
        "nonperiodic" => Ok(false),
        w => Err(a.err(format!(
            "{what} \"{w}\" is not \"periodic\" or \"nonperiodic\""
        ))),
    }
}

/// Patches along one direction of a mesh (RenderMan rules).
fn mesh_patches(
    a: &Args,
    dir: &str,
    n: usize,
    periodic: bool,
    step: usize,
    order: usize,
) -> Result<usize, SceneError> {
    let ok = if periodic {
        n.is_multiple_of(step)
    } else {
        n >= order && (n - order).is_multiple_of(step)
    };
    if !ok {
        let rule = if periodic {
            format!("a multiple of the step {step}")
        } else {
            format!("{order} + k * step {step}")
        };
        return Err(a.err(format!("n{dir} = {n} does not fit the basis: need {rule}")));
    }
    Ok(if periodic {
        n / step
    } else {
        (n - order) / step + 1
    })
}

/// Elevates a bilinear patch (corners (0,0), (1,0), (0,1), (1,1)) to bicubic Bezier.
fn bilinear_to_bezier(c: [DVec3; 4]) -> [DVec3; 16] {
    std::array::from_fn(|k| {
        let (u, v) = ((k % 4) as f64 / 3.0, (k / 4) as f64 / 3.0);
        c[0].lerp(c[1], u).lerp(c[2].lerp(c[3], u), v)
    })
}

/// One half of a `Basis` request: a name or 16 numbers, then the step.
fn basis_arg(a: &mut Args, dir: &str) -> Result<Basis, SceneError> {
    let what = format!("the {dir} basis");
    let matrix = match a.peek() {
        Some(Arg::Str(_)) | Some(Arg::Strs(_)) => {
            let name = a.string(&what)?;
            Basis::by_name(name)
                .ok_or_else(|| a.err(format!("unknown basis \"{name}\"")))?
                .matrix
        }
        _ => {
            let v = a.fixed(16, &what)?;
            std::array::from_fn(|r| std::array::from_fn(|c| v[4 * r + c]))
        }
    };
    let step = a.int(&format!("the {dir} step"), 1, 1 << 16)? as u32;
    Ok(Basis { matrix, step })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::eval_bezier;

    fn parse(s: &str) -> Scene {
        match parse_rib(s, "t.rib") {
            Ok(s) => s,
            Err(e) => panic!("unexpected error: {e}"),
        }
    }

    fn err(s: &str) -> String {
        parse_rib(s, "t.rib")
            .expect_err("expected an error")
            .to_string()
    }

    fn world(body: &str) -> String {
        format!("WorldBegin\n{body}\nWorldEnd\n")
    }

    /// Corners (0,0,0), (1,0,0), (0,1,0), (1,1,0).
    const QUAD: &str = "Patch \"bilinear\" \"P\" [0 0 0  1 0 0  0 1 0  1 1 0]";

    fn close(a: DVec3, b: DVec3) -> bool {
        a.distance(b) < 1e-9
    }

    /// 16 points of a wavy 4x4 grid, as RIB numbers.
    fn grid_numbers(nu: usize, nv: usize) -> (Vec<DVec3>, String) {
        let pts: Vec<DVec3> = (0..nu * nv)
            .map(|k| {
                let (c, r) = ((k % nu) as f64, (k / nu) as f64);
                DVec3::new(c, r, (c * 0.9).sin() * (r * 0.7 + 0.3).cos())
            })
            .collect();
        let s = pts
            .iter()
            .map(|p| format!("{} {} {}", p.x, p.y, p.z))
            .collect::<Vec<_>>()
            .join(" ");
        (pts, s)
    }

    #[test]
    fn defaults() {
        let s = parse("WorldBegin WorldEnd");
        assert_eq!((s.width, s.height), (640, 480));
        assert_eq!(s.pixel_samples, (2, 2));
        assert_eq!(
            s.camera,
            crate::scene::Camera {
                fov_deg: 90.0,
                near: 1e-10,
                far: 1e38
            }
        );
        assert!(s.patches.is_empty() && s.lights.is_empty() && s.warnings.is_empty());
    }

    #[test]
    fn options() {
        let s = parse(&format!(
            "Format 320 200 1\nPixelSamples 3 1.5\nProjection \"perspective\" \"fov\" [40]\n\
             Clipping 0.5 100\n{}",
            world("")
        ));
        assert_eq!((s.width, s.height), (320, 200));
        assert_eq!(s.pixel_samples, (3, 2));
        assert_eq!(
            s.camera,
            crate::scene::Camera {
                fov_deg: 40.0,
                near: 0.5,
                far: 100.0
            }
        );
        let s = parse(&format!(
            "Projection \"perspective\" \"fov\" 35 {}",
            world("")
        ));
        assert_eq!(s.camera.fov_deg, 35.0);
        // No fov: RenderMan's 90.
        let s = parse(&format!("Projection \"perspective\" {}", world("")));
        assert_eq!(s.camera.fov_deg, 90.0);
    }

    #[test]
    fn option_errors() {
        let e = err(&format!("\nProjection \"orthographic\"\n{}", world("")));
        assert_eq!(
            e,
            "t.rib:2: `Projection`: projection \"orthographic\" is not supported (only \"perspective\")"
        );
        assert!(err("Projection \"perspective\" \"fov\" 0 WorldBegin WorldEnd").contains("fov 0"));
        assert!(
            err("Format 640 0 1 WorldBegin WorldEnd")
                .starts_with("t.rib:1: `Format`: the y resolution")
        );
        assert!(err("Format 640 480.5 1 WorldBegin WorldEnd").contains("integer"));
        assert!(err("Clipping 10 1 WorldBegin WorldEnd").contains("near < far"));
        assert!(err("PixelSamples 0 1 WorldBegin WorldEnd").contains("sample count"));
        assert!(err("WorldBegin Projection \"perspective\" WorldEnd").contains("inside"));
    }

    #[test]
    fn transforms_apply_last_first() {
        // Translate then Scale: points are scaled first, then translated.
        let s = parse(&world(&format!("Translate 1 0 0\nScale 2 2 2\n{QUAD}")));
        let cp = &s.patches[0].cp;
        assert!(close(cp[3], DVec3::new(3.0, 0.0, 0.0)), "{}", cp[3]);
        assert!(close(cp[12], DVec3::new(1.0, 2.0, 0.0)));
        let s = parse(&world(&format!("Scale 2 2 2\nTranslate 1 0 0\n{QUAD}")));
        assert!(close(s.patches[0].cp[3], DVec3::new(4.0, 0.0, 0.0)));
    }

    #[test]
    fn rotate_convention() {
        let s = parse(&world(&format!("Rotate 90 0 0 1\n{QUAD}")));
        assert!(
            close(s.patches[0].cp[3], DVec3::new(0.0, 1.0, 0.0)),
            "x -> y about z"
        );
        let s = parse(&world(&format!("Rotate 90 1 0 0\n{QUAD}")));
        assert!(
            close(s.patches[0].cp[12], DVec3::new(0.0, 0.0, 1.0)),
            "y -> z about x"
        );
        let s = parse(&world(&format!("Rotate 90 0 2 0\n{QUAD}")));
        assert!(
            close(s.patches[0].cp[3], DVec3::new(0.0, 0.0, -1.0)),
            "x -> -z about y"
        );
        assert!(err(&world("Rotate 30 0 0 0")).contains("axis is zero"));
    }

    #[test]
    fn camera_transform_and_identity_in_world() {
        let s = parse(&format!(
            "Translate 0 0 5\n{}",
            world(&format!("Translate 1 0 0\nIdentity\n{QUAD}"))
        ));
        assert!(close(s.patches[0].cp[0], DVec3::new(0.0, 0.0, 5.0)));
        // Before WorldBegin, Identity really is the identity.
        let s = parse(&format!(
            "Translate 0 0 5 Identity Translate 0 0 2\n{}",
            world(QUAD)
        ));
        assert!(close(s.patches[0].cp[0], DVec3::new(0.0, 0.0, 2.0)));
    }

    #[test]
    fn transform_matrices_are_row_vector_order() {
        let m = "[1 0 0 0  0 1 0 0  0 0 1 0  10 20 30 1]";
        // Transform inside the world block is relative to world space.
        let s = parse(&format!(
            "Translate 0 0 5\n{}",
            world(&format!("Translate 7 7 7\nTransform {m}\n{QUAD}"))
        ));
        assert!(close(s.patches[0].cp[0], DVec3::new(10.0, 20.0, 35.0)));
        let s = parse(&format!(
            "Translate 0 0 5\n{}",
            world(&format!("Scale 2 2 2\nConcatTransform {m}\n{QUAD}"))
        ));
        assert!(close(s.patches[0].cp[0], DVec3::new(20.0, 40.0, 65.0)));
        // A non-symmetric linear part: the first row is where x goes.
        let s = parse(&world(&format!(
            "ConcatTransform [0 1 0 0  -1 0 0 0  0 0 1 0  0 0 0 1]\n{QUAD}"
        )));
        assert!(close(s.patches[0].cp[3], DVec3::new(0.0, 1.0, 0.0)));
        assert!(
            err(&world("Transform [1 0 0 0 0 1 0 0 0 0 1 0 0 0 0]"))
                .contains("expected 16 numbers")
        );
    }

    #[test]
    fn transform_and_attribute_blocks() {
        let s = parse(&world(&format!(
            "TransformBegin\nTranslate 5 0 0\nColor [1 0 0]\nTransformEnd\n{QUAD}\n\
             AttributeBegin\nTranslate 0 3 0\nColor [0 1 0]\nSides 1\nReverseOrientation\n{QUAD}\nAttributeEnd\n{QUAD}"
        )));
        let [a, b, c] = [&s.patches[0], &s.patches[1], &s.patches[2]];
        assert!(
            close(a.cp[0], DVec3::ZERO),
            "TransformEnd restores the transform"
        );
        assert_eq!(
            s.materials[a.material as usize].color,
            DVec3::new(1.0, 0.0, 0.0),
            "but not attributes"
        );
        assert!(close(b.cp[0], DVec3::new(0.0, 3.0, 0.0)));
        assert_eq!(
            s.materials[b.material as usize].color,
            DVec3::new(0.0, 1.0, 0.0)
        );
        assert!(!b.two_sided && b.flip_normal);
        assert!(close(c.cp[0], DVec3::ZERO));
        assert_eq!(c.material, a.material);
        assert!(c.two_sided && !c.flip_normal);
        assert_eq!(s.materials.len(), 2);
    }

    #[test]
    fn orientation_and_handedness() {
        let flips = |body: &str| parse(&world(&format!("{body}\n{QUAD}"))).patches[0].flip_normal;
        assert!(!flips(""));
        assert!(flips("ReverseOrientation"));
        assert!(!flips("ReverseOrientation ReverseOrientation"));
        assert!(flips("Orientation \"rh\""));
        assert!(!flips("Orientation \"lh\""));
        assert!(!flips("Orientation \"outside\""));
        assert!(flips("Orientation \"inside\""));
        // A mirror flips the current orientation along with the coordinate system...
        assert!(flips("Scale -1 1 1"));
        assert!(!flips("Scale -1 1 1 Scale 1 -1 1"));
        // ... so "outside" and "inside" then mean rh and lh.
        assert!(flips("Scale -1 1 1 Orientation \"outside\""));
        assert!(!flips("Scale -1 1 1 Orientation \"inside\""));
        // Explicit lh/rh are absolute.
        assert!(!flips("Scale -1 1 1 Orientation \"lh\""));
        // Restoring a transform restores the handedness, and the orientation with it.
        assert!(!flips("TransformBegin Scale 1 1 -1 TransformEnd"));
        assert!(flips(
            "TransformBegin Scale 1 1 -1 TransformEnd ReverseOrientation"
        ));
        // A mirrored camera transform counts too (killeroo.rib's Transform).
        let s = parse(&format!("Scale 1 1 -1\n{}", world(QUAD)));
        assert!(s.patches[0].flip_normal);
        assert!(err(&world("Orientation \"up\"")).contains("not one of"));
    }

    #[test]
    fn mirrored_patch_keeps_its_outside() {
        // The outside normal of a mirror image is the mirror image of the outside normal.
        let outside = |body: &str| {
            let s = parse(&world(&format!("{body}\n{QUAD}")));
            let (_, du, dv) = eval_bezier(&s.patches[0].cp, 0.5, 0.5);
            let n = du.cross(dv).normalize();
            if s.patches[0].flip_normal { -n } else { n }
        };
        let n = outside("");
        // Unflipped, the quad (counter-clockwise on screen) faces away from the camera: the
        // spec's left-handed rule (clockwise vertices face the viewer).
        assert!(close(n, DVec3::Z));
        assert!(
            close(outside("Scale -1 1 1"), DVec3::Z),
            "x mirror keeps a z normal"
        );
        assert!(
            close(outside("Scale 1 1 -1"), -DVec3::Z),
            "z mirror mirrors it"
        );
    }

    fn eval_bspline(pts: &[DVec3], nu: usize, r0: usize, c0: usize, u: f64, v: f64) -> DVec3 {
        let w = |t: f64| {
            let s = 1.0 - t;
            [
                s * s * s / 6.0,
                (3.0 * t * t * t - 6.0 * t * t + 4.0) / 6.0,
                (-3.0 * t * t * t + 3.0 * t * t + 3.0 * t + 1.0) / 6.0,
                t * t * t / 6.0,
            ]
        };
        let (wu, wv) = (w(u), w(v));
        let mut p = DVec3::ZERO;
        for j in 0..4 {
            for i in 0..4 {
                p += pts[(r0 + j) * nu + c0 + i] * (wu[i] * wv[j]);
            }
        }
        p
    }

    #[test]
    fn basis_b_spline_patch_becomes_the_same_surface() {
        let (pts, nums) = grid_numbers(4, 4);
        let by_name = parse(&world(&format!(
            "Basis \"b-spline\" 1 \"b-spline\" 1\nPatch \"bicubic\" \"P\" [{nums}]"
        )));
        let by_matrix = parse(&world(&format!(
            "Basis [-0.16666666666666666 0.5 -0.5 0.16666666666666666  0.5 -1 0.5 0  -0.5 0 0.5 0  \
             0.16666666666666666 0.6666666666666666 0.16666666666666666 0] 1 \"b-spline\" 1\n\
             Patch \"bicubic\" \"P\" [{nums}]"
        )));
        for (u, v) in [(0.0, 0.0), (0.5, 0.5), (0.2, 0.9), (1.0, 1.0)] {
            let want = eval_bspline(&pts, 4, 0, 0, u, v);
            assert!(close(eval_bezier(&by_name.patches[0].cp, u, v).0, want));
            assert!(close(eval_bezier(&by_matrix.patches[0].cp, u, v).0, want));
        }
        assert!(err(&world("Basis \"nurbs\" 1 \"bezier\" 3")).contains("unknown basis \"nurbs\""));
        assert!(err(&world("Basis \"bezier\" 0 \"bezier\" 3")).contains("step"));
    }

    #[test]
    fn bilinear_patch_is_elevated() {
        let s = parse(&world(QUAD));
        let cp = &s.patches[0].cp;
        assert!(close(cp[0], DVec3::ZERO) && close(cp[3], DVec3::X) && close(cp[12], DVec3::Y));
        assert!(close(cp[15], DVec3::new(1.0, 1.0, 0.0)));
        assert!(close(cp[5], DVec3::new(1.0 / 3.0, 1.0 / 3.0, 0.0)));
        // The basis does not matter for bilinear patches.
        let t = parse(&world(&format!(
            "Basis \"b-spline\" 1 \"catmull-rom\" 1\n{QUAD}"
        )));
        assert_eq!(t.patches[0].cp, *cp);
    }

    fn mesh(
        basis: &str,
        kind: &str,
        nu: usize,
        uwrap: &str,
        nv: usize,
        vwrap: &str,
    ) -> Result<Scene, SceneError> {
        let (_, nums) = grid_numbers(nu, nv);
        parse_rib(
            &world(&format!(
                "Basis {basis}\nPatchMesh \"{kind}\" {nu} \"{uwrap}\" {nv} \"{vwrap}\" \"P\" [{nums}]"
            )),
            "t.rib",
        )
    }

    #[test]
    fn patch_mesh_counts() {
        let bz = "\"bezier\" 3 \"bezier\" 3";
        let bs = "\"b-spline\" 1 \"b-spline\" 1";
        let n = |r: Result<Scene, SceneError>| r.unwrap().patches.len();
        assert_eq!(
            n(mesh(bz, "bicubic", 7, "nonperiodic", 4, "nonperiodic")),
            2
        );
        assert_eq!(n(mesh(bz, "bicubic", 6, "periodic", 4, "nonperiodic")), 2);
        assert_eq!(
            n(mesh(bs, "bicubic", 6, "nonperiodic", 5, "nonperiodic")),
            6
        );
        assert_eq!(n(mesh(bs, "bicubic", 6, "periodic", 5, "periodic")), 30);
        assert_eq!(n(mesh(bs, "bicubic", 6, "periodic", 5, "nonperiodic")), 12);
        assert_eq!(
            n(mesh(
                "\"catmull-rom\" 1 \"hermite\" 2",
                "bicubic",
                5,
                "nonperiodic",
                6,
                "nonperiodic"
            )),
            2 * 2
        );
        assert_eq!(
            n(mesh(bz, "bilinear", 3, "nonperiodic", 2, "nonperiodic")),
            2
        );
        assert_eq!(n(mesh(bz, "bilinear", 3, "periodic", 2, "nonperiodic")), 3);
        let e = mesh(bz, "bicubic", 6, "nonperiodic", 4, "nonperiodic")
            .unwrap_err()
            .to_string();
        assert!(e.contains("nu = 6 does not fit the basis"), "{e}");
        let e = mesh(bz, "bicubic", 7, "periodic", 4, "nonperiodic")
            .unwrap_err()
            .to_string();
        assert!(e.contains("multiple of the step 3"), "{e}");
        let e = mesh(bz, "bicubic", 7, "closed", 4, "nonperiodic")
            .unwrap_err()
            .to_string();
        assert!(e.contains("\"closed\""), "{e}");
    }

    #[test]
    fn patch_mesh_patches_follow_the_basis_steps() {
        let (pts, _) = grid_numbers(6, 5);
        let s = mesh(
            "\"b-spline\" 1 \"b-spline\" 1",
            "bicubic",
            6,
            "periodic",
            5,
            "nonperiodic",
        )
        .unwrap();
        // 6 u patches per row; patch (pu = 1, pv = 1) uses columns 1..5 and rows 1..5.
        let p = &s.patches[6 + 1];
        assert_eq!(p.source.index, 7);
        for (u, v) in [(0.0, 0.0), (0.4, 0.7), (1.0, 1.0)] {
            assert!(close(
                eval_bezier(&p.cp, u, v).0,
                eval_bspline(&pts, 6, 1, 1, u, v)
            ));
        }
        // Periodic in u: the last patch of a row ends where the first begins.
        let (first, last) = (&s.patches[0], &s.patches[5]);
        for v in [0.0, 0.5, 1.0] {
            assert!(close(
                eval_bezier(&last.cp, 1.0, v).0,
                eval_bezier(&first.cp, 0.0, v).0
            ));
        }
        // Bezier meshes share edge points (step 3).
        let s = mesh(
            "\"bezier\" 3 \"bezier\" 3",
            "bicubic",
            7,
            "nonperiodic",
            4,
            "nonperiodic",
        )
        .unwrap();
        assert_eq!(s.patches[0].cp[3], s.patches[1].cp[0]);
    }

    /// NuPatch 5x4 cubic, clamped in u with one interior knot, a Bezier span in v.
    fn nu_patch(pw: bool, w: f64) -> String {
        let (_, nums) = grid_numbers(5, 4);
        let nums = if pw {
            nums.split(' ')
                .collect::<Vec<_>>()
                .chunks(3)
                .map(|c| format!("{} {w}", c.join(" ")))
                .collect::<Vec<_>>()
                .join(" ")
        } else {
            nums
        };
        let p = if pw { "Pw" } else { "P" };
        world(&format!(
            "NuPatch 5 4 [0 0 0 0 1 2 2 2 2] 0 2 4 4 [0 0 0 0 1 1 1 1] 0 1\n\"{p}\" [{nums}]"
        ))
    }

    #[test]
    fn nu_patch_spans_become_patches() {
        let s = parse(&nu_patch(false, 1.0));
        assert_eq!(s.patches.len(), 2);
        assert_eq!(
            s.patches[1].source,
            PatchSource {
                file: "t.rib".into(),
                line: 2,
                index: 1
            }
        );
        let t = parse(&nu_patch(true, 1.0));
        assert_eq!(s.patches[0].cp, t.patches[0].cp);
        // The two spans meet.
        assert!(close(
            eval_bezier(&s.patches[0].cp, 1.0, 0.3).0,
            eval_bezier(&s.patches[1].cp, 0.0, 0.3).0
        ));
    }

    #[test]
    fn nu_patch_errors_name_the_line() {
        let e = err(&nu_patch(true, 0.5));
        assert!(
            e.starts_with("t.rib:2: `NuPatch`: point 0 of \"Pw\" has w = 0.5: rational patches"),
            "{e}"
        );
        let e = err(&world(
            "\n\nNuPatch 3 3 [0 0 0 1 1 1] 0 1 3 3 [0 0 0 1 1 1] 0 1 \"P\" [0 0 0]",
        ));
        assert_eq!(
            e,
            "t.rib:4: `NuPatch`: order 3 is not supported (only order 4, bicubic)"
        );
        let e = err(&nu_patch(false, 1.0).replace("[0 0 0 0 1 2 2 2 2]", "[0 0 0 0 1 2 2 2]"));
        assert!(
            e.starts_with(
                "t.rib:2: `NuPatch`: u knot vector has 8 values, expected nu + order = 9"
            ),
            "{e}"
        );
        let e = err(&nu_patch(false, 1.0).replace("NuPatch 5 4", "NuPatch 6 4"));
        assert!(
            e.contains("u knot vector has 9 values, expected nu + order = 10"),
            "{e}"
        );
        let e = err(&nu_patch(false, 1.0)
            .replace("[0 0 0 0 1 1 1 1] 0 1", "[0 0 0 0 0.5 1 1 1 1] 0 1")
            .replace("4 4 [", "5 4 ["));
        assert!(
            e.contains("\"P\" needs 75 numbers (25 points), found 60"),
            "{e}"
        );
        let e = err(&nu_patch(false, 1.0)
            .replace("0 2 4 4", "0 2 3 4")
            .replace("[0 0 0 0 1 1 1 1]", "[0 0 0 0 1 1 1]"));
        assert!(e.contains("less than the order"), "{e}");
        let e = err(&nu_patch(false, 1.0).replace("\"P\" [0 ", "\"P\" ["));
        assert!(
            e.contains("\"P\" needs 60 numbers (20 points), found 59"),
            "{e}"
        );
    }

    #[test]
    fn materials() {
        let s = parse(&world(&format!(
            "{QUAD}\nColor [1 0 0]\nOpacity .5 .5 .5\nSurface \"plastic\" \"Ks\" .8 \"uniform float roughness\" [.2] \"specularcolor\" [1 1 0]\n{QUAD}\n\
             Surface \"wood\"\n{QUAD}\nSurface \"constant\"\n{QUAD}\nSurface \"matte\" \"Kd\" .7\n{QUAD}\n\
             Surface \"plastic\" \"Ks\" .8 \"roughness\" .2 \"specularcolor\" [1 1 0]\n{QUAD}"
        )));
        let m: Vec<&Material> = s
            .patches
            .iter()
            .map(|p| &s.materials[p.material as usize])
            .collect();
        assert_eq!(
            *m[0],
            Material::standard(SurfaceKind::Matte),
            "default surface: matte"
        );
        let plastic = Material {
            color: DVec3::new(1.0, 0.0, 0.0),
            opacity: DVec3::splat(0.5),
            ks: 0.8,
            roughness: 0.2,
            specular_color: DVec3::new(1.0, 1.0, 0.0),
            ..Material::standard(SurfaceKind::Plastic)
        };
        assert_eq!(*m[1], plastic);
        assert_eq!(
            s.patches[2].material, s.patches[1].material,
            "unknown shader keeps the surface"
        );
        assert_eq!(m[3].kind, SurfaceKind::Constant);
        assert_eq!(
            (m[4].kind, m[4].ka, m[4].kd),
            (SurfaceKind::Matte, 1.0, 0.7)
        );
        assert_eq!(
            s.patches[5].material, s.patches[1].material,
            "equal materials are shared"
        );
        assert_eq!(s.materials.len(), 4);
        assert!(s.warnings.iter().any(|w| w == "t.rib:7: skipped unsupported surface shader \"wood\" (keeping the previous surface)"));
        assert!(
            err(&world("Surface \"plastic\" \"Ks\" \"high\"")).contains("needs one finite number")
        );
        assert!(err(&world("Color [1 0]")).contains("expected 3 numbers"));
    }

    #[test]
    fn lights() {
        let s = parse(&format!(
            "Rotate 90 0 1 0\nTranslate 0 0 5\n{}",
            world(
                "LightSource \"ambientlight\" 1 \"intensity\" .5 \"lightcolor\" [1 0 0]\n\
                 LightSource \"distantlight\" 2\n\
                 LightSource \"distantlight\" 3 \"from\" [0 0 0] \"to\" [0 -2 0] \"intensity\" 2\n\
                 LightSource \"pointlight\" \"key\" \"from\" [1 2 3]\n\
                 LightSource \"spotlight\" 5\n\
                 LightSource \"pointlight\" 6"
            )
        ));
        assert_eq!(s.lights.len(), 5);
        assert_eq!(
            s.lights[0],
            Light::Ambient {
                color: DVec3::new(0.5, 0.0, 0.0)
            }
        );
        let Light::Distant { color, dir } = &s.lights[1] else {
            panic!()
        };
        // World +z, rotated 90 degrees about y: camera +x.
        assert!(*color == DVec3::ONE && close(*dir, DVec3::X), "{dir}");
        let Light::Distant { color, dir } = &s.lights[2] else {
            panic!()
        };
        assert!(*color == DVec3::splat(2.0) && close(*dir, -DVec3::Y));
        let Light::Point { pos, .. } = &s.lights[3] else {
            panic!()
        };
        // (1,2,3) + (0,0,5) = (1,2,8), then about y: (8, 2, -1).
        assert!(close(*pos, DVec3::new(8.0, 2.0, -1.0)), "{pos}");
        let Light::Point { pos, .. } = &s.lights[4] else {
            panic!()
        };
        assert!(close(*pos, DVec3::new(5.0, 0.0, 0.0)), "{pos}");
        assert!(
            s.warnings
                .iter()
                .any(|w| w.contains("light shader \"spotlight\""))
        );
        assert!(
            err(&world(
                "LightSource \"distantlight\" 1 \"from\" [1 1 1] \"to\" [1 1 1]"
            ))
            .contains("no direction")
        );
    }

    #[test]
    fn sides() {
        let s = parse(&world(&format!("Sides 1\n{QUAD}\nSides 2\n{QUAD}")));
        assert!(!s.patches[0].two_sided && s.patches[1].two_sided);
        assert_eq!(
            err(&world("Sides 3")),
            "t.rib:2: `Sides`: sides must be 1 or 2, found 3"
        );
    }

    #[test]
    fn one_warning_per_skipped_request_kind() {
        let s = parse(&format!(
            "set -x\nDisplay \"a\" \"file\" \"rgb\"\nDisplay \"b\" \"file\" \"rgb\"\nOption \"x\" \"y\" [1]\n{}",
            world(
                "Attribute \"a\" \"b\" [1]\nAttribute \"c\" \"d\" [2]\nPatch \"bilinear\" \"P\" [0 0 0 1 0 0 0 1 0 1 1 0] \"Cs\" [1 0 0 0 1 0 0 0 1 1 1 1]"
            )
        ));
        assert_eq!(
            s.warnings,
            vec![
                "t.rib:1: skipped unsupported request `set`",
                "t.rib:2: skipped unsupported request `Display`",
                "t.rib:4: skipped unsupported request `Option`",
                "t.rib:6: skipped unsupported request `Attribute`",
                "t.rib:8: ignored parameter \"Cs\" of `Patch`",
            ]
        );
        assert_eq!(s.patches.len(), 1);
    }

    #[test]
    fn object_and_motion_blocks() {
        let s = parse(&world(&format!(
            "ObjectBegin 1\n{QUAD}\nObjectEnd\nMotionBegin [0 1]\nTranslate 1 0 0\nTranslate 5 0 0\nMotionEnd\n{QUAD}"
        )));
        assert_eq!(s.patches.len(), 1);
        assert!(close(s.patches[0].cp[0], DVec3::X));
        assert_eq!(s.warnings.len(), 2);
        assert!(err(&world("ObjectBegin 1")).contains("inside `ObjectBegin`"));
    }

    #[test]
    fn truncated_files() {
        let full = world(&format!("AttributeBegin\n{QUAD}\nAttributeEnd"));
        let e = err(&full[..full.find("AttributeEnd").unwrap()]);
        assert_eq!(
            e,
            "t.rib:3: unexpected end of file inside `AttributeBegin` (line 2)"
        );
        let e = err(&full[..full.find(" 1 1 0]").unwrap()]);
        assert_eq!(
            e,
            "t.rib:3: unexpected end of file inside the array opened at line 3"
        );
        let e = err("WorldBegin\nDisplay \"x");
        assert_eq!(e, "t.rib:2: unterminated string");
        let e = err("Format 640 480 1\n");
        assert_eq!(
            e,
            "t.rib:1: no `WorldBegin` ... `WorldEnd` block in the file"
        );
    }

    #[test]
    fn wrong_value_counts() {
        let (_, nums) = grid_numbers(4, 4);
        let short: Vec<&str> = nums.split(' ').collect();
        let e = err(&world(&format!(
            "\nPatch \"bicubic\" \"P\" [{}]",
            short[..47].join(" ")
        )));
        assert_eq!(
            e,
            "t.rib:3: `Patch`: \"P\" needs 48 numbers (16 points), found 47"
        );
        assert_eq!(
            err(&world("Translate 1 2")),
            "t.rib:2: `Translate`: expected 3 numbers for the offset, found 2"
        );
        assert_eq!(
            err("Format 1 2 3 4 WorldBegin WorldEnd"),
            "t.rib:1: `Format`: unexpected extra argument: number 4"
        );
        assert!(err(&world("Patch \"bicubic\"")).contains("missing the \"P\" parameter"));
        assert!(err(&world("Patch \"bicubic\" \"P\"")).contains("parameter \"P\" has no value"));
        assert!(err(&world("Patch \"biquadratic\" \"P\" [0 0 0]")).contains("\"biquadratic\""));
    }

    #[test]
    fn non_numbers_where_numbers_are_expected() {
        assert_eq!(
            err(&world("Translate 1 \"a\" 3")),
            "t.rib:2: `Translate`: expected a number for the offset, found string \"a\""
        );
        assert_eq!(
            err(&world("Translate 1 2 3x")),
            "t.rib:2: `Translate`: unexpected `3x` (not a number or string)"
        );
        assert_eq!(
            err(&world(
                "Patch \"bilinear\" \"P\" [0 0 0 1 0 zero 0 1 0 1 1 0]"
            )),
            "t.rib:2: unexpected `zero` inside an array (not a number or string)"
        );
        assert_eq!(
            err(&world("Color [1 \"x\" 0]")),
            "t.rib:2: array mixes numbers and strings"
        );
        assert_eq!(
            err("42 WorldBegin WorldEnd"),
            "t.rib:1: expected a request, found number 42"
        );
        assert_eq!(err("WorldBegin ] WorldEnd"), "t.rib:1: unexpected `]`");
        assert!(err(&world("Translate 1 2 3 -x")).contains("unexpected `-x`"));
    }

    #[test]
    fn nan_and_inf_name_the_patch() {
        let e = err(&world(
            "Patch \"bilinear\" \"P\" [0 0 0 1 0 0 0 1 nan 1 1 0]",
        ));
        let p = DVec3::new(0.0, 1.0, f64::NAN);
        assert_eq!(
            e,
            format!("t.rib:2: `Patch`: patch 0: point 2 of \"P\" is NaN ({p})")
        );
        let (_, nums) = grid_numbers(7, 4);
        let mut v: Vec<String> = nums.split(' ').map(String::from).collect();
        v[3 * 5 + 2] = "inf".into(); // point (5, 0): in the second patch only
        let e = err(&world(&format!(
            "PatchMesh \"bicubic\" 7 \"nonperiodic\" 4 \"nonperiodic\" \"P\" [{}]",
            v.join(" ")
        )));
        assert!(
            e.starts_with("t.rib:2: `PatchMesh`: patch 1: point 5 of \"P\" is infinite ("),
            "{e}"
        );
        let e = err(&world(
            "Patch \"bilinear\" \"P\" [0 0 0 1 0 0 0 1 1e999 1 1 0]",
        ));
        assert!(e.contains("patch 0: point 2 of \"P\" is infinite"), "{e}");
        // Overflow on the way to camera space is caught as well.
        let e = err(&world(
            "Scale 1e300 1e300 1e300 Patch \"bilinear\" \"P\" [0 0 0 1e300 0 0 0 1 0 1 1 0]",
        ));
        assert!(e.contains("in camera space"), "{e}");
        // Non-finite transform arguments are rejected where they are given.
        assert!(err(&world("Translate nan 0 0")).contains("non-finite"));
    }

    #[test]
    fn unbalanced_blocks() {
        assert_eq!(
            err("AttributeEnd\nWorldBegin WorldEnd"),
            "t.rib:1: `AttributeEnd` without a matching `AttributeBegin`"
        );
        assert_eq!(
            err(&world("AttributeEnd")),
            "t.rib:2: `AttributeEnd` does not match `WorldBegin` at line 1"
        );
        assert_eq!(
            err("WorldBegin\nAttributeBegin\nWorldEnd\n"),
            "t.rib:3: `WorldEnd` does not match `AttributeBegin` at line 2"
        );
        assert_eq!(
            err("WorldEnd"),
            "t.rib:1: `WorldEnd` without a matching `WorldBegin`"
        );
        assert!(
            err("TransformEnd WorldBegin WorldEnd").contains("without a matching `TransformBegin`")
        );
        assert!(
            err(&world("TransformBegin AttributeEnd"))
                .contains("`AttributeEnd` does not match `TransformBegin`")
        );
        assert!(err("FrameBegin 1 WorldBegin WorldEnd").contains("inside `FrameBegin`"));
        assert!(err(&format!("{}{}", world(""), world(""))).contains("only one `WorldBegin`"));
        assert!(err(QUAD).contains("outside `WorldBegin`"));
        assert!(err(&world("MotionEnd")).contains("without a matching `MotionBegin`"));
    }

    /// Mutated and truncated inputs never panic.
    #[test]
    fn no_panics_on_garbage() {
        let base = format!(
            "Format 64 48 1\nProjection \"perspective\" \"fov\" [30]\nTranslate 0 0 5\nScale 1 1 -1\n{}",
            world(&format!(
                "AttributeBegin\nBasis \"b-spline\" 1 \"catmull-rom\" 1\nColor [1 .5 .2]\nSurface \"plastic\"\n\
                 LightSource \"distantlight\" 1 \"from\" [0 1 0] \"to\" [0 0 0]\n{QUAD}\n\
                 PatchMesh \"bicubic\" 4 \"periodic\" 4 \"nonperiodic\" \"P\" [{}]\n{}\nAttributeEnd",
                grid_numbers(4, 4).1,
                nu_patch(true, 1.0)
                    .replace("WorldBegin", "")
                    .replace("WorldEnd", "")
            ))
        );
        assert!(parse_rib(&base, "t.rib").is_ok());
        let bytes = base.as_bytes();
        let mut seed = 0x2545_f491_4f6c_dd1du64;
        let mut rnd = move || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            seed
        };
        let junk: &[&[u8]] = &[
            b"[",
            b"]",
            b"\"",
            b"-",
            b"nan",
            b"1e999",
            b"0",
            b"-1",
            b"AttributeEnd",
            b"#",
            b"\xff",
            b"Scale 0 0 0",
            b"999999999",
        ];
        for _ in 0..3000 {
            let mut m = bytes.to_vec();
            for _ in 0..1 + rnd() % 4 {
                let at = (rnd() as usize) % m.len();
                match rnd() % 3 {
                    0 => m.truncate(at),
                    1 => {
                        let j = junk[(rnd() as usize) % junk.len()];
                        m.splice(at..at, j.iter().copied());
                    }
                    _ => {
                        let n = ((rnd() % 8) as usize).min(m.len() - at);
                        m.drain(at..at + n);
                    }
                }
                if m.is_empty() {
                    break;
                }
            }
            let text = String::from_utf8_lossy(&m);
            let _ = parse_rib(&text, "fuzz.rib");
        }
    }
}
