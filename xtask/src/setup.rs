//! What the test suite needs of the machine, checked and installed where possible
//! (docs/testing.md, "Setting up").
//!
//! - the real-window tests: an X server without a screen (Xvfb), X input (xdotool) and
//!   screenshots (ImageMagick's `import`), and the X libraries winit opens;
//! - the GPU tests: a wgpu adapter on Vulkan: a GPU's driver when the machine has one,
//!   otherwise lavapipe (Mesa's CPU Vulkan driver), installed here. Mesa's OpenGL driver,
//!   which a fresh machine may already have, does not serve: wgpu's GL backend lacks the
//!   second view format the renderer gives its colour target (`DownlevelFlags::VIEW_FORMATS`;
//!   docs/testing.md, "Which GPU the tests use");
//! - the glTF export tests: Node.js, npm and the Khronos glTF-Validator from its lockfile;
//! - the VRML/X3D/Inventor reference tests: Coin3D through Python (`python3-pivy`);
//! - building the editor: ALSA's headers (`libasound2-dev`) and pkg-config for `cpal`.
//!
//! On Debian as root (or with password-less sudo) the missing packages are installed with
//! `apt-get`; elsewhere the task stops and prints the one command to run.

use std::path::Path;
use std::process::Command;

use crate::{root, run_status};

/// A Debian package and, when it has one, a command it provides (checked where there is no
/// dpkg).
struct Need {
    package: &'static str,
    command: Option<&'static str>,
    why: &'static str,
}

const WINDOW: &[Need] = &[
    Need { package: "xvfb", command: Some("Xvfb"), why: "the real-window tests' X server" },
    Need { package: "xauth", command: Some("xauth"), why: "Xvfb's authority file" },
    Need { package: "xdotool", command: Some("xdotool"), why: "real X input in the real-window tests" },
    Need { package: "imagemagick", command: Some("import"), why: "screenshots of the real window" },
    Need { package: "libxkbcommon-x11-0", command: None, why: "the editor window's keyboard" },
    Need { package: "libxkbcommon0", command: None, why: "the editor window's keyboard" },
    Need { package: "libx11-6", command: None, why: "the editor window" },
    Need { package: "libx11-xcb1", command: None, why: "the editor window" },
    Need { package: "libxcursor1", command: None, why: "the editor window's cursors" },
    Need { package: "libxrandr2", command: None, why: "the editor window" },
    Need { package: "libxi6", command: None, why: "the editor window's input" },
];

const COIN: &[Need] = &[Need {
    package: "python3-pivy",
    command: None,
    why: "Coin3D for Python, the VRML/Inventor reference the VRML tests compare with",
}];

const FFMPEG: &[Need] = &[Need {
    package: "ffmpeg",
    command: Some("ffprobe"),
    why: "FFmpeg's ffprobe and ffmpeg, the independent decoders of the playblast tests (MP4, GIF, APNG)",
}];

/// Building the editor: `cpal` (sound clips played in the editor) links ALSA, found with
/// pkg-config.
const SOUND: &[Need] = &[
    Need {
        package: "libasound2-dev",
        command: None,
        why: "ALSA's headers, which the editor's sound output (cpal) builds against",
    },
    Need { package: "pkg-config", command: Some("pkg-config"), why: "finding ALSA when the editor builds" },
    Need {
        package: "g++",
        command: Some("g++"),
        why: "OpenH264's bundled C++ source, which the MP4 playblast encoder builds",
    },
];

const NODE: &[Need] = &[
    Need { package: "nodejs", command: Some("node"), why: "the Khronos glTF-Validator" },
    Need { package: "npm", command: Some("npm"), why: "installing the glTF-Validator" },
];

const LAVAPIPE: &[Need] = &[
    Need { package: "mesa-vulkan-drivers", command: None, why: "lavapipe, the CPU Vulkan driver" },
    Need { package: "libvulkan1", command: None, why: "the Vulkan loader" },
];

/// The X libraries the editor's window opens (winit), without the test tools.
const EDITOR_WINDOW: &[&str] = &[
    "libxkbcommon-x11-0",
    "libxkbcommon0",
    "libx11-6",
    "libx11-xcb1",
    "libxcursor1",
    "libxrandr2",
    "libxi6",
];

/// Checks and installs what building and opening the editor needs: ALSA's headers and a C++
/// compiler (the build), the window's X libraries and a Vulkan driver (lavapipe where the
/// machine has none).
///
/// # Errors
/// What is missing and cannot be installed here, with the command that installs it.
pub fn editor() -> Result<(), String> {
    let mut needs: Vec<&Need> = WINDOW.iter().filter(|n| EDITOR_WINDOW.contains(&n.package)).collect();
    needs.extend(SOUND);
    if !vulkan_driver_installed() {
        needs.extend(LAVAPIPE);
    }
    install(&needs)
}

/// Checks and installs what the tests need.
///
/// # Errors
/// What is missing and cannot be installed here, with the command that installs it.
pub fn run(validator: bool) -> Result<(), String> {
    let mut needs: Vec<&Need> = WINDOW.iter().chain(COIN).chain(FFMPEG).chain(SOUND).collect();
    if validator && (!on_path("node") || !on_path("npm")) {
        needs.extend(NODE);
    }
    let adapter = if vulkan_driver_installed() {
        "Vulkan (the installed Vulkan driver)"
    } else {
        needs.extend(LAVAPIPE);
        "Vulkan (lavapipe)"
    };
    install(&needs)?;
    if validator {
        install_validator()?;
    }
    println!("xtask: GPU tests use {adapter}");
    Ok(())
}

/// Whether a Vulkan loader and at least one Vulkan driver (an ICD manifest) are installed.
fn vulkan_driver_installed() -> bool {
    let icd_dirs = ["/usr/share/vulkan/icd.d", "/etc/vulkan/icd.d", "/usr/local/share/vulkan/icd.d"];
    let has_icd = icd_dirs.iter().any(|dir| {
        std::fs::read_dir(dir).is_ok_and(|mut entries| {
            entries.any(|e| e.is_ok_and(|e| e.path().extension().is_some_and(|x| x == "json")))
        })
    });
    has_icd && library_present("libvulkan.so.1")
}

/// Whether a shared library is in one of the usual library folders.
fn library_present(name: &str) -> bool {
    let dirs = ["/usr/lib/x86_64-linux-gnu", "/usr/lib/aarch64-linux-gnu", "/usr/lib64", "/usr/lib", "/lib"];
    dirs.iter().any(|dir| Path::new(dir).join(name).exists())
}

fn on_path(command: &str) -> bool {
    std::env::var_os("PATH")
        .is_some_and(|paths| std::env::split_paths(&paths).any(|dir| dir.join(command).is_file()))
}

/// Installs the missing packages with apt-get (as root, or with password-less sudo); elsewhere
/// fails with the command to run.
fn install(needs: &[&Need]) -> Result<(), String> {
    let debian = on_path("dpkg-query") && on_path("apt-get");
    let missing: Vec<&Need> = if debian {
        needs.iter().copied().filter(|n| !dpkg_installed(n.package)).collect()
    } else {
        needs.iter().copied().filter(|n| n.command.is_some_and(|c| !on_path(c))).collect()
    };
    if missing.is_empty() {
        return Ok(());
    }
    let names: Vec<&str> = missing.iter().map(|n| n.package).collect();
    let list: Vec<String> = missing.iter().map(|n| format!("  {} ({})", n.package, n.why)).collect();
    let apt = format!("apt-get install -y --no-install-recommends {}", names.join(" "));
    if !debian {
        return Err(format!(
            "the tests need these programs, which are not installed:\n{}\nOn Debian or Ubuntu: sudo {apt}",
            list.join("\n")
        ));
    }
    let prefix: &[&str] = if is_root() {
        &[]
    } else if Command::new("sudo").args(["-n", "true"]).output().is_ok_and(|o| o.status.success()) {
        &["sudo", "-n"]
    } else {
        return Err(format!("the tests need these packages:\n{}\nRun: sudo {apt}", list.join("\n")));
    };
    println!("xtask: installing {}", names.join(", "));
    let apt_get = |args: &[&str]| {
        let mut all: Vec<&str> = prefix.to_vec();
        all.push("apt-get");
        all.extend_from_slice(args);
        let mut command = Command::new(all[0]);
        command.args(&all[1..]).env("DEBIAN_FRONTEND", "noninteractive");
        command
    };
    run_status(&mut apt_get(&["update", "-qq"]), "apt-get update")?;
    let mut args = vec!["install", "-y", "-qq", "--no-install-recommends"];
    args.extend(&names);
    run_status(&mut apt_get(&args), "apt-get install")
}

fn dpkg_installed(package: &str) -> bool {
    Command::new("dpkg-query")
        .args(["-W", "-f=${Status}", package])
        .output()
        .is_ok_and(|o| o.status.success() && String::from_utf8_lossy(&o.stdout).ends_with("installed"))
}

fn is_root() -> bool {
    Command::new("id").arg("-u").output().is_ok_and(|o| String::from_utf8_lossy(&o.stdout).trim() == "0")
}

/// `npm ci` in tools/validate-gltf when the validator is missing or older than its lockfile.
fn install_validator() -> Result<(), String> {
    let dir = root().join("tools/validate-gltf");
    let installed = dir.join("node_modules/.package-lock.json");
    let modified = |p: &Path| std::fs::metadata(p).and_then(|m| m.modified()).ok();
    let fresh = match (modified(&installed), modified(&dir.join("package-lock.json"))) {
        (Some(installed), Some(lock)) => installed >= lock,
        _ => false,
    };
    if fresh && dir.join("node_modules/gltf-validator").is_dir() {
        return Ok(());
    }
    println!("xtask: installing the glTF validator (npm ci --prefix tools/validate-gltf)");
    let mut npm = Command::new("npm");
    npm.args(["ci", "--no-audit", "--no-fund", "--prefix"]).arg(&dir);
    run_status(&mut npm, "npm ci --prefix tools/validate-gltf")
}
