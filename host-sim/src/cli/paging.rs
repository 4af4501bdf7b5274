//! `terracast-sim pack`, `terracast-sim page`, and `render --terrain`:
//! tiled terrain on the command line.

use super::values::{number, positive, seed, size};
use super::{view_error, Method, RenderArgs, RenderFiles};
use crate::error::{Error, Result};
use crate::output::{stats_json, write_png};
use crate::outputs::Outputs;
use crate::tiles::{
    pack, page_flight, render_tiled_in, PackInput, PageOptions, PagedFrame, Terrain, SLOTS, TILE,
};
use indicatif::{ProgressBar, ProgressStyle};
use std::path::PathBuf;
use terracast::tiles::{Tile, TileSource, World, WINDOW_SIDE};
use terracast::{Camera, HeightFilter, View};

#[derive(Debug, clap::Args)]
pub(super) struct PackArgs {
    /// Height map: 8/16-bit grayscale PNG, SRTM .hgt or GeoTIFF.
    #[arg(long, value_name = "H.png|H.hgt|H.tif")]
    height: PathBuf,
    /// Color map: an 8-bit PNG of the same size, or photos as `render`
    /// drapes them (GeoTIFF photos over a GeoTIFF height map by their
    /// georeference: give --color once for each, later over earlier)
    /// [default: colored by height and slope, as `render` colors a height
    /// map alone].
    #[arg(long, value_name = "C.png|C.tif")]
    color: Vec<PathBuf>,
    /// World height of one height-map unit, in voxels [default: 1; for an
    /// SRTM .hgt, one meter in voxels of its grid spacing].
    #[arg(long, value_name = "S", value_parser = positive(0.0f32, 1e6), allow_hyphen_values = true)]
    height_scale: Option<f32>,
    /// How the pyramid's coarse heights are made.
    #[arg(long, value_enum, default_value_t = super::HeightFilterArg::Wavelet)]
    height_filter: super::HeightFilterArg,
    /// Seed of the coloring's texture (without --color) and of the
    /// objects' planting.
    #[arg(long, default_value_t = 1, value_name = "N", value_parser = seed, allow_hyphen_values = true)]
    seed: u64,
    /// Plant a wood and a village on the map by a rule seeded with
    /// --seed, as `render --objects` does: the file carries the objects
    /// (the map is then loaded whole).
    #[arg(long)]
    objects: bool,
    /// Stand the objects a scene file places on the map, as `render
    /// --place` does (TOML; see docs/objects.md).
    #[arg(long, value_name = "FILE.toml")]
    place: Option<PathBuf>,
    /// The tiled terrain file to write.
    #[arg(long, value_name = "T.tiles")]
    out: PathBuf,
}

pub(super) fn pack_command(args: PackArgs) -> Result<()> {
    let height_scale = super::height_scale(&args.height, args.height_scale)?;
    let input = PackInput {
        height: args.height,
        colors: args.color,
        height_scale,
        filter: args.height_filter.into(),
        seed: args.seed,
        objects: args.objects,
        place: args.place,
    };
    let bar = ProgressBar::new(0).with_style(
        ProgressStyle::with_template("pack {bar:40} {pos}/{len} rows {elapsed}")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let summary = pack(&input, &args.out, &mut |done, rows| {
        bar.set_length(u64::from(rows));
        bar.set_position(u64::from(done));
    })?;
    bar.finish_and_clear();
    if let Some(objects) = &summary.objects {
        println!("{objects}");
    }
    let voids = if summary.voids > 0 {
        format!(
            ", {} voids filled holding at most {} rows",
            summary.voids, summary.void_rows_held_at_most
        )
    } else {
        String::new()
    };
    let photos = match (summary.photo_tiles, summary.photo_rows_held_at_most) {
        (0, _) => String::new(),
        (tiles, 0) => format!(
            " and {tiles} photo tiles (photos finer than the height grid, at their own resolution)"
        ),
        (tiles, rows) => format!(
            " and {tiles} photo tiles (photos finer than the height grid, at their own resolution; at most {rows} rows of a photo held)"
        ),
    };
    println!(
        "packed {}x{}: {} levels, {} tiles of {TILE}x{TILE}{photos}, {} bytes, at most {} rows held{voids}, {} -> {}",
        summary.width,
        summary.depth,
        summary.levels,
        summary.tiles,
        summary.bytes,
        summary.rows_held_at_most,
        if summary.streamed {
            "streamed"
        } else {
            "loaded whole"
        },
        args.out.display()
    );
    Ok(())
}

/// A view over the middle of a world: the south edge, as `render` places
/// it on a map, when the world fits one window; its center otherwise.
pub(super) fn default_eye(world: &World) -> [f32; 3] {
    let top = f32::from(world.max_height) / 16.0;
    if world.width <= WINDOW_SIDE && world.depth <= WINDOW_SIDE {
        crate::scene::south_edge_eye(world.width, world.depth, top)
    } else {
        [
            world.width as f32 * 0.5,
            world.depth as f32 * 0.5,
            top + 100.0,
        ]
    }
}

pub(super) fn render_tiled_command(
    args: &RenderArgs,
    spec: &str,
    outputs: Outputs,
    files: RenderFiles,
) -> Result<()> {
    if args.method != Method::Kernel {
        return Err(Error::new("--terrain renders with --method kernel only"));
    }
    args.atmosphere.check_tiled()?;
    let mut terrain = Terrain::open(spec, args.scene.seed)?;
    let world = terrain.world();
    let [yaw, pitch] = super::DEFAULT_YAW_PITCH;
    let camera = args.camera.camera(
        default_eye(&world),
        [yaw, pitch, terracast::config::DEFAULT_HFOV_DEG],
    );
    let (width, height) = args.size;
    let sky = args.sky.unwrap_or(terracast::config::DEFAULT_SKY);
    let options = args.kernel.options(sky);
    // A file's levels are built already: it renders with its own filter,
    // and asking for another is an error rather than a silent substitute.
    if let (Terrain::File(file), Some(wanted)) = (&terrain, args.kernel.height_filter) {
        if file.filter() != HeightFilter::from(wanted) {
            let packed = super::HeightFilterArg::from(file.filter()).name();
            return Err(Error::new(format!(
                "{} was packed with --height-filter {packed}; leave --height-filter out to render with it, or pack the file again",
                file.path().display(),
            )));
        }
    }
    View::new(
        &Camera {
            eye: [0.0, 0.0, camera.eye[2]],
            ..camera
        },
        width,
        height,
    )
    .map_err(view_error)?;
    let (frame, stats, tiled) = render_tiled_in(
        &mut terrain,
        &camera,
        (width, height),
        &options,
        args.kernel.vertical_samples.1,
        args.atmosphere.prepared(false)?.as_ref(),
    )?;
    let mut json = stats_json(&stats, width, height, frame.sky_pixels());
    json["tiles"] = serde_json::to_value(tiled).map_err(|e| Error::new(e.to_string()))?;
    files.write(&outputs, &frame, &json)?;
    outputs.commit()?;
    if tiled.misses > 0 {
        eprintln!(
            "warning: {} of {} footprint tiles could not be loaded ({} rejected for bad checksums); drawn from coarser levels",
            tiled.misses, tiled.footprint_tiles, tiled.rejected
        );
    }
    if tiled.photo_misses > 0 {
        eprintln!(
            "warning: {} of {} photo tiles could not be loaded; drawn from coarser fine levels of the photos",
            tiled.photo_misses, tiled.photo_tiles
        );
    }
    Ok(())
}

#[derive(Debug, clap::Args)]
pub(super) struct PageArgs {
    /// The terrain: a file from `pack`, or procedural:SIZE.
    #[arg(
        long,
        default_value = "procedural:131072",
        value_name = "T.tiles|procedural:SIZE"
    )]
    terrain: String,
    /// Seed of a procedural terrain.
    #[arg(long, default_value_t = 1, value_name = "N", value_parser = seed, allow_hyphen_values = true)]
    seed: u64,
    /// Frames to fly.
    #[arg(long, default_value_t = 90, value_name = "N", value_parser = number(1u32, 100_000), allow_hyphen_values = true)]
    frames: u32,
    /// Frame rate.
    #[arg(long, default_value_t = 30.0, value_name = "HZ", value_parser = positive(0.0f32, 1000.0), allow_hyphen_values = true)]
    fps: f32,
    /// Image size.
    #[arg(long, default_value = "320x240", value_parser = size, allow_hyphen_values = true, value_name = "WxH")]
    size: (u32, u32),
    /// The flight's first camera (it turns and flies along its heading).
    #[command(flatten)]
    camera: super::CameraArgs,
    /// Fly this keyframed path instead of turning (see `fly --path`).
    #[arg(long, value_name = "PATH.txt", conflicts_with_all = ["turn", "speed", "eye", "yaw", "pitch"])]
    path: Option<PathBuf>,
    #[command(flatten)]
    kernel: super::KernelArgs,
    /// Heading change, degrees a second [default: one field of view a
    /// second].
    #[arg(long, value_name = "DEG", value_parser = number(-3600.0f32, 3600.0), allow_hyphen_values = true)]
    turn: Option<f32>,
    /// Ground speed, voxels a second.
    #[arg(long, default_value_t = 300.0, value_name = "V", value_parser = number(0.0f32, 1e5), allow_hyphen_values = true)]
    speed: f32,
    /// Tiles the loader may fetch during one frame [default: the PVS
    /// disk's 70 MB/s over a frame].
    #[arg(long, value_name = "N", value_parser = number(1u32, 1_000_000), allow_hyphen_values = true)]
    load_budget: Option<u32>,
    /// Only fetch what a frame lacked (no next-frame or extended
    /// footprint): shows what prefetch is for.
    #[arg(long)]
    no_prefetch: bool,
    /// How far ahead the extended footprint looks, seconds.
    #[arg(long, default_value_t = 0.25, value_name = "S", value_parser = number(0.0f32, 10.0), allow_hyphen_values = true)]
    lead: f32,
    /// Folder to write each frame to as a PNG.
    #[arg(long, value_name = "DIR")]
    frames_dir: Option<PathBuf>,
    /// The report: a record per frame, as JSON.
    #[arg(long, value_name = "REPORT.json")]
    report: Option<PathBuf>,
}

pub(super) fn page_command(args: PageArgs) -> Result<()> {
    let mut outputs = Outputs::new();
    outputs.input("--terrain", std::path::Path::new(&args.terrain));
    if let Some(path) = &args.path {
        outputs.input("--path", path);
    }
    if let Some(dir) = &args.frames_dir {
        outputs.folder("--frames-dir", dir)?;
    }
    let report_out = args
        .report
        .as_deref()
        .map(|path| outputs.output("--report", path))
        .transpose()?;
    let mut terrain = Terrain::open(&args.terrain, args.seed)?;
    let world = terrain.world();
    let start = args.camera.camera(
        default_eye(&world),
        [0.0, 20.0, terracast::config::DEFAULT_HFOV_DEG],
    );
    let path = args.path.as_deref().map(super::load_path).transpose()?;
    View::new(
        &Camera {
            eye: [0.0, 0.0, start.eye[2]],
            ..start
        },
        args.size.0,
        args.size.1,
    )
    .map_err(view_error)?;
    const DISK_BYTES_PER_S: f32 = 70e6;
    let load_budget = args
        .load_budget
        .unwrap_or((DISK_BYTES_PER_S / args.fps / Tile::<TILE>::BYTES as f32).max(1.0) as u32);
    let options = PageOptions {
        size: args.size,
        frames: args.frames,
        fps: args.fps,
        turn_deg_per_s: args.turn.unwrap_or(start.hfov_deg),
        speed: args.speed,
        start,
        load_budget,
        prefetch: !args.no_prefetch,
        lead_s: args.lead,
        options: args.kernel.fixed_rays_options()?,
        path,
    };
    let bar = ProgressBar::new(u64::from(args.frames)).with_style(
        ProgressStyle::with_template("page {bar:40} {pos}/{len} frames {elapsed} {msg}")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let frames_dir = args.frames_dir.clone();
    let report = page_flight(&mut terrain, &options, &mut |image, record: &PagedFrame| {
        bar.inc(1);
        bar.set_message(format!(
            "{} loads, {} missing",
            record.loads, record.missing_tiles
        ));
        if let Some(dir) = &frames_dir {
            let id = outputs.output(
                "--frames-dir",
                &dir.join(format!("frame-{:04}.png", record.frame)),
            )?;
            write_png(outputs.temporary(id), image)?;
        }
        Ok(())
    })?;
    bar.finish_and_clear();
    let virtual_gib = u64::from(world.width) * u64::from(world.depth) * 4 / (1 << 30);
    let (mean_ratio, max_ratio) = report.resident_ratio();
    let (mean_loads, max_loads) = report.loads_per_frame();
    println!(
        "{}x{} terrain ({virtual_gib} GiB at 4 bytes a voxel), cache {SLOTS} tiles of {TILE}x{TILE} ({:.1} MiB), {} frames at {} Hz turning {:.0} deg/s, load budget {load_budget} tiles a frame{}",
        world.width,
        world.depth,
        report.cache_bytes as f64 / (1 << 20) as f64,
        args.frames,
        args.fps,
        options.turn_deg_per_s,
        if options.prefetch { "" } else { ", no prefetch" }
    );
    println!(
        "frames after the first drawn with a tile missing: {} of {}",
        report.frames_missing_after_first(),
        report.frames.len().saturating_sub(1)
    );
    println!("loads a frame after the first: mean {mean_loads:.1}, most {max_loads}");
    let (mean_touched, max_touched) = report.resident_over_touched();
    println!("resident bytes / frame footprint: mean {mean_ratio:.2}, most {max_ratio:.2}");
    println!(
        "resident bytes / tiles the frame read: mean {mean_touched:.2}, most {max_touched:.2}"
    );
    if report.rejected > 0 {
        eprintln!(
            "warning: {} tile loads rejected for bad checksums ({} frames); those tiles were drawn from coarser levels",
            report.rejected,
            report.frames.iter().filter(|f| f.rejected > 0).count()
        );
    }
    if let Some(id) = report_out {
        crate::output::write_json(outputs.temporary(id), &report)?;
    }
    outputs.commit()
}
