//! Tokens of HyperFun (SPEC section 1). Malformed input becomes a `Bad`
//! token: the parser then reports what it expected there, as the reference
//! does ("Expression expected" for `01`, "Left brace expected" for a CR).

use crate::ast::Pos;
use crate::diag::{Diagnostic, Severity};

#[derive(Debug, Clone, PartialEq)]
pub enum Tok {
    Num(f64),
    /// Identifier, keyword or function name, lower-cased.
    Id(String),
    Str,
    /// Punctuation or operator, e.g. `(` or `<=`.
    P(&'static str),
    /// A malformed number or an unknown character.
    Bad,
    Eof,
}

#[derive(Debug, Clone)]
pub struct Token {
    pub tok: Tok,
    pub pos: Pos,
}

const PUNCT2: [&str; 3] = ["<=", ">=", "/="];
const PUNCT1: [&str; 21] = [
    "(", ")", "[", "]", "{", "}", ",", ";", "+", "-", "*", "/", "^", "|", "&", "\\", "@", "~", "=",
    "<", ">",
];
const MAX_IDENT: usize = 255;
const MAX_COMMENT: usize = 256;

/// Splits `src` into tokens (ending with `Eof`). `accept_cr`: treat CR as
/// whitespace with one warning instead of an unknown lexem.
pub fn lex(src: &str, accept_cr: bool, diags: &mut Vec<Diagnostic>) -> Vec<Token> {
    // A UTF-8 byte-order mark (written by some editors) is not text.
    let src = src.strip_prefix('\u{feff}').unwrap_or(src);
    let b = src.as_bytes();
    let mut out = Vec::new();
    let (mut i, mut line, mut col) = (0usize, 1u32, 1u32);
    let mut warned_cr = false;
    while i < b.len() {
        let c = b[i];
        let pos = Pos { line, col };
        let start = i;
        match c {
            b'\n' => {
                i += 1;
                line += 1;
                col = 1;
                continue;
            }
            b' ' | b'\t' => i += 1,
            b'\r' if accept_cr => {
                if !warned_cr {
                    warned_cr = true;
                    let message = "carriage return treated as whitespace (the reference interpreter rejects it)";
                    diags.push(Diagnostic {
                        severity: Severity::Warning,
                        pos,
                        message: message.into(),
                    });
                }
                i += 1;
            }
            b'-' if b.get(i + 1) == Some(&b'-') => {
                while i < b.len() && b[i] != b'\n' {
                    i += 1;
                }
                if i - start - 2 > MAX_COMMENT {
                    diags.push(err(pos, "Lexem is very long"));
                }
            }
            c if c.is_ascii_alphabetic() => {
                while i < b.len() && (b[i].is_ascii_alphanumeric() || b[i] == b'_') {
                    i += 1;
                }
                if i - start > MAX_IDENT {
                    diags.push(err(pos, "Very long identifier"));
                }
                out.push(Token {
                    tok: Tok::Id(src[start..i].to_ascii_lowercase()),
                    pos,
                });
            }
            c if c.is_ascii_digit() || c == b'.' => {
                let (tok, end) = number(b, i);
                i = end;
                out.push(Token { tok, pos });
            }
            b'"' => {
                i += 1;
                while i < b.len() && b[i] != b'"' && b[i] != b'\n' {
                    i += 1;
                }
                if b.get(i) == Some(&b'"') {
                    i += 1;
                    out.push(Token { tok: Tok::Str, pos });
                } else {
                    diags.push(err(pos, "Second quotation mark expected"));
                    out.push(Token { tok: Tok::Bad, pos });
                }
            }
            _ => {
                let two = b
                    .get(i..i + 2)
                    .and_then(|s| PUNCT2.iter().find(|p| p.as_bytes() == s));
                let one = PUNCT1.iter().find(|p| p.as_bytes()[0] == c);
                let tok = match (two, one) {
                    (Some(p), _) => {
                        i += 2;
                        Tok::P(p)
                    }
                    (None, Some(p)) => {
                        i += 1;
                        Tok::P(p)
                    }
                    // One whole UTF-8 character, so positions stay on char boundaries.
                    _ => {
                        i += src[i..].chars().next().map_or(1, char::len_utf8);
                        Tok::Bad
                    }
                };
                out.push(Token { tok, pos });
            }
        }
        col += src[start..i].chars().count() as u32;
    }
    out.push(Token {
        tok: Tok::Eof,
        pos: Pos { line, col },
    });
    out
}

fn err(pos: Pos, message: &str) -> Diagnostic {
    Diagnostic {
        severity: Severity::Error,
        pos,
        message: message.into(),
    }
}

/// Scans a number starting at `i`; returns the token and the end offset.
/// The value follows the reference's digit-by-digit procedure, which is not
/// correctly rounded, so values match it bit for bit.
fn number(b: &[u8], mut i: usize) -> (Tok, usize) {
    let digit = |i: usize| {
        b.get(i)
            .filter(|c| c.is_ascii_digit())
            .map(|c| f64::from(c - b'0'))
    };
    let mut ok = true;
    let mut v = 0.0f64;
    let int_start = i;
    while let Some(d) = digit(i) {
        v = v * 10.0 + d;
        i += 1;
    }
    // `01`, `007`: a leading zero followed by a digit.
    if i - int_start > 1 && b[int_start] == b'0' {
        ok = false;
    }
    let mut digits = i - int_start;
    if b.get(i) == Some(&b'.') {
        i += 1;
        let mut p = 10.0f64;
        while let Some(d) = digit(i) {
            v += d / p;
            p *= 10.0;
            i += 1;
            digits += 1;
        }
    }
    if digits == 0 {
        ok = false; // a lone `.`
    }
    if matches!(b.get(i), Some(b'e' | b'E')) {
        i += 1;
        let neg = b.get(i) == Some(&b'-');
        if matches!(b.get(i), Some(b'+' | b'-')) {
            i += 1;
        }
        // The exponent's first digit may not be 0 (`1e0`, `1e05`), and it needs one.
        if digit(i).is_none_or(|d| d == 0.0) {
            ok = false;
        }
        let mut n = 0.0f64;
        while let Some(d) = digit(i) {
            n = n * 10.0 + d;
            i += 1;
        }
        if neg {
            n = -n;
        }
        v *= (n * 10f64.ln()).exp();
    }
    (if ok { Tok::Num(v) } else { Tok::Bad }, i)
}

#[cfg(test)]
// Expected literal values are the reference's, 17 significant digits.
#[allow(clippy::excessive_precision)]
mod tests {
    use super::*;

    fn toks(s: &str) -> Vec<Tok> {
        lex(s, false, &mut Vec::new())
            .into_iter()
            .map(|t| t.tok)
            .collect()
    }

    fn num(s: &str) -> f64 {
        match toks(s)[0] {
            Tok::Num(v) => v,
            ref t => panic!("{s}: {t:?}"),
        }
    }

    #[test]
    fn number_values_follow_the_reference_procedure() {
        assert_eq!(num("0.123"), 0.12300000000000001);
        assert_eq!(num("1e3"), 1000.0000000000007);
        assert_eq!(num("5e-1"), 0.49999999999999989);
        assert_eq!(num("123."), 123.0);
        assert_eq!(num(".5"), 0.5);
        assert_eq!(num("2E+2"), (2.0 * (2.0 * 10f64.ln()).exp()));
    }

    #[test]
    fn rejected_number_forms_are_bad_tokens() {
        for s in ["01", "007", "1e0", "1e05", "2E-07", ".", "1e", "1e+"] {
            assert_eq!(toks(s)[0], Tok::Bad, "{s}");
        }
        assert!(matches!(toks("0.5")[0], Tok::Num(_)));
        assert!(matches!(toks("0")[0], Tok::Num(_)));
    }

    #[test]
    fn comments_case_and_operators() {
        assert_eq!(
            toks("y--1\nZ"),
            [Tok::Id("y".into()), Tok::Id("z".into()), Tok::Eof]
        );
        assert_eq!(toks("HfSphere"), [Tok::Id("hfsphere".into()), Tok::Eof]);
        assert_eq!(
            toks("<=/=>"),
            [Tok::P("<="), Tok::P("/="), Tok::P(">"), Tok::Eof]
        );
        assert_eq!(toks("a % b")[1], Tok::Bad);
    }

    #[test]
    fn positions_are_one_based_and_tabs_count_one() {
        let t = lex("a\n\tbb c", false, &mut Vec::new());
        let p: Vec<_> = t.iter().map(|t| (t.pos.line, t.pos.col)).collect();
        assert_eq!(p, [(1, 1), (2, 2), (2, 5), (2, 6)]);
    }

    #[test]
    fn carriage_return_is_bad_or_a_warning() {
        assert_eq!(toks("a\r\nb")[1], Tok::Bad);
        let mut d = Vec::new();
        let t = lex("a\r\nb\r\n", true, &mut d);
        assert_eq!(t.len(), 3);
        assert_eq!(d.len(), 1);
        assert_eq!(d[0].severity, Severity::Warning);
    }

    #[test]
    fn long_lexemes_are_errors() {
        let mut d = Vec::new();
        lex(&format!("--{}", "c".repeat(257)), false, &mut d);
        lex(&"q".repeat(256), false, &mut d);
        let m: Vec<_> = d.iter().map(|d| d.message.as_str()).collect();
        assert_eq!(m, ["Lexem is very long", "Very long identifier"]);
    }
}
