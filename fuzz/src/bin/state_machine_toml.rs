//! libFuzzer entry point for `tassel_fuzz::state_machine_toml` (built by fuzz/run.sh).
#![no_main]
libfuzzer_sys::fuzz_target!(|data: &[u8]| tassel_fuzz::state_machine_toml(data));
