//! terracast on the reference board: an Arm MPS2 with the AN500 image
//! (Cortex-M7), as emulated by `qemu-system-arm -machine mps2-an500`.
//!
//! At boot it builds the pyramid of the baked-in scene into static RAM, then
//! for each of the scene's views:
//!
//! 1. renders it into a framebuffer with the sky put first (`SkyFirst`),
//!    which is written to the host as
//!    `frame-K.rgb` (RGB888, row-major) — the frame the host kernel must
//!    match byte for byte;
//! 2. sends the framebuffer through the SPI display driver, whose wire
//!    traffic is captured and written as `wire-K.bin` — the stream a panel
//!    would receive;
//! 3. renders it again with every ray cast from the eye (coherence off),
//!    written as `frame-K-from-eye.rgb`: the same rays with many more
//!    steps, which separates the cost of a step from that of a ray;
//! 4. renders it again with the flight's sky, sun and fog
//!    (`Atmosphere::FLIGHT`), written as `frame-K-atmosphere.rgb`, and
//!    with its sky and sun alone, as `frame-K-clear-air.rgb`: what the
//!    atmosphere costs a pixel, and what its fog does.
//!
//! A scene with objects (`terracast-sim board scene --objects`) renders
//! them through its stick layer, whose table is decoded into static RAM at
//! boot.
//!
//! The renders, and the render plus the transfer, are timed with SysTick. Under QEMU's `-icount` the clock
//! advances by instruction count, so ticks convert to instructions exactly
//! and repeatably (QEMU does not model the DWT cycle counter). A loop of a
//! known number of instructions is timed first, to calibrate that
//! conversion. The ticks go to `board-results.txt`; `terracast-sim board
//! verify` turns them into instructions per pixel. Everything is reported over semihosting, and the
//! firmware exits QEMU with status 0 on success.
//!
//! What lives where is described in `memory.x`.
#![no_std]
#![no_main]

use core::fmt::Write as _;
use core::ptr::addr_of_mut;
use core::sync::atomic::{AtomicU32, Ordering};
use cortex_m::peripheral::{syst::SystClkSource, SYST};
use cortex_m_rt::{entry, exception};
use cortex_m_semihosting::{debug, hprintln, nr, syscall};
use embedded_hal::delay::DelayNs;
use embedded_hal::digital::{ErrorType, OutputPin};
use panic_semihosting as _;
use terracast::{
    max_lines, pyramid_cells, pyramid_points, render, render_level_columns,
    render_level_columns_lean, render_pixel_lines, render_pixel_path, render_pixel_path_lean,
    render_pixel_path_tabled, tabulate_pixel_ownership, Atmosphere, Camera, Coherence, Framebuffer,
    HeightFilter, HeightPath, NoProbe, PreparedAtmosphere, Pyramid, RenderOptions, Resolution, Rgb,
    Shading, SkyFirst, Stick, Surface, View, WithSticks, U8F8,
};
use terracast_board::governed;
use terracast_board::scene::{BoardScene, MAX_STICKS};
use terracast_board::{wire::frame_capture_bytes, CaptureBus, SpiDisplay};

/// Lets the scene file be read in place as `u16` heights.
#[repr(C, align(4))]
pub struct Aligned<T: ?Sized>(T);

mod scene {
    use super::Aligned;
    include!(concat!(env!("OUT_DIR"), "/scene.rs"));
}
use scene::{IMAGE_HEIGHT, IMAGE_WIDTH, MAP_DEPTH, MAP_WIDTH, SCENE};

const PYRAMID_POINTS: usize = pyramid_points(MAP_WIDTH, MAP_DEPTH);
const PYRAMID_CELLS: usize = pyramid_cells(MAP_WIDTH, MAP_DEPTH);
const PIXELS: usize = IMAGE_WIDTH as usize * IMAGE_HEIGHT as usize;
const CAPTURE_BYTES: usize = frame_capture_bytes(IMAGE_WIDTH, IMAGE_HEIGHT);
const COLUMN: usize = IMAGE_HEIGHT as usize;
/// The frame's pixel-ownership table (`render_pixel_path_tabled`), in
/// the bound's build only: a pixel each in two arrays, a line each.
const TABLED: bool = option_env!("TERRACAST_BOARD_BOUND").is_some();
const TABLE_PIXELS: usize = if TABLED { PIXELS } else { 0 };
const TABLE_LINES: usize = if TABLED {
    max_lines(IMAGE_WIDTH, IMAGE_HEIGHT) as usize + 1
} else {
    0
};

// The board's working memory, in .bss (RAM). Each is borrowed mutably
// exactly once, at the top of `main`.
static mut COARSE_HEIGHTS: [u16; PYRAMID_POINTS] = [0; PYRAMID_POINTS];
static mut COARSE_COLORS: [Rgb; PYRAMID_POINTS] = [[0; 3]; PYRAMID_POINTS];
static mut BOUNDS: [u16; PYRAMID_CELLS] = [0; PYRAMID_CELLS];
static mut FRAME: [Rgb; PIXELS] = [[0; 3]; PIXELS];
static mut CAPTURE: [u8; CAPTURE_BYTES] = [0; CAPTURE_BYTES];
static mut LINE_OF: [u16; TABLE_PIXELS] = [0; TABLE_PIXELS];
static mut ORDER: [u32; TABLE_PIXELS] = [0; TABLE_PIXELS];
static mut STARTS: [u32; TABLE_LINES] = [0; TABLE_LINES];
static mut STICKS: [Stick; MAX_STICKS] = [Stick {
    first: 0,
    texels: 0,
    height: 0,
}; MAX_STICKS];

/// SysTick's reload: the full 24 bits.
const RELOAD: u32 = 0x00FF_FFFF;
/// SysTick wraps, counted by its exception.
static WRAPS: AtomicU32 = AtomicU32::new(0);

#[exception]
fn SysTick() {
    WRAPS.fetch_add(1, Ordering::Relaxed);
}

/// Core clock ticks since the counter started.
fn ticks() -> u64 {
    loop {
        let before = WRAPS.load(Ordering::Relaxed);
        let current = SYST::get_current();
        if WRAPS.load(Ordering::Relaxed) == before {
            return u64::from(before) * (u64::from(RELOAD) + 1) + u64::from(RELOAD - current);
        }
    }
}

/// Instructions the calibration loop runs: two an iteration.
const CALIBRATION_INSTRUCTIONS: u32 = 20_000_000;

/// Ticks of a loop of exactly [`CALIBRATION_INSTRUCTIONS`] instructions:
/// the host divides by them to turn ticks into instructions, whatever the
/// emulator's clock model and `-icount` shift.
fn calibration_ticks() -> u64 {
    let start = ticks();
    // SAFETY: a countdown in one register; touches no memory or stack.
    unsafe {
        core::arch::asm!(
            "2:",
            "subs {n}, {n}, #1",
            "bne 2b",
            n = inout(reg) CALIBRATION_INSTRUCTIONS / 2 => _,
            options(nomem, nostack),
        );
    }
    ticks() - start
}

/// A busy-wait delay at the board's 25 MHz core clock.
struct BusyDelay;

impl DelayNs for BusyDelay {
    fn delay_ns(&mut self, ns: u32) {
        cortex_m::asm::delay(ns / 40 + 1);
    }
}

/// The FPGA's user LED 0 (FPGAIO at 0x4002_8000, LED register at offset 0):
/// blinks once a frame alongside the display's frame-done line.
struct FrameLed;

impl ErrorType for FrameLed {
    type Error = core::convert::Infallible;
}

impl OutputPin for FrameLed {
    fn set_low(&mut self) -> Result<(), Self::Error> {
        // SAFETY: the FPGAIO LED register is a write-only MMIO word on the
        // MPS2 memory map; no other code touches it.
        unsafe { core::ptr::write_volatile(0x4002_8000 as *mut u32, 0) };
        Ok(())
    }

    fn set_high(&mut self) -> Result<(), Self::Error> {
        // SAFETY: as in `set_low`.
        unsafe { core::ptr::write_volatile(0x4002_8000 as *mut u32, 1) };
        Ok(())
    }
}

/// Writes a file on the host (QEMU's working directory); `name` ends in NUL.
fn write_host_file(name: &str, bytes: &[u8]) -> Result<(), &'static str> {
    let path = name.as_bytes();
    if path.last() != Some(&0) {
        return Err("host file name must end in NUL");
    }
    // SAFETY: semihosting calls with a NUL-terminated name and its length
    // without the NUL, then a live buffer and its length, as the Arm
    // semihosting specification requires.
    let handle = unsafe {
        syscall!(
            OPEN,
            path.as_ptr(),
            nr::open::W_TRUNC_BINARY,
            path.len() - 1
        )
    };
    if handle as isize == -1 {
        return Err("semihosting cannot open a host file");
    }
    // SAFETY: as above; WRITE returns the number of bytes not written.
    let unwritten = unsafe { syscall!(WRITE, handle, bytes.as_ptr(), bytes.len()) };
    // SAFETY: `handle` is the open file of this call.
    unsafe { syscall!(CLOSE, handle) };
    if unwritten != 0 {
        return Err("semihosting write to a host file failed");
    }
    Ok(())
}

/// The resolution the views are rendered with: the default, or for
/// scripts/board-profile the one named at build time by
/// `TERRACAST_BOARD_RESOLUTION` (`single`, or a pixel-to-voxel ratio in
/// 256ths: `128` is 0.5). Any other value stops the build.
/// scripts/board-check always builds the default.
const RESOLUTION: Resolution = match option_env!("TERRACAST_BOARD_RESOLUTION") {
    Some(name) => resolution_named(name.as_bytes()),
    None => Resolution::DEFAULT,
};

/// See [`RESOLUTION`]; empty is the default.
const fn resolution_named(name: &[u8]) -> Resolution {
    const USAGE: &str =
        "TERRACAST_BOARD_RESOLUTION: `single`, or a pixel-to-voxel ratio in 256ths (1 to 65535)";
    if name.is_empty() {
        return Resolution::DEFAULT;
    }
    if name.len() == 6 {
        let (single, mut i) = (b"single", 0);
        while i < 6 && name[i] == single[i] {
            i += 1;
        }
        if i == 6 {
            return Resolution::Single;
        }
    }
    let (mut ratio, mut i) = (0u32, 0);
    while i < name.len() {
        assert!(name[i].is_ascii_digit(), "{}", USAGE);
        ratio = ratio * 10 + (name[i] - b'0') as u32;
        assert!(ratio <= u16::MAX as u32, "{}", USAGE);
        i += 1;
    }
    assert!(ratio >= 1, "{}", USAGE);
    Resolution::Multi {
        pixel_to_voxel: U8F8::from_bits(ratio as u16),
    }
}

/// The shading the views are rendered with: subvoxel (the default), or
/// for scripts/board-profile nearest when `TERRACAST_BOARD_SHADING` is
/// `nearest` at build time. Any other value stops the build.
const SHADING: Shading = match option_env!("TERRACAST_BOARD_SHADING") {
    Some(name) => shading_named(name.as_bytes()),
    None => Shading::Subvoxel,
};

/// See [`SHADING`]; empty is the default.
const fn shading_named(name: &[u8]) -> Shading {
    match name {
        b"" | b"subvoxel" => Shading::Subvoxel,
        b"nearest" => Shading::Nearest,
        _ => panic!("TERRACAST_BOARD_SHADING: `subvoxel` or `nearest`"),
    }
}

/// Where the line caster reads heights: on each image line's plane (the
/// default), or on each ray's own path when `TERRACAST_BOARD_HEIGHT_PATH`
/// is `ray` at build time (scripts/board-check's third run, which leaves
/// the governor's run out: that is the default's). Any other value stops
/// the build.
const HEIGHT_PATH: HeightPath = match option_env!("TERRACAST_BOARD_HEIGHT_PATH") {
    Some(name) => height_path_named(name.as_bytes()),
    None => HeightPath::DEFAULT,
};

/// See [`HEIGHT_PATH`]; empty is the default.
const fn height_path_named(name: &[u8]) -> HeightPath {
    match name {
        b"" | b"line" => HeightPath::Line,
        b"ray" => HeightPath::Ray,
        _ => panic!("TERRACAST_BOARD_HEIGHT_PATH: `line` or `ray`"),
    }
}

#[entry]
fn main() -> ! {
    let code = match run() {
        Ok(()) => debug::EXIT_SUCCESS,
        Err(message) => {
            hprintln!("terracast-firmware: {}", message);
            debug::EXIT_FAILURE
        }
    };
    debug::exit(code);
    loop {
        cortex_m::asm::wfi();
    }
}

fn run() -> Result<(), &'static str> {
    // SAFETY: `run` is called once, from `main`, before any interrupt that
    // could reach these statics is enabled (none ever does); each is
    // borrowed exactly once here.
    let (coarse_heights, coarse_colors, bounds, frame, capture, sticks) = unsafe {
        (
            &mut *addr_of_mut!(COARSE_HEIGHTS),
            &mut *addr_of_mut!(COARSE_COLORS),
            &mut *addr_of_mut!(BOUNDS),
            &mut *addr_of_mut!(FRAME),
            &mut *addr_of_mut!(CAPTURE),
            &mut *addr_of_mut!(STICKS),
        )
    };
    let mut core = cortex_m::Peripherals::take().ok_or("core peripherals taken twice")?;
    core.SYST.set_clock_source(SystClkSource::Core);
    core.SYST.set_reload(RELOAD);
    core.SYST.clear_current();
    core.SYST.enable_interrupt();
    core.SYST.enable_counter();
    // The counter starts from 0 and reloads on its first tick: wait for
    // that, so that the first reading is on the running count.
    while SYST::get_current() == 0 {}

    let calibration = calibration_ticks();
    let scene = BoardScene::parse(&SCENE.0).map_err(|_| "the baked-in scene does not parse")?;
    let terrain = scene
        .terrain()
        .map_err(|_| "the kernel refused the terrain")?;
    let objects = scene
        .objects(&terrain, sticks)
        .map_err(|_| "the kernel refused the scene's objects")?;
    let start = ticks();
    Pyramid::build_with_sticks(
        &terrain,
        HeightFilter::default(),
        objects.as_ref(),
        coarse_heights,
        coarse_colors,
        bounds,
    )
    .map_err(|_| "pyramid storage does not match the map")?;
    let pyramid_ticks = ticks() - start;
    let pyramid = Pyramid::new(terrain, coarse_heights, coarse_colors, bounds)
        .map_err(|_| "the kernel refused the pyramid")?;
    let options = RenderOptions {
        resolution: RESOLUTION,
        shading: SHADING,
        height_path: HEIGHT_PATH,
        ..RenderOptions::default()
    };
    let from_eye = RenderOptions {
        coherence: Coherence::Off,
        ..options
    };

    let air = Atmosphere::FLIGHT
        .prepare()
        .map_err(|_| "the kernel refused the flight's atmosphere")?;
    let clear_air = Atmosphere::FLIGHT
        .without_fog()
        .prepare()
        .map_err(|_| "the kernel refused the flight's sky and sun")?;

    let mut results: heapless::String<4096> = heapless::String::new();
    let _ = writeln!(
        results,
        "calibration instructions {CALIBRATION_INSTRUCTIONS} ticks {calibration}"
    );
    let _ = writeln!(results, "pyramid_ticks {pyramid_ticks}");
    hprintln!(
        "terracast-firmware: {}x{} map, pyramid built in {} ticks",
        MAP_WIDTH,
        MAP_DEPTH,
        pyramid_ticks
    );
    // scripts/board-profile BOUND=path (or lean): the per-pixel path
    // alone (or at its leanest), each view once, and nothing else;
    // BOUND=columns: the column caster written lean, each view turned
    // level.
    let bound = option_env!("TERRACAST_BOARD_BOUND");
    if bound == Some("columns") {
        let single = RenderOptions {
            resolution: Resolution::Single,
            ..RenderOptions::default()
        };
        for camera in scene.header.views() {
            let view = View::new(&camera.turned_level(), IMAGE_WIDTH, IMAGE_HEIGHT)
                .map_err(|_| "a view is refused")?;
            render_level_columns_lean(pyramid.base(), &view, &single, frame)
                .map_err(|_| "not a level view")?;
            // The frame is read after: its colors are worked out.
            core::hint::black_box(&mut *frame);
        }
        return Ok(());
    }
    if bound == Some("path") || bound == Some("lean") {
        for camera in scene.header.views() {
            let view =
                View::new(camera, IMAGE_WIDTH, IMAGE_HEIGHT).map_err(|_| "a view is refused")?;
            if bound == Some("lean") {
                // SAFETY: as the statics above; borrowed only here.
                let table: (&mut [u16], &mut [u32], &mut [u32]) = unsafe {
                    (
                        &mut *addr_of_mut!(LINE_OF),
                        &mut *addr_of_mut!(ORDER),
                        &mut *addr_of_mut!(STARTS),
                    )
                };
                render_pixel_path_lean(
                    pyramid.base(),
                    &view,
                    &RenderOptions {
                        shading: SHADING,
                        ..RenderOptions::default()
                    },
                    table,
                    frame,
                )
                .map_err(|_| "the pixel table is too small")?;
                // The frame is read after: its colors are worked out.
                core::hint::black_box(&mut *frame);
                continue;
            }
            let mut framebuffer = Framebuffer::new(frame, IMAGE_WIDTH, IMAGE_HEIGHT)
                .map_err(|_| "framebuffer too small")?;
            render_pixel_path(
                pyramid.base(),
                &view,
                &RenderOptions::default(),
                &mut framebuffer,
            );
        }
        return Ok(());
    }
    // scripts/board-bound: the per-pixel path against its bound, and
    // nothing else.
    if option_env!("TERRACAST_BOARD_BOUND").is_some() {
        hprintln!(
            "calibration instructions {} ticks {}",
            CALIBRATION_INSTRUCTIONS,
            calibration
        );
        // SAFETY: as the statics above; borrowed only here.
        let table: (&mut [u16], &mut [u32], &mut [u32]) = unsafe {
            (
                &mut *addr_of_mut!(LINE_OF),
                &mut *addr_of_mut!(ORDER),
                &mut *addr_of_mut!(STARTS),
            )
        };
        return level_bound(&pyramid, scene.header.views(), frame, table);
    }
    let renders = Renders {
        options,
        from_eye,
        air,
        clear_air,
    };
    let views = scene.header.views();
    match objects {
        Some(layer) => renders.all(
            &WithSticks::new(&pyramid, layer),
            views,
            frame,
            capture,
            &mut results,
        )?,
        // scripts/board-profile GOVERNED=1 profiles the governor's run alone.
        None if option_env!("TERRACAST_BOARD_GOVERNED_ONLY").is_some() => {
            governed_run(&pyramid, views, &options, frame, &mut results)?;
        }
        None => {
            renders.all(&pyramid, views, frame, capture, &mut results)?;
            if option_env!("TERRACAST_BOARD_DEFAULT_ONLY").is_none()
                && matches!(HEIGHT_PATH, HeightPath::Line)
            {
                governed_run(&pyramid, views, &options, frame, &mut results)?;
            }
        }
    }
    write_host_file("board-results.txt\0", results.as_bytes())
}

/// The governor's check (`terracast_board::governed`): its cameras in
/// order at each of its budgets, each frame within its run's budget, its
/// ticks to `results` and its frame to the host.
fn governed_run<T: Surface>(
    surface: &T,
    views: &[Camera],
    options: &RenderOptions,
    frame: &mut [Rgb; PIXELS],
    results: &mut heapless::String<4096>,
) -> Result<(), &'static str> {
    let (cameras, count) = governed::cameras(views);
    let mut index = 0;
    for per_pixel in governed::BUDGETS {
        let mut governor = governed::governor(IMAGE_WIDTH, IMAGE_HEIGHT, per_pixel);
        for camera in &cameras[..count] {
            let view =
                View::new(camera, IMAGE_WIDTH, IMAGE_HEIGHT).map_err(|_| "a view is refused")?;
            let mut framebuffer = Framebuffer::new(frame, IMAGE_WIDTH, IMAGE_HEIGHT)
                .map_err(|_| "framebuffer too small")?;
            let start = ticks();
            governor.render(surface, &view, options, &mut framebuffer, &mut NoProbe);
            let governed_ticks = ticks() - start;
            let mut name: heapless::String<32> = heapless::String::new();
            let _ = write!(name, "frame-{index}-governed.rgb\0");
            write_host_file(&name, frame.as_flattened())?;
            let _ = writeln!(results, "governed {index} ticks {governed_ticks}");
            index += 1;
        }
    }
    hprintln!(
        "terracast-firmware: {} frames at each of {} budgets",
        count,
        governed::BUDGETS.len()
    );
    Ok(())
}

/// How each view is rendered: the default, from the eye, under the
/// flight's atmosphere, and under its sky and sun without the fog.
struct Renders {
    options: RenderOptions,
    from_eye: RenderOptions,
    air: PreparedAtmosphere,
    clear_air: PreparedAtmosphere,
}

impl Renders {
    /// Renders every view of `cameras` over `surface` each way, sends the
    /// default frame through the display driver, writes the frames and
    /// wire captures to the host and each render's ticks to `results`.
    fn all<T: Surface>(
        &self,
        surface: &T,
        cameras: &[Camera],
        frame: &mut [Rgb; PIXELS],
        capture: &mut [u8; CAPTURE_BYTES],
        results: &mut heapless::String<4096>,
    ) -> Result<(), &'static str> {
        let Self {
            options,
            from_eye,
            air,
            clear_air,
        } = self;
        let mut led = FrameLed;
        for (index, camera) in cameras.iter().enumerate() {
            let view =
                View::new(camera, IMAGE_WIDTH, IMAGE_HEIGHT).map_err(|_| "a view is refused")?;

            let mut framebuffer = Framebuffer::new(frame, IMAGE_WIDTH, IMAGE_HEIGHT)
                .map_err(|_| "framebuffer too small")?;
            let start = ticks();
            // scripts/board-profile with ATMOSPHERE=1 profiles the render
            // under the flight's atmosphere in its place.
            if option_env!("TERRACAST_BOARD_ATMOSPHERE").is_some() {
                let mut hazy = air.sink_over_sky(&view, &mut framebuffer);
                render(surface, &view, options, &mut hazy, &mut NoProbe);
            } else {
                // The sky put first, a row at a time: the line caster then
                // leaves the pixels above each line's last hit unwalked.
                let mut sky_first =
                    SkyFirst::new(&mut framebuffer, IMAGE_WIDTH, IMAGE_HEIGHT, options.sky);
                render(surface, &view, options, &mut sky_first, &mut NoProbe);
            }
            let kernel_ticks = ticks() - start;

            let bus = CaptureBus::new(capture);
            let mut display: SpiDisplay<_, _, _, COLUMN> = SpiDisplay::new(
                bus.spi(),
                bus.data_command(),
                bus.frame_done(),
                IMAGE_WIDTH,
                IMAGE_HEIGHT,
            )
            .map_err(|_| "display refused the image size")?;
            display
                .init(&mut BusyDelay)
                .map_err(|_| "display init failed")?;
            // The kernel's lines are not columns under pitch: the frame goes
            // to the display from the framebuffer. A displayed frame costs
            // both.
            let start = ticks();
            display
                .send_frame(frame)
                .map_err(|_| "display frame failed")?;
            let display_ticks = kernel_ticks + (ticks() - start);
            let _ = display.release();
            let wire = bus
                .into_written()
                .map_err(|_| "display capture overflowed")?;
            let _ = led.set_high();
            let _ = led.set_low();

            let mut name: heapless::String<32> = heapless::String::new();
            let _ = write!(name, "frame-{index}.rgb\0");
            write_host_file(&name, frame.as_flattened())?;
            name.clear();
            let _ = write!(name, "wire-{index}.bin\0");
            write_host_file(&name, wire)?;

            // The same view with every ray cast from the eye: many more
            // steps for the same rays, which separates the cost of a step
            // from the cost of a ray, and checks the slow path on the board
            // too. scripts/board-profile leaves it out, to profile the
            // default alone.
            if option_env!("TERRACAST_BOARD_DEFAULT_ONLY").is_some() {
                continue;
            }
            let mut framebuffer = Framebuffer::new(frame, IMAGE_WIDTH, IMAGE_HEIGHT)
                .map_err(|_| "framebuffer too small")?;
            let start = ticks();
            // With the sky put first as the default's is: one sink type for
            // both, so the casters are compiled once for it.
            let mut sky_first =
                SkyFirst::new(&mut framebuffer, IMAGE_WIDTH, IMAGE_HEIGHT, from_eye.sky);
            render(surface, &view, from_eye, &mut sky_first, &mut NoProbe);
            let from_eye_ticks = ticks() - start;
            name.clear();
            let _ = write!(name, "frame-{index}-from-eye.rgb\0");
            write_host_file(&name, frame.as_flattened())?;

            // The same view under the flight's sky, sun and fog, and under
            // its sky and sun alone: one sink type, so one compiled caster,
            // and what the fog costs is the difference.
            let mut air_ticks = [0u64; 2];
            for (ticks_of, (air, file)) in air_ticks
                .iter_mut()
                .zip([(air, "atmosphere"), (clear_air, "clear-air")])
            {
                let mut framebuffer = Framebuffer::new(frame, IMAGE_WIDTH, IMAGE_HEIGHT)
                    .map_err(|_| "framebuffer too small")?;
                let start = ticks();
                render(
                    surface,
                    &view,
                    options,
                    &mut air.sink_over_sky(&view, &mut framebuffer),
                    &mut NoProbe,
                );
                *ticks_of = ticks() - start;
                name.clear();
                let _ = write!(name, "frame-{index}-{file}.rgb\0");
                write_host_file(&name, frame.as_flattened())?;
            }
            let [atmosphere_ticks, clear_air_ticks] = air_ticks;
            let _ = writeln!(
            results,
            "frame {index} kernel_ticks {kernel_ticks} display_ticks {display_ticks} from_eye_ticks {from_eye_ticks} atmosphere_ticks {atmosphere_ticks} clear_air_ticks {clear_air_ticks}"
        );
            hprintln!(
                "terracast-firmware: frame {} rendered in {} ticks ({} with the display)",
                index,
                kernel_ticks,
                display_ticks
            );
        }
        Ok(())
    }
}

/// Each view turned level (pitch 0, no roll), rendered by the kernel's
/// default, by the kernel at single resolution, by the per-line design at
/// its smallest (`render_level_columns`: level 0, one set-up a column,
/// subvoxel shading) and by that caster written lean in words
/// (`render_level_columns_lean`); then each view as it is, by the kernel's
/// default, at single resolution, by the same design under pitch and roll
/// (`render_pixel_lines`), and by its per-pixel path alone
/// (`render_pixel_path`: no step), stepped line by line and from a table
/// of the frame's pixel ownership (`render_pixel_path_tabled`, into
/// `table`), and that path with its rays set up in single words
/// (`render_pixel_path_lean`): each render's ticks, over semihosting, for
/// `scripts/board-bound`.
fn level_bound(
    pyramid: &Pyramid,
    cameras: &[Camera],
    frame: &mut [Rgb],
    (line_of, order, starts): (&mut [u16], &mut [u32], &mut [u32]),
) -> Result<(), &'static str> {
    let default = RenderOptions::default();
    let single = RenderOptions {
        resolution: Resolution::Single,
        ..default
    };
    for (index, camera) in cameras.iter().enumerate() {
        let view = View::new(&camera.turned_level(), IMAGE_WIDTH, IMAGE_HEIGHT)
            .map_err(|_| "a view is refused")?;
        let posed =
            View::new(camera, IMAGE_WIDTH, IMAGE_HEIGHT).map_err(|_| "a view is refused")?;
        // The column caster written lean, straight into the frame.
        let start = ticks();
        render_level_columns_lean(pyramid.base(), &view, &single, frame)
            .map_err(|_| "not a level view")?;
        let columns_lean = ticks() - start;
        /// The kernel renders as the board's default does, the sky put
        /// first.
        fn sky_first<'a, 'b>(
            frame: &'a mut Framebuffer<'b>,
            sky: Rgb,
        ) -> SkyFirst<&'a mut Framebuffer<'b>> {
            SkyFirst::new(frame, IMAGE_WIDTH, IMAGE_HEIGHT, sky)
        }
        let mut ticks_of = |how: &dyn Fn(&mut Framebuffer) -> Result<(), &'static str>| {
            let mut framebuffer = Framebuffer::new(frame, IMAGE_WIDTH, IMAGE_HEIGHT)
                .map_err(|_| "framebuffer too small")?;
            let start = ticks();
            how(&mut framebuffer)?;
            Ok::<u64, &'static str>(ticks() - start)
        };
        let kernel = ticks_of(&|f| {
            render(
                pyramid,
                &view,
                &default,
                &mut sky_first(f, default.sky),
                &mut NoProbe,
            );
            Ok(())
        })?;
        let kernel_single = ticks_of(&|f| {
            render(
                pyramid,
                &view,
                &single,
                &mut sky_first(f, single.sky),
                &mut NoProbe,
            );
            Ok(())
        })?;
        let columns = ticks_of(&|f| {
            render_level_columns(pyramid.base(), &view, &single, f).map_err(|_| "not a level view")
        })?;
        hprintln!(
            "level view {} kernel {} single {} columns {} lean {}",
            index,
            kernel,
            kernel_single,
            columns,
            columns_lean
        );
        let kernel = ticks_of(&|f| {
            render(
                pyramid,
                &posed,
                &default,
                &mut sky_first(f, default.sky),
                &mut NoProbe,
            );
            Ok(())
        })?;
        let kernel_single = ticks_of(&|f| {
            render(
                pyramid,
                &posed,
                &single,
                &mut sky_first(f, single.sky),
                &mut NoProbe,
            );
            Ok(())
        })?;
        let lines = ticks_of(&|f| {
            render_pixel_lines(pyramid.base(), &posed, &single, f);
            Ok(())
        })?;
        let path = ticks_of(&|f| {
            render_pixel_path(pyramid.base(), &posed, &single, f);
            Ok(())
        })?;
        // Under nearest shading: the kernel at single resolution (and the
        // lean path below, taking one voxel a hit).
        let nearest = RenderOptions {
            shading: Shading::Nearest,
            ..single
        };
        let kernel_nearest = ticks_of(&|f| {
            render(
                pyramid,
                &posed,
                &nearest,
                &mut sky_first(f, nearest.sky),
                &mut NoProbe,
            );
            Ok(())
        })?;
        // Its ownership tabled once a frame (the table's build counted).
        let mut framebuffer = Framebuffer::new(frame, IMAGE_WIDTH, IMAGE_HEIGHT)
            .map_err(|_| "framebuffer too small")?;
        let start = ticks();
        render_pixel_path_tabled(
            pyramid.base(),
            &posed,
            &single,
            (&mut *line_of, &mut *order, &mut *starts),
            &mut framebuffer,
        )
        .map_err(|_| "the pixel table is too small")?;
        let tabled = ticks() - start;
        let start = ticks();
        tabulate_pixel_ownership(&posed, (&mut *line_of, &mut *order, &mut *starts))
            .map_err(|_| "the pixel table is too small")?;
        let table_only = ticks() - start;
        // Its rays set up in single words, written straight to the frame
        // (the table's build counted).
        let start = ticks();
        render_pixel_path_lean(
            pyramid.base(),
            &posed,
            &single,
            (&mut *line_of, &mut *order, &mut *starts),
            frame,
        )
        .map_err(|_| "the pixel table is too small")?;
        let lean = ticks() - start;
        let start = ticks();
        render_pixel_path_lean(
            pyramid.base(),
            &posed,
            &nearest,
            (&mut *line_of, &mut *order, &mut *starts),
            frame,
        )
        .map_err(|_| "the pixel table is too small")?;
        let lean_nearest = ticks() - start;
        hprintln!(
            "posed view {} kernel {} single {} lines {} path {} tabled {} table {} lean {} nearest {} lean-nearest {}",
            index,
            kernel,
            kernel_single,
            lines,
            path,
            tabled,
            table_only,
            lean,
            kernel_nearest,
            lean_nearest
        );
    }
    Ok(())
}
