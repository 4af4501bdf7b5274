//! The camera of the view contract, turned once per frame into fixed point.
//!
//! Float math (glam, libm) lives here and nowhere else: [`View::new`] turns
//! the camera into three fixed-point direction vectors, and every ray of the
//! frame is derived from them with integer arithmetic only (see [`ray`]).

pub(crate) mod lines;
pub use lines::{max_lines, TableError};
pub(crate) mod lod;
pub(crate) mod plane;
pub(crate) mod ray;
pub(crate) mod words;

use crate::config::{
    HFOV_RANGE_DEG, MAX_EYE_COORD, MAX_EYE_HEIGHT, MAX_IMAGE_SIDE, MAX_VERTICAL_TANGENT,
    PITCH_RANGE_DEG, ROLL_RANGE_DEG,
};
use core::fmt;
use fixed::types::{I32F32, I48F16};
use glam::DVec3;

/// A camera as the view contract defines it: eye in voxels, angles in degrees.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Camera {
    /// Eye position (x, y, z) in voxel units.
    pub eye: [f32; 3],
    /// Heading, measured from +x toward +y.
    pub yaw_deg: f32,
    /// Angle below the horizon (positive looks down), −89° to +90°.
    pub pitch_deg: f32,
    /// Bank, positive = right wing down, −180° to +180°.
    pub roll_deg: f32,
    /// Full horizontal field of view.
    pub hfov_deg: f32,
}

impl Camera {
    /// Forward, right and up, the contract's camera axes (float, once a
    /// frame; the warp uses them too).
    pub(crate) fn axes(&self) -> [DVec3; 3] {
        let (yaw, pitch) = (
            f64::from(self.yaw_deg).to_radians(),
            f64::from(self.pitch_deg).to_radians(),
        );
        let (sy, cy) = (libm::sin(yaw), libm::cos(yaw));
        let (sp, cp) = (libm::sin(pitch), libm::cos(pitch));
        let forward = DVec3::new(cp * cy, cp * sy, -sp);
        let right = DVec3::new(-sy, cy, 0.0);
        let up = forward.cross(right);
        if self.roll_deg == 0.0 {
            return [forward, right, up];
        }
        // The view contract's bank: r = r₀ cos ρ − u₀ sin ρ, u = u₀ cos ρ + r₀ sin ρ.
        let roll = f64::from(self.roll_deg).to_radians();
        let (sr, cr) = (libm::sin(roll), libm::cos(roll));
        [forward, right * cr - up * sr, up * cr + right * sr]
    }

    /// A camera at `eye` heading `yaw_deg` and looking `pitch_deg` below
    /// the horizon, with the contract's defaults otherwise: no roll, a 60°
    /// field of view.
    ///
    /// ```
    /// use terracast::Camera;
    /// let camera = Camera::looking([512.0, 40.0, 180.0], 90.0, 12.0);
    /// assert_eq!((camera.roll_deg, camera.hfov_deg), (0.0, 60.0));
    /// ```
    pub const fn looking(eye: [f32; 3], yaw_deg: f32, pitch_deg: f32) -> Self {
        Self {
            eye,
            yaw_deg,
            pitch_deg,
            roll_deg: 0.0,
            hfov_deg: crate::config::DEFAULT_HFOV_DEG,
        }
    }

    /// The same camera turned level: pitch 0 and no roll, where the image
    /// columns are the images of vertical planes.
    ///
    /// ```
    /// use terracast::Camera;
    /// let camera = Camera { roll_deg: 30.0, ..Camera::looking([5.0, 6.0, 70.0], 45.0, 20.0) };
    /// assert_eq!(camera.turned_level(), Camera::looking([5.0, 6.0, 70.0], 45.0, 0.0));
    /// ```
    pub const fn turned_level(self) -> Self {
        Self {
            pitch_deg: 0.0,
            roll_deg: 0.0,
            ..self
        }
    }
}

impl Default for Camera {
    fn default() -> Self {
        Self::looking([0.0, 0.0, 100.0], 0.0, 0.0)
    }
}

/// Why a view could not be set up.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ViewError {
    /// A camera number is NaN or infinite.
    NotFinite,
    /// The eye is farther from the origin than the fixed-point range allows.
    EyeOutOfRange,
    /// Pitch outside −89° to +90°.
    PitchOutOfRange,
    /// Roll outside −180° to +180°.
    RollOutOfRange,
    /// Field of view outside 1° to 160°.
    FovOutOfRange,
    /// Image width or height is zero or above the largest side.
    ImageSize,
    /// The image is so tall for its width that the vertical field of view
    /// approaches 180°.
    AspectOutOfRange,
}

impl fmt::Display for ViewError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::NotFinite => "camera value is NaN or infinite",
            Self::EyeOutOfRange => "eye is outside |x|,|y| <= 32000, |z| <= 16000 voxels",
            Self::PitchOutOfRange => "pitch must be between -89 and 90 degrees",
            Self::RollOutOfRange => "roll must be between -180 and 180 degrees",
            Self::FovOutOfRange => "horizontal field of view must be between 1 and 160 degrees",
            Self::ImageSize => "image width and height must be between 1 and 8192",
            Self::AspectOutOfRange => "image is too tall for its width at this field of view",
        })
    }
}

impl core::error::Error for ViewError {}

/// One frame's camera in fixed point: everything a column needs.
///
/// The direction of the ray through pixel column `c`, `j` rows above the
/// bottom, is `base + c·per_column + j·per_row` (exact in `I32F32`), which is
/// the contract's `f + a·t·r + b·t·(H/W)·u` at the pixel center.
#[derive(Debug, Clone, Copy)]
pub struct View {
    pub(crate) eye: [I48F16; 3],
    pub(crate) base: [I32F32; 3],
    pub(crate) per_column: [I32F32; 3],
    pub(crate) per_row: [I32F32; 3],
    /// Pixels per unit of depth (`W / 2·tan(hfov/2)`), Q16: a voxel at depth
    /// `D` is `focal / D` pixels wide.
    pub(crate) focal: i64,
    /// The image lines through the vertical's vanishing point.
    pub(crate) lines: lines::Lines,
    width: u32,
    height: u32,
}

impl View {
    /// Validates the camera and image size and sets up the frame.
    pub fn new(camera: &Camera, width: u32, height: u32) -> Result<Self, ViewError> {
        let numbers = [
            camera.eye[0],
            camera.eye[1],
            camera.eye[2],
            camera.yaw_deg,
            camera.pitch_deg,
            camera.roll_deg,
            camera.hfov_deg,
        ];
        if numbers.iter().any(|v| !v.is_finite()) {
            return Err(ViewError::NotFinite);
        }
        if camera.eye[0].abs() > MAX_EYE_COORD
            || camera.eye[1].abs() > MAX_EYE_COORD
            || camera.eye[2].abs() > MAX_EYE_HEIGHT
        {
            return Err(ViewError::EyeOutOfRange);
        }
        if !(PITCH_RANGE_DEG.0..=PITCH_RANGE_DEG.1).contains(&camera.pitch_deg) {
            return Err(ViewError::PitchOutOfRange);
        }
        if !(ROLL_RANGE_DEG.0..=ROLL_RANGE_DEG.1).contains(&camera.roll_deg) {
            return Err(ViewError::RollOutOfRange);
        }
        if !(HFOV_RANGE_DEG.0..=HFOV_RANGE_DEG.1).contains(&camera.hfov_deg) {
            return Err(ViewError::FovOutOfRange);
        }
        if width == 0 || height == 0 || width > MAX_IMAGE_SIDE || height > MAX_IMAGE_SIDE {
            return Err(ViewError::ImageSize);
        }
        let tangent = libm::tan(f64::from(camera.hfov_deg).to_radians() * 0.5);
        let (w, h) = (f64::from(width), f64::from(height));
        if tangent * h / w > f64::from(MAX_VERTICAL_TANGENT) {
            return Err(ViewError::AspectOutOfRange);
        }

        let [forward, right, up] = camera.axes();
        let (pitch, roll) = (
            f64::from(camera.pitch_deg).to_radians(),
            f64::from(camera.roll_deg).to_radians(),
        );

        // Pixel (c, row j from the bottom) has a = (2c+1)/W − 1 and
        // b = (2j+1)/H − 1, so both advance by 2/W · t per pixel.
        let step = 2.0 * tangent / w;
        let base =
            forward + right * (tangent * (1.0 / w - 1.0)) + up * (tangent * (1.0 / w - h / w));
        let pixels = lines::PixelDirections {
            corner: base.to_array(),
            per_column: (right * step).to_array(),
            per_row: (up * step).to_array(),
        };
        Ok(Self {
            eye: camera.eye.map(|v| I48F16::from_num(v)),
            base: to_fixed(base),
            per_column: to_fixed(right * step),
            per_row: to_fixed(up * step),
            focal: (w / (2.0 * tangent) * 65536.0) as i64,
            lines: lines::Lines::new(width, height, pitch, tangent, roll, &pixels),
            width,
            height,
        })
    }

    /// Image width in pixels.
    pub fn width(&self) -> u32 {
        self.width
    }
    /// Image height in pixels.
    pub fn height(&self) -> u32 {
        self.height
    }
}

fn to_fixed(v: DVec3) -> [I32F32; 3] {
    [v.x, v.y, v.z].map(I32F32::from_num)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn camera() -> Camera {
        Camera {
            eye: [10.0, 20.0, 30.0],
            ..Camera::default()
        }
    }

    #[test]
    fn rejects_each_bad_parameter() {
        let ok = camera();
        assert!(View::new(&ok, 64, 48).is_ok());
        let cases = [
            (
                Camera {
                    yaw_deg: f32::NAN,
                    ..ok
                },
                ViewError::NotFinite,
            ),
            (
                Camera {
                    eye: [0.0, 0.0, f32::INFINITY],
                    ..ok
                },
                ViewError::NotFinite,
            ),
            (
                Camera {
                    eye: [40_000.0, 0.0, 0.0],
                    ..ok
                },
                ViewError::EyeOutOfRange,
            ),
            (
                Camera {
                    pitch_deg: 91.0,
                    ..ok
                },
                ViewError::PitchOutOfRange,
            ),
            (
                Camera {
                    pitch_deg: -90.0,
                    ..ok
                },
                ViewError::PitchOutOfRange,
            ),
            (
                Camera {
                    roll_deg: 180.5,
                    ..ok
                },
                ViewError::RollOutOfRange,
            ),
            (
                Camera {
                    hfov_deg: 0.0,
                    ..ok
                },
                ViewError::FovOutOfRange,
            ),
            (
                Camera {
                    hfov_deg: 179.0,
                    ..ok
                },
                ViewError::FovOutOfRange,
            ),
        ];
        for (cam, err) in cases {
            assert_eq!(View::new(&cam, 64, 48).unwrap_err(), err, "{cam:?}");
        }
        assert_eq!(View::new(&ok, 0, 48).unwrap_err(), ViewError::ImageSize);
        assert_eq!(View::new(&ok, 64, 9000).unwrap_err(), ViewError::ImageSize);
        assert_eq!(
            View::new(&ok, 1, 8000).unwrap_err(),
            ViewError::AspectOutOfRange
        );
    }

    #[test]
    fn center_ray_is_forward() {
        // An odd-sized image has a pixel centered on the optical axis.
        let cam = Camera {
            yaw_deg: 90.0,
            pitch_deg: 30.0,
            ..camera()
        };
        let view = View::new(&cam, 5, 3).unwrap();
        let d: [f64; 3] = core::array::from_fn(|i| {
            (view.base[i] + view.per_column[i] * 2 + view.per_row[i]).to_num()
        });
        let expect = [0.0, 30f64.to_radians().cos(), -30f64.to_radians().sin()];
        for i in 0..3 {
            assert!((d[i] - expect[i]).abs() < 1e-6, "{d:?}");
        }
    }
}
