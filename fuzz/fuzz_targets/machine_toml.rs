#![no_main]
//! The machine description: any text is a machine or a one-line error.
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = terracast_sim::sim::Machine::from_toml(&String::from_utf8_lossy(data));
});
