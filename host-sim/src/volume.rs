//! Qu et al. (1998, §3–4): the terrain as a filtered 3D density volume,
//! ray cast in true 3D, and its approximate form, the 2D boundary array.
//!
//! **The volume.** Voxels below the surface are 255, above it 0, filtered so
//! that those near the surface take values between. The filter is a 3D
//! Gaussian of width `sigma` applied to the solid the height field bounds:
//! along z it is applied in closed form (a column's density at height `z`
//! is `255 Φ((h − z) / σ_z)`, so a height between layers is kept, not
//! rounded to one), then across each layer separably in x and y. The
//! paper names a Gaussian or an oriented box filter and is silent on its
//! width; `sigma` is a setting (default 0.7 voxels), and `σ_z` is the larger
//! of it and the layer spacing, so that the density changes smoothly from
//! layer to layer for the trilinear reconstruction. Layers span the
//! terrain's height range and 3 σ_z beyond it; their spacing is a setting
//! (default: the range in 64 layers, as Qu's 512 × 512 × 64 volume, and at
//! least one voxel). Each column's color is the photo's (pre-texturing).
//!
//! **Cells** lie between eight voxels; a cell whose voxels are on both
//! sides of the threshold is a boundary cell. The 2D boundary array keeps
//! the lowest and highest boundary cell of each cell column: above the
//! highest a cell is all air, below the lowest all terrain.
//!
//! **`volume`**, the accurate mode: each ray is sampled at `interval`
//! voxels; a sample above its column's highest boundary cell is air and one
//! below the lowest is terrain without a look at the volume; between, the
//! density is trilinear. The hit lies between the last sample in air and
//! the first at or over the threshold (128), placed by their densities. Its
//! color is the photo's, bilinear. Ray coherence as Qu describe it: the
//! rays of a vertical plane are cast in the order they reach farther, and
//! each starts at the distance from the eye where the ray before it hit;
//! when that start is already inside the terrain the ray retraces, back
//! along itself, to the surface. Qu take image columns for the planes,
//! which are vertical only where the camera is level; here they are the
//! kernel's image lines through the vertical's vanishing point
//! ([`View::line_pixels`]), vertical at any pitch and roll.
//!
//! **`boundary`**, the approximate mode: the same walk on the boundary
//! array alone, the hit at the first sample inside a boundary cell or
//! below one (no densities, no refinement).
//!
//! Both are single-threaded, as the other baselines are, and float, as the
//! reference is: they are host methods for the chart. The boundary array
//! alone (4 bytes a point) is a 2D array the kernel's static storage could
//! hold; it is not on the board.

use crate::camera::{length, ContractCamera};
use crate::frame::{Frame, RenderStats};
use crate::scene::Scene;
use std::time::Instant;
use terracast::{Camera, Rgb, View};

/// The density that separates terrain from air.
pub const THRESHOLD: u8 = 128;

/// How the volume is made and sampled.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VolumeOptions {
    /// The Gaussian filter's standard deviation, voxels.
    pub sigma: f32,
    /// Spacing of the layers, voxels; `None`: the height range in 64
    /// layers, at least one voxel.
    pub layer: Option<f32>,
    /// Sampling interval along a ray, voxels.
    pub interval: f32,
    /// Ray coherence: a ray starts where the one below it on its image
    /// column hit (off: every ray from where it enters the volume).
    pub coherence: bool,
    /// Sky color.
    pub sky: Rgb,
}

impl Default for VolumeOptions {
    fn default() -> Self {
        Self {
            sigma: 0.7,
            layer: None,
            interval: 0.5,
            coherence: true,
            sky: terracast::config::DEFAULT_SKY,
        }
    }
}

/// The filtered density volume and its boundary array.
#[derive(Debug, Clone)]
pub struct TerrainVolume {
    width: usize,
    depth: usize,
    layers: usize,
    /// Height of layer 0, and the spacing of the layers.
    base: f32,
    layer: f32,
    /// Densities, column by column: `(y · width + x) · layers + k`.
    density: Vec<u8>,
    /// Each cell column's lowest and highest boundary cell (cell `k` lies
    /// between layers `k` and `k + 1`); `[layers, 0]` for none.
    boundary: Vec<[u16; 2]>,
}

/// Standard normal CDF.
fn normal_cdf(x: f32) -> f32 {
    0.5 * (1.0 + libm::erff(x * core::f32::consts::FRAC_1_SQRT_2))
}

/// A normalized Gaussian kernel of standard deviation `sigma` (3σ each
/// side; one tap for a width under a hundredth of a voxel).
fn gaussian(sigma: f32) -> Vec<f32> {
    if sigma < 0.01 {
        return vec![1.0];
    }
    let radius = (3.0 * sigma).ceil() as i32;
    let taps: Vec<f32> = (-radius..=radius)
        .map(|i| (-(i * i) as f32 / (2.0 * sigma * sigma)).exp())
        .collect();
    let sum: f32 = taps.iter().sum();
    taps.into_iter().map(|t| t / sum).collect()
}

/// Convolves `line` (stride `stride`, `n` values from `start`) with
/// `taps`, clamping at the ends; `scratch` holds the input.
fn blur_line(
    values: &mut [f32],
    start: usize,
    stride: usize,
    n: usize,
    taps: &[f32],
    scratch: &mut Vec<f32>,
) {
    let radius = (taps.len() / 2) as isize;
    scratch.clear();
    scratch.extend((0..n).map(|i| values[start + i * stride]));
    for i in 0..n {
        let mut sum = 0.0;
        for (t, &weight) in taps.iter().enumerate() {
            let j = (i as isize + t as isize - radius).clamp(0, n as isize - 1) as usize;
            sum += weight * scratch[j];
        }
        values[start + i * stride] = sum;
    }
}

impl TerrainVolume {
    /// The layers a volume of `scene` with `options` has: their count, the
    /// height of the lowest and their spacing (what its memory is, before
    /// it is made: a byte a voxel).
    pub fn layers_for(scene: &Scene, options: &VolumeOptions) -> (usize, f32, f32) {
        let (low, high) = scene
            .heights
            .iter()
            .fold((f32::MAX, f32::MIN), |(lo, hi), &h| (lo.min(h), hi.max(h)));
        let layer = options
            .layer
            .unwrap_or(((high - low) / 63.0).max(1.0))
            .max(1e-3);
        let margin = 3.0 * options.sigma.max(layer) + layer;
        let base = low - margin;
        let layers = (((high + margin - base) / layer).ceil() as usize + 1).clamp(2, 65_535);
        (layers, base, layer)
    }

    /// Voxelizes and filters `scene`'s height field.
    pub fn build(scene: &Scene, options: &VolumeOptions) -> Self {
        let (width, depth) = (scene.width as usize, scene.depth as usize);
        let (layers, base, layer) = Self::layers_for(scene, options);
        let sigma_z = options.sigma.max(layer);
        let taps = gaussian(options.sigma);
        let mut density = vec![0u8; width * depth * layers];
        let mut plane = vec![0f32; width * depth];
        let mut scratch = Vec::new();
        for k in 0..layers {
            let z = base + k as f32 * layer;
            // The layer through the solid, filtered along z in closed form.
            for (value, &h) in plane.iter_mut().zip(&scene.heights) {
                let x = (h - z) / sigma_z;
                *value = if x > 4.0 {
                    255.0
                } else if x < -4.0 {
                    0.0
                } else {
                    255.0 * normal_cdf(x)
                };
            }
            // Across the layer: a layer all air or all terrain stays so.
            let (lo, hi) = plane
                .iter()
                .fold((f32::MAX, f32::MIN), |(a, b), &v| (a.min(v), b.max(v)));
            if taps.len() > 1 && lo != hi {
                for y in 0..depth {
                    blur_line(&mut plane, y * width, 1, width, &taps, &mut scratch);
                }
                for x in 0..width {
                    blur_line(&mut plane, x, width, depth, &taps, &mut scratch);
                }
            }
            for (column, &value) in plane.iter().enumerate() {
                density[column * layers + k] = value.round().clamp(0.0, 255.0) as u8;
            }
        }
        let mut volume = Self {
            width,
            depth,
            layers,
            base,
            layer,
            density,
            boundary: Vec::new(),
        };
        volume.boundary = volume.boundary_array();
        volume
    }

    /// The lowest and highest boundary cell of each cell column.
    fn boundary_array(&self) -> Vec<[u16; 2]> {
        let mut boundary = vec![[self.layers as u16, 0]; self.width * self.depth];
        for y in 0..self.depth.saturating_sub(1) {
            for x in 0..self.width.saturating_sub(1) {
                let columns = [
                    self.column(x, y),
                    self.column(x + 1, y),
                    self.column(x, y + 1),
                    self.column(x + 1, y + 1),
                ];
                let mut found = [self.layers as u16, 0];
                for k in 0..self.layers - 1 {
                    let (mut inside, mut outside) = (false, false);
                    for column in &columns {
                        for v in [column[k], column[k + 1]] {
                            if v >= THRESHOLD {
                                inside = true;
                            } else {
                                outside = true;
                            }
                        }
                    }
                    if inside && outside {
                        found[0] = found[0].min(k as u16);
                        found[1] = found[1].max(k as u16);
                    }
                }
                boundary[y * self.width + x] = found;
            }
        }
        boundary
    }

    fn column(&self, x: usize, y: usize) -> &[u8] {
        let start = (y * self.width + x) * self.layers;
        &self.density[start..start + self.layers]
    }

    /// The trilinear density at `p` (world voxels, on the map).
    fn density_at(&self, p: [f32; 3]) -> f32 {
        let kz = ((p[2] - self.base) / self.layer).clamp(0.0, (self.layers - 1) as f32);
        let (ix, iy) = (
            (p[0].max(0.0) as usize).min(self.width - 2),
            (p[1].max(0.0) as usize).min(self.depth - 2),
        );
        let k = (kz as usize).min(self.layers - 2);
        let (fx, fy, fz) = (p[0] - ix as f32, p[1] - iy as f32, kz - k as f32);
        let at = |x: usize, y: usize| {
            let c = self.column(x, y);
            f32::from(c[k]) * (1.0 - fz) + f32::from(c[k + 1]) * fz
        };
        (at(ix, iy) * (1.0 - fx) + at(ix + 1, iy) * fx) * (1.0 - fy)
            + (at(ix, iy + 1) * (1.0 - fx) + at(ix + 1, iy + 1) * fx) * fy
    }

    /// Bytes of the density volume.
    pub fn volume_bytes(&self) -> u64 {
        self.density.len() as u64
    }

    /// Bytes of the boundary array (two u16 a point).
    pub fn boundary_bytes(&self) -> u64 {
        self.boundary.len() as u64 * 4
    }

    /// One line: the volume's size and memory, and the boundary array's.
    pub fn describe(&self) -> String {
        let mib = |bytes: u64| bytes as f64 / (1 << 20) as f64;
        format!(
            "volume: {} x {} x {} layers {} voxels apart, {:.1} MiB; boundary array {:.1} MiB",
            self.width,
            self.depth,
            self.layers,
            self.layer,
            mib(self.volume_bytes()),
            mib(self.boundary_bytes())
        )
    }

    /// Layers of the volume.
    pub fn layers(&self) -> usize {
        self.layers
    }

    /// The layer spacing, voxels.
    pub fn layer(&self) -> f32 {
        self.layer
    }
}

/// `scene` with its heights filtered by the volume's Gaussian across x and
/// y (`sigma` voxels): the surface a filtered volume approximates, for the
/// reference to render so that the volume is also compared with the
/// terrain it models.
pub fn filtered_heights(scene: &Scene, sigma: f32) -> crate::error::Result<Scene> {
    let (width, depth) = (scene.width as usize, scene.depth as usize);
    let mut heights = scene.heights.clone();
    let taps = gaussian(sigma);
    let mut scratch = Vec::new();
    if taps.len() > 1 {
        for y in 0..depth {
            blur_line(&mut heights, y * width, 1, width, &taps, &mut scratch);
        }
        for x in 0..width {
            blur_line(&mut heights, x, width, depth, &taps, &mut scratch);
        }
    }
    Scene::new(scene.width, scene.depth, heights, scene.colors.clone())
}

/// Which of Qu's two modes renders.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mode {
    /// The density volume, trilinear, the hit refined between samples.
    Accurate,
    /// The boundary array alone.
    Approximate,
}

/// What a sample of a ray finds.
enum Found {
    Air,
    Ground,
    /// Off the map's columns.
    Outside,
}

/// Renders `camera`'s view of `volume` (made from `scene`, whose colors
/// drape it) in `mode`.
pub fn render_volume(
    scene: &Scene,
    volume: &TerrainVolume,
    camera: &Camera,
    size: (u32, u32),
    options: &VolumeOptions,
    mode: Mode,
) -> (Frame, RenderStats) {
    render_volume_touching(scene, volume, camera, size, options, mode, &mut |_, _| {})
}

/// [`render_volume`], calling `touch` with the cell column (`y · width +
/// x`) and layer of every sample that reads the boundary array (a no-op
/// closure compiles away).
pub fn render_volume_touching(
    scene: &Scene,
    volume: &TerrainVolume,
    camera: &Camera,
    size: (u32, u32),
    options: &VolumeOptions,
    mode: Mode,
    touch: &mut impl FnMut(usize, i32),
) -> (Frame, RenderStats) {
    let started = Instant::now();
    let (width, height) = size;
    let rays = ContractCamera::new(camera, width, height);
    let mut frame = Frame::new(width, height);
    frame.colors.fill(options.sky);
    let eye = rays.eye.map(|v| v as f32);
    let (map_w, map_d) = ((volume.width - 1) as f32, (volume.depth - 1) as f32);
    let top = volume.base + (volume.layers - 1) as f32 * volume.layer;
    let interval = options.interval.max(1e-3);
    let threshold = f32::from(THRESHOLD);
    let mut samples = 0u64;
    let mut sample = |p: [f32; 3]| -> Found {
        if !(0.0..=map_w).contains(&p[0]) || !(0.0..=map_d).contains(&p[1]) {
            return Found::Outside;
        }
        let kz = (p[2] - volume.base) / volume.layer;
        let (ix, iy) = (
            (p[0] as usize).min(volume.width - 2),
            (p[1] as usize).min(volume.depth - 2),
        );
        let column = iy * volume.width + ix;
        touch(column, kz as i32);
        let [lowest, highest] = volume.boundary[column];
        if kz >= f32::from(highest) + 1.0 || kz >= (volume.layers - 1) as f32 {
            return Found::Air;
        }
        if kz < f32::from(lowest) || kz < 0.0 || mode == Mode::Approximate {
            return Found::Ground;
        }
        if volume.density_at(p) >= threshold {
            Found::Ground
        } else {
            Found::Air
        }
    };
    // Vertical planes for coherence: the kernel's image lines through the
    // vertical's vanishing point, whose pixels come in the order their
    // rays reach farther (image columns, bottom to top, where the camera
    // is level). A camera the kernel refuses renders column by column.
    let view = View::new(camera, width, height).ok();
    let lines: Vec<Vec<(u32, u32)>> = match &view {
        Some(view) => (0..view.lines())
            .map(|i| view.line_pixels(i).collect())
            .collect(),
        None => (0..width)
            .map(|x| (0..height).rev().map(|y| (x, y)).collect())
            .collect(),
    };
    for line in &lines {
        // Where the ray before hit, from the eye: the next one starts there.
        let mut resume: Option<f32> = None;
        for &(px, py) in line {
            let d = rays.direction(f64::from(px) + 0.5, f64::from(py) + 0.5);
            let n = length(d);
            let d = d.map(|v| (v / n) as f32);
            let Some((enter, exit)) = clip(eye, d, [map_w, map_d], [volume.base, top]) else {
                if options.coherence && resume.is_some() {
                    break;
                }
                continue;
            };
            let at = |t: f32| core::array::from_fn(|i| eye[i] + d[i] * t);
            let mut t = resume
                .filter(|_| options.coherence)
                .map_or(enter, |r| r.max(enter));
            let mut found = sample(at(t));
            samples += 1;
            // Started inside the terrain: retrace back to the air.
            let mut inside = None;
            if let Found::Ground = found {
                inside = Some(t);
                loop {
                    let back = t - interval;
                    if back < enter {
                        break;
                    }
                    samples += 1;
                    match sample(at(back)) {
                        Found::Ground => inside = Some(back),
                        other => {
                            found = other;
                            t = back;
                            break;
                        }
                    }
                    t = back;
                }
            }
            let hit = loop {
                if let Some(hit) = inside.take() {
                    break Some((hit, t, &found));
                }
                let next = t + interval;
                if next > exit {
                    break None;
                }
                samples += 1;
                match sample(at(next)) {
                    Found::Ground => inside = Some(next),
                    other => {
                        found = other;
                        t = next;
                    }
                }
            };
            let Some((t_in, t_air, air)) = hit else {
                // A ray that left the volume without a hit: the rays after
                // it on the line are higher, and see the sky too (the
                // coherence argument once more, as the kernel's sky span).
                if options.coherence {
                    break;
                }
                continue;
            };
            // Between the last sample in air and the first inside, by
            // their densities (the approximate mode stops at the sample).
            // (A sample the boundary array called air or terrain has no
            // density of its own: both ends are read from the volume.)
            let t_hit = match (mode, air) {
                (Mode::Accurate, Found::Air) if t_in > t_air => {
                    let (density_air, density_in) =
                        (volume.density_at(at(t_air)), volume.density_at(at(t_in)));
                    let f = ((threshold - density_air) / (density_in - density_air).max(1e-3))
                        .clamp(0.0, 1.0);
                    t_air + (t_in - t_air) * f
                }
                _ => t_in,
            };
            let p = at(t_hit);
            let color = scene.color_at(f64::from(p[0]), f64::from(p[1]));
            let index = py as usize * width as usize + px as usize;
            frame.colors[index] = color.map(|v| v.round().clamp(0.0, 255.0) as u8);
            frame.depth[index] = t_hit;
            resume = Some(t_hit);
        }
    }
    let stats = RenderStats {
        method: match mode {
            Mode::Accurate => "volume",
            Mode::Approximate => "boundary",
        },
        pixels: u64::from(width) * u64::from(height),
        rays: u64::from(width) * u64::from(height),
        steps: samples,
        resident_bytes: volume.boundary_bytes()
            + match mode {
                Mode::Accurate => volume.volume_bytes(),
                Mode::Approximate => 0,
            }
            + scene.colors.len() as u64 * 3,
        render_ns: started.elapsed().as_nanos() as u64,
        levels: None,
    };
    (frame, stats)
}

/// The stretch of the ray from `eye` along unit `d` inside the box
/// `[0, size[0]] × [0, size[1]] × heights`: (enter, exit) distances.
fn clip(eye: [f32; 3], d: [f32; 3], size: [f32; 2], heights: [f32; 2]) -> Option<(f32, f32)> {
    let bounds = [(0.0, size[0]), (0.0, size[1]), (heights[0], heights[1])];
    let (mut enter, mut exit) = (0.0f32, f32::MAX);
    for (axis, &(lo, hi)) in bounds.iter().enumerate() {
        if d[axis].abs() < 1e-9 {
            if eye[axis] < lo || eye[axis] > hi {
                return None;
            }
            continue;
        }
        let (a, b) = ((lo - eye[axis]) / d[axis], (hi - eye[axis]) / d[axis]);
        enter = enter.max(a.min(b));
        exit = exit.min(a.max(b));
    }
    (enter <= exit).then_some((enter, exit))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::metrics::psnr;
    use crate::reference::{Reference, ReferenceOptions};

    fn plane_scene(height: f32) -> Scene {
        let (w, d) = (32u32, 32u32);
        let colors = (0..w * d)
            .map(|i| [(i % w * 8) as u8, (i / w * 8) as u8, 100])
            .collect();
        Scene::new(w, d, vec![height; (w * d) as usize], colors).unwrap()
    }

    #[test]
    fn a_flat_terrain_is_hit_where_it_is() {
        // A plane at 10.3: the filtered step's threshold is the plane
        // itself, between layers.
        let scene = plane_scene(10.3);
        let options = VolumeOptions::default();
        let volume = TerrainVolume::build(&scene, &options);
        let camera = Camera::looking([16.0, 2.0, 20.0], 90.0, 40.0);
        for mode in [Mode::Accurate, Mode::Approximate] {
            let (frame, stats) = render_volume(&scene, &volume, &camera, (24, 16), &options, mode);
            let rays = ContractCamera::new(&camera, 24, 16);
            let mut worst: f32 = 0.0;
            for (i, &t) in frame.depth.iter().enumerate() {
                if !t.is_finite() {
                    continue;
                }
                let (x, y) = ((i % 24) as f64 + 0.5, (i / 24) as f64 + 0.5);
                let d = rays.direction(x, y);
                let z = 20.0 + d[2] / length(d) * f64::from(t);
                worst = worst.max((z as f32 - 10.3).abs());
            }
            let bound = match mode {
                Mode::Accurate => 0.05,
                // A sample inside a boundary cell: within a layer of it.
                Mode::Approximate => volume.layer() + options.interval,
            };
            assert!(worst < bound, "{mode:?}: off by {worst}");
            assert!(stats.steps > 0);
        }
    }

    #[test]
    fn coherence_finds_the_hits_a_ray_from_the_eye_finds() {
        // A rugged scene, level, tilted and steep: the ray before hit
        // nearer than the next one starts; where the start is inside, the
        // retrace finds the surface.
        let scene = crate::scene::procedural(128, 4);
        let volume = TerrainVolume::build(&scene, &VolumeOptions::default());
        for pitch in [0.0, 20.0, 60.0] {
            let camera = Camera::looking([64.0, 5.0, scene.max_height() + 5.0], 90.0, pitch);
            let frame = |coherence| {
                let options = VolumeOptions {
                    coherence,
                    ..VolumeOptions::default()
                };
                render_volume(&scene, &volume, &camera, (64, 48), &options, Mode::Accurate)
            };
            let ((coherent, fast), (from_eye, slow)) = (frame(true), frame(false));
            let same = coherent
                .colors
                .iter()
                .zip(&from_eye.colors)
                .filter(|(a, b)| a == b)
                .count();
            // Samples half a voxel apart step over thin crests at other
            // places when they start elsewhere: a few pixels differ.
            assert!(same * 100 >= 98 * 64 * 48, "pitch {pitch}: {same} the same");
            assert!(fast.steps < slow.steps, "pitch {pitch}");
            let reference = Reference::new(&scene).render(
                &camera,
                64,
                48,
                &ReferenceOptions {
                    supersample: 1,
                    sky: VolumeOptions::default().sky,
                    ..ReferenceOptions::default()
                },
            );
            assert!(
                psnr(&coherent.colors, &reference.0.colors) > 25.0,
                "pitch {pitch}"
            );
        }
    }

    #[test]
    fn the_volume_spans_the_heights_and_its_boundary_cells_hold_the_surface() {
        let scene = crate::scene::procedural(64, 2);
        let volume = TerrainVolume::build(&scene, &VolumeOptions::default());
        assert!(volume.layers() >= 2 && volume.layers() <= 64 + 16);
        for y in 0..63 {
            for x in 0..63 {
                let [low, high] = volume.boundary[y * 64 + x];
                assert!(low <= high, "a boundary cell in every column");
                let h = scene.height(x, y);
                let cell_top = volume.base + (f32::from(high) + 1.0) * volume.layer;
                assert!(
                    h <= cell_top + 1.0,
                    "{h} above the highest boundary cell {cell_top}"
                );
            }
        }
        assert_eq!(volume.volume_bytes(), 64 * 64 * volume.layers() as u64);
    }
}
