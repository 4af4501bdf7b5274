#![no_main]
//! The camera path file: any text is accepted or refused, never a panic.
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = terracast_sim::fly::Path::parse(&String::from_utf8_lossy(data));
});
