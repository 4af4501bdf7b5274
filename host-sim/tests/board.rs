//! `terracast-sim board scene` and `board verify` without the emulator: the
//! host plays the board (writing what the firmware writes), and verify must
//! accept that, and reject any changed byte, a missing file, or an exceeded
//! budget, each with one line.

mod common;

use common::{s, sim};
use std::path::{Path, PathBuf};
use terracast::HeightPath;
use terracast_sim::board::SceneFile;

fn fresh_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("terracast-board-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// `board verify` of `scene` against what the board wrote in `board`, with
/// the further arguments `extra`.
fn board_verify(scene: &Path, board: &Path, extra: &[&str]) -> (i32, String, String) {
    let mut args = vec!["board", "verify", "--scene", s(scene), "--from", s(board)];
    args.extend_from_slice(extra);
    sim(&args)
}

/// A small scene, and a folder holding what the board would have written
/// for it (the host's own frames, 1000 ticks a frame at 40 instructions a
/// tick).
fn scene_and_board_output(name: &str) -> (PathBuf, PathBuf) {
    scene_and_board_output_with(name, &[], 1000)
}

/// A small scene written with the extra `board scene` arguments `extra`,
/// and what the board would have written for it, `ticks` a frame.
fn scene_and_board_output_with(name: &str, extra: &[&str], ticks: u32) -> (PathBuf, PathBuf) {
    scene_and_board_output_on(name, extra, ticks, HeightPath::Line)
}

/// As [`scene_and_board_output_with`], the frames rendered reading heights
/// on `height_path`.
fn scene_and_board_output_on(
    name: &str,
    extra: &[&str],
    ticks: u32,
    height_path: HeightPath,
) -> (PathBuf, PathBuf) {
    let dir = fresh_dir(name);
    let scene = dir.join("scene.tcb");
    let mut args = vec![
        "board",
        "scene",
        "--procedural-size",
        "96",
        "--size",
        "40x30",
        "--out",
        s(&scene),
    ];
    args.extend_from_slice(extra);
    let (code, out, err) = sim(&args);
    assert_eq!(code, 0, "{err}");
    // Turned level, the rolled view is its level twin: left out.
    let views = if extra.contains(&"--level") { 5 } else { 6 };
    assert!(
        out.contains(&format!("96x96 map, {views} views at 40x30")),
        "{out}"
    );
    let board = dir.join("board");
    std::fs::create_dir_all(&board).unwrap();
    let (frames, governed) = SceneFile::read(&scene)
        .unwrap()
        .render(height_path)
        .unwrap();
    assert_eq!(frames.len(), views);
    let mut results = String::from("calibration instructions 4000 ticks 100\npyramid_ticks 7\n");
    for (k, frame) in frames.iter().enumerate() {
        std::fs::write(board.join(format!("frame-{k}.rgb")), &frame.rgb).unwrap();
        std::fs::write(board.join(format!("wire-{k}.bin")), &frame.wire).unwrap();
        std::fs::write(
            board.join(format!("frame-{k}-from-eye.rgb")),
            &frame.from_eye_rgb,
        )
        .unwrap();
        std::fs::write(
            board.join(format!("frame-{k}-atmosphere.rgb")),
            &frame.atmosphere_rgb,
        )
        .unwrap();
        std::fs::write(
            board.join(format!("frame-{k}-clear-air.rgb")),
            &frame.clear_air_rgb,
        )
        .unwrap();
        results += &format!(
            "frame {k} kernel_ticks {ticks} display_ticks 1100 from_eye_ticks 3000 atmosphere_ticks 1050 clear_air_ticks 1000\n"
        );
    }
    // The governor's run (a bare map's): each frame at 0.95 of its budget,
    // 40 instructions a tick.
    for (k, (_, _, rgb, cost)) in governed.iter().enumerate() {
        std::fs::write(board.join(format!("frame-{k}-governed.rgb")), rgb).unwrap();
        results += &format!("governed {k} ticks {}\n", cost.budget * 95 / 100 / 40);
    }
    std::fs::write(board.join("board-results.txt"), results).unwrap();
    (scene, board)
}

#[test]
fn a_governed_frame_over_its_budget_on_the_board_fails_the_check() {
    let (scene, board) = scene_and_board_output("governed");
    let (code, out, err) = board_verify(&scene, &board, &[]);
    assert_eq!(code, 0, "{err}");
    assert!(
        out.contains("governed frames") && !out.contains("DIFFERENT"),
        "{out}"
    );
    assert!(
        out.contains("the check's run (3000 a pixel): board instructions 0.950 to 0.950 of the budget: max/min 1.000"),
        "{out}"
    );
    // One frame counted past its budget.
    let results = std::fs::read_to_string(board.join("board-results.txt")).unwrap();
    let over = results
        .lines()
        .map(|line| match line.strip_prefix("governed 3 ticks ") {
            Some(ticks) => format!(
                "governed 3 ticks {}",
                ticks.parse::<u64>().unwrap() * 11 / 9
            ),
            None => line.to_string(),
        })
        .collect::<Vec<_>>()
        .join("\n");
    std::fs::write(board.join("board-results.txt"), over).unwrap();
    let (code, _, err) = board_verify(&scene, &board, &[]);
    assert_ne!(code, 0);
    assert!(err.contains("a governed frame took 1.16"), "{err}");
}

#[test]
fn identical_output_passes_and_reports_instructions_per_pixel_last() {
    let (scene, board) = scene_and_board_output("same");
    let (code, out, err) = board_verify(&scene, &board, &[]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("all frames identical"), "{out}");
    assert!(
        out.contains("with the flight's sky, sun and fog: 35 instructions a pixel, 1.050x"),
        "{out}"
    );
    // 1000 ticks x 40 instructions over 40 x 30 pixels.
    assert_eq!(
        out.lines().last(),
        Some("instructions per pixel: 33"),
        "{out}"
    );
}

#[test]
fn one_changed_byte_of_a_frame_or_the_wire_fails() {
    let (scene, board) = scene_and_board_output("changed");
    let frame = board.join("frame-2.rgb");
    let mut bytes = std::fs::read(&frame).unwrap();
    bytes[1234] ^= 1;
    std::fs::write(&frame, &bytes).unwrap();
    let (code, out, err) = board_verify(&scene, &board, &[]);
    assert_eq!(code, 1);
    assert_eq!(
        err.trim(),
        "terracast-sim: board and host frames differ in view(s) 2"
    );
    assert!(out.contains("   2  DIFFERENT"), "{out}");

    // Restore the frame, change one pixel byte on the wire (past the init
    // and the first column's addresses): the wire differs and so does
    // what the panel shows.
    bytes[1234] ^= 1;
    std::fs::write(&frame, &bytes).unwrap();
    let wire = board.join("wire-0.bin");
    let mut bytes = std::fs::read(&wire).unwrap();
    let last = bytes.len() - 3;
    bytes[last] ^= 0x80;
    std::fs::write(&wire, &bytes).unwrap();
    let (code, out, err) = board_verify(&scene, &board, &[]);
    assert_eq!(code, 1, "{out}");
    assert!(err.contains("differ in view(s) 0"), "{err}");
    assert!(
        out.contains("   0  identical   DIFFERENT  DIFFERS"),
        "{out}"
    );

    // Restore the wire; a flipped byte in a from-eye frame fails too, and
    // in a frame under the atmosphere, and under its sky and sun alone.
    bytes[last] ^= 0x80;
    std::fs::write(&wire, &bytes).unwrap();
    for (file, byte, view) in [
        ("frame-1-from-eye.rgb", 99, 1),
        ("frame-3-atmosphere.rgb", 7, 3),
        ("frame-2-clear-air.rgb", 11, 2),
    ] {
        let path = board.join(file);
        let mut bytes = std::fs::read(&path).unwrap();
        bytes[byte] ^= 4;
        std::fs::write(&path, &bytes).unwrap();
        let (code, out, err) = board_verify(&scene, &board, &[]);
        assert_eq!(code, 1, "{file}: {out}");
        assert!(
            err.contains(&format!("differ in view(s) {view}")),
            "{file}: {err}"
        );
        bytes[byte] ^= 4;
        std::fs::write(&path, &bytes).unwrap();
    }
}

#[test]
fn exceeded_budget_fails_and_missing_or_bad_files_are_named() {
    let (scene, board) = scene_and_board_output("budget");
    let (code, _, err) = board_verify(&scene, &board, &["--budget", "30"]);
    assert_eq!(code, 1);
    assert_eq!(
        err.trim(),
        "terracast-sim: 33 instructions per pixel exceeds the budget of 30"
    );

    std::fs::remove_file(board.join("wire-3.bin")).unwrap();
    let (code, _, err) = board_verify(&scene, &board, &[]);
    assert_eq!(code, 1);
    assert!(
        err.contains("cannot read") && err.contains("wire-3.bin"),
        "{err}"
    );
    assert_eq!(err.lines().count(), 1);

    let (code, _, err) = board_verify(&board.join("board-results.txt"), &board, &[]);
    assert_eq!(code, 1);
    assert!(err.contains("not a board scene file"), "{err}");

    let (code, _, err) = sim(&[
        "board",
        "scene",
        "--procedural-size",
        "4000",
        "--out",
        s(&scene),
    ]);
    assert_eq!(code, 2);
    assert!(
        err.contains("'--procedural-size ") && err.contains("from 2 to 800"),
        "{err}"
    );
}

#[test]
fn objects_read_on_each_rays_path_are_compared_with_the_bare_map_on_its_lines() {
    let (_, bare_board) = scene_and_board_output("objects-ray-bare");
    let (scene, board) =
        scene_and_board_output_on("objects-ray", &["--objects"], 1500, HeightPath::Ray);
    let verify = |height_path: &str| {
        board_verify(
            &scene,
            &board,
            &["--height-path", height_path, "--without", s(&bare_board)],
        )
    };
    let (code, out, err) = verify("ray");
    assert_eq!(code, 0, "{err}");
    assert!(
        out.contains("with objects on each ray's path against without on each line's plane"),
        "{out}"
    );
    assert!(out.contains(" all       33    50  1.500x"), "{out}");
    // Its frames are not the line caster's on each line's plane.
    let (code, _, err) = verify("line");
    assert_ne!(code, 0);
    assert!(err.contains("differ"), "{err}");
}

#[test]
fn a_scene_with_objects_renders_them_and_is_compared_with_the_bare_map() {
    let (bare_scene, bare_board) = scene_and_board_output("objects-bare");
    let (scene, board) = scene_and_board_output_with("objects", &["--objects"], 1300);
    let (code, out, err) = board_verify(&scene, &board, &["--without", s(&bare_board)]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("with objects against without"), "{out}");
    assert!(out.contains("   0       33    43  1.300x"), "{out}");
    assert!(out.contains(" all       33    43  1.300x"), "{out}");
    // The objects are in the frames.
    let (bare, _) = SceneFile::read(&bare_scene)
        .unwrap()
        .render(HeightPath::Line)
        .unwrap();
    let (planted, _) = SceneFile::read(&scene)
        .unwrap()
        .render(HeightPath::Line)
        .unwrap();
    assert!(bare.iter().zip(&planted).any(|(b, p)| b.rgb != p.rgb));

    // A damaged objects section: one line that names it.
    let bytes = std::fs::read(&scene).unwrap();
    let section = terracast_board::scene::objects_at(96 * 96);
    let damaged = |name: &str, change: &dyn Fn(&mut Vec<u8>)| {
        let mut bytes = bytes.clone();
        change(&mut bytes);
        let path = scene.with_file_name(name);
        std::fs::write(&path, bytes).unwrap();
        path
    };
    let bad_magic = damaged("magic.tcb", &|b| b[section] = b'X');
    let error = SceneFile::read(&bad_magic).unwrap_err().to_string();
    assert!(error.contains("not objects"), "{error}");
    let short = damaged("short.tcb", &|b| b.truncate(b.len() - 2));
    let error = SceneFile::read(&short).unwrap_err().to_string();
    assert!(error.contains("shorter than its header says"), "{error}");
    // A grid point naming a stick past the table: refused by the kernel
    // when the scene is rendered (on the board, at boot).
    let past = damaged("past.tcb", &|b| {
        b[section + 16..section + 18].copy_from_slice(&60_000u16.to_le_bytes())
    });
    let (code, _, err) = board_verify(&past, &board, &[]);
    assert_ne!(code, 0);
    assert!(err.contains("objects refused"), "{err}");
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    // A map too large for the board's code memory with its objects.
    let (code, _, err) = sim(&[
        "board",
        "scene",
        "--objects",
        "--procedural-size",
        "800",
        "--out",
        s(&scene.with_file_name("large.tcb")),
    ]);
    assert_ne!(code, 0);
    assert!(err.contains("at most 740 a side"), "{err}");
}

/// A real height map and its photo as the board's terrain: refused whole
/// where it is larger than the board holds or not square, cut to a square
/// from its middle with `--crop`, every view level with `--level`; the
/// scene renders as the host renders it.
#[test]
fn a_real_map_becomes_a_board_scene_cut_from_its_middle() {
    let dir = fresh_dir("real-map");
    let (height, color) = (dir.join("h.png"), dir.join("c.png"));
    let (width, depth) = (900u32, 70u32);
    image::ImageBuffer::from_fn(width, depth, |x, y| {
        image::Luma([((x * 7 + y * 13) % 251) as u8])
    })
    .save(&height)
    .unwrap();
    image::ImageBuffer::from_fn(width, depth, |x, y| {
        image::Rgb([(x % 256) as u8, (y * 3) as u8, 90u8])
    })
    .save(&color)
    .unwrap();
    let scene = dir.join("scene.tcb");
    let board_scene = |extra: &[&str]| {
        let mut args = vec![
            "board",
            "scene",
            "--height",
            s(&height),
            "--color",
            s(&color),
        ];
        args.extend_from_slice(extra);
        args.extend_from_slice(&["--size", "40x30", "--out", s(&scene)]);
        sim(&args)
    };
    let (code, _, err) = board_scene(&[]);
    assert_ne!(code, 0);
    assert!(
        err.contains("is 900x70: a board map is square and at most 800 a side")
            && err.contains("--crop N")
            && err.lines().count() == 1,
        "{err}"
    );
    let (code, _, err) = board_scene(&["--crop", "71"]);
    assert_ne!(code, 0);
    assert!(
        err.contains("cannot cut 71x71 from a 900x70 terrain"),
        "{err}"
    );

    let (code, out, err) = board_scene(&["--crop", "64", "--level"]);
    assert_eq!(code, 0, "{err}");
    assert!(
        out.contains("64x64 map (the middle of h.png, 900x70), 5 views at 40x30"),
        "{out}"
    );
    let file = SceneFile::read(&scene).unwrap();
    let board = file.scene().unwrap();
    let views = board.header.views();
    assert_eq!(
        views.len(),
        5,
        "the rolled view turned level is its twin: left out"
    );
    assert!(views
        .iter()
        .all(|v| v.pitch_deg == 0.0 && v.roll_deg == 0.0));
    // The middle square: column 418 of the map is the crop's first, row 3
    // its first row.
    // (Kernel heights are in sixteenths of a voxel.)
    let terrain = board.terrain().unwrap();
    let expected = |x: u32, y: u32| 16 * ((x * 7 + y * 13) % 251) as u16;
    assert_eq!(terrain.heights()[0], expected(418, 3));
    assert_eq!(terrain.heights()[64 * 5 + 9], expected(427, 8));
    assert_eq!(terrain.colors()[0], [(418 % 256) as u8, 9, 90]);
    let (frames, _) = file.render(HeightPath::Line).unwrap();
    assert_eq!(frames.len(), 5);
}

/// `--fit-with` fits the prices to two scenes' governed runs together:
/// its line names the other run, beside this run's own fit.
#[test]
fn the_prices_are_fitted_to_two_runs_together() {
    let (scene, board) = scene_and_board_output("fit-this");
    let (other_scene, other_board) = scene_and_board_output_with("fit-other", &["--level"], 1000);
    let (code, out, err) = board_verify(
        &scene,
        &board,
        &["--fit-with", s(&other_scene), s(&other_board)],
    );
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("prices fitted to these frames ("), "{out}");
    let joint = format!(
        "prices fitted to these frames and {}'s (",
        other_board.display()
    );
    assert!(out.contains(&joint), "{out}");
}
