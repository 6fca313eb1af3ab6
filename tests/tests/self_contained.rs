//! The repository stands on its own: no source, shader, script or fuzz target refers to a
//! document or a folder outside it (the design is `docs/design.md`, the test models are
//! `tests/corpus/`), and every `docs/NAME.md` a source file cites exists.

use std::path::{Path, PathBuf};

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// Source files of the repository: Rust, WGSL, Python and C++ under the code folders.
fn sources() -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut stack: Vec<PathBuf> =
        ["crates", "tests/tests", "tests/lib.rs", "xtask", "fuzz/fuzz_targets", "tools"]
            .iter()
            .map(|d| repo().join(d))
            .collect();
    while let Some(path) = stack.pop() {
        if path.is_dir() {
            if path.file_name().is_some_and(|n| n == "node_modules" || n == "target") {
                continue;
            }
            for entry in std::fs::read_dir(&path).expect("a source folder") {
                stack.push(entry.expect("an entry").path());
            }
        } else if path.extension().is_some_and(|e| ["rs", "wgsl", "py", "cc", "mjs"].iter().any(|x| e == *x))
        {
            out.push(path);
        }
    }
    out.sort();
    out
}

#[test]
fn no_source_file_refers_to_a_document_outside_the_repository() {
    let files = sources();
    assert!(files.len() > 100, "found only {} source files under {}", files.len(), repo().display());
    let outside = ["DESIGN.md", "../shared", "shared/corpus", "shared/seeds"];
    let mut found = Vec::new();
    for file in &files {
        let text = std::fs::read_to_string(file).expect("a UTF-8 source file");
        // This test names the strings it looks for.
        if file.ends_with("self_contained.rs") {
            continue;
        }
        for (n, line) in text.lines().enumerate() {
            if let Some(what) = outside.iter().find(|w| line.contains(**w)) {
                found.push(format!("{}:{}: `{what}`", file.display(), n + 1));
            }
        }
    }
    assert!(found.is_empty(), "references outside the repository:\n{}", found.join("\n"));
}

#[test]
fn every_cited_document_exists() {
    let mut missing = Vec::new();
    for file in sources().into_iter().filter(|f| !f.ends_with("self_contained.rs")) {
        let text = std::fs::read_to_string(&file).expect("a UTF-8 source file");
        let mut rest = text.as_str();
        while let Some(at) = rest.find("docs/") {
            let tail = &rest[at + 5..];
            let name: String = tail
                .chars()
                .take_while(|c| c.is_ascii_alphanumeric() || matches!(c, '-' | '_' | '.' | '/'))
                .collect();
            if let Some(doc) = name.split_inclusive(".md").next().filter(|d| d.ends_with(".md")) {
                if !repo().join("docs").join(doc).is_file() {
                    missing.push(format!("{}: docs/{doc}", file.display()));
                }
            }
            rest = tail;
        }
    }
    assert!(missing.is_empty(), "cited documents that do not exist:\n{}", missing.join("\n"));
}
