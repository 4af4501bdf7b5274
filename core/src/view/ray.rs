//! Per-ray set-up: direction, major axis, fixed-point increments, clipping.
//!
//! Integer arithmetic only (one division per increment, per ray, as in
//! Cohen-Or's Figure 7). A ray samples the terrain on the grid lines of its
//! major axis: sample `k` lies on grid line `major0 + k·sign` at distance
//! `delta0 + k` voxels from the eye along that axis. Clipping bounds `k` so
//! that every sample the caster visits is inside the map and every
//! fixed-point value stays in range.

use super::View;
use crate::config::{COORD_FRAC_BITS, HEIGHT_FRAC_BITS, MAX_RAY_SLOPE};
use crate::terrain::Terrain;
use fixed::types::I16F16;

const ONE: i64 = 1 << COORD_FRAC_BITS;

/// Which family of grid lines a ray steps across. Two rays with the same key
/// number their samples identically, so one can resume where the other hit.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct RayKey {
    pub x_major: bool,
    pub forward: bool,
}

/// One ray, ready to traverse.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Ray {
    pub key: RayKey,
    /// Major-axis grid coordinate of sample 0.
    major0: i64,
    /// Distance from the eye to sample 0 along the major axis, Q16 in [0, 1).
    delta0: i64,
    /// Minor coordinate and height at sample 0, Q16.
    minor0: i64,
    z0: i64,
    /// Per-step increments of the minor coordinate and of the height.
    pub dminor: I16F16,
    pub dz: I16F16,
    /// First sample inside the map; may be −1 (one step behind the eye),
    /// which only the hit refinement reads.
    pub first: i32,
    /// First sample the traversal visits.
    pub start: i32,
    /// Last sample where a hit is possible.
    pub end: i32,
}

/// Where sample `k` of a ray is: the voxel index of its grid-line start
/// (`base + floor(minor)·minor_stride`), the minor coordinate and the height.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Cursor {
    pub k: i32,
    pub base: isize,
    pub minor: I16F16,
    pub z: I16F16,
}

/// Index arithmetic of one ray's grid lines on one terrain.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Strides {
    /// Voxel-index change per step along the ray (±1 or ±width).
    pub step: isize,
    /// Voxel-index change across a minor grid line (width or 1).
    pub minor: isize,
    /// Voxel-index change per major grid coordinate (1 or width).
    major: isize,
}

impl View {
    /// Sets up the ray of pixel column `column`, `row` rows above the bottom.
    pub(crate) fn ray(&self, terrain: &Terrain<'_>, column: u32, row: u32) -> Ray {
        let d: [i64; 3] = core::array::from_fn(|i| {
            self.base[i].to_bits()
                + self.per_column[i].to_bits() * i64::from(column)
                + self.per_row[i].to_bits() * i64::from(row)
        });
        let x_major = d[0].abs() >= d[1].abs();
        let (d_major, d_minor) = if x_major { (d[0], d[1]) } else { (d[1], d[0]) };
        let forward = d_major >= 0;
        let run = d_major.abs();
        let max_slope = i64::from(MAX_RAY_SLOPE) << COORD_FRAC_BITS;
        // Directions are I32F32 below 2^7 in magnitude, so `<< 16` cannot
        // overflow; |d_minor| <= run keeps the minor slope within ±1.
        let (dminor, dz) = if run == 0 {
            (0, if d[2] < 0 { -max_slope } else { max_slope })
        } else {
            (
                (d_minor << COORD_FRAC_BITS) / run,
                ((d[2] << COORD_FRAC_BITS) / run).clamp(-max_slope, max_slope),
            )
        };

        let [ex, ey, ez] = self.eye.map(|v| v.to_bits());
        let (e_major, e_minor) = if x_major { (ex, ey) } else { (ey, ex) };
        let (major0, delta0) = if forward {
            let m = (e_major + ONE - 1) >> COORD_FRAC_BITS;
            (m, (m << COORD_FRAC_BITS) - e_major)
        } else {
            let m = e_major >> COORD_FRAC_BITS;
            (m, e_major - (m << COORD_FRAC_BITS))
        };
        let minor0 = e_minor + ((delta0 * dminor) >> COORD_FRAC_BITS);
        let z0 = ez + ((delta0 * dz) >> COORD_FRAC_BITS);

        let (major_len, minor_len) = if x_major {
            (terrain.width(), terrain.depth())
        } else {
            (terrain.depth(), terrain.width())
        };
        // Samples inside the map: 0 <= major <= len-1 and 0 <= minor < len-1,
        // so that the neighbour across the minor grid line exists too.
        let (mut first, mut last) = (-1i64, i64::MAX);
        let major_last = i64::from(major_len) - 1;
        let (lo, hi) = if forward {
            (-major0, major_last - major0)
        } else {
            (major0 - major_last, major0)
        };
        first = first.max(lo);
        last = last.min(hi);
        let minor_max = ((i64::from(minor_len) - 1) << COORD_FRAC_BITS) - 1;
        match dminor.signum() {
            1 => {
                first = first.max(div_ceil(-minor0, dminor));
                last = last.min(div_floor(minor_max - minor0, dminor));
            }
            -1 => {
                first = first.max(div_ceil(minor_max - minor0, dminor));
                last = last.min(div_floor(-minor0, dminor));
            }
            _ if (0..=minor_max).contains(&minor0) => {}
            _ => last = first - 1,
        }
        let start = first.max(0);
        // A hit needs the ray at or below the highest height; a falling ray
        // is certainly below the surface once its height is <= 0.
        let top = i64::from(terrain.max_height()) << (COORD_FRAC_BITS - HEIGHT_FRAC_BITS);
        let end = match dz.signum() {
            1 => last.min(div_floor(top - z0, dz)),
            0 if z0 > top => start - 1,
            0 => last,
            _ => last.min(start.max(div_ceil(z0, -dz))),
        };

        let narrow = |v: i64| v.clamp(-(1 << 20), 1 << 20) as i32;
        Ray {
            key: RayKey { x_major, forward },
            major0,
            delta0,
            minor0,
            z0,
            dminor: I16F16::from_bits(dminor as i32),
            dz: I16F16::from_bits(dz as i32),
            first: narrow(first),
            start: narrow(start),
            end: narrow(end),
        }
    }
}

impl Ray {
    /// The voxel-index strides of this ray on a map `width` voxels wide.
    pub fn strides(&self, width: u32) -> Strides {
        let width = width as isize;
        let (major, minor) = if self.key.x_major {
            (1, width)
        } else {
            (width, 1)
        };
        Strides {
            step: if self.key.forward { major } else { -major },
            minor,
            major,
        }
    }

    /// The position of sample `k`, computed directly (not by stepping), so a
    /// resumed ray sees exactly the values it would have reached by walking.
    pub fn cursor(&self, k: i32, strides: &Strides) -> Cursor {
        let k64 = i64::from(k);
        let major = if self.key.forward {
            self.major0 + k64
        } else {
            self.major0 - k64
        };
        // Inside [first, end] both values are in range by construction; the
        // clamp keeps an out-of-range request harmless (it reads as far
        // below the surface, or as outside the map).
        let fit = |v: i64| v.clamp(i64::from(i32::MIN), i64::from(i32::MAX)) as i32;
        Cursor {
            k,
            base: major as isize * strides.major,
            minor: I16F16::from_bits(fit(self.minor0 + k64 * i64::from(self.dminor.to_bits()))),
            z: I16F16::from_bits(fit(self.z0 + k64 * i64::from(self.dz.to_bits()))),
        }
    }

    /// Distance from the eye along the major axis to sample `k`, Q16, never
    /// negative.
    pub fn distance(&self, k: i32) -> i64 {
        (self.delta0 + (i64::from(k) << COORD_FRAC_BITS)).max(0)
    }
}

impl Cursor {
    /// Moves to the next sample along the ray.
    #[inline(always)]
    pub fn advance(&mut self, ray: &Ray, strides: &Strides) {
        self.k += 1;
        self.base += strides.step;
        self.minor += ray.dminor;
        self.z += ray.dz;
    }
}

fn div_floor(a: i64, b: i64) -> i64 {
    let q = a / b;
    if a % b != 0 && ((a < 0) != (b < 0)) {
        q - 1
    } else {
        q
    }
}

fn div_ceil(a: i64, b: i64) -> i64 {
    -div_floor(-a, b)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::view::Camera;

    #[test]
    fn floor_and_ceil_division_round_toward_infinities() {
        assert_eq!(div_floor(7, 2), 3);
        assert_eq!(div_floor(-7, 2), -4);
        assert_eq!(div_floor(7, -2), -4);
        assert_eq!(div_ceil(7, 2), 4);
        assert_eq!(div_ceil(-7, 2), -3);
        assert_eq!(div_ceil(-8, -2), 4);
    }

    fn flat(side: u32, height: u16) -> (std::vec::Vec<u16>, std::vec::Vec<[u8; 3]>) {
        let n = (side * side) as usize;
        (std::vec![height; n], std::vec![[0; 3]; n])
    }

    #[test]
    fn samples_inside_the_clip_range_are_inside_the_map() {
        let (h, c) = flat(16, 0);
        let terrain = Terrain::new(16, 16, &h, &c).unwrap();
        for yaw in [0.0, 37.0, 90.0, 150.0, 200.0, 271.0, 333.0] {
            let cam = Camera {
                eye: [-5.5, 7.25, 20.0],
                yaw_deg: yaw,
                pitch_deg: 10.0,
                ..Camera::default()
            };
            let view = View::new(&cam, 32, 8).unwrap();
            for col in 0..32 {
                for row in 0..8 {
                    let ray = view.ray(&terrain, col, row);
                    let s = ray.strides(16);
                    for k in ray.first..=ray.end {
                        let cur = ray.cursor(k, &s);
                        let idx = cur.base + (cur.minor.to_bits() >> 16) as isize * s.minor;
                        assert!(
                            idx >= 0 && ((idx + s.minor) as usize) < h.len(),
                            "yaw {yaw} k {k}"
                        );
                    }
                }
            }
        }
    }
}
