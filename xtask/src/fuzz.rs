//! `cargo xtask fuzz [--seconds N] [TARGET…]`: each cargo-fuzz target of `fuzz/` for N seconds
//! (60 by default), on the stable toolchain (`RUSTC_BOOTSTRAP=1`, no sanitizer, optimised),
//! from seeds made of the repository's own files (docs/fuzzing.md). Fails when a target finds a
//! crash, and names the input libFuzzer saved.
//!
//! Seeds are copied into `fuzz/seeds/TARGET/` (git-ignored) from `tests/corpus/` and `assets/`
//! at every run; what the fuzzer learns stays in `fuzz/corpus/TARGET/` (git-ignored) and is
//! reused by the next run on the same machine.

use std::path::{Path, PathBuf};

use crate::{cargo, root, run_status};

/// A fuzz target and the files its seeds are made of: (folder under the repository, file
/// endings).
struct Target {
    name: &'static str,
    seeds: &'static [(&'static str, &'static [&'static str])],
}

const TARGETS: &[Target] = &[
    Target { name: "scene_ron", seeds: &[("assets", &["ron"]), ("crates/io/tests", &["ron"])] },
    Target { name: "gltf", seeds: &[("tests/corpus/gltf", &["glb", "gltf"])] },
    Target { name: "md2", seeds: &[("tests/corpus/md2", &["md2"])] },
    Target { name: "fbx", seeds: &[("tests/corpus/fbx", &["fbx"])] },
    Target { name: "vrml", seeds: &[("tests/corpus/vrml", &["wrl"]), ("tests/corpus/x3d", &["x3dv"])] },
    Target { name: "x3d", seeds: &[("tests/corpus/x3d", &["x3d"])] },
    Target { name: "inventor", seeds: &[("tests/corpus/iv", &["iv"])] },
    Target { name: "sound", seeds: &[("crates/io/tests/fixtures/sound", &["wav", "flac", "ogg", "mp3"])] },
    Target {
        name: "bvh",
        seeds: &[("tests/corpus/bvh", &["bvh"]), ("crates/io/tests/fixtures/bvh", &["bvh"])],
    },
];

/// Largest seed file copied: libFuzzer's default `-max_len` follows the largest seed, and inputs
/// of hundreds of kilobytes run a hundred times slower than the small models that reach the
/// same code.
const MAX_SEED_BYTES: u64 = 128 << 10;

pub fn run(args: &[String]) -> Result<(), String> {
    let mut seconds = 60u64;
    let mut names = Vec::new();
    let mut rest = args.iter();
    while let Some(arg) = rest.next() {
        if arg == "--seconds" {
            let value = rest.next().ok_or("--seconds needs a number")?;
            seconds = value.parse().map_err(|_| format!("--seconds {value}: not a whole number"))?;
        } else {
            names.push(arg.as_str());
        }
    }
    let targets: Vec<&Target> = if names.is_empty() {
        TARGETS.iter().collect()
    } else {
        names
            .iter()
            .map(|n| {
                TARGETS.iter().find(|t| t.name == *n).ok_or_else(|| {
                    let known: Vec<&str> = TARGETS.iter().map(|t| t.name).collect();
                    format!("unknown fuzz target `{n}` (targets: {})", known.join(", "))
                })
            })
            .collect::<Result<_, _>>()?
    };
    ensure_cargo_fuzz()?;
    let root = root();
    for target in targets {
        let seeds = root.join("fuzz/seeds").join(target.name);
        let count = make_seeds(&root, target, &seeds)?;
        let corpus = root.join("fuzz/corpus").join(target.name);
        std::fs::create_dir_all(&corpus).map_err(|e| format!("{}: {e}", corpus.display()))?;
        println!("xtask: fuzzing `{}` for {seconds} s from {count} seed files", target.name);
        let mut command = cargo();
        command
            .current_dir(&root)
            .env("RUSTC_BOOTSTRAP", "1")
            .args(["fuzz", "run", "--sanitizer", "none", "-O", target.name])
            .arg(&corpus)
            .arg(&seeds)
            .arg("--")
            .arg(format!("-max_total_time={seconds}"))
            .arg("-malloc_limit_mb=256")
            .arg("-rss_limit_mb=2048")
            .arg("-print_final_stats=1");
        run_status(
            &mut command,
            &format!("fuzz target `{}` (a crash input is in fuzz/artifacts/{0}/)", target.name),
        )?;
    }
    Ok(())
}

/// Installs cargo-fuzz when `cargo fuzz` is not there.
fn ensure_cargo_fuzz() -> Result<(), String> {
    let present = cargo().args(["fuzz", "--version"]).output().is_ok_and(|o| o.status.success());
    if present {
        return Ok(());
    }
    println!("xtask: installing cargo-fuzz (cargo install cargo-fuzz --locked)");
    run_status(cargo().args(["install", "cargo-fuzz", "--locked"]), "cargo install cargo-fuzz")
}

/// Copies the target's seed files into `into` (emptied first); returns how many.
fn make_seeds(root: &Path, target: &Target, into: &Path) -> Result<usize, String> {
    let _ = std::fs::remove_dir_all(into);
    std::fs::create_dir_all(into).map_err(|e| format!("{}: {e}", into.display()))?;
    let mut files = Vec::new();
    for (folder, endings) in target.seeds {
        collect(&root.join(folder), endings, &mut files);
    }
    files.sort();
    for (i, file) in files.iter().enumerate() {
        let name = file.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
        let to = into.join(format!("{i:03}-{name}"));
        std::fs::copy(file, &to).map_err(|e| format!("{} → {}: {e}", file.display(), to.display()))?;
    }
    if files.is_empty() {
        return Err(format!("fuzz target `{}`: no seed files found", target.name));
    }
    Ok(files.len())
}

fn collect(dir: &Path, endings: &[&str], out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else { return };
    for entry in entries.flatten() {
        let path = entry.path();
        let Ok(meta) = entry.metadata() else { continue };
        if meta.is_dir() {
            collect(&path, endings, out);
        } else if meta.is_file()
            && meta.len() <= MAX_SEED_BYTES
            && path.extension().is_some_and(|e| endings.iter().any(|x| e.eq_ignore_ascii_case(x)))
        {
            out.push(path);
        }
    }
}

/// The seed files of every target, for the test that keeps this list true.
#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_fuzz_target_is_listed_and_has_seeds() {
        let manifest = std::fs::read_to_string(root().join("fuzz/Cargo.toml")).expect("fuzz/Cargo.toml");
        let declared: Vec<&str> = manifest
            .lines()
            .filter_map(|l| l.trim().strip_prefix("name = \""))
            .filter_map(|l| l.strip_suffix('"'))
            .filter(|n| *n != "keyrig-fuzz")
            .collect();
        let listed: Vec<&str> = TARGETS.iter().map(|t| t.name).collect();
        let mut a = declared.clone();
        let mut b = listed.clone();
        a.sort_unstable();
        b.sort_unstable();
        assert_eq!(a, b, "fuzz/Cargo.toml's targets and xtask's list differ");
        for target in TARGETS {
            let dir = tempdir(target.name);
            let n = make_seeds(&root(), target, &dir).expect("seeds");
            assert!(n > 0, "{}: no seeds", target.name);
            let _ = std::fs::remove_dir_all(&dir);
        }
    }

    fn tempdir(name: &str) -> PathBuf {
        std::env::temp_dir().join(format!("keyrig-xtask-seeds-{name}-{}", std::process::id()))
    }
}
