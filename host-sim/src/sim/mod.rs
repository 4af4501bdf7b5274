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
/// Table 1's horizontal field of view. Cohen-Or explain their pitch trend
/// by the frame's footprint on the terrain, which is bounded only when the
/// whole frame looks below the horizon. A 30° field at 4:3 is 11.3° from
/// the middle to the top edge, under the shallowest pitch (14.6°); the
/// default 60° (23.4°) would put sky in the frame there.
pub const TABLE_HFOV_DEG: f32 = 30.0;
/// Side of Table 1's built-in map: from the default eye its far edge is
/// 3600 voxels ahead, about where the 14.6° footprint ends (on a 1024² map
/// most of the frame's top would look past the edge, at sky).
pub const TABLE_MAP_SIDE: u32 = 4096;
/// Cohen-Or's Table 1 (fps on the PVS), rows by [`TABLE_PITCH`], columns by
/// [`TABLE_PROCESSORS`].
pub const COHEN_OR_TABLE_1: [[f64; 5]; 3] = [
    [0.36, 1.1, 2.5, 5.4, 11.0],
    [0.51, 1.5, 3.6, 7.6, 15.6],
    [0.53, 1.6, 3.7, 8.0, 16.3],
];

/// Table 1: a flight of `frames` views `speed` voxels apart from `start`
/// at each of [`TABLE_PITCH`] (its pitch replaced), recorded once and
/// simulated on `machine` with each of [`TABLE_PROCESSORS`]. The kernel
/// renders at its default options. `progress` hears (pitch row, frames
/// recorded) after each frame.
pub fn table(
    scene: &KernelScene,
    start: &Camera,
    size: (u32, u32),
    frames: u32,
    speed: f32,
    machine: &Machine,
    mut progress: impl FnMut(usize, usize),
) -> Result<Table> {
    let options = RenderOptions::default();
    let mut fps = Vec::new();
    for (row, &pitch) in TABLE_PITCH.iter().enumerate() {
        let cameras = flight(
            &Camera {
                pitch_deg: pitch as f32,
                ..*start
            },
            frames,
            speed,
        );
        let traces = record_flight(scene, &cameras, size, &options, machine, |done| {
            progress(row, done)
        })?;
        fps.push(
            TABLE_PROCESSORS
                .iter()
                .map(|&processors| {
                    let machine = Machine {
                        processors,
                        ..machine.clone()
                    };
                    simulate(&machine, &traces).fps()
                })
                .collect(),
        );
    }
    Ok(Table {
        processors: TABLE_PROCESSORS.to_vec(),
        pitch: TABLE_PITCH.to_vec(),
        fps,
    })
}

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
                // Three significant figures: the 2-processor column is
                // near 0.05 fps.
                if *fps < 1.0 {
                    out += &format!(" {fps:.3} |");
                } else {
                    out += &format!(" {fps:.2} |");
                }
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
