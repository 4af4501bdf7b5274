//! A scene file: objects placed by name on any terrain.
//!
//! ```toml
//! # Objects sculpted from three views (paths beside this file).
//! [objects.barn]
//! front = "barn-front.png"
//! side = "barn-side.png"
//! top = "barn-top.png"
//! background = [255, 255, 255]   # besides transparent pixels; optional
//!
//! # Each placement: an object by name (the library's: conifer,
//! # broadleaf, house, vehicle; or one defined above), the grid point of
//! # its footprint's middle, a heading in degrees from +x toward +y
//! # (default 0) and a scale (default 1).
//! [[place]]
//! object = "barn"
//! at = [412, 380]
//! heading = 30
//! scale = 2
//! ```
//!
//! An object stands where it is put, whatever the ground (the seeded wood
//! and village keep to dry, gentle land); one that cannot be placed (off
//! the map, over another object, too high) is an error that names it.

use super::sculpt::Sculpture;
use super::{PlaceError, Planting, Shape};
use crate::error::{Error, Result};
use serde::Deserialize;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// The file as written.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct File {
    #[serde(default)]
    objects: BTreeMap<String, Sculpted>,
    #[serde(default)]
    place: Vec<Placement>,
}

/// An object sculpted from three views ([`Sculpture`]).
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct Sculpted {
    front: PathBuf,
    side: PathBuf,
    top: PathBuf,
    background: Option<[u8; 3]>,
}

/// One object placed.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct Placement {
    object: String,
    at: [f64; 2],
    #[serde(default)]
    heading: f64,
    #[serde(default = "unit_scale")]
    scale: f64,
}

fn unit_scale() -> f64 {
    1.0
}

/// The scales a placement may take.
const SCALES: std::ops::RangeInclusive<f64> = 0.25..=8.0;

/// A scene file read: each placement's object turned and scaled, ready to
/// stand on a terrain.
#[derive(Debug, Clone, PartialEq)]
pub struct ScenePlan {
    /// The file, for messages.
    name: String,
    /// What each placement puts where, with how it is named in messages.
    placements: Vec<(String, Shape, (i32, i32))>,
    /// Objects sculpted from views.
    pub sculpted: usize,
}

impl ScenePlan {
    /// Reads the scene file at `path`, the views of its sculpted objects
    /// (paths relative to the file) and carves them.
    pub fn read(path: &Path) -> Result<Self> {
        let name = path.display().to_string();
        let text = std::fs::read_to_string(path)
            .map_err(|e| Error::new(format!("cannot read scene file {name}: {e}")))?;
        Self::parse(&text, &name, path.parent().unwrap_or(Path::new(".")))
    }

    /// The views a scene file's sculpted objects are read from (none when
    /// it cannot be read or parsed: reading it reports that).
    pub fn view_paths(path: &Path) -> Vec<PathBuf> {
        let dir = path.parent().unwrap_or(Path::new("."));
        std::fs::read_to_string(path)
            .ok()
            .and_then(|text| toml::from_str::<File>(&text).ok())
            .map(|file| {
                file.objects
                    .values()
                    .flat_map(|s| [&s.front, &s.side, &s.top])
                    .map(|p| dir.join(p))
                    .collect()
            })
            .unwrap_or_default()
    }

    /// Parses scene file `text` (named `name` in messages), its views'
    /// paths relative to `dir`.
    pub fn parse(text: &str, name: &str, dir: &Path) -> Result<Self> {
        let file: File = toml::from_str(text).map_err(|e| {
            let line = e
                .span()
                .map(|span| text[..span.start].matches('\n').count() + 1);
            let at = line.map_or(String::new(), |line| format!(" (line {line})"));
            Error::new(format!("{name}{at}: {}", e.message().trim_end()))
        })?;
        let mut shapes = BTreeMap::new();
        for (object, sculpted) in &file.objects {
            if Shape::library(object).is_some() {
                return Err(Error::new(format!(
                    "{name}: object {object:?} is the library's; give a sculpted object another name"
                )));
            }
            let view = |path: &PathBuf| -> Result<image::RgbaImage> {
                let path = dir.join(path);
                image::open(&path)
                    .map(|image| image.to_rgba8())
                    .map_err(|e| {
                        Error::new(format!(
                            "{name}: object {object:?}: cannot read {}: {e}",
                            path.display()
                        ))
                    })
            };
            let (front, side, top) = (
                view(&sculpted.front)?,
                view(&sculpted.side)?,
                view(&sculpted.top)?,
            );
            let shape = Sculpture {
                front: &front,
                side: &side,
                top: &top,
                background: sculpted.background,
            }
            .carve()
            .map_err(|e| Error::new(format!("{name}: object {object:?}: {e}")))?;
            shapes.insert(object.clone(), shape);
        }
        let mut placements = Vec::with_capacity(file.place.len());
        for (number, place) in file.place.iter().enumerate() {
            let what = format!(
                "place {} ({} at {}, {})",
                number + 1,
                place.object,
                place.at[0],
                place.at[1]
            );
            let shape = match shapes.get(&place.object) {
                Some(shape) => shape.clone(),
                None => Shape::library(&place.object).ok_or_else(|| {
                    let mut known: Vec<&str> = Shape::LIBRARY.to_vec();
                    known.extend(shapes.keys().map(String::as_str));
                    Error::new(format!(
                        "{name}: {what}: no object {:?} (known: {})",
                        place.object,
                        known.join(", ")
                    ))
                })?,
            };
            if !SCALES.contains(&place.scale) {
                return Err(Error::new(format!(
                    "{name}: {what}: scale {} is outside {} to {}",
                    place.scale,
                    SCALES.start(),
                    SCALES.end()
                )));
            }
            if !(place.heading.is_finite() && place.at.iter().all(|a| a.abs() < 1e6)) {
                return Err(Error::new(format!(
                    "{name}: {what}: heading and position must be finite numbers"
                )));
            }
            if let Some(why) = shape.too_large_at(place.scale) {
                return Err(Error::new(format!("{name}: {what}: {why}")));
            }
            let at = (place.at[0].round() as i32, place.at[1].round() as i32);
            placements.push((what, shape.placed(place.heading, place.scale), at));
        }
        Ok(Self {
            name: name.to_owned(),
            placements,
            sculpted: shapes.len(),
        })
    }

    /// Objects the file places.
    pub fn len(&self) -> usize {
        self.placements.len()
    }

    /// Whether the file places nothing.
    pub fn is_empty(&self) -> bool {
        self.placements.is_empty()
    }

    /// Stands every object of the file on `planting`'s scene, in order;
    /// the first that cannot stand is an error naming it.
    pub fn place(&self, planting: &mut Planting<'_>) -> Result<()> {
        for (what, shape, at) in &self.placements {
            planting
                .place(&shape.columns, *at, |_, _| true)
                .map_err(|e: PlaceError| Error::new(format!("{}: {what}: {e}", self.name)))?;
            planting.objects.placed += 1;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::procedural;

    fn plan(text: &str) -> Result<ScenePlan> {
        ScenePlan::parse(text, "test.toml", Path::new("."))
    }

    #[test]
    fn library_objects_stand_where_the_file_puts_them() {
        let plan = plan(
            "[[place]]\nobject = \"house\"\nat = [60, 70]\n\n\
             [[place]]\nobject = \"vehicle\"\nat = [80, 70]\nheading = 90\nscale = 2\n",
        )
        .unwrap();
        assert_eq!(plan.len(), 2);
        let mut scene = procedural(128, 1);
        let bare = scene.heights.clone();
        let mut planting = Planting::new(&mut scene);
        plan.place(&mut planting).unwrap();
        let objects = planting.finish();
        assert_eq!(objects.placed, 2);
        let at = |x: usize, y: usize| y * 128 + x;
        // The house's middle is raised by its height; the vehicle (6
        // points long along x, 3 wide), turned a quarter and doubled, is
        // 12 long along y and 6 wide.
        assert!(scene.heights[at(60, 70)] > bare[at(60, 70)] + 4.0);
        assert_ne!(objects.points[at(60, 70)], 0);
        let vehicle_along_y = (60..=80)
            .filter(|&y| objects.points[at(80, y)] != 0)
            .count();
        assert_eq!(vehicle_along_y, 12, "the vehicle's length along y");
        let vehicle_along_x = (75..=85)
            .filter(|&x| objects.points[at(x, 70)] != 0)
            .count();
        assert_eq!(vehicle_along_x, 6, "the vehicle's width along x");
    }

    #[test]
    fn a_bad_file_is_one_line_that_names_the_problem() {
        let cases = [
            (
                "[[place]]\nobject = \"tower\"\nat = [1, 2]\n",
                "no object \"tower\" (known: conifer, broadleaf, house, vehicle)",
            ),
            (
                "[[place]]\nobject = \"house\"\nat = [60, 70]\nscale = 20\n",
                "scale 20 is outside 0.25 to 8",
            ),
            ("[[place]]\nobject = \"house\"\n", "line 1"),
            (
                "[[place]]\nobject = \"house\"\nat = [60, 70]\ncolour = 3\n",
                "line 4",
            ),
            (
                "[objects.house]\nfront = \"a.png\"\nside = \"b.png\"\ntop = \"c.png\"\n",
                "is the library's",
            ),
            (
                "[objects.barn]\nfront = \"missing.png\"\nside = \"b.png\"\ntop = \"c.png\"\n",
                "object \"barn\": cannot read ./missing.png",
            ),
        ];
        for (text, expected) in cases {
            let error = plan(text).unwrap_err().to_string();
            assert!(
                error.contains(expected),
                "{error:?} should say {expected:?}"
            );
            assert!(!error.contains('\n'), "{error:?}");
            assert!(error.starts_with("test.toml"), "{error:?}");
        }
    }

    #[test]
    fn an_object_that_cannot_stand_is_named_and_the_scene_keeps_the_others() {
        let mut scene = procedural(128, 1);
        let text = "[[place]]\nobject = \"house\"\nat = [60, 70]\n\n\
                    [[place]]\nobject = \"conifer\"\nat = [61, 71]\n";
        let mut planting = Planting::new(&mut scene);
        let error = plan(text)
            .unwrap()
            .place(&mut planting)
            .unwrap_err()
            .to_string();
        assert_eq!(
            error,
            "test.toml: place 2 (conifer at 61, 71): it overlaps another object (or stands right beside one)"
        );
        let off = plan("[[place]]\nobject = \"house\"\nat = [127, 5]\n").unwrap();
        let error = off.place(&mut planting).unwrap_err().to_string();
        assert!(error.contains("does not fit on the map"), "{error}");
        assert_eq!(planting.finish().placed, 1);
    }
}
