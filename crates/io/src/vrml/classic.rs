//! The parser of the classic encodings (VRML97, X3D classic, Open Inventor ASCII) into the
//! node tree ([`super::tree`]).
//!
//! Grammar (ISO/IEC 14772-1 Annex A, with X3D's and Inventor's additions): a file is
//! statements — nodes (`DEF name Type { … }`, `USE name`, `Type { … }`), `PROTO`,
//! `EXTERNPROTO`, `ROUTE a.f TO b.g`, and X3D's `PROFILE`, `COMPONENT`, `META`, `UNIT`,
//! `IMPORT`, `EXPORT`. A node body holds `field value` pairs, interface declarations (Script),
//! `ROUTE`s and `PROTO`s, and — in Inventor — child nodes written directly.
//!
//! Values are read without a schema: after a field name comes a list `[ … ]`, a run of
//! numbers, a string, `TRUE`/`FALSE`, `NULL`, a node, `IS name` or (Inventor) an enum name or a
//! `( A | B )` mask. Inventor's `~` (ignored field) and `= node.field` connections are read
//! too; connections become routes.
//!
//! `DEF` binds its name when the node's body is complete, so a node cannot `USE` itself: the
//! node graph of a file is acyclic by construction. Nesting is limited to [`MAX_DEPTH`]
//! levels and the document to [`MAX_NODES`] nodes, so that no file can exhaust the stack or
//! the memory.

use std::collections::HashMap;

use super::lex::{clip, LexError, Lexer, Tok, Token};
use super::tree::{
    Document, Encoding, Field, FileId, Node, NodeId, Parsed, Place, Proto, ProtoField, Route, Value,
};

/// Deepest nesting of nodes and lists a file may have.
pub const MAX_DEPTH: usize = 200;
/// Most nodes a document may hold, after PROTO expansion and Inlines.
pub const MAX_NODES: usize = 4_000_000;

/// A parse error: byte offset and message (the caller adds the file, line and column).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ParseError {
    pub at: usize,
    pub message: String,
    /// A limit was reached (too deep, too many nodes) rather than a syntax error.
    pub limit: bool,
}

impl From<LexError> for ParseError {
    fn from(e: LexError) -> Self {
        ParseError { at: e.at, message: e.message, limit: false }
    }
}

type Result<T> = std::result::Result<T, ParseError>;

fn err<T>(at: usize, message: impl Into<String>) -> Result<T> {
    Err(ParseError { at, message: message.into(), limit: false })
}

const INTERFACE_KEYWORDS: [&str; 8] = [
    "eventIn",
    "eventOut",
    "field",
    "exposedField",
    "inputOnly",
    "outputOnly",
    "initializeOnly",
    "inputOutput",
];

fn takes_value(access: &str) -> bool {
    matches!(access, "field" | "exposedField" | "initializeOnly" | "inputOutput")
}

/// One naming scope: the file, or a PROTO body.
#[derive(Default)]
struct Scope {
    defs: HashMap<String, NodeId>,
    protos: HashMap<String, usize>,
    routes: Vec<PendingRoute>,
}

struct PendingRoute {
    from: String,
    from_field: String,
    to: String,
    to_field: String,
    at: usize,
}

pub(crate) struct Parser<'a, 'd> {
    lex: Lexer<'a>,
    doc: &'d mut Document,
    file: FileId,
    scopes: Vec<Scope>,
    depth: usize,
    inventor: bool,
    /// PROTOs visible from the file that includes this one (EXTERNPROTO files see none).
    template_depth: usize,
}

impl<'a, 'd> Parser<'a, 'd> {
    /// A parser of `text` (the file `file` of `doc`, its header line already checked).
    pub fn new(text: &'a str, encoding: Encoding, doc: &'d mut Document, file: FileId) -> Self {
        let inventor = encoding == Encoding::Inventor;
        Parser {
            lex: Lexer::new(text, inventor),
            doc,
            file,
            scopes: vec![Scope::default()],
            depth: 0,
            inventor,
            template_depth: 0,
        }
    }

    fn place(&self, at: usize) -> Place {
        Place { file: self.file, at }
    }

    /// Parses the whole file; returns its top-level nodes and routes (resolved) and the
    /// indices of its PROTOs by name.
    pub fn parse_file(mut self) -> Result<Parsed> {
        let mut roots = Vec::new();
        loop {
            let t = self.lex.next()?;
            match t.tok {
                Tok::Eof => break,
                Tok::Ident("PROFILE") => {
                    self.expect_name("a profile name")?;
                }
                Tok::Ident("COMPONENT") => {
                    self.expect_name("a component name")?;
                }
                Tok::Ident("UNIT") => {
                    self.expect_name("a unit category")?;
                    self.expect_name("a unit name")?;
                    self.expect_number("a conversion factor")?;
                }
                Tok::Ident("META") => {
                    let name = self.expect_string("a META name")?;
                    let content = self.expect_string("a META content")?;
                    self.doc.meta.push((name, content));
                }
                Tok::Ident("EXPORT") => {
                    self.expect_name("a DEF name")?;
                    self.expect_keyword("AS")?;
                    self.expect_name("an exported name")?;
                }
                Tok::Ident("IMPORT") => {
                    return err(t.at, "IMPORT statements are not supported");
                }
                _ => {
                    if let Some(node) = self.statement(t)? {
                        roots.push(node);
                    }
                }
            }
        }
        let scope = self.scopes.pop().unwrap_or_default();
        let routes = self.resolve_routes(&scope)?;
        Ok((roots, routes, scope.protos))
    }

    /// A statement that may appear at the top level, in a PROTO body and in an MFNode list:
    /// a node, `ROUTE`, `PROTO`, `EXTERNPROTO`. Returns the node, if it was one.
    fn statement(&mut self, t: Token<'a>) -> Result<Option<NodeId>> {
        match t.tok {
            Tok::Ident("ROUTE") => {
                self.route(t.at)?;
                Ok(None)
            }
            Tok::Ident("PROTO") => {
                self.proto(t.at, false)?;
                Ok(None)
            }
            Tok::Ident("EXTERNPROTO") => {
                self.proto(t.at, true)?;
                Ok(None)
            }
            Tok::Ident(_) => Ok(self.node_from(t)?),
            _ => err(t.at, format!("expected a node, found {}", describe(&t.tok))),
        }
    }

    fn expect_name(&mut self, what: &str) -> Result<&'a str> {
        let t = self.lex.next()?;
        match t.tok {
            Tok::Ident(name) => Ok(name),
            other => err(t.at, format!("expected {what}, found {}", describe(&other))),
        }
    }

    fn expect_keyword(&mut self, keyword: &str) -> Result<()> {
        let t = self.lex.next()?;
        match t.tok {
            Tok::Ident(k) if k == keyword => Ok(()),
            other => err(t.at, format!("expected `{keyword}`, found {}", describe(&other))),
        }
    }

    fn expect_string(&mut self, what: &str) -> Result<String> {
        let t = self.lex.next()?;
        match t.tok {
            Tok::Str(s) => Ok(s),
            other => err(t.at, format!("expected {what} (a string), found {}", describe(&other))),
        }
    }

    fn expect_number(&mut self, what: &str) -> Result<f64> {
        let t = self.lex.next()?;
        match t.tok {
            Tok::Number(v) => Ok(v),
            other => err(t.at, format!("expected {what}, found {}", describe(&other))),
        }
    }

    fn expect_punct(&mut self, p: u8) -> Result<usize> {
        let t = self.lex.next()?;
        match t.tok {
            Tok::Punct(q) if q == p => Ok(t.at),
            other => err(t.at, format!("expected `{}`, found {}", p as char, describe(&other))),
        }
    }

    /// A `DEF`/`USE` name: any run of characters up to white space or a brace (Inventor
    /// writes names such as `+0`).
    fn def_name(&mut self) -> Result<(String, usize)> {
        let t = self.lex.next()?;
        match t.tok {
            Tok::Ident(name) => Ok((name.to_owned(), t.at)),
            Tok::Number(_) if self.inventor => {
                let text = self.lex.text();
                let end = text[t.at..]
                    .find(|c: char| c.is_whitespace() || "{}[]".contains(c))
                    .map_or(text.len(), |n| t.at + n);
                Ok((text[t.at..end].to_owned(), t.at))
            }
            other => err(t.at, format!("expected a node name, found {}", describe(&other))),
        }
    }

    fn lookup_def(&self, name: &str) -> Option<NodeId> {
        self.scopes.last().and_then(|s| s.defs.get(name).copied())
    }

    fn lookup_proto(&self, name: &str) -> Option<usize> {
        self.scopes.iter().rev().find_map(|s| s.protos.get(name).copied())
    }

    /// A node starting with token `t` (`DEF`, `USE` or its type name). `USE` gives the
    /// node it names.
    fn node_from(&mut self, t: Token<'a>) -> Result<Option<NodeId>> {
        match t.tok {
            Tok::Ident("USE") => {
                let (name, at) = self.def_name()?;
                match self.lookup_def(&name) {
                    Some(id) => Ok(Some(id)),
                    None => err(
                        at,
                        format!(
                            "USE {}: no node named `{}` is defined before this point (a node cannot USE itself or a later node)",
                            clip(&name),
                            clip(&name)
                        ),
                    ),
                }
            }
            Tok::Ident("DEF") => {
                let (name, _) = self.def_name()?;
                let t = self.lex.next()?;
                let Tok::Ident(kind) = t.tok else {
                    return err(t.at, format!("expected a node type after DEF {}", clip(&name)));
                };
                let id = self.node_body(kind, t.at, Some(name.clone()))?;
                if let Some(scope) = self.scopes.last_mut() {
                    scope.defs.insert(name, id);
                }
                Ok(Some(id))
            }
            Tok::Ident("NULL") => Ok(None),
            Tok::Ident(kind) => Ok(Some(self.node_body(kind, t.at, None)?)),
            other => err(t.at, format!("expected a node, found {}", describe(&other))),
        }
    }

    fn new_node(&mut self, kind: &str, at: usize, def: Option<String>) -> Result<NodeId> {
        if self.doc.nodes.len() >= MAX_NODES {
            return Err(ParseError {
                at,
                message: format!("more than {MAX_NODES} nodes; keyrig reads no larger scene"),
                limit: true,
            });
        }
        let id = NodeId(self.doc.nodes.len() as u32);
        // Coin writes VRML97 nodes in Inventor files with a `VRML` prefix
        // (`VRMLPositionInterpolator`): they are the VRML97 nodes.
        let kind = match kind.strip_prefix("VRML") {
            Some(rest) if self.inventor && rest.starts_with(|c: char| c.is_ascii_uppercase()) => rest,
            _ => kind,
        };
        let proto = self.lookup_proto(kind);
        self.doc.nodes.push(Node {
            kind: kind.to_owned(),
            def,
            fields: Vec::new(),
            children: Vec::new(),
            place: self.place(at),
            proto,
            expanded: None,
            template: self.template_depth > 0,
            depth: 0,
        });
        Ok(id)
    }

    fn enter(&mut self, at: usize) -> Result<()> {
        self.depth += 1;
        if self.depth > MAX_DEPTH {
            return Err(ParseError {
                at,
                message: format!("nodes are nested more than {MAX_DEPTH} levels deep"),
                limit: true,
            });
        }
        Ok(())
    }

    /// The body `{ … }` of a node of type `kind` whose type name is at `at`.
    fn node_body(&mut self, kind: &'a str, at: usize, def: Option<String>) -> Result<NodeId> {
        self.enter(at)?;
        let open = self.lex.next()?;
        if open.tok != Tok::Punct(b'{') {
            return err(
                open.at,
                format!("expected `{{` after the node type `{}`, found {}", clip(kind), describe(&open.tok)),
            );
        }
        let id = self.new_node(kind, at, def)?;
        let mut fields = Vec::new();
        let mut children = Vec::new();
        loop {
            let t = self.lex.next()?;
            match t.tok {
                Tok::Punct(b'}') => break,
                Tok::Eof => {
                    return err(t.at, format!("the file ends inside the `{}` node begun here", clip(kind)))
                        .map_err(|e| ParseError { at, ..e })
                }
                Tok::Ident("ROUTE") => self.route(t.at)?,
                Tok::Ident("PROTO") => self.proto(t.at, false)?,
                Tok::Ident("EXTERNPROTO") => self.proto(t.at, true)?,
                Tok::Ident("DEF" | "USE") => {
                    if let Some(child) = self.node_from(t)? {
                        children.push(child);
                    }
                }
                Tok::Ident(name) if INTERFACE_KEYWORDS.contains(&name) && !self.inventor => {
                    // A Script's own interface: `field SFBool x TRUE`, `eventIn SFTime t`.
                    let _kind = self.expect_name("a field type")?;
                    let (fname, fat) = {
                        let t = self.lex.next()?;
                        match t.tok {
                            Tok::Ident(n) => (n, t.at),
                            other => {
                                return err(
                                    t.at,
                                    format!("expected a field name, found {}", describe(&other)),
                                )
                            }
                        }
                    };
                    let value = if takes_value(name) {
                        self.value(fname, fat)?
                    } else if self.lex.peek()?.tok == Tok::Ident("IS") {
                        self.lex.next()?;
                        Value::Is(self.expect_name("a PROTO field name")?.to_owned())
                    } else {
                        Value::Empty
                    };
                    fields.push(Field { name: fname.to_owned(), value, place: self.place(fat) });
                }
                Tok::Ident(name) => {
                    if self.lex.peek()?.tok == Tok::Punct(b'{') {
                        // A child written in the body (Inventor), or a node where a field was
                        // expected (VRML); either way a child.
                        let child = self.node_body(name, t.at, None)?;
                        children.push(child);
                    } else {
                        let value = self.value(name, t.at)?;
                        if self.inventor {
                            self.inventor_suffix(id, name)?;
                        }
                        fields.push(Field { name: name.to_owned(), value, place: self.place(t.at) });
                    }
                }
                other => {
                    return err(
                        t.at,
                        format!(
                            "expected a field name or `}}` in the `{}` node, found {}",
                            clip(kind),
                            describe(&other)
                        ),
                    )
                }
            }
        }
        let node = &mut self.doc.nodes[id.0 as usize];
        node.fields = fields;
        node.children = children;
        self.depth -= 1;
        Ok(id)
    }

    /// Inventor: `~` after a value (the field is ignored) and `= node.field` connections.
    fn inventor_suffix(&mut self, id: NodeId, field: &str) -> Result<()> {
        loop {
            let at = match self.lex.peek()?.tok {
                Tok::Punct(b'~') => {
                    self.lex.next()?;
                    continue;
                }
                Tok::Punct(b'=') => self.lex.next()?.at,
                _ => return Ok(()),
            };
            let t = self.lex.next()?;
            let Some(from) = self.node_from(t)? else {
                return err(at, "a field connection needs a node after `=`");
            };
            self.expect_punct(b'.')?;
            let from_field = self.expect_name("the connected field's name")?.to_owned();
            self.doc.routes.push(Route {
                from,
                from_field,
                to: id,
                to_field: field.to_owned(),
                place: self.place(at),
            });
        }
    }

    /// The value of field `name` (at `at`).
    fn value(&mut self, name: &str, at: usize) -> Result<Value> {
        let t = self.lex.next()?;
        match t.tok {
            Tok::Punct(b'[') => self.list(name, t.at),
            Tok::Number(v) => {
                let mut numbers = vec![v];
                while let Tok::Number(v) = self.lex.peek()?.tok {
                    self.lex.next()?;
                    numbers.push(v);
                }
                Ok(Value::Numbers(numbers))
            }
            Tok::Str(s) => {
                let mut strings = vec![s];
                while let Tok::Str(_) = self.lex.peek()?.tok {
                    if let Tok::Str(s) = self.lex.next()?.tok {
                        strings.push(s);
                    }
                }
                Ok(Value::Strings(strings))
            }
            Tok::Ident("TRUE") => Ok(Value::Bools(vec![true])),
            Tok::Ident("FALSE") => Ok(Value::Bools(vec![false])),
            Tok::Ident("NULL") => Ok(Value::Nodes(Vec::new())),
            Tok::Ident("IS") => Ok(Value::Is(self.expect_name("a PROTO field name")?.to_owned())),
            Tok::Ident("DEF" | "USE") => Ok(Value::Nodes(self.node_from(t)?.into_iter().collect())),
            Tok::Ident(word) => {
                if self.lex.peek()?.tok == Tok::Punct(b'{') {
                    Ok(Value::Nodes(vec![self.node_body(word, t.at, None)?]))
                } else {
                    Ok(Value::Names(vec![word.to_owned()]))
                }
            }
            Tok::Punct(b'(') => {
                let mut names = Vec::new();
                loop {
                    let t = self.lex.next()?;
                    match t.tok {
                        Tok::Punct(b')') => break,
                        Tok::Punct(b'|') => {}
                        Tok::Ident(n) => names.push(n.to_owned()),
                        other => {
                            return err(
                                t.at,
                                format!("expected a name or `)` in a bit mask, found {}", describe(&other)),
                            )
                        }
                    }
                }
                Ok(Value::Names(names))
            }
            Tok::Punct(b'~') => Ok(Value::Empty),
            Tok::Eof => err(at, format!("the file ends where field `{}` needs a value", clip(name))),
            other => {
                err(t.at, format!("expected a value for field `{}`, found {}", clip(name), describe(&other)))
            }
        }
    }

    /// A `[ … ]` list (the `[` at `open` is read).
    fn list(&mut self, name: &str, open: usize) -> Result<Value> {
        self.enter(open)?;
        // The first element decides the list's kind; numbers, the common and large case, are
        // read in a tight loop.
        let value = match self.lex.peek()?.tok {
            Tok::Punct(b']') => {
                self.lex.next()?;
                Value::Empty
            }
            Tok::Number(_) => {
                let mut numbers = Vec::new();
                loop {
                    let t = self.lex.next()?;
                    match t.tok {
                        Tok::Number(v) => numbers.push(v),
                        Tok::Punct(b']') => break,
                        Tok::Eof => return self.unclosed(name, open),
                        other => {
                            return err(
                                t.at,
                                format!(
                                    "expected a number or `]` in field `{}`, found {}",
                                    clip(name),
                                    describe(&other)
                                ),
                            )
                        }
                    }
                }
                Value::Numbers(numbers)
            }
            Tok::Str(_) => {
                let mut strings = Vec::new();
                loop {
                    let t = self.lex.next()?;
                    match t.tok {
                        Tok::Str(s) => strings.push(s),
                        Tok::Punct(b']') => break,
                        Tok::Eof => return self.unclosed(name, open),
                        other => {
                            return err(
                                t.at,
                                format!(
                                    "expected a string or `]` in field `{}`, found {}",
                                    clip(name),
                                    describe(&other)
                                ),
                            )
                        }
                    }
                }
                Value::Strings(strings)
            }
            Tok::Ident("TRUE" | "FALSE") => {
                let mut bools = Vec::new();
                loop {
                    let t = self.lex.next()?;
                    match t.tok {
                        Tok::Ident("TRUE") => bools.push(true),
                        Tok::Ident("FALSE") => bools.push(false),
                        Tok::Punct(b']') => break,
                        Tok::Eof => return self.unclosed(name, open),
                        other => {
                            return err(
                                t.at,
                                format!(
                                    "expected TRUE, FALSE or `]` in field `{}`, found {}",
                                    clip(name),
                                    describe(&other)
                                ),
                            )
                        }
                    }
                }
                Value::Bools(bools)
            }
            _ => self.node_or_mixed_list(name, open)?,
        };
        self.depth -= 1;
        Ok(value)
    }

    /// A list of nodes (with ROUTE and PROTO statements between them, as VRML allows), or of
    /// names and other words (Inventor's `fields [ SFFloat a ]`).
    fn node_or_mixed_list(&mut self, name: &str, open: usize) -> Result<Value> {
        let mut nodes = Vec::new();
        let mut words = Vec::new();
        let mut mixed = false;
        loop {
            let t = self.lex.next()?;
            match t.tok {
                Tok::Punct(b']') => break,
                Tok::Eof => return self.unclosed(name, open),
                Tok::Ident("DEF" | "USE" | "NULL") => nodes.extend(self.node_from(t)?),
                Tok::Ident("ROUTE" | "PROTO" | "EXTERNPROTO") => {
                    self.statement(t)?;
                }
                Tok::Ident(word) => {
                    if self.lex.peek()?.tok == Tok::Punct(b'{') {
                        nodes.push(self.node_body(word, t.at, None)?);
                    } else {
                        words.push(word.to_owned());
                    }
                }
                Tok::Number(_) | Tok::Str(_) => mixed = true,
                other => {
                    return err(
                        t.at,
                        format!("unexpected {} in the list of field `{}`", describe(&other), clip(name)),
                    )
                }
            }
        }
        Ok(match (nodes.is_empty(), words.is_empty(), mixed) {
            (_, true, false) => Value::Nodes(nodes),
            (true, false, false) => Value::Names(words),
            _ => Value::Mixed,
        })
    }

    fn unclosed<T>(&self, name: &str, open: usize) -> Result<T> {
        err(
            open,
            format!(
                "the list of field `{}` opened here is not closed before the end of the file",
                clip(name)
            ),
        )
    }

    /// `ROUTE a.f TO b.g` (the keyword is read).
    fn route(&mut self, at: usize) -> Result<()> {
        let from = self.expect_name("a node name")?.to_owned();
        self.expect_punct(b'.')?;
        let from_field = self.expect_name("a field name")?.to_owned();
        self.expect_keyword("TO")?;
        let to = self.expect_name("a node name")?.to_owned();
        self.expect_punct(b'.')?;
        let to_field = self.expect_name("a field name")?.to_owned();
        if let Some(scope) = self.scopes.last_mut() {
            scope.routes.push(PendingRoute { from, from_field, to, to_field, at });
        }
        Ok(())
    }

    fn resolve_routes(&self, scope: &Scope) -> Result<Vec<Route>> {
        scope
            .routes
            .iter()
            .map(|r| {
                let find = |name: &str| {
                    scope.defs.get(name).copied().ok_or_else(|| ParseError {
                        at: r.at,
                        message: format!("ROUTE: no node named `{}`", clip(name)),
                        limit: false,
                    })
                };
                Ok(Route {
                    from: find(&r.from)?,
                    from_field: r.from_field.clone(),
                    to: find(&r.to)?,
                    to_field: r.to_field.clone(),
                    place: self.place(r.at),
                })
            })
            .collect()
    }

    /// `PROTO Name [ interface ] { body }` or `EXTERNPROTO Name [ interface ] urls` (the
    /// keyword is read).
    fn proto(&mut self, at: usize, external: bool) -> Result<()> {
        self.enter(at)?;
        let name = self.expect_name("a PROTO name")?.to_owned();
        self.expect_punct(b'[')?;
        let mut fields = Vec::new();
        loop {
            let t = self.lex.next()?;
            match t.tok {
                Tok::Punct(b']') => break,
                Tok::Ident(access) if INTERFACE_KEYWORDS.contains(&access) => {
                    let kind = self.expect_name("a field type")?.to_owned();
                    let fname = self.expect_name("a field name")?;
                    let fat = self.lex.offset();
                    let default =
                        if takes_value(access) && !external { Some(self.value(fname, fat)?) } else { None };
                    fields.push(ProtoField {
                        access: access.to_owned(),
                        kind,
                        name: fname.to_owned(),
                        default,
                    });
                }
                other => {
                    return err(
                        t.at,
                        format!(
                            "expected an interface declaration (field, eventIn, …) or `]`, found {}",
                            describe(&other)
                        ),
                    )
                }
            }
        }
        let index = self.doc.protos.len();
        if external {
            let t = self.lex.next()?;
            let urls = match t.tok {
                Tok::Str(s) => vec![s],
                Tok::Punct(b'[') => match self.list("url", t.at)? {
                    Value::Strings(s) => s,
                    Value::Empty => Vec::new(),
                    _ => return err(t.at, "an EXTERNPROTO's URL list must hold strings"),
                },
                other => {
                    return err(t.at, format!("expected the EXTERNPROTO's URL, found {}", describe(&other)))
                }
            };
            self.doc.protos.push(Proto {
                name: name.clone(),
                fields,
                body: Vec::new(),
                routes: Vec::new(),
                extern_urls: Some(urls),
                place: self.place(at),
            });
        } else {
            self.expect_punct(b'{')?;
            self.scopes.push(Scope::default());
            self.template_depth += 1;
            let mut body = Vec::new();
            loop {
                let t = self.lex.next()?;
                match t.tok {
                    Tok::Punct(b'}') => break,
                    Tok::Eof => return err(at, format!("the file ends inside PROTO {}", clip(&name))),
                    _ => body.extend(self.statement(t)?),
                }
            }
            self.template_depth -= 1;
            let scope = self.scopes.pop().unwrap_or_default();
            let routes = self.resolve_routes(&scope)?;
            self.doc.protos.push(Proto {
                name: name.clone(),
                fields,
                body,
                routes,
                extern_urls: None,
                place: self.place(at),
            });
        }
        if let Some(scope) = self.scopes.last_mut() {
            scope.protos.insert(name, index);
        }
        self.depth -= 1;
        Ok(())
    }
}

/// A token for messages.
pub(crate) fn describe(tok: &Tok<'_>) -> String {
    match tok {
        Tok::Ident(s) => format!("`{}`", clip(s)),
        Tok::Number(v) => format!("the number {v}"),
        Tok::Str(s) => format!("the string \"{}\"", clip(s)),
        Tok::Punct(p) => format!("`{}`", *p as char),
        Tok::Eof => "the end of the file".into(),
    }
}
