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

/// Draws a chart of `size` pixels with `draw` into an RGB buffer and
/// writes it to `path` as a PNG (with the host's own PNG encoder:
/// plotters' file backend would pull a second version of `image` into
/// the build).
fn png_chart(
    path: &Path,
    size: (u32, u32),
    draw: impl FnOnce(DrawingArea<BitMapBackend<'_>, plotters::coord::Shift>) -> Result<()>,
) -> Result<()> {
    let mut rgb = vec![0u8; size.0 as usize * size.1 as usize * 3];
    draw(BitMapBackend::with_buffer(&mut rgb, size).into_drawing_area())?;
    image::save_buffer(path, &rgb, size.0, size.1, image::ExtendedColorType::Rgb8)
        .map_err(|e| Error::new(format!("cannot write the chart {}: {e}", path.display())))
}

/// Draws `table` to a PNG: frames a second (log scale) against processors,
/// one line per pitch, Cohen-Or's PVS figures beside ours as lighter lines
/// of the same colors.
pub fn draw_table(path: &Path, table: &Table) -> Result<()> {
    font()?;
    let failed = |e: &dyn std::fmt::Display| {
        Error::new(format!("cannot draw the chart {}: {e}", path.display()))
    };
    png_chart(path, (800, 560), |root| {
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
                .legend(move |(x, y)| {
                    PathElement::new([(x, y), (x + 20, y)], color.stroke_width(2))
                });
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
    })
}

/// How far right of its point a label beside it begins, pixels.
const LABEL_GAP: i32 = 8;
/// How far right of its point a label moved up or down begins, pixels: far
/// enough for the line back to the point to show.
const LEADER: i32 = 36;
/// A label's height, pixels.
const LABEL_HEIGHT: i32 = 14;

/// Where a point's label goes ([`place_labels`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct LabelPlace {
    /// The label box's top left corner, pixels from the point.
    at: (i32, i32),
    /// For a label moved up or down, the near end of the line that ties
    /// it to its point (pixels from the point); `None` beside it.
    leader: Option<(i32, i32)>,
}

/// Where each point's label goes, as pixels from the point (its box's top
/// left corner): beside it on the right, centred; else farther right, one
/// label height up, one down, two up, two down and so on; then the same
/// on the left. The first place where it lies inside `area` (the plot:
/// left, top, right, bottom) and covers no point and no label placed
/// before it wins (beside it on the right, covering, when none is free).
/// `sizes` are the labels' boxes; a point covers 10 pixels a side.
fn place_labels(
    points: &[(i32, i32)],
    sizes: &[(i32, i32)],
    area: (i32, i32, i32, i32),
) -> Vec<LabelPlace> {
    let mut taken: Vec<(i32, i32, i32, i32)> = points
        .iter()
        .map(|&(x, y)| (x - 5, y - 5, x + 5, y + 5))
        .collect();
    let inside =
        |b: (i32, i32, i32, i32)| b.0 >= area.0 && b.1 >= area.1 && b.2 <= area.2 && b.3 <= area.3;
    points
        .iter()
        .zip(sizes)
        .map(|(&(px, py), &(width, height))| {
            let label_at =
                |(dx, dy): (i32, i32)| (px + dx, py + dy, px + dx + width, py + dy + height);
            let free = |place: &LabelPlace| {
                let label = label_at(place.at);
                inside(label) && !taken.iter().any(|&t| overlap(label, t))
            };
            // Pixel y grows downward: -1, 1, -2, 2, ...
            let shifts = || (1..16).map(|k: i32| if k % 2 == 0 { k / 2 } else { -(k + 1) / 2 });
            // Beside the point at `gap`, else moved up or down at `moved`,
            // tied by a line to the label's end `near_end` across from it.
            let beside = |gap: i32| LabelPlace {
                at: (gap, -height / 2),
                leader: None,
            };
            let side = |gap: i32, moved: i32, near_end: i32| {
                std::iter::once(beside(gap)).chain(shifts().map(move |shift| {
                    let dy = -height / 2 + shift * height;
                    LabelPlace {
                        at: (moved, dy),
                        leader: Some((near_end, dy + height / 2)),
                    }
                }))
            };
            let place = side(LABEL_GAP, LEADER, LEADER - 2)
                .chain(side(-LABEL_GAP - width, -LEADER - width, -LEADER + 2))
                .find(|place| free(place))
                .unwrap_or(beside(LABEL_GAP));
            taken.push(label_at(place.at));
            place
        })
        .collect()
}

/// Whether boxes `a` and `b` (left, top, right, bottom; pixels) overlap.
fn overlap(a: (i32, i32, i32, i32), b: (i32, i32, i32, i32)) -> bool {
    a.0 < b.2 && b.0 < a.2 && a.1 < b.3 && b.1 < a.3
}

/// Draws the bench summary to a PNG: mean PSNR against Mpx/s (log scale),
/// a point per setting, the Pareto front joined by a line.
pub fn draw_bench(path: &Path, summaries: &[Summary]) -> Result<()> {
    font()?;
    let failed = |e: &dyn std::fmt::Display| {
        Error::new(format!("cannot draw the chart {}: {e}", path.display()))
    };
    png_chart(path, (900, 600), |root| {
        root.fill(&WHITE).map_err(|e| failed(&e))?;
        let speeds = summaries.iter().map(|s| s.mpx_per_s);
        let lo_x = speeds.clone().fold(f64::MAX, f64::min).max(1e-3) / 2.0;
        // Room on the right for the fastest setting's label.
        let hi_x = speeds.fold(0.0, f64::max).max(lo_x * 4.0) * 8.0;
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
            .legend(|(x, y)| {
                PathElement::new([(x, y), (x + 20, y)], BLACK.mix(0.5).stroke_width(2))
            });
        let color_of = |setting: &str| {
            if setting.starts_with("kernel") {
                RED
            } else if setting.starts_with("voxelspace") {
                BLUE
            } else if setting.starts_with("march") {
                GREEN
            } else {
                MAGENTA
            }
        };
        let points: Vec<(i32, i32)> = summaries
            .iter()
            .map(|s| chart.backend_coord(&(s.mpx_per_s, s.psnr)))
            .collect();
        let sizes: Vec<(i32, i32)> = summaries
            .iter()
            .map(|s| (7 * s.setting.chars().count() as i32, LABEL_HEIGHT))
            .collect();
        let (across, down) = chart.plotting_area().get_pixel_range();
        let area = (across.start, down.start, across.end, down.end);
        let places = place_labels(&points, &sizes, area);
        for (s, place) in summaries.iter().zip(places) {
            let point = (s.mpx_per_s, s.psnr);
            // A label moved up or down is tied to its point by a thin
            // line, to the near end of the label.
            let leader = place.leader.map_or(Vec::new(), |end| vec![(0, 0), end]);
            chart
                .draw_series([EmptyElement::at(point)
                    + Circle::new((0, 0), 5, color_of(s.setting).filled())
                    + PathElement::new(leader, color_of(s.setting).mix(0.6))
                    + Text::new(
                        s.setting.to_string(),
                        place.at,
                        ("sans-serif", 13).into_font(),
                    )])
                .map_err(|e| failed(&e))?;
        }
        // The upper right is empty: speed and accuracy trade against each
        // other, so no setting is both fast and accurate.
        legend(&mut chart, SeriesLabelPosition::UpperRight).map_err(|e| failed(&e))?;
        root.present().map_err(|e| failed(&e))?;
        Ok(())
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The bench's kernel settings crowd around one speed: their labels
    /// must still cover no point and no other label, and a lone point's
    /// label sits beside it.
    #[test]
    fn crowded_labels_cover_no_point_and_no_other_label() {
        let mut points = vec![(300, 200), (302, 203), (304, 206), (301, 210), (303, 214)];
        points.push((600, 400));
        let sizes = vec![(180, LABEL_HEIGHT); points.len()];
        let places = place_labels(&points, &sizes, (0, 0, 900, 600));
        let boxes: Vec<_> = points
            .iter()
            .zip(&places)
            .zip(&sizes)
            .map(|((&(x, y), place), &(w, h))| {
                let (dx, dy) = place.at;
                (x + dx, y + dy, x + dx + w, y + dy + h)
            })
            .collect();
        for (i, a) in boxes.iter().enumerate() {
            for &(x, y) in &points {
                assert!(
                    !overlap(*a, (x - 5, y - 5, x + 5, y + 5)),
                    "label {i} covers ({x}, {y})"
                );
            }
            for (j, b) in boxes.iter().enumerate().skip(i + 1) {
                assert!(!overlap(*a, *b), "labels {i} and {j} overlap");
            }
        }
        // The lone point's label is beside it; in the crowd, labels moved.
        assert_eq!(
            places[5],
            LabelPlace {
                at: (LABEL_GAP, -LABEL_HEIGHT / 2),
                leader: None
            }
        );
        // A moved label's line runs to its left end, two pixels short.
        let moved: Vec<_> = places[..5].iter().filter(|p| p.at.0 == LEADER).collect();
        assert!(moved.len() >= 4, "{places:?}");
        for place in moved {
            assert_eq!(
                place.leader,
                Some((LEADER - 2, place.at.1 + LABEL_HEIGHT / 2))
            );
        }
    }

    /// A point near the plot's right edge (the fastest settings) takes
    /// its label on its left, and a crowd there stays inside the plot.
    #[test]
    fn labels_stay_inside_the_plot() {
        let area = (60, 40, 880, 560);
        let points = vec![(800, 300), (802, 304), (804, 308), (300, 100)];
        let sizes = vec![(240, LABEL_HEIGHT); points.len()];
        let places = place_labels(&points, &sizes, area);
        for (i, ((&(x, y), place), &(w, h))) in points.iter().zip(&places).zip(&sizes).enumerate() {
            let (dx, dy) = place.at;
            let label = (x + dx, y + dy, x + dx + w, y + dy + h);
            assert!(
                label.0 >= area.0 && label.2 <= area.2 && label.1 >= area.1 && label.3 <= area.3,
                "label {i} at {label:?} leaves the plot"
            );
        }
        assert_eq!(places[0].at, (-LABEL_GAP - 240, -LABEL_HEIGHT / 2));
        assert_eq!(places[3].at, (LABEL_GAP, -LABEL_HEIGHT / 2));
        // Moved on the left, a label's line runs to its right end.
        for place in &places[1..3] {
            assert_eq!(place.at.0, -LEADER - 240, "{places:?}");
            assert_eq!(
                place.leader,
                Some((-LEADER + 2, place.at.1 + LABEL_HEIGHT / 2))
            );
        }
    }
}
