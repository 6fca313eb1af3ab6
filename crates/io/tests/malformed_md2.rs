//! Malformed MD2 files made from the corpus: every one is rejected with a byte offset or
//! accepted, never a panic, and never more memory than the file can justify.

mod malformed_support;

use std::path::{Path, PathBuf};

use keyrig_io::md2::parse_md2;
use malformed_support::{byte_flips, overwrite_u32, run_suite, truncations, CountingAlloc, Mutant};

#[global_allocator]
static ALLOC: CountingAlloc = CountingAlloc;

fn corpus(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/corpus/md2").join(rel)
}

const FILES: [&str; 5] = [
    "ratamahatta/ratamahatta.md2",
    "ratamahatta/weapon.md2",
    "sydney/sydney.md2",
    "faerie/faerie.md2",
    "dolphin/dolphin.md2",
];

/// Every header field overwritten with hostile values: counts of 2^31 and more, −1,
/// offsets past the end, zero.
fn header_overwrites(data: &[u8]) -> Vec<Mutant> {
    let mut out = Vec::new();
    for field in 0..17 {
        for value in
            [0x8000_0000u32, 0x7fff_ffff, 0xffff_ffff, 0, data.len() as u32, data.len() as u32 + 4, 1 << 20]
        {
            out.push(overwrite_u32(data, 4 * field, value, &format!("header field {field}")));
        }
    }
    out
}

/// NaN and infinity in the first frame's scale and translation.
fn float_overwrites(data: &[u8]) -> Vec<Mutant> {
    let ofs_frames = u32::from_le_bytes([data[56], data[57], data[58], data[59]]) as usize;
    let mut out = Vec::new();
    for k in 0..6 {
        for value in [f32::NAN, f32::INFINITY, f32::MAX] {
            out.push(overwrite_u32(data, ofs_frames + 4 * k, value.to_bits(), "frame float"));
        }
    }
    out
}

/// Out-of-range triangle indices and normal indices.
fn index_overwrites(data: &[u8]) -> Vec<Mutant> {
    let ofs_tris = u32::from_le_bytes([data[52], data[53], data[54], data[55]]) as usize;
    let ofs_frames = u32::from_le_bytes([data[56], data[57], data[58], data[59]]) as usize;
    let mut out = Vec::new();
    for corner in 0..6 {
        let mut bytes = data.to_vec();
        bytes[ofs_tris + 2 * corner..ofs_tris + 2 * corner + 2].copy_from_slice(&u16::MAX.to_le_bytes());
        out.push(Mutant { label: format!("triangle 0 index {corner} := 65535"), bytes });
    }
    let mut bytes = data.to_vec();
    bytes[ofs_frames + 40 + 3] = 200;
    out.push(Mutant { label: "normal index 200".into(), bytes });
    out
}

#[test]
fn malformed_md2_files_are_rejected_with_a_byte_offset_never_a_panic() {
    let mut mutants = Vec::new();
    for (i, file) in FILES.iter().enumerate() {
        let data = std::fs::read(corpus(file)).expect("read corpus file");
        let mut local = truncations(&data, 40);
        local.extend(byte_flips(&data, 40, 1, 0x5eed + i as u64));
        // Flips concentrated in the header, where they matter most.
        let mut header_flips = byte_flips(&data[..68], 30, 2, 0xfeed + i as u64);
        for m in &mut header_flips {
            m.bytes.extend_from_slice(&data[68..]);
        }
        local.extend(header_flips);
        local.extend(header_overwrites(&data));
        local.extend(float_overwrites(&data));
        local.extend(index_overwrites(&data));
        for m in &mut local {
            m.label = format!("{file}: {}", m.label);
        }
        mutants.extend(local);
    }
    assert!(mutants.len() >= 500, "only {} mutants", mutants.len());
    // Decompressed frames take 13 bytes per 4-byte packed vertex, plus names and the weld map.
    let (accepted, rejected) = run_suite(
        "md2",
        &mutants,
        parse_md2,
        |len| 6 * len + (64 << 10),
        |e| e.to_string().starts_with("byte "),
    );
    assert!(
        rejected > mutants.len() / 2,
        "only {rejected} of {} rejected ({accepted} accepted)",
        mutants.len()
    );
}
