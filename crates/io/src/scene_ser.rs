//! The RON writer of scene files: a small serde serializer with one fixed layout.
//!
//! Layout rules (they define the bytes of every saved scene; changing them changes files):
//! - structs, lists and maps: one field or element per line, indented by four spaces, each
//!   followed by a comma; empty ones are `()`, `[]`, `{}`;
//! - tuples (vectors `(x, y, z)`, quaternions `(x, y, z, w)`) and struct variants
//!   (`Spot(cutoff_deg: 35.0, …)`) on one line;
//! - a struct named `Key` ([`keyrig_core::Key`]) and everything inside it on one line, with
//!   the fields equal to their defaults left out (`interpolation: Tcb`,
//!   `tcb: (tension: 0.0, continuity: 0.0, bias: 0.0)`; `Key`'s deserializer fills them in);
//! - `Option` as `Some(…)` / `None`, enum variants by name, no struct names;
//! - floats in Rust's shortest round-trip form (`{:?}`: `0.1`, `1e-7`, `30.0`), so that
//!   reading a file back gives the same bits and writing it again gives the same bytes;
//! - strings in double quotes with `\\`, `\"`, `\n`, `\r`, `\t` and `\u{…}` escapes for other
//!   control characters; everything else as UTF-8.
//!
//! `ron`'s own pretty printer would print each key over eleven lines (50 MB for 100 000
//! keys) and is several times slower; this writer produces what `ron` parses, which the
//! round-trip tests check.

use std::fmt::{self, Write as _};

use serde::ser::{self, Serialize};

/// The struct printed on one line, defaults omitted.
const KEY_STRUCT: &str = "Key";

/// Fields of [`KEY_STRUCT`] that are left out when equal to their default.
const KEY_DEFAULTS: [(&str, &str); 2] =
    [("interpolation", "Tcb"), ("tcb", "(tension: 0.0, continuity: 0.0, bias: 0.0)")];

/// An error of the writer (only custom errors from `Serialize` impls; the writer itself
/// cannot fail).
#[derive(Debug)]
pub struct WriteError(String);

impl fmt::Display for WriteError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for WriteError {}

impl ser::Error for WriteError {
    fn custom<T: fmt::Display>(msg: T) -> Self {
        WriteError(msg.to_string())
    }
}

type Result<T = ()> = std::result::Result<T, WriteError>;

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
    type Error = WriteError;
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
    type Error = WriteError;
    fn serialize_element<T: ?Sized + Serialize>(&mut self, value: &T) -> Result {
        self.element(value)
    }
    fn end(self) -> Result {
        self.close(']')
    }
}

impl ser::SerializeTuple for Compound<'_> {
    type Ok = ();
    type Error = WriteError;
    fn serialize_element<T: ?Sized + Serialize>(&mut self, value: &T) -> Result {
        self.element(value)
    }
    fn end(self) -> Result {
        self.close(')')
    }
}

impl ser::SerializeTupleStruct for Compound<'_> {
    type Ok = ();
    type Error = WriteError;
    fn serialize_field<T: ?Sized + Serialize>(&mut self, value: &T) -> Result {
        self.element(value)
    }
    fn end(self) -> Result {
        self.close(')')
    }
}

impl ser::SerializeTupleVariant for Compound<'_> {
    type Ok = ();
    type Error = WriteError;
    fn serialize_field<T: ?Sized + Serialize>(&mut self, value: &T) -> Result {
        self.element(value)
    }
    fn end(self) -> Result {
        self.close(')')
    }
}

impl ser::SerializeMap for Compound<'_> {
    type Ok = ();
    type Error = WriteError;
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
    type Error = WriteError;
    fn serialize_field<T: ?Sized + Serialize>(&mut self, key: &'static str, value: &T) -> Result {
        self.field(key, value)
    }
    fn end(self) -> Result {
        self.close(')')
    }
}

impl ser::SerializeStructVariant for Compound<'_> {
    type Ok = ();
    type Error = WriteError;
    fn serialize_field<T: ?Sized + Serialize>(&mut self, key: &'static str, value: &T) -> Result {
        self.field(key, value)
    }
    fn end(self) -> Result {
        self.close(')')
    }
}

#[cfg(test)]
mod tests {
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
}
