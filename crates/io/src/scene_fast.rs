//! A fast reader for well-formed scene files.
//!
//! `ron`'s parser allocates a string for every float it reads, which makes a 100 000-key scene
//! take several hundred milliseconds to load. This is a serde deserializer for the strict
//! subset of RON that keyrig's writer produces (and that people write by hand): structs
//! `(field: value, …)`, lists `[…]`, tuples, `Some(…)`/`None`, enum variants, numbers
//! (`-1.5e-3`, `inf`, `NaN`), plain strings and comments.
//!
//! It is only a fast path: it reports no positions and gives up on anything outside the
//! subset. [`crate::scene_file`] then parses the same text again with `ron`, which accepts
//! all of RON and produces the located error messages. The subset is strict, never more
//! lenient than `ron` (for example it requires commas between elements and nothing after the
//! document), so it accepts a file only when `ron` reads it to the same value; the tests
//! compare the two on generated scenes.

use std::fmt;

use serde::de::{self, DeserializeSeed, Visitor};

/// Why the fast path gave up (never shown to users; `ron` re-reads the text for that).
#[derive(Debug)]
pub struct GaveUp(String);

impl fmt::Display for GaveUp {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for GaveUp {}

impl de::Error for GaveUp {
    fn custom<T: fmt::Display>(msg: T) -> Self {
        GaveUp(msg.to_string())
    }
}

type Result<T> = std::result::Result<T, GaveUp>;

fn give_up<T>(why: &str) -> Result<T> {
    Err(GaveUp(why.to_string()))
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
    type Error = GaveUp;

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
    type Error = GaveUp;

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
    type Error = GaveUp;

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
    type Error = GaveUp;
    type Variant = Self;

    fn variant_seed<V: DeserializeSeed<'de>>(self, seed: V) -> Result<(V::Value, Self)> {
        let variant = seed.deserialize(Identifier(&mut *self))?;
        Ok((variant, self))
    }
}

impl<'de> de::VariantAccess<'de> for &mut Parser<'de> {
    type Error = GaveUp;

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
    type Error = GaveUp;

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
