//! libFuzzer entry point for `tassel_fuzz::ffi_load` (built by fuzz/run.sh).
#![no_main]
libfuzzer_sys::fuzz_target!(|data: &[u8]| tassel_fuzz::ffi_load(data));
