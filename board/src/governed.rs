//! The governor's check on the board: a run of frames, each within one
//! budget, over the board scene's views and a sweep of pitches.
//!
//! The firmware renders [`cameras`] in order with one [`Governor`] from
//! [`governor`] (so each frame's level bias comes from the frames before,
//! as in a flight), once for each of [`BUDGETS`], and reports each
//! frame's ticks; the host renders the same runs with the same governors,
//! checks the frames byte for byte, and sets each frame's counted
//! instructions against its budget. The check's bars are on the first
//! budget's run; the leaner runs are there for the fit of the prices
//! (`board verify` prints it): the base pass (the line caster) and the
//! refinement (the per-ray path) take different shares of a frame at
//! each budget, which tells their prices apart (at the leanest the base
//! pass is most of a frame).

use terracast::{Camera, Governor};

/// The check's budget, in the board's instructions a pixel of the image.
pub const BUDGET_INSTRUCTIONS_PER_PIXEL: u64 = 3000;

/// The budgets the run is rendered at, in order, in the board's
/// instructions a pixel: the check's, then leaner ones for the price fit.
pub const BUDGETS: [u64; 3] = [BUDGET_INSTRUCTIONS_PER_PIXEL, 2000, 1200];

/// The pitches swept from the first view's eye and heading: level, where
/// a line is a column, and those of `scripts/steps-table`.
pub const PITCHES: [f32; 7] = [0.0, 2.0, 5.0, 15.0, 30.0, 60.0, 90.0];

/// The most frames of a run at one budget: every view of a scene, then
/// the sweep.
pub const MAX_FRAMES: usize = crate::scene::MAX_VIEWS + PITCHES.len();

/// The run's cameras: `views` (at most [`crate::scene::MAX_VIEWS`]), then
/// the first view's eye and heading at each of [`PITCHES`]. The count is
/// returned with them.
pub fn cameras(views: &[Camera]) -> ([Camera; MAX_FRAMES], usize) {
    let mut out = [Camera::looking([0.0; 3], 0.0, 0.0); MAX_FRAMES];
    let mut count = 0;
    for (slot, view) in out.iter_mut().zip(views) {
        *slot = *view;
        count += 1;
    }
    if let Some(first) = views.first() {
        for pitch in PITCHES {
            out[count] = Camera {
                pitch_deg: pitch,
                roll_deg: 0.0,
                ..*first
            };
            count += 1;
        }
    }
    (out, count)
}

/// A run's governor for `width × height` frames: `per_pixel` (one of
/// [`BUDGETS`]) instructions a pixel at the board's prices
/// ([`Governor::on_board`]).
pub fn governor(width: u32, height: u32, per_pixel: u64) -> Governor {
    Governor::on_board(u64::from(width) * u64::from(height) * per_pixel)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_run_is_the_views_then_the_sweep_from_the_first() {
        let a = Camera::looking([1.0, 2.0, 3.0], 40.0, 12.0);
        let b = Camera::looking([5.0, 6.0, 7.0], 80.0, 45.0);
        let (run, count) = cameras(&[a, b]);
        assert_eq!(count, 2 + PITCHES.len());
        assert_eq!(run[..2], [a, b]);
        for (camera, pitch) in run[2..count].iter().zip(PITCHES) {
            assert_eq!(camera.eye, a.eye);
            assert_eq!(camera.yaw_deg, a.yaw_deg);
            assert_eq!(camera.pitch_deg, pitch);
        }
        assert_eq!(cameras(&[]).1, 0);
    }
}
