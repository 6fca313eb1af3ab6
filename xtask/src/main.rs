//! keyrig's repository tasks (`cargo xtask TASK`, the Rust `xtask` convention; the alias is in
//! `.cargo/config.toml`):
//!
//! - `cargo xtask test [ARGS…]`: sets the machine up for the test suite (system packages, the
//!   glTF validator) and runs `cargo test --workspace ARGS…` (docs/testing.md).
//! - `cargo xtask run [ARGS…]`: the README's run command: installs what building and opening
//!   the editor needs (ALSA's headers for the sound output, the window's X libraries, a Vulkan
//!   driver) and runs `cargo run --release -- ARGS…`.
//! - `cargo xtask setup`: only the test suite's set-up.
//! - `cargo xtask fuzz [--seconds N] [TARGET…]`: every fuzz target (or those named) for N
//!   seconds each (60 by default) from its seed corpus, on the stable toolchain
//!   (docs/fuzzing.md).
//! - `cargo xtask screenshots [--dev] [NAME…]`: the guide's pictures of imported models and
//!   shipped scenes (all, or those named), taken from the real editor window under Xvfb with a
//!   release build (`--dev`: the dev profile's) of `keyrig` (docs/guide.md).
//!
//! Only the standard library: the task must build on a fresh machine before anything else is
//! installed.

mod fuzz;
mod screenshots;
mod setup;

use std::path::PathBuf;
use std::process::{Command, ExitCode};

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let result = match args.first().map(String::as_str) {
        Some("test") => setup::run(true).and_then(|()| test(&args[1..])),
        Some("setup") => setup::run(true),
        Some("run") => setup::editor().and_then(|()| run_editor(&args[1..])),
        Some("fuzz") => fuzz::run(&args[1..]),
        Some("screenshots") => setup::run(false).and_then(|()| screenshots::run(&args[1..])),
        Some("help" | "--help" | "-h") | None => {
            println!("{}", USAGE);
            Ok(())
        }
        Some(other) => Err(format!("unknown task `{other}`\n{USAGE}")),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(message) => {
            eprintln!("xtask: {message}");
            ExitCode::FAILURE
        }
    }
}

const USAGE: &str =
    "usage: cargo xtask test [CARGO TEST ARGS…] | run [KEYRIG ARGS…] | setup | fuzz [--seconds N] [TARGET…] | screenshots [--dev] [NAME…]";

/// The repository's root (the folder above `xtask/`).
pub fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).parent().map(PathBuf::from).unwrap_or_default()
}

/// `cargo test --workspace ARGS…`.
fn test(args: &[String]) -> Result<(), String> {
    let mut command = cargo();
    command.current_dir(root()).arg("test").arg("--workspace").args(args);
    run_status(&mut command, "cargo test --workspace")
}

/// `cargo run --release -- ARGS…`: builds and opens the editor (or runs a subcommand).
fn run_editor(args: &[String]) -> Result<(), String> {
    let mut command = cargo();
    command.current_dir(root()).args(["run", "--release", "--package", "keyrig-editor", "--"]).args(args);
    run_status(&mut command, "cargo run --release")
}

/// The cargo that runs this task.
pub fn cargo() -> Command {
    Command::new(std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into()))
}

/// Runs `command`, failing with `what` and its exit status when it fails.
pub fn run_status(command: &mut Command, what: &str) -> Result<(), String> {
    let status = command.status().map_err(|e| format!("cannot run {what}: {e}"))?;
    if status.success() {
        Ok(())
    } else {
        Err(format!("{what} failed ({status})"))
    }
}
