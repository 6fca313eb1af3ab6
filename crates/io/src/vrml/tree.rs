//! The node tree every reader fills: VRML97, X3D (classic and XML) and Open Inventor files
//! become one arena of [`Node`]s with their fields, `DEF` names, `ROUTE`s and `PROTO`s, so
//! that expansion ([`super::expand`]) and mapping ([`super::map`]) exist once.
//!
//! Field values are kept as the file wrote them, without a schema: a run of numbers, strings,
//! booleans, names or nodes. The mapping reads the fields it knows and converts them then.

use std::path::PathBuf;

/// Index of a node in [`Document::nodes`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct NodeId(pub u32);

/// Index of a file in [`Document::files`] (the file read, then each `Inline` and
/// `EXTERNPROTO` file).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct FileId(pub u32);

/// Where something is: a file of the document and a byte offset in its text.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Place {
    pub file: FileId,
    pub at: usize,
}

/// A field's value as written.
#[derive(Clone, Debug, PartialEq)]
pub enum Value {
    /// Numbers: an SFFloat, SFVec3f, SFRotation, SFColor, SFImage … or a list of them.
    Numbers(Vec<f64>),
    Strings(Vec<String>),
    Bools(Vec<bool>),
    /// Names: Inventor enum values and bit masks, `fields [ SFFloat a ]`.
    Names(Vec<String>),
    /// SFNode or MFNode: none (`NULL`, `[ ]`), one or several nodes.
    Nodes(Vec<NodeId>),
    /// `field IS protoField` inside a PROTO body.
    Is(String),
    /// An empty list `[ ]` (whose type the text does not tell) or Inventor's `~`.
    Empty,
    /// A list mixing numbers, strings and names (Inventor `fields` declarations); kept to be
    /// listed, never mapped.
    Mixed,
}

impl Value {
    /// The numbers of the value (`[ ]` is an empty list of numbers).
    #[must_use]
    pub fn numbers(&self) -> Option<&[f64]> {
        match self {
            Value::Numbers(v) => Some(v),
            Value::Empty => Some(&[]),
            _ => None,
        }
    }

    #[must_use]
    pub fn nodes(&self) -> &[NodeId] {
        match self {
            Value::Nodes(v) => v,
            _ => &[],
        }
    }
}

/// One `name value` of a node.
#[derive(Clone, Debug, PartialEq)]
pub struct Field {
    pub name: String,
    pub value: Value,
    pub place: Place,
}

/// A node: its type, `DEF` name, fields and (Open Inventor) the child nodes written directly in
/// its body.
#[derive(Clone, Debug, PartialEq)]
pub struct Node {
    pub kind: String,
    pub def: Option<String>,
    pub fields: Vec<Field>,
    /// Open Inventor's children, in order (VRML and X3D keep theirs in the `children` field).
    pub children: Vec<NodeId>,
    pub place: Place,
    /// The PROTO (or EXTERNPROTO) this node instantiates, when its type names one.
    pub proto: Option<usize>,
    /// After expansion: the node that stands for this PROTO instance or `Inline` in the scene
    /// graph (a PROTO's first body node; an Inline's children in a group).
    pub expanded: Option<NodeId>,
    /// Nodes of a PROTO body (templates): not part of the scene until copied into an instance.
    pub template: bool,
    /// How many PROTO instances this node is nested in (0 for nodes written in the file).
    pub depth: u32,
}

impl Node {
    #[must_use]
    pub fn field(&self, name: &str) -> Option<&Field> {
        self.fields.iter().rev().find(|f| f.name == name)
    }

    #[must_use]
    pub fn value(&self, name: &str) -> Option<&Value> {
        self.field(name).map(|f| &f.value)
    }
}

/// `ROUTE from.field TO to.field` (or an Inventor field connection).
#[derive(Clone, Debug, PartialEq)]
pub struct Route {
    pub from: NodeId,
    pub from_field: String,
    pub to: NodeId,
    pub to_field: String,
    pub place: Place,
}

/// One interface declaration of a PROTO.
#[derive(Clone, Debug, PartialEq)]
pub struct ProtoField {
    /// `field`, `exposedField`, `eventIn`, `eventOut` (or X3D's `initializeOnly`, …).
    pub access: String,
    pub kind: String,
    pub name: String,
    pub default: Option<Value>,
}

/// A PROTO declaration (or an EXTERNPROTO, whose body is loaded from its file).
#[derive(Clone, Debug, PartialEq)]
pub struct Proto {
    pub name: String,
    pub fields: Vec<ProtoField>,
    /// Top-level body nodes (templates); the first is what an instance is.
    pub body: Vec<NodeId>,
    pub routes: Vec<Route>,
    /// EXTERNPROTO: the URLs to load the definition from.
    pub extern_urls: Option<Vec<String>>,
    pub place: Place,
}

/// Which encoding a file is in.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Encoding {
    /// `#VRML V2.0 utf8` (ISO/IEC 14772-1).
    Vrml97,
    /// `#X3D V3.x utf8` / `#X3D V4.x utf8` (ISO/IEC 19776-2).
    X3dClassic,
    /// X3D's XML encoding (ISO/IEC 19776-1).
    X3dXml,
    /// `#Inventor V2.1 ascii`, `#Inventor V1.0 ascii` or `#VRML V1.0 ascii` (Inventor's
    /// descendant, read with the same rules).
    Inventor,
}

impl Encoding {
    /// A name for messages.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Encoding::Vrml97 => "VRML97",
            Encoding::X3dClassic => "X3D (classic encoding)",
            Encoding::X3dXml => "X3D (XML encoding)",
            Encoding::Inventor => "Open Inventor ASCII",
        }
    }
}

/// A file of the document and its text (kept for error positions).
#[derive(Clone, Debug)]
pub struct SourceFile {
    pub path: PathBuf,
    pub text: std::sync::Arc<str>,
    pub encoding: Encoding,
}

/// Everything read: the nodes of every file, the top-level nodes of the main file, its routes
/// and PROTOs.
#[derive(Clone, Debug, Default)]
pub struct Document {
    pub nodes: Vec<Node>,
    pub roots: Vec<NodeId>,
    pub routes: Vec<Route>,
    pub protos: Vec<Proto>,
    pub files: Vec<SourceFile>,
    /// `META` statements / `<meta>` elements of the main file (name, content).
    pub meta: Vec<(String, String)>,
}

impl Document {
    #[must_use]
    pub fn node(&self, id: NodeId) -> &Node {
        &self.nodes[id.0 as usize]
    }

    /// The node that stands for `id` in the scene graph: through PROTO instances and Inlines.
    #[must_use]
    pub fn resolved(&self, mut id: NodeId) -> NodeId {
        for _ in 0..256 {
            match self.node(id).expanded {
                Some(next) if next != id => id = next,
                _ => break,
            }
        }
        id
    }
}

/// What parsing one file gives: its top-level nodes, its routes (resolved) and its PROTOs by
/// name (indices into [`Document::protos`]).
pub type Parsed = (Vec<NodeId>, Vec<Route>, std::collections::HashMap<String, usize>);

/// The first line of the metadata string that carries keyrig's own scene in a file keyrig
/// wrote (a `WorldInfo` `info` string, an Inventor `Info` node's `string`; see
/// [`super::export`]).
pub const METADATA_TAG: &str = "keyrig-scene-ron";
