//! Every command: an output that is one of its inputs is refused and the
//! input kept; outputs are all or nothing; every numeric flag refuses bad
//! values the same way, naming the flag.

mod common;

use common::{s, sim};
use std::path::{Path, PathBuf};

/// A fresh folder with a 16 x 16 height map `h.png` and color map `c.png`.
fn folder_with_maps() -> (tempfile::TempDir, PathBuf, PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let (h, c) = (dir.path().join("h.png"), dir.path().join("c.png"));
    common::write_small_maps(&h, &c);
    (dir, h, c)
}

/// The names in `dir`, sorted.
fn names(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

fn run(args: &[String]) -> (i32, String) {
    let refs: Vec<&str> = args.iter().map(String::as_str).collect();
    let (code, _, err) = sim(&refs);
    (code, err)
}

fn strings(args: &[&str]) -> Vec<String> {
    args.iter().map(|a| a.to_string()).collect()
}

#[test]
fn no_command_writes_over_its_input() {
    let (dir, h, c) = folder_with_maps();
    let tiles = dir.path().join("t.tiles");
    let (code, err) = run(&strings(&[
        "pack",
        "--height",
        s(&h),
        "--color",
        s(&c),
        "--out",
        s(&tiles),
    ]));
    assert_eq!(code, 0, "{err}");
    // A data folder for bench: its Comanche maps are inputs.
    let comanche = dir.path().join("data/comanche");
    std::fs::create_dir_all(&comanche).unwrap();
    let d1 = comanche.join("D1.png");
    std::fs::copy(&h, &d1).unwrap();
    let symlink = dir.path().join("link");
    let hard_link = dir.path().join("hard");
    let before: Vec<(PathBuf, Vec<u8>)> = [&h, &c, &tiles, &d1]
        .iter()
        .map(|p| (p.to_path_buf(), std::fs::read(p).unwrap()))
        .collect();
    // Each command, with the flag that names the output and the input it
    // may not overwrite.
    type Case = (Vec<String>, &'static str, PathBuf);
    let scene = |cmd: &str| strings(&[cmd, "--height", s(&h), "--color", s(&c)]);
    let cases: Vec<Case> = vec![
        (strings(&["render", "--height", s(&h)]), "--out", h.clone()),
        (scene("render"), "--depth", c.clone()),
        (
            strings(&["render", "--terrain", s(&tiles)]),
            "--stats",
            tiles.clone(),
        ),
        (strings(&["pack", "--height", s(&h)]), "--out", h.clone()),
        (
            strings(&["pack", "--height", s(&h), "--color", s(&c)]),
            "--out",
            c.clone(),
        ),
        (scene("fly"), "--report", h.clone()),
        (
            strings(&["page", "--terrain", s(&tiles), "--frames", "1"]),
            "--report",
            tiles.clone(),
        ),
        (
            strings(&["sim", "--height", s(&h), "--table"]),
            "--chart",
            h.clone(),
        ),
        (
            strings(&["bench", "--data", s(&dir.path().join("data"))]),
            "--csv",
            d1.clone(),
        ),
    ];
    for (command, flag, input) in cases {
        for alias in ["same", "symlink", "hard link"] {
            let _ = std::fs::remove_file(&symlink);
            let _ = std::fs::remove_file(&hard_link);
            let output = match alias {
                "same" => input.clone(),
                "symlink" => {
                    std::os::unix::fs::symlink(&input, &symlink).unwrap();
                    symlink.clone()
                }
                _ => {
                    std::fs::hard_link(&input, &hard_link).unwrap();
                    hard_link.clone()
                }
            };
            let mut args = command.clone();
            args.extend([flag.to_string(), s(&output).to_string()]);
            if command[0] == "render" && flag != "--out" {
                args.extend(strings(&["--out", s(&dir.path().join("r.png"))]));
            }
            let (code, err) = run(&args);
            assert_ne!(code, 0, "{args:?} ({alias}) was accepted");
            assert!(
                err.contains(flag) && err.contains("is the input"),
                "{args:?} ({alias}): {err}"
            );
            for (path, bytes) in &before {
                assert_eq!(
                    &std::fs::read(path).unwrap(),
                    bytes,
                    "{args:?} ({alias}) changed {}",
                    path.display()
                );
            }
        }
    }
    let _ = std::fs::remove_file(&symlink);
    let _ = std::fs::remove_file(&hard_link);
    assert_eq!(names(dir.path()), ["c.png", "data", "h.png", "t.tiles"]);
}

#[test]
fn a_failed_output_leaves_no_output_and_no_temporary() {
    let (dir, h, c) = folder_with_maps();
    let out = dir.path().join("out");
    std::fs::create_dir(&out).unwrap();
    let missing = dir.path().join("no-such-folder");
    let at = |name: &str| s(&out.join(name)).to_string();
    let into_missing = |name: &str| s(&missing.join(name)).to_string();
    let scene = |cmd: &str| strings(&[cmd, "--height", s(&h), "--color", s(&c)]);
    let with = |mut base: Vec<String>, extra: Vec<String>| {
        base.extend(extra);
        base
    };
    let cases: Vec<Vec<String>> = vec![
        // render: the image and depth could be written, the stats not.
        with(
            scene("render"),
            vec![
                "--size".into(),
                "32x24".into(),
                "--out".into(),
                at("v.png"),
                "--depth".into(),
                at("v.pfm"),
                "--stats".into(),
                into_missing("v.json"),
            ],
        ),
        // render: an output that is a folder.
        with(
            scene("render"),
            vec![
                "--out".into(),
                at("v.png"),
                "--depth".into(),
                s(&out).into(),
            ],
        ),
        // render: two outputs on one file.
        with(
            scene("render"),
            vec!["--out".into(), at("v.png"), "--stats".into(), at("v.png")],
        ),
        // fly: the GIF could be written, the report not.
        with(
            scene("fly"),
            vec![
                "--frames".into(),
                "2".into(),
                "--size".into(),
                "16x12".into(),
                "--out".into(),
                at("f.gif"),
                "--report".into(),
                into_missing("r.json"),
            ],
        ),
        // page: frames could be written, the report not.
        strings(&[
            "page",
            "--terrain",
            "procedural:4096",
            "--frames",
            "2",
            "--size",
            "16x12",
            "--frames-dir",
            s(&out),
            "--report",
            &into_missing("r.json"),
        ]),
    ];
    for args in cases {
        let (code, err) = run(&args);
        assert_ne!(code, 0, "{args:?} was accepted");
        assert_eq!(err.trim_end().lines().count(), 1, "{args:?}: {err}");
        assert!(names(&out).is_empty(), "{args:?} left {:?}", names(&out));
    }
    assert_eq!(names(dir.path()), ["c.png", "h.png", "out"]);
}

#[test]
fn a_failed_pack_leaves_nothing() {
    let (dir, h, _) = folder_with_maps();
    let out = dir.path().join("t.tiles");
    // Heights beyond the kernel's range, found before the file is begun.
    let (code, err) = run(&strings(&[
        "pack",
        "--height",
        s(&h),
        "--height-scale",
        "1000",
        "--out",
        s(&out),
    ]));
    assert_ne!(code, 0);
    assert!(err.contains("outside the kernel's range"), "{err}");
    // A color map cut off at 60 %, found mid-stream.
    let big = dir.path().join("big-c.png");
    let big_h = dir.path().join("big-h.png");
    image::GrayImage::from_fn(256, 256, |x, y| image::Luma([((x ^ y) & 63) as u8]))
        .save(&big_h)
        .unwrap();
    image::RgbImage::from_fn(256, 256, |x, y| {
        image::Rgb([((x * 7) ^ (y * 13)) as u8, (x * y) as u8, (x + y) as u8])
    })
    .save(&big)
    .unwrap();
    let bytes = std::fs::read(&big).unwrap();
    let truncated = dir.path().join("cut.png");
    std::fs::write(&truncated, &bytes[..bytes.len() * 6 / 10]).unwrap();
    let (code, err) = run(&strings(&[
        "pack",
        "--height",
        s(&big_h),
        "--color",
        s(&truncated),
        "--out",
        s(&out),
    ]));
    assert_ne!(code, 0);
    assert!(err.contains(s(&truncated)), "names the file: {err}");
    assert_eq!(
        names(dir.path()),
        ["big-c.png", "big-h.png", "c.png", "cut.png", "h.png"]
    );
}

/// Every numeric flag of every command, with a base command line that is
/// otherwise valid and the values it must refuse.
#[test]
fn every_numeric_flag_refuses_bad_values_naming_the_flag() {
    let (dir, h, _) = folder_with_maps();
    let out = |name: &str| s(&dir.path().join(name)).to_string();
    let render = strings(&["render", "--height", s(&h), "--out", &out("r.png")]);
    let pack = strings(&["pack", "--height", s(&h), "--out", &out("t.tiles")]);
    let fly = strings(&["fly", "--out", &out("f.gif")]);
    let page = strings(&["page"]);
    let sim_ = strings(&["sim"]);
    let bench = strings(&["bench", "--csv", &out("b.csv"), "--chart", &out("b.png")]);
    let board = strings(&["board", "scene", "--out", &out("s.tcb")]);
    let verify = strings(&["board", "verify", "--scene", "s", "--from", "d"]);
    const REAL: &[&str] = &["nan", "inf", "-inf", "1e308", "-1e308"];
    const COUNT: &[&str] = &["nan", "inf", "-inf", "1e308", "-1", "1.5"];
    let mut cases: Vec<(&Vec<String>, &str, Vec<&str>)> = Vec::new();
    // (base command line, flag, generic bad values, the flag's own)
    type Row<'a> = (&'a Vec<String>, &'a str, &'a [&'a str], &'a [&'a str]);
    let table: Vec<Row> = vec![
        (&render, "--height-scale", REAL, &["0", "-1"]),
        (&render, "--procedural-size", COUNT, &["0", "1", "8193"]),
        (&render, "--seed", COUNT, &[]),
        (&render, "--yaw", REAL, &["361", "-361"]),
        (&render, "--pitch", REAL, &["-90", "91"]),
        (&render, "--hfov", REAL, &["0", "-1", "161"]),
        (&render, "--roll", REAL, &["181", "-181"]),
        (&render, "--pixel-to-voxel", REAL, &["0", "-1", "256"]),
        (&render, "--voxelspace-growth", REAL, &["-1", "11"]),
        (&render, "--march-step", REAL, &["0", "-1", "65"]),
        (&render, "--supersample", COUNT, &["0", "17"]),
        (
            &render,
            "--eye",
            &["nan,1,1", "1,inf,1", "1,1,-inf"],
            &["1,2"],
        ),
        (
            &render,
            "--size",
            &["0x10", "-1x10", "nanx10"],
            &["9000x10"],
        ),
        (&render, "--sky", &["-1,0,0", "256,0,0", "nan,0,0"], &[]),
        (&pack, "--height-scale", REAL, &["0", "-1"]),
        (&pack, "--seed", COUNT, &[]),
        (&fly, "--frames", COUNT, &["0", "100001"]),
        (&fly, "--display-hz", REAL, &["0", "-30", "1001"]),
        (&fly, "--render-hz", REAL, &["0", "-1"]),
        (&fly, "--hfov", REAL, &["0", "179"]),
        (&fly, "--margin", REAL, &["0.5", "3"]),
        (&fly, "--processors", COUNT, &["0", "1", "1025"]),
        (&fly, "--size", &["0x10"], &["4096x10"]),
        (&fly, "--height-scale", REAL, &["0"]),
        (&fly, "--procedural-size", COUNT, &["1"]),
        (&fly, "--seed", COUNT, &[]),
        (&page, "--seed", COUNT, &[]),
        (&page, "--frames", COUNT, &["0"]),
        (&page, "--fps", REAL, &["0", "-30", "1001"]),
        (&page, "--hfov", REAL, &["0", "179"]),
        (&page, "--turn", REAL, &["3601"]),
        (&page, "--speed", REAL, &["-1"]),
        (&page, "--pitch", REAL, &["91"]),
        (&page, "--load-budget", COUNT, &["0"]),
        (&page, "--lead", REAL, &["-1", "11"]),
        (&page, "--eye", &["nan,1,1"], &[]),
        (&page, "--size", &["0x10"], &[]),
        (&sim_, "--processors", COUNT, &["1", "1025"]),
        (&sim_, "--deadline-ms", REAL, &["0", "-1"]),
        (&sim_, "--frames", COUNT, &["0"]),
        (&sim_, "--speed", REAL, &["1e5"]),
        (&sim_, "--threads", COUNT, &["0", "1025", "1,0"]),
        (&sim_, "--yaw", REAL, &[]),
        (&sim_, "--pitch", REAL, &["-90"]),
        (&sim_, "--hfov", REAL, &["0"]),
        (&bench, "--repeats", COUNT, &["0", "21"]),
        (&bench, "--size", &["0x10"], &[]),
        (&board, "--procedural-size", COUNT, &["1", "801"]),
        (&board, "--seed", COUNT, &[]),
        (&board, "--size", &["0x10"], &[]),
        (&verify, "--budget", REAL, &["0", "-1"]),
    ];
    for (base, flag, generic, specific) in &table {
        cases.push((
            base,
            flag,
            generic.iter().chain(specific.iter()).copied().collect(),
        ));
    }
    let mut checked = 0;
    for (base, flag, values) in cases {
        for value in values {
            let mut args = base.clone();
            args.extend([flag.to_string(), value.to_string()]);
            let (code, err) = run(&args);
            assert_eq!(code, 2, "{args:?}: exit {code}: {err}");
            assert!(
                err.contains(&format!("'{flag} "))
                    && err.contains(value.split(',').next().unwrap_or(value)),
                "{args:?}: '{err}' names neither the flag nor the value"
            );
            assert_eq!(err.trim_end().lines().count(), 1, "{args:?}: {err}");
            checked += 1;
        }
    }
    assert!(checked > 250, "{checked} bad values checked");
    assert!(names(dir.path()).iter().all(|n| n.ends_with(".png")));
}

#[test]
fn a_bare_command_lists_the_commands() {
    for args in [&[][..], &["board"][..]] {
        let (code, out, err) = sim(args);
        assert_eq!(code, 2, "{args:?}");
        let text = out + &err;
        assert!(text.contains("Commands:"), "{args:?}: {text}");
    }
    let (_, _, err) = sim(&[]);
    for command in ["fly", "render", "pack", "page", "sim", "bench", "board"] {
        assert!(err.contains(command), "{command} missing: {err}");
    }
}

#[test]
fn the_gif_keeps_the_flights_clock() {
    use image::AnimationDecoder;
    let dir = tempfile::tempdir().unwrap();
    let gif = dir.path().join("f.gif");
    let frames = 45;
    let (code, _, err) = sim(&[
        "fly",
        "--procedural-size",
        "128",
        "--frames",
        &frames.to_string(),
        "--size",
        "16x12",
        "--no-measure",
        "--out",
        s(&gif),
    ]);
    assert_eq!(code, 0, "{err}");
    let decoder = image::codecs::gif::GifDecoder::new(std::io::BufReader::new(
        std::fs::File::open(&gif).unwrap(),
    ))
    .unwrap();
    let delays_ms: Vec<f64> = decoder
        .into_frames()
        .map(|f| {
            let (numer, denom) = f.unwrap().delay().numer_denom_ms();
            f64::from(numer) / f64::from(denom)
        })
        .collect();
    assert_eq!(delays_ms.len(), frames);
    let total_ms: f64 = delays_ms.iter().sum();
    let flight_ms = frames as f64 * 1000.0 / 30.0;
    assert!(
        (total_ms - flight_ms).abs() <= 10.0,
        "{frames} frames at 30 Hz play {total_ms} ms, the flight is {flight_ms} ms"
    );
}
