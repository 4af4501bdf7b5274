//! `terracast-sim fly`: the main job. A flight at a steady display rate on
//! the modeled machine, written as an animation and a report.

use super::values::{hfov, number, positive, size};
use super::{load_scene, SceneArgs};
use crate::error::{Error, Result};
use crate::fly::{fly, FlyOptions, Kind, Path};
use crate::outputs::{OutputId, Outputs};
use image::codecs::gif::{GifEncoder, Repeat};
use image::{Delay, Frame, RgbaImage};
use indicatif::{ProgressBar, ProgressStyle};
use std::path::PathBuf;

#[derive(Debug, clap::Args)]
pub(super) struct FlyArgs {
    #[command(flatten)]
    scene: SceneArgs,
    /// Camera path: one keyframe a line, `t x y z yaw pitch [roll]`
    /// (seconds, voxels, degrees; roll 0 when left out) [default: a
    /// built-in scenic path over the scene, banking into its turns].
    #[arg(long, value_name = "PATH.txt")]
    path: Option<PathBuf>,
    /// Fly the path level: every keyframe's roll taken as 0.
    #[arg(long)]
    level: bool,
    /// Display frames [default: the path's length at the display rate].
    #[arg(long, value_name = "N", value_parser = number(1u32, 100_000), allow_hyphen_values = true)]
    frames: Option<u32>,
    /// Display rate, frames a second.
    #[arg(long, default_value_t = 30.0, value_name = "HZ", value_parser = positive(0.0f64, 1000.0), allow_hyphen_values = true)]
    display_hz: f64,
    /// Rendering rate the budget is made for; the frames between are
    /// warped.
    #[arg(long, default_value_t = 10.0, value_name = "HZ", value_parser = positive(0.0f64, 1000.0), allow_hyphen_values = true)]
    render_hz: f64,
    /// Display size, up to 2048x2048.
    #[arg(long, default_value = "200x150", value_parser = display_size, allow_hyphen_values = true, value_name = "WxH")]
    size: (u32, u32),
    /// Horizontal field of view, degrees.
    #[arg(long, default_value_t = 60.0, value_name = "DEG", value_parser = hfov, allow_hyphen_values = true)]
    hfov: f32,
    /// How much wider and taller than the display frames are rendered, so
    /// that warps stay inside them.
    #[arg(long, default_value_t = 1.2, value_name = "M", value_parser = number(1.0f32, 2.0), allow_hyphen_values = true)]
    margin: f32,
    /// Machine description (TOML); fields left out keep the PVS defaults.
    #[arg(long, value_name = "MACHINE.toml")]
    machine: Option<PathBuf>,
    /// Processors, master included (overrides the machine file).
    #[arg(long, value_name = "N", value_parser = number(2u32, 1024), allow_hyphen_values = true)]
    processors: Option<u32>,
    /// Skip rendering each warped frame's true view (faster; no warp PSNR).
    #[arg(long)]
    no_measure: bool,
    /// The animation: an animated GIF (`.gif`), or an existing folder for a
    /// PNG a frame.
    #[arg(long, default_value = "fly.gif", value_name = "OUT.gif|DIR")]
    out: PathBuf,
    /// The report: a record per display frame, as JSON.
    #[arg(long, value_name = "REPORT.json")]
    report: Option<PathBuf>,
    #[command(flatten)]
    atmosphere: super::atmosphere::AtmosphereArgs,
    #[command(flatten)]
    kernel: super::KernelArgs,
}

/// `fly --size`: the display is at most 2048 a side.
fn display_size(text: &str) -> std::result::Result<(u32, u32), String> {
    let (w, h) = size(text)?;
    if w > 2048 || h > 2048 {
        return Err(format!("{w}x{h} is larger than 2048x2048"));
    }
    Ok((w, h))
}

pub(super) fn fly_command(args: FlyArgs) -> Result<()> {
    let machine = super::sim::load_machine(args.machine.as_deref(), args.processors)?;
    machine.check()?;
    let png_dir = args.out.is_dir();
    let is_gif = args
        .out
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("gif"));
    if !png_dir && !is_gif {
        return Err(Error::new(format!(
            "--out {}: give a .gif file or an existing folder",
            args.out.display()
        )));
    }
    let mut outputs = Outputs::new();
    args.scene.name_inputs(&mut outputs);
    for (flag, path) in [("--path", &args.path), ("--machine", &args.machine)] {
        if let Some(path) = path {
            outputs.input(flag, path);
        }
    }
    let gif: Option<OutputId> = if png_dir {
        outputs.folder("--out", &args.out)?;
        None
    } else {
        Some(outputs.output("--out", &args.out)?)
    };
    let report_out = args
        .report
        .as_deref()
        .map(|path| outputs.output("--report", path))
        .transpose()?;
    let mut scene = load_scene(&args.scene)?;
    args.atmosphere
        .shade(&mut scene, true, !args.scene.color.is_empty())?;
    let path = match &args.path {
        Some(file) => super::load_path(file)?,
        None => Path::scenic(&scene),
    };
    let path = if args.level { path.level() } else { path };
    let frames = match args.frames {
        Some(n) => n,
        None => ((path.duration() * args.display_hz).floor() as u32 + 1).min(100_000),
    };
    let options = FlyOptions {
        frames,
        display_hz: args.display_hz,
        render_hz: args.render_hz,
        size: args.size,
        hfov: args.hfov,
        margin: args.margin,
        measure_warp: !args.no_measure,
        render: args.kernel.fixed_rays_options()?,
        atmosphere: args.atmosphere.prepared(true)?,
    };
    let kernel = scene.to_kernel_with(args.kernel.height_filter())?;
    let bar = ProgressBar::new(u64::from(frames)).with_style(
        ProgressStyle::with_template("fly: {bar:30} {pos}/{len} display frames, {eta} left")
            .map_err(|e| Error::new(e.to_string()))?,
    );
    let flight = fly(&kernel, &path, &machine, &options, |k| {
        bar.set_position(u64::from(k))
    })?;
    bar.finish_and_clear();

    match gif {
        Some(id) => write_gif(
            outputs.temporary(id),
            &flight.images,
            args.size,
            args.display_hz,
        )?,
        None => {
            for (k, image) in flight.images.iter().enumerate() {
                let id = outputs.output("--out", &args.out.join(format!("frame-{k:05}.png")))?;
                crate::output::write_png(
                    outputs.temporary(id),
                    &crate::frame::Frame {
                        width: args.size.0,
                        height: args.size.1,
                        colors: image.clone(),
                        depth: vec![f32::INFINITY; image.len()],
                    },
                )?;
            }
        }
    }
    if let Some(id) = report_out {
        crate::output::write_json(outputs.temporary(id), &flight.report_json(&options))?;
    }
    outputs.commit()?;

    let rendered = flight
        .frames
        .iter()
        .filter(|f| f.kind == Kind::Rendered)
        .count();
    let met = flight.frames.iter().filter(|f| f.deadline_met).count();
    let render_ms: Vec<f64> = {
        let mut seen = std::collections::BTreeMap::new();
        for f in &flight.frames {
            seen.insert(f.render, f.render_ms);
        }
        seen.into_values().collect()
    };
    let mean_render = render_ms.iter().sum::<f64>() / render_ms.len().max(1) as f64;
    let mut renders = std::collections::BTreeMap::new();
    for f in &flight.frames {
        renders.insert(
            f.render,
            (f.coarse_lines, f.filled_rays, f.level_bias, f.cost),
        );
    }
    let coarse = renders.values().filter(|r| r.0 > 0).count();
    let filled = renders.values().filter(|r| r.1 > 0).count();
    let biases = renders.values().map(|r| r.2);
    let (low, high) = biases.fold((f64::INFINITY, 0.0f64), |(l, h), b| (l.min(b), h.max(b)));
    println!(
        "{frames} display frames at {} Hz, {}x{}: {rendered} rendered, {} warped; {met}/{frames} on time",
        args.display_hz,
        args.size.0,
        args.size.1,
        frames as usize - rendered,
    );
    let shares = renders
        .values()
        .map(|r| r.3 as f64 / flight.budget.max(1) as f64);
    let (least, most) = shares.fold((f64::INFINITY, 0.0f64), |(l, h), s| (l.min(s), h.max(s)));
    println!(
        "renders: budget {} cycles, each render {:.4} to {:.4} of it; mean {:.1} ms ({:.1} Hz alone), longest {:.1} ms, on {} processors at {} MHz",
        flight.budget,
        least,
        most,
        mean_render,
        1e3 / mean_render.max(1e-9),
        render_ms.iter().copied().fold(0.0, f64::max),
        machine.processors,
        machine.clock_mhz,
    );
    println!(
        "governor: level bias {low:.2} to {high:.2}; {coarse} of {} renders finished coarser, {filled} repeated pixels",
        renders.len()
    );
    let psnr: Vec<f64> = flight.frames.iter().filter_map(|f| f.warp_psnr).collect();
    if !psnr.is_empty() {
        let finite: Vec<f64> = psnr.iter().copied().filter(|p| p.is_finite()).collect();
        println!(
            "warped frames against a true render: mean {:.2} dB, worst {:.2} dB",
            finite.iter().sum::<f64>() / finite.len().max(1) as f64,
            psnr.iter().copied().fold(f64::INFINITY, f64::min)
        );
    }
    println!("wrote {}", args.out.display());
    Ok(())
}

/// Display frame `k`'s delay in the GIF's centiseconds: frame k ends at
/// round((k + 1) × 100 / hz) cs, so the delays alternate (3 and 4 cs at
/// 30 Hz) and their sum keeps the flight's clock to within a centisecond.
/// A delay is at least 1 cs (players treat 0 as "as fast as you can").
fn frame_delay_cs(k: usize, hz: f64) -> u32 {
    let end = |k: usize| (k as f64 * 100.0 / hz).round() as u32;
    (end(k + 1) - end(k)).max(1)
}

fn write_gif(
    path: &std::path::Path,
    images: &[Vec<[u8; 3]>],
    size: (u32, u32),
    hz: f64,
) -> Result<()> {
    let file = std::fs::File::create(path)
        .map_err(|e| Error::new(format!("cannot write {}: {e}", path.display())))?;
    let mut encoder = GifEncoder::new_with_speed(std::io::BufWriter::new(file), 10);
    encoder
        .set_repeat(Repeat::Infinite)
        .map_err(|e| Error::new(format!("cannot write {}: {e}", path.display())))?;
    for (k, image) in images.iter().enumerate() {
        let delay = Delay::from_numer_denom_ms(frame_delay_cs(k, hz) * 10, 1);
        let rgba: Vec<u8> = image.iter().flat_map(|c| [c[0], c[1], c[2], 255]).collect();
        let buffer = RgbaImage::from_raw(size.0, size.1, rgba)
            .ok_or_else(|| Error::new("frame size does not match the display size"))?;
        encoder
            .encode_frame(Frame::from_parts(buffer, 0, 0, delay))
            .map_err(|e| Error::new(format!("cannot write {}: {e}", path.display())))?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::frame_delay_cs;

    #[test]
    fn gif_delays_keep_the_flights_clock() {
        for (hz, frames) in [(30.0, 300), (30.0, 7), (24.0, 100), (60.0, 61), (10.0, 9)] {
            let total: u32 = (0..frames).map(|k| frame_delay_cs(k, hz)).sum();
            let flight_cs = frames as f64 * 100.0 / hz;
            assert!(
                (f64::from(total) - flight_cs).abs() <= 1.0,
                "{frames} frames at {hz} Hz: {total} cs against {flight_cs}"
            );
        }
        let first: Vec<u32> = (0..3).map(|k| frame_delay_cs(k, 30.0)).collect();
        assert_eq!(first, [3, 4, 3]);
    }
}
