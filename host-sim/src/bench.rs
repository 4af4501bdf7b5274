//! `terracast-sim bench`: every method and setting on a fixed suite of
//! views, measured against the exact reference in the same process, speed
//! charted against accuracy.
//!
//! Speed is single-threaded Mpx/s of the render call alone, the best of a
//! few runs (the machines here are shared; the best run is the least
//! disturbed), taken in rounds over all settings of a view so that a
//! change of load disturbs every setting alike. Accuracy is PSNR and SSIM
//! of the colors, sky agreement, and the median and 95th percentile of the
//! relative depth error.

use crate::baselines::{
    march, march_touching, voxel_space, voxel_space_touching, MarchOptions, VoxelSpaceOptions,
};
use crate::error::{Error, Result};
use crate::frame::{Frame, RenderStats};
use crate::kernel::{render_kernel_with, time_kernel, PixelRays};
use crate::metrics::{
    mean_abs_difference, psnr, relative_depth_error_quantile, sky_agreement, ssim,
};
use crate::reference::{Reference, ReferenceOptions};
use crate::scene::{KernelScene, Scene};
use crate::sim::trace::Discard;
use crate::volume::{render_volume, render_volume_touching, Mode, TerrainVolume, VolumeOptions};
use std::collections::HashSet;
use std::fmt::Write as _;
use std::sync::OnceLock;
use terracast::{
    Camera, Coherence, HeightPath, Probe, RenderOptions, Resolution, Shading, VerticalSamples,
    View, U8F8,
};

/// One way of rendering.
#[derive(Debug, Clone)]
pub enum Method {
    /// The kernel with these options and rays a pixel.
    Kernel(RenderOptions, PixelRays),
    /// Voxel Space with this slice-spacing growth.
    VoxelSpace(f64),
    /// The fixed-step march with this step.
    March(f64),
    /// Qu et al.'s filtered volume, accurate or by its boundary array
    /// alone, with the default filter, layers and sampling interval.
    Volume(Mode),
}

/// A method and its setting, named for tables and the chart.
#[derive(Debug, Clone)]
pub struct Setting {
    /// Short name (CSV and chart).
    pub name: &'static str,
    /// What renders.
    pub method: Method,
}

/// The settings every bench run measures.
pub fn settings() -> Vec<Setting> {
    let default = RenderOptions::default();
    let kernel = |name, options| Setting {
        name,
        method: Method::Kernel(options, PixelRays::Fixed),
    };
    vec![
        kernel("kernel", default),
        kernel(
            "kernel without terrain fit",
            RenderOptions {
                terrain_fit: false,
                ..default
            },
        ),
        kernel(
            "kernel coherence off",
            RenderOptions {
                coherence: Coherence::Off,
                ..default
            },
        ),
        kernel(
            "kernel single resolution",
            RenderOptions {
                resolution: Resolution::Single,
                ..default
            },
        ),
        kernel(
            "kernel pixel-to-voxel 0.5",
            RenderOptions {
                resolution: Resolution::Multi {
                    pixel_to_voxel: U8F8::from_num(0.5),
                },
                ..default
            },
        ),
        kernel(
            "kernel pixel-to-voxel 2",
            RenderOptions {
                resolution: Resolution::Multi {
                    pixel_to_voxel: U8F8::from_num(2),
                },
                ..default
            },
        ),
        kernel(
            "kernel 4 vertical samples",
            RenderOptions {
                vertical_samples: VerticalSamples::Four,
                ..default
            },
        ),
        Setting {
            name: "kernel rays by footprint",
            method: Method::Kernel(default, PixelRays::ByFootprint),
        },
        kernel(
            "kernel nearest color",
            RenderOptions {
                shading: Shading::Nearest,
                ..default
            },
        ),
        kernel(
            "kernel level-0 colors",
            RenderOptions {
                shading: Shading::LevelZero,
                ..default
            },
        ),
        kernel(
            "kernel heights on each ray's path",
            RenderOptions {
                height_path: HeightPath::Ray,
                ..default
            },
        ),
        kernel(
            "kernel level-0 colors and heights on each ray's path",
            RenderOptions {
                shading: Shading::LevelZero,
                height_path: HeightPath::Ray,
                ..default
            },
        ),
        kernel(
            "kernel highest quality",
            RenderOptions {
                resolution: Resolution::Single,
                vertical_samples: VerticalSamples::Eight,
                ..default
            },
        ),
        Setting {
            name: "voxelspace",
            method: Method::VoxelSpace(0.005),
        },
        Setting {
            name: "voxelspace growth 0.02",
            method: Method::VoxelSpace(0.02),
        },
        Setting {
            name: "march 0.5",
            method: Method::March(0.5),
        },
        Setting {
            name: "march 2",
            method: Method::March(2.0),
        },
        Setting {
            name: "volume",
            method: Method::Volume(Mode::Accurate),
        },
        Setting {
            name: "boundary",
            method: Method::Volume(Mode::Approximate),
        },
    ]
}

/// A scene of the suite.
#[derive(Debug)]
pub struct BenchScene {
    /// Name for tables.
    pub name: String,
    /// The float scene (reference and baselines).
    pub scene: Scene,
    /// The kernel's form of it.
    pub kernel: KernelScene,
    /// Its filtered volume (`volume`, `boundary`), made when first asked
    /// for.
    pub volume: OnceLock<TerrainVolume>,
}

impl BenchScene {
    /// `scene` named `name`, in the kernel's form too.
    pub fn new(name: String, scene: Scene) -> Result<Self> {
        let kernel = scene.to_kernel()?;
        Ok(Self {
            name,
            scene,
            kernel,
            volume: OnceLock::new(),
        })
    }

    /// The scene's volume with the default filter and layers.
    pub fn volume(&self) -> &TerrainVolume {
        self.volume
            .get_or_init(|| TerrainVolume::build(&self.scene, &VolumeOptions::default()))
    }
}

/// One view of the suite.
#[derive(Debug, Clone)]
pub struct BenchView {
    /// Index into the scenes.
    pub scene: usize,
    /// Name for tables.
    pub name: String,
    /// The camera.
    pub camera: Camera,
}

/// The suite's views of `scene`: from over its south edge at pitch 0°,
/// 5°, 15°, 30° and 60° (far), and from low inside the map (near).
pub fn views(index: usize, scene: &Scene) -> Vec<BenchView> {
    let (w, d) = (scene.width as f32, scene.depth as f32);
    let far = scene.default_eye();
    let mut views: Vec<BenchView> = [0.0f32, 5.0, 15.0, 30.0, 60.0]
        .iter()
        .map(|&pitch| BenchView {
            scene: index,
            name: format!("far pitch {pitch}"),
            camera: Camera::looking(far, 90.0, pitch),
        })
        .collect();
    let (nx, ny) = (w * 0.35, d * 0.4);
    let ground = scene.height(nx as usize, ny as usize);
    views.push(BenchView {
        scene: index,
        name: "near pitch 10".into(),
        camera: Camera::looking([nx, ny, ground + 25.0], 60.0, 10.0),
    });
    views
}

/// One setting on one view.
#[derive(Debug, Clone, PartialEq)]
pub struct Measure {
    /// Scene name.
    pub scene: String,
    /// View name.
    pub view: String,
    /// Pitch of the view.
    pub pitch: f32,
    /// Setting name.
    pub setting: &'static str,
    /// Colors against the reference, dB.
    pub psnr: f64,
    /// Luma structure against the reference.
    pub ssim: f64,
    /// Share of pixels agreeing on sky or terrain.
    pub sky_agreement: f64,
    /// Relative depth error, median and 95th percentile (NaN when no pixel
    /// sees terrain in both).
    pub depth_median: f64,
    /// See `depth_median`.
    pub depth_p95: f64,
    /// Traversal steps a pixel (method-specific: voxel visits, slice
    /// samples, march samples).
    pub steps_per_pixel: f64,
    /// Single-threaded speed, best of the runs.
    pub mpx_per_s: f64,
    /// Terrain bytes the method holds.
    pub resident_bytes: u64,
    /// Terrain bytes the frame read: distinct voxels (and bounds) read,
    /// times their bytes in the method's storage (see [`bytes_touched`]).
    pub bytes_touched: u64,
}

fn render(
    setting: &Setting,
    scene: &BenchScene,
    camera: &Camera,
    size: (u32, u32),
    sky: terracast::Rgb,
) -> Result<(Frame, RenderStats)> {
    Ok(match &setting.method {
        Method::Kernel(options, rays) => render_kernel_with(
            &scene.kernel,
            camera,
            size.0,
            size.1,
            &RenderOptions { sky, ..*options },
            *rays,
        )?,
        Method::VoxelSpace(growth) => voxel_space(
            &scene.scene,
            camera,
            size.0,
            size.1,
            &VoxelSpaceOptions {
                spacing_growth: *growth,
                sky,
            },
        ),
        Method::March(step) => march(
            &scene.scene,
            camera,
            size.0,
            size.1,
            &MarchOptions { step: *step, sky },
        ),
        Method::Volume(mode) => render_volume(
            &scene.scene,
            scene.volume(),
            camera,
            size,
            &VolumeOptions {
                sky,
                ..VolumeOptions::default()
            },
            *mode,
        ),
    })
}

/// Records every distinct terrain element the kernel reads.
#[derive(Debug, Default)]
struct TouchProbe {
    heights: HashSet<(u8, usize)>,
    colors: HashSet<(u8, usize)>,
    color_squares: HashSet<(u8, usize)>,
    bounds: HashSet<(u8, usize)>,
}

impl TouchProbe {
    /// The bytes of what was read (see [`bytes_touched`]).
    fn bytes(&self) -> u64 {
        self.heights.len() as u64 * 4
            + self.colors.len() as u64 * 6
            + self.color_squares.len() as u64 * 12
            + self.bounds.len() as u64 * 2
    }
}

impl Probe for TouchProbe {
    fn visit(&mut self, level: u8, voxel: usize) {
        self.heights.insert((level, voxel));
    }
    fn bound(&mut self, level: u8, cell: usize) {
        self.bounds.insert((level, cell));
    }
    fn color(&mut self, level: u8, voxel: usize) {
        self.colors.insert((level, voxel));
    }
    fn color_square(&mut self, level: u8, corner: usize) {
        self.color_squares.insert((level, corner));
    }
}

/// Terrain bytes a frame reads, by method:
/// - kernel: each visit reads two U12.4 heights (the voxel and its
///   neighbour across the minor grid line), each shading two RGB colors
///   (the same pair) or, past the color reach, four (a grid square), each
///   bound test one u16; distinct (level, index) pairs, neighbours counted
///   with each;
/// - Voxel Space: an f32 height and an RGB color for each distinct voxel;
/// - march: the four corners (f32 height and RGB color) of each distinct
///   cell sampled.
pub fn bytes_touched(
    setting: &Setting,
    scene: &BenchScene,
    camera: &Camera,
    size: (u32, u32),
) -> Result<u64> {
    let sky = terracast::config::DEFAULT_SKY;
    Ok(match &setting.method {
        Method::Kernel(options, rays) => {
            let pyramid = scene.kernel.pyramid_for(options)?;
            let view = View::new(camera, size.0, size.1)
                .map_err(|e| Error::new(format!("bad view: {e}")))?;
            let mut probe = TouchProbe::default();
            rays.render(&pyramid, &view, options, &mut Discard, &mut probe);
            probe.bytes()
        }
        Method::VoxelSpace(growth) => {
            let mut seen = HashSet::new();
            let options = VoxelSpaceOptions {
                spacing_growth: *growth,
                sky,
            };
            voxel_space_touching(&scene.scene, camera, size.0, size.1, &options, &mut |v| {
                seen.insert(v);
            });
            seen.len() as u64 * 7
        }
        Method::March(step) => {
            let mut seen = HashSet::new();
            let options = MarchOptions { step: *step, sky };
            let width = scene.scene.width as usize;
            march_touching(&scene.scene, camera, size.0, size.1, &options, &mut |v| {
                for corner in [v, v + 1, v + width, v + width + 1] {
                    seen.insert(corner);
                }
            });
            seen.len() as u64 * 7
        }
        Method::Volume(mode) => {
            let mut seen = HashSet::new();
            let options = VolumeOptions::default();
            let volume = scene.volume();
            render_volume_touching(
                &scene.scene,
                volume,
                camera,
                size,
                &options,
                *mode,
                &mut |column, layer| {
                    seen.insert((column, layer));
                },
            );
            let columns = seen.iter().map(|&(c, _)| c).collect::<HashSet<_>>().len() as u64;
            // The boundary array's entry and the color of each column; the
            // accurate mode also each cell's eight densities.
            columns * 7
                + match mode {
                    Mode::Accurate => seen.len() as u64 * 8,
                    Mode::Approximate => 0,
                }
        }
    })
}

/// A setting's timed runs on a view add up to this much render time at
/// least (ns), beyond the `repeats` every setting gets.
pub const TIMED_NS: u64 = 60_000_000;

/// The timed runs of one setting on one view so far.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Timing {
    runs: u32,
    spent_ns: u64,
    best: u64,
}

impl Default for Timing {
    fn default() -> Self {
        Self {
            runs: 0,
            spent_ns: 0,
            best: u64::MAX,
        }
    }
}

impl Timing {
    /// With one more run, of `ns`.
    fn with(self, ns: u64) -> Self {
        Self {
            runs: self.runs + 1,
            spent_ns: self.spent_ns.saturating_add(ns),
            best: self.best.min(ns),
        }
    }

    /// At least `repeats` runs, adding up to [`TIMED_NS`] at least.
    fn enough(&self, repeats: u32) -> bool {
        self.runs >= repeats && self.spent_ns >= TIMED_NS
    }
}

/// Measures every setting on every view; `progress(done, total)` after
/// each view.
pub fn run(
    scenes: &[BenchScene],
    views: &[BenchView],
    size: (u32, u32),
    repeats: u32,
    mut progress: impl FnMut(usize, usize),
) -> Result<Vec<Measure>> {
    let sky = terracast::config::DEFAULT_SKY;
    let settings = settings();
    let mut measures = Vec::new();
    for (done, view) in views.iter().enumerate() {
        let scene = scenes
            .get(view.scene)
            .ok_or_else(|| Error::new("bench view names a missing scene"))?;
        let (exact, _) = Reference::new(&scene.scene).render(
            &view.camera,
            size.0,
            size.1,
            &ReferenceOptions {
                supersample: 3,
                sky,
                ..ReferenceOptions::default()
            },
        );
        let mut renders = Vec::with_capacity(settings.len());
        for setting in &settings {
            renders.push(render(setting, scene, &view.camera, size, sky)?);
        }
        // The timed runs go round the settings, so that a change in the
        // shared machine's load falls on all of them alike. The kernel's
        // render above counted its work with a probe: its times are
        // renders without one, as a user's render runs. Every setting
        // runs `repeats` times at least, and a fast one until its runs
        // add up to `TIMED_NS`: a render of a millisecond or two meets
        // the machine's noise in each of a few runs.
        let mut timings: Vec<Timing> = settings
            .iter()
            .zip(&renders)
            .map(|(setting, (_, stats))| match setting.method {
                Method::Kernel(..) => Timing::default(),
                // Its render above was its first timed run.
                _ => Timing::default().with(stats.render_ns),
            })
            .collect();
        loop {
            let mut timed_any = false;
            for (setting, timing) in settings.iter().zip(&mut timings) {
                if timing.enough(repeats) {
                    continue;
                }
                let time = match &setting.method {
                    Method::Kernel(options, rays) => {
                        let options = RenderOptions { sky, ..*options };
                        time_kernel(&scene.kernel, &view.camera, size, &options, *rays)?
                    }
                    _ => render(setting, scene, &view.camera, size, sky)?.1.render_ns,
                };
                *timing = timing.with(time);
                timed_any = true;
            }
            if !timed_any {
                break;
            }
        }
        let best = timings.iter().map(|t| t.best);
        for ((setting, (frame, stats)), best) in settings.iter().zip(renders).zip(best) {
            let pixels = stats.pixels as f64;
            measures.push(Measure {
                scene: scene.name.clone(),
                view: view.name.clone(),
                pitch: view.camera.pitch_deg,
                setting: setting.name,
                psnr: psnr(&frame.colors, &exact.colors),
                ssim: ssim(&frame.colors, &exact.colors, size.0, size.1).unwrap_or(f64::NAN),
                sky_agreement: sky_agreement(&frame.depth, &exact.depth),
                depth_median: relative_depth_error_quantile(&frame.depth, &exact.depth, 0.5)
                    .unwrap_or(f64::NAN),
                depth_p95: relative_depth_error_quantile(&frame.depth, &exact.depth, 0.95)
                    .unwrap_or(f64::NAN),
                steps_per_pixel: stats.steps as f64 / pixels,
                mpx_per_s: pixels / (best.max(1) as f64 / 1e9) / 1e6,
                resident_bytes: stats.resident_bytes,
                bytes_touched: bytes_touched(setting, scene, &view.camera, size)?,
            });
        }
        progress(done + 1, views.len());
    }
    Ok(measures)
}

/// A setting over the whole suite.
#[derive(Debug, Clone, PartialEq)]
pub struct Summary {
    /// Setting name.
    pub setting: &'static str,
    /// Mean PSNR over the views (identical views count as 99 dB).
    pub psnr: f64,
    /// Mean SSIM.
    pub ssim: f64,
    /// Mean sky agreement.
    pub sky_agreement: f64,
    /// Mean steps a pixel.
    pub steps_per_pixel: f64,
    /// All pixels over all render time (the harmonic mean of the views'
    /// speeds).
    pub mpx_per_s: f64,
    /// On the Pareto front of speed and PSNR.
    pub pareto: bool,
    /// Mean terrain KiB a frame reads.
    pub kib_touched: f64,
    /// Frame-to-frame change along a flight minus the reference's (0–255
    /// a channel; 0 is as steady as the exact picture), when measured.
    pub flicker: Option<f64>,
}

/// Per-setting summaries, Pareto front marked (no other setting is both
/// faster and more accurate).
pub fn summarize(measures: &[Measure]) -> Vec<Summary> {
    let mut out: Vec<Summary> = Vec::new();
    for setting in settings() {
        let mine: Vec<&Measure> = measures
            .iter()
            .filter(|m| m.setting == setting.name)
            .collect();
        if mine.is_empty() {
            continue;
        }
        let n = mine.len() as f64;
        let mean = |f: fn(&Measure) -> f64| mine.iter().map(|m| f(m)).sum::<f64>() / n;
        out.push(Summary {
            setting: setting.name,
            psnr: mean(|m| m.psnr.min(99.0)),
            ssim: mean(|m| m.ssim),
            sky_agreement: mean(|m| m.sky_agreement),
            steps_per_pixel: mean(|m| m.steps_per_pixel),
            kib_touched: mean(|m| m.bytes_touched as f64 / 1024.0),
            mpx_per_s: n / mine.iter().map(|m| 1.0 / m.mpx_per_s).sum::<f64>(),
            pareto: false,
            flicker: None,
        });
    }
    let points: Vec<(f64, f64)> = out.iter().map(|s| (s.mpx_per_s, s.psnr)).collect();
    for (i, s) in out.iter_mut().enumerate() {
        s.pareto = !points.iter().enumerate().any(|(j, &(speed, quality))| {
            j != i
                && speed >= points[i].0
                && quality >= points[i].1
                && (speed > points[i].0 || quality > points[i].1)
        });
    }
    out
}

/// Flicker of every setting: on each scene, a flight of `frames` frames
/// from the far pitch-15° view, the eye advancing one voxel a frame; the
/// mean frame-to-frame change of the setting minus the reference's,
/// averaged over the scenes.
pub fn flicker(
    scenes: &[BenchScene],
    size: (u32, u32),
    frames: u32,
    mut progress: impl FnMut(usize, usize),
) -> Result<Vec<(&'static str, f64)>> {
    let sky = terracast::config::DEFAULT_SKY;
    let settings = settings();
    let mut sums = vec![0.0; settings.len()];
    for (done, scene) in scenes.iter().enumerate() {
        let start = views(0, &scene.scene)
            .into_iter()
            .find(|v| v.camera.pitch_deg == 15.0)
            .ok_or_else(|| Error::new("the suite has no pitch-15 view"))?
            .camera;
        let cameras = crate::sim::flight(&start, frames, 1.0);
        let change = |frames: &[Vec<terracast::Rgb>]| {
            frames
                .windows(2)
                .map(|pair| mean_abs_difference(&pair[0], &pair[1]))
                .sum::<f64>()
                / (frames.len().max(2) - 1) as f64
        };
        let reference = Reference::new(&scene.scene);
        let exact: Vec<_> = cameras
            .iter()
            .map(|c| {
                let options = ReferenceOptions {
                    supersample: 3,
                    sky,
                    ..ReferenceOptions::default()
                };
                reference.render(c, size.0, size.1, &options).0.colors
            })
            .collect();
        let exact_change = change(&exact);
        for (sum, setting) in sums.iter_mut().zip(&settings) {
            let rendered = cameras
                .iter()
                .map(|c| Ok(render(setting, scene, c, size, sky)?.0.colors))
                .collect::<Result<Vec<_>>>()?;
            *sum += change(&rendered) - exact_change;
        }
        progress(done + 1, scenes.len());
    }
    let n = scenes.len().max(1) as f64;
    Ok(settings
        .iter()
        .zip(sums)
        .map(|(s, sum)| (s.name, sum / n))
        .collect())
}

/// `text` as one CSV field: quoted where it holds a comma, a quote or a
/// line break (RFC 4180), as a scene named after a file may.
fn csv_field(text: &str) -> std::borrow::Cow<'_, str> {
    if text.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", text.replace('"', "\"\"")).into()
    } else {
        text.into()
    }
}

/// The measures as CSV, one row per view and setting.
pub fn csv(measures: &[Measure]) -> String {
    let mut out = String::from(
        "scene,view,pitch,setting,psnr_db,ssim,sky_agreement,depth_error_median,depth_error_p95,steps_per_pixel,mpx_per_s,resident_bytes,bytes_touched\n",
    );
    for m in measures {
        let _ = writeln!(
            out,
            "{},{},{},{},{:.3},{:.4},{:.4},{:.5},{:.5},{:.3},{:.3},{},{}",
            csv_field(&m.scene),
            csv_field(&m.view),
            m.pitch,
            csv_field(m.setting),
            m.psnr.min(99.0),
            m.ssim,
            m.sky_agreement,
            m.depth_median,
            m.depth_p95,
            m.steps_per_pixel,
            m.mpx_per_s,
            m.resident_bytes,
            m.bytes_touched
        );
    }
    out
}

/// The summary as a Markdown table.
pub fn summary_table(summaries: &[Summary]) -> String {
    let mut out = String::from(
        "| setting | Mpx/s | PSNR dB | SSIM | sky agreement | steps/px | KiB read | flicker | Pareto |\n|---|---|---|---|---|---|---|---|---|\n",
    );
    for s in summaries {
        let _ = writeln!(
            out,
            "| {} | {:.2} | {:.2} | {:.3} | {:.3} | {:.2} | {:.0} | {} | {} |",
            s.setting,
            s.mpx_per_s,
            s.psnr,
            s.ssim,
            s.sky_agreement,
            s.steps_per_pixel,
            s.kib_touched,
            s.flicker.map_or("–".to_string(), |f| format!("{f:+.2}")),
            if s.pareto { "yes" } else { "" }
        );
    }
    out
}

/// Map side past which the command summarizes a scene apart: the 4096²
/// map's far views reach the distances the pyramid's levels are built
/// for, the smaller maps' do not.
pub const LARGE_MAP_SIDE: u32 = 1024;

/// The measures of maps up to [`LARGE_MAP_SIDE`] a side, and of larger
/// maps (a map's larger side decides), for the command's split summaries:
/// which setting wins depends on how far the terrain reaches. A measure of
/// a scene not in `scenes` is in neither.
pub fn split_by_map_size(measures: &[Measure], scenes: &[BenchScene]) -> [Vec<Measure>; 2] {
    let side = |name: &str| {
        scenes
            .iter()
            .find(|s| s.name == name)
            .map(|s| s.scene.width.max(s.scene.depth))
    };
    let part = |large: bool| {
        measures
            .iter()
            .filter(|m| side(&m.scene).is_some_and(|side| (side > LARGE_MAP_SIDE) == large))
            .cloned()
            .collect()
    };
    [part(false), part(true)]
}

/// At pitch 0, `setting` against Voxel Space over the same views,
/// measured in this run: (speed ratio, the setting's PSNR, Voxel Space's
/// PSNR), means over the views (the speeds harmonic); `None` where the
/// run has no such views.
pub fn against_voxel_space_at_pitch_0(
    measures: &[Measure],
    setting: &str,
) -> Option<(f64, f64, f64)> {
    let at = |name: &str| -> Vec<&Measure> {
        measures
            .iter()
            .filter(|m| m.setting == name && m.pitch == 0.0)
            .collect()
    };
    let (kernel, voxel) = (at(setting), at("voxelspace"));
    if kernel.is_empty() || kernel.len() != voxel.len() {
        return None;
    }
    let time = |ms: &[&Measure]| ms.iter().map(|m| 1.0 / m.mpx_per_s).sum::<f64>();
    let mean_psnr =
        |ms: &[&Measure]| ms.iter().map(|m| m.psnr.min(99.0)).sum::<f64>() / ms.len() as f64;
    Some((
        time(&voxel) / time(&kernel),
        mean_psnr(&kernel),
        mean_psnr(&voxel),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn summary(setting: &'static str, mpx_per_s: f64, psnr: f64) -> Measure {
        Measure {
            scene: "s".into(),
            view: "v".into(),
            pitch: 0.0,
            setting,
            psnr,
            ssim: 0.5,
            sky_agreement: 1.0,
            depth_median: 0.0,
            depth_p95: 0.0,
            steps_per_pixel: 1.0,
            mpx_per_s,
            resident_bytes: 0,
            bytes_touched: 0,
        }
    }

    #[test]
    fn a_csv_field_with_a_comma_or_a_quote_is_quoted() {
        assert_eq!(csv_field("C7W/D7"), "C7W/D7");
        assert_eq!(csv_field("hills, west"), "\"hills, west\"");
        assert_eq!(csv_field("the \"big\" map"), "\"the \"\"big\"\" map\"");
    }

    #[test]
    fn a_fast_setting_is_timed_until_its_runs_add_up_and_a_slow_one_repeats_times() {
        let runs = |ns: u64, repeats: u32| {
            let mut timing = Timing::default();
            while !timing.enough(repeats) {
                timing = timing.with(ns);
            }
            timing
        };
        // A 2 ms render: 30 runs make the 60 ms.
        assert_eq!(runs(2_000_000, 3).runs, 30);
        // A second's render: the repeats alone.
        assert_eq!(runs(1_000_000_000, 3).runs, 3);
        assert_eq!(runs(1_000_000_000, 5).runs, 5);
        // The best is the least.
        let timing = Timing::default().with(7).with(5).with(9);
        assert_eq!((timing.runs, timing.best, timing.spent_ns), (3, 5, 21));
    }

    #[test]
    fn measures_split_by_the_larger_side_of_their_map() {
        // Flat strips: only their sides matter here.
        let scene = |name: &str, width: u32, depth: u32| {
            let n = (width * depth) as usize;
            let map = Scene::new(width, depth, vec![0.0; n], vec![[0; 3]; n]).unwrap();
            BenchScene::new(name.into(), map).unwrap()
        };
        let scenes = [
            scene("long", 1024, 8),
            scene("wide", 1025, 64),
            scene("deep", 64, 1100),
        ];
        let on = |name: &str| Measure {
            scene: name.into(),
            ..summary("kernel", 1.0, 30.0)
        };
        let measures = [on("long"), on("wide"), on("deep"), on("unknown")];
        let [small, large] = split_by_map_size(&measures, &scenes);
        let names = |ms: &[Measure]| ms.iter().map(|m| m.scene.clone()).collect::<Vec<_>>();
        assert_eq!(names(&small), ["long"]);
        assert_eq!(names(&large), ["wide", "deep"]);
    }

    #[test]
    fn the_pareto_front_keeps_exactly_the_undominated_settings() {
        let measures = [
            summary("kernel", 4.0, 30.0),
            summary("voxelspace", 8.0, 20.0),
            summary("march 0.5", 0.5, 31.0),
            summary("march 2", 1.0, 25.0), // slower and worse than kernel
        ];
        let front: Vec<(&str, bool)> = summarize(&measures)
            .iter()
            .map(|s| (s.setting, s.pareto))
            .collect();
        assert_eq!(
            front,
            [
                ("kernel", true),
                ("voxelspace", true),
                ("march 0.5", true),
                ("march 2", false)
            ]
        );
        let (ratio, k, v) = against_voxel_space_at_pitch_0(&measures, "kernel").unwrap();
        assert_eq!((ratio, k, v), (0.5, 30.0, 20.0));
        assert_eq!(against_voxel_space_at_pitch_0(&measures, "no such"), None);
        assert!(csv(&measures).lines().count() == 5);
    }

    #[test]
    fn every_setting_reads_some_terrain_and_finer_marches_read_more() {
        let scene = crate::scene::procedural(96, 2);
        let bench = BenchScene::new("small".into(), scene).unwrap();
        let view = &views(0, &bench.scene)[2];
        let touched: Vec<(&str, u64)> = settings()
            .iter()
            .map(|s| {
                (
                    s.name,
                    bytes_touched(s, &bench, &view.camera, (48, 36)).unwrap(),
                )
            })
            .collect();
        assert!(touched.iter().all(|(_, b)| *b > 0), "{touched:?}");
        let of = |name| touched.iter().find(|(n, _)| *n == name).unwrap().1;
        assert!(of("march 0.5") >= of("march 2"), "{touched:?}");
        // The kernel reads a part of what it holds: 5 bytes a voxel, plus
        // the pyramid and bounds.
        assert!(of("kernel") < 96 * 96 * 5 * 2, "{touched:?}");
    }

    #[test]
    fn a_color_square_is_four_colors_and_what_is_read_twice_counts_once() {
        let mut probe = TouchProbe::default();
        probe.visit(0, 7); // two heights
        probe.color(0, 7); // a pair of colors
        probe.color(0, 7);
        probe.color_square(0, 7); // four colors
        probe.color_square(1, 7);
        probe.bound(1, 2);
        assert_eq!(probe.bytes(), 4 + 6 + 2 * 12 + 2);
    }

    #[test]
    fn flicker_is_measured_for_every_setting_and_a_still_camera_has_none() {
        let scene = crate::scene::procedural(96, 2);
        let scenes = [BenchScene::new("small".into(), scene).unwrap()];
        let moving = flicker(&scenes, (32, 24), 3, |_, _| {}).unwrap();
        assert_eq!(moving.len(), settings().len());
        assert!(moving.iter().all(|(_, f)| f.is_finite()), "{moving:?}");
        // One frame: no change at all, for the method and the reference.
        let still = flicker(&scenes, (32, 24), 1, |_, _| {}).unwrap();
        assert!(still.iter().all(|(_, f)| *f == 0.0), "{still:?}");
    }
}
