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

pub use engine::{simulate, simulate_with_sticks, FrameResult, MissReason, SimResult};
pub use machine::Machine;
pub use trace::{record_frame, record_governed_frame, FrameTrace, TileKey};

use crate::error::{Error, Result};
use crate::scene::KernelScene;
use terracast::{Camera, FrameCost, Governor, RenderOptions, View, MAX_COLOR_FETCHES_A_RAY};

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

/// The governor of a flight on `machine` whose frames' work may take
/// `share` of the frame deadline on all its workers (the rest is left for
/// copying tiles and waiting for memory and the disk), at the prices of
/// the simulator's replay ([`Machine::replay_prices`]). Refused when that
/// budget cannot set up every ray of a `size` frame.
pub fn flight_governor(machine: &Machine, share: f64, size: (u32, u32)) -> Result<Governor> {
    let seconds = machine.frame.deadline_ms * 1e-3 * share;
    let budget = machine.worker_cycles(seconds).floor().max(0.0) as u64;
    let governor = Governor::new(budget, machine.replay_prices()?);
    // The least a frame costs depends on its lines only through their
    // price (none): any camera gives it.
    let view = View::new(&Camera::default(), size.0, size.1)
        .map_err(|e| Error::new(format!("bad image size: {e}")))?;
    let least = least_frame_cost(&governor, &view, &RenderOptions::default());
    if budget < least {
        let pixels = f64::from(size.0) * f64::from(size.1);
        return Err(Error::new(format!(
            "a governed frame of {}x{} needs at least {:.0} cycles a pixel and {share} of the {} ms deadline on {} workers at {} MHz gives {:.0}: use a smaller --size, a later --deadline-ms or more --processors",
            size.0,
            size.1,
            least as f64 / pixels,
            machine.frame.deadline_ms,
            machine.workers(),
            machine.clock_mhz,
            budget as f64 / pixels,
        )));
    }
    Ok(governor)
}

/// The least a governed frame of `view` costs at `governor`'s base pass
/// prices and still shows every pixel's own ray: every ray set up and
/// shaded ([`MAX_COLOR_FETCHES_A_RAY`] color fetches), and half a step
/// each.
pub fn least_frame_cost(governor: &Governor, view: &View, options: &RenderOptions) -> u64 {
    let prices = governor.base_prices();
    let rays = u64::from(view.width())
        * u64::from(view.height())
        * u64::from(options.vertical_samples.count());
    governor.least_cost(view, options)
        + rays * u64::from(MAX_COLOR_FETCHES_A_RAY) * u64::from(prices.per_color)
        + rays * u64::from(prices.per_step) / 2
}

/// Records every view of a flight, each rendered by `governor` within its
/// budget ([`record_governed_frame`]); with each frame's cost.
pub fn record_governed_flight(
    scene: &KernelScene,
    cameras: &[Camera],
    size: (u32, u32),
    options: &RenderOptions,
    machine: &Machine,
    governor: &mut Governor,
    mut progress: impl FnMut(usize),
) -> Result<(Vec<FrameTrace>, Vec<FrameCost>)> {
    let mut traces = Vec::with_capacity(cameras.len());
    let mut costs = Vec::with_capacity(cameras.len());
    for (i, camera) in cameras.iter().enumerate() {
        let (trace, cost) = record_governed_frame(scene, camera, size, options, machine, governor)?;
        traces.push(trace);
        costs.push(cost);
        progress(i + 1);
    }
    Ok((traces, costs))
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
                    simulate_with_sticks(&machine, &traces, scene.stick_table_bytes()).fps()
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

#[cfg(test)]
mod tests {
    use super::trace::Event;
    use super::*;

    /// A governed flight whose view swings from grazing to straight down
    /// meets its deadline every frame, and every frame that has something
    /// left to buy takes about the same time, where the same flight
    /// rendered without the governor takes times five times apart; its
    /// recording holds exactly the work the governor counted, at no more
    /// than the frame's budget.
    #[test]
    fn a_governed_flight_meets_the_deadline_at_every_pitch() {
        let scene = crate::scene::procedural(256, 3).to_kernel().unwrap();
        let size = (96, 72);
        let options = RenderOptions::default();
        // A first frame that loads the tiles from disk, then the swing.
        let cameras: Vec<Camera> = [2.0, 2.0, 15.0, 30.0, 60.0, 90.0, 30.0, 2.0]
            .iter()
            .map(|&pitch| Camera {
                pitch_deg: pitch,
                ..Camera::looking([40.0, 60.0, 120.0], 35.0, 0.0)
            })
            .collect();
        let mut machine = Machine {
            processors: 8,
            ..Machine::default()
        };
        let ungoverned = record_flight(&scene, &cameras, size, &options, &machine, |_| {}).unwrap();
        let times = |result: &SimResult| -> Vec<f64> {
            result.frames[1..].iter().map(|f| f.time as f64).collect()
        };
        let spread = |times: &[f64]| {
            let (low, high) = times
                .iter()
                .fold((f64::MAX, 0f64), |(l, h), &t| (l.min(t), h.max(t)));
            high / low
        };
        let free = times(&simulate(&machine, &ungoverned));
        // A deadline half as long again as the slowest ungoverned frame
        // (ps to ms): the governor spends 0.8 of it, leaving every frame a
        // budget above its least (see `flight_governor`).
        let slowest = free.iter().copied().fold(0.0, f64::max);
        machine.frame.deadline_ms = 1.5 * slowest / 1e9;

        let mut governor = flight_governor(&machine, 0.8, size).unwrap();
        let (traces, costs) = record_governed_flight(
            &scene,
            &cameras,
            size,
            &options,
            &machine,
            &mut governor,
            |_| {},
        )
        .unwrap();
        let result = simulate(&machine, &traces);
        let governed = times(&result);
        let mut filled = Vec::new();
        for (i, (frame, cost)) in result.frames.iter().zip(&costs).enumerate().skip(1) {
            assert_eq!(frame.miss, None, "frame {i}: {frame:?}");
            let spent = cost.cost as f64 / cost.budget as f64;
            let lines = View::new(&cameras[i], size.0, size.1).unwrap().lines();
            // A frame spends its budget unless both refinement rounds
            // refined every line (a view of mostly sky).
            assert!(
                spent <= 1.0 && (spent >= 0.9 || cost.refined_lines == 2 * lines),
                "frame {i} spent {spent}: {cost:?}"
            );
            if spent >= 0.9 {
                filled.push(governed[i - 1]);
            }
        }
        assert!(
            filled.len() >= 4,
            "{} frames filled their budget",
            filled.len()
        );
        assert!(
            spread(&filled) < 1.1 && spread(&governed) * 3.0 < spread(&free),
            "frame time max/min: governed {:.2} ({:.2} over the frames that filled their budget), ungoverned {:.2}",
            spread(&governed),
            spread(&filled),
            spread(&free)
        );
        // The recording is the governor's work, priced at most its cost.
        for ((trace, cost), camera) in traces.iter().zip(&costs).zip(&cameras) {
            let events = trace.lines.iter().flatten();
            let sum = |f: fn(&Event) -> u32| events.clone().map(|e| u64::from(f(e))).sum::<u64>();
            assert_eq!(
                (sum(|e| e.rays), sum(|e| e.steps), sum(|e| e.colors)),
                (cost.work.rays, cost.work.steps, cost.work.colors)
            );
            let view = View::new(camera, size.0, size.1).unwrap();
            assert_eq!(
                trace.lines.len() as u64,
                u64::from(view.lines()) + u64::from(cost.refined_lines)
            );
            let compute: u64 = events.map(|e| engine::work_cycles(&machine, e)).sum();
            assert!(compute <= cost.cost, "{compute} cycles for {}", cost.cost);
        }
    }
}
