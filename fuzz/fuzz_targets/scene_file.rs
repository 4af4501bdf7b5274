#![no_main]
//! The scene file (`--place`): any text is a plan or a one-line error.
use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data);
    // Views are read beside the file: none exist here, so a sculpted
    // object is an error and the fuzzing stays on the text.
    if let Err(e) = terracast_sim::objects::placing::ScenePlan::parse(
        &text,
        "fuzz.toml",
        Path::new("/nonexistent-terracast-fuzz"),
    ) {
        assert!(!e.to_string().contains('\n'));
    }
});
