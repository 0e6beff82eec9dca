//! Regression tests for inputs found by the mutation fuzz of the CLI
//! (tests/it/fuzz_inputs/mod.rs at the workspace root), one per bug.
use image::{GrayImage, Luma};
use std::path::PathBuf;
use tactrace_sensor::read_frame;

fn temp_file(name: &str, bytes: &[u8]) -> PathBuf {
    let dir = tempfile::Builder::new()
        .prefix("tactrace-sensor-fuzz-")
        .tempdir()
        .expect("temp dir")
        .keep();
    let path = dir.join(name);
    std::fs::write(&path, bytes).expect("write");
    path
}

/// A PNG whose IDAT checksum is wrong: the decoder's message used to end in
/// `while decoding ChunkType { type: IDAT, critical: true, .. } chunk`.
#[test]
fn corrupt_png_chunk_is_named_without_debug_struct() {
    let img = GrayImage::from_pixel(8, 8, Luma([200]));
    let mut bytes = std::io::Cursor::new(Vec::new());
    img.write_to(&mut bytes, image::ImageFormat::Png)
        .expect("encode");
    let mut bytes = bytes.into_inner();
    let idat = bytes
        .windows(4)
        .position(|w| w == b"IDAT")
        .expect("IDAT chunk");
    let len = u32::from_be_bytes(bytes[idat - 4..idat].try_into().expect("length")) as usize;
    bytes[idat + 4 + len] ^= 0x10; // the chunk's CRC
    let err = read_frame(&temp_file("crc.png", &bytes)).expect_err("corrupt");
    let msg = err.to_string();
    assert!(msg.contains("corrupt") && msg.contains("IDAT"), "{msg}");
    assert!(!msg.contains("ChunkType {"), "{msg}");
    assert!(!msg.contains("critical:"), "{msg}");
}
