//! `terracast-sim view`: fly over a terrain yourself, in a window, with
//! the line pool on the host's cores and the governor holding the frame
//! time (see `docs/viewer.md`).

use super::values::{number, positive, size};
use super::{load_scene, view_error, CameraArgs, KernelArgs, SceneArgs, DEFAULT_YAW_PITCH};
use crate::error::{Error, Result};
use crate::kernel::PixelRays;
use crate::outputs::Outputs;
use crate::tiles::{new_photo_slots, new_slots, Terrain, TiledViewer};
use crate::viewer::{
    describe_camera, draw_line_of_text, fly_step, ground_under, keep_above, render_arguments,
    render_governed, render_pool, shell_word, threads_or_cores, turn_by, FrameBudget, FrameFigures,
    Governed, GovernedShare, Motion, Pixels, Recorder, ScaleGovernor, Settings, WindowGovernor,
    DRAG_DEG_PER_PIXEL,
};
use std::collections::HashSet;
use std::num::NonZeroU32;
use std::path::{Path, PathBuf};
use std::rc::Rc;
use std::time::Instant;
use terracast::config::DEFAULT_HFOV_DEG;
use terracast::{
    Camera, Detail, Governor, PreparedAtmosphere, Pyramid, RenderOptions, Resolution, Rgb,
    StickLayer, View, WithDetail, WithSticks, U8F8,
};
use winit::application::ApplicationHandler;
use winit::dpi::{PhysicalPosition, PhysicalSize};
use winit::event::{ElementState, MouseButton, WindowEvent};
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop};
use winit::keyboard::{KeyCode, PhysicalKey};
use winit::window::{Window, WindowId};

#[derive(Debug, clap::Args)]
pub(super) struct ViewArgs {
    #[command(flatten)]
    scene: SceneArgs,
    /// A tiled terrain instead: a file from `pack`, or `procedural:SIZE`.
    #[arg(long, value_name = "T.tiles|procedural:SIZE", conflicts_with_all = ["height", "color"])]
    terrain: Option<String>,
    #[command(flatten)]
    camera: CameraArgs,
    /// Window size at the start (the window is resizable).
    #[arg(long, default_value = "960x540", value_parser = size, allow_hyphen_values = true, value_name = "WxH")]
    size: (u32, u32),
    /// Rendering threads [default: the host's cores].
    #[arg(long, value_name = "N", value_parser = number(1usize, 1024), allow_hyphen_values = true)]
    threads: Option<usize>,
    /// Frame rate the governor holds [default: the display's refresh rate,
    /// or 60 where it does not say].
    #[arg(long, value_name = "HZ", value_parser = positive(0.0f32, 1000.0), allow_hyphen_values = true)]
    fps: Option<f32>,
    /// What holds the frame time. size: frames are rendered smaller
    /// (enlarged to the window) when one would be late, and grow back to
    /// the window's size when there is time. cost: the kernel's governor
    /// spends a budget that stands for a share of the display frame (level
    /// bias, refined lines), the size shrinking when one ray a pixel
    /// leaves no room in it. off: every frame at the window's size.
    #[arg(long, value_enum, default_value_t = WindowGovernor::Size)]
    governor: WindowGovernor,
    /// Ground speed at the start, voxels a second [default: a tenth of
    /// the map's side, at most 100].
    #[arg(long, value_name = "V", value_parser = positive(0.0f32, 1e6), allow_hyphen_values = true)]
    speed: Option<f32>,
    /// Sky color.
    #[arg(long, value_parser = super::values::rgb, allow_hyphen_values = true, value_name = "R,G,B")]
    sky: Option<Rgb>,
    /// Views saved with P go to PREFIX-N.png (the first N not taken).
    #[arg(long, default_value = "terracast-view", value_name = "PREFIX")]
    save_prefix: String,
    /// Write the flown path to this file, in `fly`'s path format, when the
    /// window closes.
    #[arg(long, value_name = "PATH.txt")]
    record: Option<PathBuf>,
    /// Measure instead of waiting for keys: fly `fly`'s built-in scenic
    /// path (over a tiled terrain: straight ahead) in real time for
    /// SECONDS, rendering frame after frame, then print the frame rate and
    /// close.
    #[arg(long, value_name = "SECONDS", value_parser = positive(0.0f32, 3600.0), allow_hyphen_values = true)]
    measure: Option<f32>,
    #[command(flatten)]
    atmosphere: super::atmosphere::AtmosphereArgs,
    #[command(flatten)]
    kernel: KernelArgs,
}

/// How long the view stays still before a frame the governor shrank is
/// drawn again at the window's size.
const STILL_AFTER: std::time::Duration = std::time::Duration::from_millis(300);

/// The keys, as printed at the start and in `docs/viewer.md`.
const KEYS_HELP: &str =
    "keys: W/S forward/back, A/D sideways, R/F up/down, arrows turn and pitch, Q/E bank, \
drag with the left button to look, +/- speed; 1 shading, 2 resolution, 3 rays by footprint, \
4 coherence, 5 sky and fog, G governor, H on-screen line; P save the view; Esc quit";

pub(super) fn view_command(args: ViewArgs) -> Result<()> {
    let threads = threads_or_cores(args.threads)?;
    let mut outputs = Outputs::new();
    args.scene.name_inputs(&mut outputs);
    if let Some(spec) = &args.terrain {
        outputs.input("--terrain", Path::new(spec));
    }
    let record = args
        .record
        .as_deref()
        .map(|path| outputs.output("--record", path))
        .transpose()?;
    let sky = args.sky.unwrap_or(terracast::config::DEFAULT_SKY);
    let options = args.kernel.options(sky);
    let settings = Settings::new(options, args.kernel.vertical_samples.1, args.governor);
    let mut slots;
    let mut scene_storage = None;
    let mut early_event_loop = None;
    let mut scenic = None;
    let world = match &args.terrain {
        Some(spec) => {
            args.atmosphere.check_tiled()?;
            args.scene.refuse_objects("a tiled terrain (--terrain)")?;
            let terrain = Terrain::open(spec, args.scene.seed)?;
            if let (Terrain::File(file), Some(wanted)) = (&terrain, args.kernel.height_filter) {
                if file.filter() != terracast::HeightFilter::from(wanted) {
                    return Err(Error::new(format!(
                        "{} was packed with another --height-filter; leave --height-filter out",
                        file.path().display()
                    )));
                }
            }
            slots = (new_slots(), new_photo_slots());
            World::Tiled(Box::new(TiledViewer::new(
                terrain,
                &mut slots.0,
                &mut slots.1,
            )))
        }
        None => {
            let mut scene = load_scene(&args.scene)?;
            // The display before the relief shading, which takes a while
            // and says so.
            need_display()?;
            early_event_loop = Some(connect()?);
            args.atmosphere
                .shade(&mut scene, true, !args.scene.color.is_empty())?;
            let eye = scene.default_eye();
            scenic = Some(crate::fly::Path::scenic(&scene));
            let kernel = scene.to_kernel_with(args.kernel.height_filter())?;
            let scene = scene_storage.insert((kernel, eye));
            let full = scene.0.pyramid()?;
            World::Memory {
                flat: Box::new(Pyramid::flat(*full.base())),
                full: Box::new(full),
                sticks: scene.0.sticks()?,
                details: scene.0.details()?,
                eye: scene.1,
            }
        }
    };
    let [yaw, pitch] = DEFAULT_YAW_PITCH;
    let (side_x, side_y) = world.size();
    let camera = args
        .camera
        .camera(world.default_eye(), [yaw, pitch, DEFAULT_HFOV_DEG]);
    // A tiled terrain's eye is checked in the window it is drawn from,
    // whose origin moves with it.
    let local = match world {
        World::Tiled(_) => Camera {
            eye: [0.0, 0.0, camera.eye[2]],
            ..camera
        },
        World::Memory { .. } => camera,
    };
    View::new(&local, args.size.0, args.size.1).map_err(view_error)?;
    let speed = args
        .speed
        .unwrap_or((side_x.min(side_y) as f32 / 10.0).clamp(1.0, 100.0));
    need_display()?;
    let event_loop = match early_event_loop {
        Some(event_loop) => event_loop,
        None => connect()?,
    };
    println!(
        "terracast view: {}x{} window, {threads} thread(s), governor {}; {KEYS_HELP}",
        args.size.0,
        args.size.1,
        settings.governor.name()
    );
    let mut app = App {
        terrain_flags: terrain_flags(&args),
        atmosphere: args.atmosphere.prepared_settings()?,
        atmosphere_on: args.atmosphere.atmosphere(true).is_some(),
        atmosphere_flags: [false, true].map(|on| {
            args.atmosphere
                .arguments(on, true, !args.scene.color.is_empty())
        }),
        save_prefix: args.save_prefix.clone(),
        world,
        camera,
        settings,
        governor: ScaleGovernor::new(1.0 / 60.0),
        budget: FrameBudget::new(1.0 / 60.0, threads),
        fps: args.fps,
        threads,
        speed,
        keys: HashSet::new(),
        cursor: None,
        dragging: false,
        overlay: true,
        window: None,
        surface: None,
        pixels: Pixels::new(1, 1),
        shown: None,
        started: Instant::now(),
        last_tick: None,
        recorder: args.record.as_ref().map(|_| Recorder::default()),
        redraw: true,
        initial_size: args.size,
        window_size: (0, 0),
        last_change: Instant::now(),
        still_frame: false,
        error: None,
        measure: args.measure.map(|seconds| Measure {
            seconds: f64::from(seconds),
            ..Measure::default()
        }),
        scenic: scenic.filter(|_| args.measure.is_some()),
    };
    if app.measure.is_some() && app.scenic.is_none() {
        app.keys.insert(KeyCode::KeyW);
    }
    event_loop
        .run_app(&mut app)
        .map_err(|e| Error::new(format!("window: {e}")))?;
    if let Some(error) = app.error.take() {
        return Err(error);
    }
    if let (Some(id), Some(recorder)) = (record, &app.recorder) {
        std::fs::write(outputs.temporary(id), recorder.path_text())
            .map_err(|e| Error::new(format!("cannot write --record: {e}")))?;
        outputs.commit()?;
        if let Some(path) = &args.record {
            println!(
                "recorded {} keyframes -> {}",
                recorder.keys().len(),
                path.display()
            );
        }
    }
    Ok(())
}

/// The window is X11's (a Wayland desktop serves it through XWayland,
/// which sets DISPLAY): without one, say so.
fn need_display() -> Result<()> {
    if std::env::var_os("DISPLAY").is_none_or(|v| v.is_empty()) {
        return Err(Error::new(
            "no display to open a window on (DISPLAY is not set): run it on a desktop, or under xvfb-run",
        ));
    }
    Ok(())
}

/// The window's event loop: the connection to the display.
fn connect() -> Result<EventLoop<()>> {
    EventLoop::new()
        .map_err(|e| Error::new(format!("cannot connect to the display: {}", os_message(&e))))
}

/// The flags that name the terrain, for the `render` command line.
fn terrain_flags(args: &ViewArgs) -> Vec<String> {
    let mut flags = Vec::new();
    let mut flag = |name: &str, value: String| {
        flags.push(format!("--{name}"));
        flags.push(value);
    };
    if let Some(spec) = &args.terrain {
        flag("terrain", spec.clone());
    }
    if let Some(path) = &args.scene.height {
        flag("height", path.display().to_string());
    }
    for path in &args.scene.color {
        flag("color", path.display().to_string());
    }
    if let Some(scale) = args.scene.height_scale {
        flag("height-scale", scale.to_string());
    }
    if let Some(side) = args.scene.procedural_size {
        flag("procedural-size", side.to_string());
    }
    flag("seed", args.scene.seed.to_string());
    if let Some(filter) = args.kernel.height_filter {
        flag("height-filter", filter.name());
    }
    flags
}

/// The terrain the window flies over.
enum World<'s> {
    /// A map in memory: its pyramid, and level 0 alone for single
    /// resolution (boxed, as the tiled terrain is: both are large).
    Memory {
        full: Box<Pyramid<'s>>,
        flat: Box<Pyramid<'s>>,
        /// Its objects (`--objects`), if any.
        sticks: Option<StickLayer<'s>>,
        /// Its photos kept finer than the height grid.
        details: Vec<Detail<'s>>,
        eye: [f32; 3],
    },
    /// A tiled terrain through the tile cache.
    Tiled(Box<TiledViewer<'s, Terrain>>),
}

impl World<'_> {
    fn size(&self) -> (u32, u32) {
        match self {
            Self::Memory { full, .. } => (full.base().width(), full.base().depth()),
            Self::Tiled(viewer) => {
                let world = viewer.world();
                (world.width, world.depth)
            }
        }
    }

    fn default_eye(&self) -> [f32; 3] {
        match self {
            Self::Memory { eye, .. } => *eye,
            Self::Tiled(viewer) => super::paging::default_eye(&viewer.world()),
        }
    }

    /// The ground under the eye, where it is known.
    fn ground(&self, eye: [f32; 3]) -> Option<f32> {
        match self {
            Self::Memory { full, .. } => ground_under(&**full, eye[0], eye[1]),
            Self::Tiled(viewer) => viewer.ground_under(eye),
        }
    }

    /// Renders `camera` into `pixels`; returns the steps taken.
    fn render(
        &mut self,
        camera: &Camera,
        options: (&RenderOptions, Option<&PreparedAtmosphere>),
        rays: PixelRays,
        threads: usize,
        pixels: &Pixels,
    ) -> Result<u64> {
        let size = pixels.size();
        match self {
            Self::Memory {
                full,
                flat,
                sticks,
                details,
                ..
            } => {
                let view = View::new(camera, size.0, size.1).map_err(view_error)?;
                let surface: &Pyramid = if options.0.resolution == Resolution::Single
                    && !options.0.hierarchical_first_hit
                {
                    flat
                } else {
                    full
                };
                Ok(match sticks {
                    Some(layer) => {
                        let surface = WithSticks::new(surface, *layer);
                        render_pool(&surface, &view, options, rays, threads, pixels)
                    }
                    None if !details.is_empty() => {
                        let surface = WithDetail::new(surface, details);
                        render_pool(&surface, &view, options, rays, threads, pixels)
                    }
                    None => render_pool(surface, &view, options, rays, threads, pixels),
                })
            }
            Self::Tiled(viewer) => {
                let (steps, _misses) =
                    viewer.frame(camera, size, options.0, |surface, local| {
                        let view = View::new(local, size.0, size.1).map_err(view_error)?;
                        Ok::<_, Error>(render_pool(surface, &view, options, rays, threads, pixels))
                    })?;
                steps
            }
        }
    }

    /// Renders `camera` into `pixels` within `governors`' budgets, one
    /// share of the lines a worker; returns the steps taken and each
    /// share's cost.
    fn render_governed(
        &mut self,
        camera: &Camera,
        options: (&RenderOptions, Option<&PreparedAtmosphere>),
        governors: &mut [Governor],
        pixels: &Pixels,
    ) -> Result<(u64, Vec<GovernedShare>)> {
        let size = pixels.size();
        match self {
            Self::Memory {
                full,
                sticks,
                details,
                ..
            } => {
                let view = View::new(camera, size.0, size.1).map_err(view_error)?;
                let surface: &Pyramid = full;
                Ok(match sticks {
                    Some(layer) => {
                        let surface = WithSticks::new(surface, *layer);
                        render_governed(&surface, &view, options, governors, pixels)
                    }
                    None if !details.is_empty() => {
                        let surface = WithDetail::new(surface, details);
                        render_governed(&surface, &view, options, governors, pixels)
                    }
                    None => render_governed(surface, &view, options, governors, pixels),
                })
            }
            Self::Tiled(viewer) => {
                // The cache loads what the finest of the governors' biases
                // needs.
                let finest = governors
                    .iter()
                    .map(Governor::level_bias)
                    .min()
                    .unwrap_or(U8F8::ONE);
                let loading = RenderOptions {
                    resolution: Resolution::Multi {
                        pixel_to_voxel: finest,
                    },
                    ..*options.0
                };
                let (drawn, _misses) = viewer.frame(camera, size, &loading, |surface, local| {
                    let view = View::new(local, size.0, size.1).map_err(view_error)?;
                    Ok::<_, Error>(render_governed(surface, &view, options, governors, pixels))
                })?;
                drawn
            }
        }
    }
}

/// What the window shows: the camera and options it was rendered with.
#[derive(Debug, Clone, Copy)]
struct Shown {
    camera: Camera,
    /// Whether the sky, sun and fog were on.
    atmosphere_on: bool,
    options: RenderOptions,
    rays: PixelRays,
    size: (u32, u32),
    figures: FrameFigures,
}

struct App<'s> {
    terrain_flags: Vec<String>,
    /// Sky, sun and fog over every frame while on (5 turns them on and
    /// off), and the `render` flags that ask for them off and on.
    atmosphere: PreparedAtmosphere,
    atmosphere_on: bool,
    atmosphere_flags: [Vec<String>; 2],
    save_prefix: String,
    world: World<'s>,
    camera: Camera,
    settings: Settings,
    /// The size frames are rendered at.
    governor: ScaleGovernor,
    /// The cost each frame is rendered within.
    budget: FrameBudget,
    fps: Option<f32>,
    threads: usize,
    speed: f32,
    keys: HashSet<KeyCode>,
    /// Where the cursor is, and whether the left button is held (a drag
    /// looks around).
    cursor: Option<PhysicalPosition<f64>>,
    dragging: bool,
    overlay: bool,
    window: Option<Rc<Window>>,
    surface: Option<softbuffer::Surface<Rc<Window>, Rc<Window>>>,
    pixels: Pixels,
    shown: Option<Shown>,
    started: Instant,
    last_tick: Option<Instant>,
    recorder: Option<Recorder>,
    /// Whether the next frame must be drawn: something changed.
    redraw: bool,
    initial_size: (u32, u32),
    /// The window's size at the last frame.
    window_size: (u32, u32),
    /// When the governor last rendered a frame; the next frame is the still
    /// frame at the window's size.
    last_change: Instant,
    still_frame: bool,
    error: Option<Error>,
    measure: Option<Measure>,
    /// The path `--measure` flies.
    scenic: Option<crate::fly::Path>,
}

/// `--measure`: frames rendered and shown in a set time.
#[derive(Debug, Default)]
struct Measure {
    seconds: f64,
    began: Option<Instant>,
    frames: u64,
    render_seconds: f64,
    /// Each render's seconds, for their spread.
    renders: Vec<f64>,
    /// Renders longer than a display frame, and the longest.
    late: u64,
    slowest: f64,
    pixels: u64,
    /// The least and most the governor divided the window's sides by, and
    /// the rendered pixels' share of the window's, summed over the frames.
    scale: Option<(f32, f32)>,
    pixel_share: f64,
    /// Over the governed frames: their count, the least and most level
    /// bias, and their budgets and costs a pixel, summed.
    governed: u64,
    bias: Option<(f32, f32)>,
    budget_per_pixel: f64,
    cost_per_pixel: f64,
}

impl Measure {
    fn note(&mut self, figures: &FrameFigures, scale: f32, period: f64) {
        self.began.get_or_insert_with(Instant::now);
        self.frames += 1;
        self.render_seconds += figures.seconds;
        self.renders.push(figures.seconds);
        self.late += u64::from(figures.seconds > period);
        self.slowest = self.slowest.max(figures.seconds);
        self.pixels += figures.pixels;
        let (lo, hi) = self.scale.unwrap_or((scale, scale));
        self.scale = Some((lo.min(scale), hi.max(scale)));
        self.pixel_share += 1.0 / f64::from(scale * scale);
        if let Some(g) = &figures.governed {
            self.governed += 1;
            let (lo, hi) = self.bias.unwrap_or(g.bias);
            self.bias = Some((lo.min(g.bias.0), hi.max(g.bias.1)));
            self.budget_per_pixel += g.budget_per_pixel;
            self.cost_per_pixel += g.cost_per_pixel;
        }
    }

    fn done(&self) -> bool {
        self.began
            .is_some_and(|t| t.elapsed().as_secs_f64() >= self.seconds)
    }

    fn report(
        &self,
        size: (u32, u32),
        threads: usize,
        governor: WindowGovernor,
        period: f64,
    ) -> String {
        let wall = self
            .began
            .map_or(0.0, |t| t.elapsed().as_secs_f64())
            .max(1e-9);
        let frames = self.frames.max(1) as f64;
        let (lo, hi) = self.scale.unwrap_or((1.0, 1.0));
        let mut renders = self.renders.clone();
        renders.sort_by(f64::total_cmp);
        let percentile =
            |p: usize| renders.get(renders.len() * p / 100).copied().unwrap_or(0.0) * 1e3;
        let spent = match self.bias {
            Some((least, most)) => {
                let governed = self.governed.max(1) as f64;
                format!(
                    "; {} frames governed: budget {:.0} a pixel on average, {:.3} of it spent, level bias {least:.2} to {most:.2}",
                    self.governed,
                    self.budget_per_pixel / governed,
                    self.cost_per_pixel / self.budget_per_pixel.max(1e-9),
                )
            }
            None => String::new(),
        };
        format!(
            "measured: {} frames at {}x{} in {wall:.1} s: {:.1} frames a second ({:.1} ms a render, 5 % to 95 % of them {:.1} to {:.1} ms, slowest {:.1} ms; {} of the renders longer than a {:.0} Hz frame; {:.1} Mpx/s rendering; {threads} thread(s), governor {}: sides divided by {lo:.2} to {hi:.2}, {:.0} % of the window's pixels on average{spent})",
            self.frames,
            size.0,
            size.1,
            self.frames as f64 / wall,
            self.render_seconds / frames * 1e3,
            percentile(5),
            percentile(95),
            self.slowest * 1e3,
            self.late,
            1.0 / period,
            self.pixels as f64 / self.render_seconds.max(1e-9) / 1e6,
            governor.name(),
            100.0 * self.pixel_share / frames,
        )
    }
}

impl App<'_> {
    fn motion(&self) -> Motion {
        let axis = |plus: KeyCode, minus: KeyCode| {
            f32::from(u8::from(self.keys.contains(&plus)))
                - f32::from(u8::from(self.keys.contains(&minus)))
        };
        Motion {
            forward: axis(KeyCode::KeyW, KeyCode::KeyS),
            right: axis(KeyCode::KeyD, KeyCode::KeyA),
            up: axis(KeyCode::KeyR, KeyCode::KeyF),
            turn: axis(KeyCode::ArrowRight, KeyCode::ArrowLeft),
            pitch: axis(KeyCode::ArrowDown, KeyCode::ArrowUp),
            bank: axis(KeyCode::KeyE, KeyCode::KeyQ),
        }
    }

    /// Moves the camera by the keys held since the last frame, renders and
    /// shows the frame.
    fn frame(&mut self) -> Result<()> {
        let Some(window) = self.window.clone() else {
            return Ok(());
        };
        let now = Instant::now();
        let seconds = self
            .last_tick
            .map_or(0.0, |t| now.duration_since(t).as_secs_f32().min(0.1));
        self.last_tick = Some(now);
        let motion = self.motion();
        if let (Some(path), Some(measure)) = (&self.scenic, &self.measure) {
            let t = measure
                .began
                .map_or(0.0, |t| now.duration_since(t).as_secs_f64());
            self.camera = path.camera(t % path.duration().max(1e-3), self.camera.hfov_deg);
        } else if !motion.is_still() {
            fly_step(&mut self.camera, &motion, self.speed, seconds);
        }
        let (width, depth) = self.world.size();
        let ground = self.world.ground(self.camera.eye);
        keep_above(&mut self.camera, width, depth, ground);
        if let Some(recorder) = &mut self.recorder {
            recorder.note(now.duration_since(self.started).as_secs_f64(), &self.camera);
        }
        let PhysicalSize { width, height } = window.inner_size();
        let window_size = (width.max(1), height.max(1));
        if self.window_size != window_size {
            self.window_size = window_size;
            let (Some(w), Some(h), Some(surface)) = (
                NonZeroU32::new(window_size.0),
                NonZeroU32::new(window_size.1),
                self.surface.as_mut(),
            ) else {
                return Ok(());
            };
            surface
                .resize(w, h)
                .map_err(|e| Error::new(format!("window: {e}")))?;
        }
        let still = std::mem::take(&mut self.still_frame);
        let moving_governed = self.settings.governor != WindowGovernor::Off && !still;
        let size = if moving_governed {
            self.governor.render_size(window_size)
        } else {
            window_size
        };
        if self.pixels.size() != size {
            self.pixels = Pixels::new(size.0, size.1);
        }
        let options = self.settings.options;
        let rays = self.settings.rays;
        let began = Instant::now();
        let air = self.atmosphere_on.then_some(&self.atmosphere);
        let pixel_count = u64::from(size.0) * u64::from(size.1);
        let governed = self.settings.governor == WindowGovernor::Cost && !still;
        let (steps, costs) = if governed {
            let governors = self.budget.governors(pixel_count);
            self.world
                .render_governed(&self.camera, (&options, air), governors, &self.pixels)?
        } else {
            let steps = self.world.render(
                &self.camera,
                (&options, air),
                rays,
                self.threads,
                &self.pixels,
            )?;
            (steps, Vec::new())
        };
        let seconds = began.elapsed().as_secs_f64();
        let figures = FrameFigures {
            seconds,
            pixels: pixel_count,
            steps,
            governed: governed.then(|| Governed::of(&costs, pixel_count)),
        };
        let scale_before = self.governor.scale();
        if governed {
            // The cost holds the time; the size follows the base pass,
            // which no budget makes cheaper than every ray once.
            self.budget.adapt(seconds, &costs);
            self.governor
                .adapt(self.budget.seconds_for_size(seconds, &costs));
            self.last_change = now;
        } else if moving_governed {
            self.governor.adapt(seconds);
            self.last_change = now;
        }
        // Frames go on while the governor is still finding its size.
        self.redraw = self.governor.scale() != scale_before;
        let period = self.period();
        if let Some(measure) = &mut self.measure {
            let scale = window_size.0 as f32 / size.0 as f32;
            measure.note(&figures, scale, period);
        }
        self.shown = Some(Shown {
            camera: self.camera,
            atmosphere_on: self.atmosphere_on,
            options,
            rays,
            size,
            figures,
        });
        let Some(surface) = self.surface.as_mut() else {
            return Ok(());
        };
        let mut buffer = surface
            .buffer_mut()
            .map_err(|e| Error::new(format!("window: {e}")))?;
        self.pixels.enlarge_to(&mut buffer, window_size);
        if self.overlay {
            let text = format!(
                "{}  {}x{}  {}{}  {}",
                figures.describe(),
                size.0,
                size.1,
                self.settings.describe(),
                if self.atmosphere_on { " fog" } else { "" },
                describe_camera(&self.camera)
            );
            draw_line_of_text(&mut buffer, window_size.0, &text);
        }
        buffer
            .present()
            .map_err(|e| Error::new(format!("window: {e}")))?;
        Ok(())
    }

    /// Writes the view on screen to the first free PREFIX-N.png and prints
    /// the `render` command line that draws it.
    fn save(&self) -> Result<()> {
        let Some(shown) = self.shown else {
            return Ok(());
        };
        let path = (1..)
            .map(|n| PathBuf::from(format!("{}-{n}.png", self.save_prefix)))
            .find(|p| !p.exists())
            .unwrap_or_default();
        let mut outputs = Outputs::new();
        let id = outputs.output("the saved view", &path)?;
        let (w, h) = shown.size;
        let image = image::RgbImage::from_raw(w, h, self.pixels.rgb())
            .ok_or_else(|| Error::new("the frame does not match its size"))?;
        image
            .save_with_format(outputs.temporary(id), image::ImageFormat::Png)
            .map_err(|e| Error::new(format!("cannot write {}: {e}", path.display())))?;
        outputs.commit()?;
        let replay = format!("{}-{}.render.png", self.save_prefix, path_number(&path));
        let mut flags = self.terrain_flags.clone();
        flags.extend_from_slice(&self.atmosphere_flags[usize::from(shown.atmosphere_on)]);
        let args = render_arguments(
            &flags,
            &shown.camera,
            shown.size,
            &shown.options,
            shown.rays,
            &replay,
        );
        let line: Vec<String> = args.iter().map(|a| shell_word(a)).collect();
        println!(
            "saved {} ({}; {}; {}); the same view: terracast-sim render {}",
            path.display(),
            describe_camera(&shown.camera),
            shown.figures.describe(),
            match (shown.size == self.window_size, shown.figures.governed) {
                (true, None) => "at the window's size".to_string(),
                (false, None) => format!(
                    "the governor rendered it at {}x{} for the window's {}x{}",
                    shown.size.0, shown.size.1, self.window_size.0, self.window_size.1
                ),
                (_, Some(g)) => format!(
                    "the governor rendered it at {}x{} within {:.0} a pixel; the command renders the view without a budget",
                    shown.size.0, shown.size.1, g.budget_per_pixel
                ),
            },
            line.join(" ")
        );
        Ok(())
    }

    fn key(&mut self, event_loop: &ActiveEventLoop, code: KeyCode, pressed: bool, repeat: bool) {
        if !pressed {
            self.keys.remove(&code);
            return;
        }
        if repeat {
            return;
        }
        // A changed setting redraws; saving and the speed do not.
        self.redraw = true;
        match code {
            KeyCode::Escape => event_loop.exit(),
            KeyCode::Digit1 => self.settings.toggle_shading(),
            KeyCode::Digit2 => self.settings.toggle_resolution(),
            KeyCode::Digit3 => self.settings.toggle_rays(),
            KeyCode::Digit4 => self.settings.next_coherence(),
            KeyCode::Digit5 => self.atmosphere_on = !self.atmosphere_on,
            KeyCode::KeyG => self.settings.governor = self.settings.governor.next(),
            KeyCode::KeyH => {
                // The same view with or without the line: drawn at the
                // window's size, as a still view is.
                self.overlay = !self.overlay;
                self.still_frame = true;
            }
            KeyCode::Equal | KeyCode::NumpadAdd => {
                self.speed *= 1.5;
                self.redraw = false;
            }
            KeyCode::Minus | KeyCode::NumpadSubtract => {
                self.speed /= 1.5;
                self.redraw = false;
            }
            KeyCode::KeyP => {
                self.redraw = false;
                if let Err(e) = self.save() {
                    eprintln!("error: {e}");
                }
            }
            _ => {
                // A key that moves the camera redraws while it is held.
                self.redraw = false;
                self.keys.insert(code);
            }
        }
    }

    /// A display frame, seconds: the governor's budget.
    fn period(&self) -> f64 {
        self.governor.period()
    }

    fn fail(&mut self, event_loop: &ActiveEventLoop, error: Error) {
        self.error = Some(error);
        event_loop.exit();
    }
}

/// A windowing error's message without the source location winit puts
/// before it ("os error at …/mod.rs:788: Failed to open …").
fn os_message(error: &dyn std::fmt::Display) -> String {
    let text = error.to_string();
    text.find(".rs:")
        .and_then(|at| text[at..].find(": ").map(|colon| at + colon + 2))
        .map_or(text.clone(), |start| text[start..].to_string())
}

/// The N of PREFIX-N.png.
fn path_number(path: &Path) -> String {
    path.file_stem()
        .and_then(|s| s.to_str())
        .and_then(|s| s.rsplit('-').next())
        .unwrap_or("0")
        .to_string()
}

impl ApplicationHandler for App<'_> {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.window.is_some() {
            return;
        }
        let (w, h) = self.initial_size;
        let attributes = Window::default_attributes()
            .with_title("terracast")
            .with_inner_size(PhysicalSize::new(w, h));
        let window = match event_loop.create_window(attributes) {
            Ok(window) => Rc::new(window),
            Err(e) => {
                return self.fail(
                    event_loop,
                    Error::new(format!("cannot open a window: {}", os_message(&e))),
                )
            }
        };
        let surface = softbuffer::Context::new(window.clone())
            .and_then(|context| softbuffer::Surface::new(&context, window.clone()));
        match surface {
            Ok(surface) => self.surface = Some(surface),
            Err(e) => {
                return self.fail(
                    event_loop,
                    Error::new(format!("cannot draw into the window: {e}")),
                )
            }
        }
        let hz = self.fps.unwrap_or_else(|| {
            window
                .current_monitor()
                .and_then(|m| m.refresh_rate_millihertz())
                .map_or(60.0, |mhz| mhz as f32 / 1000.0)
        });
        let period = 1.0 / f64::from(hz.max(1.0));
        self.governor = ScaleGovernor::new(period);
        self.budget = FrameBudget::new(period, self.threads);
        window.request_redraw();
        self.window = Some(window);
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _: WindowId, event: WindowEvent) {
        match event {
            WindowEvent::CloseRequested => event_loop.exit(),
            WindowEvent::Resized(_) => self.redraw = true,
            WindowEvent::KeyboardInput { event, .. } => {
                if let PhysicalKey::Code(code) = event.physical_key {
                    self.key(
                        event_loop,
                        code,
                        event.state == ElementState::Pressed,
                        event.repeat,
                    );
                }
            }
            WindowEvent::MouseInput {
                state,
                button: MouseButton::Left,
                ..
            } => {
                self.dragging = state == ElementState::Pressed;
            }
            WindowEvent::CursorMoved { position, .. } => {
                let before = self.cursor.replace(position);
                if let (true, Some(before)) = (self.dragging, before) {
                    let (dx, dy) = (position.x - before.x, position.y - before.y);
                    turn_by(
                        &mut self.camera,
                        dx as f32 * DRAG_DEG_PER_PIXEL,
                        dy as f32 * DRAG_DEG_PER_PIXEL,
                        0.0,
                    );
                    self.redraw = true;
                }
            }
            WindowEvent::CursorLeft { .. } => self.cursor = None,
            WindowEvent::RedrawRequested => {
                if let Err(e) = self.frame() {
                    self.fail(event_loop, e);
                }
            }
            _ => {}
        }
    }

    fn about_to_wait(&mut self, event_loop: &ActiveEventLoop) {
        if let Some(measure) = &self.measure {
            if measure.done() {
                let size = self.window_size;
                let report =
                    measure.report(size, self.threads, self.settings.governor, self.period());
                println!("{report}");
                event_loop.exit();
                return;
            }
        }
        let moving = !self.motion().is_still() || self.measure.is_some();
        let mut flow = ControlFlow::Wait;
        if moving || self.redraw {
            if let Some(window) = &self.window {
                window.request_redraw();
            }
        } else {
            // Nothing changes: the clock that moves the camera restarts
            // with the next key, and a frame the governor shrank or
            // rendered within a budget is drawn once more at the window's
            // size, as the settings say, when the view has been still for
            // a moment (a still view is sharp, and `render` draws it).
            self.last_tick = None;
            let governed = self
                .shown
                .is_some_and(|s| s.size != self.window_size || s.figures.governed.is_some());
            if governed {
                let at = self.last_change + STILL_AFTER;
                if Instant::now() >= at {
                    self.still_frame = true;
                    if let Some(window) = &self.window {
                        window.request_redraw();
                    }
                } else {
                    flow = ControlFlow::WaitUntil(at);
                }
            }
        }
        event_loop.set_control_flow(flow);
    }
}
