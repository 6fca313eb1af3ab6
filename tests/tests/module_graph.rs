//! No import cycles between the modules of a crate: for every crate of the workspace, the
//! graph of "module A names something in module B" (`crate::b::…`, `super::b::…`, grouped
//! `use crate::{b, c}`) has no cycle. A module naming its own ancestors (a child using its
//! parent's items) is not counted; `#[cfg(test)]` modules at the end of a file are left out.
//!
//! In the same graph, no panel of the editor (a module under `crates/editor/src/panels/`, with
//! its submodules) names another panel: what two panels share lives outside them.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

type Module = Vec<String>;

/// Every `.rs` file under `src` as its module path (`src/cli/mod.rs` → `["cli"]`).
fn modules(src: &Path) -> BTreeMap<Module, PathBuf> {
    let mut out = BTreeMap::new();
    let mut stack = vec![src.to_path_buf()];
    while let Some(dir) = stack.pop() {
        for entry in std::fs::read_dir(&dir).expect("a source folder") {
            let path = entry.expect("an entry").path();
            if path.is_dir() {
                stack.push(path);
            } else if path.extension().is_some_and(|e| e == "rs") {
                let rel = path.strip_prefix(src).expect("under src").with_extension("");
                let mut parts: Module = rel.iter().map(|p| p.to_string_lossy().into_owned()).collect();
                if matches!(parts.last().map(String::as_str), Some("mod" | "lib" | "main")) {
                    parts.pop();
                }
                out.insert(parts, path);
            }
        }
    }
    out
}

/// The source without `//` comments and without the trailing `#[cfg(test)] mod …` block.
fn code_of(text: &str) -> String {
    let end = text.find("#[cfg(test)]\nmod ").unwrap_or(text.len());
    text[..end].lines().map(|l| l.split("//").next().unwrap_or("")).collect::<Vec<_>>().join("\n")
}

fn ident_path(s: &str) -> Vec<String> {
    let mut parts = Vec::new();
    let mut rest = s;
    loop {
        let len = rest.find(|c: char| !(c.is_alphanumeric() || c == '_')).unwrap_or(rest.len());
        if len == 0 {
            break;
        }
        parts.push(rest[..len].to_owned());
        rest = &rest[len..];
        match rest.strip_prefix("::") {
            Some(r) => rest = r,
            None => break,
        }
    }
    parts
}

/// The module `name` directly under `module`.
fn child(module: &Module, name: &str) -> Module {
    module.iter().cloned().chain([name.to_owned()]).collect()
}

/// The longest prefix of `path` that is a module.
fn resolve(mods: &BTreeMap<Module, PathBuf>, path: &[String]) -> Option<Module> {
    (0..=path.len()).rev().map(|n| path[..n].to_vec()).find(|p| mods.contains_key(p))
}

fn edges(mods: &BTreeMap<Module, PathBuf>) -> BTreeMap<Module, BTreeSet<Module>> {
    let mut out: BTreeMap<Module, BTreeSet<Module>> = BTreeMap::new();
    for (module, file) in mods {
        let code = code_of(&std::fs::read_to_string(file).expect("a source file"));
        let mut targets = Vec::new();
        for (at, _) in code.match_indices("crate::") {
            let after = &code[at + "crate::".len()..];
            if at > 0 && code[..at].ends_with(|c: char| c.is_alphanumeric() || c == '_') {
                continue; // `keyrig_crate::`
            }
            let mut path = ident_path(after);
            // `crate::a::{b, c}`: each item.
            let head_len: usize = path.iter().map(|p| p.len() + 2).sum();
            if let Some(group) = after.get(head_len..).and_then(|r| r.strip_prefix('{')) {
                let group = &group[..group.find('}').unwrap_or(group.len())];
                for item in group.split(',') {
                    let item = ident_path(item.trim());
                    if !item.is_empty() && item[0] != "self" {
                        targets.push(path.iter().cloned().chain(item).collect::<Vec<_>>());
                    }
                }
            }
            targets.push(std::mem::take(&mut path));
        }
        for (at, _) in code.match_indices("super::") {
            if code[..at].ends_with("super::") {
                continue;
            }
            let mut rest = &code[at..];
            let mut ups = 0;
            while let Some(r) = rest.strip_prefix("super::") {
                ups += 1;
                rest = r;
            }
            let base = module.len().saturating_sub(ups);
            targets.push(module[..base].iter().cloned().chain(ident_path(rest)).collect());
        }
        // Paths relative to the module: `child::…` (a child module named without `crate::`, as
        // `use inspector::Inspector;` in `panels/mod.rs`) and `self::child::…`.
        for (at, _) in code.match_indices("::") {
            let start = code[..at].rfind(|c: char| !(c.is_alphanumeric() || c == '_')).map_or(0, |i| i + 1);
            if start == at || code[..start].ends_with("::") {
                continue;
            }
            let mut rest = &code[start..];
            if let Some(r) = rest.strip_prefix("self::") {
                rest = r;
            }
            let path = ident_path(rest);
            if path.first().is_some_and(|first| mods.contains_key(&child(module, first))) {
                targets.push(module.iter().cloned().chain(path).collect());
            }
        }
        let set = out.entry(module.clone()).or_default();
        for target in targets {
            if let Some(to) = resolve(mods, &target) {
                // A module naming itself or an ancestor is not an edge.
                if to != *module && !module.starts_with(&to) {
                    set.insert(to);
                }
            }
        }
    }
    out
}

/// A cycle in the graph, if any, as the modules along it.
fn find_cycle(graph: &BTreeMap<Module, BTreeSet<Module>>) -> Option<Vec<Module>> {
    fn visit(
        at: &Module,
        graph: &BTreeMap<Module, BTreeSet<Module>>,
        state: &mut BTreeMap<Module, u8>,
        path: &mut Vec<Module>,
    ) -> Option<Vec<Module>> {
        state.insert(at.clone(), 1);
        path.push(at.clone());
        for next in graph.get(at).into_iter().flatten() {
            match state.get(next).copied().unwrap_or(0) {
                1 => {
                    let from = path.iter().position(|m| m == next).expect("on the path");
                    return Some(path[from..].iter().cloned().chain([next.clone()]).collect());
                }
                0 => {
                    if let Some(cycle) = visit(next, graph, state, path) {
                        return Some(cycle);
                    }
                }
                _ => {}
            }
        }
        path.pop();
        state.insert(at.clone(), 2);
        None
    }
    let mut state = BTreeMap::new();
    for module in graph.keys() {
        if state.get(module).copied().unwrap_or(0) == 0 {
            if let Some(cycle) = visit(module, graph, &mut state, &mut Vec::new()) {
                return Some(cycle);
            }
        }
    }
    None
}

#[test]
fn no_crate_has_a_module_import_cycle() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).parent().expect("the workspace");
    let mut checked = 0;
    let mut cycles = Vec::new();
    for entry in std::fs::read_dir(root.join("crates")).expect("crates/") {
        let src = entry.expect("an entry").path().join("src");
        if !src.is_dir() {
            continue;
        }
        let mods = modules(&src);
        checked += mods.len();
        if let Some(cycle) = find_cycle(&edges(&mods)) {
            let names: Vec<String> =
                cycle.iter().map(|m| if m.is_empty() { "(root)".to_owned() } else { m.join("::") }).collect();
            cycles.push(format!("{}: {}", src.display(), names.join(" → ")));
        }
    }
    assert!(checked > 50, "only {checked} modules found: is the workspace layout as expected?");
    assert!(cycles.is_empty(), "module import cycles:\n{}", cycles.join("\n"));
}

#[test]
fn the_cycle_check_sees_a_cycle() {
    // Two modules that name each other, and one that names only its parent.
    let dir = tempfile::tempdir().expect("a temporary folder");
    let src = dir.path();
    std::fs::create_dir(src.join("cli")).expect("a folder");
    std::fs::write(src.join("lib.rs"), "pub mod a;\npub mod b;\npub mod cli;\n").expect("write");
    std::fs::write(src.join("a.rs"), "use crate::b::thing;\n").expect("write");
    std::fs::write(src.join("b.rs"), "pub fn thing() { crate::a::other() }\n").expect("write");
    std::fs::write(src.join("cli/mod.rs"), "pub mod x;\npub fn helper() {}\n").expect("write");
    std::fs::write(src.join("cli/x.rs"), "fn f() { super::helper() }\n").expect("write");
    let mods = modules(src);
    let cycle = find_cycle(&edges(&mods)).expect("a and b name each other");
    assert!(cycle.contains(&vec!["a".to_owned()]) && cycle.contains(&vec!["b".to_owned()]), "{cycle:?}");
    std::fs::write(src.join("b.rs"), "pub fn thing() {}\n").expect("write");
    std::fs::write(src.join("a.rs"), "use crate::{b, cli::x};\n").expect("write");
    assert_eq!(find_cycle(&edges(&modules(src))), None, "a child using its parent is not a cycle");
    std::fs::write(src.join("cli/x.rs"), "use crate::a;\n").expect("write");
    assert!(find_cycle(&edges(&modules(src))).is_some(), "a grouped use is an edge: a → cli::x → a");
    // A child named by a relative path is an edge: a → cli (crate::cli) → cli::x (`x::…`) → a.
    std::fs::write(src.join("a.rs"), "use crate::cli::helper;\n").expect("write");
    std::fs::write(src.join("cli/mod.rs"), "mod x;\npub use x::run;\npub fn helper() {}\n").expect("write");
    std::fs::write(src.join("cli/x.rs"), "pub fn run() { crate::a::f() }\n").expect("write");
    let cycle = find_cycle(&edges(&modules(src))).expect("a relative path to a child is an edge");
    assert!(cycle.contains(&vec!["cli".to_owned(), "x".to_owned()]), "{cycle:?}");
    std::fs::write(src.join("cli/mod.rs"), "mod x;\npub use self::x::run;\npub fn helper() {}\n")
        .expect("write");
    assert!(find_cycle(&edges(&modules(src))).is_some(), "`self::x` is an edge too");
}

/// The edges from one editor panel to another: `panels::a` (or a module under it) naming
/// `panels::b` (or a module under it), as "a → b".
fn panel_crossings(graph: &BTreeMap<Module, BTreeSet<Module>>) -> Vec<String> {
    let panel = |m: &Module| (m.len() >= 2 && m[0] == "panels").then(|| m[1].clone());
    let mut out = Vec::new();
    for (from, targets) in graph {
        let Some(a) = panel(from) else { continue };
        for to in targets {
            if panel(to).is_some_and(|b| b != a) {
                out.push(format!("{} → {}", from.join("::"), to.join("::")));
            }
        }
    }
    out
}

#[test]
fn no_editor_panel_names_another_panel() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).parent().expect("the workspace");
    let mods = modules(&root.join("crates/editor/src"));
    let panels: BTreeSet<&String> =
        mods.keys().filter(|m| m.len() == 2 && m[0] == "panels").map(|m| &m[1]).collect();
    assert!(
        panels.len() >= 6,
        "only {panels:?} found under crates/editor/src/panels: is the layout as expected?"
    );
    let crossings = panel_crossings(&edges(&mods));
    assert!(crossings.is_empty(), "panels that name another panel:\n{}", crossings.join("\n"));
}

#[test]
fn the_panel_check_sees_a_panel_naming_another() {
    let dir = tempfile::tempdir().expect("a temporary folder");
    let src = dir.path();
    std::fs::create_dir_all(src.join("panels/a")).expect("a folder");
    std::fs::write(src.join("lib.rs"), "pub mod panels;\npub mod widgets;\n").expect("write");
    std::fs::write(src.join("widgets.rs"), "pub fn shared() {}\n").expect("write");
    std::fs::write(src.join("panels/mod.rs"), "pub mod a;\npub mod b;\n").expect("write");
    std::fs::write(src.join("panels/a/mod.rs"), "mod inner;\nuse crate::widgets::shared;\n").expect("write");
    std::fs::write(src.join("panels/a/inner.rs"), "fn f() { super::g() }\n").expect("write");
    std::fs::write(src.join("panels/b.rs"), "pub fn thing() {}\n").expect("write");
    assert_eq!(
        panel_crossings(&edges(&modules(src))),
        Vec::<String>::new(),
        "shared code and a panel's own parts"
    );
    // A submodule of one panel naming another panel, through `super::super`.
    std::fs::write(src.join("panels/a/inner.rs"), "fn f() { super::super::b::thing() }\n").expect("write");
    assert_eq!(panel_crossings(&edges(&modules(src))), vec!["panels::a::inner → panels::b".to_owned()]);
    // A grouped use.
    std::fs::write(src.join("panels/a/inner.rs"), "fn f() {}\n").expect("write");
    std::fs::write(src.join("panels/b.rs"), "use crate::panels::{a, b};\n").expect("write");
    assert_eq!(panel_crossings(&edges(&modules(src))), vec!["panels::b → panels::a".to_owned()]);
}
