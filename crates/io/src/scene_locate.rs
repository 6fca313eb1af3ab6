//! Maps field paths of a RON document (`scene.objects[0].rotation.track[4].time`) to the line
//! and column where their value starts, so that problems found in the deserialized scene can
//! be reported at their place in the file.
//!
//! This is a small structural scanner over RON's syntax, not a second RON parser: it only runs
//! on text that `ron` has already parsed successfully, and it is best-effort: when it meets
//! something it does not understand it stops, and paths it has not seen are reported at
//! the nearest enclosing value it has seen.
//!
//! Path syntax: struct fields are joined with `.`, list and tuple elements are `[i]`.
//! A named one-element wrapper (`Some(x)`, a newtype variant, a struct name) is transparent:
//! `skeleton: Some((joints: …))` records `skeleton.joints`, not `skeleton[0].joints`.

use std::collections::{HashMap, HashSet};

/// A 1-based line and column (columns count characters, not bytes).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TextPosition {
    pub line: usize,
    pub column: usize,
}

/// Deepest nesting the scanner follows; `ron` itself refuses deeper documents.
const MAX_DEPTH: usize = 256;

#[derive(Clone, Debug, PartialEq)]
enum Tok<'a> {
    Ident(&'a str),
    /// A number literal, or `inf` / `NaN` with an optional sign.
    Number(&'a str),
    /// A string, byte string or character literal; its content does not matter here.
    Literal,
    Punct(char),
}

struct Lexer<'a> {
    text: &'a str,
    /// Byte offset of the next character.
    pos: usize,
    line: usize,
    column: usize,
}

impl<'a> Lexer<'a> {
    fn new(text: &'a str) -> Self {
        Lexer { text, pos: 0, line: 1, column: 1 }
    }

    fn peek_char(&self) -> Option<char> {
        self.text[self.pos..].chars().next()
    }

    fn peek_char_at(&self, n: usize) -> Option<char> {
        self.text[self.pos..].chars().nth(n)
    }

    fn bump(&mut self) -> Option<char> {
        let c = self.peek_char()?;
        self.pos += c.len_utf8();
        if c == '\n' {
            self.line += 1;
            self.column = 1;
        } else {
            self.column += 1;
        }
        Some(c)
    }

    fn here(&self) -> TextPosition {
        TextPosition { line: self.line, column: self.column }
    }

    /// Skips whitespace, comments and `#![…]` attributes. `None` on an unclosed comment.
    fn skip_trivia(&mut self) -> Option<()> {
        loop {
            match (self.peek_char(), self.peek_char_at(1)) {
                (Some(c), _) if c.is_whitespace() => {
                    self.bump();
                }
                (Some('/'), Some('/')) => {
                    while let Some(c) = self.bump() {
                        if c == '\n' {
                            break;
                        }
                    }
                }
                (Some('/'), Some('*')) => {
                    self.bump();
                    self.bump();
                    let mut depth = 1usize;
                    while depth > 0 {
                        match (self.bump()?, self.peek_char()) {
                            ('*', Some('/')) => {
                                self.bump();
                                depth -= 1;
                            }
                            ('/', Some('*')) => {
                                self.bump();
                                depth += 1;
                            }
                            _ => {}
                        }
                    }
                }
                (Some('#'), _) => {
                    // An attribute such as `#![enable(implicit_some)]`: skip to its `]`.
                    while self.bump()? != ']' {}
                }
                _ => return Some(()),
            }
        }
    }

    /// The next token and where it starts; `None` at the end or on text it cannot scan.
    fn next_token(&mut self) -> Option<(Tok<'a>, TextPosition)> {
        self.skip_trivia()?;
        let start = self.here();
        let begin = self.pos;
        let c = self.peek_char()?;
        let tok = match c {
            '(' | ')' | '[' | ']' | '{' | '}' | ',' | ':' => {
                self.bump();
                Tok::Punct(c)
            }
            '"' => {
                self.skip_quoted('"')?;
                Tok::Literal
            }
            '\'' => {
                self.skip_quoted('\'')?;
                Tok::Literal
            }
            'b' if self.peek_char_at(1) == Some('"') || self.peek_char_at(1) == Some('\'') => {
                self.bump();
                let quote = self.peek_char()?;
                self.skip_quoted(quote)?;
                Tok::Literal
            }
            'r' if matches!(self.peek_char_at(1), Some('"'))
                || (self.peek_char_at(1) == Some('#') && self.raw_string_follows()) =>
            {
                self.skip_raw_string()?;
                Tok::Literal
            }
            'b' if self.peek_char_at(1) == Some('r') && matches!(self.peek_char_at(2), Some('"' | '#')) => {
                self.bump();
                self.skip_raw_string()?;
                Tok::Literal
            }
            c if c == '+' || c == '-' || c == '.' || c.is_ascii_digit() => {
                self.bump();
                let hex = |s: &str| s.trim_start_matches(['+', '-']).starts_with("0x");
                while let Some(c) = self.peek_char() {
                    let so_far = &self.text[begin..self.pos];
                    let exponent_sign =
                        matches!(c, '+' | '-') && so_far.ends_with(['e', 'E']) && !hex(so_far);
                    if c.is_alphanumeric() || c == '_' || c == '.' || exponent_sign {
                        self.bump();
                    } else {
                        break;
                    }
                }
                Tok::Number(&self.text[begin..self.pos])
            }
            c if c == '_' || c.is_alphabetic() => {
                if c == 'r' && self.peek_char_at(1) == Some('#') {
                    self.bump();
                    self.bump();
                }
                while self.peek_char().is_some_and(|c| c.is_alphanumeric() || c == '_') {
                    self.bump();
                }
                let word = &self.text[begin..self.pos];
                if word.starts_with("inf") || word.starts_with("NaN") {
                    Tok::Number(word)
                } else {
                    Tok::Ident(word)
                }
            }
            _ => return None,
        };
        Some((tok, start))
    }

    fn skip_quoted(&mut self, quote: char) -> Option<()> {
        self.bump();
        loop {
            match self.bump()? {
                '\\' => {
                    self.bump()?;
                }
                c if c == quote => return Some(()),
                _ => {}
            }
        }
    }

    fn raw_string_follows(&self) -> bool {
        let rest = &self.text[self.pos + 1..];
        let hashes = rest.chars().take_while(|&c| c == '#').count();
        rest[hashes..].starts_with('"')
    }

    fn skip_raw_string(&mut self) -> Option<()> {
        self.bump(); // r
        let mut hashes = 0usize;
        while self.peek_char() == Some('#') {
            self.bump();
            hashes += 1;
        }
        if self.bump()? != '"' {
            return None;
        }
        loop {
            if self.bump()? == '"' {
                let rest = &self.text[self.pos..];
                if rest.chars().take(hashes).filter(|&c| c == '#').count() == hashes {
                    for _ in 0..hashes {
                        self.bump();
                    }
                    return Some(());
                }
            }
        }
    }
}

/// Walks the token stream and records the start of every value whose path is wanted.
struct Walker<'a, 'w> {
    lexer: Lexer<'a>,
    peeked: Vec<(Tok<'a>, TextPosition)>,
    path: String,
    wanted: &'w HashSet<String>,
    found: HashMap<String, TextPosition>,
}

impl<'a> Walker<'a, '_> {
    fn peek(&mut self, n: usize) -> Option<&(Tok<'a>, TextPosition)> {
        while self.peeked.len() <= n {
            let tok = self.lexer.next_token()?;
            self.peeked.push(tok);
        }
        self.peeked.get(n)
    }

    fn next(&mut self) -> Option<(Tok<'a>, TextPosition)> {
        if self.peeked.is_empty() {
            self.lexer.next_token()
        } else {
            Some(self.peeked.remove(0))
        }
    }

    fn expect_punct(&mut self, c: char) -> Option<()> {
        match self.next()? {
            (Tok::Punct(p), _) if p == c => Some(()),
            _ => None,
        }
    }

    fn record(&mut self, at: TextPosition) {
        if self.wanted.contains(&self.path) && !self.found.contains_key(&self.path) {
            self.found.insert(self.path.clone(), at);
        }
    }

    fn value(&mut self, depth: usize) -> Option<()> {
        if depth > MAX_DEPTH {
            return None;
        }
        let (tok, at) = self.next()?;
        self.record(at);
        match tok {
            Tok::Ident(_) => {
                if matches!(self.peek(0), Some((Tok::Punct('('), _))) {
                    self.next();
                    self.paren_body(true, depth)?;
                }
                Some(())
            }
            Tok::Number(_) | Tok::Literal => Some(()),
            Tok::Punct('(') => self.paren_body(false, depth),
            Tok::Punct('[') => self.list_body(']', depth),
            Tok::Punct('{') => self.map_body(depth),
            Tok::Punct(_) => None,
        }
    }

    /// After `(`: either `field: value, …` or tuple elements, up to and including `)`.
    fn paren_body(&mut self, named: bool, depth: usize) -> Option<()> {
        let is_struct = matches!(self.peek(0), Some((Tok::Ident(_), _)))
            && matches!(self.peek(1), Some((Tok::Punct(':'), _)));
        if !is_struct {
            if named {
                // `Some(x)`, `Procedural(ArmLowPoly)`: the first element is the value itself.
                return self.elements(')', depth, true);
            }
            return self.list_body(')', depth);
        }
        loop {
            if matches!(self.peek(0), Some((Tok::Punct(')'), _))) {
                self.next();
                return Some(());
            }
            let name = match self.next()? {
                (Tok::Ident(name), _) => name.strip_prefix("r#").unwrap_or(name),
                _ => return None,
            };
            self.expect_punct(':')?;
            let len = self.path.len();
            if !self.path.is_empty() {
                self.path.push('.');
            }
            self.path.push_str(name);
            let result = self.value(depth + 1);
            self.path.truncate(len);
            result?;
            match self.next()? {
                (Tok::Punct(','), _) => {}
                (Tok::Punct(')'), _) => return Some(()),
                _ => return None,
            }
        }
    }

    fn list_body(&mut self, close: char, depth: usize) -> Option<()> {
        self.elements(close, depth, false)
    }

    fn elements(&mut self, close: char, depth: usize, first_transparent: bool) -> Option<()> {
        let mut index = 0usize;
        loop {
            if matches!(self.peek(0), Some((Tok::Punct(p), _)) if *p == close) {
                self.next();
                return Some(());
            }
            let len = self.path.len();
            if !(first_transparent && index == 0) {
                self.path.push('[');
                self.path.push_str(&index.to_string());
                self.path.push(']');
            }
            let result = self.value(depth + 1);
            self.path.truncate(len);
            result?;
            index += 1;
            match self.next()? {
                (Tok::Punct(','), _) => {}
                (Tok::Punct(p), _) if p == close => return Some(()),
                _ => return None,
            }
        }
    }

    fn map_body(&mut self, depth: usize) -> Option<()> {
        loop {
            if matches!(self.peek(0), Some((Tok::Punct('}'), _))) {
                self.next();
                return Some(());
            }
            self.value(depth + 1)?;
            self.expect_punct(':')?;
            self.value(depth + 1)?;
            match self.next()? {
                (Tok::Punct(','), _) => {}
                (Tok::Punct('}'), _) => return Some(()),
                _ => return None,
            }
        }
    }
}

/// Candidate paths for `path`, most specific first: the path itself, then its parents.
/// A trailing vector component (`.x`, `.y`, `.z`, `.w`) is also tried as a tuple index.
fn candidates(path: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut current = path.to_string();
    loop {
        if let Some((parent, last)) = current.rsplit_once('.') {
            if let Some(i) = ["x", "y", "z", "w"].iter().position(|c| *c == last) {
                out.push(format!("{parent}[{i}]"));
            }
        }
        out.push(current.clone());
        let cut = current.rfind(['.', '[']);
        match cut {
            Some(i) if i > 0 => current.truncate(i),
            _ => break,
        }
    }
    out
}

/// Finds, for each of `paths`, where its value (or its nearest located parent) starts in
/// `text`. `None` where not even a parent could be found.
#[must_use]
pub fn locate(text: &str, paths: &[String]) -> Vec<Option<TextPosition>> {
    let per_path: Vec<Vec<String>> = paths.iter().map(|p| candidates(p)).collect();
    let wanted: HashSet<String> = per_path.iter().flatten().cloned().collect();
    let mut walker = Walker {
        lexer: Lexer::new(text),
        peeked: Vec::new(),
        path: String::new(),
        wanted: &wanted,
        found: HashMap::new(),
    };
    // Best-effort: stop at the first thing the scanner does not understand.
    let _ = walker.value(0);
    per_path.iter().map(|cands| cands.iter().find_map(|c| walker.found.get(c).copied())).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn at(text: &str, path: &str) -> Option<(usize, usize)> {
        locate(text, &[path.to_string()])[0].map(|p| (p.line, p.column))
    }

    #[test]
    fn finds_fields_elements_and_components() {
        let text = "(\n    version: 1,\n    scene: (\n        fps: 30.0,\n        list: [\n            (time: 0.0, value: (1.0, NaN, 3.0)),\n            (time: -1e-5, value: (1.0, 2.0, inf)),\n        ],\n        skeleton: Some((joints: [\"a\"])),\n    ),\n)\n";
        assert_eq!(at(text, "version"), Some((2, 14)));
        assert_eq!(at(text, "scene.fps"), Some((4, 14)));
        assert_eq!(at(text, "scene.list[0].value.y"), Some((6, 38)));
        assert_eq!(at(text, "scene.list[1].value.z"), Some((7, 45)));
        assert_eq!(at(text, "scene.list[1].time"), Some((7, 20)));
        assert_eq!(at(text, "scene.skeleton.joints[0]"), Some((9, 34)));
        // Not in the text: the nearest parent.
        assert_eq!(at(text, "scene.list[1].tcb.bias"), Some((7, 13)));
        assert_eq!(at(text, "nothing"), None);
    }

    #[test]
    fn skips_comments_strings_and_attributes() {
        let text = "#![enable(implicit_some)]\n// a (comment\n/* block /* nested */ ) */ (name: \"a ) \\\" b\", other: r#\"x\"y\"#, c: 'x', d: 2)";
        assert_eq!(at(text, "d"), Some((3, 75)));
        assert_eq!(at(text, "other"), Some((3, 54)));
    }

    #[test]
    fn stops_quietly_on_garbage() {
        assert_eq!(at("(a: 1, b: ~~~)", "a"), Some((1, 5)));
        assert_eq!(at("(a: 1, b: ~~~)", "b"), None);
        assert_eq!(at("", "a"), None);
        assert_eq!(at("(a: /* unclosed", "a"), None);
    }
}
