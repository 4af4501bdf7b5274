//! The post-rendering warp (Cohen-Or §4): a frame rendered for one camera,
//! shown from a nearby one.
//!
//! Cohen-Or rendered at 10–15 Hz and displayed at 30 Hz: a post-rendering
//! processor warped the last frame toward the camera of the display time
//! with a second-degree polynomial fitted by least squares to nine control
//! points. Here:
//!
//! 1. [`control_points`] takes the terrain points seen at nine fixed image
//!    positions of the rendered frame (a 3 × 3 grid), from the distances a
//!    [`Framebuffer`](crate::Framebuffer) keeps; sky is a direction at
//!    infinity.
//! 2. [`Warp::fit`] projects them into the display camera and fits, by
//!    least squares, `x_r = f_x(x_d, y_d)` and `y_r = f_y(x_d, y_d)`, each
//!    `c0 + c1·x + c2·y + c3·x² + c4·x·y + c5·y²`: where in the rendered
//!    frame each display pixel is found. The fit is float (glam), once a
//!    frame.
//! 3. [`Warp::apply`] evaluates the polynomials by forward differences and
//!    samples the rendered frame bilinearly, in fixed point. The frame is
//!    rendered wider than the display (margins, see [`with_margin`]), so a
//!    warp rarely samples outside it; where it does, the nearest edge pixel
//!    is used.

use crate::color::Rgb;
use crate::sink::Sample;
use crate::view::Camera;
use core::fmt;
use glam::DVec3;

/// A terrain point seen at a position of the rendered frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ControlPoint {
    /// Pixel position in the rendered frame (x right, y down, pixel
    /// centers at whole numbers).
    pub at: [f64; 2],
    /// The world point seen there, or `None` for sky (then the direction
    /// through `at` is taken at infinity).
    pub point: Option<[f64; 3]>,
}

/// Why a warp could not be fitted.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum WarpError {
    /// Fewer than six control points are in front of the display camera.
    TooFewPoints,
    /// The points do not determine the polynomials (for instance all on a
    /// line).
    Degenerate,
}

impl fmt::Display for WarpError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::TooFewPoints => {
                "fewer than six control points are in front of the display camera"
            }
            Self::Degenerate => "the control points do not determine a warp",
        })
    }
}

impl core::error::Error for WarpError {}

/// The camera of a frame rendered `margin` times wider and taller than a
/// display of `size` seen by `camera`: same eye and angles, a wider field of
/// view, and the image size to keep the pixel size.
pub fn with_margin(camera: &Camera, size: (u32, u32), margin: f32) -> (Camera, (u32, u32)) {
    let margin = margin.clamp(1.0, 4.0);
    let half = f64::from(camera.hfov_deg).to_radians() * 0.5;
    let wide = 2.0 * libm::atan(libm::tan(half) * f64::from(margin));
    let grow = |n: u32| ((f64::from(n) * f64::from(margin)) as u32).max(n);
    (
        Camera {
            // Not `f32::min`, which would turn a NaN field into the
            // widest one: a bad camera stays bad, for `View::new` to refuse.
            hfov_deg: match wide.to_degrees() as f32 {
                deg if deg > crate::config::HFOV_RANGE_DEG.1 => crate::config::HFOV_RANGE_DEG.1,
                deg => deg,
            },
            ..*camera
        },
        (grow(size.0), grow(size.1)),
    )
}

/// A camera's frame as vectors: eye, forward, right, up, and the tangent of
/// half the horizontal field of view; the same conventions as
/// [`View`](crate::View).
#[derive(Debug, Clone, Copy)]
struct Basis {
    eye: DVec3,
    forward: DVec3,
    right: DVec3,
    up: DVec3,
    tangent: f64,
    size: (f64, f64),
}

impl Basis {
    fn new(camera: &Camera, size: (u32, u32)) -> Self {
        let [forward, right, up] = camera.axes();
        Self {
            eye: DVec3::from(camera.eye.map(f64::from)),
            forward,
            right,
            up,
            tangent: libm::tan(f64::from(camera.hfov_deg).to_radians() * 0.5),
            size: (f64::from(size.0), f64::from(size.1)),
        }
    }

    /// The direction through pixel position `(x, y)` (y down).
    fn direction(&self, x: f64, y: f64) -> DVec3 {
        let (w, h) = self.size;
        let a = (2.0 * x + 1.0) / w - 1.0;
        let b = 1.0 - (2.0 * y + 1.0) / h;
        self.forward + self.right * (a * self.tangent) + self.up * (b * self.tangent * h / w)
    }

    /// Where direction `v` from the eye lands on the image, if in front.
    fn project(&self, v: DVec3) -> Option<(f64, f64)> {
        let z = v.dot(self.forward);
        if z <= 1e-9 {
            return None;
        }
        let (w, h) = self.size;
        let a = v.dot(self.right) / (z * self.tangent);
        let b = v.dot(self.up) / (z * self.tangent * h / w);
        Some(((a + 1.0) * w * 0.5 - 0.5, (1.0 - b) * h * 0.5 - 0.5))
    }
}

/// The nine control points of a frame rendered by `camera` at `size`: the
/// pixels at 1/6, 1/2 and 5/6 of the width and height, with the world points
/// their `samples` (row-major, from a framebuffer with distances) saw.
pub fn control_points(
    camera: &Camera,
    size: (u32, u32),
    samples: impl Fn(u32, u32) -> Option<Sample>,
) -> [ControlPoint; 9] {
    let basis = Basis::new(camera, size);
    core::array::from_fn(|i| {
        let (x, y) = (
            (size.0 * (2 * (i as u32 % 3) + 1)) / 6,
            (size.1 * (2 * (i as u32 / 3) + 1)) / 6,
        );
        let point = samples(x, y).filter(|s| !s.is_sky()).map(|s| {
            // The sample's distance is along the ray's major axis.
            let d = basis.direction(f64::from(x), f64::from(y));
            let major = d.x.abs().max(d.y.abs()).max(1e-12);
            let p = basis.eye + d * (f64::from(s.distance) / 65536.0 / major);
            [p.x, p.y, p.z]
        });
        ControlPoint {
            at: [f64::from(x), f64::from(y)],
            point,
        }
    })
}

/// Where in the rendered frame each display pixel is found: two quadratic
/// polynomials of the display position.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Warp {
    /// `f_x` and `f_y`: coefficients of `1, x, y, x², x·y, y²`.
    coefficients: [[f64; 6]; 2],
}

impl Warp {
    /// The warp that shows the frame rendered by `rendered` (at
    /// `rendered_size`, whose `points` are its control points) from
    /// `display` at `display_size`.
    pub fn fit(
        rendered: &Camera,
        rendered_size: (u32, u32),
        display: &Camera,
        display_size: (u32, u32),
        points: &[ControlPoint],
    ) -> Result<Self, WarpError> {
        let source = Basis::new(rendered, rendered_size);
        let target = Basis::new(display, display_size);
        // Normal equations of the least-squares fit, both polynomials.
        let mut normal = [[0.0f64; 6]; 6];
        let mut right = [[0.0f64; 6]; 2];
        let mut used = 0;
        for point in points {
            let v = match point.point {
                Some(p) => DVec3::from(p) - target.eye,
                None => source.direction(point.at[0], point.at[1]),
            };
            let Some((x, y)) = target.project(v) else {
                continue;
            };
            // Scaled to about ±1 for a well-conditioned system.
            let basis = monomials(x / target.size.0, y / target.size.1);
            for r in 0..6 {
                for c in 0..6 {
                    normal[r][c] += basis[r] * basis[c];
                }
                right[0][r] += basis[r] * point.at[0];
                right[1][r] += basis[r] * point.at[1];
            }
            used += 1;
        }
        if used < 6 {
            return Err(WarpError::TooFewPoints);
        }
        let mut coefficients = [[0.0; 6]; 2];
        for (axis, rhs) in right.iter().enumerate() {
            let solved = solve(normal, *rhs).ok_or(WarpError::Degenerate)?;
            // Undo the scaling: c·(x/w)^i (y/h)^j.
            let (w, h) = target.size;
            let scale = [
                1.0,
                1.0 / w,
                1.0 / h,
                1.0 / (w * w),
                1.0 / (w * h),
                1.0 / (h * h),
            ];
            for ((c, s), k) in coefficients[axis].iter_mut().zip(solved).zip(scale) {
                *c = s * k;
            }
        }
        Ok(Self { coefficients })
    }

    /// Where display pixel `(x, y)` is found in the rendered frame.
    pub fn source_of(&self, x: f64, y: f64) -> (f64, f64) {
        let m = monomials(x, y);
        let eval = |c: &[f64; 6]| c.iter().zip(m).map(|(c, m)| c * m).sum::<f64>();
        (eval(&self.coefficients[0]), eval(&self.coefficients[1]))
    }

    /// Fills `display` (row-major, `display_size`) from `rendered`
    /// (row-major, `rendered_size`): each pixel samples the rendered frame
    /// bilinearly where the warp sends it, or its nearest edge pixel
    /// outside it. Fixed point per pixel; a short buffer is left as is.
    pub fn apply(
        &self,
        rendered: &[Rgb],
        rendered_size: (u32, u32),
        display: &mut [Rgb],
        display_size: (u32, u32),
    ) {
        let (sw, sh) = (rendered_size.0 as i64, rendered_size.1 as i64);
        let (dw, dh) = (display_size.0 as usize, display_size.1 as usize);
        if rendered.len() < (sw * sh) as usize || display.len() < dw * dh || sw == 0 || sh == 0 {
            return;
        }
        // Forward differences along a row in Q24: value, first and second
        // difference of each polynomial.
        const ONE: f64 = (1u64 << 24) as f64;
        let q = |v: f64| (v * ONE).clamp(-9.0e18, 9.0e18) as i64;
        for (y, row) in display.chunks_exact_mut(dw).take(dh).enumerate() {
            let y = y as f64;
            let mut axes = self.coefficients.map(|c| {
                // f(x) = A + B·x + C·x² on this row.
                let (a, b, cc) = (c[0] + c[2] * y + c[5] * y * y, c[1] + c[4] * y, c[3]);
                [q(a), q(b + cc), q(2.0 * cc)]
            });
            for pixel in row.iter_mut() {
                *pixel = bilinear(rendered, sw, sh, axes[0][0], axes[1][0]);
                for axis in axes.iter_mut() {
                    axis[0] = axis[0].saturating_add(axis[1]);
                    axis[1] = axis[1].saturating_add(axis[2]);
                }
            }
        }
    }
}

/// `1, x, y, x², x·y, y²`.
fn monomials(x: f64, y: f64) -> [f64; 6] {
    [1.0, x, y, x * x, x * y, y * y]
}

/// Solves `a·c = b` by Gaussian elimination with partial pivoting.
fn solve(mut a: [[f64; 6]; 6], mut b: [f64; 6]) -> Option<[f64; 6]> {
    for col in 0..6 {
        let pivot = (col..6).max_by(|&i, &j| a[i][col].abs().total_cmp(&a[j][col].abs()))?;
        if a[pivot][col].abs() < 1e-12 {
            return None;
        }
        a.swap(col, pivot);
        b.swap(col, pivot);
        let (upper, lower) = a.split_at_mut(col + 1);
        let pivot_row = &upper[col];
        for (row, below) in lower.iter_mut().enumerate() {
            let f = below[col] / pivot_row[col];
            for (x, p) in below.iter_mut().zip(pivot_row).skip(col) {
                *x -= f * p;
            }
            b[col + 1 + row] -= f * b[col];
        }
    }
    let mut c = [0.0; 6];
    for row in (0..6).rev() {
        let rest: f64 = (row + 1..6).map(|k| a[row][k] * c[k]).sum();
        c[row] = (b[row] - rest) / a[row][row];
    }
    c.iter().all(|v| v.is_finite()).then_some(c)
}

/// The rendered frame at `(x, y)` (Q24 pixels), bilinear, clamped to its
/// edge.
#[inline]
fn bilinear(frame: &[Rgb], w: i64, h: i64, x: i64, y: i64) -> Rgb {
    // Q24 to Q8: 8 bits of blend weight.
    let (x8, y8) = (
        (x >> 16).clamp(0, (w - 1) << 8),
        (y >> 16).clamp(0, (h - 1) << 8),
    );
    let (x0, y0) = (x8 >> 8, y8 >> 8);
    let (fx, fy) = ((x8 & 255) as u32, (y8 & 255) as u32);
    let (x1, y1) = ((x0 + 1).min(w - 1), (y0 + 1).min(h - 1));
    let at = |x: i64, y: i64| frame.get((y * w + x) as usize).copied().unwrap_or_default();
    let (c00, c10, c01, c11) = (at(x0, y0), at(x1, y0), at(x0, y1), at(x1, y1));
    core::array::from_fn(|i| {
        let top = u32::from(c00[i]) * (256 - fx) + u32::from(c10[i]) * fx;
        let bottom = u32::from(c01[i]) * (256 - fx) + u32::from(c11[i]) * fx;
        ((top * (256 - fy) + bottom * fy + (1 << 15)) >> 16) as u8
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_nan_field_of_view_stays_nan_for_the_view_to_refuse() {
        let camera = Camera {
            hfov_deg: f32::NAN,
            ..Camera::looking([10.0, 10.0, 50.0], 0.0, 10.0)
        };
        let (wide, _) = with_margin(&camera, (64, 48), 1.2);
        assert!(wide.hfov_deg.is_nan());
        assert!(crate::View::new(&wide, 64, 48).is_err());
        let (widest, _) = with_margin(
            &Camera {
                hfov_deg: 159.0,
                ..camera
            },
            (64, 48),
            1.2,
        );
        assert_eq!(widest.hfov_deg, crate::config::HFOV_RANGE_DEG.1);
    }

    /// Control points of a flat ground at height 0 seen by `camera`.
    fn ground_points(camera: &Camera, size: (u32, u32)) -> [ControlPoint; 9] {
        let basis = Basis::new(camera, size);
        core::array::from_fn(|i| {
            let at = [
                f64::from(size.0 * (2 * (i as u32 % 3) + 1) / 6),
                f64::from(size.1 * (2 * (i as u32 / 3) + 1) / 6),
            ];
            let d = basis.direction(at[0], at[1]);
            let point = (d.z < 0.0).then(|| {
                let p = basis.eye + d * (-basis.eye.z / d.z);
                [p.x, p.y, p.z]
            });
            ControlPoint { at, point }
        })
    }

    #[test]
    fn the_same_camera_maps_the_display_into_the_middle_of_the_margins() {
        let display = Camera::looking([0.0, 0.0, 50.0], 30.0, 20.0);
        let (rendered, size) = with_margin(&display, (40, 30), 1.25);
        assert_eq!(size, (50, 37));
        let warp = Warp::fit(
            &rendered,
            size,
            &display,
            (40, 30),
            &ground_points(&rendered, size),
        )
        .unwrap();
        // The display's center pixel lies at the rendered frame's center,
        // and a display pixel step is a rendered pixel step.
        let (x, y) = warp.source_of(19.5, 14.5);
        assert!((x - 24.5).abs() < 0.05 && (y - 18.0).abs() < 0.1, "{x} {y}");
        let (x2, _) = warp.source_of(20.5, 14.5);
        assert!((x2 - x - 1.0).abs() < 0.01, "{}", x2 - x);
    }

    #[test]
    fn a_turned_camera_finds_its_pixels_where_the_ground_points_are() {
        let rendered_cam = Camera::looking([0.0, 0.0, 60.0], 0.0, 30.0);
        let (rendered, size) = with_margin(&rendered_cam, (64, 48), 1.3);
        let display = Camera::looking([2.0, 1.0, 60.0], 3.0, 31.0);
        let points = ground_points(&rendered, size);
        let warp = Warp::fit(&rendered, size, &display, (64, 48), &points).unwrap();
        // The ground is a plane: a homography, which the quadratic follows
        // to well under a pixel here.
        assert_points_map_back(&warp, &display, (64, 48), &points);
    }

    /// Every control point's display position maps back to within half a
    /// pixel of where it was rendered.
    fn assert_points_map_back(
        warp: &Warp,
        display: &Camera,
        size: (u32, u32),
        points: &[ControlPoint],
    ) {
        let target = Basis::new(display, size);
        for p in points {
            let world = DVec3::from(p.point.unwrap());
            let (x, y) = target.project(world - target.eye).unwrap();
            let (sx, sy) = warp.source_of(x, y);
            assert!(
                (sx - p.at[0]).abs() < 0.5 && (sy - p.at[1]).abs() < 0.5,
                "{p:?}: {sx} {sy}"
            );
        }
    }

    #[test]
    fn a_rolled_camera_is_a_rotation_the_margins_cover() {
        // Five degrees of bank between two frames (a bank rate of 150° a
        // second at 30 Hz, far past any flight's): every display pixel
        // finds its source inside the rendered frame with 1.2× margins,
        // and the ground points map back to where they were rendered.
        let rendered_cam = Camera {
            roll_deg: 10.0,
            ..Camera::looking([0.0, 0.0, 60.0], 0.0, 30.0)
        };
        let (rendered, size) = with_margin(&rendered_cam, (200, 150), 1.2);
        let display = Camera {
            roll_deg: 15.0,
            ..rendered_cam
        };
        let points = ground_points(&rendered, size);
        let warp = Warp::fit(&rendered, size, &display, (200, 150), &points).unwrap();
        assert_points_map_back(&warp, &display, (200, 150), &points);
        for (x, y) in [(0.0, 0.0), (199.0, 0.0), (0.0, 149.0), (199.0, 149.0)] {
            let (sx, sy) = warp.source_of(x, y);
            let inside = (0.0..=f64::from(size.0 - 1)).contains(&sx)
                && (0.0..=f64::from(size.1 - 1)).contains(&sy);
            assert!(inside, "corner ({x}, {y}) samples ({sx}, {sy}) of {size:?}");
        }
    }

    #[test]
    fn apply_samples_bilinearly_and_clamps_to_the_edge() {
        // A horizontal ramp 0, 10, 20, ... in red.
        let rendered: std::vec::Vec<Rgb> = (0..8 * 4).map(|i| [(i % 8 * 10) as u8, 0, 0]).collect();
        // Shift by half a pixel right: x_r = x_d + 0.5.
        let warp = Warp {
            coefficients: [
                [0.5, 1.0, 0.0, 0.0, 0.0, 0.0],
                [0.0, 0.0, 1.0, 0.0, 0.0, 0.0],
            ],
        };
        let mut display = [[0u8; 3]; 8 * 4];
        warp.apply(&rendered, (8, 4), &mut display, (8, 4));
        assert_eq!(display[0], [5, 0, 0]);
        assert_eq!(display[3], [35, 0, 0]);
        // Past the right edge: the edge pixel.
        assert_eq!(display[7], [70, 0, 0]);
        // A curved warp evaluated by differences equals direct evaluation.
        let warp = Warp {
            coefficients: [
                [1.0, 0.9, 0.1, 0.01, 0.02, 0.0],
                [0.5, 0.05, 1.1, 0.0, 0.01, 0.005],
            ],
        };
        let rendered: std::vec::Vec<Rgb> = (0..64 * 64)
            .map(|i| [(i % 64 * 4) as u8, (i / 64 * 4) as u8, 0])
            .collect();
        let mut display = [[0u8; 3]; 40 * 30];
        warp.apply(&rendered, (64, 64), &mut display, (40, 30));
        for (i, got) in display.iter().enumerate() {
            let (x, y) = warp.source_of((i % 40) as f64, (i / 40) as f64);
            let expected = [(x.clamp(0.0, 63.0) * 4.0), (y.clamp(0.0, 63.0) * 4.0)];
            assert!(
                (f64::from(got[0]) - expected[0]).abs() <= 2.0,
                "{i}: {got:?} {expected:?}"
            );
            assert!(
                (f64::from(got[1]) - expected[1]).abs() <= 2.0,
                "{i}: {got:?} {expected:?}"
            );
        }
    }

    #[test]
    fn too_few_points_in_front_is_an_error() {
        let rendered = Camera::looking([0.0, 0.0, 60.0], 0.0, 30.0);
        let points = ground_points(&rendered, (32, 24));
        let behind = Camera::looking([0.0, 0.0, 60.0], 180.0, -30.0);
        assert_eq!(
            Warp::fit(&rendered, (32, 24), &behind, (32, 24), &points),
            Err(WarpError::TooFewPoints)
        );
    }
}
