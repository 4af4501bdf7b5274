#![no_main]
//! The board scene file, read in place as the firmware reads it; every
//! view it carries goes through the kernel's camera check, and its
//! objects, if any, through the kernel's stick layer check.
use libfuzzer_sys::fuzz_target;
use terracast_board::scene::BoardScene;

fuzz_target!(|data: &[u8]| {
    // The heights are read in place as u16: 2-byte aligned storage.
    let mut words = vec![0u16; data.len().div_ceil(2)];
    for (i, byte) in data.iter().enumerate() {
        words[i / 2] |= u16::from(*byte) << (8 * (i % 2));
    }
    let bytes: Vec<u8> = words.iter().flat_map(|w| w.to_le_bytes()).collect();
    if let Ok(scene) = BoardScene::parse(&bytes[..data.len()]) {
        let header = scene.header;
        for camera in header.views() {
            let _ = terracast::View::new(camera, header.image_width, header.image_height);
        }
        if let Ok(terrain) = scene.terrain() {
            let mut sticks = vec![terracast::Stick::default(); scene.stick_count()];
            let _ = scene.objects(&terrain, &mut sticks);
        }
    }
});
