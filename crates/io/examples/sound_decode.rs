//! Decodes and summarises sound files as `keyrig info` and the editor do, and says how long
//! each took on the wall clock: the figures of docs/benchmarks.md's sound table, where the
//! process's CPU time (`/usr/bin/time`) says what a machine busy with other work hides.
//!
//! `cargo run --release -p keyrig-io --example sound_decode -- [--threads N] FILE…`
//! (`--threads 1`: one pass; by default one part per core).

use std::path::Path;
use std::time::Instant;

fn main() {
    let mut args = std::env::args().skip(1).peekable();
    let mut threads = std::thread::available_parallelism().map_or(1, std::num::NonZeroUsize::get);
    if args.peek().map(String::as_str) == Some("--threads") {
        args.next();
        threads = match args.next().and_then(|n| n.parse().ok()) {
            Some(n) => n,
            None => {
                eprintln!("--threads takes a number");
                std::process::exit(2);
            }
        };
    }
    for file in args {
        let start = Instant::now();
        match keyrig_io::sound::decode_sound_file_on_threads(Path::new(&file), None, threads) {
            Ok(sound) => println!(
                "{file}: {} frames, {} part(s), {:.3} s",
                sound.summary.frames,
                sound.parts,
                start.elapsed().as_secs_f64()
            ),
            Err(e) => {
                eprintln!("{e}");
                std::process::exit(1);
            }
        }
    }
}
