//! Requests as read ([`Request`]: a name and its arguments, grouped by `super::input`), and
//! a cursor over a request's arguments whose errors name the file, request and line
//! ([`Args`]).

use super::lexer::shown;
use crate::scene::SceneError;
use glam::DVec3;
use std::rc::Rc;

/// One argument of a request.
#[derive(Clone, Debug, PartialEq)]
pub(super) enum Arg {
    Num(f64),
    Str(String),
    Nums(Vec<f64>),
    Strs(Vec<String>),
}

impl Arg {
    pub(super) fn describe(&self) -> String {
        match self {
            Arg::Num(v) => format!("number {v}"),
            Arg::Str(s) => format!("string \"{}\"", shown(s)),
            Arg::Nums(v) => format!("array of {} numbers", v.len()),
            Arg::Strs(v) => format!("array of {} strings", v.len()),
        }
    }
}

#[derive(Debug)]
pub(super) struct Request {
    pub(super) name: String,
    /// The file (or archive) the request is in, as errors name it.
    pub(super) file: Rc<str>,
    pub(super) line: u64,
    pub(super) args: Vec<Arg>,
}

pub(super) fn is_identifier(w: &str) -> bool {
    w.starts_with(|c: char| c.is_ascii_alphabetic() || c == '_')
        && w.bytes().all(|c| c.is_ascii_alphanumeric() || c == b'_')
}

/// A parameter of a request's parameter list: the name without its inline type declaration,
/// and that declaration (`"varying color Cs"` gives name `Cs`, decl `varying color`).
pub(super) struct Param<'r> {
    pub(super) name: &'r str,
    pub(super) decl: Option<&'r str>,
    pub(super) value: &'r Arg,
}

/// Cursor over a request's arguments with error messages naming the request and line.
pub(super) struct Args<'r> {
    pub(super) req: &'r Request,
    pub(super) pos: usize,
}

impl<'r> Args<'r> {
    pub(super) fn new(req: &'r Request) -> Args<'r> {
        Args { req, pos: 0 }
    }

    pub(super) fn err(&self, msg: impl std::fmt::Display) -> SceneError {
        SceneError::new(
            &self.req.file,
            self.req.line,
            format!("`{}`: {msg}", self.req.name),
        )
    }

    pub(super) fn peek(&self) -> Option<&'r Arg> {
        self.req.args.get(self.pos)
    }

    pub(super) fn take(&mut self, what: &str) -> Result<&'r Arg, SceneError> {
        let a = self
            .req
            .args
            .get(self.pos)
            .ok_or_else(|| self.err(format!("missing {what}")))?;
        self.pos += 1;
        Ok(a)
    }

    /// A finite number (a bare number or a one-element array).
    pub(super) fn num(&mut self, what: &str) -> Result<f64, SceneError> {
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
    pub(super) fn int(&mut self, what: &str, lo: usize, hi: usize) -> Result<usize, SceneError> {
        let v = self.num(what)?;
        if v.fract() != 0.0 || v < lo as f64 || v > hi as f64 {
            return Err(self.err(format!(
                "{what} must be an integer in {lo}..={hi}, found {v}"
            )));
        }
        Ok(v as usize)
    }

    pub(super) fn string(&mut self, what: &str) -> Result<&'r str, SceneError> {
        match self.take(what)? {
            Arg::Str(s) => Ok(s),
            Arg::Strs(v) if v.len() == 1 => Ok(&v[0]),
            other => Err(self.err(format!(
                "expected a string for {what}, found {}",
                other.describe()
            ))),
        }
    }

    pub(super) fn array(&mut self, what: &str) -> Result<&'r [f64], SceneError> {
        match self.take(what)? {
            Arg::Nums(v) => Ok(v),
            other => Err(self.err(format!(
                "expected an array of numbers for {what}, found {}",
                other.describe()
            ))),
        }
    }

    /// `n` finite numbers, given either bare or as one array.
    pub(super) fn fixed(&mut self, n: usize, what: &str) -> Result<Vec<f64>, SceneError> {
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
    pub(super) fn params(&mut self) -> Result<Vec<Param<'r>>, SceneError> {
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
            let decl = name.trim_end().strip_suffix(short).map(str::trim);
            let decl = decl.filter(|d| !d.is_empty());
            let value = self
                .peek()
                .ok_or_else(|| self.err(format!("parameter \"{}\" has no value", shown(short))))?;
            self.pos += 1;
            out.push(Param {
                name: short,
                decl,
                value,
            });
        }
        Ok(out)
    }

    pub(super) fn done(&self) -> Result<(), SceneError> {
        match self.peek() {
            None => Ok(()),
            Some(a) => Err(self.err(format!("unexpected extra argument: {}", a.describe()))),
        }
    }
}

impl Param<'_> {
    pub(super) fn num(&self, a: &Args) -> Result<f64, SceneError> {
        match self.value {
            Arg::Num(v) if v.is_finite() => Ok(*v),
            Arg::Nums(v) if v.len() == 1 && v[0].is_finite() => Ok(v[0]),
            other => Err(a.err(format!(
                "parameter \"{}\" needs one finite number, found {}",
                shown(self.name),
                other.describe()
            ))),
        }
    }

    pub(super) fn vec3(&self, a: &Args) -> Result<DVec3, SceneError> {
        match self.value {
            Arg::Nums(v) if v.len() == 3 && v.iter().all(|x| x.is_finite()) => {
                Ok(DVec3::new(v[0], v[1], v[2]))
            }
            other => Err(a.err(format!(
                "parameter \"{}\" needs 3 finite numbers, found {}",
                shown(self.name),
                other.describe()
            ))),
        }
    }

    pub(super) fn nums<'a>(&'a self, a: &Args) -> Result<&'a [f64], SceneError> {
        match self.value {
            Arg::Nums(v) => Ok(v),
            Arg::Num(v) => Ok(std::slice::from_ref(v)),
            other => Err(a.err(format!(
                "parameter \"{}\" needs numbers, found {}",
                shown(self.name),
                other.describe()
            ))),
        }
    }
}
