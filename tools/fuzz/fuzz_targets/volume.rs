#![no_main]
libfuzzer_sys::fuzz_target!(|data: &[u8]| mint_fuzz_targets::volume(data));
