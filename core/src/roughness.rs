//! How rough a terrain is, as the level switch needs it: the height detail
//! a coarse level cannot carry, per voxel of its spacing.
//!
//! The pixel-to-voxel ratio switches levels by width alone (Cohen-Or
//! §2.1): level `l` begins at depth `D_l = 2^(l−1)·focal / ratio`, where
//! a voxel of level `l − 1` gets narrower than `1 / ratio` pixels. Its
//! coarser surface departs from the terrain by some height `e_l`, which
//! shows as `e_l·focal / D_l` pixels of silhouette (and hit) error where
//! the level begins. On a smooth map that is well below a pixel; on rugged
//! real terrain it is not, and the coarse levels then cost accuracy at
//! silhouettes (README, "Accuracy against the exact reference"; colors
//! switch levels by the ratio as given, so the fit moves heights only).
//! Keeping that error within [`TERRAIN_FIT_PIXELS`] takes
//! `ratio ≤ TERRAIN_FIT_PIXELS / E`, with `E = max_l e_l / 2^(l−1)`: this
//! module's roughness.
//!
//! `e_l` is measured as the RMS of how far each point lies from the
//! straight line between its neighbours `2^(l−1)` points away along its
//! row: the error of interpolating across a level-`l` voxel. Rows only,
//! and every [`ROUGHNESS_ROW_STEP`]-th of them, so that a packer streaming
//! rows computes exactly what a pyramid computes from its level 0, and
//! cheaply (levels 1 to [`ROUGHNESS_LEVELS`]: the ones a frame mostly
//! uses).

/// Levels whose detail is measured: 1 to this.
pub const ROUGHNESS_LEVELS: u32 = 4;

/// Rows measured: every this-many-th, from row 0.
pub const ROUGHNESS_ROW_STEP: u32 = 4;

/// Silhouette error allowed where a level begins, RMS, in pixels: an
/// eighth of a pixel, so that most points (95 % of normally distributed
/// errors, which lie within twice the RMS) are within a quarter pixel,
/// the spacing of the reference's 4 × 4 samples. Silhouettes are drawn
/// by ridges, where the error is largest, so the RMS alone (a quarter
/// pixel, until colors got their own levels) let the coarse heights cost
/// views up to 0.6 dB against single resolution.
pub const TERRAIN_FIT_PIXELS: f32 = 0.125;

/// Sums of squared interpolation errors, row by row (see the module
/// notes). Feed it level 0's rows in any order, each with its number
/// ([`RoughnessSum::add_row_at`] keeps the sampled ones), or a whole grid
/// ([`RoughnessSum::add_grid`]), then read [`RoughnessSum::roughness`].
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct RoughnessSum {
    /// Per level: the sum of `(2h(x) − h(x − s) − h(x + s))²` (U12.4
    /// heights, so 1/256 voxel² units, four times the squared error) and
    /// the number of terms.
    squares: [u64; ROUGHNESS_LEVELS as usize],
    terms: [u64; ROUGHNESS_LEVELS as usize],
}

impl RoughnessSum {
    /// Adds one row of U12.4 heights, sampled or not.
    pub fn add_row(&mut self, row: &[u16]) {
        for (level, (squares, terms)) in self.squares.iter_mut().zip(&mut self.terms).enumerate() {
            let s = 1usize << level;
            // Windows of 2s + 1 points: the two ends and the middle.
            for window in row.windows(2 * s + 1) {
                let (a, m, b) = (window[0], window[s], window[2 * s]);
                let d = 2 * i64::from(m) - i64::from(a) - i64::from(b);
                *squares = squares.saturating_add(d.unsigned_abs().pow(2));
                *terms += 1;
            }
        }
    }

    /// Adds row `y` of U12.4 heights if it is one the measure samples
    /// (every [`ROUGHNESS_ROW_STEP`]-th): what a caller streaming every
    /// row calls.
    pub fn add_row_at(&mut self, y: u32, row: &[u16]) {
        if y % ROUGHNESS_ROW_STEP == 0 {
            self.add_row(row);
        }
    }

    /// Adds the rows the measure samples of a `width`-point-wide grid of
    /// heights stored row by row.
    pub fn add_grid(&mut self, heights: &[u16], width: usize) {
        if width == 0 {
            return;
        }
        for (y, row) in (0..).zip(heights.chunks_exact(width)) {
            self.add_row_at(y, row);
        }
    }

    /// The roughness `E` (see the module notes) in 1/64 units, saturating
    /// at 255 (about 4): 0 for a map too small to measure or flat.
    pub fn roughness(&self) -> u8 {
        let mut worst = 0u64;
        for (level, (&squares, &terms)) in self.squares.iter().zip(&self.terms).enumerate() {
            if terms == 0 {
                continue;
            }
            // E_l² in 1/64² units: (sum / 4 / terms) / 256 / 4^level · 64²
            // = sum · 4 / (terms · 4^level).
            let scaled = squares.saturating_mul(4) / (terms << (2 * level));
            worst = worst.max(scaled);
        }
        worst.isqrt().min(255) as u8
    }
}

/// The factor, Q16 and at most 1, by which the pixel-to-voxel ratio is
/// scaled on a map of `roughness` ([`RoughnessSum::roughness`]) so that a
/// level's silhouette error where it begins stays within
/// [`TERRAIN_FIT_PIXELS`]: `min(1, TERRAIN_FIT_PIXELS / E)`.
pub fn terrain_fit(roughness: u8) -> u32 {
    const ONE: u32 = 1 << 16;
    // TERRAIN_FIT_PIXELS / (roughness / 64), Q16.
    const NUMERATOR: u32 = (TERRAIN_FIT_PIXELS * 64.0 * 65536.0) as u32;
    match roughness {
        0 => ONE,
        r => (NUMERATOR / u32::from(r)).min(ONE),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_plane_is_smooth_and_keeps_the_ratio() {
        // A tilted plane: every point lies on the line between its
        // neighbours.
        let heights: std::vec::Vec<u16> = (0..64 * 64)
            .map(|i| (i % 64 * 7 + i / 64 * 3) as u16)
            .collect();
        let mut sum = RoughnessSum::default();
        sum.add_grid(&heights, 64);
        assert_eq!(sum.roughness(), 0);
        assert_eq!(terrain_fit(sum.roughness()), 1 << 16);
        assert_eq!(terrain_fit(0), 1 << 16);
    }

    #[test]
    fn roughness_is_the_worst_level_error_per_voxel_of_spacing() {
        // Alternating heights 0 and half a voxel (8 in U12.4): each point
        // is half a voxel from the line between its neighbours one point
        // away, and on the line between those two points away.
        let row: std::vec::Vec<u16> = (0..32).map(|x| (x % 2) * 8).collect();
        let mut sum = RoughnessSum::default();
        sum.add_row(&row);
        // E = 0.5 voxel per voxel at level 1: 32/64.
        assert_eq!(sum.roughness(), 32);
        // Keeping an eighth of a pixel takes a quarter of the ratio.
        assert_eq!(terrain_fit(32), 1 << 14);
        // Rougher still: never more than the ratio, never zero.
        assert_eq!(terrain_fit(255), (8 << 16) / 255);
        assert!(terrain_fit(1) == 1 << 16);
    }

    #[test]
    fn rows_are_sampled_every_fourth_from_the_first() {
        // Only row 4 is rough: it is measured, and rows 1 to 3 are not.
        let mut heights = std::vec![0u16; 8 * 16];
        for x in 0..16 {
            heights[4 * 16 + x] = (x as u16 % 2) * 64;
            heights[16 + x] = (x as u16 % 2) * 640;
        }
        let mut measured = RoughnessSum::default();
        measured.add_grid(&heights, 16);
        let mut by_hand = RoughnessSum::default();
        for y in [0, 4] {
            by_hand.add_row(&heights[y * 16..(y + 1) * 16]);
        }
        assert_eq!(measured, by_hand);
        assert!(measured.roughness() > 0);
    }
}
