//! `terracast-sim sim`: a flight on the modeled parallel machine, Table 1,
//! and the line pool on real threads.

use super::values::{number, positive, size};
use super::{load_scene_or, CameraArgs, SceneArgs, DEFAULT_PROCEDURAL_SIDE};
use crate::error::{Error, Result};
use crate::outputs::Outputs;
use crate::scene::KernelScene;
use crate::sim::threads::render_threads;
use crate::sim::{
    flight, flight_governor, record_flight, record_governed_flight, simulate_with_sticks, table,
    Machine, SimResult, TABLE_HFOV_DEG, TABLE_MAP_SIDE, TABLE_PITCH,
};
use std::path::PathBuf;
use terracast::config::DEFAULT_HFOV_DEG;
use terracast::{Camera, FrameCost, RenderOptions};

/// Most pixels a run records (frames × image size), about 4 GiB of events.
const MAX_RECORDED_PIXELS: u64 = 100_000_000;

#[derive(Debug, clap::Args)]
pub(super) struct SimArgs {
    #[command(flatten)]
    scene: SceneArgs,
    /// Machine description (TOML); fields left out keep the PVS defaults.
    #[arg(long, value_name = "MACHINE.toml")]
    machine: Option<PathBuf>,
    /// Processors, master included (overrides the machine file).
    #[arg(long, value_name = "N", value_parser = number(2u32, 1024), allow_hyphen_values = true)]
    processors: Option<u32>,
    /// Frame deadline in milliseconds (overrides the machine file).
    #[arg(long, value_name = "MS", value_parser = positive(0.0f64, 1e6), allow_hyphen_values = true)]
    deadline_ms: Option<f64>,
    /// The flight's first camera (it flies along its heading).
    #[command(flatten)]
    camera: CameraArgs,
    /// Image size.
    #[arg(long, default_value = "640x480", value_parser = size, allow_hyphen_values = true, value_name = "WxH")]
    size: (u32, u32),
    /// Frames of the flight.
    #[arg(long, default_value_t = 8, value_name = "N", value_parser = number(1u32, 100_000), allow_hyphen_values = true)]
    frames: u32,
    /// Fly this keyframed path instead (see `fly --path`): the flight's
    /// frames at even times over it.
    #[arg(long, value_name = "PATH.txt", conflicts_with_all = ["speed", "table"])]
    path: Option<PathBuf>,
    /// The kernel's settings (Table 1 keeps the defaults).
    #[command(flatten)]
    kernel: super::KernelArgs,
    /// Render each frame with the kernel's governor, its work within
    /// SHARE of the deadline on all the workers (0.8 when no SHARE is
    /// given; the rest is left for tile copies and memory and disk
    /// waits), at the machine's cycles (`cycles`, local fetches
    /// included): the governor coarsens a frame that would overrun and
    /// spends what a frame leaves on more rays a pixel.
    #[arg(long, value_name = "SHARE", num_args = 0..=1, default_missing_value = "0.8", value_parser = positive(0.0f64, 1.0), conflicts_with_all = ["table", "threads"])]
    governed: Option<f64>,
    /// Voxels the eye advances a frame.
    #[arg(long, default_value_t = 4.0, value_name = "V", value_parser = number(-1e4f32, 1e4), allow_hyphen_values = true)]
    speed: f32,
    /// Print Table 1 instead: fps for 2 to 32 processors at pitch 14.6°,
    /// 26.5° and 39° (a flight of --frames frames at each). Its view sees
    /// only terrain, as Cohen-Or's footprint does: a 4096² map and a 30°
    /// field unless --procedural-size / --height and --hfov say otherwise.
    #[arg(long)]
    table: bool,
    /// With --table: print it as JSON.
    #[arg(long, requires = "table")]
    json: bool,
    /// With --table: draw it as a PNG chart here.
    #[arg(long, requires = "table", value_name = "OUT.png")]
    chart: Option<PathBuf>,
    /// Instead of simulating, render the flight on this many real threads
    /// (a list: 1,2,4) sharing the kernel's line pool, and print Mpx/s.
    #[arg(long, value_delimiter = ',', value_name = "N,N,...", value_parser = number(1usize, 1024), allow_hyphen_values = true)]
    threads: Vec<usize>,
}

/// The machine file at `path` (the PVS without one), with `processors`
/// overriding its count.
pub(super) fn load_machine(
    path: Option<&std::path::Path>,
    processors: Option<u32>,
) -> Result<Machine> {
    let mut machine = match path {
        Some(path) => {
            let text = std::fs::read_to_string(path)
                .map_err(|e| Error::new(format!("cannot read {}: {e}", path.display())))?;
            Machine::from_toml(&text).map_err(|e| Error::new(format!("{}: {e}", path.display())))?
        }
        None => Machine::default(),
    };
    if let Some(p) = processors {
        machine.processors = p;
    }
    Ok(machine)
}

pub(super) fn sim_command(args: SimArgs) -> Result<()> {
    let mut machine = load_machine(args.machine.as_deref(), args.processors)?;
    if let Some(d) = args.deadline_ms {
        machine.frame.deadline_ms = d;
    }
    machine.check()?;
    // The recording holds every frame's events (about 40 bytes a pixel)
    // until the replay: keep it to a few GiB.
    let pixels = u64::from(args.size.0) * u64::from(args.size.1);
    if u64::from(args.frames) * pixels > MAX_RECORDED_PIXELS {
        return Err(Error::new(format!(
            "--frames {} x --size {}x{}: frames x image pixels must be at most {MAX_RECORDED_PIXELS} (the recording keeps about 40 bytes a pixel)",
            args.frames, args.size.0, args.size.1
        )));
    }
    let mut outputs = Outputs::new();
    args.scene.name_inputs(&mut outputs);
    for (flag, path) in [("--machine", &args.machine), ("--path", &args.path)] {
        if let Some(path) = path {
            outputs.input(flag, path);
        }
    }
    let chart = args
        .chart
        .as_deref()
        .map(|path| outputs.output("--chart", path))
        .transpose()?;
    // Table 1 has its own view (see TABLE_HFOV_DEG): every flag given
    // still wins.
    let (side, hfov) = if args.table {
        (TABLE_MAP_SIDE, TABLE_HFOV_DEG)
    } else {
        (DEFAULT_PROCEDURAL_SIDE, DEFAULT_HFOV_DEG)
    };
    let scene = load_scene_or(&args.scene, side)?;
    let kernel = scene.to_kernel_with(args.kernel.height_filter())?;
    let stick_table_bytes = kernel.stick_table_bytes();
    machine.check_resident(stick_table_bytes)?;
    if stick_table_bytes > 0 {
        eprintln!(
            "the objects' stick table ({:.1} KiB) is read from disk once and held whole in global memory and by every worker",
            stick_table_bytes as f64 / 1024.0
        );
    }
    let [yaw, pitch] = super::DEFAULT_YAW_PITCH;
    let start = args.camera.camera(scene.default_eye(), [yaw, pitch, hfov]);
    let options = args.kernel.fixed_rays_options()?;
    let cameras = match &args.path {
        Some(file) => {
            let path = super::load_path(file)?;
            // The frames at even times over the path.
            let last = f64::from(args.frames.max(2) - 1);
            (0..args.frames)
                .map(|i| path.camera(path.duration() * f64::from(i) / last, start.hfov_deg))
                .collect()
        }
        None => flight(&start, args.frames, args.speed),
    };
    if !args.threads.is_empty() {
        return threads_command(&kernel, &cameras, &args, &options);
    }
    if args.table {
        let [x, y, z] = start.eye;
        eprintln!(
            "Table 1 on a {}x{} map: eye ({x:.0}, {y:.0}, {z:.0}), yaw {}°, hfov {}°, {}x{}, {} frames {} voxels apart at each pitch",
            scene.width, scene.depth, start.yaw_deg, start.hfov_deg, args.size.0, args.size.1, args.frames, args.speed
        );
        let table = table(
            &kernel,
            &start,
            args.size,
            args.frames,
            args.speed,
            &machine,
            |row, done| {
                eprint!(
                    "\rrecording pitch {}° ({}/{}): frame {done}/{}   ",
                    TABLE_PITCH[row],
                    row + 1,
                    TABLE_PITCH.len(),
                    args.frames
                )
            },
        )?;
        eprintln!();
        if let Some(id) = chart {
            crate::chart::draw_table(outputs.temporary(id), &table)?;
            outputs.commit()?;
        }
        if args.json {
            println!("{}", table.to_json());
        } else {
            print!("{}", table.markdown());
        }
        return Ok(());
    }
    let progress = |done| {
        eprint!(
            "\rrecording the kernel's work: frame {done}/{}",
            cameras.len()
        );
    };
    let (traces, costs) = match args.governed {
        Some(share) => {
            let mut governor = flight_governor(&machine, share, args.size)?;
            eprintln!(
                "governed: {} cycles a frame ({share} of the deadline on the workers), {:.0} a pixel",
                governor.budget(),
                governor.budget() as f64 / pixels as f64
            );
            let (traces, costs) = record_governed_flight(
                &kernel,
                &cameras,
                args.size,
                &options,
                &machine,
                &mut governor,
                progress,
            )?;
            (traces, Some(costs))
        }
        None => (
            record_flight(&kernel, &cameras, args.size, &options, &machine, progress)?,
            None,
        ),
    };
    eprintln!();
    let result = simulate_with_sticks(&machine, &traces, stick_table_bytes);
    print!("{}", report(&machine, &result, costs.as_deref()));
    Ok(())
}

/// The per-frame table and the summary; with the governor's `costs`, each
/// frame's cost against its budget and its level bias too.
fn report(machine: &Machine, result: &SimResult, costs: Option<&[FrameCost]>) -> String {
    let ms = |ps: u64| ps as f64 / 1e9;
    let mut out = format!(
        "{} processors ({} workers) at {} MHz, deadline {} ms\n",
        machine.processors,
        machine.workers(),
        machine.clock_mhz,
        machine.frame.deadline_ms
    );
    out += "frame  time ms  deadline  compute ms  transfer ms  bank wait ms  disk wait ms  disk reads (critical)";
    out += if costs.is_some() {
        "  cost / budget  level bias  refined line renders\n"
    } else {
        "\n"
    };
    for (i, f) in result.frames.iter().enumerate() {
        let verdict = match f.miss {
            None => "met".to_string(),
            Some(reason) => format!("MISSED ({})", reason.as_str()),
        };
        out += &format!(
            "{i:>5}  {:>7.2}  {verdict:<8}  {:>10.2}  {:>11.2}  {:>12.2}  {:>12.2}  {} ({})",
            ms(f.time),
            ms(f.compute),
            ms(f.transfer),
            ms(f.bank_wait),
            ms(f.disk_wait),
            f.disk_reads,
            f.critical_loads
        );
        match costs.and_then(|c| c.get(i)) {
            Some(cost) => {
                out += &format!(
                    "  {:>13.3}  {:>10.2}  {}\n",
                    cost.cost as f64 / cost.budget.max(1) as f64,
                    cost.level_bias.to_num::<f64>(),
                    cost.refined_lines
                )
            }
            None => out += "\n",
        }
    }
    let utilization = &result.utilization;
    let mean = utilization.iter().sum::<f64>() / utilization.len().max(1) as f64;
    let (lo, hi) = utilization
        .iter()
        .fold((f64::MAX, 0f64), |(lo, hi), &u| (lo.min(u), hi.max(u)));
    let banks = &result.bank_utilization;
    let bank_max = banks.iter().copied().fold(0.0, f64::max);
    let bank_mean = banks.iter().sum::<f64>() / banks.len().max(1) as f64;
    out += &format!(
        "fps (frames after the first): {:.2}; deadline misses: {}/{}\n",
        result.fps(),
        result.misses(),
        result.frames.len()
    );
    out += &format!(
        "worker utilization: mean {:.1} %, min {:.1} %, max {:.1} %; master {:.1} %\n",
        100.0 * mean,
        100.0 * lo.min(hi),
        100.0 * hi,
        100.0 * result.master_utilization
    );
    out += &format!(
        "bank utilization: mean {:.1} %, max {:.1} %; bank contention {:.3} ms in all\n",
        100.0 * bank_mean,
        100.0 * bank_max,
        ms(result.bank_contention)
    );
    out
}

fn threads_command(
    kernel: &KernelScene,
    cameras: &[Camera],
    args: &SimArgs,
    options: &RenderOptions,
) -> Result<()> {
    let available = std::thread::available_parallelism().map_or(1, |n| n.get());
    println!(
        "{} frames of {}x{} on the line pool; this machine has {available} cores",
        cameras.len(),
        args.size.0,
        args.size.1
    );
    println!("threads  Mpx/s  speed-up vs {} thread(s)", args.threads[0]);
    let mut baseline: Option<(f64, Vec<Vec<terracast::Rgb>>)> = None;
    for &threads in &args.threads {
        let run = render_threads(kernel, cameras, args.size, options, threads)?;
        let mpx = run.mpx_per_s(args.size);
        let (base, frames) = baseline.get_or_insert_with(|| (mpx, run.frames.clone()));
        if *frames != run.frames {
            return Err(Error::new(format!(
                "{threads} threads rendered different frames than {}",
                args.threads[0]
            )));
        }
        println!("{threads:>7}  {mpx:>5.2}  {:.2}x", mpx / *base);
    }
    Ok(())
}
