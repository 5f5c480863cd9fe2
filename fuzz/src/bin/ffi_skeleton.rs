//! libFuzzer entry point for `tassel_fuzz::ffi_skeleton` (built by fuzz/run.sh).
#![no_main]
libfuzzer_sys::fuzz_target!(|data: &[u8]| tassel_fuzz::ffi_skeleton(data));
