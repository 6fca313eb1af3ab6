//! `cargo xtask screenshots`: the guide's pictures of imported models and of the shipped
//! scenes (docs/guide.md), each the real `keyrig edit FILE` window on an X server without a
//! screen (Xvfb, 1280×800), driven with `xdotool` keys where the picture needs a frame or a
//! view, captured with ImageMagick's `import` once the window has stopped drawing (two equal
//! captures 300 ms apart), and written atomically into `docs/screenshots/`.
//!
//! The real-window tests (`crates/editor/tests/e2e_xdotool.rs`) take the guide's other
//! pictures while they assert, and copy them with `KEYRIG_UPDATE_SCREENSHOTS=1`.

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use crate::{cargo, root, run_status};

/// One picture: the file opened (relative to the repository) and the keys pressed before the
/// capture, each `(xdotool key name, times)`.
struct Picture {
    name: &'static str,
    file: &'static str,
    keys: &'static [(&'static str, u32)],
}

const SHOWCASE: &str = "assets/showcase.ron";

const PICTURES: &[Picture] = &[
    Picture { name: "guide-cesium-man", file: "tests/corpus/gltf/CesiumMan/CesiumMan.glb", keys: &[] },
    Picture {
        name: "guide-md2-ratamahatta",
        file: "tests/corpus/md2/ratamahatta/ratamahatta.md2",
        keys: &[],
    },
    // The orbit view at frame 20: both cameras' frustums, the marker on the ruler.
    Picture { name: "guide-showcase-cameras", file: SHOWCASE, keys: &[("Right", 20)] },
    // Through the active camera (Track, from the marker on) at frame 74 and 75: the deformer
    // switches from linear blend to bones blending between them.
    Picture { name: "guide-showcase-wrapper", file: SHOWCASE, keys: &[("Right", 74), ("0", 1)] },
    Picture { name: "guide-showcase-repaired", file: SHOWCASE, keys: &[("Right", 75), ("0", 1)] },
    // The IK constraint's target drawn in the viewport (the pink diamond the wrist follows) at
    // frame 20.
    Picture { name: "guide-ik-target", file: "assets/ik.ron", keys: &[("Right", 20)] },
];

/// A child process killed and reaped when dropped.
struct Guard(Child);

impl Drop for Guard {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

/// Takes the pictures named in `args` (every picture when none is named); `--dev` takes them
/// with the dev profile's `keyrig` (optimized too, `Cargo.toml`), which a machine that has
/// built the tests has already, instead of a release build.
pub fn run(args: &[String]) -> Result<(), String> {
    let dev = args.iter().any(|a| a == "--dev");
    let names: Vec<&String> = args.iter().filter(|a| *a != "--dev").collect();
    if let Some(unknown) = names.iter().find(|n| !PICTURES.iter().any(|p| p.name == n.as_str())) {
        let known: Vec<&str> = PICTURES.iter().map(|p| p.name).collect();
        return Err(format!("no picture named `{unknown}` (pictures: {})", known.join(", ")));
    }
    let root = root();
    let mut build = cargo();
    build.current_dir(&root).args(["build", "-p", "keyrig-editor", "--bin", "keyrig"]);
    if !dev {
        build.arg("--release");
    }
    run_status(&mut build, "cargo build -p keyrig-editor --bin keyrig")?;
    let keyrig = root.join(if dev { "target/debug/keyrig" } else { "target/release/keyrig" });
    let (_xvfb, display) = start_xvfb()?;
    let home = std::env::temp_dir().join(format!("keyrig-screenshots-{}", std::process::id()));
    std::fs::create_dir_all(&home).map_err(|e| format!("{}: {e}", home.display()))?;
    let docs = root.join("docs/screenshots");
    let wanted = PICTURES.iter().filter(|p| names.is_empty() || names.iter().any(|n| *n == p.name));
    for Picture { name, file, keys } in wanted {
        let model = root.join(file);
        let mut command = Command::new(&keyrig);
        command
            .arg("edit")
            .arg(&model)
            .env("DISPLAY", &display)
            .env_remove("WAYLAND_DISPLAY")
            .env("HOME", &home)
            .env("XDG_DATA_HOME", home.join("data"))
            .env("XDG_CONFIG_HOME", home.join("config"))
            .stdout(Stdio::null())
            .stderr(Stdio::null());
        let _editor = Guard(command.spawn().map_err(|e| format!("cannot start {}: {e}", keyrig.display()))?);
        let window = wait_for_window(&display)?;
        x(&display, "xdotool", &["windowmove", "--sync", &window, "0", "0"])?;
        x(&display, "xdotool", &["windowsize", "--sync", &window, "1280", "800"])?;
        wait_idle(&display, &home)?;
        if !keys.is_empty() {
            x(&display, "xdotool", &["windowfocus", "--sync", &window])?;
            for (key, times) in *keys {
                let times = times.to_string();
                x(
                    &display,
                    "xdotool",
                    &["key", "--clearmodifiers", "--delay", "40", "--repeat", &times, key],
                )?;
            }
            wait_idle(&display, &home)?;
        }
        let out = docs.join(format!("{name}.png"));
        let temp = docs.join(format!(".{name}.png.tmp.png"));
        x(&display, "import", &["-window", "root", &temp.to_string_lossy()])?;
        std::fs::rename(&temp, &out).map_err(|e| format!("{}: {e}", out.display()))?;
        println!("xtask: wrote {}", out.display());
    }
    let _ = std::fs::remove_dir_all(&home);
    Ok(())
}

/// Runs an X client on `display`, 20 s at most; its standard output.
fn x(display: &str, program: &str, args: &[&str]) -> Result<String, String> {
    let out = Command::new("timeout")
        .arg("20")
        .arg(program)
        .args(args)
        .env("DISPLAY", display)
        .output()
        .map_err(|e| format!("{program}: {e}"))?;
    if !out.status.success() {
        return Err(format!("{program} {args:?} failed: {}", String::from_utf8_lossy(&out.stderr)));
    }
    Ok(String::from_utf8_lossy(&out.stdout).into_owned())
}

fn start_xvfb() -> Result<(Guard, String), String> {
    for display in 170..400 {
        if Path::new(&format!("/tmp/.X11-unix/X{display}")).exists()
            || Path::new(&format!("/tmp/.X{display}-lock")).exists()
        {
            continue;
        }
        let child = Command::new("Xvfb")
            .args([&format!(":{display}"), "-screen", "0", "1280x800x24", "-nolisten", "tcp"])
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .map_err(|e| format!("cannot start Xvfb: {e}"))?;
        let guard = Guard(child);
        let socket = PathBuf::from(format!("/tmp/.X11-unix/X{display}"));
        let deadline = Instant::now() + Duration::from_secs(10);
        while Instant::now() < deadline {
            if socket.exists() {
                return Ok((guard, format!(":{display}")));
            }
            std::thread::sleep(Duration::from_millis(50));
        }
    }
    Err("Xvfb did not start on any display number".to_owned())
}

/// The editor's window id, once it is shown (60 s at most).
fn wait_for_window(display: &str) -> Result<String, String> {
    let deadline = Instant::now() + Duration::from_secs(60);
    while Instant::now() < deadline {
        let out = Command::new("timeout")
            .args(["3", "xdotool", "search", "--sync", "--onlyvisible", "--name", "keyrig"])
            .env("DISPLAY", display)
            .output()
            .map_err(|e| format!("xdotool: {e}"))?;
        if let Some(id) = String::from_utf8_lossy(&out.stdout).lines().find(|l| !l.trim().is_empty()) {
            return Ok(id.trim().to_owned());
        }
    }
    Err("the keyrig window did not appear within 60 s".to_owned())
}

/// Waits (30 s at most) until two captures 300 ms apart are equal.
fn wait_idle(display: &str, home: &Path) -> Result<(), String> {
    let raw = home.join("idle.rgb");
    let capture = || -> Result<Vec<u8>, String> {
        x(display, "import", &["-window", "root", "-depth", "8", &format!("rgb:{}", raw.display())])?;
        Ok(std::fs::read(&raw).unwrap_or_default())
    };
    std::thread::sleep(Duration::from_secs(2));
    let start = Instant::now();
    let mut last = capture()?;
    while start.elapsed() < Duration::from_secs(30) {
        std::thread::sleep(Duration::from_millis(300));
        let now = capture()?;
        if now == last && !now.is_empty() {
            return Ok(());
        }
        last = now;
    }
    Err("the editor window was still drawing after 30 s".to_owned())
}
