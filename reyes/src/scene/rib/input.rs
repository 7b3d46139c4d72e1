//! Where requests come from: the stack of open inputs (the scene file, then each archive that
//! `ReadArchive` opens inside it), each a token stream grouped into requests, and the opening
//! of RIB files, gzip-compressed or not.
//!
//! `ReadArchive "name"` reads the named file's requests in place of the request, as if they
//! were written there (RenderMan Interface Specification 3.2, §5.6 "Archive files"). The name
//! is looked up beside the including file first, then relative to the current directory.
//! Archives nest at most [`MAX_ARCHIVE_DEPTH`] deep; an archive that (directly or not) reads
//! itself is an error naming the files of the cycle.

use super::lexer::{Lexer, Tok, Token, shown};
use super::requests::KNOWN;
use super::syntax::{Arg, Args, Request, is_identifier};
use crate::scene::SceneError;
use std::io::{BufRead, BufReader, Read};
use std::path::{Path, PathBuf};
use std::rc::Rc;

/// Most inputs open at once: the scene file and 31 archives, each read by the one before.
pub(super) const MAX_ARCHIVE_DEPTH: usize = 32;

/// Most values (numbers, or strings) the arguments of one request may hold, counted over all
/// its arrays and bare values: 2^24, 128 MiB of numbers, far beyond any hand-written request
/// (a `PatchMesh` of 5 million points is 15 million numbers). A request past it is refused at
/// the line where it crosses the limit, before more is held (a 1.2 MB gzip of one request of
/// 600 million numbers once took 4 GB). An unknown request's arguments are read but never
/// held, so they count against nothing.
pub(crate) const MAX_REQUEST_VALUES: usize = 1 << 24;

/// Most strings the arguments of one request may hold (each costs a heap allocation besides
/// its bytes): 2^20. RIB string arrays name things (shaders, maps, parameters); 200 million
/// one-character strings once took 4 GB.
pub(crate) const MAX_REQUEST_STRINGS: usize = 1 << 20;

/// The two bytes every gzip member starts with (RFC 1952, §2.3.1).
const GZIP_MAGIC: [u8; 2] = [0x1f, 0x8b];

/// A byte stream of a RIB file's text: gzip-compressed files (by their first two bytes, not
/// their name) are decompressed as they are read.
pub fn open_rib(path: &Path) -> std::io::Result<Box<dyn Read>> {
    let mut r = BufReader::with_capacity(64 << 10, std::fs::File::open(path)?);
    Ok(if r.fill_buf()?.starts_with(&GZIP_MAGIC) {
        Box::new(flate2::bufread::MultiGzDecoder::new(r))
    } else {
        Box::new(r)
    })
}

/// One open input and its next token, read ahead.
struct Input<'a> {
    lexer: Lexer<'a>,
    peeked: Option<Token>,
    /// The file, canonical, to find cycles; `None` for text given directly.
    canonical: Option<PathBuf>,
    /// The folder archives are looked up in first.
    dir: PathBuf,
    /// Whether a request has been read from it (its first token is checked to be RIB).
    started: bool,
}

impl Input<'_> {
    fn peek(&mut self) -> Result<Option<&Token>, SceneError> {
        if self.peeked.is_none() {
            self.peeked = self.lexer.next_token()?;
        }
        Ok(self.peeked.as_ref())
    }

    fn next(&mut self) -> Result<Option<Token>, SceneError> {
        self.peek()?;
        Ok(self.peeked.take())
    }
}

/// The values one request's arguments hold so far, against [`MAX_REQUEST_VALUES`] and
/// [`MAX_REQUEST_STRINGS`].
#[derive(Default)]
struct Held {
    values: usize,
    strings: usize,
}

impl Held {
    /// Counts one more value (a string if `is_str`); the error message when it is one too many.
    fn add(&mut self, is_str: bool) -> Result<(), String> {
        self.values += 1;
        self.strings += usize::from(is_str);
        if self.values > MAX_REQUEST_VALUES {
            return Err(format!(
                "more than {MAX_REQUEST_VALUES} values in one request's arguments (the limit \
                 on array length)"
            ));
        }
        if self.strings > MAX_REQUEST_STRINGS {
            return Err(format!(
                "more than {MAX_REQUEST_STRINGS} strings in one request's arguments (the limit \
                 on string arrays)"
            ));
        }
        Ok(())
    }
}

/// Groups tokens into requests (a bare word followed by its arguments), reading through
/// archives as they are opened.
pub(super) struct Reader<'a> {
    /// The scene file first; the innermost archive last.
    inputs: Vec<Input<'a>>,
}

impl<'a> Reader<'a> {
    /// A reader of `src`, named `file` in messages; archives are looked up beside `path`
    /// when it is given (the file `src` was opened from), else beside `file`.
    pub(super) fn new(src: Box<dyn Read + 'a>, file: &str, path: Option<&Path>) -> Reader<'a> {
        let path = path.unwrap_or(Path::new(file));
        Reader {
            inputs: vec![Input {
                lexer: Lexer::new(src, file.into()),
                peeked: None,
                canonical: std::fs::canonicalize(path).ok(),
                dir: path.parent().map(Path::to_path_buf).unwrap_or_default(),
                started: false,
            }],
        }
    }

    /// The scene file's name.
    pub(super) fn file(&self) -> Rc<str> {
        self.inputs[0].lexer.file().clone()
    }

    /// An error at the end of the scene file (after `next_request` returned `None`).
    pub(super) fn eof_error(&self, msg: impl Into<String>) -> SceneError {
        let top = &self.inputs[0].lexer;
        SceneError::new(top.file(), top.eof_line(), msg)
    }

    fn top(&mut self) -> &mut Input<'a> {
        self.inputs.last_mut().expect("the scene file stays open")
    }

    fn err(&mut self, line: u64, msg: impl Into<String>) -> SceneError {
        SceneError::new(self.top().lexer.file(), line, msg)
    }

    /// The next request; an archive that ends hands back to the input that read it.
    pub(super) fn next_request(&mut self) -> Result<Option<Request>, SceneError> {
        let first = loop {
            match self.top().next()? {
                Some(t) => break t,
                None if self.inputs.len() > 1 => {
                    self.inputs.pop();
                }
                None => return Ok(None),
            }
        };
        // A file that is not RIB (`ReadArchive "/etc/shadow"`, whose first token is a whole
        // line) is refused at its first token with one error that quotes none of it. Real
        // RIB files start with a request, possibly one the reader skips (`set -x`).
        if !std::mem::replace(&mut self.top().started, true)
            && !matches!(&first.tok, Tok::Word(w) if is_identifier(w))
        {
            let file = self.top().lexer.file().clone();
            return Err(self.err(
                first.line,
                format!(
                    "{file} is not RIB: it does not start with a request name (a RIB file \
                     starts with a request such as `version`, `Display` or `WorldBegin`, or a \
                     `#` comment)"
                ),
            ));
        }
        let name = match first.tok {
            Tok::Word(w) if is_identifier(&w) => w,
            Tok::Word(w) => {
                return Err(self.err(first.line, format!("unexpected `{}`", shown(&w))));
            }
            Tok::Num(v) => {
                return Err(self.err(first.line, format!("expected a request, found number {v}")));
            }
            Tok::Str(s) => {
                let msg = format!("expected a request, found string \"{}\"", shown(&s));
                return Err(self.err(first.line, msg));
            }
            Tok::Open => return Err(self.err(first.line, "expected a request, found `[`")),
            Tok::Close => return Err(self.err(first.line, "unexpected `]`")),
        };
        let known = KNOWN.contains(&name.as_str());
        let mut args = Vec::new();
        // Values held so far (numbers and strings; strings alone).
        let mut held = Held::default();
        loop {
            let (line, stop) = match self.top().peek()? {
                None => break,
                Some(t) => (
                    t.line,
                    match &t.tok {
                        Tok::Word(w) if is_identifier(w) => Some(None),
                        // Junk after an unknown request (`set -x`) belongs to it; after a
                        // known one it is an error.
                        Tok::Word(w) if known => Some(Some(format!(
                            "`{name}`: unexpected `{}` (not a number or string)",
                            shown(w)
                        ))),
                        Tok::Close => Some(Some("unexpected `]`".to_string())),
                        _ => None,
                    },
                ),
            };
            match stop {
                Some(None) => break,
                Some(Some(msg)) => return Err(self.err(line, msg)),
                None => {}
            }
            let tok = self.top().next()?.map(|t| t.tok);
            // An unknown request's arguments are read (their syntax checked) but not held:
            // the request is skipped with a warning that names it alone.
            if !known {
                if let Some(Tok::Open) = tok {
                    self.array(line, None)?;
                }
                continue;
            }
            let arg = match tok {
                Some(Tok::Num(v)) => Arg::Num(v),
                Some(Tok::Str(s)) => Arg::Str(s),
                Some(Tok::Open) => match self.array(line, Some((&mut held, name.as_str())))? {
                    Some(a) => a,
                    None => continue,
                },
                _ => continue,
            };
            if matches!(arg, Arg::Num(_) | Arg::Str(_)) {
                let is_str = matches!(arg, Arg::Str(_));
                held.add(is_str)
                    .map_err(|msg| self.err(line, format!("`{name}`: {msg}")))?;
            }
            args.push(arg);
        }
        Ok(Some(Request {
            name,
            file: self.top().lexer.file().clone(),
            line: first.line,
            args,
        }))
    }

    /// The rest of an array opened at `open_line`: counted into `held` (with the request's
    /// name for errors) and returned, or with `held` `None` (an unknown request's) read
    /// through and dropped.
    fn array(
        &mut self,
        open_line: u64,
        mut held: Option<(&mut Held, &str)>,
    ) -> Result<Option<Arg>, SceneError> {
        let mut nums = Vec::new();
        let mut strs = Vec::new();
        loop {
            let Some(t) = self.top().next()? else {
                let line = self.top().lexer.eof_line();
                return Err(self.err(
                    line,
                    format!("unexpected end of file inside the array opened at line {open_line}"),
                ));
            };
            if let (Some((h, name)), Tok::Num(_) | Tok::Str(_)) = (held.as_mut(), &t.tok) {
                let name = *name;
                h.add(matches!(t.tok, Tok::Str(_))).map_err(|msg| {
                    let msg = format!("`{name}`: {msg} (in the array opened at line {open_line})");
                    self.err(t.line, msg)
                })?;
            }
            match t.tok {
                Tok::Close => break,
                Tok::Num(_) | Tok::Str(_) if held.is_none() => {}
                Tok::Num(v) => nums.push(v),
                Tok::Str(s) => strs.push(s),
                Tok::Open => return Err(self.err(t.line, "unexpected `[` inside an array")),
                Tok::Word(w) => {
                    let msg = format!(
                        "unexpected `{}` inside an array (not a number or string)",
                        shown(&w)
                    );
                    return Err(self.err(t.line, msg));
                }
            }
            if !nums.is_empty() && !strs.is_empty() {
                return Err(self.err(t.line, "array mixes numbers and strings"));
            }
        }
        Ok(held.map(|_| {
            if strs.is_empty() {
                Arg::Nums(nums)
            } else {
                Arg::Strs(strs)
            }
        }))
    }

    /// `ReadArchive "name"`: opens the archive; its requests come next.
    pub(super) fn read_archive(&mut self, req: &Request) -> Result<(), SceneError> {
        let mut a = Args::new(req);
        let name = a.string("the archive name")?;
        // Parameters (RIB 3.3 adds some for procedural archives) do not change what is read.
        a.params()?;
        if self.inputs.len() >= MAX_ARCHIVE_DEPTH {
            return Err(a.err(format!(
                "archives nested deeper than {MAX_ARCHIVE_DEPTH} (each read by the one before)"
            )));
        }
        let beside = self.top().dir.join(name);
        let path = [beside.clone(), PathBuf::from(name)]
            .into_iter()
            .find(|p| p.is_file())
            .ok_or_else(|| {
                a.err(format!(
                    "cannot find the archive \"{}\" (looked for {} and in the current directory)",
                    shown(name),
                    beside.display()
                ))
            })?;
        let canonical = std::fs::canonicalize(&path).ok();
        if let Some(at) = self
            .inputs
            .iter()
            .position(|i| i.canonical.is_some() && i.canonical == canonical)
        {
            let chain: Vec<String> = self.inputs[at..]
                .iter()
                .map(|i| i.lexer.file().to_string())
                .chain([path.display().to_string()])
                .collect();
            return Err(a.err(format!(
                "archive cycle: {} is already being read ({})",
                path.display(),
                chain.join(" reads ")
            )));
        }
        let src = open_rib(&path)
            .map_err(|e| a.err(format!("cannot read the archive {}: {e}", path.display())))?;
        self.inputs.push(Input {
            lexer: Lexer::new(src, path.display().to_string().into()),
            peeked: None,
            canonical,
            dir: path.parent().map(Path::to_path_buf).unwrap_or_default(),
            started: false,
        });
        Ok(())
    }
}
