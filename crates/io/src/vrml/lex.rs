//! The tokenizer shared by the classic encodings: VRML97 (ISO/IEC 14772-1 §5), X3D's classic
//! VRML encoding (ISO/IEC 19776-2) and Open Inventor 2.1 ASCII. All three write nodes as
//! `Type { field value … }`, `DEF`/`USE` names, `[ ]` lists, `"…"` strings with `\"` and `\\`
//! escapes and `#` comments to the end of the line; commas are white space.
//!
//! Tokens borrow the text; a number is parsed to `f64` on the spot (decimal, exponent, or
//! `0x` hexadecimal as Inventor's packed colours and SFImage pixels are written). Every token
//! carries its byte offset, from which [`line_column`] finds the line and column of an error.

/// One token and where it starts (byte offset in the text).
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Token<'a> {
    pub tok: Tok<'a>,
    pub at: usize,
}

#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Tok<'a> {
    /// A name: a node type, a field name, a `DEF` name, a keyword, an enum value.
    Ident(&'a str),
    Number(f64),
    /// A string with its escapes resolved.
    Str(String),
    /// One of `{ } [ ] ( ) | = . ~`.
    Punct(u8),
    Eof,
}

/// Why a token could not be read.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) struct LexError {
    pub at: usize,
    pub message: String,
}

/// The tokenizer. `inventor` selects Open Inventor's name rules (names are letters, digits
/// and `_`, and `( | ) =` are punctuation), else VRML's (ISO/IEC 14772-1 §5.1.2: any printable
/// character but `" # ' , . [ \ ] { }` and, first, digits and `+ -`).
pub(crate) struct Lexer<'a> {
    text: &'a str,
    pos: usize,
    inventor: bool,
    peeked: Option<Token<'a>>,
}

fn is_space(b: u8) -> bool {
    matches!(b, b' ' | b'\t' | b'\n' | b'\r' | b',' | 0x0b | 0x0c)
}

impl<'a> Lexer<'a> {
    pub fn new(text: &'a str, inventor: bool) -> Self {
        Lexer { text, pos: 0, inventor, peeked: None }
    }

    /// Byte offset of the next unread character (after a peeked token: its start).
    pub fn offset(&self) -> usize {
        self.peeked.as_ref().map_or(self.pos, |t| t.at)
    }

    pub fn text(&self) -> &'a str {
        self.text
    }

    fn is_ident_char(&self, b: u8) -> bool {
        if self.inventor {
            b.is_ascii_alphanumeric() || matches!(b, b'_' | b'+' | b'-' | b':') || b >= 0x80
        } else {
            !(b <= 0x20
                || b == 0x7f
                || matches!(b, b'"' | b'#' | b'\'' | b',' | b'.' | b'[' | b'\\' | b']' | b'{' | b'}'))
        }
    }

    fn is_ident_start(&self, b: u8) -> bool {
        self.is_ident_char(b) && !b.is_ascii_digit() && b != b'+' && b != b'-'
    }

    /// Skips white space (commas included) and comments.
    fn skip(&mut self) {
        let bytes = self.text.as_bytes();
        while self.pos < bytes.len() {
            let b = bytes[self.pos];
            if is_space(b) {
                self.pos += 1;
            } else if b == b'#' {
                match memchr_newline(&bytes[self.pos..]) {
                    Some(n) => self.pos += n,
                    None => self.pos = bytes.len(),
                }
            } else {
                break;
            }
        }
    }

    pub fn peek(&mut self) -> Result<&Token<'a>, LexError> {
        if self.peeked.is_none() {
            let t = self.read()?;
            self.peeked = Some(t);
        }
        Ok(self.peeked.as_ref().expect("just set"))
    }

    pub fn next(&mut self) -> Result<Token<'a>, LexError> {
        match self.peeked.take() {
            Some(t) => Ok(t),
            None => self.read(),
        }
    }

    fn read(&mut self) -> Result<Token<'a>, LexError> {
        self.skip();
        let bytes = self.text.as_bytes();
        let at = self.pos;
        let Some(&b) = bytes.get(at) else { return Ok(Token { tok: Tok::Eof, at }) };
        let punct = match b {
            b'{' | b'}' | b'[' | b']' => true,
            b'(' | b')' | b'|' | b'=' | b'~' => self.inventor,
            _ => false,
        };
        if punct {
            self.pos += 1;
            return Ok(Token { tok: Tok::Punct(b), at });
        }
        if b == b'"' {
            return self.string(at);
        }
        let next = bytes.get(at + 1).copied().unwrap_or(0);
        let starts_number = b.is_ascii_digit()
            || ((b == b'+' || b == b'-') && (next.is_ascii_digit() || next == b'.'))
            || (b == b'.' && next.is_ascii_digit());
        if starts_number {
            return self.number(at);
        }
        if b == b'.' {
            self.pos += 1;
            return Ok(Token { tok: Tok::Punct(b'.'), at });
        }
        if self.is_ident_start(b) {
            let mut end = at + 1;
            while end < bytes.len() && self.is_ident_char(bytes[end]) {
                end += 1;
            }
            self.pos = end;
            return Ok(Token { tok: Tok::Ident(&self.text[at..end]), at });
        }
        let c = self.text[at..].chars().next().unwrap_or('?');
        Err(LexError { at, message: format!("unexpected character {c:?}") })
    }

    fn string(&mut self, at: usize) -> Result<Token<'a>, LexError> {
        let bytes = self.text.as_bytes();
        let mut i = at + 1;
        let mut out = String::new();
        let mut run = i;
        loop {
            let Some(&b) = bytes.get(i) else {
                return Err(LexError {
                    at,
                    message: "a string is not closed before the end of the file".into(),
                });
            };
            match b {
                b'"' => {
                    out.push_str(&self.text[run..i]);
                    self.pos = i + 1;
                    return Ok(Token { tok: Tok::Str(out), at });
                }
                b'\\' => {
                    out.push_str(&self.text[run..i]);
                    // `\"` and `\\` escape; any other character after a backslash stands for
                    // itself (as Coin and FreeWRL read it).
                    match bytes.get(i + 1) {
                        Some(&e @ (b'"' | b'\\')) => {
                            out.push(e as char);
                            i += 2;
                        }
                        _ => i += 1,
                    }
                    run = i;
                }
                _ => i += 1,
            }
        }
    }

    fn number(&mut self, at: usize) -> Result<Token<'a>, LexError> {
        let bytes = self.text.as_bytes();
        let mut i = at;
        let negative = bytes[i] == b'-';
        if bytes[i] == b'+' || bytes[i] == b'-' {
            i += 1;
        }
        if bytes.get(i) == Some(&b'0') && matches!(bytes.get(i + 1), Some(b'x' | b'X')) {
            let start = i + 2;
            let mut end = start;
            while end < bytes.len() && bytes[end].is_ascii_hexdigit() {
                end += 1;
            }
            if end == start || end - start > 16 {
                return Err(LexError { at, message: "a hexadecimal number needs 1 to 16 digits".into() });
            }
            let v = u64::from_str_radix(&self.text[start..end], 16)
                .map_err(|e| LexError { at, message: format!("hexadecimal number: {e}") })?;
            self.pos = end;
            self.check_end(end, at)?;
            let v = v as f64;
            return Ok(Token { tok: Tok::Number(if negative { -v } else { v }), at });
        }
        while i < bytes.len() && bytes[i].is_ascii_digit() {
            i += 1;
        }
        if bytes.get(i) == Some(&b'.') {
            i += 1;
            while i < bytes.len() && bytes[i].is_ascii_digit() {
                i += 1;
            }
        }
        if matches!(bytes.get(i), Some(b'e' | b'E')) {
            let mut j = i + 1;
            if matches!(bytes.get(j), Some(b'+' | b'-')) {
                j += 1;
            }
            if bytes.get(j).is_some_and(u8::is_ascii_digit) {
                while j < bytes.len() && bytes[j].is_ascii_digit() {
                    j += 1;
                }
                i = j;
            }
        }
        let text = &self.text[at..i];
        let text = text.strip_prefix('+').unwrap_or(text);
        let v: f64 = text
            .parse()
            .map_err(|_| LexError { at, message: format!("`{}` is not a number", clip(text)) })?;
        self.pos = i;
        self.check_end(i, at)?;
        Ok(Token { tok: Tok::Number(v), at })
    }

    /// A number must end at white space or punctuation (`1.5.3`, `12abc` are not numbers).
    fn check_end(&self, end: usize, at: usize) -> Result<(), LexError> {
        match self.text.as_bytes().get(end) {
            Some(&b) if self.is_ident_char(b) || b == b'.' || b == b'"' => {
                let stop = self.text[end..]
                    .find(|c: char| c.is_whitespace() || "[]{},".contains(c))
                    .map_or(self.text.len(), |n| end + n);
                Err(LexError { at, message: format!("`{}` is not a number", clip(&self.text[at..stop])) })
            }
            _ => Ok(()),
        }
    }
}

fn memchr_newline(bytes: &[u8]) -> Option<usize> {
    bytes.iter().position(|&b| b == b'\n' || b == b'\r')
}

/// A token quoted in a message, cut to a readable length.
pub(crate) fn clip(text: &str) -> std::borrow::Cow<'_, str> {
    crate::message::clip_long_tokens(text)
}

/// 1-based line and column (in characters) of byte `at` in `text`.
#[must_use]
pub(crate) fn line_column(text: &str, at: usize) -> (usize, usize) {
    let at = at.min(text.len());
    let mut at = at;
    while !text.is_char_boundary(at) {
        at -= 1;
    }
    let before = &text.as_bytes()[..at];
    let line = 1 + before.iter().filter(|&&b| b == b'\n').count();
    let line_start = before.iter().rposition(|&b| b == b'\n').map_or(0, |p| p + 1);
    let column = 1 + text[line_start..at].chars().count();
    (line, column)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tokens(text: &str, inventor: bool) -> Vec<Tok<'_>> {
        let mut lexer = Lexer::new(text, inventor);
        let mut out = Vec::new();
        loop {
            let t = lexer.next().expect("token");
            if t.tok == Tok::Eof {
                return out;
            }
            out.push(t.tok);
        }
    }

    #[test]
    fn vrml_tokens() {
        assert_eq!(
            tokens(
                "DEF A Transform { translation 1,-2.5e1 .5 # c\n url \"a\\\"b\" } ROUTE A.x TO B.y_z",
                false
            ),
            vec![
                Tok::Ident("DEF"),
                Tok::Ident("A"),
                Tok::Ident("Transform"),
                Tok::Punct(b'{'),
                Tok::Ident("translation"),
                Tok::Number(1.0),
                Tok::Number(-25.0),
                Tok::Number(0.5),
                Tok::Ident("url"),
                Tok::Str("a\"b".into()),
                Tok::Punct(b'}'),
                Tok::Ident("ROUTE"),
                Tok::Ident("A"),
                Tok::Punct(b'.'),
                Tok::Ident("x"),
                Tok::Ident("TO"),
                Tok::Ident("B"),
                Tok::Punct(b'.'),
                Tok::Ident("y_z"),
            ]
        );
    }

    #[test]
    fn inventor_tokens() {
        assert_eq!(
            tokens("orderedRGBA [ 0xff0000ff ] parts (SIDES|TOP) value ~", true),
            vec![
                Tok::Ident("orderedRGBA"),
                Tok::Punct(b'['),
                Tok::Number(4_278_190_335.0),
                Tok::Punct(b']'),
                Tok::Ident("parts"),
                Tok::Punct(b'('),
                Tok::Ident("SIDES"),
                Tok::Punct(b'|'),
                Tok::Ident("TOP"),
                Tok::Punct(b')'),
                Tok::Ident("value"),
                Tok::Punct(b'~'),
            ]
        );
    }

    #[test]
    fn bad_tokens_are_located() {
        let mut lexer = Lexer::new("a 12abc", false);
        lexer.next().unwrap();
        let e = lexer.next().unwrap_err();
        assert_eq!(e.at, 2);
        assert!(e.message.contains("12abc"), "{}", e.message);
        let e = Lexer::new("\n  \"open", false).next().unwrap_err();
        assert_eq!(line_column("\n  \"open", e.at), (2, 3));
    }
}
