//! The `terracast-sim` command line (the view contract,
//! `shared/spec/view-contract.md` beside the repository).

mod atmosphere;
mod bench;
mod fly;
mod paging;
mod sim;
mod values;
#[cfg(feature = "window")]
mod view;

use crate::baselines::{march, voxel_space, MarchOptions, VoxelSpaceOptions};
use crate::board::{against_without, board_views, price_fit, verify, write_scene, MAX_BOARD_SIDE};
use crate::error::{Error, Result};
use crate::kernel::{render_kernel_in, PixelRays};
use crate::objects::placing::ScenePlan;
use crate::output::{stats_json, write_json, write_pfm, write_png};
use crate::outputs::{OutputId, Outputs};
use crate::reference::{Reference, ReferenceOptions};
use crate::scene::{load_scene_files, procedural, Scene};
use crate::volume::{render_volume, Mode, TerrainVolume, VolumeOptions};
use clap::{Parser, Subcommand, ValueEnum};
use std::path::{Path, PathBuf};
use terracast::config::DEFAULT_HFOV_DEG;
use terracast::{
    Camera, Coherence, HeightFilter, HeightPath, RenderOptions, Resolution, Rgb, Shading,
    VerticalSamples, View, ViewError, U8F8,
};
use values::{angle, hfov, number, pitch, positive, roll, seed, size, triple};

/// Real-time terrain flythrough: the terracast kernel on the host.
#[derive(Debug, Parser)]
#[command(name = "terracast-sim", version, about, arg_required_else_help = true)]
pub struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Fly a path at a steady display rate on the modeled machine: frames
    /// rendered within a fixed budget, the ones between warped; writes an
    /// animated GIF and a report. The main job.
    Fly(fly::FlyArgs),
    /// Render one view to a PNG (with optional depth and stats).
    Render(RenderArgs),
    /// The emulated board: pack its scene, verify what it rendered
    /// (scripts/board-check runs both around QEMU).
    #[command(subcommand, arg_required_else_help = true)]
    Board(BoardCommand),
    /// Fly on the modeled parallel machine (Cohen-Or's PVS by default):
    /// simulated frame times, deadlines, utilization, bank contention;
    /// --table for Table 1; --threads for the same line pool on real
    /// cores.
    Sim(sim::SimArgs),
    /// Speed against accuracy: every method and setting on a fixed suite
    /// of views, against the reference; writes a CSV and a chart.
    Bench(bench::BenchArgs),
    /// Convert a height map (PNG, SRTM .hgt or GeoTIFF) and its color map or
    /// photos into a tiled terrain file; PNG maps stream, so inputs larger
    /// than memory can be packed.
    Pack(paging::PackArgs),
    /// Fly over a tiled terrain (a .tiles file, or procedural:SIZE) through
    /// a fixed tile cache, paging tiles as Cohen-Or's master did; reports
    /// each frame's missing tiles, loads and resident bytes.
    Page(paging::PageArgs),
    /// Fly over a terrain yourself, in a window: keys and mouse, the line
    /// pool on the host's cores, the governor holding the frame time.
    #[cfg(feature = "window")]
    View(view::ViewArgs),
}

#[derive(Debug, Subcommand)]
enum BoardCommand {
    /// Write the scene file the firmware bakes in: the procedural terrain
    /// and the board's views.
    Scene(BoardSceneArgs),
    /// Compare the board's frames and display wire with the host kernel's,
    /// byte for byte, and report instructions per pixel. Fails on any
    /// difference or when the budget is exceeded.
    Verify(BoardVerifyArgs),
}

#[derive(Debug, clap::Args)]
struct BoardSceneArgs {
    /// Side of the procedural map (it must fit the board's 4 MiB of code
    /// memory: 5 bytes a voxel).
    #[arg(long, default_value_t = 512, value_name = "N",
          value_parser = number(2u32, MAX_BOARD_SIDE), allow_hyphen_values = true)]
    procedural_size: u32,
    /// A real height map instead of the procedural one (as `render
    /// --height`): square and at most 800 a side, or a square cut from
    /// its middle with --crop.
    #[arg(
        long,
        value_name = "H.png|H.hgt|H.tif",
        conflicts_with = "procedural_size"
    )]
    height: Option<PathBuf>,
    /// Its color map, stretched over it (as `render --color`; a photo
    /// finer than the height grid is reduced to it). Without it, the
    /// heights are colored by height and slope.
    #[arg(long, value_name = "C.png|C.tif", requires = "height")]
    color: Option<PathBuf>,
    /// World height of one height-map unit, in voxels (as `render
    /// --height-scale`).
    #[arg(long, value_name = "S", value_parser = positive(0.0f32, 1e6),
          allow_hyphen_values = true, requires = "height")]
    height_scale: Option<f32>,
    /// Take the N x N square at the middle of the height map (Comanche's
    /// maps are 1024 a side: more than the board holds).
    #[arg(long, value_name = "N", value_parser = number(2u32, MAX_BOARD_SIDE),
          allow_hyphen_values = true, requires = "height")]
    crop: Option<u32>,
    /// Every view turned level (pitch 0, no roll), where the kernel is
    /// compared with Voxel Space; the rolled view, then its level twin's
    /// double, is left out.
    #[arg(long)]
    level: bool,
    /// Seed of the procedural scene.
    #[arg(long, default_value_t = 1, value_name = "N", value_parser = seed, allow_hyphen_values = true)]
    seed: u64,
    /// Image size of the board's frames.
    #[arg(long, default_value = "320x240", value_parser = size, allow_hyphen_values = true, value_name = "WxH")]
    size: (u32, u32),
    /// Only the board's view N (0 to 5), to profile one view alone.
    #[arg(long, value_name = "N", value_parser = number(0usize, 5), allow_hyphen_values = true)]
    view: Option<usize>,
    /// Plant a wood and a village on the map (as `render --objects`): the
    /// scene carries their stick layer and the board renders through it
    /// (maps up to 740 a side).
    #[arg(long)]
    objects: bool,
    /// Output scene file.
    #[arg(long, value_name = "SCENE.tcb")]
    out: PathBuf,
}

#[derive(Debug, clap::Args)]
struct BoardVerifyArgs {
    /// The scene file the firmware was built with.
    #[arg(long, value_name = "SCENE.tcb")]
    scene: PathBuf,
    /// Folder holding the board's frame-K.rgb, wire-K.bin and
    /// board-results.txt.
    #[arg(long, value_name = "DIR")]
    from: PathBuf,
    /// Fail when the kernel's instructions per pixel over all views exceed
    /// this.
    #[arg(long, value_name = "N", value_parser = positive(0.0f64, 1e9), allow_hyphen_values = true)]
    budget: Option<f64>,
    /// The board's results for the same views without objects, or with
    /// heights read on each line's plane (a folder holding its
    /// board-results.txt): the scene's instructions a pixel against them,
    /// view by view.
    #[arg(long, value_name = "DIR")]
    without: Option<PathBuf>,
    /// Where the firmware's line caster read heights (its build's
    /// TERRACAST_BOARD_HEIGHT_PATH): the host renders the same.
    #[arg(long, value_enum, default_value_t = HeightPathArg::Line)]
    height_path: HeightPathArg,
    /// Another scene's governed run (its scene file and the folder of its
    /// board-results.txt, already verified): the prices are fitted to its
    /// frames and this run's together too, so that they cover both
    /// terrains.
    #[arg(long, num_args = 2, value_names = ["SCENE.tcb", "DIR"])]
    fit_with: Vec<PathBuf>,
}

/// The kernel's vertical ray coherence.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum CoherenceArg {
    /// Every ray from the eye.
    Off,
    /// Resume only between rays on the same levels: same image as `off`.
    Exact,
    /// Resume across level switches too (the default, faster on the pyramid).
    AcrossLevels,
}

/// Which pyramid levels the kernel steps on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum ResolutionArg {
    /// Every level, switching by the pixel-to-voxel ratio.
    Multi,
    /// Level 0 only.
    Single,
}

/// How the pyramid's coarse heights are filtered.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum HeightFilterArg {
    /// The LeGall 5/3 wavelet's low-pass of the 5 x 5 finer points (the
    /// default).
    Wavelet,
    /// The finer point at the coarse point's position.
    Subsample,
    /// Tent-weighted mean of the nine finer points.
    Mean,
    /// Largest of the nine finer points.
    Max,
}

impl From<HeightFilter> for HeightFilterArg {
    fn from(filter: HeightFilter) -> Self {
        match filter {
            HeightFilter::Wavelet => Self::Wavelet,
            HeightFilter::Subsample => Self::Subsample,
            HeightFilter::Mean => Self::Mean,
            HeightFilter::Max => Self::Max,
        }
    }
}

impl HeightFilterArg {
    /// The name `--height-filter` takes.
    fn name(self) -> String {
        self.to_possible_value()
            .map(|v| v.get_name().to_owned())
            .unwrap_or_default()
    }
}

impl From<HeightFilterArg> for HeightFilter {
    fn from(arg: HeightFilterArg) -> Self {
        match arg {
            HeightFilterArg::Wavelet => Self::Wavelet,
            HeightFilterArg::Subsample => Self::Subsample,
            HeightFilterArg::Mean => Self::Mean,
            HeightFilterArg::Max => Self::Max,
        }
    }
}

/// Whether the kernel scales its pixel-to-voxel ratio by the terrain's
/// roughness.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum TerrainFitArg {
    /// Scale it down on rugged terrain (no change on smooth maps).
    On,
    /// Use the ratio as given.
    Off,
}

/// Where the kernel's line caster reads heights.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum HeightPathArg {
    /// On each image line's plane: coherence exact.
    Line,
    /// On each ray's own path: silhouettes where the pixel's ray sees them.
    Ray,
}

impl From<HeightPathArg> for HeightPath {
    fn from(path: HeightPathArg) -> Self {
        match path {
            HeightPathArg::Line => HeightPath::Line,
            HeightPathArg::Ray => HeightPath::Ray,
        }
    }
}

/// How the kernel colors a hit.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum ShadingArg {
    /// Subvoxel weights across and along grid lines, levels blended.
    Subvoxel,
    /// The nearest voxel, no blend.
    Nearest,
    /// Subvoxel weights on level 0's colors at any depth: no footprint
    /// colors past the color reach.
    LevelZero,
}

/// How rays cast from the eye find their first hit.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum FirstHitArg {
    /// Top-down through the pyramid's height bounds.
    Hierarchical,
    /// Voxel by voxel from the eye.
    Walk,
}

/// Which renderer draws the view.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Method {
    /// The fixed-point kernel.
    Kernel,
    /// The exact float reference (bilinear surface, supersampled).
    Reference,
    /// Comanche's Voxel Space (front-to-back slices, y-buffer); its pitch
    /// is a horizon shift, not a rotation.
    Voxelspace,
    /// A naive per-pixel float ray march with a fixed step.
    March,
    /// Qu et al.'s filtered 3D density volume, sampled along each ray
    /// (trilinear, ray coherence, retrace).
    Volume,
    /// Qu et al.'s approximate mode: the volume's 2D boundary array alone.
    Boundary,
}

/// Where the terrain comes from.
#[derive(Debug, clap::Args)]
struct SceneArgs {
    /// Height map: 8/16-bit grayscale PNG, SRTM .hgt or single-band
    /// GeoTIFF. Without it, the built-in procedural scene is rendered.
    #[arg(long, value_name = "H.png|H.hgt|H.tif")]
    height: Option<PathBuf>,
    /// Color map: RGB, RGBA, gray or palette PNG, or an 8-bit TIFF,
    /// stretched over the height map (one finer than the height grid is
    /// kept at its own resolution: see --photo-detail); or GeoTIFF photos
    /// over a GeoTIFF height map, placed by their georeference (give
    /// --color once for each, later over earlier). Without it, real
    /// heights are colored by height and slope.
    #[arg(long, value_name = "C.png|C.tif")]
    color: Vec<PathBuf>,
    /// A color map stretched over the height map with more than 1.5
    /// pixels a grid spacing: on, near hits take their colors from its
    /// own texels (2 to 32 a spacing, the power of two at or above the
    /// map's, resampled up to it); off, it is reduced to the height grid.
    #[arg(long, value_enum, value_name = "on|off", default_value = "on")]
    photo_detail: atmosphere::Switch,
    /// World height of one height-map unit, in voxels [default: 1; for an
    /// SRTM .hgt or a georeferenced GeoTIFF, one meter in voxels of its
    /// grid spacing].
    #[arg(long, value_name = "S", value_parser = positive(0.0f32, 1e6), allow_hyphen_values = true)]
    height_scale: Option<f32>,
    /// Side of the procedural scene, used when no --height is given
    /// [default: 1024; `sim --table`: 4096].
    #[arg(long, value_name = "N", value_parser = number(2u32, 8192), allow_hyphen_values = true)]
    procedural_size: Option<u32>,
    /// Seed of the procedural scene (and of the objects' planting).
    #[arg(long, default_value_t = 1, value_name = "N", value_parser = seed, allow_hyphen_values = true)]
    seed: u64,
    /// Plant a wood and a village on the terrain by a rule seeded with
    /// --seed: 3D objects as sticks (trees and houses).
    #[arg(long)]
    objects: bool,
    /// Stand the objects a scene file places on the terrain: library
    /// objects and ones sculpted from three views, by name, position,
    /// heading and scale (TOML; see docs/objects.md). With --objects, the
    /// wood and the village grow around them.
    #[arg(long, value_name = "FILE.toml")]
    place: Option<PathBuf>,
}

/// Where the camera is and where it looks.
#[derive(Debug, clap::Args)]
struct CameraArgs {
    /// Eye position in voxels [default: over the middle of the map's south
    /// edge, a little above the highest terrain].
    #[arg(long, value_parser = triple, allow_hyphen_values = true, value_name = "X,Y,Z")]
    eye: Option<[f32; 3]>,
    /// Heading in degrees, from +x toward +y [default: 90; `page`: 0].
    #[arg(long, value_parser = angle, allow_hyphen_values = true, value_name = "DEG")]
    yaw: Option<f32>,
    /// Degrees below the horizon (positive looks down), -89 to 90
    /// [default: 12; `page`: 20].
    #[arg(long, value_parser = pitch, allow_hyphen_values = true, value_name = "DEG")]
    pitch: Option<f32>,
    /// Full horizontal field of view in degrees, 1 to 160 [default: 60;
    /// `sim --table`: 30].
    #[arg(long, value_parser = hfov, allow_hyphen_values = true, value_name = "DEG")]
    hfov: Option<f32>,
    /// Bank in degrees, positive = right wing down, -180 to 180 [default: 0].
    #[arg(long, value_parser = roll, allow_hyphen_values = true, value_name = "DEG")]
    roll: Option<f32>,
}

impl CameraArgs {
    /// The field of view asked for, or the command's default.
    fn hfov_or(&self, default_deg: f32) -> f32 {
        self.hfov.unwrap_or(default_deg)
    }

    /// The camera these flags describe: `eye` where none is given, and the
    /// command's defaults (heading, pitch, field of view; level) for the
    /// rest.
    fn camera(&self, eye: [f32; 3], [yaw, pitch, hfov]: [f32; 3]) -> Camera {
        Camera {
            eye: self.eye.unwrap_or(eye),
            yaw_deg: self.yaw.unwrap_or(yaw),
            pitch_deg: self.pitch.unwrap_or(pitch),
            roll_deg: self.roll.unwrap_or(0.0),
            hfov_deg: self.hfov_or(hfov),
        }
    }
}

/// The heading and pitch a camera takes by default (`render`, `sim`).
const DEFAULT_YAW_PITCH: [f32; 2] = [90.0, 12.0];

/// `--path PATH.txt`: one keyframe a line, `t x y z yaw pitch [roll]`
/// (seconds, voxels, degrees); `fly`, `sim` and `page` fly it.
fn load_path(file: &Path) -> Result<crate::fly::Path> {
    let text = std::fs::read_to_string(file)
        .map_err(|e| Error::new(format!("cannot read --path {}: {e}", file.display())))?;
    crate::fly::Path::parse(&text).map_err(|e| Error::new(format!("{}: {e}", file.display())))
}

/// The side of the built-in scene given no --procedural-size.
const DEFAULT_PROCEDURAL_SIDE: u32 = 1024;

/// The kernel's settings: every command that renders with the kernel takes
/// them (`bench` compares them all instead).
#[derive(Debug, clap::Args)]
struct KernelArgs {
    /// Kernel: vertical ray coherence along each image line. `exact` gives
    /// the same image as `off` (every ray cast from the eye); `across-levels`
    /// (the line caster: a line set up once, a ray by its slope) shares a
    /// level schedule between the rays of a stretch of a line, about twice
    /// as fast.
    #[arg(long, value_enum, default_value_t = CoherenceArg::AcrossLevels)]
    coherence: CoherenceArg,
    /// Kernel: step on the pyramid's coarser levels in the distance
    /// (`multi`), or on the full-resolution map only (`single`).
    #[arg(long, value_enum, default_value_t = ResolutionArg::Multi)]
    resolution: ResolutionArg,
    /// Kernel: the pixel-to-voxel ratio of the level switch. A level is left
    /// where its voxels get narrower than 1/RATIO pixels: higher is faster
    /// and blurrier. Colors switch by it as given; heights by it scaled
    /// down on rugged terrain by --terrain-fit.
    #[arg(long, default_value_t = 1.0, value_name = "RATIO",
          value_parser = number(1.0f32 / 256.0, 255.0), allow_hyphen_values = true)]
    pixel_to_voxel: f32,
    /// Kernel: scale the pixel-to-voxel ratio of the height levels down by
    /// the terrain's roughness, so that coarse levels begin where their
    /// silhouettes are within an eighth of a pixel, RMS (`on`), or use it
    /// as given (`off`).
    #[arg(long, value_enum, default_value_t = TerrainFitArg::On)]
    terrain_fit: TerrainFitArg,
    /// Kernel: how the pyramid's coarse heights are made [default:
    /// wavelet; with --terrain, the filter the file was packed with].
    #[arg(long, value_enum)]
    height_filter: Option<HeightFilterArg>,
    /// Kernel: how rays cast from the eye find their first hit.
    #[arg(long, value_enum, default_value_t = FirstHitArg::Hierarchical)]
    first_hit: FirstHitArg,
    /// Kernel: rays per pixel, spread over its height: 1, 2, 4 or 8, or
    /// `footprint` (one to four, as many as each pixel's footprint is
    /// longer than wide along its image line).
    #[arg(long, default_value = "1", value_name = "N", value_parser = parse_vertical_samples)]
    vertical_samples: (VerticalSamples, PixelRays),
    /// Kernel: how a hit is colored: subvoxel weights (the default), the
    /// nearest voxel, or subvoxel weights on level 0's colors at any depth
    /// (`level-zero`: no footprint colors, the far terrain aliased).
    #[arg(long, value_enum, default_value_t = ShadingArg::Subvoxel)]
    shading: ShadingArg,
    /// Kernel (--coherence across-levels, one ray a pixel): read heights
    /// on each image line's plane (`line`: every ray of a line on the same
    /// heights, coherence exact) or on each ray's own path (`ray`: a
    /// pitched or rolled view's silhouettes half a pixel truer, and
    /// slower; docs/kernel.md).
    #[arg(long, value_enum, default_value_t = HeightPathArg::Line)]
    height_path: HeightPathArg,
}

#[derive(Debug, clap::Args)]
struct RenderArgs {
    #[command(flatten)]
    scene: SceneArgs,
    /// Render from a tiled terrain through the kernel's tile cache instead:
    /// a file from `pack`, or `procedural:SIZE` (SIZE voxels a side,
    /// e.g. procedural:131072). Kernel method only.
    #[arg(long, value_name = "T.tiles|procedural:SIZE", conflicts_with_all = ["height", "color"])]
    terrain: Option<String>,
    #[command(flatten)]
    camera: CameraArgs,
    /// Image size.
    #[arg(long, default_value = "640x360", value_parser = size, allow_hyphen_values = true, value_name = "WxH")]
    size: (u32, u32),
    /// Sky color.
    #[arg(long, value_parser = values::rgb, allow_hyphen_values = true, value_name = "R,G,B")]
    sky: Option<Rgb>,
    /// Renderer.
    #[arg(long, value_enum, default_value_t = Method::Kernel)]
    method: Method,
    #[command(flatten)]
    atmosphere: atmosphere::AtmosphereArgs,
    #[command(flatten)]
    kernel: KernelArgs,
    /// Voxel Space: growth of the slice spacing each slice.
    #[arg(long, default_value_t = 0.005, value_name = "G",
          value_parser = number(0.0f64, 10.0), allow_hyphen_values = true)]
    voxelspace_growth: f64,
    /// March: step length in voxels.
    #[arg(long, default_value_t = 0.5, value_name = "V",
          value_parser = number(0.01f64, 64.0), allow_hyphen_values = true)]
    march_step: f64,
    /// Volume and boundary: the Gaussian filter's width (standard
    /// deviation), voxels.
    #[arg(long, default_value_t = 0.7, value_name = "V",
          value_parser = number(0.0f32, 16.0), allow_hyphen_values = true)]
    volume_sigma: f32,
    /// Volume and boundary: the layers' spacing, voxels [default: the
    /// height range in 64 layers, at least 1].
    #[arg(long, value_name = "V", value_parser = number(0.05f32, 1024.0), allow_hyphen_values = true)]
    volume_layer: Option<f32>,
    /// Volume and boundary: the sampling interval along a ray, voxels.
    #[arg(long, default_value_t = 0.5, value_name = "V",
          value_parser = number(0.01f32, 64.0), allow_hyphen_values = true)]
    volume_interval: f32,
    /// Reference: rays per pixel side (n x n rays a pixel).
    #[arg(long, default_value_t = 4, value_name = "N",
          value_parser = number(1u32, 16), allow_hyphen_values = true)]
    supersample: u32,
    /// Kernel: one frame within a budget of COST of the board's
    /// instructions a pixel (the governor at the board's prices, from a
    /// level bias of 1): what it spends and how, on the terminal and in
    /// --stats. The per-ray path, one ray a pixel and two or four on the
    /// lines the budget refines; --pixel-to-voxel and --vertical-samples
    /// are the governor's to choose
    #[arg(long, value_name = "COST", value_parser = number(1u64, 1_000_000),
          allow_hyphen_values = true, conflicts_with = "vertical_samples")]
    budget: Option<u64>,
    /// Output image (8-bit RGB PNG).
    #[arg(long, value_name = "OUT.png")]
    out: PathBuf,
    /// Output depth (grayscale PFM: Euclidean distance, +inf for sky).
    #[arg(long, value_name = "OUT.pfm")]
    depth: Option<PathBuf>,
    /// Output statistics (JSON).
    #[arg(long, value_name = "OUT.json")]
    stats: Option<PathBuf>,
}

/// Runs a parsed command line.
pub fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Fly(args) => fly::fly_command(args),
        Command::Render(args) => render_command(args),
        Command::Board(BoardCommand::Scene(args)) => board_scene_command(args),
        Command::Board(BoardCommand::Verify(args)) => board_verify_command(args),
        Command::Sim(args) => sim::sim_command(args),
        Command::Bench(args) => bench::bench_command(args),
        Command::Pack(args) => paging::pack_command(args),
        Command::Page(args) => paging::page_command(args),
        #[cfg(feature = "window")]
        Command::View(args) => view::view_command(args),
    }
}

fn board_scene_command(args: BoardSceneArgs) -> Result<()> {
    let mut outputs = Outputs::new();
    let out = outputs.output("--out", &args.out)?;
    // 5 bytes a voxel, and 2 more for the objects' stick index, must fit
    // the board's 4 MiB of code memory beside the code.
    const MAX_SIDE_WITH_OBJECTS: u32 = 740;
    let (mut scene, source) = board_map(&args)?;
    let side = scene.width;
    if args.objects && side > MAX_SIDE_WITH_OBJECTS {
        return Err(Error::new(format!(
            "with --objects a board map is at most {MAX_SIDE_WITH_OBJECTS} a side \
             (7 bytes a voxel in the board's 4 MiB of code memory)"
        )));
    }
    // The views stand where they do over the bare map, objects or not.
    let mut views = board_views(side, scene.max_height());
    if args.level {
        views = level_board_views(views);
    }
    if let Some(view) = args.view {
        views = vec![*views.get(view).ok_or_else(|| {
            Error::new(format!(
                "--view {view}: the board scene has {} views",
                views.len()
            ))
        })?];
    }
    let planted = args
        .objects
        .then(|| scene.plant_objects(args.seed))
        .map_or(String::new(), |line| format!("; {line}"));
    write_scene(outputs.temporary(out), &scene, args.size, &views)?;
    outputs.commit()?;
    println!(
        "board scene: {0}x{0} map{source}, {1} views at {2}x{3} -> {4}{planted}",
        side,
        views.len(),
        args.size.0,
        args.size.1,
        args.out.display()
    );
    Ok(())
}

/// The board scene's map: the procedural one, or the real one `--height`
/// names (cut to `--crop`), square; and where it came from in a few
/// words for the summary line (empty for the procedural map).
fn board_map(args: &BoardSceneArgs) -> Result<(Scene, String)> {
    let Some(height) = &args.height else {
        return Ok((procedural(args.procedural_size, args.seed), String::new()));
    };
    let scale = height_scale(height, args.height_scale)?;
    let colors: Vec<PathBuf> = args.color.iter().cloned().collect();
    let mut scene = load_scene_files(height, &colors, scale, args.seed)?;
    // The board's terrain is one color a grid point: a finer photo is
    // kept reduced to the grid (as `--photo-detail off`).
    scene.details.clear();
    let (width, depth) = (scene.width, scene.depth);
    if let Some(side) = args.crop {
        scene = scene.middle_square(side)?;
    } else if width != depth || width > MAX_BOARD_SIDE {
        return Err(Error::new(format!(
            "{} is {width}x{depth}: a board map is square and at most \
             {MAX_BOARD_SIDE} a side (5 bytes a voxel in the board's 4 MiB of code \
             memory); cut a square from its middle with --crop N",
            height.display()
        )));
    }
    let name = height
        .file_name()
        .unwrap_or(height.as_os_str())
        .to_string_lossy();
    let source = match args.crop {
        Some(_) => format!(" (the middle of {name}, {width}x{depth})"),
        None => format!(" ({name})"),
    };
    Ok((scene, source))
}

/// `views` turned level (pitch 0, no roll), each once.
fn level_board_views(views: Vec<Camera>) -> Vec<Camera> {
    let mut level: Vec<Camera> = Vec::with_capacity(views.len());
    for camera in views {
        let camera = camera.turned_level();
        if !level.contains(&camera) {
            level.push(camera);
        }
    }
    level
}

fn board_verify_command(args: BoardVerifyArgs) -> Result<()> {
    let height_path = HeightPath::from(args.height_path);
    let report = verify(&args.scene, &args.from, height_path)?;
    print!("{}", report.table());
    if let Some(without) = &args.without {
        let what = match (report.objects, height_path) {
            (true, HeightPath::Line) => "with objects against without",
            (false, HeightPath::Ray) => "heights on each ray's path against on each line's plane",
            (true, HeightPath::Ray) => {
                "with objects on each ray's path against without on each line's plane"
            }
            (false, HeightPath::Line) => "against the run without",
        };
        print!("{}", against_without(&report, without, what)?);
    }
    let differing: Vec<String> = report
        .frames
        .iter()
        .filter(|f| !f.identical())
        .map(|f| f.index.to_string())
        .collect();
    let differing: Vec<String> = differing
        .into_iter()
        .chain(
            report
                .governed
                .iter()
                .enumerate()
                .filter(|(_, g)| g.differing_pixels > 0)
                .map(|(index, _)| format!("governed {index}")),
        )
        .collect();
    let per_pixel = report.instructions_per_pixel();
    if !differing.is_empty() {
        println!("instructions per pixel: {per_pixel:.0}");
        return Err(Error::new(format!(
            "board and host frames differ in view(s) {}",
            differing.join(", ")
        )));
    }
    if let [other_scene, other_run] = args.fit_with.as_slice() {
        let other = verify(other_scene, other_run, height_path)?;
        let what = format!("these frames and {}'s", other_run.display());
        print!("{}", price_fit(&[&report, &other], &what));
    }
    let most = report.governed_most_share();
    if most > 1.0 {
        return Err(Error::new(format!(
            "a governed frame took {most:.3} of its budget on the board: Prices::BOARD_LINES and Prices::BOARD no longer cover the kernel's cost (refit them: `prices fitted to these frames`)"
        )));
    }
    if let Some(budget) = args.budget {
        if per_pixel > budget {
            println!("instructions per pixel: {per_pixel:.0}");
            return Err(Error::new(format!(
                "{per_pixel:.0} instructions per pixel exceeds the budget of {budget:.0}"
            )));
        }
        println!("all frames identical; budget {budget:.0} instructions per pixel holds");
    } else {
        println!("all frames identical");
    }
    println!("instructions per pixel: {per_pixel:.0}");
    Ok(())
}

fn render_command(args: RenderArgs) -> Result<()> {
    let (width, height) = args.size;
    // Every output is refused or made ready before any time is spent.
    let mut outputs = Outputs::new();
    args.scene.name_inputs(&mut outputs);
    if let Some(spec) = &args.terrain {
        outputs.input("--terrain", Path::new(spec));
    }
    let files = RenderFiles::name(&args, &mut outputs)?;
    if let Some(spec) = &args.terrain {
        args.scene.refuse_objects("a tiled terrain (--terrain)")?;
        return paging::render_tiled_command(&args, spec, outputs, files);
    }
    let mut scene = load_scene(&args.scene)?;
    args.atmosphere
        .shade(&mut scene, false, !args.scene.color.is_empty())?;
    let air = args.atmosphere.atmosphere(false);
    let [yaw, pitch] = DEFAULT_YAW_PITCH;
    let camera = args
        .camera
        .camera(scene.default_eye(), [yaw, pitch, DEFAULT_HFOV_DEG]);
    let sky = args.sky.unwrap_or(terracast::config::DEFAULT_SKY);
    // Every method shares the kernel's camera limits.
    let check_view = || View::new(&camera, width, height).map_err(view_error);
    if args.method != Method::Kernel {
        check_view()?;
    }
    if args.method == Method::Voxelspace && camera.roll_deg != 0.0 {
        return Err(Error::new(
            "--method voxelspace cannot roll (its columns stay vertical): use --roll 0".to_string(),
        ));
    }
    let (mut frame, stats) = match args.method {
        Method::Kernel => {
            // The kernel's terrain first: heights out of its range are the
            // problem to report, before the camera placed over them.
            let kernel = scene.to_kernel_with(args.kernel.height_filter())?;
            check_view()?;
            let options = args.kernel.options(sky);
            let prepared = args.atmosphere.prepared(false)?;
            let rays = match args.budget {
                Some(per_pixel) => PixelRays::Governed(per_pixel),
                None => args.kernel.vertical_samples.1,
            };
            let rendered = render_kernel_in(
                &kernel,
                &camera,
                (width, height),
                &options,
                rays,
                prepared.as_ref(),
            )?;
            if let Some(cost) = rendered.1.levels.and_then(|l| l.governed) {
                let pixels = f64::from(width) * f64::from(height);
                println!(
                    "budget {:.0} a pixel: spent {:.0} ({:.1} %), the base pass {:.0} at a level bias of {}; {} refined line renders (a line the second round refines counts twice), {} finished coarser, {} rays repeated",
                    cost.budget as f64 / pixels,
                    cost.cost as f64 / pixels,
                    100.0 * cost.cost as f64 / cost.budget.max(1) as f64,
                    cost.base_cost as f64 / pixels,
                    cost.level_bias,
                    cost.refined_lines,
                    cost.coarse_lines,
                    cost.filled_rays,
                );
            }
            rendered
        }
        Method::Reference => {
            let options = ReferenceOptions {
                supersample: args.supersample,
                sky,
                atmosphere: air,
            };
            Reference::new(&scene).render(&camera, width, height, &options)
        }
        Method::Voxelspace => {
            let options = VoxelSpaceOptions {
                spacing_growth: args.voxelspace_growth,
                sky,
            };
            voxel_space(&scene, &camera, width, height, &options)
        }
        Method::March => {
            let options = MarchOptions {
                step: args.march_step,
                sky,
            };
            march(&scene, &camera, width, height, &options)
        }
        Method::Volume | Method::Boundary => {
            let options = VolumeOptions {
                sigma: args.volume_sigma,
                layer: args.volume_layer,
                interval: args.volume_interval,
                coherence: true,
                sky,
            };
            let volume = TerrainVolume::build(&scene, &options);
            eprintln!("{}", volume.describe());
            let mode = if args.method == Method::Volume {
                Mode::Accurate
            } else {
                Mode::Approximate
            };
            render_volume(&scene, &volume, &camera, (width, height), &options, mode)
        }
    };
    // The kernel and the reference put the atmosphere on ray by ray; the
    // others' frames get it from their depth.
    if let (Some(air), Method::Voxelspace | Method::March | Method::Volume | Method::Boundary) =
        (&air, args.method)
    {
        crate::atmosphere::apply_exact(&mut frame, &camera, air);
    }
    let stats = stats_json(&stats, width, height, frame.sky_pixels());
    files.write(&outputs, &frame, &stats)?;
    outputs.commit()
}

/// `render`'s outputs: the image, and the depth and stats when asked for.
struct RenderFiles {
    image: OutputId,
    depth: Option<OutputId>,
    stats: Option<OutputId>,
}

impl RenderFiles {
    fn name(args: &RenderArgs, outputs: &mut Outputs) -> Result<Self> {
        Ok(Self {
            image: outputs.output("--out", &args.out)?,
            depth: args
                .depth
                .as_deref()
                .map(|p| outputs.output("--depth", p))
                .transpose()?,
            stats: args
                .stats
                .as_deref()
                .map(|p| outputs.output("--stats", p))
                .transpose()?,
        })
    }

    /// Writes the frame, and its depth and `stats` where asked for, into
    /// their temporaries.
    fn write(
        &self,
        outputs: &Outputs,
        frame: &crate::frame::Frame,
        stats: &serde_json::Value,
    ) -> Result<()> {
        write_png(outputs.temporary(self.image), frame)?;
        if let Some(id) = self.depth {
            write_pfm(outputs.temporary(id), frame)?;
        }
        if let Some(id) = self.stats {
            write_json(outputs.temporary(id), stats)?;
        }
        Ok(())
    }
}

impl KernelArgs {
    /// The kernel's options (each flag checked by its parser), with `sky`.
    fn options(&self, sky: Rgb) -> RenderOptions {
        let coherence = match self.coherence {
            CoherenceArg::Off => Coherence::Off,
            CoherenceArg::Exact => Coherence::Exact,
            CoherenceArg::AcrossLevels => Coherence::AcrossLevels,
        };
        let resolution = match self.resolution {
            ResolutionArg::Single => Resolution::Single,
            ResolutionArg::Multi => Resolution::Multi {
                pixel_to_voxel: U8F8::from_num(self.pixel_to_voxel),
            },
        };
        RenderOptions {
            coherence,
            resolution,
            hierarchical_first_hit: self.first_hit == FirstHitArg::Hierarchical,
            vertical_samples: self.vertical_samples.0,
            shading: match self.shading {
                ShadingArg::Subvoxel => Shading::Subvoxel,
                ShadingArg::Nearest => Shading::Nearest,
                ShadingArg::LevelZero => Shading::LevelZero,
            },
            terrain_fit: self.terrain_fit == TerrainFitArg::On,
            height_path: self.height_path.into(),
            sky,
        }
    }

    /// The height filter asked for, or the default.
    fn height_filter(&self) -> HeightFilter {
        self.height_filter
            .map_or_else(HeightFilter::default, Into::into)
    }

    /// The options of a command that casts a fixed number of rays a pixel
    /// (every command but `render`): `--vertical-samples footprint` is
    /// refused there.
    fn fixed_rays_options(&self) -> Result<RenderOptions> {
        if self.vertical_samples.1 == PixelRays::ByFootprint {
            return Err(Error::new(
                "--vertical-samples footprint: only `render` gives a pixel rays by its footprint; give 1, 2, 4 or 8",
            ));
        }
        Ok(self.options(terracast::config::DEFAULT_SKY))
    }
}

impl SceneArgs {
    /// `--objects` and `--place` refused for `what`, a tiled terrain,
    /// which carries the objects it was packed with.
    fn refuse_objects(&self, what: &str) -> Result<()> {
        let flag = if self.objects {
            "--objects"
        } else if self.place.is_some() {
            "--place"
        } else {
            return Ok(());
        };
        Err(Error::new(format!(
            "{flag} stands objects on a terrain in memory; {what} carries the objects it was packed with (pack --objects, --place)"
        )))
    }

    /// Names the files the scene is read from as inputs.
    fn name_inputs(&self, outputs: &mut Outputs) {
        if let Some(path) = &self.height {
            outputs.input("--height", path);
        }
        for path in &self.color {
            outputs.input("--color", path);
        }
        if let Some(path) = &self.place {
            outputs.input("--place", path);
            for view in ScenePlan::view_paths(path) {
                outputs.input("--place", &view);
            }
        }
    }
}

fn load_scene(args: &SceneArgs) -> Result<Scene> {
    load_scene_or(args, DEFAULT_PROCEDURAL_SIDE)
}

/// The scene the arguments name; the built-in one is `default_side` a side
/// unless --procedural-size says otherwise.
fn load_scene_or(args: &SceneArgs, default_side: u32) -> Result<Scene> {
    let mut scene = load_terrain(args, default_side)?;
    if args.photo_detail == atmosphere::Switch::Off {
        scene.details.clear();
    }
    let plan = args.place.as_deref().map(ScenePlan::read).transpose()?;
    if plan.is_some() || args.objects {
        let seed = args.objects.then_some(args.seed);
        eprintln!("{}", scene.add_objects(plan.as_ref(), seed)?);
    }
    for detail in &scene.details {
        eprintln!(
            "photo kept at {} texels a grid spacing over {}x{} grid points ({:.1} MiB; --photo-detail off reduces it to the height grid)",
            1 << detail.shift,
            detail.size[0],
            detail.size[1],
            detail.bytes() as f64 / f64::from(1 << 20)
        );
    }
    Ok(scene)
}

/// The terrain the arguments name, without objects.
fn load_terrain(args: &SceneArgs, default_side: u32) -> Result<Scene> {
    match (&args.height, args.color.as_slice()) {
        (None, [_, ..]) => Err(Error::new("--color needs --height")),
        (None, []) => Ok(procedural(
            args.procedural_size.unwrap_or(default_side),
            args.seed,
        )),
        (Some(h), colors) => {
            let scale = height_scale(h, args.height_scale)?;
            load_scene_files(h, colors, scale, args.seed)
        }
    }
}

/// `--height-scale` as given, or derived from an SRTM tile's grid spacing
/// or a GeoTIFF's georeference (saying what it chose), or 1.
fn height_scale(height: &Path, given: Option<f32>) -> Result<f32> {
    if let Some(scale) = given {
        return Ok(scale);
    }
    match crate::scene::derived_height_scale(height)? {
        Some((scale, why)) => {
            eprintln!("{why}");
            Ok(scale)
        }
        None => Ok(1.0),
    }
}

/// A camera the kernel refuses, with the flag to change.
fn view_error(e: ViewError) -> Error {
    let flag = match e {
        ViewError::NotFinite => "--eye, --yaw, --pitch, --hfov",
        ViewError::EyeOutOfRange => "--eye",
        ViewError::PitchOutOfRange => "--pitch",
        ViewError::RollOutOfRange => "--roll",
        ViewError::FovOutOfRange => "--hfov",
        ViewError::ImageSize | ViewError::AspectOutOfRange => "--size",
    };
    Error::new(format!("bad camera ({flag}): {e}"))
}

/// `--vertical-samples`: a count of rays every pixel gets, or `footprint`.
fn parse_vertical_samples(text: &str) -> std::result::Result<(VerticalSamples, PixelRays), String> {
    let fixed = |count| Ok((count, PixelRays::Fixed));
    match text {
        "1" => fixed(VerticalSamples::One),
        "2" => fixed(VerticalSamples::Two),
        "4" => fixed(VerticalSamples::Four),
        "8" => fixed(VerticalSamples::Eight),
        "footprint" => Ok((VerticalSamples::One, PixelRays::ByFootprint)),
        other => Err(format!("must be 1, 2, 4, 8 or footprint, not {other:?}")),
    }
}
