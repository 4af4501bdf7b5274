//! `terracast-sim view` in a real window on an X server (Xvfb): real key
//! presses (xdotool, through the XTEST extension), the window's pixels read
//! back from the server (xwd), and the view compared with what `render`
//! draws from the command line the viewer printed.
//!
//! Needs `Xvfb`, `xdotool` and `xwd` (Debian: xvfb, xdotool, x11-apps).
//! Without them the test says so and passes, so that `cargo test` passes
//! on a bare machine; `.ci/run` installs them and sets
//! `TERRACAST_REQUIRE_XVFB=1`, which turns their absence into a failure.

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::mpsc::{channel, Receiver};
use std::time::{Duration, Instant};
use terracast_sim::fly::Path as FlightPath;

/// One window test at a time: each times key presses against frames, and
/// two at once on a small machine starve each other.
static ONE_AT_A_TIME: std::sync::Mutex<()> = std::sync::Mutex::new(());

/// A process killed when dropped (the X server, the viewer on failure).
struct Killed(Child);

impl Drop for Killed {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

fn tools_present() -> bool {
    ["Xvfb", "xdotool", "xwd"].iter().all(|tool| {
        Command::new("sh")
            .args(["-c", &format!("command -v {tool}")])
            .stdout(Stdio::null())
            .status()
            .is_ok_and(|s| s.success())
    })
}

/// Starts Xvfb on a free display; returns it and its `:N`.
fn start_x_server() -> (Killed, String) {
    for n in (90 + std::process::id() % 50)..200 {
        if Path::new(&format!("/tmp/.X11-unix/X{n}")).exists()
            || Path::new(&format!("/tmp/.X{n}-lock")).exists()
        {
            continue;
        }
        let display = format!(":{n}");
        let server = Command::new("Xvfb")
            .args([&display, "-screen", "0", "800x600x24", "-nolisten", "tcp"])
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .expect("Xvfb starts");
        let server = Killed(server);
        let socket = format!("/tmp/.X11-unix/X{n}");
        let began = Instant::now();
        while !Path::new(&socket).exists() && began.elapsed() < Duration::from_secs(10) {
            std::thread::sleep(Duration::from_millis(50));
        }
        assert!(
            Path::new(&socket).exists(),
            "Xvfb did not start on {display}"
        );
        return (server, display);
    }
    panic!("no free X display number");
}

fn x_tool(display: &str, tool: &str, args: &[&str]) -> Vec<u8> {
    let out = Command::new(tool)
        .args(args)
        .env("DISPLAY", display)
        .output()
        .unwrap_or_else(|e| panic!("{tool}: {e}"));
    assert!(
        out.status.success(),
        "{tool} {args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    out.stdout
}

/// The window's pixels as RGB rows, from an XWD dump (ZPixmap, 32 bits a
/// pixel, as Xvfb's 24-bit screen gives).
fn xwd_rgb(dump: &[u8]) -> (u32, u32, Vec<u8>) {
    let field = |i: usize| u32::from_be_bytes(dump[i * 4..i * 4 + 4].try_into().unwrap());
    let (header, format, width, height) = (field(0) as usize, field(2), field(4), field(5));
    let (byte_order, bits, bytes_per_line) = (field(7), field(11), field(12) as usize);
    let (red, green, blue, colors) = (field(14), field(15), field(16), field(19) as usize);
    assert_eq!((format, bits), (2, 32), "an XWD ZPixmap of 32-bit pixels");
    let pixels = &dump[header + colors * 12..];
    let channel = |word: u32, mask: u32| ((word & mask) >> mask.trailing_zeros()) as u8;
    let mut rgb = Vec::with_capacity(width as usize * height as usize * 3);
    for y in 0..height as usize {
        for x in 0..width as usize {
            let at = y * bytes_per_line + x * 4;
            let bytes: [u8; 4] = pixels[at..at + 4].try_into().unwrap();
            let word = if byte_order == 0 {
                u32::from_le_bytes(bytes)
            } else {
                u32::from_be_bytes(bytes)
            };
            rgb.extend([
                channel(word, red),
                channel(word, green),
                channel(word, blue),
            ]);
        }
    }
    (width, height, rgb)
}

/// Waits for the viewer's next "saved …" line.
fn next_saved(lines: &Receiver<String>) -> String {
    let deadline = Instant::now() + Duration::from_secs(60);
    loop {
        let left = deadline.saturating_duration_since(Instant::now());
        let line = lines
            .recv_timeout(left)
            .expect("the viewer printed a saved view");
        if line.starts_with("saved ") {
            return line;
        }
    }
}

/// The saved line of a view saved while the eye climbs.
fn saved_climbing(display: &str, lines: &Receiver<String>) -> String {
    x_tool(display, "xdotool", &["keydown", "r"]);
    std::thread::sleep(Duration::from_millis(500));
    x_tool(display, "xdotool", &["key", "p"]);
    let saved = next_saved(lines);
    x_tool(display, "xdotool", &["keyup", "r"]);
    saved
}

/// The `render` arguments a saved line gives (the test's paths need no
/// quoting).
fn render_args(saved: &str) -> Vec<String> {
    let (_, command) = saved
        .split_once("terracast-sim render ")
        .expect("a render command line");
    assert!(!command.contains('\''), "{command}");
    command.split_whitespace().map(str::to_string).collect()
}

/// The number a render command line gives `flag` (`--yaw=`).
fn number_flag(args: &[String], flag: &str) -> f32 {
    let value = args.iter().find_map(|a| a.strip_prefix(flag));
    value.expect(flag).parse().unwrap()
}

/// The eye a render command line names.
fn eye_of(args: &[String]) -> [f32; 3] {
    let eye = args
        .iter()
        .find_map(|a| a.strip_prefix("--eye="))
        .expect("--eye");
    let v: Vec<f32> = eye.split(',').map(|x| x.parse().unwrap()).collect();
    [v[0], v[1], v[2]]
}

/// The saved view a saved line names.
fn saved_image(saved: &str) -> image::RgbImage {
    let saved_png = saved
        .strip_prefix("saved ")
        .and_then(|s| s.split(" (").next())
        .unwrap();
    image::open(saved_png).unwrap().to_rgb8()
}

/// Renders what a saved line names and compares it with the saved PNG:
/// the same, pixel for pixel. Returns the saved image.
fn check_saved(saved: &str) -> image::RgbImage {
    let saved_image = saved_image(saved);
    let args = render_args(saved);
    run_ok("render", &args);
    let rendered_png = args.iter().find_map(|a| a.strip_prefix("--out=")).unwrap();
    let rendered = image::open(rendered_png).unwrap().to_rgb8();
    assert_eq!(rendered.dimensions(), saved_image.dimensions());
    assert_eq!(
        differing(rendered.as_raw(), saved_image.as_raw()),
        0,
        "`render` draws the view that was saved"
    );
    saved_image
}

fn differing(a: &[u8], b: &[u8]) -> usize {
    a.chunks(3).zip(b.chunks(3)).filter(|(p, q)| p != q).count()
}

/// [`check_saved`], and the window's pixels are the saved view's, pixel
/// for pixel (enlarged where the governor rendered it smaller).
fn check_view(display: &str, window: &str, saved: &str) {
    let (w, h, window_rgb) = xwd_rgb(&x_tool(display, "xwd", &["-id", window, "-silent"]));
    let saved_image = check_saved(saved);
    // The window shows the saved frame, enlarged where the governor
    // rendered it smaller than the window.
    let (rw, rh) = saved_image.dimensions();
    let shown =
        image::RgbImage::from_fn(w, h, |x, y| *saved_image.get_pixel(x * rw / w, y * rh / h));
    assert_eq!(
        differing(shown.as_raw(), &window_rgb),
        0,
        "the window shows what was saved"
    );
    if (rw, rh) == (w, h) {
        println!("window and `render` identical at {w}x{h}, the window's size");
    } else {
        println!("the governor rendered {rw}x{rh} for the {w}x{h} window: `render` at that size is identical to it, and the window shows it enlarged");
    }
}

/// The viewer running on `display`: the process, its stdout's lines and
/// its window, focused for key presses.
struct Viewer {
    process: Killed,
    lines: Receiver<String>,
    window: String,
}

impl Viewer {
    fn start(display: &str, args: &[String]) -> Self {
        let child = Command::new(env!("CARGO_BIN_EXE_terracast-sim"))
            .arg("view")
            .args(args)
            .env("DISPLAY", display)
            .stdout(Stdio::piped())
            .spawn()
            .unwrap();
        let mut process = Killed(child);
        let (send, lines) = channel();
        let stdout = process.0.stdout.take().unwrap();
        std::thread::spawn(move || {
            for line in BufReader::new(stdout).lines().map_while(Result::ok) {
                println!("viewer: {line}");
                if send.send(line).is_err() {
                    break;
                }
            }
        });
        let found = x_tool(
            display,
            "xdotool",
            &["search", "--sync", "--name", "^terracast$"],
        );
        let window = String::from_utf8(found)
            .unwrap()
            .lines()
            .next()
            .unwrap()
            .to_string();
        x_tool(display, "xdotool", &["windowfocus", "--sync", &window]);
        Self {
            process,
            lines,
            window,
        }
    }
}

/// Runs `terracast-sim COMMAND ARGS`, which must succeed.
fn run_ok(command: &str, args: &[String]) {
    let out = Command::new(env!("CARGO_BIN_EXE_terracast-sim"))
        .arg(command)
        .args(args)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{command}: {err}");
}

fn temp_dir() -> PathBuf {
    let dir = std::env::temp_dir().join(format!("terracast-viewer-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

#[test]
fn keys_fly_the_window_and_render_draws_what_it_shows() {
    if !tools_present() {
        assert!(
            std::env::var_os("TERRACAST_REQUIRE_XVFB").is_none(),
            "TERRACAST_REQUIRE_XVFB is set, but Xvfb, xdotool or xwd is missing"
        );
        eprintln!("skipped: Xvfb, xdotool and xwd are needed (Debian: xvfb xdotool x11-apps)");
        return;
    }
    let _alone = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let (_server, display) = start_x_server();
    let dir = temp_dir();
    let record = dir.join("flown.txt");
    let prefix = dir.join("view");
    // A render at 2 Hz has time to spare: the governor keeps the window's
    // size, and the window then stays as it is until a key.
    let args = "--procedural-size 256 --size 320x200 --fps 2 --threads 2 --yaw 90 --pitch 15";
    let mut args: Vec<String> = args.split(' ').map(str::to_string).collect();
    args.push(format!("--record={}", record.display()));
    args.push(format!("--save-prefix={}", prefix.display()));
    let mut viewer = Viewer::start(&display, &args);
    let (lines, window) = (&viewer.lines, &viewer.window);
    let key = |args: &[&str]| {
        x_tool(&display, "xdotool", args);
    };
    // Let the governor settle, hide the on-screen line, save.
    std::thread::sleep(Duration::from_secs(3));
    key(&["key", "h"]);
    std::thread::sleep(Duration::from_millis(500));
    key(&["key", "p"]);
    let first = next_saved(lines);
    check_view(&display, window, &first);

    // Forward (toward +y at a heading of 90°) for a moment, then bank
    // right a little: the camera moves as the keys say. Nearest shading
    // and rays by footprint on, the sky and fog off: the render command
    // says so.
    key(&["key", "1"]);
    key(&["key", "3"]);
    key(&["key", "5"]);
    key(&["keydown", "w"]);
    std::thread::sleep(Duration::from_millis(600));
    key(&["keyup", "w"]);
    key(&["keydown", "e"]);
    std::thread::sleep(Duration::from_millis(300));
    key(&["keyup", "e"]);
    // A drag 50 pixels to the right with the left button: a turn of 10°.
    key(&["mousemove", "--window", window, "100", "100"]);
    std::thread::sleep(Duration::from_millis(200));
    key(&["mousedown", "1"]);
    key(&["mousemove", "--window", window, "150", "100"]);
    std::thread::sleep(Duration::from_millis(200));
    key(&["mouseup", "1"]);
    std::thread::sleep(Duration::from_secs(2));
    key(&["key", "p"]);
    let second = next_saved(lines);
    check_view(&display, window, &second);
    let (before, after) = (eye_of(&render_args(&first)), eye_of(&render_args(&second)));
    assert_eq!(before[0], after[0], "no sideways motion");
    assert!(
        after[1] > before[1] + 5.0,
        "forward: {before:?} -> {after:?}"
    );
    let roll = number_flag(&render_args(&second), "--roll=");
    assert!(roll > 1.0, "banked right: roll {roll}");
    let yaw = number_flag(&render_args(&second), "--yaw=");
    assert!(
        (yaw - 100.0).abs() < 0.01,
        "turned right by the drag: yaw {yaw}"
    );
    let settings = render_args(&second);
    assert!(render_args(&first).contains(&"--atmosphere=on".to_string()));
    assert!(settings.contains(&"--atmosphere=off".to_string()));
    assert!(settings.contains(&"--relief=shadows".to_string()));
    assert!(settings.contains(&"--shading=nearest".to_string()));
    assert!(settings.contains(&"--vertical-samples=footprint".to_string()));

    // Escape closes it; the flown path replays to the camera it ended at.
    key(&["key", "Escape"]);
    let began = Instant::now();
    let status = loop {
        if let Some(status) = viewer.process.0.try_wait().unwrap() {
            break status;
        }
        assert!(
            began.elapsed() < Duration::from_secs(30),
            "the viewer did not exit"
        );
        std::thread::sleep(Duration::from_millis(50));
    };
    assert!(status.success());
    let path = FlightPath::parse(&std::fs::read_to_string(&record).unwrap()).unwrap();
    let end = path.camera(1e9, 60.0);
    assert_eq!(end.eye, after);
    assert_eq!(end.roll_deg, roll);
    let replay = dir.join("replay.gif");
    let fly = format!(
        "--procedural-size 256 --frames 3 --size 64x48 --path={} --out={}",
        record.display(),
        replay.display()
    );
    run_ok(
        "fly",
        &fly.split(' ').map(str::to_string).collect::<Vec<_>>(),
    );
}

#[test]
fn a_late_frame_is_rendered_smaller_and_a_still_view_at_the_windows_size() {
    if !tools_present() {
        eprintln!("skipped: Xvfb, xdotool and xwd are needed (Debian: xvfb xdotool x11-apps)");
        return;
    }
    let _alone = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let (_server, display) = start_x_server();
    let prefix = temp_dir().join("late");
    // A millisecond a frame: no render of 200 x 120 pixels on one thread
    // is that fast, so while the view moves the size governor shrinks the
    // frame as far as it goes (a quarter of each side); once it is still,
    // the view is drawn once more at the window's size.
    let args = "--procedural-size 256 --size 800x480 --fps 1000 --threads 1 --governor size";
    let mut args: Vec<String> = args.split(' ').map(str::to_string).collect();
    args.push(format!("--save-prefix={}", prefix.display()));
    let viewer = Viewer::start(&display, &args);
    let (lines, window) = (&viewer.lines, &viewer.window);
    std::thread::sleep(Duration::from_secs(2));
    x_tool(&display, "xdotool", &["key", "h"]);
    std::thread::sleep(Duration::from_secs(1));
    x_tool(&display, "xdotool", &["key", "p"]);
    let still = next_saved(lines);
    assert!(still.contains("at the window's size"), "{still}");
    check_view(&display, window, &still);
    // Climbing: every frame is late, so every frame is small.
    let moving = saved_climbing(&display, lines);
    assert!(
        moving.contains("the governor rendered it at 200x120"),
        "{moving}"
    );
    assert_eq!(check_saved(&moving).dimensions(), (200, 120));
    drop(viewer);

    // The cost governor: a base pass that cannot fit the budget shrinks
    // the frame too; the saved frame is the governor's, which the printed
    // command (no budget) does not claim to draw.
    let args = "--procedural-size 256 --size 800x480 --fps 1000 --threads 2 --governor cost";
    let mut args: Vec<String> = args.split(' ').map(str::to_string).collect();
    args.push(format!(
        "--save-prefix={}",
        temp_dir().join("cost").display()
    ));
    let viewer = Viewer::start(&display, &args);
    std::thread::sleep(Duration::from_secs(2));
    let moving = saved_climbing(&display, &viewer.lines);
    assert!(
        moving.contains("the governor rendered it at 200x120 within")
            && moving.contains("the command renders the view without a budget"),
        "{moving}"
    );
    assert_eq!(saved_image(&moving).dimensions(), (200, 120));
}
