//! The parallel machine: the kernel's work on a modeled multiprocessor
//! (processors with local memory, interleaved global memory banks, a disk,
//! frame deadlines), and the same line pool on the host's real cores.
//!
//! 1. [`trace::record_frame`] runs the kernel unchanged on each image line of a
//!    view, observing it through its probe.
//! 2. [`engine::simulate`] replays the recordings on a [`Machine`] in
//!    simulated time. Nothing depends on the host's speed or load: the same
//!    inputs give the same times on every run.
//! 3. [`threads::render_threads`] drives std threads from the same
//!    [`terracast::LinePool`] and measures real time.

pub mod engine;
pub mod footprint;
pub mod machine;
pub mod memory;
pub mod threads;
pub mod trace;

pub use engine::{simulate, FrameResult, MissReason, SimResult};
pub use machine::Machine;
pub use trace::{record_frame, FrameTrace, TileKey};

use crate::error::Result;
use crate::scene::KernelScene;
use terracast::{Camera, RenderOptions};

/// A straight flight: `frames` views from `start`, the eye advancing
/// `speed` voxels a frame along the heading.
pub fn flight(start: &Camera, frames: u32, speed: f32) -> Vec<Camera> {
    let (sin, cos) = start.yaw_deg.to_radians().sin_cos();
    (0..frames)
        .map(|i| {
            let t = i as f32 * speed;
            Camera {
                eye: [start.eye[0] + t * cos, start.eye[1] + t * sin, start.eye[2]],
                ..*start
            }
        })
        .collect()
}

/// Records every view of a flight.
pub fn record_flight(
    scene: &KernelScene,
    cameras: &[Camera],
    size: (u32, u32),
    options: &RenderOptions,
    machine: &Machine,
    mut progress: impl FnMut(usize),
) -> Result<Vec<FrameTrace>> {
    cameras
        .iter()
        .enumerate()
        .map(|(i, camera)| {
            let trace = record_frame(scene, camera, size, options, machine);
            progress(i + 1);
            trace
        })
        .collect()
}

/// Cohen-Or's Table 1 for our kernel: frames a second by processors and
/// pitch.
#[derive(Debug, Clone, PartialEq)]
pub struct Table {
    /// Processor counts (master included), one column each.
    pub processors: Vec<u32>,
    /// Pitches in degrees, one row each.
    pub pitch: Vec<f64>,
    /// `fps[row][column]`.
    pub fps: Vec<Vec<f64>>,
}

/// Table 1's processor counts.
pub const TABLE_PROCESSORS: [u32; 5] = [2, 4, 8, 16, 32];
/// Table 1's pitches.
pub const TABLE_PITCH: [f64; 3] = [14.6, 26.5, 39.0];
/// Cohen-Or's Table 1 (fps on the PVS), rows by [`TABLE_PITCH`], columns by
/// [`TABLE_PROCESSORS`].
pub const COHEN_OR_TABLE_1: [[f64; 5]; 3] = [
    [0.36, 1.1, 2.5, 5.4, 11.0],
    [0.51, 1.5, 3.6, 7.6, 15.6],
    [0.53, 1.6, 3.7, 8.0, 16.3],
];

impl Table {
    /// `{"processors": [...], "pitch": [...], "fps": [[...], ...]}`, one
    /// row of `fps` per pitch.
    pub fn to_json(&self) -> serde_json::Value {
        serde_json::json!({
            "processors": self.processors,
            "pitch": self.pitch,
            "fps": self.fps,
        })
    }

    /// A Markdown table, ours beside Cohen-Or's.
    pub fn markdown(&self) -> String {
        let mut out = String::from("| pitch |");
        for p in &self.processors {
            out += &format!(" {p}p |");
        }
        out += " 32p / 2p | Cohen-Or (PVS) 2p…32p |\n|---|";
        out += &"---|".repeat(self.processors.len() + 2);
        out.push('\n');
        for (row, pitch) in self.fps.iter().zip(&self.pitch) {
            out += &format!("| {pitch}° |");
            for fps in row {
                out += &format!(" {fps:.2} |");
            }
            let ratio = row.last().copied().unwrap_or(0.0) / row.first().copied().unwrap_or(1.0);
            let theirs = TABLE_PITCH
                .iter()
                .position(|p| p == pitch)
                .map(|i| {
                    COHEN_OR_TABLE_1[i]
                        .iter()
                        .map(|v| format!("{v}"))
                        .collect::<Vec<_>>()
                        .join(" / ")
                })
                .unwrap_or_default();
            out += &format!(" {ratio:.1}× | {theirs} |\n");
        }
        out
    }
}
