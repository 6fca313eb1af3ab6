//! Every example in README.md and docs/*.md runs: the blocks are read from the Markdown
//! itself, so the documents and these tests cannot drift apart.
//!
//! A fenced block's info string says what it is and how it is checked:
//!
//! | info | checked by |
//! |---|---|
//! | `sh` | each line is a `keyrig` command, run (the real binary, in a scratch folder with `assets/` and `tests/corpus`) and must exit 0 |
//! | `console` | `$ keyrig …` lines are run; the lines under each are its output (stdout, or stderr for `keyrig: error: …`, which must exit non-zero); JSON is compared as JSON |
//! | `synopsis` | every `--flag` named must be one `keyrig help SUBCOMMAND` lists |
//! | `ron` | a whole scene file loads and evaluates without problems; a `field: value` fragment parses as that field of the scene format and validates |
//! | `rust` | a doctest of keyrig-tests (`tests/lib.rs` includes the file), compiled and run |
//! | `text` | not code: diagrams, formulas, messages (must not hold commands) |
//! | `… by-hand`, `rust no_run` | not run here; listed in [`BY_HAND`] with the reason |
//!
//! A failure names the file and line of the block (or of the command inside it).

use std::collections::{BTreeSet, HashMap};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use keyrig_core::{Animated, AnimatedTrack, MeshSource};
use keyrig_io::scene_file;

/// Blocks not run by these tests, matched by file and the start of their first line, and why.
const BY_HAND: &[(&str, &str, &str)] = &[
    (
        "docs/scene-format.md",
        "actions: [",
        "a fragment of a scene's fields with elided keys; crates/io/tests/scene_file.rs saves and reads a scene with actions",
    ),
    (
        "docs/scene-format.md",
        "clip_tracks: [",
        "a fragment of an object's fields; tests/tests/clips_file.rs saves and reads assets/clips.ron, which has clip tracks and a layer",
    ),
    (
        "README.md",
        "cargo xtask run",
        "installs the build's system packages, builds and opens the editor's window",
    ),
    (
        "README.md",
        "cargo xtask test",
        "sets the machine up and runs the whole test suite, of which this is a part",
    ),
    ("docs/guide.md", "cargo xtask run", "opens the editor's window (one line per way to open it)"),
    (
        "docs/guide.md",
        "keyrig edit assets/",
        "opens the editor's window; ui_guide.rs performs the walkthrough",
    ),
    (
        "docs/guide.md",
        "KEYRIG_WRITE_SCREENSHOTS=1 cargo test",
        "the ui_guide test itself, writing screenshots",
    ),
    ("docs/benchmarks.md", "cargo ", "release builds and benchmarks of minutes each"),
    ("docs/fuzzing.md", "cargo xtask fuzz", "installs a tool and fuzzes for half an hour"),
    ("docs/interpolation.md", "python3 -m venv", "installs Python packages to regenerate reference fixtures"),
    ("docs/scene-format.md", "(", "an outline of the file: `( … )` stands for the scene described below it"),
    (
        "docs/rendering.md",
        "use egui_wgpu::wgpu;",
        "needs eframe's window with the wgpu backend: compiled as a doctest, not run",
    ),
    (
        "docs/testing.md",
        "cargo install cargo-mutants",
        "installs a tool and mutation-tests for most of an hour",
    ),
    ("docs/testing.md", "# the full eighth", "mutation-tests keyrig-io for hours"),
    ("docs/testing.md", "export CARGO_TARGET_DIR", "mutation-tests keyrig-skin for minutes"),
    (
        "docs/skinning-vs-ozz.md",
        "# keyrig: build the example",
        "builds ozz-animation from its source outside the repository and times both",
    ),
];

struct Block {
    /// Relative to the repository root.
    file: String,
    /// 1-based line of the opening fence.
    line: usize,
    info: Vec<String>,
    lines: Vec<String>,
}

impl Block {
    fn at(&self, index: usize) -> String {
        format!("{}:{}", self.file, self.line + 1 + index)
    }

    fn lang(&self) -> &str {
        self.info.first().map_or("", String::as_str)
    }

    fn by_hand(&self) -> bool {
        self.info.iter().any(|w| w == "by-hand" || w == "no_run" || w == "ignore")
    }

    fn first_line(&self) -> &str {
        self.lines.iter().map(|l| l.trim()).find(|l| !l.is_empty()).unwrap_or("")
    }
}

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..").canonicalize().expect("repository root")
}

/// README.md and every docs/*.md, in a fixed order.
fn markdown_files() -> Vec<String> {
    let mut docs: Vec<String> = std::fs::read_dir(repo().join("docs"))
        .expect("read docs/")
        .map(|e| e.expect("docs/ entry").file_name().to_string_lossy().into_owned())
        .filter(|name| name.ends_with(".md"))
        .map(|name| format!("docs/{name}"))
        .collect();
    docs.sort();
    std::iter::once("README.md".to_string()).chain(docs).collect()
}

fn blocks() -> Vec<Block> {
    let mut out = Vec::new();
    for file in markdown_files() {
        let text = std::fs::read_to_string(repo().join(&file)).unwrap_or_else(|e| panic!("read {file}: {e}"));
        let mut open: Option<Block> = None;
        for (i, line) in text.lines().enumerate() {
            let fence = line.trim_start().starts_with("```");
            match (&mut open, fence) {
                (None, true) => {
                    let info = line
                        .trim_start()
                        .trim_start_matches('`')
                        .split_whitespace()
                        .map(String::from)
                        .collect();
                    open = Some(Block { file: file.clone(), line: i + 1, info, lines: Vec::new() });
                }
                (Some(_), true) => out.push(open.take().expect("open block")),
                (Some(block), false) => block.lines.push(line.to_string()),
                (None, false) => {}
            }
        }
        assert!(open.is_none(), "{file}: a code block is not closed");
    }
    out
}

/// A scratch folder laid out like the repository for commands: `assets/` copied, `tests/corpus`
/// pointing at the repository's test models.
struct Scratch {
    _dir: tempfile::TempDir,
    cwd: PathBuf,
}

fn scratch() -> Scratch {
    let dir = tempfile::tempdir().expect("temp dir");
    let cwd = dir.path().join("keyrig");
    copy_dir(&repo().join("assets"), &cwd.join("assets"));
    std::fs::create_dir_all(cwd.join("tests")).expect("create tests folder");
    std::os::unix::fs::symlink(repo().join("tests/corpus"), cwd.join("tests/corpus"))
        .expect("link tests/corpus");
    Scratch { _dir: dir, cwd }
}

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).expect("create folder");
    for entry in std::fs::read_dir(from).expect("read folder") {
        let entry = entry.expect("folder entry");
        let target = to.join(entry.file_name());
        if entry.file_type().expect("file type").is_dir() {
            copy_dir(&entry.path(), &target);
        } else {
            std::fs::copy(entry.path(), &target).expect("copy file");
        }
    }
}

/// The words of a command line without its trailing `# comment`.
fn words(line: &str) -> Vec<&str> {
    let without_comment = match line.find(" #") {
        Some(i) => &line[..i],
        None => line,
    };
    without_comment.split_whitespace().collect()
}

fn keyrig(cwd: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_keyrig")).args(args).current_dir(cwd).output().expect("run keyrig")
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

#[test]
fn every_block_is_run_or_marked() {
    let lib_rs = std::fs::read_to_string(repo().join("tests/lib.rs")).expect("read tests/lib.rs");
    let mut problems = Vec::new();
    let mut used = BTreeSet::new();
    for block in blocks() {
        if block.by_hand() {
            match BY_HAND.iter().position(|(file, start, _)| *file == block.file && block.first_line().starts_with(start)) {
                Some(i) => {
                    used.insert(i);
                }
                None => problems.push(format!(
                    "{}:{}: a block marked not to run (`{}`) that BY_HAND in docs_run.rs does not list with a reason",
                    block.file,
                    block.line,
                    block.info.join(" ")
                )),
            }
        }
        match block.lang() {
            "sh" | "console" | "synopsis" | "ron" => {}
            "rust" => {
                let include = format!("include_str!(\"../{}\")", block.file);
                if !lib_rs.contains(&include) {
                    problems.push(format!(
                        "{}:{}: a Rust block, but tests/lib.rs does not include {} as a doctest",
                        block.file, block.line, block.file
                    ));
                }
            }
            "text" => {
                for (i, line) in block.lines.iter().enumerate() {
                    let line = line.trim_start();
                    if ["$ ", "keyrig ", "cargo "].iter().any(|p| line.starts_with(p)) {
                        problems.push(format!("{}: a command in a `text` block: `{line}`", block.at(i)));
                    }
                }
            }
            other => problems.push(format!(
                "{}:{}: block with info string `{other}` is neither run (sh, console, synopsis, ron, rust) nor \
                 marked (text, by-hand)",
                block.file, block.line
            )),
        }
    }
    for (i, (file, start, _)) in BY_HAND.iter().enumerate() {
        if !used.contains(&i) {
            problems
                .push(format!("BY_HAND lists a block of {file} starting `{start}` that is no longer there"));
        }
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

#[test]
fn shell_examples_run() {
    let scratch = scratch();
    let mut problems = Vec::new();
    let mut ran = 0;
    for block in blocks().iter().filter(|b| b.lang() == "sh" && !b.by_hand()) {
        for (i, line) in block.lines.iter().enumerate() {
            let words = words(line);
            match words.split_first() {
                None => {}
                Some((&"keyrig", args)) => {
                    let out = keyrig(&scratch.cwd, args);
                    ran += 1;
                    if !out.status.success() {
                        problems.push(format!(
                            "{}: `{}` failed ({}): {}",
                            block.at(i),
                            line.trim(),
                            out.status,
                            text(&out.stderr)
                        ));
                    }
                }
                Some(_) => problems.push(format!(
                    "{}: `{}` is not a keyrig command: mark the block by-hand",
                    block.at(i),
                    line.trim()
                )),
            }
        }
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
    assert!(ran >= 6, "only {ran} commands ran");
}

#[test]
fn console_examples_print_what_the_docs_show() {
    let scratch = scratch();
    let mut problems = Vec::new();
    let mut ran = 0;
    for block in blocks().iter().filter(|b| b.lang() == "console") {
        // (line index, command, expected output lines)
        let mut sessions: Vec<(usize, &str, Vec<&str>)> = Vec::new();
        for (i, line) in block.lines.iter().enumerate() {
            if let Some(command) = line.strip_prefix("$ ") {
                sessions.push((i, command, Vec::new()));
            } else if let Some((_, _, expected)) = sessions.last_mut() {
                expected.push(line);
            } else if !line.trim().is_empty() {
                problems.push(format!("{}: output before any `$ ` command", block.at(i)));
            }
        }
        for (i, command, mut expected) in sessions {
            while expected.last().is_some_and(|l| l.trim().is_empty()) {
                expected.pop();
            }
            let words = words(command);
            let Some((&"keyrig", args)) = words.split_first() else {
                problems.push(format!("{}: `{command}` is not a keyrig command", block.at(i)));
                continue;
            };
            let out = keyrig(&scratch.cwd, args);
            ran += 1;
            let fails = expected.first().is_some_and(|l| l.starts_with("keyrig: error:"));
            let got = if fails { text(&out.stderr) } else { text(&out.stdout) };
            if out.status.success() == fails {
                problems.push(format!(
                    "{}: `{command}` exited with {} ({} expected): {}",
                    block.at(i),
                    out.status,
                    if fails { "an error" } else { "success" },
                    text(&out.stderr)
                ));
                continue;
            }
            let expected = expected.join("\n");
            let same = match (
                serde_json::from_str::<serde_json::Value>(&expected),
                serde_json::from_str::<serde_json::Value>(&got),
            ) {
                (Ok(a), Ok(b)) => a == b,
                _ => got.trim_end() == expected.trim_end(),
            };
            if !same {
                problems.push(format!(
                    "{}: `{command}` printed\n{got}\nbut the document shows\n{expected}",
                    block.at(i)
                ));
            }
        }
    }
    assert!(problems.is_empty(), "{}", problems.join("\n\n"));
    assert!(ran >= 5, "only {ran} commands ran");
}

/// The flags of one subcommand, from `keyrig help SUBCOMMAND`.
fn flags_of(subcommand: &str, cache: &mut HashMap<String, String>) -> String {
    cache
        .entry(subcommand.to_string())
        .or_insert_with(|| {
            let out = keyrig(&repo(), &["help", subcommand]);
            assert!(out.status.success(), "keyrig help {subcommand}: {}", text(&out.stderr));
            text(&out.stdout)
        })
        .clone()
}

/// Every `keyrig SUBCOMMAND … --flag` line of synopses and of the blocks not run names flags
/// that exist, and the repository files it names exist.
#[test]
fn synopses_and_unrun_commands_name_real_flags_and_files() {
    let mut cache = HashMap::new();
    let mut problems = Vec::new();
    let mut checked = 0;
    for block in blocks().iter().filter(|b| b.lang() == "synopsis" || b.by_hand()) {
        // Synopsis lines continue on indented lines.
        let mut lines: Vec<(usize, String)> = Vec::new();
        for (i, line) in block.lines.iter().enumerate() {
            match lines.last_mut() {
                Some((_, previous)) if line.starts_with(' ') && block.lang() == "synopsis" => {
                    previous.push(' ');
                    previous.push_str(line.trim());
                }
                _ => lines.push((i, line.clone())),
            }
        }
        for (i, line) in lines {
            let words = words(&line);
            let Some((&"keyrig", rest)) = words.split_first() else {
                if block.lang() == "synopsis" {
                    problems.push(format!("{}: a synopsis line that is not a keyrig command", block.at(i)));
                }
                continue;
            };
            let subcommand = rest.first().copied().unwrap_or("edit");
            let help = flags_of(subcommand, &mut cache);
            checked += 1;
            for word in rest {
                let word = word.trim_matches(|c| "[]()|".contains(c));
                let flag = word.split('=').next().unwrap_or(word);
                if flag.starts_with("--")
                    && !help.contains(&format!("{flag} "))
                    && !help.contains(&format!("{flag}\n"))
                {
                    problems.push(format!("{}: `keyrig {subcommand}` has no flag {flag}", block.at(i)));
                }
                if word.starts_with("assets/") && !repo().join(word).exists() {
                    problems.push(format!("{}: {word} does not exist", block.at(i)));
                }
            }
        }
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
    assert!(checked >= 10, "only {checked} command lines checked");
}

/// A RON fragment `field: value,` parsed as that field of the scene format, then validated.
fn check_fragment(field: &str, value: &str) -> Result<(), String> {
    let ron = ron::Options::default();
    match field {
        "mesh" => ron.from_str::<Option<MeshSource>>(value).map(drop).map_err(|e| e.to_string()),
        "translation" | "scale" => {
            let animated: Animated<glam::Vec3> = ron.from_str(value).map_err(|e| e.to_string())?;
            AnimatedTrack::new(&animated).map(drop).map_err(|e| e.to_string())
        }
        "rotation" => {
            let animated: Animated<glam::Quat> = ron.from_str(value).map_err(|e| e.to_string())?;
            AnimatedTrack::new(&animated).map(drop).map_err(|e| e.to_string())
        }
        // Euler keys: the angles as an animated Vec3.
        "rotation_euler" => {
            let keys: Option<Animated<glam::Vec3>> = ron.from_str(value).map_err(|e| e.to_string())?;
            let keys = keys.ok_or("`None` is the same as leaving the field out")?;
            AnimatedTrack::new(&keys).map(drop).map_err(|e| e.to_string())
        }
        "ik_constraints" => {
            let constraints: Vec<keyrig_core::IkConstraint> =
                ron.from_str(value).map_err(|e| e.to_string())?;
            for c in &constraints {
                AnimatedTrack::new(&c.target).map_err(|e| e.to_string())?;
                AnimatedTrack::new(&c.blend).map_err(|e| e.to_string())?;
            }
            Ok(())
        }
        // Scene cameras: they parse and validate as the cameras of an otherwise empty scene
        // (an aim at an object or joint would need that object: the examples aim at points).
        "cameras" => {
            let cameras: Vec<keyrig_core::SceneCamera> = ron.from_str(value).map_err(|e| e.to_string())?;
            let scene = keyrig_core::Scene { cameras, ..keyrig_core::Scene::default() };
            let problems = scene.problems();
            if problems.is_empty() {
                Ok(())
            } else {
                Err(problems.iter().map(ToString::to_string).collect::<Vec<_>>().join("; "))
            }
        }
        // Object constraints: parsed here; crates/io/tests/scene_constraints.rs loads the same
        // example into a scene with the objects it names and validates it.
        "constraints" => {
            ron.from_str::<Vec<keyrig_core::ObjectConstraint>>(value).map(drop).map_err(|e| e.to_string())
        }
        // Sound clips: parsed and validated as a scene's.
        "sounds" => {
            let sounds: Vec<keyrig_core::SoundClip> = ron.from_str(value).map_err(|e| e.to_string())?;
            let scene = keyrig_core::Scene { sounds, ..keyrig_core::Scene::default() };
            match scene.problems().first() {
                Some(problem) => Err(format!("{}: {}", problem.path, problem.message)),
                None => Ok(()),
            }
        }
        // The pose library and the reference image: parsed and validated as a scene's.
        "poses" | "reference_image" => {
            let mut scene = keyrig_core::Scene::default();
            if field == "poses" {
                scene.poses = ron.from_str(value).map_err(|e| e.to_string())?;
            } else {
                scene.reference_image = ron.from_str(value).map_err(|e| e.to_string())?;
            }
            match scene.problems().first() {
                Some(p) => Err(p.to_string()),
                None => Ok(()),
            }
        }
        // The keys of a rotation track (the format's examples of spins).
        "track" => check_fragment("rotation", &format!("(value: (0.0, 0.0, 0.0, 1.0), track: {value})")),
        "attributes" => {
            // An object's attributes, validated as those of a cube in an otherwise empty scene.
            let attributes: keyrig_core::ObjectAttributes = ron.from_str(value).map_err(|e| e.to_string())?;
            let mut scene = keyrig_core::Scene::default();
            let mut cube = keyrig_core::Object::new("Cube");
            cube.attributes = attributes;
            scene.objects.push(cube);
            match scene.problems().first() {
                Some(p) => Err(p.to_string()),
                None => Ok(()),
            }
        }
        other => Err(format!("no rule for a fragment of field `{other}`: add one to docs_run.rs")),
    }
}

#[test]
fn ron_examples_load() {
    let mut problems = Vec::new();
    let mut scenes = 0;
    for block in blocks().iter().filter(|b| b.lang() == "ron" && !b.by_hand()) {
        let body = block.lines.join("\n");
        let at = format!("{}:{}", block.file, block.line + 1);
        if body.trim_start().starts_with('(') {
            match scene_file::from_str(&body, Path::new(&at)) {
                Ok(scene) => {
                    let eval = keyrig_eval::SceneEvaluator::new(&scene, &HashMap::new());
                    if !eval.problems().is_empty() {
                        problems
                            .push(format!("{at}: the scene evaluates with problems {:?}", eval.problems()));
                    }
                    scenes += 1;
                }
                Err(e) => problems.push(format!("{at}: {e}")),
            }
        } else {
            let Some((field, value)) = body.trim().split_once(':') else {
                problems.push(format!("{at}: neither a scene nor a `field: value` fragment"));
                continue;
            };
            let value = value.trim().trim_end_matches(',');
            if let Err(e) = check_fragment(field.trim(), value) {
                problems.push(format!("{at}: `{}` fragment: {e}", field.trim()));
            }
        }
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
    assert!(scenes >= 1, "no whole scene among the RON examples");
}
