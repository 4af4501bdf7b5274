//! The view contract's pinhole camera in `f64`: the rays every renderer and
//! every check agree on (the view contract, `shared/spec/view-contract.md`
//! beside the repository; `docs/command-line.md` says how `render` follows it).

use terracast::Camera;

/// Ray directions of one camera and image size.
#[derive(Debug, Clone, Copy)]
pub struct ContractCamera {
    /// Eye position.
    pub eye: [f64; 3],
    forward: [f64; 3],
    right: [f64; 3],
    up: [f64; 3],
    tangent: f64,
    width: f64,
    height: f64,
}

impl ContractCamera {
    /// The contract's basis: forward, right and up, with roll applied.
    pub fn new(camera: &Camera, width: u32, height: u32) -> Self {
        let (yaw, pitch, roll) = (
            f64::from(camera.yaw_deg).to_radians(),
            f64::from(camera.pitch_deg).to_radians(),
            f64::from(camera.roll_deg).to_radians(),
        );
        let forward = [
            pitch.cos() * yaw.cos(),
            pitch.cos() * yaw.sin(),
            -pitch.sin(),
        ];
        let right0 = [-yaw.sin(), yaw.cos(), 0.0];
        let up0 = cross(forward, right0);
        let (sr, cr) = roll.sin_cos();
        let right = core::array::from_fn(|i| right0[i] * cr - up0[i] * sr);
        let up = core::array::from_fn(|i| up0[i] * cr + right0[i] * sr);
        Self {
            eye: camera.eye.map(f64::from),
            forward,
            right,
            up,
            tangent: (f64::from(camera.hfov_deg).to_radians() / 2.0).tan(),
            width: f64::from(width),
            height: f64::from(height),
        }
    }

    /// Direction (not normalized) of the ray through image point
    /// `(sx, sy)`; pixel centers are at `(px + 0.5, py + 0.5)`.
    pub fn direction(&self, sx: f64, sy: f64) -> [f64; 3] {
        let a = (2.0 * sx / self.width - 1.0) * self.tangent;
        let b = (1.0 - 2.0 * sy / self.height) * self.tangent * self.height / self.width;
        core::array::from_fn(|i| self.forward[i] + a * self.right[i] + b * self.up[i])
    }
}

/// Cross product.
pub fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// Euclidean length.
pub fn length(v: [f64; 3]) -> f64 {
    (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
}
