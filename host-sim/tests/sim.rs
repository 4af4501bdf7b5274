//! `terracast-sim sim`: Table 1 as JSON, a flight report, real threads, and
//! bad input ending in one line.

mod common;

use common::{s, sim};

#[test]
fn table_json_has_one_row_of_fps_per_pitch() {
    let (code, out, err) = sim(&[
        "sim",
        "--table",
        "--json",
        "--procedural-size",
        "128",
        "--size",
        "48x36",
        "--frames",
        "2",
    ]);
    assert_eq!(code, 0, "{err}");
    let table: serde_json::Value = serde_json::from_str(out.trim()).unwrap();
    assert_eq!(table["processors"], serde_json::json!([2, 4, 8, 16, 32]));
    assert_eq!(table["pitch"], serde_json::json!([14.6, 26.5, 39.0]));
    let rows = table["fps"].as_array().unwrap();
    assert_eq!(rows.len(), 3);
    for row in rows {
        let fps: Vec<f64> = row
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect();
        assert_eq!(fps.len(), 5);
        assert!(
            fps.windows(2).all(|w| w[1] > w[0]),
            "more processors, more fps: {fps:?}"
        );
    }
}

#[test]
fn a_flight_reports_every_frame_and_the_machine() {
    let dir = std::env::temp_dir().join(format!("terracast-sim-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let machine = dir.join("machine.toml");
    std::fs::write(&machine, "processors = 8\n[frame]\ndeadline_ms = 50.0\n").unwrap();
    let args = [
        "sim",
        "--machine",
        s(&machine),
        "--procedural-size",
        "128",
        "--size",
        "64x48",
        "--frames",
        "3",
    ];
    let (code, out, err) = sim(&args);
    assert_eq!(code, 0, "{err}");
    assert!(
        out.starts_with("8 processors (7 workers) at 40 MHz, deadline 50 ms"),
        "{out}"
    );
    assert_eq!(
        out.lines()
            .filter(|l| l.starts_with(' ') && l.trim_start().starts_with(char::is_numeric))
            .count(),
        3
    );
    assert!(
        out.contains("worker utilization") && out.contains("bank contention"),
        "{out}"
    );
    // Deterministic: the same report again.
    assert_eq!(sim(&args).1, out);

    std::fs::write(&machine, "processors = 8\nbanks = 3\n").unwrap();
    let (code, _, err) = sim(&["sim", "--machine", s(&machine)]);
    assert_eq!(code, 1);
    assert!(
        err.contains("machine.toml") && err.contains("unknown field `banks`"),
        "{err}"
    );
    assert_eq!(err.lines().count(), 1, "{err}");
    let (code, _, err) = sim(&["sim", "--frames", "400", "--size", "640x480"]);
    assert_eq!(code, 1);
    assert!(err.contains("frames x image pixels"), "{err}");
    let (code, _, err) = sim(&["sim", "--processors", "1"]);
    assert_eq!(code, 2);
    assert!(
        err.contains("'--processors <N>'") && err.contains("from 2 to 1024"),
        "{err}"
    );
    let (code, _, err) = sim(&["sim", "--machine", "/nonexistent/m.toml"]);
    assert_eq!(code, 1);
    assert!(err.contains("cannot read /nonexistent/m.toml"), "{err}");
}

#[test]
fn a_flight_over_objects_holds_their_stick_table_or_says_it_cannot() {
    let args = [
        "sim",
        "--objects",
        "--procedural-size",
        "256",
        "--size",
        "64x48",
        "--frames",
        "3",
        "--processors",
        "8",
    ];
    let (code, out, err) = sim(&args);
    assert_eq!(code, 0, "{err}");
    assert!(
        err.contains("trees and") && err.contains("stick table") && err.contains("every worker"),
        "{err}"
    );
    assert!(out.contains("worker utilization"), "{out}");
    // On real threads too.
    let (code, out, err) = sim(&[&args[..], &["--threads", "2"]].concat());
    assert_eq!(code, 0, "{err}");
    assert!(
        out.lines().any(|l| l.trim_start().starts_with("2 ")),
        "{out}"
    );
    // A processor whose local memory holds one tile has no room for it.
    let dir = std::env::temp_dir().join(format!("terracast-sim-objects-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let machine = dir.join("one-tile.toml");
    std::fs::write(&machine, "[local_memory]\nmib = 1\n[tiles]\nside = 512\n").unwrap();
    let (code, _, err) = sim(&[&args[..], &["--machine", s(&machine)]].concat());
    assert_eq!(code, 1);
    assert!(
        err.contains("stick table") && err.contains("local_memory.mib"),
        "{err}"
    );
    assert_eq!(
        err.trim_end()
            .lines()
            .last()
            .map(|l| l.contains("stick table")),
        Some(true)
    );
}

#[test]
fn threads_render_the_same_frames_and_report_mpx() {
    let (code, out, err) = sim(&[
        "sim",
        "--threads",
        "1,2",
        "--procedural-size",
        "128",
        "--size",
        "64x48",
        "--frames",
        "2",
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(
        out.lines()
            .any(|l| l.trim_start().starts_with("2 ") && l.ends_with('x')),
        "{out}"
    );
    let (code, _, err) = sim(&["sim", "--threads", "0"]);
    assert_eq!(code, 2);
    assert!(err.contains("--threads"), "{err}");
}

#[test]
fn bench_writes_one_csv_row_per_view_and_setting_and_marks_the_front() {
    let dir = std::env::temp_dir().join(format!("terracast-bench-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (csv, chart) = (dir.join("b.csv"), dir.join("b.png"));
    let (code, out, err) = sim(&[
        "bench",
        "--quick",
        "--size",
        "48x36",
        "--repeats",
        "1",
        "--csv",
        s(&csv),
        "--chart",
        s(&chart),
    ]);
    let text = std::fs::read_to_string(&csv).unwrap();
    // Two views (pitch 0 and 15 of the first scene), every setting.
    let settings = terracast_sim::bench::settings().len();
    assert_eq!(text.lines().count(), 1 + 2 * settings, "{text}");
    assert!(text.starts_with("scene,view,pitch,setting,psnr_db,ssim"));
    // Every setting is timed: the kernel's without its probe, in renders
    // of their own (a setting left untimed would show no speed at all).
    let header: Vec<&str> = text.lines().next().unwrap().split(',').collect();
    let speed = header.iter().position(|&c| c == "mpx_per_s").unwrap();
    for row in text.lines().skip(1) {
        let mpx_per_s: f64 = row.split(',').nth(speed).unwrap().parse().unwrap();
        assert!(mpx_per_s.is_finite() && mpx_per_s > 0.01, "{row}");
    }
    let fonts = std::path::Path::new("/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf").exists();
    if fonts {
        assert_eq!(code, 0, "{err}");
        assert!(image::open(&chart).is_ok());
        assert!(
            out.contains("| kernel |")
                && out.contains("pitch 0: the kernel is")
                && out.contains("pitch 0: kernel level-0 colors is")
                && out.contains("pitch 0: kernel level-0 colors and heights on each ray's path is"),
            "{out}"
        );
    }
    let (code, _, err) = sim(&["bench", "--repeats", "0"]);
    assert_eq!(code, 2);
    assert!(err.contains("--repeats"), "{err}");
}
