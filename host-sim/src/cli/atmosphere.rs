//! `--atmosphere`, `--fog`, `--sun` and `--relief`: the sky, sun, fog and
//! relief shading that `render`, `fly` and `view` share.

use super::values::{number, positive};
use crate::error::{Error, Result};
use crate::scene::Scene;
use terracast::{Atmosphere, PreparedAtmosphere, Relief};

/// Sky, sun, fog and relief shading.
#[derive(Debug, Clone, clap::Args)]
pub(super) struct AtmosphereArgs {
    /// Sky gradient, sun and fog [default: on for `fly` and `view`, off for
    /// `render`, which --fog or --sun turn on].
    #[arg(long, value_enum, value_name = "on|off")]
    atmosphere: Option<Switch>,
    /// Fog: the distance in voxels at which the ground layer's fog leaves
    /// 2 % of a color, or `off` [default: 2500].
    #[arg(long, value_name = "V|off", value_parser = fog_visibility)]
    fog: Option<Visibility>,
    /// Top of the fog's ground layer, voxels.
    #[arg(long, default_value_t = 30.0, value_name = "H",
          value_parser = number(0.0f32, 16000.0), allow_hyphen_values = true)]
    fog_ceiling: f32,
    /// Height over which the fog thins by half above its ceiling, voxels,
    /// or `none` for uniform fog (which hides the sky too).
    #[arg(long, default_value = "45", value_name = "H|none", value_parser = fog_halving)]
    fog_halving: Halving,
    /// The sun: azimuth (from +x toward +y) and elevation, degrees; it
    /// lights the sky and the relief shading [default: 225,35].
    #[arg(long, value_name = "AZ,EL", value_parser = sun, allow_hyphen_values = true)]
    sun: Option<[f32; 2]>,
    /// Relief shading baked into the colors: `off`, `slopes`, or `shadows`
    /// (slopes and cast shadows) [default: with the atmosphere, shadows on
    /// terrain colored by height, off over a photo].
    #[arg(long, value_enum, value_name = "off|slopes|shadows")]
    relief: Option<ReliefArg>,
}

/// A setting that is on or off.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub(super) enum Switch {
    On,
    Off,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
enum ReliefArg {
    Off,
    Slopes,
    Shadows,
}

/// `--fog`: a visibility, or none (no fog).
#[derive(Debug, Clone, Copy, PartialEq)]
struct Visibility(Option<f32>);

/// `--fog-halving`: a height, or none (uniform fog).
#[derive(Debug, Clone, Copy, PartialEq)]
struct Halving(Option<f32>);

/// The ambient share of the relief shading's light.
const AMBIENT: f32 = 0.35;

fn fog_visibility(text: &str) -> std::result::Result<Visibility, String> {
    if text.trim() == "off" {
        return Ok(Visibility(None));
    }
    number(8.0f32, 1e7)(text).map(|v| Visibility(Some(v)))
}

fn fog_halving(text: &str) -> std::result::Result<Halving, String> {
    if text.trim() == "none" {
        return Ok(Halving(None));
    }
    positive(0.0f32, 1e6)(text).map(|h| Halving(Some(h)))
}

fn sun(text: &str) -> std::result::Result<[f32; 2], String> {
    let (azimuth, elevation) = text
        .split_once(',')
        .ok_or_else(|| format!("expected AZ,EL, got '{text}'"))?;
    let azimuth = number(-360.0f32, 360.0)(azimuth).map_err(|e| format!("azimuth {e}"))?;
    let elevation = positive(0.0f32, 90.0)(elevation).map_err(|e| format!("elevation {e}"))?;
    Ok([azimuth, elevation])
}

impl AtmosphereArgs {
    /// Whether the sky, sun and fog are on, `default` when not said.
    fn on(&self, default: bool) -> bool {
        match self.atmosphere {
            Some(switch) => switch == Switch::On,
            None => default || self.fog.is_some() || self.sun.is_some(),
        }
    }

    /// The sky, sun and fog asked for (none when off).
    pub(super) fn atmosphere(&self, default: bool) -> Option<Atmosphere> {
        self.on(default).then(|| self.settings())
    }

    /// The sky, sun and fog these flags describe, on or off.
    fn settings(&self) -> Atmosphere {
        let flight = Atmosphere::FLIGHT;
        let sun = flight.sun.map(|sun| match self.sun {
            Some([azimuth_deg, elevation_deg]) => terracast::Sun {
                azimuth_deg,
                elevation_deg,
                ..sun
            },
            None => sun,
        });
        let fog = match self.fog {
            Some(Visibility(None)) => None,
            visibility => flight.fog.map(|fog| terracast::Fog {
                visibility: visibility.and_then(|v| v.0).unwrap_or(fog.visibility),
                ceiling: self.fog_ceiling,
                halving: self.fog_halving.0,
                ..fog
            }),
        };
        Atmosphere { sun, fog, ..flight }
    }

    /// [`AtmosphereArgs::settings`] in fixed point, for a window that
    /// turns them on and off.
    #[cfg(feature = "window")]
    pub(super) fn prepared_settings(&self) -> Result<PreparedAtmosphere> {
        self.settings()
            .prepare()
            .map_err(|e| Error::new(e.to_string()))
    }

    /// [`AtmosphereArgs::atmosphere`] in fixed point, for the kernel.
    pub(super) fn prepared(&self, default: bool) -> Result<Option<PreparedAtmosphere>> {
        self.atmosphere(default)
            .map(|air| air.prepare().map_err(|e| Error::new(e.to_string())))
            .transpose()
    }

    /// The relief shading asked for: `default_on` with the atmosphere,
    /// shadows unless the scene has a photo.
    pub(super) fn relief(&self, default: bool, photo: bool) -> Option<Relief> {
        let chosen = self.relief.unwrap_or(if self.on(default) && !photo {
            ReliefArg::Shadows
        } else {
            ReliefArg::Off
        });
        let [azimuth, elevation] = self.sun.unwrap_or_else(|| {
            let sun = Atmosphere::FLIGHT.sun.expect("the flight has a sun");
            [sun.azimuth_deg, sun.elevation_deg]
        });
        (chosen != ReliefArg::Off).then_some(Relief {
            sun_azimuth_deg: azimuth,
            sun_elevation_deg: elevation,
            ambient: AMBIENT,
            shadows: chosen == ReliefArg::Shadows,
        })
    }

    /// Shades `scene` as asked (saying how many points lie in shadow);
    /// `photo`: whether its colors are a photo.
    pub(super) fn shade(&self, scene: &mut Scene, default: bool, photo: bool) -> Result<()> {
        if let Some(relief) = self.relief(default, photo) {
            let started = std::time::Instant::now();
            let shadowed = crate::atmosphere::shade_scene(scene, &relief)?;
            let seconds = started.elapsed().as_secs_f64();
            if relief.shadows {
                let share = shadowed as f64 / scene.heights.len().max(1) as f64;
                // Progress, not a warning: standard output, so that an
                // error after it is still the one line on standard error.
                println!(
                    "relief shading: {shadowed} of {} points in shadow ({:.1} %), {seconds:.2} s",
                    scene.heights.len(),
                    100.0 * share
                );
            }
        }
        Ok(())
    }

    /// The flags that ask for exactly these settings, with the sky, sun
    /// and fog `on` or off whatever the flags say and the relief as
    /// resolved for a command whose default is `default`, on a scene with
    /// or without a `photo`: for a `render` command line that draws the
    /// same frame.
    #[cfg(any(feature = "window", test))]
    pub(super) fn arguments(&self, on: bool, default: bool, photo: bool) -> Vec<String> {
        let mut flags = Vec::new();
        match on.then(|| self.settings()) {
            None => flags.push("--atmosphere=off".to_string()),
            Some(air) => {
                flags.push("--atmosphere=on".to_string());
                flags.push(match air.fog {
                    Some(fog) => format!("--fog={}", fog.visibility),
                    None => "--fog=off".to_string(),
                });
                flags.push(format!("--fog-ceiling={}", self.fog_ceiling));
                flags.push(match self.fog_halving.0 {
                    Some(h) => format!("--fog-halving={h}"),
                    None => "--fog-halving=none".to_string(),
                });
            }
        }
        let relief = self.relief(default, photo);
        if let Some([azimuth, elevation]) = self.sun {
            flags.push(format!("--sun={azimuth},{elevation}"));
        }
        flags.push(format!(
            "--relief={}",
            match relief {
                None => "off",
                Some(r) if r.shadows => "shadows",
                Some(_) => "slopes",
            }
        ));
        flags
    }

    /// Refuses relief shading asked for on a terrain that is not in
    /// memory (a tiled one).
    pub(super) fn check_tiled(&self) -> Result<()> {
        match self.relief {
            Some(ReliefArg::Slopes | ReliefArg::Shadows) => Err(Error::new(
                "--relief needs a terrain in memory (not --terrain): pack shaded colors instead",
            )),
            _ => Ok(()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Parser;

    #[derive(Debug, clap::Parser)]
    struct Line {
        #[command(flatten)]
        air: AtmosphereArgs,
    }

    fn parse(args: &[&str]) -> std::result::Result<AtmosphereArgs, String> {
        Line::try_parse_from(std::iter::once("t").chain(args.iter().copied()))
            .map(|l| l.air)
            .map_err(|e| e.to_string())
    }

    #[test]
    fn defaults_follow_the_command_and_flags_turn_it_on() {
        let none = parse(&[]).unwrap();
        assert_eq!(none.atmosphere(false), None);
        assert_eq!(none.atmosphere(true), Some(Atmosphere::FLIGHT));
        assert!(none.relief(true, false).is_some_and(|r| r.shadows));
        assert_eq!(none.relief(true, true), None);
        assert_eq!(none.relief(false, false), None);
        let fog = parse(&["--fog", "300"]).unwrap();
        assert_eq!(
            fog.atmosphere(false).unwrap().fog.unwrap().visibility,
            300.0
        );
        let off = parse(&["--atmosphere", "off", "--fog", "300"]).unwrap();
        assert_eq!(off.atmosphere(true), None);
        let no_fog = parse(&["--fog", "off"]).unwrap();
        assert!(no_fog.atmosphere(false).is_some_and(|a| a.fog.is_none()));
        let uniform = parse(&["--fog-halving", "none", "--atmosphere", "on"]).unwrap();
        assert_eq!(
            uniform.atmosphere(false).unwrap().fog.unwrap().halving,
            None
        );
        let sun = parse(&["--sun", "90,20", "--relief", "slopes"]).unwrap();
        let relief = sun.relief(false, true).unwrap();
        assert_eq!((relief.sun_azimuth_deg, relief.shadows), (90.0, false));
    }

    #[test]
    fn arguments_ask_for_the_same_settings_again() {
        for (line, default, photo) in [
            (vec![], true, false),
            (vec![], false, false),
            (vec!["--fog", "off", "--sun", "10,50"], true, true),
            (
                vec!["--fog-halving", "none", "--relief", "slopes"],
                false,
                false,
            ),
        ] {
            let first = parse(&line).unwrap();
            let flags = first.arguments(first.on(default), default, photo);
            let again = parse(&flags.iter().map(String::as_str).collect::<Vec<_>>()).unwrap();
            // The render command's default is off: the flags must not need it.
            assert_eq!(
                again.atmosphere(false),
                first.atmosphere(default),
                "{line:?}"
            );
            assert_eq!(
                again.relief(false, photo),
                first.relief(default, photo),
                "{line:?}"
            );
        }
    }

    #[test]
    fn bad_values_name_the_problem() {
        assert!(parse(&["--fog", "2"]).unwrap_err().contains("--fog"));
        assert!(parse(&["--sun", "90"]).unwrap_err().contains("AZ,EL"));
        assert!(parse(&["--sun", "90,-5"])
            .unwrap_err()
            .contains("elevation"));
        assert!(parse(&["--fog-halving", "0"])
            .unwrap_err()
            .contains("--fog-halving"));
        assert!(parse(&["--relief", "maybe"]).is_err());
    }
}
