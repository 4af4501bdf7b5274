//! What the caster touches, reported as it happens.
//!
//! The simulator turns these events into time and traffic; tests count them.
//! Every method has an empty default body, so [`NoProbe`] compiles to nothing.

/// Receives the caster's memory events.
pub trait Probe {
    /// One traversal step: the heights of voxel `voxel` and of its neighbour
    /// across the minor grid line were fetched and compared with the ray.
    #[inline(always)]
    fn visit(&mut self, voxel: usize) {
        let _ = voxel;
    }
    /// The colors of voxel `voxel` and its minor-axis neighbour were fetched
    /// to shade a pixel.
    #[inline(always)]
    fn color(&mut self, voxel: usize) {
        let _ = voxel;
    }
    /// A ray was set up (one per pixel).
    #[inline(always)]
    fn ray(&mut self) {}
}

/// The probe that observes nothing and costs nothing.
#[derive(Debug, Default, Clone, Copy)]
pub struct NoProbe;

impl Probe for NoProbe {}

/// Counts events: steps (voxel visits), color fetches and rays.
#[derive(Debug, Default, Clone, Copy, PartialEq, Eq)]
pub struct CountingProbe {
    /// Traversal steps (height fetches compared with a ray).
    pub steps: u64,
    /// Color fetches (one per shaded grid-line sample).
    pub color_fetches: u64,
    /// Rays set up.
    pub rays: u64,
}

impl Probe for CountingProbe {
    #[inline(always)]
    fn visit(&mut self, _voxel: usize) {
        self.steps += 1;
    }
    #[inline(always)]
    fn color(&mut self, _voxel: usize) {
        self.color_fetches += 1;
    }
    #[inline(always)]
    fn ray(&mut self) {
        self.rays += 1;
    }
}
