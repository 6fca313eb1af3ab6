//! The scene file's text: a writer and a fast reader for the subset of RON that keyrig
//! writes. This is the one hand-written piece of RON beside the `ron` crate, kept for speed
//! only; everything else (other RON syntax, versions, error messages with their line and
//! column, placing a scene's problems) is `ron`'s.
//!
//! Why it exists: the 100 000-key load and save targets of docs/benchmarks.md (each under
//! 200 ms), measured by the criterion bench `crates/io/benches/scene.rs`
//! (`cargo bench -p keyrig-io --bench scene`, groups `scene_100k_keys_default_tcb` and
//! `scene_100k_keys_varied_tcb`). On the 2-core VM of that file, release build, 100 010 keys,
//! default / varied T/C/B: `ron` alone reads the documents in 195 / 355 ms and its pretty
//! printer writes them in 195 / 246 ms (before the file is written and synced); this module
//! reads them in 49 / 71 ms and writes them in 38 / 40 ms.
//!
//! What keeps it honest: the reader accepts a text only when `ron` reads it to the same value
//! (on anything else it gives up and [`crate::scene_file`] reads the text with `ron`), and
//! `ron` reads everything the writer writes back to exactly the value written. The tests in
//! `scene_file` compare both with `ron` on generated scenes (tricky floats, `-0.0`, NaN,
//! Unicode names, escapes) and on mutated files.
//!
//! # Writer
//!
//! One fixed layout (it defines the bytes of every saved scene; changing it changes files):
//! - structs, lists and maps: one field or element per line, indented by four spaces, each
//!   followed by a comma; empty ones are `()`, `[]`, `{}`;
//! - tuples (vectors `(x, y, z)`, quaternions `(x, y, z, w)`) and struct variants
//!   (`Spot(cutoff_deg: 35.0, …)`) on one line;
//! - a struct named `Key` ([`keyrig_core::Key`]) and everything inside it on one line, with
//!   the fields equal to their defaults left out (`interpolation: Tcb`,
//!   `tcb: (tension: 0.0, continuity: 0.0, bias: 0.0)`; `Key`'s deserializer fills them in);
//! - `Option` as `Some(…)` / `None`, enum variants by name, no struct names;
//! - floats in their shortest round-trip form (`zmij`: `0.1`, `1e-7`, `3e+38`, `30.0`), so
//!   that reading a file back gives the same bits and writing it again gives the same bytes;
//! - strings in double quotes with `\\`, `\"`, `\n`, `\r`, `\t` and `\u{…}` escapes for other
//!   control characters; everything else as UTF-8.
//!
//! (`ron`'s pretty printer cannot write this layout: it would print each key over eleven
//! lines, 50 MB for 100 000 keys.)
//!
//! # Reader
//!
//! A serde deserializer for the strict subset that the writer produces (and that people
//! write by hand): structs `(field: value, …)`, lists `[…]`, tuples, `Some(…)`/`None`, enum
//! variants, numbers (`-1.5e-3`, `inf`, `NaN`), plain strings and comments. It reports no
//! positions and gives up on anything outside the subset. The subset is strict, never more
//! lenient than `ron` (for example it requires commas between elements and nothing after the
//! document).

use std::fmt::{self, Write as _};

use serde::de::{self, DeserializeSeed, Visitor};
use serde::ser::{self, Serialize};

/// Why the reader gave up (never shown to users; `ron` re-reads the text for that), or a
/// custom error of a `Serialize` impl (the writer itself cannot fail).
#[derive(Debug)]
pub struct TextError(String);

impl fmt::Display for TextError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for TextError {}

impl de::Error for TextError {
    fn custom<T: fmt::Display>(msg: T) -> Self {
        TextError(msg.to_string())
    }
}

impl ser::Error for TextError {
    fn custom<T: fmt::Display>(msg: T) -> Self {
        TextError(msg.to_string())
    }
}

type Result<T = ()> = std::result::Result<T, TextError>;

// ---- Writer ----

/// The struct printed on one line, defaults omitted.
const KEY_STRUCT: &str = "Key";

/// Fields of [`KEY_STRUCT`] that are left out when equal to their default.
const KEY_DEFAULTS: [(&str, &str); 2] =
    [("interpolation", "Tcb"), ("tcb", "(tension: 0.0, continuity: 0.0, bias: 0.0)")];

/// Writes `value` as RON with the scene file layout (no trailing newline).
pub(crate) fn to_ron<T: ?Sized + Serialize>(value: &T) -> Result<String> {
    let mut writer = Writer { out: String::with_capacity(4096), indent: 0, inline: 0 };
    value.serialize(&mut writer)?;
    Ok(writer.out)
}

struct Writer {
    out: String,
    indent: usize,
    /// > 0 while writing something that goes on one line.
    inline: usize,
}

impl Writer {
    fn newline(&mut self) {
        self.out.push('\n');
        for _ in 0..self.indent {
            self.out.push_str("    ");
        }
    }

    fn write_str_literal(&mut self, s: &str) {
        self.out.push('"');
        for c in s.chars() {
            match c {
                '"' => self.out.push_str("\\\""),
                '\\' => self.out.push_str("\\\\"),
                '\n' => self.out.push_str("\\n"),
                '\r' => self.out.push_str("\\r"),
                '\t' => self.out.push_str("\\t"),
                c if c.is_control() => {
                    let _ = write!(self.out, "\\u{{{:x}}}", u32::from(c));
                }
                c => self.out.push(c),
            }
        }
        self.out.push('"');
    }

    /// Shortest round-trip text of a float (zmij, Schubfach); `NaN`, `inf`, `-inf` otherwise.
    /// Integral values keep a `.0` so that they read as floats.
    fn write_float<F: zmij::Float + Copy + fmt::Debug>(&mut self, v: F) {
        let mut buffer = zmij::Buffer::new();
        self.out.push_str(buffer.format(v));
    }

    fn open(&mut self, bracket: char, inline: bool, skip_defaults: bool) -> Compound<'_> {
        self.out.push(bracket);
        if inline {
            self.inline += 1;
        } else {
            self.indent += 1;
        }
        Compound { w: self, inline, first: true, skip_defaults }
    }
}

/// A struct, tuple, list or map being written.
struct Compound<'a> {
    w: &'a mut Writer,
    inline: bool,
    first: bool,
    skip_defaults: bool,
}

impl Compound<'_> {
    /// Starts the next element: separator and line break as the layout wants.
    fn next(&mut self) {
        if self.inline {
            if !self.first {
                self.w.out.push_str(", ");
            }
        } else {
            self.w.newline();
        }
        self.first = false;
    }

    fn element<T: ?Sized + Serialize>(&mut self, value: &T) -> Result {
        self.next();
        value.serialize(&mut *self.w)?;
        if !self.inline {
            self.w.out.push(',');
        }
        Ok(())
    }

    fn field<T: ?Sized + Serialize>(&mut self, name: &str, value: &T) -> Result {
        let start = self.w.out.len();
        let was_first = self.first;
        self.next();
        self.w.out.push_str(name);
        self.w.out.push_str(": ");
        let value_start = self.w.out.len();
        value.serialize(&mut *self.w)?;
        if self.skip_defaults
            && KEY_DEFAULTS.iter().any(|(n, default)| *n == name && self.w.out[value_start..] == **default)
        {
            // Equal to its default: take the field out again.
            self.w.out.truncate(start);
            self.first = was_first;
            return Ok(());
        }
        if !self.inline {
            self.w.out.push(',');
        }
        Ok(())
    }

    fn close(self, bracket: char) -> Result {
        if self.inline {
            self.w.inline -= 1;
        } else {
            self.w.indent -= 1;
            if !self.first {
                self.w.newline();
            }
        }
        self.w.out.push(bracket);
        Ok(())
    }
}

impl<'a> ser::Serializer for &'a mut Writer {
    type Ok = ();
    type Error = TextError;
    type SerializeSeq = Compound<'a>;
    type SerializeTuple = Compound<'a>;
    type SerializeTupleStruct = Compound<'a>;
    type SerializeTupleVariant = Compound<'a>;
    type SerializeMap = Compound<'a>;
    type SerializeStruct = Compound<'a>;
    type SerializeStructVariant = Compound<'a>;

    fn serialize_bool(self, v: bool) -> Result {
        self.out.push_str(if v { "true" } else { "false" });
        Ok(())
    }
    fn serialize_i8(self, v: i8) -> Result {
        self.serialize_i64(i64::from(v))
    }
    fn serialize_i16(self, v: i16) -> Result {
        self.serialize_i64(i64::from(v))
    }
    fn serialize_i32(self, v: i32) -> Result {
        self.serialize_i64(i64::from(v))
    }
    fn serialize_i64(self, v: i64) -> Result {
        let _ = write!(self.out, "{v}");
        Ok(())
    }
    fn serialize_i128(self, v: i128) -> Result {
        let _ = write!(self.out, "{v}");
        Ok(())
    }
    fn serialize_u8(self, v: u8) -> Result {
        self.serialize_u64(u64::from(v))
    }
    fn serialize_u16(self, v: u16) -> Result {
        self.serialize_u64(u64::from(v))
    }
    fn serialize_u32(self, v: u32) -> Result {
        self.serialize_u64(u64::from(v))
    }
    fn serialize_u64(self, v: u64) -> Result {
        let _ = write!(self.out, "{v}");
        Ok(())
    }
    fn serialize_u128(self, v: u128) -> Result {
        let _ = write!(self.out, "{v}");
        Ok(())
    }
    fn serialize_f32(self, v: f32) -> Result {
        self.write_float(v);
        Ok(())
    }
    fn serialize_f64(self, v: f64) -> Result {
        self.write_float(v);
        Ok(())
    }
    fn serialize_char(self, v: char) -> Result {
        match v {
            '\'' => self.out.push_str("'\\''"),
            '\\' => self.out.push_str("'\\\\'"),
            '\n' => self.out.push_str("'\\n'"),
            '\r' => self.out.push_str("'\\r'"),
            '\t' => self.out.push_str("'\\t'"),
            c if c.is_control() => {
                let _ = write!(self.out, "'\\u{{{:x}}}'", u32::from(c));
            }
            c => {
                self.out.push('\'');
                self.out.push(c);
                self.out.push('\'');
            }
        }
        Ok(())
    }
    fn serialize_str(self, v: &str) -> Result {
        self.write_str_literal(v);
        Ok(())
    }
    fn serialize_bytes(self, v: &[u8]) -> Result {
        use ser::SerializeSeq;
        let mut seq = self.serialize_seq(Some(v.len()))?;
        for b in v {
            seq.serialize_element(b)?;
        }
        seq.end()
    }
    fn serialize_none(self) -> Result {
        self.out.push_str("None");
        Ok(())
    }
    fn serialize_some<T: ?Sized + Serialize>(self, value: &T) -> Result {
        self.out.push_str("Some(");
        value.serialize(&mut *self)?;
        self.out.push(')');
        Ok(())
    }
    fn serialize_unit(self) -> Result {
        self.out.push_str("()");
        Ok(())
    }
    fn serialize_unit_struct(self, _name: &'static str) -> Result {
        self.out.push_str("()");
        Ok(())
    }
    fn serialize_unit_variant(self, _name: &'static str, _index: u32, variant: &'static str) -> Result {
        self.out.push_str(variant);
        Ok(())
    }
    fn serialize_newtype_struct<T: ?Sized + Serialize>(self, _name: &'static str, value: &T) -> Result {
        self.out.push('(');
        value.serialize(&mut *self)?;
        self.out.push(')');
        Ok(())
    }
    fn serialize_newtype_variant<T: ?Sized + Serialize>(
        self,
        _name: &'static str,
        _index: u32,
        variant: &'static str,
        value: &T,
    ) -> Result {
        self.out.push_str(variant);
        self.out.push('(');
        value.serialize(&mut *self)?;
        self.out.push(')');
        Ok(())
    }
    fn serialize_seq(self, _len: Option<usize>) -> Result<Compound<'a>> {
        let inline = self.inline > 0;
        Ok(self.open('[', inline, false))
    }
    fn serialize_tuple(self, _len: usize) -> Result<Compound<'a>> {
        Ok(self.open('(', true, false))
    }
    fn serialize_tuple_struct(self, _name: &'static str, _len: usize) -> Result<Compound<'a>> {
        Ok(self.open('(', true, false))
    }
    fn serialize_tuple_variant(
        self,
        _name: &'static str,
        _index: u32,
        variant: &'static str,
        _len: usize,
    ) -> Result<Compound<'a>> {
        self.out.push_str(variant);
        Ok(self.open('(', true, false))
    }
    fn serialize_map(self, _len: Option<usize>) -> Result<Compound<'a>> {
        let inline = self.inline > 0;
        Ok(self.open('{', inline, false))
    }
    fn serialize_struct(self, name: &'static str, _len: usize) -> Result<Compound<'a>> {
        let key = name == KEY_STRUCT;
        let inline = key || self.inline > 0;
        Ok(self.open('(', inline, key))
    }
    fn serialize_struct_variant(
        self,
        _name: &'static str,
        _index: u32,
        variant: &'static str,
        _len: usize,
    ) -> Result<Compound<'a>> {
        self.out.push_str(variant);
        Ok(self.open('(', true, false))
    }
}

impl ser::SerializeSeq for Compound<'_> {
    type Ok = ();
    type Error = TextError;
    fn serialize_element<T: ?Sized + Serialize>(&mut self, value: &T) -> Result {
        self.element(value)
    }
    fn end(self) -> Result {
        self.close(']')
    }
}

impl ser::SerializeTuple for Compound<'_> {
    type Ok = ();
    type Error = TextError;
    fn serialize_element<T: ?Sized + Serialize>(&mut self, value: &T) -> Result {
        self.element(value)
    }
    fn end(self) -> Result {
        self.close(')')
    }
}

impl ser::SerializeTupleStruct for Compound<'_> {
    type Ok = ();
    type Error = TextError;
    fn serialize_field<T: ?Sized + Serialize>(&mut self, value: &T) -> Result {
        self.element(value)
    }
    fn end(self) -> Result {
        self.close(')')
    }
}

impl ser::SerializeTupleVariant for Compound<'_> {
    type Ok = ();
    type Error = TextError;
    fn serialize_field<T: ?Sized + Serialize>(&mut self, value: &T) -> Result {
        self.element(value)
    }
    fn end(self) -> Result {
        self.close(')')
    }
}

impl ser::SerializeMap for Compound<'_> {
    type Ok = ();
    type Error = TextError;
    fn serialize_key<T: ?Sized + Serialize>(&mut self, key: &T) -> Result {
        self.next();
        key.serialize(&mut *self.w)?;
        self.w.out.push_str(": ");
        Ok(())
    }
    fn serialize_value<T: ?Sized + Serialize>(&mut self, value: &T) -> Result {
        value.serialize(&mut *self.w)?;
        if !self.inline {
            self.w.out.push(',');
        }
        Ok(())
    }
    fn end(self) -> Result {
        self.close('}')
    }
}

impl ser::SerializeStruct for Compound<'_> {
    type Ok = ();
    type Error = TextError;
    fn serialize_field<T: ?Sized + Serialize>(&mut self, key: &'static str, value: &T) -> Result {
        self.field(key, value)
    }
    fn end(self) -> Result {
        self.close(')')
    }
}

impl ser::SerializeStructVariant for Compound<'_> {
    type Ok = ();
    type Error = TextError;
    fn serialize_field<T: ?Sized + Serialize>(&mut self, key: &'static str, value: &T) -> Result {
        self.field(key, value)
    }
    fn end(self) -> Result {
        self.close(')')
    }
}

// ---- Reader ----

fn give_up<T>(why: &str) -> Result<T> {
    Err(TextError(why.to_string()))
}

/// Reads a whole document with `seed`; nothing but whitespace and comments may follow.
pub fn from_str_seed<'de, S: DeserializeSeed<'de>>(text: &'de str, seed: S) -> Result<S::Value> {
    let mut parser = Parser { src: text.as_bytes(), text, pos: 0 };
    let value = seed.deserialize(&mut parser)?;
    parser.skip_trivia()?;
    if parser.pos != parser.src.len() {
        return give_up("text after the document");
    }
    Ok(value)
}

struct Parser<'de> {
    src: &'de [u8],
    text: &'de str,
    pos: usize,
}

fn is_ident_start(b: u8) -> bool {
    b.is_ascii_alphabetic() || b == b'_'
}

fn is_ident_continue(b: u8) -> bool {
    b.is_ascii_alphanumeric() || b == b'_'
}

impl<'de> Parser<'de> {
    fn skip_trivia(&mut self) -> Result<()> {
        loop {
            match self.src.get(self.pos) {
                Some(b' ' | b'\n' | b'\t' | b'\r') => self.pos += 1,
                Some(b'/') => match self.src.get(self.pos + 1) {
                    Some(b'/') => {
                        while let Some(&b) = self.src.get(self.pos) {
                            self.pos += 1;
                            if b == b'\n' {
                                break;
                            }
                        }
                    }
                    Some(b'*') => {
                        self.pos += 2;
                        let mut depth = 1usize;
                        while depth > 0 {
                            match (self.src.get(self.pos), self.src.get(self.pos + 1)) {
                                (Some(b'*'), Some(b'/')) => {
                                    depth -= 1;
                                    self.pos += 2;
                                }
                                (Some(b'/'), Some(b'*')) => {
                                    depth += 1;
                                    self.pos += 2;
                                }
                                (Some(_), _) => self.pos += 1,
                                (None, _) => return give_up("unclosed comment"),
                            }
                        }
                    }
                    _ => return Ok(()),
                },
                _ => return Ok(()),
            }
        }
    }

    fn peek(&mut self) -> Result<Option<u8>> {
        self.skip_trivia()?;
        Ok(self.src.get(self.pos).copied())
    }

    fn eat(&mut self, c: u8) -> Result<bool> {
        if self.peek()? == Some(c) {
            self.pos += 1;
            Ok(true)
        } else {
            Ok(false)
        }
    }

    fn expect(&mut self, c: u8) -> Result<()> {
        if self.eat(c)? {
            Ok(())
        } else {
            give_up("unexpected character")
        }
    }

    fn ident(&mut self) -> Result<&'de str> {
        self.skip_trivia()?;
        let start = self.pos;
        match self.src.get(self.pos) {
            Some(&b) if is_ident_start(b) => self.pos += 1,
            _ => return give_up("expected an identifier"),
        }
        while self.src.get(self.pos).is_some_and(|&b| is_ident_continue(b)) {
            self.pos += 1;
        }
        // An identifier cannot be directly followed by a non-ASCII character in this subset
        // (RON identifiers may be Unicode; leave those to `ron`).
        if self.src.get(self.pos).is_some_and(|&b| b >= 0x80) {
            return give_up("non-ASCII identifier");
        }
        Ok(&self.text[start..self.pos])
    }

    /// A number: `-?digits(.digits)?([eE][+-]?digits)?`, or `inf`/`NaN` with an optional sign.
    fn number(&mut self) -> Result<&'de str> {
        self.skip_trivia()?;
        let start = self.pos;
        let digits = |p: &mut Self| {
            let s = p.pos;
            while p.src.get(p.pos).is_some_and(u8::is_ascii_digit) {
                p.pos += 1;
            }
            p.pos > s
        };
        if matches!(self.src.get(self.pos), Some(b'-' | b'+')) {
            self.pos += 1;
        }
        let rest = &self.src[self.pos..];
        if rest.starts_with(b"inf") || rest.starts_with(b"NaN") {
            self.pos += 3;
        } else {
            if !digits(self) {
                return give_up("expected a number");
            }
            if self.src.get(self.pos) == Some(&b'.') {
                self.pos += 1;
                if !digits(self) {
                    return give_up("expected digits after '.'");
                }
            }
            if matches!(self.src.get(self.pos), Some(b'e' | b'E')) {
                self.pos += 1;
                if matches!(self.src.get(self.pos), Some(b'-' | b'+')) {
                    self.pos += 1;
                }
                if !digits(self) {
                    return give_up("expected an exponent");
                }
            }
        }
        // Suffixes (`1f32`), underscores and the like are left to `ron`.
        if self.src.get(self.pos).is_some_and(|&b| is_ident_continue(b) || b == b'.') {
            return give_up("unusual number");
        }
        Ok(&self.text[start..self.pos])
    }

    fn float<T: std::str::FromStr>(&mut self) -> Result<T> {
        let token = self.number()?;
        // `ron` reads `+NaN`/`-NaN` with signs of its own; leave signed NaN to it.
        if token.len() == 4 && token.ends_with("NaN") {
            return give_up("signed NaN");
        }
        token.parse().or_else(|_| give_up("bad float"))
    }

    fn integer<T: std::str::FromStr>(&mut self) -> Result<T> {
        let token = self.number()?;
        if token.starts_with('+') || !token.bytes().skip(1).all(|b| b.is_ascii_digit()) {
            return give_up("not a plain integer");
        }
        token.parse().or_else(|_| give_up("integer out of range"))
    }

    /// A double-quoted string with the escapes `\" \\ \n \r \t`; anything else goes to `ron`.
    fn string(&mut self) -> Result<std::borrow::Cow<'de, str>> {
        self.expect(b'"')?;
        let start = self.pos;
        let mut owned: Option<String> = None;
        let mut run_start = start;
        loop {
            match self.src.get(self.pos) {
                None => return give_up("unclosed string"),
                Some(b'"') => {
                    let tail = &self.text[run_start..self.pos];
                    self.pos += 1;
                    return Ok(match owned {
                        None => std::borrow::Cow::Borrowed(tail),
                        Some(mut s) => {
                            s.push_str(tail);
                            std::borrow::Cow::Owned(s)
                        }
                    });
                }
                Some(b'\\') => {
                    let s = owned.get_or_insert_with(String::new);
                    s.push_str(&self.text[run_start..self.pos]);
                    let c = match self.src.get(self.pos + 1) {
                        Some(b'"') => '"',
                        Some(b'\\') => '\\',
                        Some(b'n') => '\n',
                        Some(b'r') => '\r',
                        Some(b't') => '\t',
                        _ => return give_up("unusual escape"),
                    };
                    s.push(c);
                    self.pos += 2;
                    run_start = self.pos;
                }
                // Raw control characters inside strings are left to `ron` to judge.
                Some(&b) if b < 0x20 => return give_up("control character in string"),
                Some(_) => self.pos += 1,
            }
        }
    }

    /// After an element of a `(…)` or `[…]`: a comma, or the closing bracket. Returns true
    /// when the sequence has ended (the bracket is consumed).
    fn after_element(&mut self, close: u8) -> Result<bool> {
        if self.eat(b',')? {
            Ok(self.eat(close)?)
        } else if self.eat(close)? {
            Ok(true)
        } else {
            give_up("expected ',' or a closing bracket")
        }
    }
}

/// Elements up to `close`.
struct Elements<'a, 'de> {
    p: &'a mut Parser<'de>,
    close: u8,
    done: bool,
}

impl<'a, 'de> Elements<'a, 'de> {
    fn new(p: &'a mut Parser<'de>, close: u8) -> Result<Self> {
        let done = p.eat(close)?;
        Ok(Elements { p, close, done })
    }

    fn finish(self) -> Result<()> {
        if self.done {
            Ok(())
        } else {
            give_up("more elements than expected")
        }
    }
}

impl<'de> de::SeqAccess<'de> for Elements<'_, 'de> {
    type Error = TextError;

    fn next_element_seed<T: DeserializeSeed<'de>>(&mut self, seed: T) -> Result<Option<T::Value>> {
        if self.done {
            return Ok(None);
        }
        let value = seed.deserialize(&mut *self.p)?;
        self.done = self.p.after_element(self.close)?;
        Ok(Some(value))
    }
}

impl<'de> de::MapAccess<'de> for Elements<'_, 'de> {
    type Error = TextError;

    fn next_key_seed<K: DeserializeSeed<'de>>(&mut self, seed: K) -> Result<Option<K::Value>> {
        if self.done {
            return Ok(None);
        }
        let key = seed.deserialize(Identifier(&mut *self.p))?;
        self.p.expect(b':')?;
        Ok(Some(key))
    }

    fn next_value_seed<V: DeserializeSeed<'de>>(&mut self, seed: V) -> Result<V::Value> {
        let value = seed.deserialize(&mut *self.p)?;
        self.done = self.p.after_element(self.close)?;
        Ok(value)
    }
}

/// Deserializes a struct field name.
struct Identifier<'a, 'de>(&'a mut Parser<'de>);

impl<'de> de::Deserializer<'de> for Identifier<'_, 'de> {
    type Error = TextError;

    fn deserialize_any<V: Visitor<'de>>(self, visitor: V) -> Result<V::Value> {
        visitor.visit_borrowed_str(self.0.ident()?)
    }

    serde::forward_to_deserialize_any! {
        bool i8 i16 i32 i64 i128 u8 u16 u32 u64 u128 f32 f64 char str string bytes byte_buf
        option unit unit_struct newtype_struct seq tuple tuple_struct map struct enum
        identifier ignored_any
    }
}

impl<'de> de::EnumAccess<'de> for &mut Parser<'de> {
    type Error = TextError;
    type Variant = Self;

    fn variant_seed<V: DeserializeSeed<'de>>(self, seed: V) -> Result<(V::Value, Self)> {
        let variant = seed.deserialize(Identifier(&mut *self))?;
        Ok((variant, self))
    }
}

impl<'de> de::VariantAccess<'de> for &mut Parser<'de> {
    type Error = TextError;

    fn unit_variant(self) -> Result<()> {
        if self.peek()? == Some(b'(') {
            return give_up("unit variant with parentheses");
        }
        Ok(())
    }

    fn newtype_variant_seed<T: DeserializeSeed<'de>>(self, seed: T) -> Result<T::Value> {
        self.expect(b'(')?;
        let value = seed.deserialize(&mut *self)?;
        // `Name(x,)` is fine for ron too.
        self.eat(b',')?;
        self.expect(b')')?;
        Ok(value)
    }

    fn tuple_variant<V: Visitor<'de>>(self, _len: usize, visitor: V) -> Result<V::Value> {
        self.expect(b'(')?;
        let mut elements = Elements::new(self, b')')?;
        let value = visitor.visit_seq(&mut elements)?;
        elements.finish()?;
        Ok(value)
    }

    fn struct_variant<V: Visitor<'de>>(
        self,
        _fields: &'static [&'static str],
        visitor: V,
    ) -> Result<V::Value> {
        self.expect(b'(')?;
        let mut elements = Elements::new(self, b')')?;
        let value = visitor.visit_map(&mut elements)?;
        elements.finish()?;
        Ok(value)
    }
}

impl<'de> de::Deserializer<'de> for &mut Parser<'de> {
    type Error = TextError;

    fn deserialize_any<V: Visitor<'de>>(self, _visitor: V) -> Result<V::Value> {
        give_up("self-describing value")
    }

    fn deserialize_ignored_any<V: Visitor<'de>>(self, _visitor: V) -> Result<V::Value> {
        give_up("ignored value")
    }

    fn deserialize_bool<V: Visitor<'de>>(self, visitor: V) -> Result<V::Value> {
        match self.ident()? {
            "true" => visitor.visit_bool(true),
            "false" => visitor.visit_bool(false),
            _ => give_up("expected a bool"),
        }
    }

    fn deserialize_i8<V: Visitor<'de>>(self, visitor: V) -> Result<V::Value> {
        visitor.visit_i8(self.integer()?)
    }
    fn deserialize_i16<V: Visitor<'de>>(self, visitor: V) -> Result<V::Value> {
        visitor.visit_i16(self.integer()?)
    }
    fn deserialize_i32<V: Visitor<'de>>(self, visitor: V) -> Result<V::Value> {
        visitor.visit_i32(self.integer()?)
    }
    fn deserialize_i64<V: Visitor<'de>>(self, visitor: V) -> Result<V::Value> {
        visitor.visit_i64(self.integer()?)
    }
    fn deserialize_u8<V: Visitor<'de>>(self, visitor: V) -> Result<V::Value> {
        visitor.visit_u8(self.integer()?)
    }
    fn deserialize_u16<V: Visitor<'de>>(self, visitor: V) -> Result<V::Value> {
        visitor.visit_u16(self.integer()?)
    }
    fn deserialize_u32<V: Visitor<'de>>(self, visitor: V) -> Result<V::Value> {
        visitor.visit_u32(self.integer()?)
    }
    fn deserialize_u64<V: Visitor<'de>>(self, visitor: V) -> Result<V::Value> {
        visitor.visit_u64(self.integer()?)
    }
    fn deserialize_f32<V: Visitor<'de>>(self, visitor: V) -> Result<V::Value> {
        visitor.visit_f32(self.float()?)
    }
    fn deserialize_f64<V: Visitor<'de>>(self, visitor: V) -> Result<V::Value> {
        visitor.visit_f64(self.float()?)
    }
    fn deserialize_char<V: Visitor<'de>>(self, _visitor: V) -> Result<V::Value> {
        give_up("char")
    }
    fn deserialize_str<V: Visitor<'de>>(self, visitor: V) -> Result<V::Value> {
        match self.string()? {
            std::borrow::Cow::Borrowed(s) => visitor.visit_borrowed_str(s),
            std::borrow::Cow::Owned(s) => visitor.visit_string(s),
        }
    }
    fn deserialize_string<V: Visitor<'de>>(self, visitor: V) -> Result<V::Value> {
        self.deserialize_str(visitor)
    }
    fn deserialize_bytes<V: Visitor<'de>>(self, _visitor: V) -> Result<V::Value> {
        give_up("bytes")
    }
    fn deserialize_byte_buf<V: Visitor<'de>>(self, _visitor: V) -> Result<V::Value> {
        give_up("bytes")
    }

    fn deserialize_option<V: Visitor<'de>>(self, visitor: V) -> Result<V::Value> {
        match self.ident()? {
            "None" => visitor.visit_none(),
            "Some" => {
                self.expect(b'(')?;
                let value = visitor.visit_some(&mut *self)?;
                self.eat(b',')?;
                self.expect(b')')?;
                Ok(value)
            }
            _ => give_up("expected an option"),
        }
    }

    fn deserialize_unit<V: Visitor<'de>>(self, visitor: V) -> Result<V::Value> {
        self.expect(b'(')?;
        self.expect(b')')?;
        visitor.visit_unit()
    }
    fn deserialize_unit_struct<V: Visitor<'de>>(self, _name: &'static str, visitor: V) -> Result<V::Value> {
        self.deserialize_unit(visitor)
    }
    fn deserialize_newtype_struct<V: Visitor<'de>>(
        self,
        _name: &'static str,
        _visitor: V,
    ) -> Result<V::Value> {
        give_up("newtype struct")
    }

    fn deserialize_seq<V: Visitor<'de>>(self, visitor: V) -> Result<V::Value> {
        self.expect(b'[')?;
        let mut elements = Elements::new(self, b']')?;
        let value = visitor.visit_seq(&mut elements)?;
        elements.finish()?;
        Ok(value)
    }
    fn deserialize_tuple<V: Visitor<'de>>(self, _len: usize, visitor: V) -> Result<V::Value> {
        self.expect(b'(')?;
        let mut elements = Elements::new(self, b')')?;
        let value = visitor.visit_seq(&mut elements)?;
        elements.finish()?;
        Ok(value)
    }
    fn deserialize_tuple_struct<V: Visitor<'de>>(
        self,
        _name: &'static str,
        len: usize,
        visitor: V,
    ) -> Result<V::Value> {
        self.deserialize_tuple(len, visitor)
    }
    fn deserialize_map<V: Visitor<'de>>(self, _visitor: V) -> Result<V::Value> {
        give_up("map")
    }
    fn deserialize_struct<V: Visitor<'de>>(
        self,
        _name: &'static str,
        _fields: &'static [&'static str],
        visitor: V,
    ) -> Result<V::Value> {
        self.expect(b'(')?;
        let mut elements = Elements::new(self, b')')?;
        let value = visitor.visit_map(&mut elements)?;
        elements.finish()?;
        Ok(value)
    }
    fn deserialize_enum<V: Visitor<'de>>(
        self,
        _name: &'static str,
        _variants: &'static [&'static str],
        visitor: V,
    ) -> Result<V::Value> {
        visitor.visit_enum(self)
    }
    fn deserialize_identifier<V: Visitor<'de>>(self, visitor: V) -> Result<V::Value> {
        visitor.visit_borrowed_str(self.ident()?)
    }
}

#[cfg(test)]
mod writer_tests {
    use super::*;
    use serde::Serialize;

    #[derive(Serialize)]
    struct Key {
        time: f64,
        value: (f32, f32),
        interpolation: &'static str,
        tcb: Tcb,
        flag: Option<u8>,
    }

    #[derive(Serialize)]
    struct Tcb {
        tension: f32,
        continuity: f32,
        bias: f32,
    }

    #[derive(Serialize)]
    enum Kind {
        Point,
        Spot { cutoff_deg: f32 },
        Wrapped(u8),
    }

    #[derive(Serialize)]
    struct Doc {
        name: String,
        empty: Vec<u8>,
        keys: Vec<Key>,
        kinds: Vec<Kind>,
        nothing: Option<u8>,
    }

    #[test]
    fn layout() {
        let doc = Doc {
            name: "a \"b\"\n\\ é\u{1}".into(),
            empty: vec![],
            keys: vec![
                Key {
                    time: 0.1,
                    value: (1.0, -0.0),
                    interpolation: "Tcb",
                    tcb: Tcb { tension: 0.0, continuity: 0.0, bias: 0.0 },
                    flag: Some(1),
                },
                Key {
                    time: 1e-7,
                    value: (3.0e38, 1e-45),
                    interpolation: "Step",
                    tcb: Tcb { tension: 0.5, continuity: 0.0, bias: 0.0 },
                    flag: None,
                },
            ],
            kinds: vec![Kind::Point, Kind::Spot { cutoff_deg: 30.0 }, Kind::Wrapped(3)],
            nothing: None,
        };
        // `interpolation` here is a string, so it is written quoted and never equals the
        // unquoted default; the `tcb` default is recognized and left out.
        let expected = r#"(
    name: "a \"b\"\n\\ é\u{1}",
    empty: [],
    keys: [
        (time: 0.1, value: (1.0, -0.0), interpolation: "Tcb", flag: Some(1)),
        (time: 1e-7, value: (3e+38, 1e-45), interpolation: "Step", tcb: (tension: 0.5, continuity: 0.0, bias: 0.0), flag: None),
    ],
    kinds: [
        Point,
        Spot(cutoff_deg: 30.0),
        Wrapped(3),
    ],
    nothing: None,
)"#;
        assert_eq!(to_ron(&doc).unwrap(), expected);
    }

    /// Kinds of value no scene holds today (small integers, characters, newtype structs,
    /// maps, unit) are still written so that `ron` reads them back to the same value.
    #[test]
    fn values_outside_the_scene_types_read_back_with_ron() {
        #[derive(Serialize, serde::Deserialize, Debug, PartialEq)]
        struct Wrapper(u16);

        #[derive(Serialize, serde::Deserialize, Debug, PartialEq)]
        struct Other {
            small: (i8, i16, u8, u16, u64),
            chars: Vec<char>,
            wrapped: Wrapper,
            unit: (),
            flags: (bool, bool),
            map: std::collections::BTreeMap<String, f32>,
            nested: Vec<Vec<u8>>,
        }

        let value = Other {
            small: (-8, -16, 8, 16, u64::MAX),
            chars: vec!['a', '\'', '\\', '\n', '\r', '\t', '\u{1}', 'é'],
            wrapped: Wrapper(7),
            unit: (),
            flags: (true, false),
            map: [("a".to_string(), 1.5), ("b \"c\"".to_string(), -0.0)].into_iter().collect(),
            nested: vec![vec![1, 2], vec![]],
        };
        let text = to_ron(&value).unwrap();
        assert!(text.contains(r"'\u{1}'") && text.contains("wrapped: (7)"), "{text}");
        assert!(text.contains("'a',\n") && text.contains("'é',\n"), "plain characters unescaped: {text}");
        let back: Other = ron::from_str(&text).unwrap_or_else(|e| panic!("{e}:\n{text}"));
        assert_eq!(back, value, "{text}");
    }
}

#[cfg(test)]
mod inline_layout_tests {
    use super::*;

    /// Inside a value written on one line (a key, a tuple), sequences and maps stay on that line;
    /// at the top of a document they take a line per element.
    #[test]
    fn sequences_and_maps_inside_one_line_values_stay_on_it() {
        #[derive(serde::Serialize)]
        struct Doc {
            pair: (u8, Vec<u8>, std::collections::BTreeMap<String, u8>),
            list: Vec<u8>,
        }
        let map: std::collections::BTreeMap<String, u8> = [("a".to_string(), 1)].into();
        let doc = Doc { pair: (1, vec![2, 3], map.clone()), list: vec![4, 5] };
        let text = to_ron(&doc).unwrap();
        assert_eq!(
            text, "(\n    pair: (1, [2, 3], {\"a\": 1}),\n    list: [\n        4,\n        5,\n    ],\n)",
            "{text}"
        );
        let top = to_ron(&map).unwrap();
        assert_eq!(top, "{\n    \"a\": 1,\n}", "{top}");
    }
}

#[cfg(test)]
mod reader_tests {
    use super::*;
    use serde::{Deserialize, Serialize};

    #[derive(Serialize, Deserialize, Debug, PartialEq)]
    struct Marker;

    #[derive(Serialize, Deserialize, Debug, PartialEq)]
    struct Pair(u8, i8);

    #[derive(Serialize, Deserialize, Debug, PartialEq)]
    enum Shape {
        Point,
        Spot { cutoff: f32 },
        Wrapped(u8),
        Two(u8, u8),
    }

    #[derive(Serialize, Deserialize, Debug, PartialEq)]
    struct Everything {
        ints: (i8, i16, i32, i64, u8, u16, u32, u64),
        floats: (f32, f64, f64),
        flags: (bool, bool),
        unit: (),
        marker: Marker,
        pair: Pair,
        shapes: Vec<Shape>,
        name: String,
        maybe: Option<Option<u8>>,
        nested: Vec<Vec<u8>>,
    }

    fn everything() -> Everything {
        Everything {
            ints: (-8, -16, -32, i64::MIN, 8, 16, 32, u64::MAX),
            floats: (1.5e-3, -0.0, f64::INFINITY),
            flags: (true, false),
            unit: (),
            marker: Marker,
            pair: Pair(1, -1),
            shapes: vec![Shape::Point, Shape::Spot { cutoff: 30.0 }, Shape::Wrapped(3), Shape::Two(4, 5)],
            name: "tab\tnew\nline \"q\" \\ é".into(),
            maybe: Some(None),
            nested: vec![vec![1, 2], vec![]],
        }
    }

    fn fast<'de, T: Deserialize<'de>>(text: &'de str) -> Result<T> {
        from_str_seed(text, std::marker::PhantomData::<T>)
    }

    /// Every kind of value the reader supports, as the writer writes it, reads back to the
    /// value written, as `ron` reads it.
    #[test]
    fn the_reader_reads_what_the_writer_writes_as_ron_does() {
        let value = everything();
        let text = to_ron(&value).unwrap();
        let read: Everything = fast(&text).unwrap_or_else(|e| panic!("{e}:\n{text}"));
        assert_eq!(read, value, "{text}");
        assert_eq!(ron::from_str::<Everything>(&text).expect("ron"), value, "{text}");
    }

    /// Hand-written text: tabs, CRLF line ends, comments of both kinds, trailing commas and a
    /// `\t` escape are read as `ron` reads them.
    #[test]
    fn hand_written_layout_and_comments_read_as_ron_reads_them() {
        let text = "(\r\n\tints: (-8, -16, -32, -9223372036854775808, 8, 16, 32, 18446744073709551615),\r\n\
                    \tfloats: (1.5e-3, -0.0, inf), // a comment\n\
                    /* a block\n comment */ flags: (true, false), unit: (), marker: (),\n\
                    pair: (1, -1), shapes: [Point, Spot(cutoff: 30.0), Wrapped(3), Two(4, 5),],\n\
                    name: \"tab\\tnew\\nline \\\"q\\\" \\\\ é\", maybe: Some(None), nested: [[1, 2], []],\n)\n";
        let read: Everything = fast(text).unwrap_or_else(|e| panic!("{e}:\n{text}"));
        assert_eq!(read, everything());
        assert_eq!(ron::from_str::<Everything>(text).expect("ron"), everything());
    }

    /// Where the text leaves the subset the reader gives up (and `ron` decides): a character,
    /// a map, a unit variant with parentheses, text after the document, a raw control
    /// character or a `\u{…}` escape in a string.
    #[test]
    fn the_reader_gives_up_outside_its_subset() {
        assert!(fast::<char>("'a'").is_err());
        assert!(fast::<std::collections::BTreeMap<String, u8>>("{\"a\": 1}").is_err());
        assert!(fast::<Shape>("Point()").is_err());
        assert!(fast::<u8>("1 2").is_err());
        assert!(fast::<String>("\"a\u{1}b\"").is_err());
        assert!(fast::<String>("\"a\\u{1}b\"").is_err());
        assert_eq!(fast::<Shape>("Point").expect("unit variant"), Shape::Point);
    }

    /// 128-bit integers (no scene holds one) are written as their decimal numbers (`ron`
    /// reads those only with its `integer128` feature, which keyrig leaves off).
    #[test]
    fn wide_integers_are_written_for_ron() {
        let value = (i128::MIN, u128::MAX, -1i128);
        let text = to_ron(&value).unwrap();
        assert_eq!(text, format!("({}, {}, -1)", i128::MIN, u128::MAX));
    }
}
