//! Tokenizer for ASCII RIB: strings, numbers, `[` `]`, bare words (request names), and `#`
//! comments to the end of the line. Every token carries its line number for error messages.
//! Binary (encoded) RIB is rejected with an error rather than misread.

use super::SceneError;

#[derive(Clone, Debug, PartialEq)]
pub enum Tok {
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
pub struct Token {
    pub tok: Tok,
    pub line: u32,
}

fn is_delim(b: u8) -> bool {
    b.is_ascii_whitespace() || matches!(b, b'"' | b'[' | b']' | b'#')
}

/// Splits RIB text into tokens. The last element's line (or 1) locates end-of-file errors.
pub fn tokenize(src: &[u8], file: &str) -> Result<Vec<Token>, SceneError> {
    let err = |line: u32, msg: String| SceneError::new(file, line, msg);
    let mut out = Vec::new();
    let mut line = 1u32;
    let mut i = 0;
    while i < src.len() {
        let b = src[i];
        match b {
            b'\n' => {
                line += 1;
                i += 1;
            }
            _ if b.is_ascii_whitespace() => i += 1,
            b'#' => {
                while i < src.len() && src[i] != b'\n' {
                    i += 1;
                }
            }
            b'[' => {
                out.push(Token {
                    tok: Tok::Open,
                    line,
                });
                i += 1;
            }
            b']' => {
                out.push(Token {
                    tok: Tok::Close,
                    line,
                });
                i += 1;
            }
            b'"' => {
                let start_line = line;
                let mut s = Vec::new();
                i += 1;
                loop {
                    let Some(&c) = src.get(i) else {
                        return Err(err(start_line, "unterminated string".into()));
                    };
                    i += 1;
                    match c {
                        b'"' => break,
                        b'\n' => {
                            line += 1;
                            s.push(c);
                        }
                        b'\\' => {
                            let Some(&e) = src.get(i) else {
                                return Err(err(start_line, "unterminated string".into()));
                            };
                            i += 1;
                            match e {
                                b'n' => s.push(b'\n'),
                                b't' => s.push(b'\t'),
                                b'r' => s.push(b'\r'),
                                b'b' => s.push(8),
                                b'f' => s.push(12),
                                b'\n' => line += 1, // line continuation
                                b'0'..=b'7' => {
                                    let mut v = (e - b'0') as u32;
                                    for _ in 0..2 {
                                        match src.get(i) {
                                            Some(&d @ b'0'..=b'7') => {
                                                v = v * 8 + (d - b'0') as u32;
                                                i += 1;
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
                let s = String::from_utf8_lossy(&s).into_owned();
                out.push(Token {
                    tok: Tok::Str(s),
                    line: start_line,
                });
            }
            _ if b >= 0x80 || b.is_ascii_control() => {
                return Err(err(
                    line,
                    format!("unexpected byte 0x{b:02x} (binary RIB is not supported)"),
                ));
            }
            _ => {
                let start = i;
                while i < src.len() && !is_delim(src[i]) {
                    if src[i] >= 0x80 || src[i].is_ascii_control() {
                        return Err(err(
                            line,
                            format!(
                                "unexpected byte 0x{:02x} (binary RIB is not supported)",
                                src[i]
                            ),
                        ));
                    }
                    i += 1;
                }
                // ASCII only, checked above.
                let w = std::str::from_utf8(&src[start..i]).unwrap_or_default();
                let tok = match w.parse::<f64>() {
                    Ok(v) => Tok::Num(v),
                    Err(_) => Tok::Word(w.to_string()),
                };
                out.push(Token { tok, line });
            }
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn toks(s: &str) -> Vec<(Tok, u32)> {
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
}
