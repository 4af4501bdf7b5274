//! `terracast-sim bench`: speed against accuracy for every method.

use super::values::{number, size};
use crate::bench::{
    against_voxel_space_at_pitch_0, csv, flicker, run, split_by_map_size, summarize, summary_table,
    views, BenchScene, LARGE_MAP_SIDE, TIMED_NS,
};
use crate::chart::draw_bench;
use crate::error::{Error, Result};
use crate::outputs::Outputs;
use crate::scene::{load_pair, procedural, Scene};
use std::path::PathBuf;

#[derive(Debug, clap::Args)]
pub(super) struct BenchArgs {
    /// Shared data folder: adds the Comanche maps C1W/D1 and C7W/D7 to the
    /// built-in scenes (procedural 1024², 512² and 4096²).
    #[arg(long, value_name = "DIR")]
    data: Option<PathBuf>,
    /// Image size of every view.
    #[arg(long, default_value = "320x240", value_parser = size, allow_hyphen_values = true, value_name = "WxH")]
    size: (u32, u32),
    /// Timed runs of each render at least (a fast render runs until its
    /// runs take 60 ms); the best counts.
    #[arg(long, default_value_t = 3, value_name = "N", value_parser = number(1u32, 20), allow_hyphen_values = true)]
    repeats: u32,
    /// Only the first scene's pitch-0 and pitch-15 views, and no flicker
    /// flights (a smoke run).
    #[arg(long)]
    quick: bool,
    /// Per-view measures (CSV).
    #[arg(long, default_value = "bench.csv", value_name = "OUT.csv")]
    csv: PathBuf,
    /// The chart (PNG).
    #[arg(long, default_value = "bench.png", value_name = "OUT.png")]
    chart: PathBuf,
    /// Run only the stability suite (each method where methods fail) and
    /// print its table.
    #[arg(long)]
    stability: bool,
}

pub(super) fn bench_command(args: BenchArgs) -> Result<()> {
    if args.stability {
        let outcomes = crate::stability::run(args.size, |done, total| {
            eprint!("\rstability: condition {done}/{total}   ");
        })?;
        eprintln!();
        print!("{}", crate::stability::table(&outcomes));
        return Ok(());
    }
    let mut outputs = Outputs::new();
    let comanche = args.data.as_ref().map(|dir| dir.join("comanche"));
    let comanche_maps: Vec<_> = [("C1W", "D1"), ("C7W", "D7")]
        .into_iter()
        .flat_map(|(color, height)| {
            let dir = comanche.clone().unwrap_or_default();
            [
                ("--data", dir.join(format!("{height}.png"))),
                ("--data", dir.join(format!("{color}.png"))),
            ]
        })
        .collect();
    if comanche.is_some() {
        for (flag, path) in &comanche_maps {
            outputs.input(flag, path);
        }
    }
    let csv_out = outputs.output("--csv", &args.csv)?;
    let chart_out = outputs.output("--chart", &args.chart)?;
    let mut named: Vec<(String, Scene)> = vec![
        ("procedural 1024".into(), procedural(1024, 1)),
        ("procedural 512 seed 9".into(), procedural(512, 9)),
    ];
    if comanche.is_some() {
        for pair in comanche_maps.chunks(2) {
            let (h, c) = (&pair[0].1, &pair[1].1);
            let name = |p: &std::path::Path| {
                p.file_stem()
                    .map(|s| s.to_string_lossy().into_owned())
                    .unwrap_or_default()
            };
            named.push((
                format!("{}/{}", name(c), name(h)),
                load_pair(h, Some(c), 1.0, 0)?,
            ));
        }
    }
    if args.quick {
        named.truncate(1);
    } else {
        // Terrain out to 4000 voxels, where a voxel is a seventh of a pixel
        // at 320 x 240: the pyramid's case, which the smaller maps do not
        // reach.
        named.push(("procedural 4096".into(), procedural(4096, 1)));
    }
    let scenes = named
        .into_iter()
        .map(|(name, scene)| BenchScene::new(name, scene))
        .collect::<Result<Vec<_>>>()?;
    let mut suite: Vec<_> = scenes
        .iter()
        .enumerate()
        .flat_map(|(i, s)| views(i, &s.scene))
        .collect();
    if args.quick {
        suite.retain(|v| v.camera.pitch_deg == 0.0 || v.camera.pitch_deg == 15.0);
    }
    let measures = run(&scenes, &suite, args.size, args.repeats, |done, total| {
        eprint!("\rbench: view {done}/{total} (reference, then every setting)   ");
    })?;
    eprintln!();
    std::fs::write(outputs.temporary(csv_out), csv(&measures))
        .map_err(|e| Error::new(format!("cannot write --csv {}: {e}", args.csv.display())))?;
    let mut summaries = summarize(&measures);
    if !args.quick {
        let flicker = flicker(&scenes, args.size, 8, |done, total| {
            eprint!("\rbench: flicker, scene {done}/{total} (an 8-frame flight)   ");
        })?;
        eprintln!();
        for summary in &mut summaries {
            summary.flicker = flicker
                .iter()
                .find(|(n, _)| *n == summary.setting)
                .map(|(_, f)| *f);
        }
    }
    draw_bench(outputs.temporary(chart_out), &summaries)?;
    outputs.commit()?;
    println!(
        "{} views of {}x{}, {} settings; best of {} runs or more (as many as {} ms of a setting's renders of a view take), one thread",
        suite.len(),
        args.size.0,
        args.size.1,
        summaries.len(),
        args.repeats,
        TIMED_NS / 1_000_000
    );
    print!("{}", summary_table(&summaries));
    // The same measures split by map size: which setting wins depends on
    // how far the terrain reaches.
    let labels = [
        format!("maps up to {LARGE_MAP_SIDE}²"),
        format!("maps over {LARGE_MAP_SIDE}²"),
    ];
    for (label, part) in labels.iter().zip(split_by_map_size(&measures, &scenes)) {
        if !part.is_empty() && part.len() < measures.len() {
            println!("{label} alone ({} views):", part.len() / summaries.len());
            print!("{}", summary_table(&summarize(&part)));
        }
    }
    // The default, without its footprint colors (what they cost where the
    // two methods agree on what a view is), and that with heights on each
    // ray's path (what the own path buys back).
    for setting in [
        "kernel",
        "kernel level-0 colors",
        "kernel level-0 colors and heights on each ray's path",
    ] {
        if let Some((ratio, kernel, voxel)) = against_voxel_space_at_pitch_0(&measures, setting) {
            let name = if setting == "kernel" {
                "the kernel"
            } else {
                setting
            };
            println!(
                "pitch 0: {name} is {ratio:.2}x the speed of voxelspace, at {kernel:.2} dB against {voxel:.2} dB"
            );
        }
    }
    println!("wrote {} and {}", args.csv.display(), args.chart.display());
    Ok(())
}
