//! Shared input decoding for the afl targets in `src/bin/`: each turns
//! arbitrary bytes into what a core crate's parser or detector takes.
use std::sync::OnceLock;
use tactrace_sensor::{TacTipConfig, TacTipModel};
use tactrace_vision::{BlobParams, Frame, PinExtractor};

/// A frame from arbitrary bytes: a PNG when the bytes say so (decoded as
/// `read_frame` does), else raw grey pixels whose first byte sets the width.
pub fn frame_from_bytes(data: &[u8]) -> Option<Frame> {
    if data.starts_with(b"\x89PNG") {
        let img = image::load_from_memory_with_format(data, image::ImageFormat::Png).ok()?;
        return Some(img.into_luma8());
    }
    let (&w, pixels) = data.split_first()?;
    let width = u32::from(w) + 1;
    let height = (pixels.len() as u32) / width;
    let used = (width * height) as usize;
    Frame::from_raw(width, height, pixels[..used].to_vec())
}

/// The simulated sensor's undeformed frame turned into a pin extractor
/// (built once: it is the same for every input).
pub fn reference_extractor() -> &'static PinExtractor {
    static EXTRACTOR: OnceLock<PinExtractor> = OnceLock::new();
    EXTRACTOR.get_or_init(|| {
        let model = TacTipModel::new(TacTipConfig::default()).expect("default sensor");
        let frame = model.render(model.rest_pins(), None);
        let params = BlobParams::preset("sim").expect("sim preset");
        PinExtractor::from_reference_frame(&frame, params).expect("reference pins")
    })
}

/// Split an input in two at its first NUL byte (the second part may be empty).
pub fn split_at_nul(data: &[u8]) -> (&[u8], &[u8]) {
    match data.iter().position(|&b| b == 0) {
        Some(i) => (&data[..i], &data[i + 1..]),
        None => (data, &[]),
    }
}
