//! afl target: arbitrary bytes as a frame (PNG or raw pixels) through blob
//! detection and pin ordering against the simulated reference.
fn main() {
    let extractor = tactrace_fuzz::reference_extractor();
    afl::fuzz!(|data: &[u8]| {
        if let Some(frame) = tactrace_fuzz::frame_from_bytes(data) {
            let _ = extractor.extract(&frame);
            let _ = tactrace_vision::PinExtractor::from_reference_frame(
                &frame,
                extractor.params.clone(),
            );
        }
    });
}
