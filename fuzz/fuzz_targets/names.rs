#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    myoslice::fuzz_targets::names(data);
});
