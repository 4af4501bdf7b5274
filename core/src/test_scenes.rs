//! Maps the unit tests of several modules share.

use crate::{Rgb, Terrain};
use std::vec;
use std::vec::Vec;

/// A `w` × `d` map of rolling hills (heights 0 to 82 voxels) whose
/// colors differ from each grid point to the next.
pub(crate) fn hills(w: u32, d: u32) -> (Vec<u16>, Vec<Rgb>) {
    let mut heights = vec![0u16; (w * d) as usize];
    let mut colors = vec![[0u8; 3]; (w * d) as usize];
    for y in 0..d {
        for x in 0..w {
            let (fx, fy) = (x as f32 * 0.09, y as f32 * 0.13);
            let h =
                40.0 + 30.0 * libm::sinf(fx) * libm::cosf(fy) + 12.0 * libm::sinf(fx * 3.1 + fy);
            // Held at 0 where the two waves' troughs meet.
            heights[(y * w + x) as usize] = Terrain::quantize_height(h.max(0.0)).unwrap();
            colors[(y * w + x) as usize] = [(x * 3) as u8, (y * 5) as u8, (x ^ y) as u8];
        }
    }
    (heights, colors)
}
