//! Charts (plotters): the simulator's Table 1, and the bench's speed
//! against accuracy.

use crate::bench::Summary;
use crate::error::{Error, Result};
use crate::sim::{Table, COHEN_OR_TABLE_1, TABLE_PITCH, TABLE_PROCESSORS};
use plotters::prelude::*;
use std::path::Path;
use std::sync::OnceLock;

/// Where a sans-serif TrueType font is looked for (the chart's labels).
const FONT_PATHS: [&str; 4] = [
    "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/TTF/DejaVuSans.ttf",
    "/usr/share/fonts/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/truetype/liberation/LiberationSans-Regular.ttf",
];

/// Registers a system font as plotters' "sans-serif" once.
fn font() -> Result<()> {
    static REGISTERED: OnceLock<bool> = OnceLock::new();
    let ok = *REGISTERED.get_or_init(|| {
        FONT_PATHS.iter().any(|path| {
            std::fs::read(path).is_ok_and(|bytes| {
                let bytes: &'static [u8] = Box::leak(bytes.into_boxed_slice());
                plotters::style::register_font("sans-serif", FontStyle::Normal, bytes).is_ok()
            })
        })
    });
    if ok {
        Ok(())
    } else {
        Err(Error::new(format!(
            "no font for the chart's labels (looked for {}); install fonts-dejavu-core",
            FONT_PATHS.join(", ")
        )))
    }
}

/// Draws the series' legend in a framed white box at `position`.
fn legend<'a, DB, CT>(
    chart: &mut ChartContext<'a, DB, CT>,
    position: SeriesLabelPosition,
) -> std::result::Result<(), DrawingAreaErrorKind<DB::ErrorType>>
where
    DB: DrawingBackend + 'a,
    CT: CoordTranslate,
{
    chart
        .configure_series_labels()
        .position(position)
        .label_font(("sans-serif", 13))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()
}

/// Draws `table` to a PNG: frames a second (log scale) against processors,
/// one line per pitch, Cohen-Or's PVS figures beside ours as lighter lines
/// of the same colors.
pub fn draw_table(path: &Path, table: &Table) -> Result<()> {
    font()?;
    let failed = |e: &dyn std::fmt::Display| {
        Error::new(format!("cannot draw the chart {}: {e}", path.display()))
    };
    let root = BitMapBackend::new(path, (800, 560)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| failed(&e))?;
    let mut all: Vec<f64> = table.fps.iter().flatten().copied().collect();
    all.extend(COHEN_OR_TABLE_1.iter().flatten());
    let lo = all.iter().copied().fold(f64::MAX, f64::min).max(1e-3) * 0.7;
    let hi = all.iter().copied().fold(0.0, f64::max).max(lo * 2.0) * 1.4;
    let max_p = f64::from(*table.processors.iter().max().unwrap_or(&32)) + 2.0;
    let mut chart = ChartBuilder::on(&root)
        .caption(
            "Frames a second by processors (simulated, and Cohen-Or's PVS)",
            ("sans-serif", 20),
        )
        .margin(15)
        .x_label_area_size(45)
        .y_label_area_size(60)
        .build_cartesian_2d(0f64..max_p, (lo..hi).log_scale())
        .map_err(|e| failed(&e))?;
    chart
        .configure_mesh()
        .x_desc("processors (one of them the master)")
        .x_label_formatter(&|v| format!("{v:.0}"))
        .y_desc("frames a second")
        .label_style(("sans-serif", 14))
        .draw()
        .map_err(|e| failed(&e))?;
    let colors = [RED, BLUE, GREEN, MAGENTA, CYAN];
    for (row, (fps, pitch)) in table.fps.iter().zip(&table.pitch).enumerate() {
        let color = colors[row % colors.len()];
        let ours: Vec<(f64, f64)> = table
            .processors
            .iter()
            .zip(fps)
            .map(|(&p, &f)| (f64::from(p), f.max(lo)))
            .collect();
        chart
            .draw_series(LineSeries::new(ours.clone(), color.stroke_width(2)))
            .map_err(|e| failed(&e))?
            .label(format!("terracast, pitch {pitch}°"))
            .legend(move |(x, y)| PathElement::new([(x, y), (x + 20, y)], color.stroke_width(2)));
        chart
            .draw_series(ours.iter().map(|&p| Circle::new(p, 4, color.filled())))
            .map_err(|e| failed(&e))?;
        if let Some(i) = TABLE_PITCH.iter().position(|p| p == pitch) {
            let theirs: Vec<(f64, f64)> = TABLE_PROCESSORS
                .iter()
                .zip(COHEN_OR_TABLE_1[i])
                .map(|(&p, f)| (f64::from(p), f))
                .collect();
            let light = color.mix(0.4);
            chart
                .draw_series(LineSeries::new(theirs, light.stroke_width(2)))
                .map_err(|e| failed(&e))?
                .label(format!("Cohen-Or PVS, pitch {pitch}°"))
                .legend(move |(x, y)| {
                    PathElement::new([(x, y), (x + 20, y)], light.stroke_width(2))
                });
        }
    }
    legend(&mut chart, SeriesLabelPosition::UpperLeft).map_err(|e| failed(&e))?;
    root.present().map_err(|e| failed(&e))?;
    Ok(())
}

/// Draws the bench summary to a PNG: mean PSNR against Mpx/s (log scale),
/// a point per setting, the Pareto front joined by a line.
pub fn draw_bench(path: &Path, summaries: &[Summary]) -> Result<()> {
    font()?;
    let failed = |e: &dyn std::fmt::Display| {
        Error::new(format!("cannot draw the chart {}: {e}", path.display()))
    };
    let root = BitMapBackend::new(path, (900, 600)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| failed(&e))?;
    let speeds = summaries.iter().map(|s| s.mpx_per_s);
    let lo_x = speeds.clone().fold(f64::MAX, f64::min).max(1e-3) / 2.0;
    let hi_x = speeds.fold(0.0, f64::max).max(lo_x * 4.0) * 4.0;
    let qualities = summaries.iter().map(|s| s.psnr);
    let lo_y = qualities.clone().fold(f64::MAX, f64::min) - 2.0;
    let hi_y = qualities.fold(f64::MIN, f64::max) + 2.0;
    let mut chart = ChartBuilder::on(&root)
        .caption(
            "Speed against accuracy (bench suite, single thread)",
            ("sans-serif", 20),
        )
        .margin(15)
        .x_label_area_size(45)
        .y_label_area_size(60)
        .build_cartesian_2d((lo_x..hi_x).log_scale(), lo_y..hi_y)
        .map_err(|e| failed(&e))?;
    chart
        .configure_mesh()
        .x_desc("Mpx/s (one thread)")
        .y_desc("mean PSNR against the reference, dB")
        .label_style(("sans-serif", 14))
        .draw()
        .map_err(|e| failed(&e))?;
    let mut front: Vec<(f64, f64)> = summaries
        .iter()
        .filter(|s| s.pareto)
        .map(|s| (s.mpx_per_s, s.psnr))
        .collect();
    front.sort_by(|a, b| a.0.total_cmp(&b.0));
    chart
        .draw_series(LineSeries::new(front, BLACK.mix(0.5).stroke_width(2)))
        .map_err(|e| failed(&e))?
        .label("Pareto front")
        .legend(|(x, y)| PathElement::new([(x, y), (x + 20, y)], BLACK.mix(0.5).stroke_width(2)));
    // Label boxes already drawn, in pixels: a label moves down or up in
    // steps of its height until it overlaps none (the kernel's settings
    // crowd around one speed).
    let mut taken: Vec<(i32, i32, i32, i32)> = Vec::new();
    for s in summaries {
        let color = if s.setting.starts_with("kernel") {
            RED
        } else if s.setting.starts_with("voxelspace") {
            BLUE
        } else {
            GREEN
        };
        let point = (s.mpx_per_s, s.psnr);
        chart
            .draw_series([Circle::new(point, 5, color.filled())])
            .map_err(|e| failed(&e))?;
        let (px, py) = chart.backend_coord(&point);
        let (width, height) = (7 * s.setting.chars().count() as i32, 14);
        let free = |dy: i32| {
            let (x0, y0) = (px + 8, py + dy);
            !taken
                .iter()
                .any(|&(a0, b0, a1, b1)| x0 < a1 && a0 < x0 + width && y0 < b1 && b0 < y0 + height)
        };
        // Centred on the point, then one label height up, one down, two
        // up, two down, and so on (pixel y grows downward).
        let shifts = (0..12).map(|k: i32| if k % 2 == 0 { k / 2 } else { -(k + 1) / 2 });
        let offset = shifts
            .map(|shift| -height / 2 + shift * height)
            .find(|&dy| free(dy))
            .unwrap_or(-height / 2);
        taken.push((px + 8, py + offset, px + 8 + width, py + offset + height));
        chart
            .draw_series([EmptyElement::at(point)
                + Text::new(
                    s.setting.to_string(),
                    (8, offset),
                    ("sans-serif", 13).into_font(),
                )])
            .map_err(|e| failed(&e))?;
    }
    legend(&mut chart, SeriesLabelPosition::LowerRight).map_err(|e| failed(&e))?;
    root.present().map_err(|e| failed(&e))?;
    Ok(())
}
