#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    myoslice::fuzz_targets::png_slice(data);
});
