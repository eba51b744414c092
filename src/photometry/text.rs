//! Text handling shared by the parsers: byte decoding (UTF-8 or Latin-1), line splitting (LF, CRLF
//! or CR) and a numeric token stream that remembers the line of every token.

use super::error::{parse_error, ParseError};

/// Decodes file bytes: UTF-8 when valid (without a copy), otherwise Latin-1 (every byte is one code
/// point), which is what photometric files with `°` or umlauts written on Windows contain.
pub fn decode(mut bytes: Vec<u8>) -> String {
    // A UTF-8 byte-order mark is dropped.
    if bytes.starts_with(b"\xEF\xBB\xBF") {
        bytes.drain(..3);
    }
    match String::from_utf8(bytes) {
        Ok(s) => s,
        Err(e) => e.into_bytes().iter().map(|&b| char::from(b)).collect(),
    }
}

/// Whether `c` ends a line's content: trailing white space and a DOS end-of-file marker (0x1A).
fn trailing(c: char) -> bool {
    c.is_whitespace() || c == '\u{1a}'
}

/// The lines of a text, one at a time (nothing is collected: a file of millions of short lines
/// costs no memory), accepting LF, CRLF and lone CR terminators. Trailing whitespace and a DOS
/// end-of-file marker (0x1A) are kept out of the lines.
#[derive(Debug, Clone)]
pub struct Lines<'a> {
    rest: &'a str,
    /// Lines returned so far.
    pub count: usize,
}

impl<'a> Lines<'a> {
    /// The lines of `text`.
    pub fn new(text: &'a str) -> Self {
        Lines { rest: text, count: 0 }
    }

    /// The text after the lines returned so far.
    pub fn rest(&self) -> &'a str {
        self.rest
    }
}

impl<'a> Iterator for Lines<'a> {
    type Item = &'a str;
    fn next(&mut self) -> Option<&'a str> {
        if self.rest.is_empty() {
            return None;
        }
        let bytes = self.rest.as_bytes();
        let (line, next) = match bytes.iter().position(|&b| b == b'\n' || b == b'\r') {
            Some(i) if bytes[i] == b'\r' && bytes.get(i + 1) == Some(&b'\n') => (&self.rest[..i], i + 2),
            Some(i) => (&self.rest[..i], i + 1),
            None => (self.rest, self.rest.len()),
        };
        self.rest = &self.rest[next..];
        self.count += 1;
        Some(line.trim_end_matches(trailing))
    }
}

/// One whitespace- or comma-separated token and the 1-based line it came from.
#[derive(Debug, Clone, Copy)]
pub struct Token<'a> {
    /// The token's text.
    pub text: &'a str,
    /// 1-based line number.
    pub line: usize,
}

/// A stream of numeric tokens over a text, read as they are asked for (nothing is collected, so
/// memory does not grow with the file). Records may span lines or share them: the reader consumes
/// counts, not lines (LM-63-2002 §3: delimiters are commas, spaces or line ends).
pub struct Tokens<'a> {
    file: &'a str,
    rest: &'a str,
    /// Line of the start of `rest` (1-based).
    line: usize,
    /// Line of the start of the text.
    first_line: usize,
    comma_is_delimiter: bool,
    /// Whether errors may quote a token (not for a referenced file that may be anything).
    quote: bool,
    peeked: Option<Token<'a>>,
}

impl<'a> Tokens<'a> {
    /// The tokens of `text`, whose first line is line `first_line` (1-based). When
    /// `comma_is_delimiter` is false a comma is a decimal separator (EULUMDAT), otherwise a
    /// delimiter (IES).
    pub fn new(file: &'a str, text: &'a str, first_line: usize, comma_is_delimiter: bool) -> Self {
        Tokens {
            file,
            rest: text,
            line: first_line,
            first_line,
            comma_is_delimiter,
            quote: true,
            peeked: None,
        }
    }

    /// Errors say what was expected but never quote the text found (for a file named by another,
    /// which may be anything: `TILT=/etc/passwd`).
    pub fn without_quotes(mut self) -> Self {
        self.quote = false;
        self
    }

    fn is_delimiter(&self, c: char) -> bool {
        c.is_whitespace() || c == '\u{1a}' || (self.comma_is_delimiter && c == ',')
    }

    /// Skips delimiters (counting line ends) and cuts the next token.
    fn advance(&mut self) -> Option<Token<'a>> {
        let bytes = self.rest.as_bytes();
        let mut i = 0;
        // Whether the last character skipped ended a line (at the end of the text that terminator
        // does not start another line: the last line is the one it ends).
        let mut after_terminator = false;
        while i < bytes.len() {
            match bytes[i] {
                b'\n' => {
                    self.line += 1;
                    after_terminator = true;
                }
                b'\r' => {
                    if bytes.get(i + 1) != Some(&b'\n') {
                        self.line += 1;
                    }
                    after_terminator = true;
                }
                _ => {
                    let c = self.rest[i..].chars().next().unwrap_or(' ');
                    if !self.is_delimiter(c) {
                        break;
                    }
                    after_terminator = false;
                    i += c.len_utf8();
                    continue;
                }
            }
            i += 1;
        }
        if i == bytes.len() && after_terminator && self.line > self.first_line {
            self.line -= 1;
        }
        let rest = &self.rest[i..];
        let end = rest
            .char_indices()
            .find(|&(_, c)| self.is_delimiter(c))
            .map_or(rest.len(), |(k, _)| k);
        if end == 0 {
            self.rest = "";
            return None;
        }
        let tok = Token {
            text: &rest[..end],
            line: self.line,
        };
        self.rest = &rest[end..];
        Some(tok)
    }

    fn peek(&mut self) -> Option<Token<'a>> {
        if self.peeked.is_none() {
            self.peeked = self.advance();
        }
        self.peeked
    }

    fn take(&mut self) -> Option<Token<'a>> {
        self.peek();
        self.peeked.take()
    }

    /// An upper bound of the tokens not yet consumed (each needs a character and a delimiter), for
    /// reserving memory: a huge declared count in a short file never allocates more than the file.
    pub fn upper_bound(&self) -> usize {
        usize::from(self.peeked.is_some()) + self.rest.len().div_ceil(2)
    }

    /// Counts the tokens not yet consumed (reads them all; for a warning about trailing data).
    pub fn count_rest(&mut self) -> usize {
        let mut n = 0;
        while self.take().is_some() {
            n += 1;
        }
        n
    }

    /// Whether any token is left.
    pub fn has_more(&mut self) -> bool {
        self.peek().is_some()
    }

    /// The line of the next token (or of the end of the input).
    pub fn line(&mut self) -> usize {
        self.peek().map_or(self.line, |t| t.line)
    }

    fn next_or_truncated(&mut self, field: &str) -> Result<Token<'a>, ParseError> {
        self.take().ok_or_else(|| {
            parse_error(
                self.file,
                Some(self.line),
                field,
                "file ends here (truncated?): expected a number",
            )
        })
    }

    /// The next token as a finite number.
    pub fn number(&mut self, field: &str) -> Result<f64, ParseError> {
        let tok = self.next_or_truncated(field)?;
        parse_number_quoting(self.file, tok, field, false, self.quote)
    }

    /// The next token as a finite number; a comma is accepted as the decimal separator.
    pub fn number_comma_decimal(&mut self, field: &str) -> Result<f64, ParseError> {
        let tok = self.next_or_truncated(field)?;
        parse_number_quoting(self.file, tok, field, true, self.quote)
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
        let mut out = Vec::with_capacity(n.min(self.upper_bound()));
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
    parse_number_quoting(file, tok, field, comma_decimal, true)
}

/// [`parse_number`]; the error quotes the token only if `quote`.
fn parse_number_quoting(
    file: &str,
    tok: Token<'_>,
    field: &str,
    comma_decimal: bool,
    quote: bool,
) -> Result<f64, ParseError> {
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
            if quote {
                format!("expected a finite number, found `{}`", shorten(tok.text))
            } else {
                "expected a finite number, found something else".to_string()
            },
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
        let lines = |t| Lines::new(t).collect::<Vec<_>>();
        assert_eq!(lines("a\r\nb\nc\rd"), vec!["a", "b", "c", "d"]);
        assert_eq!(lines("a  \r\n\r\nb\u{1a}"), vec!["a", "", "b"]);
    }

    #[test]
    fn latin1_bytes_decode() {
        assert_eq!(decode(b"90\xb0 M\xfcller".to_vec()), "90° Müller");
        assert_eq!(decode("\u{feff}90° Müller".as_bytes().to_vec()), "90° Müller");
    }

    #[test]
    fn tokens_span_and_share_lines_with_commas() {
        let mut t = Tokens::new("f", "1, 2,3\r\n\r4\t5  6,", 10, true);
        assert_eq!(t.numbers(6, "x").unwrap(), vec![1.0, 2.0, 3.0, 4.0, 5.0, 6.0]);
        let e = t.number("x").unwrap_err();
        assert!(e.message.contains("truncated"), "{e}");
        assert_eq!(e.line, Some(12));
    }

    #[test]
    fn nan_and_inf_are_rejected() {
        for bad in ["nan", "NaN", "inf", "-infinity", "1e999", "abc", "1.2.3"] {
            let mut t = Tokens::new("f", bad, 1, true);
            assert!(t.number("x").is_err(), "{bad} accepted");
        }
    }

    #[test]
    fn huge_declared_count_does_not_allocate() {
        let mut t = Tokens::new("f", "1 2 3", 1, true);
        let e = t.numbers(usize::MAX, "candela values").unwrap_err();
        assert!(e.field == "candela values" && e.message.contains("truncated"), "{e}");
    }

    #[test]
    fn truncation_names_the_last_line_whatever_ends_the_file() {
        for (text, line) in [
            ("1 2", 3),
            ("1 2\n", 3),
            ("1 2\r\n", 3),
            ("1 2\r", 3),
            ("1\n2\n\n", 5),
            ("1 2\n\u{1a}", 4),
        ] {
            let mut t = Tokens::new("f", text, 3, true);
            let e = t.numbers(3, "x").unwrap_err();
            assert_eq!(e.line, Some(line), "{text:?}: {e}");
        }
    }

    #[test]
    fn tokens_of_another_file_are_never_quoted() {
        let mut t = Tokens::new("f", "root:x:0:0", 1, true).without_quotes();
        let e = t.number("x").unwrap_err();
        assert!(!e.message.contains("root"), "{e}");
        let mut t = Tokens::new("f", "1 2 3 \u{1a}", 1, true);
        t.number("x").unwrap();
        assert_eq!(t.count_rest(), 2);
    }

    #[test]
    fn comma_decimal_for_eulumdat() {
        let mut t = Tokens::new("f", "12,5", 1, false);
        assert_eq!(t.number_comma_decimal("x").unwrap(), 12.5);
    }
}
