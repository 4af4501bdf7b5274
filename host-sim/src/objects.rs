//! 3D objects on a terrain as sticks (the kernel's [`StickLayer`]): a
//! procedural library of trees and houses, planted as a wood and a village
//! by a seeded rule.
//!
//! An object is a set of sticks on a footprint of grid points, each a run
//! of voxels standing on the terrain with a texture up its height. Planting
//! raises the scene's heights to the sticks' tops and gives each point its
//! top texel as its color (the color coarser levels filter), and records
//! the point's stick in a table that replicated objects share: ten
//! thousand trees of a few shapes are a few hundred sticks.
//!
//! Every object is at least two grid points across: the caster samples
//! the surface once a grid line, so a wall two points thick is solid to
//! every ray, where a lone stick is seen as the surface through its point.
//!
//! Objects also come from a scene file that places them by name
//! ([`placing`]), the library's or ones sculpted from three photographs
//! ([`sculpt`]).

pub mod placing;
pub mod sculpt;

use crate::scene::Scene;
use std::collections::HashMap;
use std::fmt;
use terracast::{Camera, Rgb, Stick, StickLayer, Terrain};

/// The sticks standing on a scene's grid points.
#[derive(Debug, Clone, PartialEq)]
pub struct Objects {
    /// Per grid point: 0 for plain terrain, `i` for `sticks[i − 1]`.
    pub points: Vec<u16>,
    /// The stick table, shared by every object that has the same stick.
    pub sticks: Vec<Stick>,
    /// The sticks' texels.
    pub texels: Vec<Rgb>,
    /// Each texel's opacity (255 opaque): one a texel.
    pub alphas: Vec<u8>,
    /// Objects planted, by kind.
    pub trees: usize,
    /// Houses planted.
    pub houses: usize,
    /// Objects a scene file placed.
    pub placed: usize,
}

/// The most sticks a table may hold (the index is 16-bit, 0 for none).
const MAX_STICKS: usize = u16::MAX as usize;

impl Objects {
    /// No objects on a `points`-point map.
    pub fn empty(points: usize) -> Self {
        Self {
            points: vec![0; points],
            sticks: Vec::new(),
            texels: Vec::new(),
            alphas: Vec::new(),
            trees: 0,
            houses: 0,
            placed: 0,
        }
    }

    /// The kernel's layer of these sticks over `terrain` (this scene's,
    /// with the sticks' tops as its heights).
    pub fn layer<'a>(&'a self, terrain: &Terrain<'_>) -> Result<StickLayer<'a>, String> {
        StickLayer::new(terrain, &self.points, &self.sticks, &self.texels)
            .and_then(|layer| layer.with_alphas(self.see_through_alphas()))
            .map_err(|e| e.to_string())
    }

    /// The opacities the kernel takes: none where every texel is opaque,
    /// so that opaque objects cost no test of them.
    pub fn see_through_alphas(&self) -> &[u8] {
        if self.alphas.iter().any(|&a| a < u8::MAX) {
            &self.alphas
        } else {
            &[]
        }
    }

    /// Grid points that hold a stick.
    pub fn points_with_sticks(&self) -> usize {
        self.points.iter().filter(|&&p| p != 0).count()
    }

    /// Bytes the kernel holds for the layer: a 16-bit index a grid point,
    /// the stick table and its texels.
    pub fn bytes(&self) -> usize {
        self.points.len() * 2
            + self.sticks.len() * std::mem::size_of::<Stick>()
            + self.texels.len() * 3
            + self.see_through_alphas().len()
    }

    /// The texel of the stick at grid point `index`, whose top is `top`
    /// voxels high, at height `z` (voxels): as the kernel's
    /// [`StickLayer::texel`] picks it, the stick's texel at `z` above its
    /// base; `None` where no stick stands.
    pub fn texel(&self, index: usize, top: f64, z: f64) -> Option<Rgb> {
        self.texels.get(self.texel_index(index, top, z)?).copied()
    }

    /// The opacity (0 to 1) of [`Objects::texel`]'s texel; `None` where no
    /// stick stands.
    pub fn alpha(&self, index: usize, top: f64, z: f64) -> Option<f64> {
        let texel = self.texel_index(index, top, z)?;
        Some(f64::from(self.alphas.get(texel).copied().unwrap_or(u8::MAX)) / 255.0)
    }

    /// Where in the texel table [`Objects::texel`] finds its texel.
    fn texel_index(&self, index: usize, top: f64, z: f64) -> Option<usize> {
        let stick = self
            .sticks
            .get(usize::from(*self.points.get(index)?).checked_sub(1)?)?;
        let base = top - f64::from(stick.height) / 16.0;
        let texel = ((z - base).floor().max(0.0) as usize).min(usize::from(stick.texels) - 1);
        Some(stick.first as usize + texel)
    }

    /// The ground's height under grid point `index`, whose top is `top`
    /// voxels high: its stick's base, or `top` where none stands.
    pub fn ground(&self, index: usize, top: f64) -> f64 {
        let stick = self
            .points
            .get(index)
            .and_then(|&p| self.sticks.get(usize::from(p).checked_sub(1)?));
        stick.map_or(top, |stick| top - f64::from(stick.height) / 16.0)
    }

    /// Whether a stick stands at grid point `index` (top `top` voxels) as
    /// high as `z` or higher: a crossing at `z` beside it is on its wall.
    pub fn stands(&self, index: usize, top: f64, z: f64) -> bool {
        self.points.get(index).is_some_and(|&p| p != 0) && top >= z
    }

    /// Adds a stick of `height` (U12.4) with `texels` to the table, or
    /// finds the one already there; its index plus one.
    fn stick(&mut self, table: &mut StickKeys, height: u16, column: &Column) -> Option<u16> {
        let key = (height, column.texels.clone(), column.alphas.clone());
        if let Some(&index) = table.get(&key) {
            return Some(index);
        }
        if self.sticks.len() >= MAX_STICKS {
            return None;
        }
        self.sticks.push(Stick {
            first: self.texels.len() as u32,
            texels: column.texels.len() as u16,
            height,
        });
        self.texels.extend_from_slice(&column.texels);
        self.alphas
            .extend((0..column.texels.len()).map(|i| column.alpha(i)));
        let index = self.sticks.len() as u16;
        table.insert(key, index);
        Some(index)
    }

    /// Puts the complex sticks (a texel less than opaque) after the opaque
    /// ones in the table, each part in its order, and renames the points
    /// to match: the kernel shades a hit on a stick before the first
    /// complex one as an opaque hit, with no opacity to look up
    /// ([`terracast::StickTable::first_complex`]). The same objects.
    pub fn order_complex_last(&mut self) {
        let (opaque, see_through): (Vec<usize>, Vec<usize>) =
            (0..self.sticks.len()).partition(|&i| !self.sticks[i].is_complex(&self.alphas));
        let order: Vec<usize> = opaque.into_iter().chain(see_through).collect();
        // A point's new value, by its old one (0 stays plain terrain).
        let mut renamed = vec![0u16; self.sticks.len() + 1];
        for (new, &old) in order.iter().enumerate() {
            renamed[old + 1] = new as u16 + 1;
        }
        self.sticks = order.iter().map(|&i| self.sticks[i]).collect();
        for point in &mut self.points {
            *point = renamed[usize::from(*point)];
        }
    }
}

/// The sticks a planting has added, by height, texels and opacities.
type StickKeys = HashMap<(u16, Vec<Rgb>, Vec<u8>), u16>;

/// One stick of an object: its grid point relative to the object's
/// anchor, its height in voxels (whole) and its texels, bottom up (one a
/// voxel of its height).
#[derive(Debug, Clone, PartialEq)]
pub struct Column {
    /// Grid points from the anchor along x.
    pub dx: i32,
    /// Grid points from the anchor along y.
    pub dy: i32,
    /// Height in whole voxels.
    pub height: u16,
    /// The texels, bottom up.
    pub texels: Vec<Rgb>,
    /// Their opacities (255 opaque), or none where all are opaque.
    pub alphas: Vec<u8>,
}

impl Column {
    /// The opacity of texel `i`.
    pub fn alpha(&self, i: usize) -> u8 {
        self.alphas.get(i).copied().unwrap_or(u8::MAX)
    }
}

/// An object: its sticks around an anchor.
#[derive(Debug, Clone, PartialEq)]
pub struct Shape {
    /// The sticks, at most one a grid point.
    pub columns: Vec<Column>,
}

impl Shape {
    /// The library's objects by name, at their own size: `conifer`,
    /// `broadleaf`, `house` and `vehicle`.
    pub const LIBRARY: [&'static str; 4] = ["conifer", "broadleaf", "house", "vehicle"];

    /// The library's object `name` ([`Shape::LIBRARY`]).
    pub fn library(name: &str) -> Option<Self> {
        let columns = match name {
            "conifer" => conifer(3, 13, 10, LEAF_ALPHA),
            "broadleaf" => broadleaf(3, 11, 10, LEAF_ALPHA),
            "house" => house(8, 6, 4, 3, [170, 60, 45]),
            "vehicle" => vehicle([40, 70, 150]),
            _ => return None,
        };
        Some(Self { columns })
    }

    /// This shape turned by `heading` degrees (from +x toward +y) and
    /// scaled by `scale`, about the middle of its footprint, which becomes
    /// its anchor: each grid point of the new footprint takes the stick
    /// of the nearest point it came from, its height and texels stretched
    /// by `scale` (nearest texel).
    pub fn placed(&self, heading: f64, scale: f64) -> Self {
        let Some((low, high)) = self.bounds() else {
            return self.clone();
        };
        let center = [
            f64::from(low[0] + high[0]) / 2.0,
            f64::from(low[1] + high[1]) / 2.0,
        ];
        let by_point: HashMap<(i32, i32), &Column> =
            self.columns.iter().map(|c| ((c.dx, c.dy), c)).collect();
        let (sin, cos) = heading.to_radians().sin_cos();
        // The new footprint's bounds: the old corners turned and scaled.
        let reach = [
            (f64::from(high[0] - low[0]) / 2.0 + 0.5) * scale,
            (f64::from(high[1] - low[1]) / 2.0 + 0.5) * scale,
        ];
        let half = [
            (reach[0] * cos.abs() + reach[1] * sin.abs()).ceil() as i32,
            (reach[0] * sin.abs() + reach[1] * cos.abs()).ceil() as i32,
        ];
        let mut columns = Vec::new();
        for dy in -half[1]..=half[1] {
            for dx in -half[0]..=half[0] {
                // Back to the shape's own frame: turned back, unscaled,
                // to the nearest point (halves up, so that a footprint
                // scaled by a whole number keeps its proportions).
                let (x, y) = (f64::from(dx) / scale, f64::from(dy) / scale);
                let nearest = |v: f64| (v + 0.5).floor() as i32;
                let from = (
                    nearest(center[0] + x * cos + y * sin),
                    nearest(center[1] - x * sin + y * cos),
                );
                let Some(source) = by_point.get(&from) else {
                    continue;
                };
                let height = (f64::from(source.height) * scale).round().max(1.0) as u16;
                let from_texel = |z: u16| {
                    let at = (f64::from(z) / scale) as usize;
                    at.min(source.texels.len() - 1)
                };
                let texels = (0..height).map(|z| source.texels[from_texel(z)]).collect();
                let alphas = if source.alphas.is_empty() {
                    Vec::new()
                } else {
                    (0..height).map(|z| source.alpha(from_texel(z))).collect()
                };
                columns.push(Column {
                    dx,
                    dy,
                    height,
                    texels,
                    alphas,
                });
            }
        }
        Self { columns }
    }

    /// The most grid points across and the most voxels tall an object
    /// may be once placed (turned and scaled).
    pub const MAX_PLACED_SIDE: f64 = 1024.0;

    /// Why this shape cannot be placed at `scale`: too wide or too tall
    /// once scaled (checked before [`Shape::placed`] builds it).
    pub fn too_large_at(&self, scale: f64) -> Option<String> {
        let (low, high) = self.bounds()?;
        let across = f64::from((high[0] - low[0]).max(high[1] - low[1]) + 1) * scale;
        let tall = f64::from(self.columns.iter().map(|c| c.height).max().unwrap_or(0)) * scale;
        if across * std::f64::consts::SQRT_2 > Self::MAX_PLACED_SIDE {
            Some(format!(
                "scaled, it is {across:.0} points across; an object turned any way must fit {} points",
                Self::MAX_PLACED_SIDE
            ))
        } else if tall > f64::from(Terrain::MAX_HEIGHT) {
            Some(format!(
                "scaled, it is {tall:.0} voxels tall; the kernel's heights reach {}",
                Terrain::MAX_HEIGHT
            ))
        } else {
            None
        }
    }

    /// The lowest and highest grid offsets of the footprint, if any.
    fn bounds(&self) -> Option<([i32; 2], [i32; 2])> {
        let first = self.columns.first()?;
        Some(self.columns.iter().fold(
            ([first.dx, first.dy], [first.dx, first.dy]),
            |(low, high), c| {
                (
                    [low[0].min(c.dx), low[1].min(c.dy)],
                    [high[0].max(c.dx), high[1].max(c.dy)],
                )
            },
        ))
    }
}

/// A conifer: a cone of `radius` points, `height` voxels tall, dark green
/// toward the ground and lighter up its height; the leaves of its outer
/// ring at opacity `leaves`.
fn conifer(radius: i32, height: u16, shade: u8, leaves: u8) -> Vec<Column> {
    footprint(radius, leaves, |d| {
        let h = (f64::from(height) * (1.0 - d / (f64::from(radius) + 1.0)))
            .round()
            .max(2.0) as u16;
        let texels = (0..h)
            .map(|z| {
                let up = f64::from(z) / f64::from(height);
                let g = 70.0 + 60.0 * up + f64::from(shade);
                [
                    (20.0 + 20.0 * up) as u8,
                    g.min(255.0) as u8,
                    (25.0 + 15.0 * up) as u8,
                ]
            })
            .collect();
        (h, texels)
    })
}

/// A broadleaf tree's trunk.
const TRUNK: Rgb = [90, 60, 35];

/// A broadleaf tree: a dome of `radius` points, `height` voxels tall,
/// its crown on a short brown trunk at the middle; the leaves of its
/// outer ring at opacity `leaves`.
fn broadleaf(radius: i32, height: u16, shade: u8, leaves: u8) -> Vec<Column> {
    footprint(radius, leaves, |d| {
        let r = f64::from(radius) + 0.5;
        let h = (f64::from(height) * (1.0 - (d / r).powi(2)).max(0.0).sqrt())
            .round()
            .max(2.0) as u16;
        let texels = (0..h)
            .map(|z| {
                if d < 1.0 && z < 2 {
                    TRUNK
                } else {
                    let up = f64::from(z) / f64::from(height);
                    [
                        (45.0 + 40.0 * up) as u8,
                        (95.0 + 55.0 * up + f64::from(shade)).min(255.0) as u8,
                        30,
                    ]
                }
            })
            .collect();
        (h, texels)
    })
}

/// The opacity of a tree's leaves on the outer ring of its crown, where
/// they are seen through: a ray sees half through them (a secondary ray
/// in the kernel).
const LEAF_ALPHA: u8 = 128;

/// The points within `radius` (and a half) of the anchor, each with the
/// stick `column` gives for its distance: its height and texels. The crown
/// of the outer ring (every texel but a trunk's) is leaves at opacity
/// `leaves`.
fn footprint(
    radius: i32,
    leaves: u8,
    mut column: impl FnMut(f64) -> (u16, Vec<Rgb>),
) -> Vec<Column> {
    let mut columns = Vec::new();
    for dy in -radius..=radius {
        for dx in -radius..=radius {
            let d = f64::from(dx * dx + dy * dy).sqrt();
            if d <= f64::from(radius) + 0.5 {
                let (height, texels) = column(d);
                let alphas = if leaves < u8::MAX && d > f64::from(radius) - 0.5 {
                    texels
                        .iter()
                        .map(|&t| if t == TRUNK { u8::MAX } else { leaves })
                        .collect()
                } else {
                    Vec::new()
                };
                columns.push(Column {
                    dx,
                    dy,
                    height,
                    texels,
                    alphas,
                });
            }
        }
    }
    columns
}

/// A house `width` × `depth` points (the ridge along x), walls `walls`
/// voxels high under a pitched roof rising `rise` more at the ridge: white
/// walls with a band of dark windows, a red roof.
fn house(width: i32, depth: i32, walls: u16, rise: u16, roof: Rgb) -> Vec<Column> {
    let half = f64::from(depth - 1) / 2.0;
    block(width, depth, |dx, dy| {
        let from_ridge = (f64::from(dy) - half).abs() / half.max(1.0);
        let height = walls + (f64::from(rise) * (1.0 - from_ridge)).round() as u16;
        let outside = dx == 0 || dy == 0 || dx == width - 1 || dy == depth - 1;
        let texels = (0..height)
            .map(|z| {
                if z >= walls {
                    roof
                } else if outside && z == walls / 2 && (dx + dy) % 3 == 1 {
                    [60, 70, 90]
                } else {
                    [225, 215, 195]
                }
            })
            .collect();
        (height, texels)
    })
}

/// A vehicle, 3 × 6 points (its length along x): a dark chassis, a body
/// in `paint` and a glazed cab over the front half.
fn vehicle(paint: Rgb) -> Vec<Column> {
    block(6, 3, |dx, dy| {
        let height = if dx >= 3 { 4 } else { 3 };
        let texels = (0..height)
            .map(|z| match z {
                0 => [30, 30, 35],
                3 if dy == 1 => paint,
                3 => [70, 90, 110],
                _ => paint,
            })
            .collect();
        (height, texels)
    })
}

/// The points of a `width` × `depth` rectangle from the anchor, each with
/// the stick `column` gives for its offset.
fn block(
    width: i32,
    depth: i32,
    mut column: impl FnMut(i32, i32) -> (u16, Vec<Rgb>),
) -> Vec<Column> {
    let mut columns = Vec::new();
    for dy in 0..depth {
        for dx in 0..width {
            let (height, texels) = column(dx, dy);
            columns.push(Column {
                dx,
                dy,
                height,
                texels,
                alphas: Vec::new(),
            });
        }
    }
    columns
}

/// Trees within this many grid points of their stand's edge (about two
/// of the largest trees across) are on its boundary, and have see-through
/// leaves.
const BOUNDARY: f64 = 16.0;

/// A small seeded generator (SplitMix64): the same planting for the same
/// seed on every machine.
struct Seeded(u64);

impl Seeded {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }
    /// Uniform in [0, 1).
    fn unit(&mut self) -> f64 {
        (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }
    /// Uniform in `low..high`.
    fn below(&mut self, low: i32, high: i32) -> i32 {
        low + (self.unit() * f64::from(high - low)) as i32
    }
}

/// How steep the terrain is at `(x, y)`: the larger height change to a
/// neighbouring point, in voxels a point.
fn slope(scene: &Scene, x: i32, y: i32) -> f32 {
    let (w, d) = (scene.width as i32, scene.depth as i32);
    let at = |x: i32, y: i32| scene.heights[(y.clamp(0, d - 1) * w + x.clamp(0, w - 1)) as usize];
    let h = at(x, y);
    [(1, 0), (-1, 0), (0, 1), (0, -1)]
        .iter()
        .map(|&(dx, dy)| (at(x + dx, y + dy) - h).abs())
        .fold(0.0, f32::max)
}

/// Plants a wood and a village on `scene` by a rule seeded with `seed`:
/// about a tree every hundred grid points of the wood's regions and a
/// house every few thousand of the village's, on dry land gentle enough
/// for them, none overlapping another. Raises the scene's heights to the
/// sticks' tops; a point where an object would rise past the kernel's
/// highest height is left bare.
pub fn plant(scene: &mut Scene, seed: u64) -> Objects {
    let mut planting = Planting::new(scene);
    planting.plant(seed);
    planting.finish()
}

impl Planting<'_> {
    /// Plants a wood and a village by the rule of [`plant`], around the
    /// objects already placed.
    pub fn plant(&mut self, seed: u64) {
        let planting = self;
        let scene = &*planting.scene;
        let (w, d) = (scene.width as i32, scene.depth as i32);
        let mut random = Seeded(seed ^ 0x00b1_ec75);
        // Nothing grows or stands in the water: at the map's lowest height
        // (the built-in scene's lake, a coast's sea).
        let water = scene.heights.iter().copied().fold(f32::MAX, f32::min);
        let area = f64::from(w) * f64::from(d);
        // Trees of a few shapes, each planted many times: the shapes share
        // their sticks. Each shape twice: opaque inside a stand, and with
        // see-through leaves on its outer ring on the stand's boundary,
        // where a ray may see through them to what is beyond (inside, it
        // would see another tree: Cohen-Or's "only the boundary trees").
        let shapes: Vec<[Vec<Column>; 2]> = (0..12)
            .map(|i| {
                let (radius, height, shade) =
                    (2 + i % 3, 7 + 3 * (i % 4) as u16, (i * 7 % 20) as u8);
                [u8::MAX, LEAF_ALPHA].map(|leaves| {
                    if i % 2 == 0 {
                        conifer(radius, height, shade, leaves)
                    } else {
                        broadleaf(radius, height - 2, shade, leaves)
                    }
                })
            })
            .collect();
        // The village: houses on a loose grid around a flat spot.
        let houses = (area / 3500.0) as usize;
        let roofs = [[170, 60, 45], [120, 55, 40], [90, 90, 100]];
        let homes: Vec<Vec<Column>> = (0..6)
            .map(|i| {
                house(
                    6 + 2 * (i % 3),
                    5 + (i % 2),
                    4 + (i % 2) as u16,
                    3,
                    roofs[i as usize % 3],
                )
            })
            .collect();
        let mut tries = 0;
        while planting.objects.houses < houses && tries < 50 {
            tries += 1;
            let (cx, cy) = (
                random.below(w / 8, w - w / 8),
                random.below(d / 8, d - d / 8),
            );
            let scene = &*planting.scene;
            if !(scene.heights[(cy * w + cx) as usize] > water + 1.0 && slope(scene, cx, cy) < 0.6)
            {
                continue;
            }
            let side = (houses as f64).sqrt().ceil() as i32 + 1;
            for gy in 0..side {
                for gx in 0..side {
                    if planting.objects.houses >= houses {
                        break;
                    }
                    let x = cx + (gx - side / 2) * 16 + random.below(-3, 4);
                    let y = cy + (gy - side / 2) * 14 + random.below(-3, 4);
                    let shape = &homes[random.below(0, homes.len() as i32) as usize];
                    if planting
                        .place(shape, (x, y), |h, s| h > water + 1.0 && s < 1.0)
                        .is_ok()
                    {
                        planting.objects.houses += 1;
                    }
                }
            }
        }
        // The wood: round stands around the village, most of the trees.
        let stands = 16;
        let trees = (area / 100.0) as usize;
        for _ in 0..stands {
            let (cx, cy) = (random.below(0, w), random.below(0, d));
            let radius = f64::from(w.min(d)) * 0.25;
            for _ in 0..trees / stands * 8 {
                if planting.objects.trees >= trees {
                    break;
                }
                let (a, r) = (
                    random.unit() * std::f64::consts::TAU,
                    radius * random.unit().sqrt(),
                );
                let (x, y) = (cx + (r * a.cos()) as i32, cy + (r * a.sin()) as i32);
                let boundary = r > radius - BOUNDARY;
                let shape =
                    &shapes[random.below(0, shapes.len() as i32) as usize][boundary as usize];
                if planting
                    .place(shape, (x, y), |h, s| h > water + 1.0 && s < 2.5)
                    .is_ok()
                {
                    planting.objects.trees += 1;
                }
            }
        }
    }
}

/// A planting under way: the scene, what stands on it, the stick table's
/// index by height and texels, and the points objects take.
pub struct Planting<'s> {
    scene: &'s mut Scene,
    objects: Objects,
    table: StickKeys,
    taken: Vec<bool>,
}

/// Why an object could not be placed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PlaceError {
    /// A point of its footprint is off the map or on its edge.
    OffMap,
    /// A point of its footprint, or one beside it, holds another object.
    Taken,
    /// The ground there does not suit it (water, too steep).
    Unfit,
    /// It would rise above the highest height the kernel stores.
    TooHigh,
    /// The stick table is full.
    TableFull,
}

impl fmt::Display for PlaceError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::OffMap => "it does not fit on the map (a point of it off the map or on its edge)",
            Self::Taken => "it overlaps another object (or stands right beside one)",
            Self::Unfit => "the ground there does not suit it",
            Self::TooHigh => "it would rise above the highest height the kernel stores",
            Self::TableFull => "the stick table is full",
        })
    }
}

impl<'s> Planting<'s> {
    /// A planting on `scene`, with nothing on it yet.
    pub fn new(scene: &'s mut Scene) -> Self {
        let points = scene.heights.len();
        Self {
            scene,
            objects: Objects::empty(points),
            table: HashMap::new(),
            taken: vec![false; points],
        }
    }

    /// What stands on the scene, its complex sticks last in the table
    /// ([`Objects::order_complex_last`]).
    pub fn finish(mut self) -> Objects {
        self.objects.order_complex_last();
        self.objects
    }

    /// Plants `shape` with its anchor at grid point `(x, y)` if every
    /// point of its footprint (and a point around it) is on the map, free,
    /// and passes `fits` (height and slope), and the stick table has room
    /// for it; the scene is left alone when it is not placed.
    pub fn place(
        &mut self,
        shape: &[Column],
        (x, y): (i32, i32),
        fits: impl Fn(f32, f32) -> bool,
    ) -> Result<(), PlaceError> {
        let scene = &*self.scene;
        let (w, d) = (scene.width as i32, scene.depth as i32);
        let mut points = Vec::with_capacity(shape.len());
        for c in shape {
            let (px, py) = (x + c.dx, y + c.dy);
            if !((1..w - 1).contains(&px) && (1..d - 1).contains(&py)) {
                return Err(PlaceError::OffMap);
            }
            let i = (py * w + px) as usize;
            let around = [(0, 0), (1, 0), (-1, 0), (0, 1), (0, -1)];
            if around
                .iter()
                .any(|&(ax, ay)| self.taken[((py + ay) * w + px + ax) as usize])
            {
                return Err(PlaceError::Taken);
            }
            if !fits(scene.heights[i], slope(scene, px, py)) {
                return Err(PlaceError::Unfit);
            }
            if scene.heights[i] + f32::from(c.height) > Terrain::MAX_HEIGHT - 1.0 {
                return Err(PlaceError::TooHigh);
            }
            points.push(i);
        }
        let mut sticks = Vec::with_capacity(shape.len());
        for c in shape {
            match self.objects.stick(&mut self.table, c.height * 16, c) {
                Some(stick) => sticks.push(stick),
                None => return Err(PlaceError::TableFull),
            }
        }
        for ((c, i), stick) in shape.iter().zip(points).zip(sticks) {
            // The stick stands on the terrain as the kernel stores it (1/16
            // voxel), so that its base is the terrain's height exactly.
            let ground = (self.scene.heights[i] * 16.0).round() / 16.0;
            self.scene.heights[i] = ground + f32::from(c.height);
            self.scene.colors[i] = *c.texels.last().unwrap_or(&self.scene.colors[i]);
            self.objects.points[i] = stick;
            self.taken[i] = true;
        }
        Ok(())
    }
}

/// The views the objects' accuracy test and the kernel bench's `objects`
/// table render, over `bare`, the terrain before planting (whose default
/// eye they take): from afar, into the wood, over the village and
/// grazing along the trees, on the built-in scene (1024², seed 1).
pub fn showcase_views(bare: &Scene) -> [(&'static str, Camera); 4] {
    [
        ("default", Camera::looking(bare.default_eye(), 90.0, 12.0)),
        (
            "into the wood",
            Camera::looking([420.0, 300.0, 140.0], 60.0, 8.0),
        ),
        (
            "over the village",
            Camera::looking([200.0, 560.0, 190.0], 20.0, 35.0),
        ),
        (
            "grazing",
            Camera::looking([600.0, 150.0, 110.0], 110.0, 2.0),
        ),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::procedural;

    #[test]
    fn planting_is_deterministic_and_shares_sticks() {
        let mut a = procedural(256, 3);
        let mut b = procedural(256, 3);
        let (oa, ob) = (plant(&mut a, 3), plant(&mut b, 3));
        assert_eq!(oa, ob);
        assert_eq!(a.heights, b.heights);
        assert!(oa.trees > 300, "{} trees", oa.trees);
        assert!(oa.houses >= 10, "{} houses", oa.houses);
        // Replicated shapes share their sticks: far fewer sticks than
        // points that hold one.
        assert!(
            oa.sticks.len() * 10 < oa.points_with_sticks(),
            "{} sticks",
            oa.sticks.len()
        );
        let kernel = a.to_kernel().unwrap();
        assert!(oa.layer(&kernel.terrain().unwrap()).is_ok());
    }

    #[test]
    fn an_object_too_large_once_scaled_is_refused_before_it_is_built() {
        let wide = Shape {
            columns: (0..200)
                .map(|dx| Column {
                    dx,
                    dy: 0,
                    height: 600,
                    texels: vec![[1, 2, 3]; 600],
                    alphas: Vec::new(),
                })
                .collect(),
        };
        assert_eq!(wide.too_large_at(1.0), None);
        let why = wide.too_large_at(8.0).unwrap();
        assert!(why.contains("1600 points across"), "{why}");
        let tall = Shape {
            columns: wide.columns[..2].to_vec(),
        };
        let why = tall.too_large_at(8.0).unwrap();
        assert!(why.contains("4800 voxels tall"), "{why}");
        assert!(Shape::library("house").unwrap().too_large_at(8.0).is_none());
    }

    #[test]
    fn a_planting_puts_its_complex_sticks_last_and_keeps_every_point() {
        let mut scene = procedural(256, 3);
        let mut planting = Planting::new(&mut scene);
        planting.plant(3);
        let unordered = planting.objects.clone();
        let ordered = planting.finish();
        let stick_at = |objects: &Objects, i: usize| {
            let point = usize::from(objects.points[i]);
            (point != 0).then(|| {
                let stick = objects.sticks[point - 1];
                let texels = stick.first as usize..stick.first as usize + usize::from(stick.texels);
                (
                    stick.height,
                    objects.texels[texels.clone()].to_vec(),
                    objects.alphas[texels].to_vec(),
                )
            })
        };
        // The same stick at every point, whatever its index.
        for i in 0..unordered.points.len() {
            assert_eq!(stick_at(&unordered, i), stick_at(&ordered, i));
        }
        let first_complex = |objects: &Objects| {
            let table = terracast::StickTable::new(&objects.sticks, &objects.texels).unwrap();
            table.with_alphas(&objects.alphas).unwrap().first_complex()
        };
        // The planting adds complex sticks among the opaque ones; ordered,
        // every stick from the first complex one on is complex.
        let first = usize::from(first_complex(&ordered));
        assert!(first_complex(&unordered) < first_complex(&ordered));
        assert!(first > 1 && first <= ordered.sticks.len());
        for stick in &ordered.sticks[first - 1..] {
            assert!(stick.is_complex(&ordered.alphas));
        }
    }

    #[test]
    fn a_stick_stands_on_the_terrain_with_its_texels_up_its_height() {
        let mut scene = procedural(128, 1);
        let before = scene.heights.clone();
        let objects = plant(&mut scene, 1);
        let (i, &p) = objects
            .points
            .iter()
            .enumerate()
            .find(|(_, &p)| p != 0)
            .unwrap();
        let stick = objects.sticks[usize::from(p) - 1];
        let top = f64::from(scene.heights[i]);
        let ground = f64::from(before[i]);
        assert!((top - ground - f64::from(stick.height) / 16.0).abs() < 1.0 / 16.0);
        let first = objects.texels[stick.first as usize];
        let last = objects.texels[stick.first as usize + usize::from(stick.texels) - 1];
        assert_eq!(objects.texel(i, top, ground + 0.5), Some(first));
        assert_eq!(objects.texel(i, top, top), Some(last));
        assert_eq!(scene.colors[i], last);
    }
}
