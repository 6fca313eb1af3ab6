//! Pretty RON with one key per line.
//!
//! `ron`'s pretty printer puts every struct field on its own line, which turns each key into
//! eleven lines and a 100 000-key scene into ~50 MB. Scene files print keys compactly
//! instead — `(time: 0.5, value: (0.0, 0.0, 0.0, 1.0), interpolation: Tcb, tcb: (…))` on one
//! line — and everything else as `ron`'s pretty printer does.
//!
//! [`CompactKeys`] wraps a serializer and forwards every call to it, wrapping nested values
//! again; when an element of a sequence is a struct named `Key`
//! ([`keyrig_core::Key`]), it is written compactly and handed to the inner serializer as a
//! [`ron::value::RawValue`].

use serde::ser::{
    self, Impossible, Serialize, SerializeMap, SerializeSeq, SerializeStruct, SerializeStructVariant,
    SerializeTuple, SerializeTupleStruct, SerializeTupleVariant, Serializer,
};

/// The struct whose instances are printed on one line.
const COMPACT_STRUCT: &str = "Key";

/// Configuration of the one-line form.
fn compact_config() -> ron::ser::PrettyConfig {
    ron::ser::PrettyConfig::new()
        .separator(" ")
        .struct_names(false)
        .compact_arrays(true)
        .compact_structs(true)
        .compact_maps(true)
        .new_line("\n")
        .indentor("")
}

/// Serializes `value` with `inner`, keys compact.
pub struct CompactKeys<'a, T: ?Sized>(pub &'a T);

impl<T: ?Sized + Serialize> Serialize for CompactKeys<'_, T> {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        self.0.serialize(Wrap(serializer))
    }
}

/// Is `value` a struct named [`COMPACT_STRUCT`]? Serializes only up to its first call.
fn is_compact_struct<T: ?Sized + Serialize>(value: &T) -> bool {
    matches!(value.serialize(Probe), Err(ProbeDone(Some(name))) if name == COMPACT_STRUCT)
}

/// Writes `value` on one line and returns it as a raw RON value.
fn compact<T: ?Sized + Serialize, E: ser::Error>(value: &T) -> Result<Box<ron::value::RawValue>, E> {
    let text = ron::ser::to_string_pretty(value, compact_config()).map_err(E::custom)?;
    ron::value::RawValue::from_boxed_ron(text.into_boxed_str()).map_err(E::custom)
}

/// A value to be serialized through [`Wrap`].
struct Wrapped<'a, T: ?Sized>(&'a T);

impl<T: ?Sized + Serialize> Serialize for Wrapped<'_, T> {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        self.0.serialize(Wrap(serializer))
    }
}

/// An element of a sequence: compact when it is a key, wrapped otherwise.
struct Element<'a, T: ?Sized>(&'a T);

impl<T: ?Sized + Serialize> Serialize for Element<'_, T> {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        if is_compact_struct(self.0) {
            compact::<T, S::Error>(self.0)?.serialize(serializer)
        } else {
            self.0.serialize(Wrap(serializer))
        }
    }
}

/// The forwarding serializer (and, through `Wrap<S::SerializeSeq>` etc., its compounds).
struct Wrap<S>(S);

impl<S: Serializer> Serializer for Wrap<S> {
    type Ok = S::Ok;
    type Error = S::Error;
    type SerializeSeq = Wrap<S::SerializeSeq>;
    type SerializeTuple = Wrap<S::SerializeTuple>;
    type SerializeTupleStruct = Wrap<S::SerializeTupleStruct>;
    type SerializeTupleVariant = Wrap<S::SerializeTupleVariant>;
    type SerializeMap = Wrap<S::SerializeMap>;
    type SerializeStruct = Wrap<S::SerializeStruct>;
    type SerializeStructVariant = Wrap<S::SerializeStructVariant>;

    fn serialize_bool(self, v: bool) -> Result<S::Ok, S::Error> {
        self.0.serialize_bool(v)
    }
    fn serialize_i8(self, v: i8) -> Result<S::Ok, S::Error> {
        self.0.serialize_i8(v)
    }
    fn serialize_i16(self, v: i16) -> Result<S::Ok, S::Error> {
        self.0.serialize_i16(v)
    }
    fn serialize_i32(self, v: i32) -> Result<S::Ok, S::Error> {
        self.0.serialize_i32(v)
    }
    fn serialize_i64(self, v: i64) -> Result<S::Ok, S::Error> {
        self.0.serialize_i64(v)
    }
    fn serialize_i128(self, v: i128) -> Result<S::Ok, S::Error> {
        self.0.serialize_i128(v)
    }
    fn serialize_u8(self, v: u8) -> Result<S::Ok, S::Error> {
        self.0.serialize_u8(v)
    }
    fn serialize_u16(self, v: u16) -> Result<S::Ok, S::Error> {
        self.0.serialize_u16(v)
    }
    fn serialize_u32(self, v: u32) -> Result<S::Ok, S::Error> {
        self.0.serialize_u32(v)
    }
    fn serialize_u64(self, v: u64) -> Result<S::Ok, S::Error> {
        self.0.serialize_u64(v)
    }
    fn serialize_u128(self, v: u128) -> Result<S::Ok, S::Error> {
        self.0.serialize_u128(v)
    }
    fn serialize_f32(self, v: f32) -> Result<S::Ok, S::Error> {
        self.0.serialize_f32(v)
    }
    fn serialize_f64(self, v: f64) -> Result<S::Ok, S::Error> {
        self.0.serialize_f64(v)
    }
    fn serialize_char(self, v: char) -> Result<S::Ok, S::Error> {
        self.0.serialize_char(v)
    }
    fn serialize_str(self, v: &str) -> Result<S::Ok, S::Error> {
        self.0.serialize_str(v)
    }
    fn serialize_bytes(self, v: &[u8]) -> Result<S::Ok, S::Error> {
        self.0.serialize_bytes(v)
    }
    fn serialize_none(self) -> Result<S::Ok, S::Error> {
        self.0.serialize_none()
    }
    fn serialize_some<T: ?Sized + Serialize>(self, value: &T) -> Result<S::Ok, S::Error> {
        self.0.serialize_some(&Wrapped(value))
    }
    fn serialize_unit(self) -> Result<S::Ok, S::Error> {
        self.0.serialize_unit()
    }
    fn serialize_unit_struct(self, name: &'static str) -> Result<S::Ok, S::Error> {
        self.0.serialize_unit_struct(name)
    }
    fn serialize_unit_variant(
        self,
        name: &'static str,
        index: u32,
        variant: &'static str,
    ) -> Result<S::Ok, S::Error> {
        self.0.serialize_unit_variant(name, index, variant)
    }
    fn serialize_newtype_struct<T: ?Sized + Serialize>(
        self,
        name: &'static str,
        value: &T,
    ) -> Result<S::Ok, S::Error> {
        self.0.serialize_newtype_struct(name, &Wrapped(value))
    }
    fn serialize_newtype_variant<T: ?Sized + Serialize>(
        self,
        name: &'static str,
        index: u32,
        variant: &'static str,
        value: &T,
    ) -> Result<S::Ok, S::Error> {
        self.0.serialize_newtype_variant(name, index, variant, &Wrapped(value))
    }
    fn serialize_seq(self, len: Option<usize>) -> Result<Self::SerializeSeq, S::Error> {
        self.0.serialize_seq(len).map(Wrap)
    }
    fn serialize_tuple(self, len: usize) -> Result<Self::SerializeTuple, S::Error> {
        self.0.serialize_tuple(len).map(Wrap)
    }
    fn serialize_tuple_struct(
        self,
        name: &'static str,
        len: usize,
    ) -> Result<Self::SerializeTupleStruct, S::Error> {
        self.0.serialize_tuple_struct(name, len).map(Wrap)
    }
    fn serialize_tuple_variant(
        self,
        name: &'static str,
        index: u32,
        variant: &'static str,
        len: usize,
    ) -> Result<Self::SerializeTupleVariant, S::Error> {
        self.0.serialize_tuple_variant(name, index, variant, len).map(Wrap)
    }
    fn serialize_map(self, len: Option<usize>) -> Result<Self::SerializeMap, S::Error> {
        self.0.serialize_map(len).map(Wrap)
    }
    fn serialize_struct(self, name: &'static str, len: usize) -> Result<Self::SerializeStruct, S::Error> {
        self.0.serialize_struct(name, len).map(Wrap)
    }
    fn serialize_struct_variant(
        self,
        name: &'static str,
        index: u32,
        variant: &'static str,
        len: usize,
    ) -> Result<Self::SerializeStructVariant, S::Error> {
        self.0.serialize_struct_variant(name, index, variant, len).map(Wrap)
    }
    fn is_human_readable(&self) -> bool {
        self.0.is_human_readable()
    }
}

impl<S: SerializeSeq> SerializeSeq for Wrap<S> {
    type Ok = S::Ok;
    type Error = S::Error;
    fn serialize_element<T: ?Sized + Serialize>(&mut self, value: &T) -> Result<(), S::Error> {
        self.0.serialize_element(&Element(value))
    }
    fn end(self) -> Result<S::Ok, S::Error> {
        self.0.end()
    }
}

impl<S: SerializeTuple> SerializeTuple for Wrap<S> {
    type Ok = S::Ok;
    type Error = S::Error;
    fn serialize_element<T: ?Sized + Serialize>(&mut self, value: &T) -> Result<(), S::Error> {
        self.0.serialize_element(&Wrapped(value))
    }
    fn end(self) -> Result<S::Ok, S::Error> {
        self.0.end()
    }
}

impl<S: SerializeTupleStruct> SerializeTupleStruct for Wrap<S> {
    type Ok = S::Ok;
    type Error = S::Error;
    fn serialize_field<T: ?Sized + Serialize>(&mut self, value: &T) -> Result<(), S::Error> {
        self.0.serialize_field(&Wrapped(value))
    }
    fn end(self) -> Result<S::Ok, S::Error> {
        self.0.end()
    }
}

impl<S: SerializeTupleVariant> SerializeTupleVariant for Wrap<S> {
    type Ok = S::Ok;
    type Error = S::Error;
    fn serialize_field<T: ?Sized + Serialize>(&mut self, value: &T) -> Result<(), S::Error> {
        self.0.serialize_field(&Wrapped(value))
    }
    fn end(self) -> Result<S::Ok, S::Error> {
        self.0.end()
    }
}

impl<S: SerializeMap> SerializeMap for Wrap<S> {
    type Ok = S::Ok;
    type Error = S::Error;
    fn serialize_key<T: ?Sized + Serialize>(&mut self, key: &T) -> Result<(), S::Error> {
        self.0.serialize_key(&Wrapped(key))
    }
    fn serialize_value<T: ?Sized + Serialize>(&mut self, value: &T) -> Result<(), S::Error> {
        self.0.serialize_value(&Wrapped(value))
    }
    fn end(self) -> Result<S::Ok, S::Error> {
        self.0.end()
    }
}

impl<S: SerializeStruct> SerializeStruct for Wrap<S> {
    type Ok = S::Ok;
    type Error = S::Error;
    fn serialize_field<T: ?Sized + Serialize>(
        &mut self,
        key: &'static str,
        value: &T,
    ) -> Result<(), S::Error> {
        self.0.serialize_field(key, &Wrapped(value))
    }
    fn skip_field(&mut self, key: &'static str) -> Result<(), S::Error> {
        self.0.skip_field(key)
    }
    fn end(self) -> Result<S::Ok, S::Error> {
        self.0.end()
    }
}

impl<S: SerializeStructVariant> SerializeStructVariant for Wrap<S> {
    type Ok = S::Ok;
    type Error = S::Error;
    fn serialize_field<T: ?Sized + Serialize>(
        &mut self,
        key: &'static str,
        value: &T,
    ) -> Result<(), S::Error> {
        self.0.serialize_field(key, &Wrapped(value))
    }
    fn skip_field(&mut self, key: &'static str) -> Result<(), S::Error> {
        self.0.skip_field(key)
    }
    fn end(self) -> Result<S::Ok, S::Error> {
        self.0.end()
    }
}

/// Stops at the first serializer call, reporting the struct name if it was a struct.
#[derive(Debug)]
struct ProbeDone(Option<&'static str>);

impl std::fmt::Display for ProbeDone {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "probe stopped at {:?}", self.0)
    }
}

impl std::error::Error for ProbeDone {}

impl ser::Error for ProbeDone {
    fn custom<T: std::fmt::Display>(_msg: T) -> Self {
        ProbeDone(None)
    }
}

struct Probe;

type ProbeResult<T = ()> = Result<T, ProbeDone>;

impl Serializer for Probe {
    type Ok = ();
    type Error = ProbeDone;
    type SerializeSeq = Impossible<(), ProbeDone>;
    type SerializeTuple = Impossible<(), ProbeDone>;
    type SerializeTupleStruct = Impossible<(), ProbeDone>;
    type SerializeTupleVariant = Impossible<(), ProbeDone>;
    type SerializeMap = Impossible<(), ProbeDone>;
    type SerializeStruct = Impossible<(), ProbeDone>;
    type SerializeStructVariant = Impossible<(), ProbeDone>;

    fn serialize_struct(self, name: &'static str, _len: usize) -> ProbeResult<Self::SerializeStruct> {
        Err(ProbeDone(Some(name)))
    }
    fn serialize_bool(self, _: bool) -> ProbeResult {
        Err(ProbeDone(None))
    }
    fn serialize_i8(self, _: i8) -> ProbeResult {
        Err(ProbeDone(None))
    }
    fn serialize_i16(self, _: i16) -> ProbeResult {
        Err(ProbeDone(None))
    }
    fn serialize_i32(self, _: i32) -> ProbeResult {
        Err(ProbeDone(None))
    }
    fn serialize_i64(self, _: i64) -> ProbeResult {
        Err(ProbeDone(None))
    }
    fn serialize_u8(self, _: u8) -> ProbeResult {
        Err(ProbeDone(None))
    }
    fn serialize_u16(self, _: u16) -> ProbeResult {
        Err(ProbeDone(None))
    }
    fn serialize_u32(self, _: u32) -> ProbeResult {
        Err(ProbeDone(None))
    }
    fn serialize_u64(self, _: u64) -> ProbeResult {
        Err(ProbeDone(None))
    }
    fn serialize_f32(self, _: f32) -> ProbeResult {
        Err(ProbeDone(None))
    }
    fn serialize_f64(self, _: f64) -> ProbeResult {
        Err(ProbeDone(None))
    }
    fn serialize_char(self, _: char) -> ProbeResult {
        Err(ProbeDone(None))
    }
    fn serialize_str(self, _: &str) -> ProbeResult {
        Err(ProbeDone(None))
    }
    fn serialize_bytes(self, _: &[u8]) -> ProbeResult {
        Err(ProbeDone(None))
    }
    fn serialize_none(self) -> ProbeResult {
        Err(ProbeDone(None))
    }
    fn serialize_some<T: ?Sized + Serialize>(self, _: &T) -> ProbeResult {
        Err(ProbeDone(None))
    }
    fn serialize_unit(self) -> ProbeResult {
        Err(ProbeDone(None))
    }
    fn serialize_unit_struct(self, _: &'static str) -> ProbeResult {
        Err(ProbeDone(None))
    }
    fn serialize_unit_variant(self, _: &'static str, _: u32, _: &'static str) -> ProbeResult {
        Err(ProbeDone(None))
    }
    fn serialize_newtype_struct<T: ?Sized + Serialize>(self, _: &'static str, _: &T) -> ProbeResult {
        Err(ProbeDone(None))
    }
    fn serialize_newtype_variant<T: ?Sized + Serialize>(
        self,
        _: &'static str,
        _: u32,
        _: &'static str,
        _: &T,
    ) -> ProbeResult {
        Err(ProbeDone(None))
    }
    fn serialize_seq(self, _: Option<usize>) -> ProbeResult<Self::SerializeSeq> {
        Err(ProbeDone(None))
    }
    fn serialize_tuple(self, _: usize) -> ProbeResult<Self::SerializeTuple> {
        Err(ProbeDone(None))
    }
    fn serialize_tuple_struct(self, _: &'static str, _: usize) -> ProbeResult<Self::SerializeTupleStruct> {
        Err(ProbeDone(None))
    }
    fn serialize_tuple_variant(
        self,
        _: &'static str,
        _: u32,
        _: &'static str,
        _: usize,
    ) -> ProbeResult<Self::SerializeTupleVariant> {
        Err(ProbeDone(None))
    }
    fn serialize_map(self, _: Option<usize>) -> ProbeResult<Self::SerializeMap> {
        Err(ProbeDone(None))
    }
    fn serialize_struct_variant(
        self,
        _: &'static str,
        _: u32,
        _: &'static str,
        _: usize,
    ) -> ProbeResult<Self::SerializeStructVariant> {
        Err(ProbeDone(None))
    }
}
