//! Where a field of a scene file is: the line and column of the value at a field path
//! (`scene.objects[0].rotation.track[4].time`), taken from `ron`'s parser.
//!
//! Problems of a scene ([`keyrig_core::Scene::problems`]) are found after it is read, by
//! path. To place one in the file, the document is read again by `ron` through a
//! deserializer that follows the path of every value it reads and stops with an error when it
//! reaches the wanted one; `ron` reports that error with its position
//! ([`ron::error::SpannedError`]), which is where the value starts. There is no second RON
//! scanner: whatever `ron` reads, this locates.
//!
//! Path syntax (the same as [`keyrig_core::Problem::path`], with the document's top-level
//! field first): struct fields are joined with `.`, list and tuple elements are `[i]`, and a
//! trailing vector component `.x` `.y` `.z` `.w` is the tuple element 0–3. `Some(x)`, newtype
//! structs and enum variants are transparent: `skeleton: Some((joints: …))` holds
//! `skeleton.joints`, and the fields of `File(path: …, fps: …)` are `mesh.path`, `mesh.fps`.
//! A path the file leaves to its default is placed at its nearest parent in the file.

use std::cell::RefCell;
use std::fmt;
use std::marker::PhantomData;

use serde::de::{
    self, Deserialize, DeserializeSeed, Deserializer, EnumAccess, MapAccess, SeqAccess, VariantAccess,
    Visitor,
};

/// A 1-based line and column (columns count characters, not bytes).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TextPosition {
    pub line: usize,
    pub column: usize,
}

/// Most re-reads of the document one [`locate`] call makes. Each reads the file up to the
/// wanted value, so a large file with many problems would otherwise take seconds; the
/// problems beyond are listed without a position.
pub const MAX_READS: usize = 32;

/// The message of the error that stops a re-read at the wanted value.
const STOP: &str = "keyrig-io: stop at the wanted path";

/// Finds, for each of `paths`, where its value (or its nearest parent in the file) starts in
/// `text`, reading `text` as a document of type `T`. `None` where not even a parent is in the
/// file, where `ron` cannot read the text up to it, or when [`MAX_READS`] re-reads are spent.
#[must_use]
pub fn locate<T: for<'de> Deserialize<'de>>(text: &str, paths: &[String]) -> Vec<Option<TextPosition>> {
    let mut reads = 0;
    paths
        .iter()
        .map(|path| {
            for candidate in candidates(path) {
                if reads == MAX_READS {
                    return None;
                }
                reads += 1;
                if let Some(at) = position_of::<T>(text, &candidate) {
                    return Some(at);
                }
            }
            None
        })
        .collect()
}

/// Candidate paths for `path`, most specific first: the path itself (a trailing vector
/// component as its tuple index), then its parents.
fn candidates(path: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut current = path.to_string();
    if let Some((parent, last)) = current.rsplit_once('.') {
        if let Some(i) = ["x", "y", "z", "w"].iter().position(|c| *c == last) {
            current = format!("{parent}[{i}]");
        }
    }
    loop {
        out.push(current.clone());
        match current.rfind(['.', '[']) {
            Some(i) if i > 0 => current.truncate(i),
            _ => break,
        }
    }
    out
}

/// Reads `text` with `ron` as a `T` and stops at the value at `path`: where it starts, or
/// `None` when the document has no value there.
fn position_of<T: for<'de> Deserialize<'de>>(text: &str, path: &str) -> Option<TextPosition> {
    let walk = Walk { path: RefCell::new(String::new()), target: path };
    let seed = Document { document: PhantomData::<T>, walk: &walk };
    match ron::Options::default().from_str_seed(text, seed) {
        Err(err) if matches!(&err.code, ron::Error::Message(m) if m == STOP) => {
            Some(TextPosition { line: err.span.end.line, column: err.span.end.col })
        }
        _ => None,
    }
}

/// The path of the value being read and the one to stop at.
struct Walk<'t> {
    path: RefCell<String>,
    target: &'t str,
}

impl Walk<'_> {
    fn at_target(&self) -> bool {
        *self.path.borrow() == self.target
    }

    /// Runs `read` with `segment` appended to the path (`.name` or `[i]`).
    fn within<R>(&self, segment: fmt::Arguments<'_>, read: impl FnOnce() -> R) -> R {
        let len = {
            let mut path = self.path.borrow_mut();
            let len = path.len();
            fmt::Write::write_fmt(&mut *path, segment).expect("writing to a String");
            len
        };
        let result = read();
        self.path.borrow_mut().truncate(len);
        result
    }
}

/// Reads the whole document, a `T`.
struct Document<'w, 't, T> {
    document: PhantomData<T>,
    walk: &'w Walk<'t>,
}

impl<'de, T: Deserialize<'de>> DeserializeSeed<'de> for Document<'_, '_, T> {
    type Value = T;
    fn deserialize<D: Deserializer<'de>>(self, deserializer: D) -> Result<T, D::Error> {
        T::deserialize(Tracked { de: deserializer, walk: self.walk })
    }
}

/// A seed of the caller's, read at the current path.
struct Wrapped<'w, 't, S> {
    seed: S,
    walk: &'w Walk<'t>,
}

impl<'de, S: DeserializeSeed<'de>> DeserializeSeed<'de> for Wrapped<'_, '_, S> {
    type Value = S::Value;
    fn deserialize<D: Deserializer<'de>>(self, deserializer: D) -> Result<S::Value, D::Error> {
        self.seed.deserialize(Tracked { de: deserializer, walk: self.walk })
    }
}

/// `ron`'s deserializer, stopping when it is asked for the wanted value.
struct Tracked<'w, 't, D> {
    de: D,
    walk: &'w Walk<'t>,
}

macro_rules! tracked_methods {
    ($($method:ident($($arg:ident: $ty:ty),*);)*) => {
        $(
            fn $method<V: Visitor<'de>>(self, $($arg: $ty,)* visitor: V) -> Result<V::Value, D::Error> {
                if self.walk.at_target() {
                    return Err(de::Error::custom(STOP));
                }
                self.de.$method($($arg,)* Track { visitor, walk: self.walk })
            }
        )*
    };
}

impl<'de, D: Deserializer<'de>> Deserializer<'de> for Tracked<'_, '_, D> {
    type Error = D::Error;

    tracked_methods! {
        deserialize_any();
        deserialize_bool();
        deserialize_i8();
        deserialize_i16();
        deserialize_i32();
        deserialize_i64();
        deserialize_i128();
        deserialize_u8();
        deserialize_u16();
        deserialize_u32();
        deserialize_u64();
        deserialize_u128();
        deserialize_f32();
        deserialize_f64();
        deserialize_char();
        deserialize_str();
        deserialize_string();
        deserialize_bytes();
        deserialize_byte_buf();
        deserialize_option();
        deserialize_unit();
        deserialize_unit_struct(name: &'static str);
        deserialize_newtype_struct(name: &'static str);
        deserialize_seq();
        deserialize_tuple(len: usize);
        deserialize_tuple_struct(name: &'static str, len: usize);
        deserialize_map();
        deserialize_struct(name: &'static str, fields: &'static [&'static str]);
        deserialize_enum(name: &'static str, variants: &'static [&'static str]);
        deserialize_identifier();
        deserialize_ignored_any();
    }
}

/// The caller's visitor; what it is given to read further is tracked.
struct Track<'w, 't, V> {
    visitor: V,
    walk: &'w Walk<'t>,
}

macro_rules! forward_visits {
    ($($method:ident($ty:ty);)*) => {
        $(
            fn $method<E: de::Error>(self, v: $ty) -> Result<V::Value, E> {
                self.visitor.$method(v)
            }
        )*
    };
}

impl<'de, V: Visitor<'de>> Visitor<'de> for Track<'_, '_, V> {
    type Value = V::Value;

    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        self.visitor.expecting(f)
    }

    forward_visits! {
        visit_bool(bool);
        visit_i8(i8);
        visit_i16(i16);
        visit_i32(i32);
        visit_i64(i64);
        visit_i128(i128);
        visit_u8(u8);
        visit_u16(u16);
        visit_u32(u32);
        visit_u64(u64);
        visit_u128(u128);
        visit_f32(f32);
        visit_f64(f64);
        visit_char(char);
        visit_str(&str);
        visit_borrowed_str(&'de str);
        visit_string(String);
        visit_bytes(&[u8]);
        visit_borrowed_bytes(&'de [u8]);
        visit_byte_buf(Vec<u8>);
    }

    fn visit_none<E: de::Error>(self) -> Result<V::Value, E> {
        self.visitor.visit_none()
    }

    fn visit_unit<E: de::Error>(self) -> Result<V::Value, E> {
        self.visitor.visit_unit()
    }

    fn visit_some<D: Deserializer<'de>>(self, deserializer: D) -> Result<V::Value, D::Error> {
        self.visitor.visit_some(Tracked { de: deserializer, walk: self.walk })
    }

    fn visit_newtype_struct<D: Deserializer<'de>>(self, deserializer: D) -> Result<V::Value, D::Error> {
        self.visitor.visit_newtype_struct(Tracked { de: deserializer, walk: self.walk })
    }

    fn visit_seq<A: SeqAccess<'de>>(self, seq: A) -> Result<V::Value, A::Error> {
        self.visitor.visit_seq(Elements { seq, walk: self.walk, index: 0 })
    }

    fn visit_map<A: MapAccess<'de>>(self, map: A) -> Result<V::Value, A::Error> {
        self.visitor.visit_map(Fields { map, walk: self.walk, key: RefCell::new(None) })
    }

    fn visit_enum<A: EnumAccess<'de>>(self, data: A) -> Result<V::Value, A::Error> {
        self.visitor.visit_enum(Variant { access: data, walk: self.walk })
    }
}

/// List and tuple elements: `[i]`.
struct Elements<'w, 't, A> {
    seq: A,
    walk: &'w Walk<'t>,
    index: usize,
}

impl<'de, A: SeqAccess<'de>> SeqAccess<'de> for Elements<'_, '_, A> {
    type Error = A::Error;

    fn next_element_seed<S: DeserializeSeed<'de>>(&mut self, seed: S) -> Result<Option<S::Value>, A::Error> {
        let walk = self.walk;
        let seq = &mut self.seq;
        let element =
            walk.within(format_args!("[{}]", self.index), || seq.next_element_seed(Wrapped { seed, walk }));
        self.index += 1;
        element
    }
}

/// Struct fields (and map entries): `.name`, the name as the key's visitor saw it.
struct Fields<'w, 't, A> {
    map: A,
    walk: &'w Walk<'t>,
    key: RefCell<Option<String>>,
}

impl<'de, A: MapAccess<'de>> MapAccess<'de> for Fields<'_, '_, A> {
    type Error = A::Error;

    fn next_key_seed<K: DeserializeSeed<'de>>(&mut self, seed: K) -> Result<Option<K::Value>, A::Error> {
        *self.key.borrow_mut() = None;
        self.map.next_key_seed(KeySeed { seed, key: &self.key })
    }

    fn next_value_seed<S: DeserializeSeed<'de>>(&mut self, seed: S) -> Result<S::Value, A::Error> {
        let walk = self.walk;
        let map = &mut self.map;
        let name = self.key.borrow_mut().take().unwrap_or_default();
        let dot = if walk.path.borrow().is_empty() { "" } else { "." };
        walk.within(format_args!("{dot}{name}"), || map.next_value_seed(Wrapped { seed, walk }))
    }
}

/// Reads a key and keeps its name.
struct KeySeed<'k, S> {
    seed: S,
    key: &'k RefCell<Option<String>>,
}

impl<'de, S: DeserializeSeed<'de>> DeserializeSeed<'de> for KeySeed<'_, S> {
    type Value = S::Value;
    fn deserialize<D: Deserializer<'de>>(self, deserializer: D) -> Result<S::Value, D::Error> {
        self.seed.deserialize(KeyDeserializer { de: deserializer, key: self.key })
    }
}

struct KeyDeserializer<'k, D> {
    de: D,
    key: &'k RefCell<Option<String>>,
}

macro_rules! key_methods {
    ($($method:ident($($arg:ident: $ty:ty),*);)*) => {
        $(
            fn $method<V: Visitor<'de>>(self, $($arg: $ty,)* visitor: V) -> Result<V::Value, D::Error> {
                self.de.$method($($arg,)* KeyVisitor { visitor, key: self.key })
            }
        )*
    };
}

impl<'de, D: Deserializer<'de>> Deserializer<'de> for KeyDeserializer<'_, D> {
    type Error = D::Error;

    key_methods! {
        deserialize_any();
        deserialize_bool();
        deserialize_i8();
        deserialize_i16();
        deserialize_i32();
        deserialize_i64();
        deserialize_i128();
        deserialize_u8();
        deserialize_u16();
        deserialize_u32();
        deserialize_u64();
        deserialize_u128();
        deserialize_f32();
        deserialize_f64();
        deserialize_char();
        deserialize_str();
        deserialize_string();
        deserialize_bytes();
        deserialize_byte_buf();
        deserialize_option();
        deserialize_unit();
        deserialize_unit_struct(name: &'static str);
        deserialize_newtype_struct(name: &'static str);
        deserialize_seq();
        deserialize_tuple(len: usize);
        deserialize_tuple_struct(name: &'static str, len: usize);
        deserialize_map();
        deserialize_struct(name: &'static str, fields: &'static [&'static str]);
        deserialize_enum(name: &'static str, variants: &'static [&'static str]);
        deserialize_identifier();
        deserialize_ignored_any();
    }
}

/// The key's visitor: a name it is given is kept.
struct KeyVisitor<'k, V> {
    visitor: V,
    key: &'k RefCell<Option<String>>,
}

impl KeyVisitor<'_, ()> {
    fn keep(key: &RefCell<Option<String>>, name: &str) {
        *key.borrow_mut() = Some(name.to_string());
    }
}

impl<'de, V: Visitor<'de>> Visitor<'de> for KeyVisitor<'_, V> {
    type Value = V::Value;

    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        self.visitor.expecting(f)
    }

    forward_visits! {
        visit_bool(bool);
        visit_i8(i8);
        visit_i16(i16);
        visit_i32(i32);
        visit_i64(i64);
        visit_i128(i128);
        visit_u8(u8);
        visit_u16(u16);
        visit_u32(u32);
        visit_u64(u64);
        visit_u128(u128);
        visit_f32(f32);
        visit_f64(f64);
        visit_char(char);
        visit_bytes(&[u8]);
        visit_borrowed_bytes(&'de [u8]);
        visit_byte_buf(Vec<u8>);
    }

    fn visit_str<E: de::Error>(self, v: &str) -> Result<V::Value, E> {
        KeyVisitor::keep(self.key, v);
        self.visitor.visit_str(v)
    }

    fn visit_borrowed_str<E: de::Error>(self, v: &'de str) -> Result<V::Value, E> {
        KeyVisitor::keep(self.key, v);
        self.visitor.visit_borrowed_str(v)
    }

    fn visit_string<E: de::Error>(self, v: String) -> Result<V::Value, E> {
        KeyVisitor::keep(self.key, &v);
        self.visitor.visit_string(v)
    }

    fn visit_none<E: de::Error>(self) -> Result<V::Value, E> {
        self.visitor.visit_none()
    }

    fn visit_unit<E: de::Error>(self) -> Result<V::Value, E> {
        self.visitor.visit_unit()
    }

    fn visit_some<D: Deserializer<'de>>(self, deserializer: D) -> Result<V::Value, D::Error> {
        self.visitor.visit_some(deserializer)
    }

    fn visit_newtype_struct<D: Deserializer<'de>>(self, deserializer: D) -> Result<V::Value, D::Error> {
        self.visitor.visit_newtype_struct(deserializer)
    }

    fn visit_seq<A: SeqAccess<'de>>(self, seq: A) -> Result<V::Value, A::Error> {
        self.visitor.visit_seq(seq)
    }

    fn visit_map<A: MapAccess<'de>>(self, map: A) -> Result<V::Value, A::Error> {
        self.visitor.visit_map(map)
    }

    fn visit_enum<A: EnumAccess<'de>>(self, data: A) -> Result<V::Value, A::Error> {
        self.visitor.visit_enum(data)
    }
}

/// An enum value: its variant's content is at the enum's own path.
struct Variant<'w, 't, A> {
    access: A,
    walk: &'w Walk<'t>,
}

impl<'de, 'w, 't, A: EnumAccess<'de>> EnumAccess<'de> for Variant<'w, 't, A> {
    type Error = A::Error;
    type Variant = Variant<'w, 't, A::Variant>;

    fn variant_seed<S: DeserializeSeed<'de>>(self, seed: S) -> Result<(S::Value, Self::Variant), A::Error> {
        let (value, access) = self.access.variant_seed(seed)?;
        Ok((value, Variant { access, walk: self.walk }))
    }
}

impl<'de, A: VariantAccess<'de>> VariantAccess<'de> for Variant<'_, '_, A> {
    type Error = A::Error;

    fn unit_variant(self) -> Result<(), A::Error> {
        self.access.unit_variant()
    }

    fn newtype_variant_seed<S: DeserializeSeed<'de>>(self, seed: S) -> Result<S::Value, A::Error> {
        self.access.newtype_variant_seed(Wrapped { seed, walk: self.walk })
    }

    fn tuple_variant<V: Visitor<'de>>(self, len: usize, visitor: V) -> Result<V::Value, A::Error> {
        self.access.tuple_variant(len, Track { visitor, walk: self.walk })
    }

    fn struct_variant<V: Visitor<'de>>(
        self,
        fields: &'static [&'static str],
        visitor: V,
    ) -> Result<V::Value, A::Error> {
        self.access.struct_variant(fields, Track { visitor, walk: self.walk })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde::Deserialize;

    #[derive(Deserialize)]
    #[allow(dead_code, reason = "only read to be located")]
    struct Doc {
        version: u32,
        scene: Inner,
    }

    #[derive(Deserialize)]
    #[allow(dead_code, reason = "only read to be located")]
    struct Inner {
        fps: f64,
        list: Vec<Item>,
        skeleton: Option<Skeleton>,
        #[serde(default)]
        kind: Option<Kind>,
    }

    #[derive(Deserialize)]
    #[allow(dead_code, reason = "only read to be located")]
    struct Item {
        time: f64,
        value: (f32, f32, f32),
        #[serde(default)]
        tcb: Option<(f32, f32, f32)>,
    }

    #[derive(Deserialize)]
    #[allow(dead_code, reason = "only read to be located")]
    struct Skeleton {
        joints: Vec<String>,
    }

    #[derive(Deserialize)]
    #[allow(dead_code, reason = "only read to be located")]
    enum Kind {
        Spot { cutoff_deg: f32 },
    }

    fn at(text: &str, path: &str) -> Option<(usize, usize)> {
        locate::<Doc>(text, &[path.to_string()])[0].map(|p| (p.line, p.column))
    }

    #[test]
    fn finds_fields_elements_components_and_variant_fields() {
        let text = "(\n    version: 1,\n    scene: (\n        fps: 30.0,\n        list: [\n            (time: 0.0, value: (1.0, NaN, 3.0)),\n            (time: -1e-5, value: (1.0, 2.0, inf)),\n        ],\n        skeleton: Some((joints: [\"a\"])),\n        kind: Some(Spot(cutoff_deg: 4.0)),\n    ),\n)\n";
        assert_eq!(at(text, "version"), Some((2, 14)));
        assert_eq!(at(text, "scene.fps"), Some((4, 14)));
        assert_eq!(at(text, "scene.list[0].value.y"), Some((6, 38)));
        assert_eq!(at(text, "scene.list[1].value.z"), Some((7, 45)));
        assert_eq!(at(text, "scene.list[1].time"), Some((7, 20)));
        assert_eq!(at(text, "scene.skeleton.joints[0]"), Some((9, 34)));
        assert_eq!(at(text, "scene.kind.cutoff_deg"), Some((10, 37)));
        // Not in the text: the nearest parent.
        assert_eq!(at(text, "scene.list[1].tcb.y"), Some((7, 13)));
        assert_eq!(at(text, "nothing"), None);
    }

    #[test]
    fn reads_what_ron_reads_comments_strings_and_attributes() {
        let text = "#![enable(implicit_some)]\n// a (comment\n/* block /* nested */ ) */ (version: 1, scene: (fps: 1.0, list: [], skeleton: (joints: [r#\"x\"y\"#, \"a ) \\\" b\"]), kind: Spot(cutoff_deg: 2.0)))";
        assert_eq!(at(text, "scene.skeleton.joints[1]"), Some((3, 99)));
        assert_eq!(at(text, "scene.kind.cutoff_deg"), Some((3, 136)));
    }

    #[test]
    fn text_ron_cannot_read_up_to_the_path_locates_nothing_and_reads_are_bounded() {
        assert_eq!(at("(version: 1, scene: (fps: ~~~))", "scene.fps"), Some((1, 27)));
        // The nearest parent that `ron` reads up to.
        assert_eq!(at("(version: 1, scene: (fps: ~~~))", "scene.list"), Some((1, 21)));
        assert_eq!(at("(version: ~~~, scene: (fps: 1.0))", "scene.list"), None);
        assert_eq!(at("", "version"), None);
        let text = "(version: 1, scene: (fps: 1.0, list: []))";
        let many: Vec<String> = (0..MAX_READS + 5).map(|_| "scene.fps".to_string()).collect();
        let found = locate::<Doc>(text, &many);
        assert!(found[..MAX_READS].iter().all(|p| *p == Some(TextPosition { line: 1, column: 27 })));
        assert!(found[MAX_READS..].iter().all(Option::is_none), "{found:?}");
    }
}
