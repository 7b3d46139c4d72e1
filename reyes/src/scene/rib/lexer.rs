//! Tokenizer for ASCII RIB: strings, numbers, `[` `]`, bare words (request names), and `#`
//! comments to the end of the line. Every token carries its line number for error messages.
//! Binary (encoded) RIB is rejected with an error rather than misread; gzip-compressed RIB is
//! decompressed before it gets here (`super::source`).
//!
//! The lexer reads its input as a stream ([`Lexer::next_token`]), so the memory it needs is
//! one token, not the file: a hostile file of millions of requests fails at its first error
//! having held only what the interpreter keeps.

use crate::scene::SceneError;
use std::io::Read;
use std::rc::Rc;

#[derive(Clone, Debug, PartialEq)]
pub(super) enum Tok {
    /// A bare word that is not a number: a request name, or junk such as `-x`.
    Word(String),
    Str(String),
    /// Any bare word Rust parses as f64, including `nan` and `inf` (caught later with a
    /// better message than "not a number").
    Num(f64),
    Open,
    Close,
}

#[derive(Clone, Debug, PartialEq)]
pub(super) struct Token {
    pub(super) tok: Tok,
    pub(super) line: u64,
}

/// Longest token (string or bare word) the lexer accepts, in bytes: far beyond any real RIB
/// string, and a bound on what one hostile token can make the reader hold.
pub(super) const MAX_TOKEN_BYTES: usize = 16 << 20;

/// Characters of an input token that a diagnostic quotes; longer tokens are cut there and
/// their length is given instead.
pub(super) const QUOTE_CHARS: usize = 64;

/// `s` for a diagnostic: whole when short, else its first [`QUOTE_CHARS`] characters and its
/// length ("AAAA…" (100000 bytes)), so that a huge token never floods the terminal.
pub(super) fn shown(s: &str) -> String {
    match s.char_indices().nth(QUOTE_CHARS) {
        None => s.to_string(),
        Some((cut, _)) => format!("{}… ({} bytes)", &s[..cut], s.len()),
    }
}

fn is_delim(b: u8) -> bool {
    b.is_ascii_whitespace() || matches!(b, b'"' | b'[' | b']' | b'#')
}

fn binary(b: u8) -> String {
    format!("unexpected byte 0x{b:02x} (binary RIB is not supported)")
}

/// A stream of tokens from one input (a file, an archive, or text).
pub(super) struct Lexer<'a> {
    src: Box<dyn Read + 'a>,
    /// The input's name in errors.
    file: Rc<str>,
    buf: Box<[u8]>,
    pos: usize,
    len: usize,
    /// The current line (1-based; 64 bits: a file of more than 2^32 lines must not wrap).
    line: u64,
    /// Whether the last byte consumed was a newline (for the end-of-file line).
    after_newline: bool,
}

impl<'a> Lexer<'a> {
    pub(super) fn new(src: Box<dyn Read + 'a>, file: Rc<str>) -> Lexer<'a> {
        Lexer {
            src,
            file,
            buf: vec![0; 64 << 10].into_boxed_slice(),
            pos: 0,
            len: 0,
            line: 1,
            after_newline: false,
        }
    }

    /// A lexer whose input starts at line `line` (a test of line numbers past 2^32).
    #[cfg(test)]
    pub(super) fn starting_at(src: Box<dyn Read + 'a>, line: u64) -> Lexer<'a> {
        Lexer {
            line,
            ..Lexer::new(src, "t".into())
        }
    }

    pub(super) fn file(&self) -> &Rc<str> {
        &self.file
    }

    /// The line an end-of-file error names: the last line that has any text (1 for an empty
    /// input), as `str::lines` counts them.
    pub(super) fn eof_line(&self) -> u64 {
        if self.after_newline && self.line > 1 {
            self.line - 1
        } else {
            self.line
        }
    }

    fn err(&self, line: u64, msg: impl Into<String>) -> SceneError {
        SceneError::new(&self.file, line, msg)
    }

    /// The next byte without consuming it; `None` at the end of the input.
    fn peek(&mut self) -> Result<Option<u8>, SceneError> {
        if self.pos == self.len {
            self.pos = 0;
            self.len = loop {
                match self.src.read(&mut self.buf) {
                    Ok(n) => break n,
                    Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
                    Err(e) => return Err(self.err(self.line, format!("cannot read: {e}"))),
                }
            };
            if self.len == 0 {
                return Ok(None);
            }
        }
        Ok(Some(self.buf[self.pos]))
    }

    fn bump(&mut self) -> Result<Option<u8>, SceneError> {
        let b = self.peek()?;
        if let Some(c) = b {
            self.pos += 1;
            self.after_newline = c == b'\n';
            if c == b'\n' {
                self.line += 1;
            }
        }
        Ok(b)
    }

    fn too_long(&self, line: u64, what: &[u8]) -> SceneError {
        let start = String::from_utf8_lossy(&what[..QUOTE_CHARS.min(what.len())]).into_owned();
        self.err(
            line,
            format!(
                "a token longer than {} MiB (starting \"{start}…\")",
                MAX_TOKEN_BYTES >> 20
            ),
        )
    }

    /// The next token, `None` at the end of the input.
    pub(super) fn next_token(&mut self) -> Result<Option<Token>, SceneError> {
        loop {
            let Some(b) = self.peek()? else {
                return Ok(None);
            };
            let line = self.line;
            let tok = match b {
                _ if b.is_ascii_whitespace() => {
                    self.bump()?;
                    continue;
                }
                b'#' => {
                    while !matches!(self.peek()?, None | Some(b'\n')) {
                        self.bump()?;
                    }
                    continue;
                }
                b'[' => {
                    self.bump()?;
                    Tok::Open
                }
                b']' => {
                    self.bump()?;
                    Tok::Close
                }
                b'"' => {
                    self.bump()?;
                    Tok::Str(self.string(line)?)
                }
                _ if b >= 0x80 || b.is_ascii_control() => return Err(self.err(line, binary(b))),
                _ => self.word(line)?,
            };
            return Ok(Some(Token { tok, line }));
        }
    }

    /// The rest of a string whose opening quote (on `start_line`) has been consumed.
    fn string(&mut self, start_line: u64) -> Result<String, SceneError> {
        let mut s = Vec::new();
        let unterminated = |l: &Self| l.err(start_line, "unterminated string");
        loop {
            if s.len() > MAX_TOKEN_BYTES {
                return Err(self.too_long(start_line, &s));
            }
            let Some(c) = self.bump()? else {
                return Err(unterminated(self));
            };
            match c {
                b'"' => break,
                b'\\' => {
                    let Some(e) = self.bump()? else {
                        return Err(unterminated(self));
                    };
                    match e {
                        b'n' => s.push(b'\n'),
                        b't' => s.push(b'\t'),
                        b'r' => s.push(b'\r'),
                        b'b' => s.push(8),
                        b'f' => s.push(12),
                        b'\n' => {} // line continuation
                        b'0'..=b'7' => {
                            let mut v = (e - b'0') as u32;
                            for _ in 0..2 {
                                match self.peek()? {
                                    Some(d @ b'0'..=b'7') => {
                                        v = v * 8 + (d - b'0') as u32;
                                        self.bump()?;
                                    }
                                    _ => break,
                                }
                            }
                            s.push(v as u8);
                        }
                        other => s.push(other),
                    }
                }
                _ => s.push(c),
            }
        }
        Ok(String::from_utf8_lossy(&s).into_owned())
    }

    /// A bare word: a number, a request name or junk.
    fn word(&mut self, line: u64) -> Result<Tok, SceneError> {
        let mut w = Vec::new();
        while let Some(c) = self.peek()? {
            if is_delim(c) {
                break;
            }
            if c >= 0x80 || c.is_ascii_control() {
                return Err(self.err(line, binary(c)));
            }
            if w.len() >= MAX_TOKEN_BYTES {
                return Err(self.too_long(line, &w));
            }
            w.push(c);
            self.bump()?;
        }
        // ASCII only, checked above.
        let w = String::from_utf8(w).unwrap_or_default();
        Ok(match w.parse::<f64>() {
            Ok(v) => Tok::Num(v),
            Err(_) => Tok::Word(w),
        })
    }
}

/// All tokens of `src` (tests).
#[cfg(test)]
pub(super) fn tokenize(src: &[u8], file: &str) -> Result<Vec<Token>, SceneError> {
    let mut lx = Lexer::new(Box::new(src), file.into());
    let mut out = Vec::new();
    while let Some(t) = lx.next_token()? {
        out.push(t);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn toks(s: &str) -> Vec<(Tok, u64)> {
        tokenize(s.as_bytes(), "t")
            .unwrap()
            .into_iter()
            .map(|t| (t.tok, t.line))
            .collect()
    }

    #[test]
    fn all_token_kinds_with_lines() {
        let t = toks("Format 640 -4.5e1 .5 # comment \"not a string\n[ \"a b\" ]\nset -x\n");
        assert_eq!(
            t,
            vec![
                (Tok::Word("Format".into()), 1),
                (Tok::Num(640.0), 1),
                (Tok::Num(-45.0), 1),
                (Tok::Num(0.5), 1),
                (Tok::Open, 2),
                (Tok::Str("a b".into()), 2),
                (Tok::Close, 2),
                (Tok::Word("set".into()), 3),
                (Tok::Word("-x".into()), 3),
            ]
        );
    }

    #[test]
    fn delimiters_need_no_spaces() {
        let t = toks("Color[1 .5 .3]Surface\"plastic\"");
        assert_eq!(t.len(), 8);
        assert_eq!(t[0].0, Tok::Word("Color".into()));
        assert_eq!(t[5].0, Tok::Close);
        assert_eq!(t[6].0, Tok::Word("Surface".into()));
        assert_eq!(t[7].0, Tok::Str("plastic".into()));
    }

    #[test]
    fn string_escapes_and_multiline_strings() {
        let t = toks("\"a\\\"b\\n\\101\" \"x\ny\" Z");
        assert_eq!(t[0], (Tok::Str("a\"b\nA".into()), 1));
        assert_eq!(t[1], (Tok::Str("x\ny".into()), 1));
        assert_eq!(t[2], (Tok::Word("Z".into()), 2));
    }

    #[test]
    fn nan_and_inf_are_numbers_junk_is_a_word() {
        let t = toks("nan inf -inf 1e999 1.2.3 3x");
        assert!(matches!(t[0].0, Tok::Num(v) if v.is_nan()));
        assert_eq!(t[1].0, Tok::Num(f64::INFINITY));
        assert_eq!(t[2].0, Tok::Num(f64::NEG_INFINITY));
        assert_eq!(t[3].0, Tok::Num(f64::INFINITY));
        assert_eq!(t[4].0, Tok::Word("1.2.3".into()));
        assert_eq!(t[5].0, Tok::Word("3x".into()));
    }

    #[test]
    fn errors() {
        let e = tokenize(b"Display \"x\n\n", "f.rib").unwrap_err();
        assert_eq!(e.to_string(), "f.rib:1: unterminated string");
        let e = tokenize(b"\n\nPatch \x81\x02", "f.rib").unwrap_err();
        assert_eq!(
            e.to_string(),
            "f.rib:3: unexpected byte 0x81 (binary RIB is not supported)"
        );
        let e = tokenize(b"ab\x00c", "f.rib").unwrap_err();
        assert!(e.to_string().starts_with("f.rib:1: unexpected byte 0x00"));
    }

    /// Tokens across the 64 KiB read buffer's boundaries come out whole, with their lines.
    #[test]
    fn tokens_span_buffer_boundaries() {
        let mut text = String::new();
        let mut want = Vec::new();
        for k in 0..20_000 {
            text += &format!("Word{k} \"s{k}\"\n{k}.5 ");
            want.push((Tok::Word(format!("Word{k}")), k as u64 + 1));
            want.push((Tok::Str(format!("s{k}")), k as u64 + 1));
            want.push((Tok::Num(k as f64 + 0.5), k as u64 + 2));
        }
        assert!(text.len() > 4 * (64 << 10));
        let got = toks(&text);
        assert_eq!(got.len(), want.len());
        if let Some(k) = (0..got.len()).find(|&k| got[k] != want[k]) {
            panic!("token {k}: {:?}, expected {:?}", got[k], want[k]);
        }
    }

    #[test]
    fn end_of_file_line_counts_like_str_lines() {
        for text in ["", "a", "a\n", "a\nb", "a\nb\n", "a\n\n", "\n"] {
            let mut lx = Lexer::new(Box::new(text.as_bytes()), "t".into());
            while lx.next_token().unwrap().is_some() {}
            assert_eq!(
                lx.eof_line(),
                text.lines().count().max(1) as u64,
                "{text:?}"
            );
        }
    }

    /// Line numbers are 64-bit: a file of more than 2^32 lines (4.4e9 once wrapped the
    /// counter) names its lines past it.
    #[test]
    fn line_numbers_go_past_two_to_the_32() {
        let start = u32::MAX as u64 - 1;
        let mut lx = Lexer::starting_at(Box::new(&b"A\n\nB\n\"x\n"[..]), start);
        assert_eq!(lx.next_token().unwrap().unwrap().line, start);
        assert_eq!(lx.next_token().unwrap().unwrap().line, start + 2);
        let e = lx.next_token().unwrap_err();
        assert_eq!(e.line, u32::MAX as u64 + 2);
        assert_eq!(e.to_string(), "t:4294967297: unterminated string");
    }

    #[test]
    fn long_tokens_are_quoted_short_and_bounded() {
        let word = "A".repeat(100_000);
        let s = shown(&word);
        assert_eq!(s, format!("{}… (100000 bytes)", "A".repeat(64)));
        assert_eq!(shown("short"), "short");
        let huge = format!("\"{}\"", "B".repeat(MAX_TOKEN_BYTES + 10));
        let e = tokenize(huge.as_bytes(), "f.rib").unwrap_err().to_string();
        assert!(e.starts_with("f.rib:1: a token longer than 16 MiB"), "{e}");
        assert!(e.len() < 200, "{e}");
    }
}
