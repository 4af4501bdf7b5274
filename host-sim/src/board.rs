//! The host side of the board check: packs the scene the firmware bakes in,
//! and verifies what the emulated board sent back against the host kernel.
//!
//! `scripts/board-check` runs the whole loop: `terracast-sim board scene`,
//! the firmware build, QEMU, `terracast-sim board verify`.

use crate::error::{Error, Result};
use crate::fit::{least_squares, non_negative_least_squares};
use crate::scene::Scene;
use std::fmt::Write as _;
use std::path::Path;
use terracast::{
    pyramid_cells, pyramid_points, render, Atmosphere, Camera, Coherence, CountingProbe, FrameCost,
    Framebuffer, HeightFilter, HeightPath, NoProbe, PreparedAtmosphere, Prices, Pyramid,
    RenderOptions, Stick, Surface, View, WithSticks,
};
use terracast_board::governed;
use terracast_board::scene::{self, BoardScene, Header};
use terracast_board::wire::frame_capture_bytes;
use terracast_board::{decode, rgb565, CaptureBus, SpiDisplay};

/// Tallest image the board check handles (the display driver's column).
pub const MAX_IMAGE_HEIGHT: usize = 1024;

/// Widest map the board holds: 5 bytes a voxel, with the firmware's code,
/// in its 4 MiB of code memory.
pub const MAX_BOARD_SIDE: u32 = 800;

/// The views the board renders, over a `side` map whose highest point is
/// `top`: the `render` command's default view, a grazing view across the
/// map, a steep one, one straight down, and a view at 20° pitch level and
/// rolled 30° (the cost of roll, against its level twin).
pub fn board_views(side: u32, top: f32) -> Vec<Camera> {
    let s = side as f32;
    let camera = terracast::Camera::looking;
    let banking = camera([s * 0.5, s * 0.1, top + 0.05 * s], 90.0, 20.0);
    vec![
        camera(crate::scene::south_edge_eye(side, side, top), 90.0, 12.0),
        camera([s * 0.08, s * 0.1, top + 0.01 * s], 40.0, 2.0),
        camera([s * 0.3, s * 0.3, top + 0.15 * s], 60.0, 45.0),
        camera([s * 0.5, s * 0.5, top + 0.25 * s], 0.0, 90.0),
        banking,
        Camera {
            roll_deg: 30.0,
            ..banking
        },
    ]
}

/// Writes the board scene file for `scene` and `views` at `image` size.
pub fn write_scene(path: &Path, scene: &Scene, image: (u32, u32), views: &[Camera]) -> Result<()> {
    if image.1 as usize > MAX_IMAGE_HEIGHT {
        return Err(Error::new(format!(
            "board images are at most {MAX_IMAGE_HEIGHT} pixels tall"
        )));
    }
    for camera in views {
        View::new(camera, image.0, image.1)
            .map_err(|e| Error::new(format!("bad board view: {e}")))?;
    }
    let kernel = scene.to_kernel()?;
    let terrain = kernel.terrain()?;
    let header = Header::new((scene.width, scene.depth), image, views)
        .map_err(|e| Error::new(e.to_string()))?;
    let mut bytes = Vec::with_capacity(header.file_bytes());
    bytes.extend_from_slice(&header.encode());
    for h in terrain.heights() {
        bytes.extend_from_slice(&h.to_le_bytes());
    }
    bytes.extend(terrain.colors().iter().flatten());
    if let Some(objects) = &scene.objects {
        let voxels = header.voxels();
        if objects.sticks.len() > scene::MAX_STICKS {
            return Err(Error::new(format!(
                "{} sticks; a board scene holds at most {}",
                objects.sticks.len(),
                scene::MAX_STICKS
            )));
        }
        bytes.resize(scene::objects_at(voxels), 0);
        let section = bytes.len();
        bytes.extend_from_slice(&scene::OBJECTS_MAGIC);
        bytes.extend_from_slice(&(objects.sticks.len() as u32).to_le_bytes());
        bytes.extend_from_slice(&(objects.texels.len() as u32).to_le_bytes());
        for p in &objects.points {
            bytes.extend_from_slice(&p.to_le_bytes());
        }
        bytes.resize(section + scene::sticks_at(voxels), 0);
        for stick in &objects.sticks {
            bytes.extend_from_slice(&scene::encode_stick(stick));
        }
        bytes.extend(objects.texels.iter().flatten());
        bytes.extend_from_slice(objects.see_through_alphas());
    }
    std::fs::write(path, &bytes)
        .map_err(|e| Error::new(format!("cannot write {}: {e}", path.display())))
}

/// One view's verdict.
#[derive(Debug, Clone, PartialEq)]
pub struct FrameCheck {
    /// Which view.
    pub index: usize,
    /// Pixels whose RGB888 color differs between board and host.
    pub differing_pixels: usize,
    /// Whether the display wire capture is byte-identical.
    pub wire_identical: bool,
    /// Pixels of the decoded board wire that differ from the host frame in
    /// RGB565.
    pub display_differing_pixels: usize,
    /// Kernel steps and color fetches of the host render (the board's are
    /// the same).
    pub steps: u64,
    /// See `steps`.
    pub color_fetches: u64,
    /// The board's core clock ticks for the kernel render, and for the
    /// render plus sending the frame through the display driver.
    pub kernel_ticks: u64,
    /// See `kernel_ticks`.
    pub display_ticks: u64,
    /// The same view with every ray cast from the eye: pixels that differ
    /// between board and host, host steps and color fetches, and board
    /// ticks.
    pub from_eye_differing_pixels: usize,
    /// See `from_eye_differing_pixels`.
    pub from_eye_steps: u64,
    /// See `from_eye_differing_pixels`.
    pub from_eye_color_fetches: u64,
    /// See `from_eye_differing_pixels`.
    pub from_eye_ticks: u64,
    /// The same view under the flight's sky, sun and fog
    /// (`Atmosphere::FLIGHT`): pixels that differ between board and host,
    /// and board ticks.
    pub atmosphere_differing_pixels: usize,
    /// See `atmosphere_differing_pixels`.
    pub atmosphere_ticks: u64,
    /// The same view under the flight's sky and sun without its fog
    /// (`Atmosphere::without_fog`): pixels that differ between board and
    /// host, and board ticks.
    pub clear_air_differing_pixels: usize,
    /// See `clear_air_differing_pixels`.
    pub clear_air_ticks: u64,
}

/// The kernel's cost on the board, in instructions: what
/// [`BoardReport::cost_fit`] finds and the simulator's default work costs
/// are (see `sim::machine`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CostFit {
    /// A ray's set-up, whatever it sees (a sky ray costs this alone).
    pub per_ray: f64,
    /// A color fetch: a ray that sees terrain makes one or two (at most
    /// [`terracast::MAX_COLOR_FETCHES_A_RAY`]) to shade its pixel.
    pub per_color: f64,
    /// A traversal step or bound test.
    pub per_step: f64,
}

impl FrameCheck {
    /// Whether board and host agree on every byte.
    pub fn identical(&self) -> bool {
        self.differing_pixels == 0
            && self.wire_identical
            && self.display_differing_pixels == 0
            && self.from_eye_differing_pixels == 0
            && self.atmosphere_differing_pixels == 0
            && self.clear_air_differing_pixels == 0
    }
}

/// Everything `board verify` found.
#[derive(Debug, Clone, PartialEq)]
pub struct BoardReport {
    /// Image size.
    pub image: (u32, u32),
    /// Per view.
    pub frames: Vec<FrameCheck>,
    /// Ticks to build the pyramid at boot.
    pub pyramid_ticks: u64,
    /// Instructions a tick, from the board's calibration loop.
    pub instructions_per_tick: f64,
    /// The governor's run (`terracast_board::governed`), on a bare map.
    pub governed: Vec<GovernedCheck>,
    /// Whether the scene has objects (a stick table).
    pub objects: bool,
}

/// One frame of the governor's run on the board.
#[derive(Debug, Clone, PartialEq)]
pub struct GovernedCheck {
    /// Its run's budget, the board's instructions a pixel.
    pub per_pixel: u64,
    /// The camera it was rendered from.
    pub camera: Camera,
    /// Pixels that differ between board and host.
    pub differing_pixels: usize,
    /// What the host's governor did, the board's too when the frames agree.
    pub cost: FrameCost,
    /// The board's ticks for the frame.
    pub ticks: u64,
}

impl BoardReport {
    /// Kernel instructions per pixel over all views.
    pub fn instructions_per_pixel(&self) -> f64 {
        let per_tick = self.instructions_per_tick;
        let ticks: u64 = self.frames.iter().map(|f| f.kernel_ticks).sum();
        let pixels = self.frames.len() as f64 * f64::from(self.image.0) * f64::from(self.image.1);
        ticks as f64 * per_tick / pixels.max(1.0)
    }

    /// The kernel's cost: the least-squares fit of every render's
    /// instructions a pixel to its color fetches and steps a pixel (one ray
    /// a pixel), the default renders and the from-eye ones together. The
    /// from-eye renders take many times the steps for the same picture,
    /// which separates steps from the rest; the views' shares of sky
    /// separate the shading from the ray's set-up.
    pub fn cost_fit(&self) -> CostFit {
        let pixels = f64::from(self.image.0) * f64::from(self.image.1);
        let per_tick = self.instructions_per_tick;
        let points: Vec<([f64; 2], f64)> = self
            .frames
            .iter()
            .flat_map(|f| {
                [
                    (f.color_fetches, f.steps, f.kernel_ticks),
                    (f.from_eye_color_fetches, f.from_eye_steps, f.from_eye_ticks),
                ]
            })
            .map(|(colors, steps, ticks)| {
                (
                    [colors as f64 / pixels, steps as f64 / pixels],
                    ticks as f64 * per_tick / pixels,
                )
            })
            .collect();
        let [per_ray, per_color, per_step] = least_squares(&points);
        CostFit {
            per_ray,
            per_color,
            per_step,
        }
    }

    /// A table of the views and the summary, for the terminal.
    pub fn table(&self) -> String {
        let per_tick = self.instructions_per_tick;
        let pixels = f64::from(self.image.0) * f64::from(self.image.1);
        let mut out = String::from(
            "view  frame       wire       display  steps/px  colors/px  instr/px  instr/step  instr/px with display  from eye: frame  steps/px  colors/px  instr/px  atmosphere: frame  instr/px  no fog: frame  instr/px\n",
        );
        for f in &self.frames {
            let verdict = |ok: bool| if ok { "identical" } else { "DIFFERENT" };
            let instructions = f.kernel_ticks as f64 * per_tick;
            let _ = writeln!(
                out,
                "{:>4}  {:<10}  {:<9}  {:<7}  {:>8.2}  {:>9.2}  {:>8.0}  {:>10.0}  {:>21.0}  {:>15}  {:>8.2}  {:>9.2}  {:>8.0}  {:>17}  {:>8.0}  {:>13}  {:>8.0}",
                f.index,
                verdict(f.differing_pixels == 0),
                verdict(f.wire_identical),
                if f.display_differing_pixels == 0 {
                    "matches"
                } else {
                    "DIFFERS"
                },
                f.steps as f64 / pixels,
                f.color_fetches as f64 / pixels,
                instructions / pixels,
                instructions / (f.steps.max(1) as f64),
                f.display_ticks as f64 * per_tick / pixels,
                verdict(f.from_eye_differing_pixels == 0),
                f.from_eye_steps as f64 / pixels,
                f.from_eye_color_fetches as f64 / pixels,
                f.from_eye_ticks as f64 * per_tick / pixels,
                verdict(f.atmosphere_differing_pixels == 0),
                f.atmosphere_ticks as f64 * per_tick / pixels,
                verdict(f.clear_air_differing_pixels == 0),
                f.clear_air_ticks as f64 * per_tick / pixels,
            );
        }
        let plain: u64 = self.frames.iter().map(|f| f.kernel_ticks).sum();
        let with_air: u64 = self.frames.iter().map(|f| f.atmosphere_ticks).sum();
        let clear_air: u64 = self.frames.iter().map(|f| f.clear_air_ticks).sum();
        let views = self.frames.len().max(1) as f64;
        let _ = writeln!(
            out,
            "with the flight's sky, sun and fog: {:.0} instructions a pixel, {:.3}x the default render's; without its fog {:.0}, {:.3}x; fog on against off {:.3}x",
            with_air as f64 * per_tick / pixels / views,
            with_air as f64 / plain.max(1) as f64,
            clear_air as f64 * per_tick / pixels / views,
            clear_air as f64 / plain.max(1) as f64,
            with_air as f64 / clear_air.max(1) as f64
        );
        let fit = self.cost_fit();
        let _ = writeln!(
            out,
            "cost fit over all renders: {:.0} instructions a ray + {:.0} a color fetch + {:.0} a step",
            fit.per_ray, fit.per_color, fit.per_step
        );
        // How far the fit is from each render, as a share of its count.
        let miss = |colors: u64, steps: u64, ticks: u64| {
            let predicted = fit.per_ray
                + fit.per_color * colors as f64 / pixels
                + fit.per_step * steps as f64 / pixels;
            let actual = ticks as f64 * per_tick / pixels;
            100.0 * (predicted - actual).abs() / actual.max(1.0)
        };
        let worst =
            |each: &dyn Fn(&FrameCheck) -> f64| self.frames.iter().map(each).fold(0.0, f64::max);
        let _ = writeln!(
            out,
            "fit off by at most {:.1} % on a default render, {:.1} % on a from-eye one",
            worst(&|f| miss(f.color_fetches, f.steps, f.kernel_ticks)),
            worst(&|f| miss(f.from_eye_color_fetches, f.from_eye_steps, f.from_eye_ticks)),
        );
        let _ = writeln!(
            out,
            "pyramid build at boot: {:.0} instructions",
            self.pyramid_ticks as f64 * per_tick
        );
        if !self.governed.is_empty() {
            out.push_str(&self.governed_table());
        }
        out
    }

    /// Each governed frame's board instructions.
    fn governed_instructions(&self, check: &GovernedCheck) -> f64 {
        check.ticks as f64 * self.instructions_per_tick
    }

    /// The governor's run: each frame's bias, refinement, cost as priced
    /// and as counted on the board, against the budget; their spread; the
    /// prices fitted to the counts.
    fn governed_table(&self) -> String {
        let mut out = String::from(
            "\ngoverned frames (a run at each budget, Governor::on_board); work a pixel of the image\nframe  budget/px  pitch  frame      bias  coarse lines  filled rays  refined lines  pixels  lines  rays  steps  colors  hits  levels  base/px  priced/budget  board/budget  board/priced\n",
        );
        let image = f64::from(self.image.0) * f64::from(self.image.1);
        for (index, g) in self.governed.iter().enumerate() {
            let budget = g.cost.budget.max(1) as f64;
            let board = self.governed_instructions(g);
            let w = &g.cost.work;
            let _ = writeln!(
                out,
                "{:>5}  {:>9}  {:>5.0}  {:<9}  {:>4.2}  {:>12}  {:>11}  {:>13}  {:>6.3}  {:>5.4}  {:>4.2}  {:>5.2}  {:>6.2}  {:>4.2}  {:>6.2}  {:>7.0}  {:>13.3}  {:>12.3}  {:>12.3}",
                index,
                g.per_pixel,
                g.camera.pitch_deg,
                if g.differing_pixels == 0 {
                    "identical"
                } else {
                    "DIFFERENT"
                },
                g.cost.level_bias.to_num::<f64>(),
                g.cost.coarse_lines,
                g.cost.filled_rays,
                g.cost.refined_lines,
                w.pixels as f64 / image,
                w.lines as f64 / image,
                w.rays as f64 / image,
                w.steps as f64 / image,
                w.colors as f64 / image,
                w.hits as f64 / image,
                w.hit_levels as f64 / image,
                g.cost.base_cost as f64 / image,
                g.cost.cost as f64 / budget,
                board / budget,
                board / (g.cost.cost.max(1) as f64),
            );
        }
        let (least, most) = self.governed_shares();
        let _ = writeln!(
            out,
            "the check's run ({} a pixel): board instructions {least:.3} to {most:.3} of the budget: max/min {:.3}",
            governed::BUDGET_INSTRUCTIONS_PER_PIXEL,
            most / least.max(1e-12)
        );
        let (least, most) = self
            .governed
            .iter()
            .map(|g| self.governed_instructions(g) / g.cost.cost.max(1) as f64)
            .fold((f64::INFINITY, 0.0f64), |(l, h), r| (l.min(r), h.max(r)));
        let _ = writeln!(
            out,
            "every run: board instructions {least:.3} to {most:.3} of the priced cost (a frame that spends its budget stays within it only where the count is under the priced cost)"
        );
        out.push_str(&price_fit(&[self], "these frames"));
        out
    }

    /// The least and the most of the check's governed frames' board
    /// instructions (the run at `governed::BUDGET_INSTRUCTIONS_PER_PIXEL`),
    /// as shares of their budget.
    pub fn governed_shares(&self) -> (f64, f64) {
        self.governed
            .iter()
            .filter(|g| g.per_pixel == governed::BUDGET_INSTRUCTIONS_PER_PIXEL)
            .map(|g| self.governed_instructions(g) / g.cost.budget.max(1) as f64)
            .fold((f64::INFINITY, 0.0f64), |(l, h), s| (l.min(s), h.max(s)))
    }

    /// The most any governed frame's board instructions take of its
    /// budget, over the runs at every budget (0 with none).
    pub fn governed_most_share(&self) -> f64 {
        self.governed
            .iter()
            .map(|g| self.governed_instructions(g) / g.cost.budget.max(1) as f64)
            .fold(0.0, f64::max)
    }
}

/// What the host kernel renders for one view of a board scene.
#[derive(Debug, Clone, PartialEq)]
pub struct HostFrame {
    /// RGB888, row-major: what the board writes as `frame-K.rgb`.
    pub rgb: Vec<u8>,
    /// The display wire capture: what the board writes as `wire-K.bin`.
    pub wire: Vec<u8>,
    /// Kernel steps and color fetches (the board's are the same).
    pub steps: u64,
    /// See `steps`.
    pub color_fetches: u64,
    /// The same view with every ray cast from the eye: what the board
    /// writes as `frame-K-from-eye.rgb`, and its steps.
    pub from_eye_rgb: Vec<u8>,
    /// See `from_eye_rgb`.
    pub from_eye_steps: u64,
    /// See `from_eye_rgb`.
    pub from_eye_color_fetches: u64,
    /// The view under the flight's atmosphere: what the board writes as
    /// `frame-K-atmosphere.rgb`.
    pub atmosphere_rgb: Vec<u8>,
    /// The view under the flight's sky and sun without its fog:
    /// `frame-K-clear-air.rgb`.
    pub clear_air_rgb: Vec<u8>,
}

/// A board scene file read into aligned storage.
#[derive(Debug)]
pub struct SceneFile {
    words: Vec<u16>,
    len: usize,
}

impl SceneFile {
    /// Reads and checks a scene file written by [`write_scene`].
    pub fn read(path: &Path) -> Result<Self> {
        let bytes = read(path)?;
        // Heights are read in place as u16: copy into 2-byte aligned storage.
        let mut words = vec![0u16; bytes.len().div_ceil(2)];
        bytemuck::cast_slice_mut::<u16, u8>(&mut words)[..bytes.len()].copy_from_slice(&bytes);
        let file = Self {
            words,
            len: bytes.len(),
        };
        let header = file
            .scene()
            .map_err(|e| Error::new(format!("{}: {e}", path.display())))?
            .header;
        if header.image_height as usize > MAX_IMAGE_HEIGHT {
            return Err(Error::new(format!(
                "{}: board images are at most {MAX_IMAGE_HEIGHT} pixels tall",
                path.display()
            )));
        }
        Ok(file)
    }

    /// The parsed scene, borrowing the file.
    pub fn scene(&self) -> std::result::Result<BoardScene<'_>, terracast_board::SceneError> {
        BoardScene::parse(&bytemuck::cast_slice::<u16, u8>(&self.words)[..self.len])
    }

    /// Renders every view as the firmware does: pyramid with the default
    /// height filter (and the scene's objects, if it has them), default
    /// options but for `height_path`, into a framebuffer and through the
    /// display driver; then with every ray cast from the eye, and under the
    /// flight's atmosphere; and, over a bare map, the governor's run (at
    /// the default options).
    pub fn render(&self, height_path: HeightPath) -> Result<(Vec<HostFrame>, Vec<GovernedFrame>)> {
        let scene = self.scene().map_err(|e| Error::new(e.to_string()))?;
        let header = scene.header;
        let terrain = scene.terrain().map_err(|e| Error::new(e.to_string()))?;
        let (w, d) = (header.map_width, header.map_depth);
        let mut sticks = vec![Stick::default(); scene.stick_count()];
        let objects = scene
            .objects(&terrain, &mut sticks)
            .map_err(|e| Error::new(e.to_string()))?;
        let mut coarse_heights = vec![0u16; pyramid_points(w, d)];
        let mut coarse_colors = vec![[0u8; 3]; pyramid_points(w, d)];
        let mut bounds = vec![0u16; pyramid_cells(w, d)];
        Pyramid::build_with_sticks(
            &terrain,
            HeightFilter::default(),
            objects.as_ref(),
            &mut coarse_heights,
            &mut coarse_colors,
            &mut bounds,
        )
        .map_err(|e| Error::new(format!("pyramid not built: {e}")))?;
        let pyramid = Pyramid::new(terrain, &coarse_heights, &coarse_colors, &bounds)
            .map_err(|e| Error::new(format!("pyramid rejected: {e}")))?;
        match objects {
            Some(layer) => Ok((
                Self::render_views(&WithSticks::new(&pyramid, layer), header, height_path)?,
                Vec::new(),
            )),
            None => Ok((
                Self::render_views(&pyramid, header, height_path)?,
                governed_run(&pyramid, &header)?,
            )),
        }
    }

    /// Renders every view of `header` over `surface` (see
    /// [`SceneFile::render`]).
    fn render_views<T: Surface>(
        surface: &T,
        header: Header,
        height_path: HeightPath,
    ) -> Result<Vec<HostFrame>> {
        let (width, height) = (header.image_width, header.image_height);
        let options = RenderOptions {
            height_path,
            ..RenderOptions::default()
        };
        let from_eye = RenderOptions {
            coherence: Coherence::Off,
            ..options
        };
        let air = Atmosphere::FLIGHT
            .prepare()
            .map_err(|e| Error::new(e.to_string()))?;
        let clear_air = Atmosphere::FLIGHT
            .without_fog()
            .prepare()
            .map_err(|e| Error::new(e.to_string()))?;
        let mut frames = Vec::new();
        for (index, camera) in header.views().iter().enumerate() {
            let view = View::new(camera, width, height)
                .map_err(|e| Error::new(format!("bad board view {index}: {e}")))?;
            let frame = |options: &RenderOptions,
                         air: Option<&PreparedAtmosphere>|
             -> Result<(Vec<u8>, CountingProbe)> {
                let mut colors = vec![[0u8; 3]; width as usize * height as usize];
                let mut framebuffer = Framebuffer::new(&mut colors, width, height)
                    .map_err(|e| Error::new(e.to_string()))?;
                let mut probe = CountingProbe::default();
                // Pixel by pixel, where the firmware puts the sky first
                // (`SkyFirst`, `sink_over_sky`): the check then holds the
                // two ways to one frame.
                match air {
                    Some(air) => render(
                        surface,
                        &view,
                        options,
                        &mut air.sink(&view, &mut framebuffer),
                        &mut probe,
                    ),
                    None => render(surface, &view, options, &mut framebuffer, &mut probe),
                }
                Ok((colors.into_iter().flatten().collect(), probe))
            };
            let (rgb, counts) = frame(&options, None)?;
            let (from_eye_rgb, from_eye_counts) = frame(&from_eye, None)?;
            let (atmosphere_rgb, _) = frame(&options, Some(&air))?;
            let (clear_air_rgb, _) = frame(&options, Some(&clear_air))?;
            frames.push(HostFrame {
                rgb,
                wire: display_capture(surface, &view, &options, width, height)?,
                steps: counts.steps,
                color_fetches: counts.color_fetches,
                from_eye_rgb,
                from_eye_steps: from_eye_counts.steps,
                from_eye_color_fetches: from_eye_counts.color_fetches,
                atmosphere_rgb,
                clear_air_rgb,
            });
        }
        Ok(frames)
    }
}

/// A frame of the governor's runs on the host: its run's budget (the
/// board's instructions a pixel), its camera, RGB888 bytes and cost.
pub type GovernedFrame = (u64, Camera, Vec<u8>, FrameCost);

/// The governor's runs (`terracast_board::governed`, one at each of its
/// budgets) over `surface`, as the firmware renders them (a bare map's
/// only).
fn governed_run<T: Surface>(surface: &T, header: &Header) -> Result<Vec<GovernedFrame>> {
    let (width, height) = (header.image_width, header.image_height);
    let (cameras, count) = governed::cameras(header.views());
    let mut frames = Vec::new();
    for per_pixel in governed::BUDGETS {
        let mut governor = governed::governor(width, height, per_pixel);
        for camera in &cameras[..count] {
            let view = View::new(camera, width, height)
                .map_err(|e| Error::new(format!("bad governed view: {e}")))?;
            let mut colors = vec![[0u8; 3]; width as usize * height as usize];
            let mut framebuffer = Framebuffer::new(&mut colors, width, height)
                .map_err(|e| Error::new(e.to_string()))?;
            let cost = governor.render(
                surface,
                &view,
                &RenderOptions::default(),
                &mut framebuffer,
                &mut NoProbe,
            );
            frames.push((
                per_pixel,
                *camera,
                colors.into_iter().flatten().collect(),
                cost,
            ));
        }
    }
    Ok(frames)
}

/// Checks the board's output in `from` (`frame-K.rgb`, `wire-K.bin`,
/// `board-results.txt`) against the host kernel rendering `scene_path`
/// with its line caster reading heights on `height_path`.
pub fn verify(scene_path: &Path, from: &Path, height_path: HeightPath) -> Result<BoardReport> {
    let file = SceneFile::read(scene_path)?;
    let scene = file.scene().map_err(|e| Error::new(e.to_string()))?;
    let (header, objects) = (scene.header, scene.stick_count() > 0);
    let (width, height) = (header.image_width, header.image_height);
    let results = parse_results(&read(&from.join("board-results.txt"))?)?;
    let pixels = width as usize * height as usize;
    let mut frames = Vec::new();
    // Pixels of the board's `name` that differ from the host's `rgb`.
    let compare = |name: String, rgb: &[u8]| -> Result<usize> {
        let board_frame = read(&from.join(&name))?;
        if board_frame.len() != pixels * 3 {
            return Err(Error::new(format!(
                "{name} has {} bytes, expected {}",
                board_frame.len(),
                pixels * 3
            )));
        }
        Ok(board_frame
            .chunks_exact(3)
            .zip(rgb.chunks_exact(3))
            .filter(|(board, host)| board != host)
            .count())
    };
    let (host_frames, run) = file.render(height_path)?;
    for (index, host) in host_frames.into_iter().enumerate() {
        let differing_pixels = compare(format!("frame-{index}.rgb"), &host.rgb)?;
        let from_eye_differing_pixels =
            compare(format!("frame-{index}-from-eye.rgb"), &host.from_eye_rgb)?;
        let atmosphere_differing_pixels = compare(
            format!("frame-{index}-atmosphere.rgb"),
            &host.atmosphere_rgb,
        )?;
        let clear_air_differing_pixels =
            compare(format!("frame-{index}-clear-air.rgb"), &host.clear_air_rgb)?;
        let board_wire = read(&from.join(format!("wire-{index}.bin")))?;
        let mut shown = vec![0u16; pixels];
        decode(&board_wire, &mut shown, width, height)
            .map_err(|e| Error::new(format!("wire-{index}.bin: {e}")))?;
        let display_differing_pixels = shown
            .iter()
            .zip(host.rgb.chunks_exact(3))
            .filter(|(shown, host)| **shown != rgb565([host[0], host[1], host[2]]))
            .count();
        let (kernel_ticks, display_ticks, from_eye_ticks, atmosphere_ticks, clear_air_ticks) =
            *results.frames.get(index).ok_or_else(|| {
                Error::new(format!("board-results.txt has no timing for frame {index}"))
            })?;
        frames.push(FrameCheck {
            index,
            differing_pixels,
            wire_identical: host.wire == board_wire,
            display_differing_pixels,
            steps: host.steps,
            color_fetches: host.color_fetches,
            kernel_ticks,
            display_ticks,
            from_eye_differing_pixels,
            from_eye_steps: host.from_eye_steps,
            from_eye_color_fetches: host.from_eye_color_fetches,
            from_eye_ticks,
            atmosphere_differing_pixels,
            atmosphere_ticks,
            clear_air_differing_pixels,
            clear_air_ticks,
        });
    }
    let mut governed = Vec::new();
    if !results.governed.is_empty() {
        if run.len() != results.governed.len() {
            return Err(Error::new(format!(
                "board-results.txt has {} governed frames, the host's run {}",
                results.governed.len(),
                run.len()
            )));
        }
        for (index, ((per_pixel, camera, rgb, cost), ticks)) in
            run.into_iter().zip(&results.governed).enumerate()
        {
            governed.push(GovernedCheck {
                per_pixel,
                camera,
                differing_pixels: compare(format!("frame-{index}-governed.rgb"), &rgb)?,
                cost,
                ticks: *ticks,
            });
        }
    }
    Ok(BoardReport {
        image: (width, height),
        frames,
        pyramid_ticks: results.pyramid_ticks,
        instructions_per_tick: results.instructions_per_tick()?,
        governed,
        objects,
    })
}

/// The board's kernel renders of `report` (a scene with objects, or heights
/// read on each ray's path) against those of the same views without that,
/// whose `board-results.txt` is in `without`: instructions a pixel of each
/// and their ratio, as a table under the title `what`.
pub fn against_without(report: &BoardReport, without: &Path, what: &str) -> Result<String> {
    let bare = parse_results(&read(&without.join("board-results.txt"))?)?;
    if bare.frames.len() != report.frames.len() {
        return Err(Error::new(format!(
            "{} has {} views, the run against it {}",
            without.display(),
            bare.frames.len(),
            report.frames.len()
        )));
    }
    let pixels = f64::from(report.image.0) * f64::from(report.image.1);
    let (with_tick, bare_tick) = (report.instructions_per_tick, bare.instructions_per_tick()?);
    let mut out =
        format!("{what} (the same views): instructions a pixel\nview  without  with  ratio\n");
    let (mut all_bare, mut all_with) = (0.0, 0.0);
    for (f, &(bare_ticks, ..)) in report.frames.iter().zip(&bare.frames) {
        let (without, with) = (
            bare_ticks as f64 * bare_tick / pixels,
            f.kernel_ticks as f64 * with_tick / pixels,
        );
        let _ = writeln!(
            out,
            "{:>4}  {without:>7.0}  {with:>4.0}  {:>5.3}x",
            f.index,
            with / without.max(1.0)
        );
        all_bare += without;
        all_with += with;
    }
    let _ = writeln!(
        out,
        " all  {:>7.0}  {:>4.0}  {:>5.3}x",
        all_bare / report.frames.len().max(1) as f64,
        all_with / report.frames.len().max(1) as f64,
        all_with / all_bare.max(1.0)
    );
    Ok(out)
}

/// The prices that fit the governed frames of `reports` best, as one line
/// naming them `what`: the non-negative least-squares fit of each frame's
/// board instructions to its work, the base pass's (pixels on straight
/// lines, lines, rays, hit levels) and the refinement's (lines, rays,
/// hits, hit levels) apart, any other written pixel's price and a far
/// hit's color square's shared, and a step's held at `Prices::BOARD`'s in
/// both (these frames take a few steps a pixel, too few to tell it
/// apart); and how far the fit is from the counts. The line caster casts
/// no ray into the sky but the one a line leaves the terrain with, so a
/// base pass ray is a hit: its price is both. Runs on more than one map
/// keep the prices from fitting one terrain alone.
pub fn price_fit(reports: &[&BoardReport], what: &str) -> String {
    let step = f64::from(Prices::BOARD.per_step);
    let frames: Vec<(&GovernedCheck, f64)> = reports
        .iter()
        .flat_map(|r| r.governed.iter().map(|g| (g, r.governed_instructions(g))))
        .collect();
    let rows: Vec<([f64; 10], f64)> = frames
        .iter()
        .map(|&(g, board)| {
            let (base, refined, all) = (&g.cost.base_work, g.cost.refined_work(), &g.cost.work);
            (
                [
                    all.pixels - base.straight_pixels,
                    all.color_squares,
                    base.straight_pixels,
                    base.lines,
                    base.rays,
                    base.hit_levels,
                    refined.lines,
                    refined.rays,
                    refined.hits,
                    refined.hit_levels,
                ]
                .map(|n| n as f64),
                board - step * all.steps as f64,
            )
        })
        .collect();
    let Some(fit) = non_negative_least_squares(&rows) else {
        return format!("prices fitted to {what}: the frames do not tell them apart\n");
    };
    let (low, high) = frames
        .iter()
        .zip(&rows)
        .map(|(&(g, board), (x, _))| {
            let priced: f64 = x.iter().zip(fit).map(|(n, p)| n * p).sum::<f64>()
                + step * g.cost.work.steps as f64;
            priced / board - 1.0
        })
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), e| {
            (l.min(e), h.max(e))
        });
    let [pixel, square, straight, line, ray, level, r_line, r_ray, r_hit, r_level] = fit;
    let (b, r) = (Prices::BOARD_LINES, Prices::BOARD);
    let (low, high) = (100.0 * low, 100.0 * high);
    format!(
        "prices fitted to {what} (non-negative least squares, a step's price held at {step:.0}): \
         {pixel:.0} a pixel written and {square:.0} a far hit's color square in both passes \
         (Prices::BOARD_LINES: {}, {}; Prices::BOARD: {}, {}); base pass {straight:.0} a pixel on a \
         straight line, {line:.0} a line, {ray:.0} a ray, {level:.0} a hit level \
         (Prices::BOARD_LINES: {}, {}, {}, {}); refinement {r_line:.0} a line, {r_ray:.0} a ray, \
         {r_hit:.0} a hit, {r_level:.0} a hit level (Prices::BOARD: {}, {}, {}, {}); \
         off the counts by {low:+.1} % to {high:+.1} %\n",
        b.per_pixel,
        b.per_color_square,
        r.per_pixel,
        r.per_color_square,
        b.per_straight_pixel,
        b.per_line,
        b.per_ray,
        b.per_hit_level,
        r.per_line,
        r.per_ray,
        r.per_hit,
        r.per_hit_level,
    )
}

/// The display wire the host produces for a view, init included.
fn display_capture<T: Surface>(
    surface: &T,
    view: &View,
    options: &RenderOptions,
    width: u32,
    height: u32,
) -> Result<Vec<u8>> {
    let mut buffer = vec![0u8; frame_capture_bytes(width, height)];
    let bus = CaptureBus::new(&mut buffer);
    let mut display: SpiDisplay<_, _, _, MAX_IMAGE_HEIGHT> = SpiDisplay::new(
        bus.spi(),
        bus.data_command(),
        bus.frame_done(),
        width,
        height,
    )
    .map_err(|e| Error::new(e.to_string()))?;
    display
        .init(&mut NoDelay)
        .map_err(|e| Error::new(e.to_string()))?;
    let mut colors = vec![[0u8; 3]; width as usize * height as usize];
    let mut framebuffer =
        Framebuffer::new(&mut colors, width, height).map_err(|e| Error::new(e.to_string()))?;
    render(surface, view, options, &mut framebuffer, &mut NoProbe);
    display
        .send_frame(&colors)
        .map_err(|e| Error::new(e.to_string()))?;
    let _ = display.release();
    let wire = bus.into_written().map_err(|e| Error::new(e.to_string()))?;
    Ok(wire.to_vec())
}

/// The host needs no real delay: the capture has no timing.
struct NoDelay;

impl embedded_hal::delay::DelayNs for NoDelay {
    fn delay_ns(&mut self, _ns: u32) {}
}

struct BoardResults {
    /// Instructions and ticks of the calibration loop.
    calibration: Option<(u64, u64)>,
    pyramid_ticks: u64,
    /// Kernel, displayed, from-eye, atmosphere and clear-air ticks of each
    /// frame.
    frames: Vec<(u64, u64, u64, u64, u64)>,
    /// Ticks of each frame of the governor's run.
    governed: Vec<u64>,
}

impl BoardResults {
    fn instructions_per_tick(&self) -> Result<f64> {
        match self.calibration {
            Some((instructions, ticks)) if instructions > 0 && ticks > 0 => {
                Ok(instructions as f64 / ticks as f64)
            }
            _ => Err(Error::new(
                "board-results.txt has no usable calibration line",
            )),
        }
    }
}

/// Reads `board-results.txt`: `calibration instructions N ticks T`,
/// `pyramid_ticks N`, `frame K kernel_ticks N display_ticks M
/// from_eye_ticks O atmosphere_ticks A clear_air_ticks C` and `governed K
/// ticks N` lines.
fn parse_results(bytes: &[u8]) -> Result<BoardResults> {
    let text =
        std::str::from_utf8(bytes).map_err(|_| Error::new("board-results.txt is not text"))?;
    let mut results = BoardResults {
        calibration: None,
        pyramid_ticks: 0,
        frames: Vec::new(),
        governed: Vec::new(),
    };
    for (number, line) in text.lines().enumerate() {
        let words: Vec<&str> = line.split_whitespace().collect();
        let bad = || {
            Error::new(format!(
                "board-results.txt line {}: cannot read '{line}'",
                number + 1
            ))
        };
        let int = |s: &str| s.parse::<u64>().map_err(|_| bad());
        match words.as_slice() {
            [] => {}
            ["calibration", "instructions", n, "ticks", t] => {
                results.calibration = Some((int(n)?, int(t)?));
            }
            ["pyramid_ticks", n] => results.pyramid_ticks = int(n)?,
            ["frame", k, "kernel_ticks", n, "display_ticks", m, "from_eye_ticks", o, "atmosphere_ticks", a, "clear_air_ticks", c] =>
            {
                if int(k)? != results.frames.len() as u64 {
                    return Err(bad());
                }
                results
                    .frames
                    .push((int(n)?, int(m)?, int(o)?, int(a)?, int(c)?));
            }
            ["governed", k, "ticks", n] => {
                if int(k)? != results.governed.len() as u64 {
                    return Err(bad());
                }
                results.governed.push(int(n)?);
            }
            _ => return Err(bad()),
        }
    }
    Ok(results)
}

fn read(path: &Path) -> Result<Vec<u8>> {
    std::fs::read(path).map_err(|e| Error::new(format!("cannot read {}: {e}", path.display())))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn results_are_read_and_bad_lines_named() {
        let ok = parse_results(
            b"calibration instructions 400 ticks 10\npyramid_ticks 12\nframe 0 kernel_ticks 5 display_ticks 7 from_eye_ticks 9 atmosphere_ticks 6 clear_air_ticks 4\nframe 1 kernel_ticks 6 display_ticks 8 from_eye_ticks 10 atmosphere_ticks 7 clear_air_ticks 5\n",
        )
        .unwrap();
        assert_eq!(ok.pyramid_ticks, 12);
        assert_eq!(ok.frames, vec![(5, 7, 9, 6, 4), (6, 8, 10, 7, 5)]);
        assert_eq!(ok.instructions_per_tick().unwrap(), 40.0);
        let uncalibrated = parse_results(b"pyramid_ticks 12\n").unwrap();
        assert!(uncalibrated.instructions_per_tick().is_err());
        let e = parse_results(b"frame 1 kernel_ticks 5 display_ticks 7\n")
            .err()
            .unwrap();
        assert!(e.to_string().contains("line 1"), "{e}");
        assert!(parse_results(b"frame 0 kernel_ticks x display_ticks 7").is_err());
    }

    #[test]
    fn host_wire_decodes_to_the_host_frame() {
        let scene = crate::scene::procedural(64, 3);
        let kernel = scene.to_kernel().unwrap();
        let pyramid = kernel.pyramid().unwrap();
        let camera = board_views(64, scene.max_height())[0];
        let view = View::new(&camera, 48, 32).unwrap();
        let options = RenderOptions::default();
        let mut colors = vec![[0u8; 3]; 48 * 32];
        let mut fb = Framebuffer::new(&mut colors, 48, 32).unwrap();
        render(&pyramid, &view, &options, &mut fb, &mut NoProbe);
        let wire = display_capture(&pyramid, &view, &options, 48, 32).unwrap();
        assert_eq!(wire.len(), frame_capture_bytes(48, 32));
        let mut shown = vec![0u16; 48 * 32];
        let decoded = decode(&wire, &mut shown, 48, 32).unwrap();
        assert_eq!(decoded.frames, 1);
        assert_eq!(decoded.pixels, 48 * 32);
        let expected: Vec<u16> = colors.iter().map(|&c| rgb565(c)).collect();
        assert_eq!(shown, expected);
    }
}
