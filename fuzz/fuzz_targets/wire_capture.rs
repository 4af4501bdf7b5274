#![no_main]
//! The display wire decoder: any capture replays or is refused. The first
//! two bytes choose the image size (1 to 64 a side).
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let (w, h) = match data {
        [w, h, ..] => (u32::from(w % 64) + 1, u32::from(h % 64) + 1),
        _ => (16, 12),
    };
    let mut image = vec![0u16; (w * h) as usize];
    let _ = terracast_board::wire::decode(data.get(2..).unwrap_or(&[]), &mut image, w, h);
});
