//! The `terracast-sim render` command line: outputs as the view contract
//! says, and bad input ending in one line, a non-zero exit and no panic.

mod common;

use common::{s, sim};
use std::path::{Path, PathBuf};

fn temp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("terracast-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

fn small_maps() -> (PathBuf, PathBuf) {
    maps_named("h.png", "c.png")
}

/// A 16 x 16 height map and color map under these names. Tests run in
/// parallel: each writes its own files.
fn maps_named(height: &str, color: &str) -> (PathBuf, PathBuf) {
    let (h, c) = (temp(height), temp(color));
    common::write_small_maps(&h, &c);
    (h, c)
}

#[test]
fn renders_png_depth_and_stats_as_the_contract_says() {
    let (h, c) = maps_named("contract-h.png", "contract-c.png");
    let (png, pfm, json) = (temp("v.png"), temp("v.pfm"), temp("v.json"));
    for method in [
        "kernel",
        "reference",
        "march",
        "voxelspace",
        "volume",
        "boundary",
    ] {
        let (code, _, err) = sim(&[
            "render",
            "--height",
            s(&h),
            "--color",
            s(&c),
            "--eye",
            "-4,7.5,80",
            "--yaw",
            "0",
            "--pitch",
            "40",
            "--size",
            "32x24",
            "--method",
            method,
            "--out",
            s(&png),
            "--depth",
            s(&pfm),
            "--stats",
            s(&json),
        ]);
        assert_eq!(code, 0, "{method}: {err}");
        let image = image::open(&png).unwrap();
        assert_eq!((image.width(), image.height()), (32, 24));
        assert!(matches!(image, image::DynamicImage::ImageRgb8(_)));
        let (w, hh, depth) =
            terracast_sim::output::read_pfm(&std::fs::read(&pfm).unwrap()).unwrap();
        assert_eq!((w, hh), (32, 24));
        assert!(depth.iter().all(|d| !d.is_nan()), "{method}: NaN depth");
        // Voxel Space cannot pitch (it shifts the horizon; looking 40° down
        // it misses this small map), so only the true cameras are held to
        // the view.
        if method != "voxelspace" {
            assert!(depth[0].is_infinite(), "{method}: top-left sees sky");
            assert!(
                depth[32 * 23 + 16].is_finite(),
                "{method}: bottom middle sees terrain"
            );
        }
        let stats: serde_json::Value =
            serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
        for key in ["pixels", "steps", "resident_bytes", "render_ns"] {
            assert!(stats[key].as_u64().is_some(), "{method}: stats lack {key}");
        }
        assert_eq!(stats["pixels"], 32 * 24);
        if method == "kernel" {
            // A terrain pixel's ray shades from one or two grid lines.
            let (colors, sky) = (&stats["color_fetches"], &stats["sky_pixels"]);
            let terrain = 32 * 24 - sky.as_u64().unwrap();
            let colors = colors.as_u64().expect("kernel stats count color fetches");
            assert!(
                (terrain..=2 * terrain).contains(&colors),
                "{colors} color fetches for {terrain} terrain pixels"
            );
        }
    }
}

#[test]
fn bad_input_gives_one_line_and_a_nonzero_exit() {
    let (h, c) = small_maps();
    let big = temp("big.png");
    image::RgbImage::new(1, 40).save(&big).unwrap();
    let not_png = temp("not.png");
    std::fs::write(&not_png, b"not an image").unwrap();
    let out = temp("bad.png");
    let base = |extra: &[&str]| {
        let mut v = vec![
            "render",
            "--height",
            s(&h),
            "--color",
            s(&c),
            "--out",
            s(&out),
        ];
        v.extend_from_slice(extra);
        v.into_iter().map(String::from).collect::<Vec<_>>()
    };
    let cases: Vec<(Vec<String>, &str)> = vec![
        (
            vec![
                "render".into(),
                "--height".into(),
                "/nonexistent/h.png".into(),
                "--out".into(),
                s(&out).into(),
            ],
            "cannot open",
        ),
        (base(&["--eye", "1,2"]), "X,Y,Z"),
        (base(&["--eye", "nan,2,3"]), "--eye"),
        (base(&["--yaw", "abc"]), "abc"),
        (base(&["--size", "0x10"]), "size"),
        (base(&["--height-path", "sideways"]), "--height-path"),
        (
            base(&["--vertical-samples", "3"]),
            "1, 2, 4, 8 or footprint",
        ),
        (
            base(&["--method", "march", "--march-step", "0"]),
            "--march-step",
        ),
        (
            base(&["--method", "voxelspace", "--voxelspace-growth", "-1"]),
            "--voxelspace-growth",
        ),
        (base(&["--pitch", "120"]), "pitch"),
        (base(&["--roll", "190"]), "--roll"),
        (
            base(&["--method", "voxelspace", "--roll", "10"]),
            "cannot roll",
        ),
        (base(&["--hfov", "0"]), "--hfov"),
        (base(&["--height-scale", "-1"]), "height-scale"),
        (base(&["--height-scale", "1000"]), "kernel's range"),
        (base(&["--sky", "1,2,300"]), "300"),
        (base(&["--method", "magic"]), "magic"),
        (
            vec![
                "render".into(),
                "--height".into(),
                s(&not_png).into(),
                "--out".into(),
                s(&out).into(),
            ],
            "decode",
        ),
        (
            vec![
                "render".into(),
                "--height".into(),
                s(&h).into(),
                "--color".into(),
                s(&big).into(),
                "--out".into(),
                s(&out).into(),
            ],
            "too small",
        ),
        (
            vec![
                "render".into(),
                "--height".into(),
                s(&h).into(),
                "--out".into(),
                "/nonexistent/dir/x.png".into(),
            ],
            "cannot write",
        ),
        (vec!["render".into()], "--out"),
    ];
    for (args, needle) in cases {
        let refs: Vec<&str> = args.iter().map(String::as_str).collect();
        let (code, _, err) = sim(&refs);
        assert_ne!(code, 0, "{args:?} succeeded");
        assert_eq!(
            err.trim_end().lines().count(),
            1,
            "{args:?}: not one line: {err}"
        );
        assert!(
            !err.contains("panicked") && !err.contains("internal error"),
            "{args:?}: {err}"
        );
        assert!(
            err.contains(needle),
            "{args:?}: '{err}' does not mention '{needle}'"
        );
    }
}

#[test]
fn rays_by_footprint_cast_more_rays_than_pixels_and_fewer_than_four_each() {
    let png = temp("footprint.png");
    let stats = temp("footprint.json");
    let (code, _, err) = sim(&[
        "render",
        "--procedural-size",
        "256",
        "--size",
        "96x72",
        "--vertical-samples",
        "footprint",
        "--out",
        s(&png),
        "--stats",
        s(&stats),
    ]);
    assert_eq!(code, 0, "{err}");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&stats).unwrap()).unwrap();
    let (rays, pixels) = (
        json["rays"].as_u64().unwrap(),
        json["pixels"].as_u64().unwrap(),
    );
    assert!(
        rays > pixels && rays < 4 * pixels,
        "{rays} rays, {pixels} pixels"
    );
}

#[test]
fn procedural_scene_needs_no_data() {
    let png = temp("proc.png");
    let (code, _, err) = sim(&[
        "render",
        "--procedural-size",
        "128",
        "--size",
        "64x36",
        "--out",
        s(&png),
    ]);
    assert_eq!(code, 0, "{err}");
    assert_eq!(image::open(&png).unwrap().width(), 64);
}

/// `--height-path ray` reads heights on each ray's own path: a level view
/// (whose image lines go through every pixel center) is the same image,
/// a pitched one is not.
#[test]
fn heights_on_each_rays_path_change_only_a_pitched_or_rolled_view() {
    let render = |pitch: &str, height_path: &str| {
        let png = temp(&format!("height-path-{pitch}-{height_path}.png"));
        let (code, _, err) = sim(&[
            "render",
            "--procedural-size",
            "256",
            "--size",
            "96x54",
            "--eye",
            "128,20,150",
            "--yaw",
            "90",
            "--pitch",
            pitch,
            "--height-path",
            height_path,
            "--out",
            s(&png),
        ]);
        assert_eq!(code, 0, "{err}");
        image::open(&png).unwrap().to_rgb8().into_raw()
    };
    assert_eq!(render("0", "line"), render("0", "ray"));
    assert_ne!(render("12", "line"), render("12", "ray"));
}

#[test]
fn a_tiles_file_renders_with_its_own_height_filter() {
    let (h, c) = maps_named("tiles-h.png", "tiles-c.png");
    let tiles = temp("mean.tiles");
    let (code, _, err) = sim(&[
        "pack",
        "--height",
        s(&h),
        "--color",
        s(&c),
        "--height-filter",
        "mean",
        "--out",
        s(&tiles),
    ]);
    assert_eq!(code, 0, "{err}");
    let png = temp("tiles.png");
    let render = |filter: &[&str]| {
        let mut args = vec!["render", "--terrain", s(&tiles), "--size", "32x24"];
        args.extend_from_slice(filter);
        args.extend_from_slice(&["--out", s(&png)]);
        sim(&args)
    };
    // Without the flag the file's own filter is used.
    let (code, _, err) = render(&[]);
    assert_eq!(code, 0, "{err}");
    let (code, _, err) = render(&["--height-filter", "mean"]);
    assert_eq!(code, 0, "{err}");
    // Asking for another is one line naming the file's.
    let (code, _, err) = render(&["--height-filter", "subsample"]);
    assert_ne!(code, 0);
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    assert!(err.contains("packed with --height-filter mean"), "{err}");
}

#[test]
fn every_rendering_command_takes_the_kernel_settings_and_a_keyframed_path() {
    let path = temp("keys.txt");
    std::fs::write(&path, "0 500 100 200 90 10\n1 520 200 200 80 14\n").unwrap();
    let gif = temp("kernel-flags.gif");
    let runs: [&[&str]; 3] = [
        &[
            "fly",
            "--frames",
            "4",
            "--size",
            "32x24",
            "--no-measure",
            "--out",
            s(&gif),
        ],
        &["sim", "--frames", "2", "--size", "32x24", "--threads", "1"],
        &[
            "page",
            "--frames",
            "2",
            "--size",
            "32x24",
            "--terrain",
            "procedural:4096",
        ],
    ];
    for run in runs {
        let with = |extra: &[&str]| -> Vec<String> {
            run.iter().chain(extra).map(|a| a.to_string()).collect()
        };
        let sim = |args: Vec<String>| sim(&args.iter().map(String::as_str).collect::<Vec<_>>());
        for settings in [
            &["--coherence", "off", "--resolution", "single"][..],
            &["--shading", "nearest", "--vertical-samples", "2"][..],
            &["--height-path", "ray"][..],
        ] {
            let (code, _, err) = sim(with(settings));
            assert_eq!(code, 0, "{run:?} {settings:?}: {err}");
        }
        let (code, _, err) = sim(with(&["--vertical-samples", "footprint"]));
        assert_eq!(code, 1, "{run:?}");
        assert!(err.contains("only `render`"), "{run:?}: {err}");
        let (code, _, err) = sim(with(&["--path", s(&path)]));
        assert_eq!(code, 0, "{run:?} --path: {err}");
    }
    // The path is an input like any other.
    let (code, _, err) = sim(&[
        "page",
        "--frames",
        "1",
        "--path",
        s(&path),
        "--report",
        s(&path),
    ]);
    assert_ne!(code, 0);
    assert!(err.contains("is the input --path"), "{err}");
    assert!(std::fs::read_to_string(&path).unwrap().starts_with("0 500"));
}

#[test]
fn the_window_without_a_display_or_with_bad_input_says_so_in_one_line() {
    let run = |args: &[&str], display: Option<&str>| {
        let mut command = std::process::Command::new(env!("CARGO_BIN_EXE_terracast-sim"));
        command.arg("view").args(args).env_remove("WAYLAND_DISPLAY");
        match display {
            Some(d) => command.env("DISPLAY", d),
            None => command.env_remove("DISPLAY"),
        };
        let out = command.output().unwrap();
        (
            out.status.code().unwrap_or(-1),
            String::from_utf8_lossy(&out.stderr).into_owned(),
        )
    };
    let missing = temp("no-such-map.png");
    let not_a_display = Some(":7951");
    let cases: [(&[&str], Option<&str>, &str); 5] = [
        (&["--procedural-size", "64"], None, "DISPLAY is not set"),
        (
            &["--procedural-size", "64"],
            not_a_display,
            "cannot connect to the display",
        ),
        (&["--height", s(&missing)], None, "no-such-map.png"),
        (&["--threads", "0"], None, "--threads"),
        (&["--pitch", "95"], None, "--pitch"),
    ];
    for (args, display, says) in cases {
        let (code, err) = run(args, display);
        assert_ne!(code, 0, "{args:?}");
        assert!(err.contains(says), "{args:?}: {err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{args:?}: {err}");
    }
}

#[test]
fn every_method_renders_the_atmosphere_and_bad_settings_get_one_line() {
    let frame = |name: &str, extra: &[&str]| {
        let png = temp(name);
        let mut args = vec![
            "render",
            "--procedural-size",
            "128",
            "--size",
            "48x27",
            "--pitch",
            "4",
            "--out",
            s(&png),
        ];
        args.extend_from_slice(extra);
        let (code, _, err) = sim(&args);
        assert_eq!(code, 0, "{args:?}: {err}");
        image::open(&png).unwrap().to_rgb8()
    };
    for method in ["kernel", "reference", "voxelspace", "march"] {
        let plain = frame(&format!("air-plain-{method}.png"), &["--method", method]);
        let hazy = frame(
            &format!("air-hazy-{method}.png"),
            &["--method", method, "--atmosphere", "on"],
        );
        // The top row is sky: the gradient, not the contract's flat sky.
        assert_eq!(
            plain.get_pixel(0, 0).0,
            terracast::config::DEFAULT_SKY,
            "{method}"
        );
        assert_ne!(plain, hazy, "{method}");
    }
    let out = temp("air-bad.png");
    for (extra, says) in [
        (vec!["--fog", "2"], "--fog"),
        (vec!["--sun", "10"], "AZ,EL"),
        (vec!["--relief", "sometimes"], "--relief"),
        (
            vec!["--terrain", "procedural:4096", "--relief", "shadows"],
            "--relief needs a terrain in memory",
        ),
    ] {
        let mut args = vec!["render", "--out", s(&out)];
        args.extend_from_slice(&extra);
        let (code, _, err) = sim(&args);
        assert_ne!(code, 0, "{extra:?}");
        assert!(err.contains(says), "{extra:?}: {err}");
        assert_eq!(err.trim().lines().count(), 1, "{err}");
    }
}

/// The example scene file in the repository (`scenes/farm.toml`).
fn farm() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../scenes/farm.toml")
}

#[test]
fn a_scene_file_stands_its_objects_on_the_terrain_and_bad_ones_get_one_line() {
    let (bare, placed) = (temp("farm-bare.png"), temp("farm.png"));
    let view = [
        "--procedural-size",
        "1024",
        "--eye",
        "520,440,150",
        "--yaw",
        "265",
        "--pitch",
        "22",
        "--size",
        "160x90",
    ];
    let render = |out: &PathBuf, extra: &[&str]| {
        let mut args = vec!["render", "--out", s(out)];
        args.extend_from_slice(&view);
        args.extend_from_slice(extra);
        sim(&args)
    };
    let (code, _, err) = render(&bare, &[]);
    assert_eq!(code, 0, "{err}");
    let (code, _, err) = render(&placed, &["--place", s(&farm())]);
    assert_eq!(code, 0, "{err}");
    assert!(err.contains("placed 6 objects (1 sculpted kinds)"), "{err}");
    let (a, b) = (image::open(&bare).unwrap(), image::open(&placed).unwrap());
    let changed = a
        .to_rgb8()
        .pixels()
        .zip(b.to_rgb8().pixels())
        .filter(|(a, b)| a != b)
        .count();
    assert!(changed > 160 * 90 / 20, "the farm changes {changed} pixels");
    // With --objects the wood and the village grow around the farm.
    let (code, _, err) = render(&placed, &["--place", s(&farm()), "--objects"]);
    assert_eq!(code, 0, "{err}");
    assert!(
        err.contains("placed 6 objects") && err.contains("trees and"),
        "{err}"
    );

    // Bad scene files, and --place where objects cannot go: one line each.
    let bad = temp("bad-scene.toml");
    std::fs::write(&bad, "[[place]]\nobject = \"castle\"\nat = [1, 2]\n").unwrap();
    let off = temp("off-map.toml");
    std::fs::write(&off, "[[place]]\nobject = \"house\"\nat = [5000, 2]\n").unwrap();
    let missing = temp("no-such-scene.toml");
    let farm = farm();
    let cases: [(&[&str], &str); 4] = [
        (&["--place", s(&bad)], "no object \"castle\""),
        (
            &["--place", s(&off)],
            "place 1 (house at 5000, 2): it does not fit on the map",
        ),
        (&["--place", s(&missing)], "cannot read scene file"),
        (
            &["--place", s(&farm), "--terrain", "procedural:4096"],
            "--place stands objects on a terrain in memory",
        ),
    ];
    for (extra, expected) in cases {
        let (code, _, err) = render(&placed, extra);
        assert_ne!(code, 0, "{extra:?}");
        assert!(err.contains(expected), "{extra:?}: {err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{extra:?}: {err}");
    }
    // A view of a sculpted object is an input: never written over.
    let front = farm.with_file_name("barn-front.png");
    let before = std::fs::read(&front).unwrap();
    let (code, _, err) = render(&front, &["--place", s(&farm)]);
    assert_ne!(code, 0);
    assert!(err.contains("--place"), "{err}");
    assert_eq!(std::fs::read(&front).unwrap(), before);
}

#[test]
fn a_photo_finer_than_the_height_grid_is_kept_unless_asked_not_to() {
    // A 16 x 16 height map under a 64 x 64 checkered photo: four pixels a
    // grid spacing, squares of two, which the grid's colors average to one gray.
    let (h, _) = maps_named("fine-h.png", "fine-unused.png");
    let photo = temp("fine-photo.png");
    image::RgbImage::from_fn(64, 64, |x, y| {
        if (x / 2 + y / 2) % 2 == 0 {
            image::Rgb([250, 250, 250])
        } else {
            image::Rgb([10, 10, 10])
        }
    })
    .save(&photo)
    .unwrap();
    let render = |extra: &[&str], out: &PathBuf| {
        let args = [
            &[
                "render",
                "--height",
                s(&h),
                "--color",
                s(&photo),
                "--eye",
                "8,2,36",
                "--yaw",
                "90",
                "--pitch",
                "50",
                "--size",
                "64x48",
                "--out",
                s(out),
            ][..],
            extra,
        ]
        .concat();
        let (code, _, err) = sim(&args);
        assert_eq!(code, 0, "{err}");
        (image::open(out).unwrap().to_rgb8(), err)
    };
    let (kept, said) = render(&[], &temp("fine-kept.png"));
    assert!(
        said.contains("photo kept at 4 texels a grid spacing"),
        "{said}"
    );
    let (reduced, said) = render(&["--photo-detail", "off"], &temp("fine-reduced.png"));
    assert!(!said.contains("photo kept"), "{said}");
    // Reduced, the terrain is the checker's gray; kept, its squares show
    // near the eye.
    let spread = |image: &image::RgbImage| {
        let reds = image.pixels().map(|p| p[0]);
        reds.clone().max().unwrap() - reds.min().unwrap()
    };
    assert!(
        spread(&kept) > spread(&reduced) + 100,
        "{} against {}",
        spread(&kept),
        spread(&reduced)
    );
}

/// `pack --place` carries a scene file's objects into the tiled file:
/// `render --terrain` draws the PNG `render --place` draws from the maps;
/// `--objects` beside `--terrain` is refused in one line that names
/// `pack`.
#[test]
fn objects_packed_into_a_tiles_file_render_as_from_the_maps() {
    let (h, c) = maps_named("objects-h.png", "objects-c.png");
    let plan = temp("objects.toml");
    std::fs::write(
        &plan,
        "[[place]]\nobject = \"house\"\nat = [8, 8]\nheading = 0\nscale = 1\n",
    )
    .unwrap();
    let tiles = temp("objects.tiles");
    let (code, out, err) = sim(&[
        "pack",
        "--height",
        s(&h),
        "--color",
        s(&c),
        "--place",
        s(&plan),
        "--out",
        s(&tiles),
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("placed 1 objects"), "{out}");
    let camera = [
        "--eye", "-6,8,45", "--yaw", "0", "--pitch", "35", "--size", "64x48",
    ];
    let render = |scene: &[&str], png: &Path| {
        let mut args = vec!["render"];
        args.extend_from_slice(scene);
        args.extend_from_slice(&camera);
        args.extend_from_slice(&["--out", s(png)]);
        let (code, _, err) = sim(&args);
        assert_eq!(code, 0, "{err}");
        std::fs::read(png).unwrap()
    };
    let from_tiles = render(&["--terrain", s(&tiles)], &temp("objects-t.png"));
    let maps = ["--height", s(&h), "--color", s(&c)];
    let from_maps = render(
        &[&maps[..], &["--place", s(&plan)]].concat(),
        &temp("objects-m.png"),
    );
    let bare = render(&maps, &temp("objects-b.png"));
    assert!(from_tiles == from_maps);
    assert!(from_tiles != bare, "the house shows");
    let (code, _, err) = sim(&[
        "render",
        "--terrain",
        s(&tiles),
        "--objects",
        "--out",
        s(&temp("refused.png")),
    ]);
    assert_ne!(code, 0);
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    assert!(err.contains("pack --objects"), "{err}");
}
