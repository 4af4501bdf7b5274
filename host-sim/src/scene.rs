//! Terrain on the host: loaded from files or generated, in world units.
//!
//! A [`Scene`] keeps heights as `f32` voxels (value × height scale) for the
//! exact reference, and converts them once to the kernel's U12.4 form.

mod detail;
pub mod geotiff;
mod load;
mod procedural;
pub mod voids;

pub use detail::{block_means, PhotoDetail, PlacedPhoto, StretchedPhoto};
pub use load::{
    derived_height_scale, fill_voids, hgt_height, hgt_side, hgt_spacing, load_colors, load_heights,
    not_a_height_map, read_color_map, refuse_mostly_void, report_filled, stretch_colors,
    HgtSpacing, Stretch,
};
pub use procedural::HeightBands;
pub use procedural::{color_by_height_and_slope, procedural};
pub(crate) use procedural::{terrain_color, value_noise, WATER_LEVEL};

use crate::error::{Error, Result};
use crate::objects::Objects;
use terracast::{
    pyramid_cells, pyramid_points, Detail, HeightFilter, Pyramid, RenderOptions, Resolution, Rgb,
    StickLayer, Terrain,
};

/// A height field and its colors, one per grid point, row-major.
#[derive(Debug, Clone)]
pub struct Scene {
    /// Grid points along x.
    pub width: u32,
    /// Grid points along y.
    pub depth: u32,
    /// Height of each grid point in voxels.
    pub heights: Vec<f32>,
    /// Color of each grid point.
    pub colors: Vec<Rgb>,
    /// 3D objects standing on the terrain, as sticks ([`crate::objects`]):
    /// `heights` are their tops where they stand.
    pub objects: Option<Objects>,
    /// Photos kept finer than the grid, each over its rectangle, later
    /// over earlier (`colors` are there the mean of each point's texels).
    pub details: Vec<PhotoDetail>,
}

/// Colors at a cell's corners (`(i, j)`, `(i + 1, j)`, `(i, j + 1)`,
/// `(i + 1, j + 1)`) blended at `(fx, fy)` within it.
fn bilinear([a, b, c, e]: [[f64; 3]; 4], fx: f64, fy: f64) -> [f64; 3] {
    core::array::from_fn(|k| {
        (a[k] * (1.0 - fx) + b[k] * fx) * (1.0 - fy) + (c[k] * (1.0 - fx) + e[k] * fx) * fy
    })
}

/// How the pyramid's coarser levels carry the objects' heights.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ObjectHeights {
    /// Raised to the tallest stick nearest each coarse point
    /// ([`Pyramid::build_with_sticks`]): far objects keep their
    /// silhouettes.
    #[default]
    Max,
    /// Filtered with the ground around them, as the terrain's heights are.
    Filtered,
    /// Raised by the opaque sticks only, the complex ones (see-through
    /// leaves) filtered with the ground: their cavities are not filled on
    /// the coarse levels ([`terracast::StickLayer::with_cavities_open`]).
    CavitiesOpen,
}

/// A scene in the kernel's storage format with its pyramid; lends a
/// [`Terrain`] and a [`Pyramid`].
#[derive(Debug, Clone)]
pub struct KernelScene {
    width: u32,
    depth: u32,
    heights: Vec<u16>,
    colors: Vec<Rgb>,
    filter: HeightFilter,
    coarse_heights: Vec<u16>,
    coarse_colors: Vec<Rgb>,
    bounds: Vec<u16>,
    /// The terrain's roughness, measured once here rather than by every
    /// `Pyramid::new` (a pass over a quarter of the rows: on a 4096² map
    /// about as long as a 320 × 240 render).
    roughness: u8,
    objects: Option<Objects>,
    /// The photos kept finer than the grid, in the kernel's storage.
    details: Vec<KernelDetail>,
}

/// A photo kept finer than the grid ([`PhotoDetail`]) with the kernel's
/// levels of it.
#[derive(Debug, Clone)]
struct KernelDetail {
    origin: [u32; 2],
    size: [u32; 2],
    shift: u32,
    levels: Vec<Rgb>,
}

/// Loads a height map and its color map (colored by height and slope when
/// `color` is `None`) into a checked scene.
pub fn load_pair(
    height: &std::path::Path,
    color: Option<&std::path::Path>,
    scale: f32,
    seed: u64,
) -> Result<Scene> {
    let (w, d, heights) = load_heights(height, scale)?;
    let Some(color) = color else {
        let colors = color_by_height_and_slope(w, d, &heights, seed);
        return Scene::new(w, d, heights, colors);
    };
    let photo = read_color_map(color)?;
    // A photo finer than the grid is kept at its own resolution.
    if let Some(detail) = PhotoDetail::from_photo(&photo, w, d) {
        let mut scene = Scene::new(w, d, heights, detail.grid_colors())?;
        scene.details.push(detail);
        return Ok(scene);
    }
    let colors = stretch_colors(&photo, color, w, d)?;
    Scene::new(w, d, heights, colors)
}

/// Loads a height map and the photos draped over it: none (colored by
/// height and slope), one stretched over the map's extent (any format, as
/// [`load_pair`]), or GeoTIFF photos placed by their georeference over a
/// georeferenced height map, each over the ones before, the points no
/// photo covers colored by height and slope. One line a placed photo says
/// how much of the terrain it covers; a photo that covers none of it is
/// refused.
pub fn load_scene_files(
    height: &std::path::Path,
    colors: &[std::path::PathBuf],
    scale: f32,
    seed: u64,
) -> Result<Scene> {
    let Some((grid_at, photos_at)) = placements(height, colors)? else {
        return match colors {
            [] => load_pair(height, None, scale, seed),
            [one] => load_pair(height, Some(one), scale, seed),
            _ => Err(Error::new(
                "several --color photos are placed by their georeference: give GeoTIFF photos over a GeoTIFF height map, or one photo to stretch over the map",
            )),
        };
    };
    let (w, d, heights) = load_heights(height, scale)?;
    let mut scene_colors = color_by_height_and_slope(w, d, &heights, seed);
    let mut details = Vec::new();
    for (path, at) in colors.iter().zip(photos_at) {
        let photo = geotiff::read_photo(path)?;
        let covered = geotiff::drape(&mut scene_colors, (w, d), &grid_at, &photo, &at);
        if covered == 0 {
            return Err(Error::new(format!(
                "photo {} does not overlap height map {}",
                path.display(),
                height.display()
            )));
        }
        eprintln!(
            "{}: covers {:.1} % of the terrain, {:.1} photo pixels a grid spacing",
            path.display(),
            100.0 * covered as f64 / (f64::from(w) * f64::from(d)),
            grid_at.pixel[0] / at.pixel[0]
        );
        // A photo finer than the grid is kept at its own resolution over
        // the points it covers, their colors its texels' mean.
        if let Some(detail) = PhotoDetail::placed(&photo, &at, &grid_at, (w, d), &scene_colors) {
            detail.reduce_into(&mut scene_colors, w);
            details.push(detail);
        }
    }
    let mut scene = Scene::new(w, d, heights, scene_colors)?;
    scene.details = details;
    Ok(scene)
}

/// Where the photos `colors` lie over the grid of `height` when they are
/// placed by their georeference (a georeferenced GeoTIFF height map and
/// every photo a georeferenced GeoTIFF): the grid's georeference and each
/// photo's; `None` when they are not placed (a photo is then stretched
/// over the map). Refuses a photo in another coordinate system than the
/// grid's, in one line.
pub fn placements(
    height: &std::path::Path,
    colors: &[std::path::PathBuf],
) -> Result<Option<(geotiff::GeoRef, Vec<geotiff::GeoRef>)>> {
    let georeferenced = |path: &std::path::Path| -> Result<Option<geotiff::GeoRef>> {
        if !geotiff::is_tiff(path) {
            return Ok(None);
        }
        Ok(geotiff::read_georef(path)?.ok())
    };
    if colors.is_empty() {
        return Ok(None);
    }
    let Some(grid_at) = georeferenced(height)? else {
        return Ok(None);
    };
    let mut photos_at = Vec::new();
    for path in colors {
        let Some(at) = georeferenced(path)? else {
            return Ok(None);
        };
        photos_at.push((path, at));
    }
    for (path, at) in &photos_at {
        if at.geographic != grid_at.geographic {
            return Err(Error::new(format!(
                "photo {} and height map {} are in different coordinate systems (one geographic, one projected)",
                path.display(),
                height.display()
            )));
        }
    }
    Ok(Some((
        grid_at,
        photos_at.into_iter().map(|(_, at)| at).collect(),
    )))
}

impl Scene {
    /// Checks that the sizes agree and every height is finite.
    pub fn new(width: u32, depth: u32, heights: Vec<f32>, colors: Vec<Rgb>) -> Result<Self> {
        let cells = width as usize * depth as usize;
        if width < 2 || depth < 2 {
            return Err(Error::new(format!(
                "terrain is {width}x{depth}: it needs at least 2x2 grid points"
            )));
        }
        if heights.len() != cells || colors.len() != cells {
            return Err(Error::new("height and color grids differ in size"));
        }
        if let Some(i) = heights.iter().position(|h| !h.is_finite()) {
            return Err(Error::new(format!(
                "height at grid point ({}, {}) is not a finite number",
                i % width as usize,
                i / width as usize
            )));
        }
        Ok(Self {
            width,
            depth,
            heights,
            colors,
            objects: None,
            details: Vec::new(),
        })
    }

    /// The `side` x `side` square at the middle of this terrain (its
    /// objects and finer photos left behind), or an error naming both
    /// sizes where the terrain is smaller.
    pub fn middle_square(&self, side: u32) -> Result<Self> {
        if side > self.width || side > self.depth {
            return Err(Error::new(format!(
                "cannot cut {side}x{side} from a {}x{} terrain",
                self.width, self.depth
            )));
        }
        let (x0, y0) = (
            ((self.width - side) / 2) as usize,
            ((self.depth - side) / 2) as usize,
        );
        let (n, width) = (side as usize, self.width as usize);
        let rows = |y: usize| (y0 + y) * width + x0..(y0 + y) * width + x0 + n;
        let heights = (0..n)
            .flat_map(|y| self.heights[rows(y)].iter().copied())
            .collect();
        let colors = (0..n)
            .flat_map(|y| self.colors[rows(y)].iter().copied())
            .collect();
        Self::new(side, side, heights, colors)
    }

    /// Plants a wood and a village on the terrain by a rule seeded with
    /// `seed` ([`crate::objects::plant`]), and reports what it planted in
    /// one line.
    pub fn plant_objects(&mut self, seed: u64) -> String {
        self.add_objects(None, Some(seed))
            .expect("planting by the seeded rule skips what does not fit")
    }

    /// Stands the objects of a scene file (`plan`) on the terrain, then,
    /// with a `seed`, plants a wood and a village around them; reports
    /// what stands in one line. An object of the file that cannot stand is
    /// an error, and the scene is left without objects.
    pub fn add_objects(
        &mut self,
        plan: Option<&crate::objects::placing::ScenePlan>,
        seed: Option<u64>,
    ) -> Result<String> {
        let bare = (self.heights.clone(), self.colors.clone());
        let mut planting = crate::objects::Planting::new(self);
        let placed = plan.map(|plan| plan.place(&mut planting));
        if let Some(Err(e)) = placed {
            drop(planting);
            (self.heights, self.colors) = bare;
            return Err(e);
        }
        if let Some(seed) = seed {
            planting.plant(seed);
        }
        let objects = planting.finish();
        let mut parts = Vec::new();
        if let Some(plan) = plan {
            parts.push(format!(
                "placed {} objects ({} sculpted kinds)",
                objects.placed, plan.sculpted
            ));
        }
        if seed.is_some() {
            parts.push(format!(
                "planted {} trees and {} houses",
                objects.trees, objects.houses
            ));
        }
        let mut line = format!(
            "{}: {} sticks on {} grid points, {} bytes in the kernel",
            parts.join("; "),
            objects.sticks.len(),
            objects.points_with_sticks(),
            objects.bytes()
        );
        self.objects = Some(objects);
        // A stick's texels color it, not the photo under it: objects
        // stand on the grid's colors.
        if !std::mem::take(&mut self.details).is_empty() {
            line += "; the photo is kept at the height grid's resolution under objects";
        }
        Ok(line)
    }

    /// Height of grid point (x, y).
    pub fn height(&self, x: usize, y: usize) -> f32 {
        self.heights[y * self.width as usize + x]
    }

    /// The grid cell holding world (x, y) (clamped into the map) and the
    /// position within it.
    pub fn cell_at(&self, x: f64, y: f64) -> (usize, usize, f64, f64) {
        let (w, d) = (self.width as usize, self.depth as usize);
        let (x, y) = (x.clamp(0.0, (w - 1) as f64), y.clamp(0.0, (d - 1) as f64));
        let (i, j) = (
            (x.floor() as usize).min(w - 2),
            (y.floor() as usize).min(d - 2),
        );
        (i, j, x - i as f64, y - j as f64)
    }

    /// Height of the bilinear surface at world (x, y).
    pub fn height_at(&self, x: f64, y: f64) -> f64 {
        let (i, j, fx, fy) = self.cell_at(x, y);
        let h = |a: usize, b: usize| f64::from(self.heights[b * self.width as usize + a]);
        (h(i, j) * (1.0 - fx) + h(i + 1, j) * fx) * (1.0 - fy)
            + (h(i, j + 1) * (1.0 - fx) + h(i + 1, j + 1) * fx) * fy
    }

    /// Bilinear color at world (x, y): of the photo's texels where it is
    /// kept finer than the grid, else of the grid's colors.
    pub fn color_at(&self, x: f64, y: f64) -> [f64; 3] {
        if let Some(color) = self.details.iter().rev().find_map(|d| d.color_at(x, y)) {
            return color;
        }
        let (i, j, fx, fy) = self.cell_at(x, y);
        let w = self.width as usize;
        let corners = [(i, j), (i + 1, j), (i, j + 1), (i + 1, j + 1)]
            .map(|(a, b)| self.colors[b * w + a].map(f64::from));
        bilinear(corners, fx, fy)
    }

    /// [`Scene::color_at`] where a ray meets the surface at height `z`:
    /// a corner that holds a stick shows its texel at `z`, and a corner
    /// lower than `z` beside a stick that stands as high shows that
    /// stick's texel, the wall's (as the kernel's `StickLayer::pair`).
    pub fn color_at_height(&self, x: f64, y: f64, z: f64) -> [f64; 3] {
        self.seen_at_height(x, y, z, &[]).0
    }

    /// [`Scene::color_at_height`] and the opacity (0 to 1) of what it
    /// shows, blended alike (the colors weighted by their opacities), for
    /// a ray that sees through the points in `lowered` (plain ground at
    /// their sticks' bases, no longer walls); and the cell's corners whose
    /// texels there are less than opaque.
    pub fn seen_at_height(
        &self,
        x: f64,
        y: f64,
        z: f64,
        lowered: &[usize],
    ) -> ([f64; 3], f64, Vec<usize>) {
        let Some(objects) = &self.objects else {
            return (self.color_at(x, y), 1.0, Vec::new());
        };
        let (i, j, fx, fy) = self.cell_at(x, y);
        let w = self.width as usize;
        let corners = [(i, j), (i + 1, j), (i, j + 1), (i + 1, j + 1)].map(|(a, b)| b * w + a);
        // A lowered corner is plain ground under the stick seen through:
        // no texel of its own, no wall.
        let top = |c: usize| f64::from(self.heights[c]);
        let stick_at = |c: usize| {
            if lowered.contains(&c) {
                return None;
            }
            objects.texel(c, top(c), z).zip(objects.alpha(c, top(c), z))
        };
        let height = |c: usize| {
            if lowered.contains(&c) {
                objects.ground(c, top(c))
            } else {
                top(c)
            }
        };
        let wall = corners
            .iter()
            .filter(|&&c| !lowered.contains(&c) && objects.stands(c, top(c), z))
            .max_by(|&&a, &&b| top(a).total_cmp(&top(b)))
            .and_then(|&c| stick_at(c));
        let seen = corners.map(|c| match (stick_at(c), wall) {
            (Some(texel), _) => texel,
            (None, Some(texel)) if height(c) < z => texel,
            _ => (self.colors[c], 1.0),
        });
        // Colors blend weighted by their opacities (premultiplied): a
        // clear texel lends its color nothing to what is seen through it.
        let alpha = bilinear(seen.map(|(_, a)| [a; 3]), fx, fy)[0];
        let color = if alpha > 0.0 && seen.iter().any(|&(_, a)| a < 1.0) {
            bilinear(seen.map(|(c, a)| c.map(|v| f64::from(v) * a)), fx, fy).map(|v| v / alpha)
        } else {
            bilinear(seen.map(|(c, _)| c.map(f64::from)), fx, fy)
        };
        let clear = corners
            .iter()
            .zip(&seen)
            .filter(|(_, (_, a))| *a < 1.0)
            .map(|(&c, _)| c)
            .collect();
        (color, alpha, clear)
    }

    /// Highest height in voxels.
    pub fn max_height(&self) -> f32 {
        self.heights.iter().copied().fold(f32::MIN, f32::max)
    }

    /// The commands' eye when none is given (see [`south_edge_eye`]).
    pub fn default_eye(&self) -> [f32; 3] {
        south_edge_eye(self.width, self.depth, self.max_height())
    }

    /// Converts to the kernel's format (heights rounded to 1/16 voxel) and
    /// builds the pyramid with the default height filter (the wavelet).
    pub fn to_kernel(&self) -> Result<KernelScene> {
        self.to_kernel_with(HeightFilter::default())
    }

    /// As [`Scene::to_kernel`], with the coarse levels' height filter.
    pub fn to_kernel_with(&self, filter: HeightFilter) -> Result<KernelScene> {
        self.to_kernel_with_object_heights(filter, ObjectHeights::Max)
    }

    /// [`Scene::to_kernel_with`], the objects' heights on the coarser
    /// levels made as `object_heights` says.
    pub fn to_kernel_with_object_heights(
        &self,
        filter: HeightFilter,
        object_heights: ObjectHeights,
    ) -> Result<KernelScene> {
        let heights = self
            .heights
            .iter()
            .enumerate()
            .map(|(i, &h)| {
                Terrain::quantize_height(h).ok_or_else(|| {
                    Error::new(format!(
                        "height {h} at grid point ({}, {}) is outside the kernel's range 0..={} voxels (adjust --height-scale)",
                        i % self.width as usize,
                        i / self.width as usize,
                        Terrain::MAX_HEIGHT
                    ))
                })
            })
            .collect::<Result<Vec<u16>>>()?;
        let (w, d) = (self.width, self.depth);
        let mut scene = KernelScene {
            width: w,
            depth: d,
            heights,
            colors: self.colors.clone(),
            filter,
            coarse_heights: vec![0; pyramid_points(w, d)],
            coarse_colors: vec![[0; 3]; pyramid_points(w, d)],
            bounds: vec![0; pyramid_cells(w, d)],
            roughness: 0,
            objects: self.objects.clone(),
            details: self
                .details
                .iter()
                .map(|detail| KernelDetail {
                    origin: detail.origin,
                    size: detail.size,
                    shift: detail.shift,
                    levels: detail.kernel_levels(),
                })
                .collect(),
        };
        let terrain = Terrain::new(w, d, &scene.heights, &scene.colors)
            .map_err(|e| Error::new(format!("terrain rejected by the kernel: {e}")))?;
        // Coarse levels keep the objects' silhouettes unless asked not to.
        let sticks = match &scene.objects {
            Some(objects) if object_heights != ObjectHeights::Filtered => {
                let layer = objects
                    .layer(&terrain)
                    .map_err(|e| Error::new(format!("objects rejected by the kernel: {e}")))?;
                Some(match object_heights {
                    ObjectHeights::CavitiesOpen => layer.with_cavities_open(),
                    _ => layer,
                })
            }
            _ => None,
        };
        Pyramid::build_with_sticks(
            &terrain,
            filter,
            sticks.as_ref(),
            &mut scene.coarse_heights,
            &mut scene.coarse_colors,
            &mut scene.bounds,
        )
        .map_err(|e| Error::new(format!("pyramid not built: {e}")))?;
        scene.roughness = Pyramid::new(
            terrain,
            &scene.coarse_heights,
            &scene.coarse_colors,
            &scene.bounds,
        )
        .map_err(|e| Error::new(format!("pyramid rejected by the kernel: {e}")))?
        .roughness();
        Ok(scene)
    }
}

impl KernelScene {
    /// The kernel's borrowed view of this scene.
    pub fn terrain(&self) -> Result<Terrain<'_>> {
        Terrain::new(self.width, self.depth, &self.heights, &self.colors)
            .map_err(|e| Error::new(format!("terrain rejected by the kernel: {e}")))
    }

    /// The terrain and its coarser levels.
    pub fn pyramid(&self) -> Result<Pyramid<'_>> {
        Pyramid::with_roughness(
            self.terrain()?,
            &self.coarse_heights,
            &self.coarse_colors,
            &self.bounds,
            self.roughness,
        )
        .map_err(|e| Error::new(format!("pyramid rejected by the kernel: {e}")))
    }

    /// What a render with `options` holds: level 0 alone for a
    /// single-resolution render without the first hit (which reads nothing
    /// else), the whole pyramid otherwise.
    pub fn pyramid_for(&self, options: &RenderOptions) -> Result<Pyramid<'_>> {
        let full = self.pyramid()?;
        if options.resolution == Resolution::Single && !options.hierarchical_first_hit {
            Ok(Pyramid::flat(*full.base()))
        } else {
            Ok(full)
        }
    }

    /// The kernel's layer of the scene's objects, if it has any.
    pub fn sticks(&self) -> Result<Option<StickLayer<'_>>> {
        let Some(objects) = &self.objects else {
            return Ok(None);
        };
        let terrain = self.terrain()?;
        objects
            .layer(&terrain)
            .map(Some)
            .map_err(|e| Error::new(format!("objects rejected by the kernel: {e}")))
    }

    /// Bytes of the objects' stick table, its sticks, their texels and
    /// the texels' opacities (0 without objects): what a parallel machine's processors hold whole,
    /// where a stick point's voxel holds an index into it in place of a
    /// color (see [`crate::sim::simulate_with_sticks`]).
    pub fn stick_table_bytes(&self) -> u64 {
        self.objects.as_ref().map_or(0, |objects| {
            (std::mem::size_of_val(objects.sticks.as_slice())
                + std::mem::size_of_val(objects.texels.as_slice())
                + objects.see_through_alphas().len()) as u64
        })
    }

    /// The kernel's view of the photos kept finer than the grid (none
    /// when it has none).
    pub fn details(&self) -> Result<Vec<Detail<'_>>> {
        self.details
            .iter()
            .map(|detail| {
                Detail::new(detail.origin, detail.size, detail.shift, &detail.levels)
                    .map_err(|e| Error::new(format!("photo detail rejected by the kernel: {e}")))
            })
            .collect()
    }

    /// The filter the coarse heights were made with.
    pub fn height_filter(&self) -> HeightFilter {
        self.filter
    }
}

/// The commands' eye over a `width` × `depth` map whose highest terrain is
/// `top`: over the middle of its south edge (12 % of the way in), a little
/// above the highest terrain, so that a view toward +y looks across the
/// whole map.
pub fn south_edge_eye(width: u32, depth: u32, top: f32) -> [f32; 3] {
    let (w, d) = (width as f32, depth as f32);
    [w * 0.5, d * 0.12, top + 0.04 * w.min(d)]
}
