//! What the kernel does for each image line, recorded once through its probe and
//! replayed by the simulator on any machine.
//!
//! The kernel runs unchanged: a [`Recorder`] (a [`Probe`]) turns its events
//! into a list of [`Event`]s per line — work counts, then a run of fetches
//! from one terrain tile. The machine's costs are applied only at replay, so
//! one recording serves every machine description.

use super::footprint::footprint_tiles;
use super::machine::Machine;
use crate::error::{Error, Result};
use crate::scene::KernelScene;
use terracast::{
    level_side, render, Camera, FrameCost, Governor, Probe, RenderOptions, Sample, Sink, Surface,
    View, WithDetail, WithSticks,
};

/// A terrain tile: pyramid level and tile coordinates on that level (the
/// kernel's own key; the simulated machine's tiles are `tiles.side` a side).
pub use terracast::tiles::TileKey;

/// Work, then fetches from one tile.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Event {
    /// Rays set up.
    pub rays: u32,
    /// Traversal steps and bound tests.
    pub steps: u32,
    /// Hits shaded.
    pub colors: u32,
    /// The tile the fetches read.
    pub tile: TileKey,
    /// Voxels (or bounds) fetched from it.
    pub fetches: u32,
}

/// One frame's recording.
#[derive(Debug, Clone)]
pub struct FrameTrace {
    /// Events of each image line (see [`View::lines`]).
    pub lines: Vec<Vec<Event>>,
    /// The tiles the master loads for the frame: its footprint.
    pub footprint: Vec<TileKey>,
    /// Tiles the master tested to find the footprint.
    pub tiles_tested: u64,
}

/// Records the kernel's events of one line.
#[derive(Debug)]
pub struct Recorder<'a> {
    /// Width of each level's voxel grid.
    widths: &'a [u32],
    tile_side: u32,
    current: Option<Event>,
    /// The recording so far.
    pub events: Vec<Event>,
    pending: (u32, u32, u32),
}

impl<'a> Recorder<'a> {
    /// A recorder for a pyramid whose level grids are `widths` wide.
    pub fn new(widths: &'a [u32], tile_side: u32) -> Self {
        Self {
            widths,
            tile_side,
            current: None,
            events: Vec::new(),
            pending: (0, 0, 0),
        }
    }

    fn fetch(&mut self, level: u8, index: usize, row_width: u32, voxels: u32) {
        let row_width = row_width.max(1) as usize;
        let tile = TileKey {
            level,
            x: (index % row_width) as u32 / self.tile_side,
            y: (index / row_width) as u32 / self.tile_side,
        };
        match &mut self.current {
            Some(event) if event.tile == tile => {
                let (rays, steps, colors) = std::mem::take(&mut self.pending);
                event.rays += rays;
                event.steps += steps;
                event.colors += colors;
                event.fetches += voxels;
            }
            _ => {
                if let Some(done) = self.current.take() {
                    self.events.push(done);
                }
                let (rays, steps, colors) = std::mem::take(&mut self.pending);
                self.current = Some(Event {
                    rays,
                    steps,
                    colors,
                    tile,
                    fetches: voxels,
                });
            }
        }
    }

    fn width(&self, level: u8) -> u32 {
        self.widths.get(usize::from(level)).copied().unwrap_or(1)
    }

    /// Ends the line: every event recorded.
    pub fn finish(&mut self) -> Vec<Event> {
        if let Some(done) = self.current.take() {
            self.events.push(done);
        }
        // Work after the last fetch (a ray that saw sky at once) joins the
        // last event; a line with no fetch at all keeps it on a tile of
        // its own.
        let (rays, steps, colors) = std::mem::take(&mut self.pending);
        match self.events.last_mut() {
            Some(last) => {
                last.rays += rays;
                last.steps += steps;
                last.colors += colors;
            }
            None if rays + steps + colors > 0 => self.events.push(Event {
                rays,
                steps,
                colors,
                tile: TileKey {
                    level: 0,
                    x: 0,
                    y: 0,
                },
                fetches: 0,
            }),
            None => {}
        }
        std::mem::take(&mut self.events)
    }

    /// Adds work to the event being recorded (or the next one).
    fn work(&mut self, rays: u32, steps: u32, colors: u32) {
        self.pending.0 += rays;
        self.pending.1 += steps;
        self.pending.2 += colors;
    }
}

impl Probe for Recorder<'_> {
    fn visit(&mut self, level: u8, voxel: usize) {
        self.work(0, 1, 0);
        // The voxel and its neighbour across the minor grid line.
        self.fetch(level, voxel, self.width(level), 2);
    }

    fn bound(&mut self, level: u8, cell: usize) {
        self.work(0, 1, 0);
        self.fetch(level, cell, self.width(level).saturating_sub(1), 1);
    }

    fn color(&mut self, level: u8, voxel: usize) {
        self.work(0, 0, 1);
        self.fetch(level, voxel, self.width(level), 2);
    }

    fn color_square(&mut self, level: u8, corner: usize) {
        self.work(0, 0, 1);
        // Charged to the first corner's tile, as a pair is to its first.
        self.fetch(level, corner, self.width(level), 4);
    }

    fn ray(&mut self) {
        self.work(1, 0, 0);
    }
}

/// A sink that keeps nothing: the simulator needs the kernel's work, not
/// its pixels.
#[derive(Debug)]
pub(crate) struct Discard;

impl Sink for Discard {
    fn put(&mut self, _x: u32, _y: u32, _sample: Sample) {}
}

/// Records every line of a view.
pub fn record_frame(
    scene: &KernelScene,
    camera: &Camera,
    size: (u32, u32),
    options: &RenderOptions,
    machine: &Machine,
) -> Result<FrameTrace> {
    Ok(record(scene, camera, size, machine, FrameRender::Plain(options))?.0)
}

/// Records a view that `governor` renders within its budget (see
/// [`Governor::render`]): each line of its base pass, then each line its
/// refinement renders again, one task of the pool each, in that order;
/// with the frame's cost at the governor's prices.
pub fn record_governed_frame(
    scene: &KernelScene,
    camera: &Camera,
    size: (u32, u32),
    options: &RenderOptions,
    machine: &Machine,
    governor: &mut Governor,
) -> Result<(FrameTrace, FrameCost)> {
    let (trace, cost) = record(
        scene,
        camera,
        size,
        machine,
        FrameRender::Governed(options, governor),
    )?;
    let cost = cost.ok_or_else(|| Error::new("a governed render gave no cost"))?;
    Ok((trace, cost))
}

/// How a recorded frame is rendered: as `render` does, or within a
/// governor's budget.
enum FrameRender<'a> {
    Plain(&'a RenderOptions),
    Governed(&'a RenderOptions, &'a mut Governor),
}

impl FrameRender<'_> {
    fn options(&self) -> &RenderOptions {
        match self {
            Self::Plain(options) | Self::Governed(options, _) => options,
        }
    }

    /// Renders `view` of `surface` into nothing, its events into `lines`;
    /// the frame's cost where a governor rendered it.
    fn run<T: Surface + ?Sized>(
        self,
        surface: &T,
        view: &View,
        lines: &mut LineRecorder<'_>,
    ) -> Option<FrameCost> {
        match self {
            Self::Plain(options) => {
                render(surface, view, options, &mut Discard, lines);
                None
            }
            Self::Governed(options, governor) => {
                Some(governor.render(surface, view, options, &mut Discard, lines))
            }
        }
    }
}

/// A frame's recording, line by line as the render reports them
/// ([`Probe::line`]) on the scene's pyramid (with its objects' sticks,
/// when it has any), and the footprint; with the governed render's cost.
fn record(
    scene: &KernelScene,
    camera: &Camera,
    size: (u32, u32),
    machine: &Machine,
    frame_render: FrameRender<'_>,
) -> Result<(FrameTrace, Option<FrameCost>)> {
    let pyramid = scene.pyramid_for(frame_render.options())?;
    let sticks = scene.sticks()?;
    let view =
        View::new(camera, size.0, size.1).map_err(|e| Error::new(format!("bad view: {e}")))?;
    let base = pyramid.base();
    let widths: Vec<u32> = (0..pyramid.levels())
        .map(|l| level_side(base.width(), l as u32))
        .collect();
    let mut lines = LineRecorder {
        recorder: Recorder::new(&widths, machine.tiles.side),
        lines: Vec::with_capacity(view.lines() as usize),
        started: false,
    };
    let details = scene.details()?;
    let cost = match sticks {
        Some(layer) => frame_render.run(&WithSticks::new(&pyramid, layer), &view, &mut lines),
        None if !details.is_empty() => {
            frame_render.run(&WithDetail::new(&pyramid, &details), &view, &mut lines)
        }
        None => frame_render.run(&pyramid, &view, &mut lines),
    };
    let (footprint, tiles_tested) = footprint_tiles(
        camera,
        size,
        (base.width(), base.depth()),
        pyramid.levels(),
        machine.tiles.side,
    );
    let trace = FrameTrace {
        lines: lines.finish(),
        footprint,
        tiles_tested,
    };
    Ok((trace, cost))
}

/// A [`Recorder`] for a whole frame: each line the kernel starts
/// ([`Probe::line`]) ends the one before.
struct LineRecorder<'a> {
    recorder: Recorder<'a>,
    lines: Vec<Vec<Event>>,
    started: bool,
}

impl LineRecorder<'_> {
    fn finish(mut self) -> Vec<Vec<Event>> {
        if self.started {
            self.lines.push(self.recorder.finish());
        }
        self.lines
    }
}

impl Probe for LineRecorder<'_> {
    fn visit(&mut self, level: u8, voxel: usize) {
        self.recorder.visit(level, voxel);
    }
    fn bound(&mut self, level: u8, cell: usize) {
        self.recorder.bound(level, cell);
    }
    fn color(&mut self, level: u8, voxel: usize) {
        self.recorder.color(level, voxel);
    }
    fn color_square(&mut self, level: u8, corner: usize) {
        self.recorder.color_square(level, corner);
    }
    fn ray(&mut self) {
        self.recorder.ray();
    }
    fn line(&mut self, _index: u32) {
        if self.started {
            self.lines.push(self.recorder.finish());
        }
        self.started = true;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use terracast::{render, CountingProbe, Pyramid};

    #[test]
    fn the_recording_holds_all_of_the_kernels_work() {
        let scene = crate::scene::procedural(256, 2).to_kernel().unwrap();
        let camera = terracast::Camera::looking([128.0, 20.0, 90.0], 90.0, 25.0);
        let options = RenderOptions::default();
        let machine = Machine::default();
        let trace = record_frame(&scene, &camera, (80, 60), &options, &machine).unwrap();
        let mut counts = CountingProbe::default();
        let view = View::new(&camera, 80, 60).unwrap();
        render(
            &scene.pyramid_for(&options).unwrap(),
            &view,
            &options,
            &mut Discard,
            &mut counts,
        );
        let events = trace.lines.iter().flatten();
        let sum = |f: fn(&Event) -> u32| events.clone().map(|e| u64::from(f(e))).sum::<u64>();
        assert_eq!(sum(|e| e.rays), counts.rays);
        assert_eq!(sum(|e| e.steps), counts.steps);
        assert_eq!(sum(|e| e.colors), counts.color_fetches);
        // Fetched voxels: two a step, one a bound, two a color pair and
        // four a color square (the far hits' footprint colors).
        #[derive(Default)]
        struct Colors {
            pairs: u64,
            squares: u64,
        }
        impl Probe for Colors {
            fn color(&mut self, _: u8, _: usize) {
                self.pairs += 1;
            }
            fn color_square(&mut self, _: u8, _: usize) {
                self.squares += 1;
            }
        }
        let mut colors = Colors::default();
        render(
            &scene.pyramid_for(&options).unwrap(),
            &view,
            &options,
            &mut Discard,
            &mut colors,
        );
        assert!(
            colors.squares > 0 && colors.pairs > 0,
            "{} squares, {} pairs",
            colors.squares,
            colors.pairs
        );
        let walk_steps = counts.steps - counts.bound_tests;
        assert_eq!(
            sum(|e| e.fetches),
            2 * walk_steps + counts.bound_tests + 2 * colors.pairs + 4 * colors.squares
        );
        assert_eq!(trace.lines.len() as u32, view.lines());
        // Each event names the tile its fetches read, inside the map.
        let side = machine.tiles.side;
        assert!(events
            .clone()
            .all(|e| e.tile.x <= 256 / side && e.tile.y <= 256 / side));
        assert!(!trace.footprint.is_empty());
    }

    #[test]
    fn a_scene_with_objects_is_recorded_as_the_kernel_renders_it_with_its_sticks() {
        let bare = crate::scene::procedural(256, 2);
        let mut planted = bare.clone();
        planted.plant_objects(2);
        let (bare, planted) = (bare.to_kernel().unwrap(), planted.to_kernel().unwrap());
        // Over the map's middle, where the seeded rule plants.
        let camera = terracast::Camera::looking([128.0, 20.0, 60.0], 90.0, 20.0);
        let options = RenderOptions::default();
        let machine = Machine::default();
        let view = View::new(&camera, 80, 60).unwrap();
        let totals = |trace: &FrameTrace| {
            let events = trace.lines.iter().flatten();
            (
                events.clone().map(|e| u64::from(e.rays)).sum::<u64>(),
                events.clone().map(|e| u64::from(e.steps)).sum::<u64>(),
                events.map(|e| u64::from(e.colors)).sum::<u64>(),
            )
        };
        let pyramid: Pyramid<'_> = planted.pyramid_for(&options).unwrap();
        let layer = planted.sticks().unwrap().expect("the scene has objects");
        let mut counts = CountingProbe::default();
        render(
            &WithSticks::new(&pyramid, layer),
            &view,
            &options,
            &mut Discard,
            &mut counts,
        );
        let with_objects =
            totals(&record_frame(&planted, &camera, (80, 60), &options, &machine).unwrap());
        assert_eq!(
            with_objects,
            (counts.rays, counts.steps, counts.color_fetches)
        );
        // The objects change the work: it is not the bare map's.
        let without = totals(&record_frame(&bare, &camera, (80, 60), &options, &machine).unwrap());
        assert_ne!(with_objects, without);
        assert_eq!(bare.stick_table_bytes(), 0);
        assert!(planted.stick_table_bytes() > 0);
    }
}
