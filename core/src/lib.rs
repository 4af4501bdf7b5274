//! # terracast
//!
//! A `no_std`, fixed-point, allocation-free terrain flythrough kernel: the
//! discrete ray caster of Cohen-Or et al. (1996), with the accuracy
//! refinements of Qu et al. (1998).
//!
//! Data flows one way: **terrain → view → image lines → sink** (the lines
//! through the vertical's vanishing point, which are the columns at pitch 0).
//!
//! ```
//! use terracast::{
//!     pyramid_cells, pyramid_points, render, Camera, CountingProbe, Framebuffer, HeightFilter,
//!     Pyramid, RenderOptions, Terrain, View,
//! };
//!
//! // A 4 x 4 map rising toward +x, every voxel green.
//! let heights: [u16; 16] = core::array::from_fn(|i| (i % 4) as u16 * 16);
//! let colors = [[0, 200, 0]; 16];
//! let terrain = Terrain::new(4, 4, &heights, &colors)?;
//!
//! // Its coarser levels, in storage sized at compile time.
//! const POINTS: usize = pyramid_points(4, 4);
//! let (mut coarse_heights, mut coarse_colors) = ([0u16; POINTS], [[0u8; 3]; POINTS]);
//! let mut bounds = [0u16; pyramid_cells(4, 4)];
//! Pyramid::build(&terrain, HeightFilter::default(), &mut coarse_heights, &mut coarse_colors, &mut bounds)?;
//! let pyramid = Pyramid::new(terrain, &coarse_heights, &coarse_colors, &bounds)?;
//!
//! let camera = Camera::looking([-2.0, 1.5, 5.0], 0.0, 30.0);
//! let view = View::new(&camera, 8, 6)?;
//! let mut pixels = [[0u8; 3]; 8 * 6];
//! let mut frame = Framebuffer::new(&mut pixels, 8, 6)?;
//! let mut probe = CountingProbe::default();
//! render(&pyramid, &view, &RenderOptions::default(), &mut frame, &mut probe);
//!
//! assert_eq!(pixels[8 * 5 + 4], [0, 200, 0]); // bottom middle sees the ground
//! assert_eq!(pixels[4], [135, 185, 235]);     // top middle sees sky
//! // A ray a pixel, but for the sky above each line's last hit, which is
//! // written without one.
//! assert!(probe.rays < 48);
//! # Ok::<(), Box<dyn core::error::Error>>(())
//! ```
#![cfg_attr(not(test), no_std)]
#![deny(missing_docs, unsafe_code, missing_debug_implementations)]
#![deny(rustdoc::broken_intra_doc_links)]

mod atmosphere;
mod caster;
mod color;
pub mod config;
mod detail;
mod divide;
mod pool;
mod probe;
mod pyramid;
mod relief;
pub mod roughness;
mod sink;
mod sticks;
mod surface;
mod terrain;
#[cfg(test)]
mod test_scenes;
pub mod tiles;
mod view;
mod warp;

pub use atmosphere::{
    Atmosphere, AtmosphereError, AtmosphereFrame, AtmosphereSink, Fog, LineShade,
    PreparedAtmosphere, SkyCell, Sun, VISIBILITY_CONTRAST,
};
pub use color::Rgb;
pub use detail::{detail_points, Detail, DetailArea, DetailError, WithDetail};

pub use caster::{
    render, render_by_footprint, render_level_columns, render_level_columns_lean, render_line,
    render_line_by_footprint, render_pixel_lines, render_pixel_path, render_pixel_path_lean,
    render_pixel_path_tabled, tabulate_pixel_ownership, Coherence, ColumnsError, FrameCost,
    FrameWork, Governor, HeightPath, LineShare, Prices, RenderOptions, Resolution, Shading,
    VerticalSamples, MAX_SEE_THROUGH, SEE_THROUGH_REACH,
};
pub use fixed::types::U8F8;
pub use pool::{LinePool, Task, Wait};
pub use probe::{CountingProbe, NoProbe, Probe, MAX_COLOR_FETCHES_A_RAY};
pub use pyramid::{
    level_count, level_side, pyramid_bytes, pyramid_cells, pyramid_points, wavelet_row,
    HeightFilter, Pyramid, PyramidError, MAX_LEVELS,
};
pub use relief::{shade_relief, Relief, ReliefError};
pub use sink::{row_run, Framebuffer, FramebufferError, LinePlane, Sample, Sink, SkyFirst};
pub use sticks::{Stick, StickError, StickGrid, StickLayer, StickTable, WithSticks};
pub use surface::{Extent, Grid, Surface};
pub use terrain::{Terrain, TerrainError};
pub use view::{max_lines, Camera, TableError, View, ViewError};
pub use warp::{control_points, with_margin, ControlPoint, Warp, WarpError};
