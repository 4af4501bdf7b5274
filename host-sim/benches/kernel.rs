//! Kernel speed at 640 × 480 on a Comanche map (C7W/D7; the procedural
//! scene when the shared data is absent): Mpx/s and steps per pixel with
//! coherence off, exact and at its default, and the speed-up ratios measured
//! in this one run.
//!
//!     cargo bench -p terracast-sim --bench kernel
//!
//! Criterion reports the time and throughput (Melem/s = Mpx/s) of each; the
//! summary at the end gives steps per pixel and the ratios against
//! coherence off, from criterion's own estimates of this run.

use criterion::{BenchmarkId, Criterion, Throughput};
use std::path::{Path, PathBuf};
use terracast::{render, Camera, Coherence, CountingProbe, NoProbe, RenderOptions, View};
use terracast_sim::kernel::SampleBuffer;
use terracast_sim::scene::{load_pair, procedural, Scene};

const SIZE: (u32, u32) = (640, 480);
const SETTINGS: [(&str, Coherence); 3] = [
    ("coherence-off", Coherence::Off),
    ("coherence-exact", Coherence::Exact),
    ("coherence-default", Coherence::DEFAULT),
];

fn scene() -> (Scene, &'static str) {
    let dir = std::env::var_os("TERRACAST_DATA")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../shared/data"))
        .join("comanche");
    match load_pair(&dir.join("D7.png"), Some(&dir.join("C7W.png")), 1.0, 0) {
        Ok(scene) => (scene, "C7W/D7"),
        Err(_) => (procedural(1024, 1), "procedural 1024"),
    }
}

fn main() {
    let (scene, name) = scene();
    let kernel = scene.to_kernel().expect("kernel scene");
    let terrain = kernel.terrain().expect("terrain");
    let camera = Camera {
        eye: [300.0, 700.0, 170.0],
        yaw_deg: 20.0,
        pitch_deg: 15.0,
        roll_deg: 0.0,
        hfov_deg: 60.0,
    };
    let view = View::new(&camera, SIZE.0, SIZE.1).expect("view");
    let pixels = u64::from(SIZE.0 * SIZE.1);
    let out_dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../target/criterion-kernel");

    let mut criterion = Criterion::default()
        .output_directory(&out_dir)
        .configure_from_args();
    let mut group = criterion.benchmark_group("kernel_640x480");
    group.throughput(Throughput::Elements(pixels));
    group.sample_size(10);
    for (label, coherence) in SETTINGS {
        let options = RenderOptions {
            coherence,
            ..RenderOptions::default()
        };
        let mut buffer = SampleBuffer::new(SIZE.0, SIZE.1);
        group.bench_function(BenchmarkId::from_parameter(label), |b| {
            b.iter(|| render(&terrain, &view, &options, &mut buffer, &mut NoProbe))
        });
    }
    group.finish();
    criterion.final_summary();

    println!(
        "\nkernel at {}x{} on {name}, eye {:?} yaw {} pitch {}:",
        SIZE.0, SIZE.1, camera.eye, camera.yaw_deg, camera.pitch_deg
    );
    println!("| setting | steps/pixel | Mpx/s | speed-up vs off |");
    println!("|---|---|---|---|");
    let mean_ns = |label: &str| -> Option<f64> {
        let path = out_dir
            .join("kernel_640x480")
            .join(label)
            .join("new/estimates.json");
        let json: serde_json::Value = serde_json::from_slice(&std::fs::read(path).ok()?).ok()?;
        json["mean"]["point_estimate"].as_f64()
    };
    let base = mean_ns("coherence-off");
    for (label, coherence) in SETTINGS {
        let options = RenderOptions {
            coherence,
            ..RenderOptions::default()
        };
        let mut probe = CountingProbe::default();
        render(
            &terrain,
            &view,
            &options,
            &mut SampleBuffer::new(SIZE.0, SIZE.1),
            &mut probe,
        );
        let spp = probe.steps as f64 / pixels as f64;
        match (mean_ns(label), base) {
            (Some(ns), Some(base)) => {
                println!(
                    "| {label} | {spp:.2} | {:.2} | {:.2}x |",
                    pixels as f64 / ns * 1e3,
                    base / ns
                )
            }
            _ => println!("| {label} | {spp:.2} | (not measured in this run) | |"),
        }
    }
}
