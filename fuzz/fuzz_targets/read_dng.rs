//! Fuzz the DNG reader and the opcode-list parser (directly and through `inspect`): any
//! bytes must give Ok or an error, never a panic, hang or OOM.
//! Run: `cd fuzz && cargo +nightly fuzz run read_dng` (crashes land in fuzz/artifacts/;
//! copy them to tests/fuzz_regressions/*.bin so `cargo test` replays them).
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = day2night::dng::read::read_dng_bytes(data);
    let _ = day2night::dng::read::inspect_bytes(data);
    let _ = day2night::dng::ljpeg::decode(data);
    let _ = day2night::dng::opcodes::parse_list(data);
});
