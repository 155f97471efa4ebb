//! Fuzz the lossless JPEG decoder alone: `cd fuzz && cargo +nightly fuzz run ljpeg`.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(d) = day2night::dng::ljpeg::decode(data) {
        assert_eq!(d.data.len(), d.width * d.height * d.components);
    }
});
