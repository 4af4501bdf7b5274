//! Where terrain renderers are known to fail: each method at each such
//! condition, checked for panics and garbage and scored against the exact
//! reference. A method that fails a condition is reported as failing.
//!
//! A render **fails** a condition when it panics, when a depth is NaN, when
//! it disagrees with the reference about sky or terrain on more than a
//! tenth of the pixels, or when its PSNR is below 15 dB or its SSIM below
//! [`MIN_SSIM`] (a picture no longer of the same view). The kernel may also refuse a camera with an
//! error; that is reported as refused, not failed.

use crate::baselines::{march, voxel_space, MarchOptions, VoxelSpaceOptions};
use crate::error::Result;
use crate::frame::Frame;
use crate::kernel::render_kernel;
use crate::metrics::{psnr, sky_agreement, ssim};
use crate::reference::{Reference, ReferenceOptions};
use crate::scene::{color_by_height_and_slope, procedural, Scene};
use crate::volume::{render_volume, Mode, TerrainVolume, VolumeOptions};
use std::fmt::Write as _;
use terracast::{Camera, RenderOptions};

/// One condition: a scene and a camera.
#[derive(Debug)]
pub struct Condition {
    /// What is hard about it.
    pub name: &'static str,
    /// The terrain.
    pub scene: Scene,
    /// The view.
    pub camera: Camera,
}

fn camera(eye: [f32; 3], yaw: f32, pitch: f32, hfov: f32) -> Camera {
    Camera {
        hfov_deg: hfov,
        ..Camera::looking(eye, yaw, pitch)
    }
}

fn rolled(camera: Camera, roll: f32) -> Camera {
    Camera {
        roll_deg: roll,
        ..camera
    }
}

/// A scene whose heights come from `height(x, y)`, colored by height and
/// slope.
fn synthetic(width: u32, depth: u32, height: impl Fn(u32, u32) -> f32) -> Result<Scene> {
    let heights: Vec<f32> = (0..depth)
        .flat_map(|y| (0..width).map(move |x| (x, y)))
        .map(|(x, y)| height(x, y))
        .collect();
    let colors = color_by_height_and_slope(width, depth, &heights, 3);
    Scene::new(width, depth, heights, colors)
}

/// Every condition of the suite.
pub fn conditions() -> Result<Vec<Condition>> {
    let hills = procedural(256, 11);
    let top = hills.max_height();
    let ground = |x: f32, y: f32| hills.height(x as usize, y as usize);
    let mut out = vec![
        Condition {
            name: "wide field of view 90°",
            camera: camera([128.0, 20.0, top + 20.0], 90.0, 15.0, 90.0),
            scene: hills.clone(),
        },
        Condition {
            name: "wide field of view 120°",
            camera: camera([128.0, 20.0, top + 20.0], 90.0, 15.0, 120.0),
            scene: hills.clone(),
        },
        Condition {
            name: "steep pitch 80°",
            camera: camera([128.0, 128.0, top + 60.0], 90.0, 80.0, 60.0),
            scene: hills.clone(),
        },
        Condition {
            name: "steep pitch 90°",
            camera: camera([128.0, 128.0, top + 60.0], 90.0, 90.0, 60.0),
            scene: hills.clone(),
        },
        Condition {
            name: "grazing, pitch 0°, eye 2 above the ground",
            camera: camera([40.0, 40.0, ground(40.0, 40.0) + 2.0], 45.0, 0.0, 60.0),
            scene: hills.clone(),
        },
        Condition {
            name: "grazing, pitch 2°",
            camera: camera([40.0, 40.0, ground(40.0, 40.0) + 5.0], 45.0, 2.0, 60.0),
            scene: hills.clone(),
        },
        Condition {
            name: "roll 30°, pitch 15°",
            camera: rolled(camera([128.0, 20.0, top + 20.0], 90.0, 15.0, 60.0), 30.0),
            scene: hills.clone(),
        },
        Condition {
            name: "roll 45°, level (pitch 0°)",
            camera: rolled(camera([128.0, 20.0, top + 10.0], 90.0, 0.0, 60.0), 45.0),
            scene: hills.clone(),
        },
        Condition {
            name: "roll 90°, pitch 10°",
            camera: rolled(camera([128.0, 20.0, top + 20.0], 90.0, 10.0, 60.0), 90.0),
            scene: hills.clone(),
        },
        Condition {
            name: "roll 180° (upside down), pitch 10°",
            camera: rolled(camera([128.0, 20.0, top + 20.0], 90.0, 10.0, 60.0), 180.0),
            scene: hills.clone(),
        },
        Condition {
            name: "eye below the surface",
            camera: camera([128.0, 128.0, ground(128.0, 128.0) - 5.0], 90.0, 10.0, 60.0),
            scene: hills.clone(),
        },
        Condition {
            name: "eye outside the map looking in",
            camera: camera([-150.0, 128.0, top + 30.0], 0.0, 10.0, 60.0),
            scene: hills.clone(),
        },
    ];
    // A long strip so that the eye can be 30000 voxels from the origin.
    let strip = synthetic(32_000, 32, |x, y| {
        20.0 + 10.0 * ((x as f32) * 0.05).sin() + 5.0 * ((y as f32) * 0.3).cos()
    })?;
    out.push(Condition {
        name: "far coordinates, eye at x = 30000",
        camera: camera([30_000.0, 16.0, 60.0], 180.0, 10.0, 60.0),
        scene: strip,
    });
    out.push(Condition {
        name: "cliff, a 220-voxel step",
        camera: camera([20.0, 64.0, 120.0], 0.0, 10.0, 60.0),
        scene: synthetic(128, 128, |x, _| if x < 64 { 10.0 } else { 230.0 })?,
    });
    out.push(Condition {
        name: "one-voxel ridges",
        camera: camera([64.0, 5.0, 40.0], 90.0, 12.0, 60.0),
        scene: synthetic(128, 128, |x, _| if x % 8 == 0 { 30.0 } else { 5.0 })?,
    });
    Ok(out)
}

/// Below this SSIM against the reference a render is not a picture of the
/// same view, whatever its PSNR (terrain colors alike in the mean can keep
/// PSNR up in a wrong picture).
pub const MIN_SSIM: f64 = 0.3;

/// The methods of the suite.
pub const METHODS: [&str; 5] = ["kernel", "voxelspace", "march 0.5", "volume", "boundary"];

/// A method at a condition.
#[derive(Debug, Clone, PartialEq)]
pub struct Outcome {
    /// Condition name.
    pub condition: &'static str,
    /// Method name.
    pub method: &'static str,
    /// What happened.
    pub verdict: Verdict,
    /// PSNR against the reference (when it rendered).
    pub psnr: Option<f64>,
    /// Sky agreement with the reference (when it rendered).
    pub sky_agreement: Option<f64>,
    /// SSIM against the reference (when it rendered).
    pub ssim: Option<f64>,
}

/// The verdict on one render.
#[derive(Debug, Clone, PartialEq)]
pub enum Verdict {
    /// Rendered a picture of the view.
    Passes,
    /// Refused the camera with this error.
    Refused(String),
    /// Failed: why.
    Fails(String),
}

fn render(method: &str, scene: &Scene, camera: &Camera, size: (u32, u32)) -> Result<Frame> {
    let sky = terracast::config::DEFAULT_SKY;
    Ok(match method {
        "kernel" => {
            render_kernel(
                &scene.to_kernel()?,
                camera,
                size.0,
                size.1,
                &RenderOptions::default(),
            )?
            .0
        }
        "volume" | "boundary" => {
            let options = VolumeOptions::default();
            let volume = TerrainVolume::build(scene, &options);
            let mode = if method == "volume" {
                Mode::Accurate
            } else {
                Mode::Approximate
            };
            render_volume(scene, &volume, camera, size, &options, mode).0
        }
        "voxelspace" => {
            let options = VoxelSpaceOptions {
                spacing_growth: 0.005,
                sky,
            };
            voxel_space(scene, camera, size.0, size.1, &options).0
        }
        _ => {
            march(
                scene,
                camera,
                size.0,
                size.1,
                &MarchOptions { step: 0.5, sky },
            )
            .0
        }
    })
}

/// Runs every method at every condition.
pub fn run(size: (u32, u32), mut progress: impl FnMut(usize, usize)) -> Result<Vec<Outcome>> {
    let conditions = conditions()?;
    let mut outcomes = Vec::new();
    for (done, condition) in conditions.iter().enumerate() {
        let options = ReferenceOptions {
            supersample: 2,
            sky: terracast::config::DEFAULT_SKY,
            ..ReferenceOptions::default()
        };
        let (exact, _) =
            Reference::new(&condition.scene).render(&condition.camera, size.0, size.1, &options);
        for method in METHODS {
            if method == "voxelspace" && condition.camera.roll_deg != 0.0 {
                // Its columns stay vertical: it renders the level view.
                outcomes.push(Outcome {
                    condition: condition.name,
                    method,
                    verdict: Verdict::Fails("cannot roll".into()),
                    psnr: None,
                    sky_agreement: None,
                    ssim: None,
                });
                continue;
            }
            let rendered = std::panic::catch_unwind(|| {
                render(method, &condition.scene, &condition.camera, size)
            });
            let (verdict, psnr_db, agreement, structure) = match rendered {
                Err(_) => (Verdict::Fails("panicked".into()), None, None, None),
                Ok(Err(e)) => (Verdict::Refused(e.to_string()), None, None, None),
                Ok(Ok(frame)) => {
                    let db = psnr(&frame.colors, &exact.colors);
                    let agree = sky_agreement(&frame.depth, &exact.depth);
                    let structure = ssim(&frame.colors, &exact.colors, size.0, size.1);
                    let verdict = if frame.depth.iter().any(|d| d.is_nan()) {
                        Verdict::Fails("NaN depth".into())
                    } else if agree < 0.9 {
                        Verdict::Fails(format!(
                            "sky/terrain wrong on {:.0} % of pixels",
                            100.0 * (1.0 - agree)
                        ))
                    } else if db < 15.0 || structure.is_some_and(|s| s < MIN_SSIM) {
                        Verdict::Fails("not the same view".into())
                    } else {
                        Verdict::Passes
                    };
                    (verdict, Some(db), Some(agree), structure)
                }
            };
            outcomes.push(Outcome {
                condition: condition.name,
                method,
                verdict,
                psnr: psnr_db,
                sky_agreement: agreement,
                ssim: structure,
            });
        }
        progress(done + 1, conditions.len());
    }
    Ok(outcomes)
}

/// The outcomes as a Markdown table: a row per condition, a column per
/// method.
pub fn table(outcomes: &[Outcome]) -> String {
    let mut out = String::from("| condition |");
    for m in METHODS {
        let _ = write!(out, " {m} |");
    }
    out += "\n|---|";
    out += &"---|".repeat(METHODS.len());
    out.push('\n');
    let mut conditions: Vec<&str> = outcomes.iter().map(|o| o.condition).collect();
    conditions.dedup();
    for condition in conditions {
        let _ = write!(out, "| {condition} |");
        for method in METHODS {
            let cell = outcomes
                .iter()
                .find(|o| o.condition == condition && o.method == method)
                .map(|o| match (&o.verdict, o.psnr) {
                    (Verdict::Passes, Some(db)) => {
                        format!("{db:.1} dB, SSIM {:.2}", o.ssim.unwrap_or(f64::NAN))
                    }
                    (Verdict::Fails(why), Some(db)) => format!(
                        "**fails** ({why}; {db:.1} dB, SSIM {:.2})",
                        o.ssim.unwrap_or(f64::NAN)
                    ),
                    (Verdict::Fails(why), None) => format!("**fails** ({why})"),
                    (Verdict::Refused(why), _) => format!("refused: {why}"),
                    (Verdict::Passes, None) => "passes".into(),
                })
                .unwrap_or_default();
            let _ = write!(out, " {cell} |");
        }
        out.push('\n');
    }
    out
}
