//! Text handling shared by the parsers: byte decoding (UTF-8 or Latin-1), line splitting (LF, CRLF
//! or CR) and a numeric token stream that remembers the line of every token.

use super::error::{parse_error, ParseError};

/// Decodes file bytes: UTF-8 when valid, otherwise Latin-1 (every byte is one code point), which is
/// what photometric files with `°` or umlauts written on Windows contain.
pub fn decode(bytes: &[u8]) -> String {
    // A UTF-8 byte-order mark is dropped.
    let bytes = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
    match std::str::from_utf8(bytes) {
        Ok(s) => s.to_string(),
        Err(_) => bytes.iter().map(|&b| char::from(b)).collect(),
    }
}

/// Splits text into lines, accepting LF, CRLF and lone CR terminators. Trailing whitespace and
/// a DOS end-of-file marker (0x1A) are kept out of the lines.
pub fn lines(text: &str) -> Vec<&str> {
    let mut out = Vec::new();
    let mut start = 0;
    let bytes = text.as_bytes();
    let mut i = 0;
    while i < bytes.len() {
        match bytes[i] {
            b'\n' => {
                out.push(&text[start..i]);
                start = i + 1;
            }
            b'\r' => {
                out.push(&text[start..i]);
                if i + 1 < bytes.len() && bytes[i + 1] == b'\n' {
                    i += 1;
                }
                start = i + 1;
            }
            _ => {}
        }
        i += 1;
    }
    if start < text.len() {
        out.push(&text[start..]);
    }
    out.into_iter()
        .map(|l| l.trim_end_matches(|c: char| c.is_whitespace() || c == '\u{1a}'))
        .collect()
}

/// One whitespace- or comma-separated token and the 1-based line it came from.
#[derive(Debug, Clone, Copy)]
pub struct Token<'a> {
    /// The token's text.
    pub text: &'a str,
    /// 1-based line number.
    pub line: usize,
}

/// A stream of numeric tokens over a range of lines. Records may span lines or share them: the
/// reader consumes counts, not lines (LM-63-2002 §3: delimiters are commas, spaces or line ends).
pub struct Tokens<'a> {
    file: &'a str,
    tokens: Vec<Token<'a>>,
    pos: usize,
    last_line: usize,
}

impl<'a> Tokens<'a> {
    /// Tokenises `lines` (the first of which is line `first_line`, 1-based). When `comma_is_delimiter`
    /// is false a comma is a decimal separator (EULUMDAT), otherwise a delimiter (IES).
    pub fn new(file: &'a str, lines: &[&'a str], first_line: usize, comma_is_delimiter: bool) -> Self {
        let mut tokens = Vec::new();
        for (i, l) in lines.iter().enumerate() {
            let split = l.split(|c: char| c.is_whitespace() || (comma_is_delimiter && c == ','));
            for t in split.filter(|t| !t.is_empty()) {
                tokens.push(Token {
                    text: t,
                    line: first_line + i,
                });
            }
        }
        let last_line = first_line + lines.len().saturating_sub(1);
        Tokens {
            file,
            tokens,
            pos: 0,
            last_line,
        }
    }

    /// Number of tokens not yet consumed.
    pub fn remaining(&self) -> usize {
        self.tokens.len() - self.pos
    }

    /// The line of the next token (or of the end of the input).
    pub fn line(&self) -> usize {
        self.tokens.get(self.pos).map_or(self.last_line, |t| t.line)
    }

    /// The next token as a finite number.
    pub fn number(&mut self, field: &str) -> Result<f64, ParseError> {
        let Some(tok) = self.tokens.get(self.pos).copied() else {
            return Err(parse_error(
                self.file,
                Some(self.last_line),
                field,
                "file ends here (truncated?): expected a number",
            ));
        };
        self.pos += 1;
        parse_number(self.file, tok, field, false)
    }

    /// The next token as a finite number; a comma is accepted as the decimal separator.
    pub fn number_comma_decimal(&mut self, field: &str) -> Result<f64, ParseError> {
        let Some(tok) = self.tokens.get(self.pos).copied() else {
            return Err(parse_error(
                self.file,
                Some(self.last_line),
                field,
                "file ends here (truncated?): expected a number",
            ));
        };
        self.pos += 1;
        parse_number(self.file, tok, field, true)
    }

    /// The next token as a whole number within `min..=max`.
    pub fn count(&mut self, field: &str, min: i64, max: i64) -> Result<i64, ParseError> {
        let line = self.line();
        let v = self.number(field)?;
        to_count(self.file, line, field, v, min, max)
    }

    /// `n` finite numbers.
    pub fn numbers(&mut self, n: usize, field: &str) -> Result<Vec<f64>, ParseError> {
        // `n` comes from the file: reserve no more than the tokens left, so a huge declared count
        // in a short file fails with "truncated" instead of allocating gigabytes first.
        let mut out = Vec::with_capacity(n.min(self.remaining()));
        for i in 0..n {
            let v = self.number(field).map_err(|mut e| {
                e.message = format!("{} (value {} of {n})", e.message, i + 1);
                e
            })?;
            out.push(v);
        }
        Ok(out)
    }
}

/// Parses one token as a finite number.
pub fn parse_number(file: &str, tok: Token<'_>, field: &str, comma_decimal: bool) -> Result<f64, ParseError> {
    let owned;
    let text = if comma_decimal && tok.text.contains(',') {
        owned = tok.text.replace(',', ".");
        owned.as_str()
    } else {
        tok.text
    };
    // Rust's parser accepts "nan", "inf" and "infinity": photometric files must not.
    let looks_numeric = text
        .chars()
        .all(|c| c.is_ascii_digit() || matches!(c, '+' | '-' | '.' | 'e' | 'E'));
    let parsed = if looks_numeric { text.parse::<f64>().ok() } else { None };
    match parsed {
        Some(v) if v.is_finite() => Ok(v),
        _ => Err(parse_error(
            file,
            Some(tok.line),
            field,
            format!("expected a finite number, found `{}`", shorten(tok.text)),
        )),
    }
}

/// A token as quoted in an error: at most 40 characters.
fn shorten(t: &str) -> String {
    match t.char_indices().nth(40) {
        Some((i, _)) => format!("{}…", &t[..i]),
        None => t.to_string(),
    }
}

/// Checks that `v` is a whole number within `min..=max`.
pub fn to_count(file: &str, line: usize, field: &str, v: f64, min: i64, max: i64) -> Result<i64, ParseError> {
    if v.fract() != 0.0 || v < min as f64 || v > max as f64 {
        return Err(parse_error(
            file,
            Some(line),
            field,
            format!("expected a whole number from {min} to {max}, found {v}"),
        ));
    }
    Ok(v as i64)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lines_accept_every_terminator() {
        assert_eq!(lines("a\r\nb\nc\rd"), vec!["a", "b", "c", "d"]);
        assert_eq!(lines("a  \r\n\r\nb\u{1a}"), vec!["a", "", "b"]);
    }

    #[test]
    fn latin1_bytes_decode() {
        assert_eq!(decode(b"90\xb0 M\xfcller"), "90° Müller");
        assert_eq!(decode("90° Müller".as_bytes()), "90° Müller");
    }

    #[test]
    fn tokens_span_and_share_lines_with_commas() {
        let ls = ["1, 2,3", "", "4\t5  6,"];
        let mut t = Tokens::new("f", &ls, 10, true);
        assert_eq!(t.numbers(6, "x").unwrap(), vec![1.0, 2.0, 3.0, 4.0, 5.0, 6.0]);
        let e = t.number("x").unwrap_err();
        assert!(e.message.contains("truncated"), "{e}");
        assert_eq!(e.line, Some(12));
    }

    #[test]
    fn nan_and_inf_are_rejected() {
        for bad in ["nan", "NaN", "inf", "-infinity", "1e999", "abc", "1.2.3"] {
            let ls = [bad];
            let mut t = Tokens::new("f", &ls, 1, true);
            assert!(t.number("x").is_err(), "{bad} accepted");
        }
    }

    #[test]
    fn huge_declared_count_does_not_allocate() {
        let ls = ["1 2 3"];
        let mut t = Tokens::new("f", &ls, 1, true);
        let e = t.numbers(usize::MAX, "candela values").unwrap_err();
        assert!(e.field == "candela values" && e.message.contains("truncated"), "{e}");
    }

    #[test]
    fn comma_decimal_for_eulumdat() {
        let ls = ["12,5"];
        let mut t = Tokens::new("f", &ls, 1, false);
        assert_eq!(t.number_comma_decimal("x").unwrap(), 12.5);
    }
}
