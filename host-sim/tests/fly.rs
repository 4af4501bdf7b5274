//! `terracast-sim fly`, the main job: on a fresh machine with no data it
//! writes a viewable animation and its report; a flight whose rendering
//! runs at 10–15 Hz alone delivers every display frame on time; bad input
//! ends in one line.

mod common;

use common::{s, sim};
use std::path::PathBuf;
use terracast_sim::fly::{fly, FlyOptions, Kind, Path};
use terracast_sim::scene::procedural;
use terracast_sim::sim::Machine;

fn temp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("terracast-fly-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

#[test]
fn with_no_data_it_writes_an_animation_and_its_report() {
    let (gif, report) = (temp("fly.gif"), temp("fly.json"));
    let (code, out, err) = sim(&[
        "fly",
        "--procedural-size",
        "256",
        "--frames",
        "12",
        "--out",
        s(&gif),
        "--report",
        s(&report),
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("12/12 on time"), "{out}");
    // A GIF of 12 frames of the display size.
    let decoder = image::codecs::gif::GifDecoder::new(std::io::BufReader::new(
        std::fs::File::open(&gif).unwrap(),
    ))
    .unwrap();
    let frames = image::AnimationDecoder::into_frames(decoder)
        .collect_frames()
        .unwrap();
    assert_eq!(frames.len(), 12);
    assert_eq!(frames[0].buffer().dimensions(), (200, 150));
    // The report: a record per display frame with the fields the issue names.
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&report).unwrap()).unwrap();
    let records = json["frames"].as_array().unwrap();
    assert_eq!(records.len(), 12);
    for r in records {
        assert!(
            matches!(r["kind"].as_str(), Some("rendered" | "warped")),
            "{r}"
        );
        assert!(
            r["cost"].as_u64().unwrap() <= r["budget"].as_u64().unwrap(),
            "{r}"
        );
        assert!(r["level_bias"].as_f64().unwrap() > 0.0, "{r}");
        assert_eq!(r["deadline_met"], serde_json::json!(true), "{r}");
    }
    assert_eq!(records[0]["kind"], "rendered");
}

#[test]
fn rendering_at_10_to_15_hz_every_display_frame_is_on_time() {
    // The default flight: the built-in scene and path, 200 x 150 at 30 Hz
    // on the PVS, with a budget made for 10 Hz.
    let scene = procedural(1024, 1);
    let kernel = scene.to_kernel().unwrap();
    let path = Path::scenic(&scene);
    let options = FlyOptions {
        frames: 60,
        ..FlyOptions::default()
    };
    let flight = fly(&kernel, &path, &Machine::default(), &options, |_| {}).unwrap();
    assert_eq!(flight.frames.len(), 60);
    assert!(flight.frames.iter().all(|f| f.deadline_met));
    // Every render spends its budget, and no more.
    assert!(flight
        .frames
        .iter()
        .all(|f| f.cost <= f.budget && f.cost * 10 >= f.budget * 9));
    // Renders start on the 10 Hz cadence (Cohen-Or's 10-15 Hz), and
    // rendering alone keeps up with it.
    assert!((10.0..=15.0).contains(&options.render_hz));
    let mut render_ms: Vec<f64> = flight.frames.iter().map(|f| f.render_ms).collect();
    render_ms.dedup();
    let rate = 1e3 * render_ms.len() as f64 / render_ms.iter().sum::<f64>();
    assert!(
        (options.render_hz..=2.0 * options.render_hz).contains(&rate),
        "renders alone at {rate:.1} Hz"
    );
    // Both kinds, and the warped ones measured against the true view.
    let rendered = flight
        .frames
        .iter()
        .filter(|f| f.kind == Kind::Rendered)
        .count();
    assert!(rendered > 10 && rendered < 40, "{rendered} rendered");
    let psnr: Vec<f64> = flight.frames.iter().filter_map(|f| f.warp_psnr).collect();
    assert_eq!(psnr.len(), 60 - rendered);
    let mean = psnr.iter().sum::<f64>() / psnr.len() as f64;
    println!(
        "60 frames, rendering alone at {rate:.1} Hz: {rendered} rendered, warped mean {mean:.2} dB, worst {:.2} dB",
        psnr.iter().copied().fold(f64::INFINITY, f64::min)
    );
    assert!(mean > 24.0, "warped frames average {mean:.2} dB");
    // Deterministic.
    let again = fly(&kernel, &path, &Machine::default(), &options, |_| {}).unwrap();
    assert_eq!(again.frames, flight.frames);
    assert_eq!(again.images, flight.images);
}

#[test]
fn bad_input_is_one_line() {
    let bad_path = temp("bad-path.txt");
    std::fs::write(&bad_path, "0 1 2 3 4 5\n1 1 2 3 4\n").unwrap();
    let gif = temp("out.gif");
    let (gif, bad_path) = (s(&gif), s(&bad_path));
    let cases: [(&[&str], &str); 5] = [
        (
            &["fly", "--out", "/tmp/x.txt"],
            "give a .gif file or an existing folder",
        ),
        (&["fly", "--frames", "0", "--out", gif], "'--frames <N>'"),
        (
            &["fly", "--size", "4000x10", "--out", gif],
            "larger than 2048x2048",
        ),
        (&["fly", "--path", bad_path, "--out", gif], "path line 2"),
        (
            &["fly", "--size", "640x480", "--out", gif],
            "the machine cannot render",
        ),
    ];
    for (args, expected) in cases {
        let (code, _, err) = sim(args);
        assert_ne!(code, 0, "{args:?}");
        assert!(err.contains(expected), "{args:?}: {err}");
        assert_eq!(err.trim().lines().count(), 1, "{args:?}: {err}");
    }
}
