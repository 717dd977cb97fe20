#![no_main]
libfuzzer_sys::fuzz_target!(|data: &[u8]| organtex::fuzz::label_map(data));
