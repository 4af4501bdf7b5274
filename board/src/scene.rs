//! The board scene file: a terrain in the kernel's own format and the views
//! to render, baked into the firmware as one constant.
//!
//! Layout, all numbers little-endian:
//!
//! | offset | size | what |
//! |---|---|---|
//! | 0 | 8 | [`MAGIC`] |
//! | 8 | 4 × u32 | map width, map depth, image width, image height |
//! | 24 | u32 | number of views, at most [`MAX_VIEWS`] |
//! | 28 | 28 a view | eye x, y, z, yaw, pitch, horizontal fov, roll: f32 each |
//! | [`HEADER_BYTES`] | 2 a voxel | heights, U12.4, row-major |
//! | after them | 3 a voxel | colors, RGB |
//!
//! The header is padded to [`HEADER_BYTES`] so that the heights start
//! aligned when the file is.
//!
//! 3D objects (the kernel's [`StickLayer`]) may follow, from the first
//! multiple of 4 after the colors ([`objects_at`]):
//!
//! | offset | size | what |
//! |---|---|---|
//! | 0 | 8 | [`OBJECTS_MAGIC`] |
//! | 8 | 2 × u32 | sticks (at most [`MAX_STICKS`]), texels |
//! | 16 | 2 a voxel | a stick index a grid point (0: none) |
//! | then, from a multiple of 4 | 8 a stick | first texel u32, texels u16, height u16 |
//! | after them | 3 a texel | texels, RGB |
//! | after them | 1 a texel, or none | texels' opacities, 255 opaque (none: all are) |
//!
//! The terrain's heights and colors are then the planted ones: a stick's
//! top and its top texel where it stands.

use core::fmt;
use terracast::{Camera, Rgb, Stick, StickError, StickLayer, Terrain, TerrainError};

/// First bytes of a board scene file.
pub const MAGIC: [u8; 8] = *b"TCBOARD2";
/// Header size; the heights start here.
pub const HEADER_BYTES: usize = 256;
/// Most views a scene carries.
pub const MAX_VIEWS: usize = 8;
/// First bytes of the objects' section.
pub const OBJECTS_MAGIC: [u8; 8] = *b"TCSTICKS";
/// Most sticks a board scene's table holds (the firmware's storage for
/// them is this many).
pub const MAX_STICKS: usize = 4096;
/// Bytes of a stick in the file.
pub const STICK_BYTES: usize = 8;
const VIEWS_AT: usize = 28;
const VIEW_BYTES: usize = 28;
const _: () = assert!(VIEWS_AT + MAX_VIEWS * VIEW_BYTES <= HEADER_BYTES);

/// Sizes and views: everything but the terrain's voxels.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Header {
    /// Map width in voxels.
    pub map_width: u32,
    /// Map depth in voxels.
    pub map_depth: u32,
    /// Image width in pixels.
    pub image_width: u32,
    /// Image height in pixels.
    pub image_height: u32,
    views: [Camera; MAX_VIEWS],
    view_count: usize,
}

impl Header {
    /// A header; fails with [`SceneError::TooManyViews`] past [`MAX_VIEWS`].
    pub fn new(map: (u32, u32), image: (u32, u32), views: &[Camera]) -> Result<Self, SceneError> {
        if views.len() > MAX_VIEWS {
            return Err(SceneError::TooManyViews);
        }
        let mut all = [Camera::default(); MAX_VIEWS];
        all[..views.len()].copy_from_slice(views);
        Ok(Self {
            map_width: map.0,
            map_depth: map.1,
            image_width: image.0,
            image_height: image.1,
            views: all,
            view_count: views.len(),
        })
    }

    /// The views, in order.
    pub fn views(&self) -> &[Camera] {
        &self.views[..self.view_count]
    }

    /// Voxels of the map.
    pub fn voxels(&self) -> usize {
        self.map_width as usize * self.map_depth as usize
    }

    /// Size of the whole file.
    pub fn file_bytes(&self) -> usize {
        HEADER_BYTES + self.voxels() * 5
    }

    /// The header's bytes.
    pub fn encode(&self) -> [u8; HEADER_BYTES] {
        let mut out = [0u8; HEADER_BYTES];
        out[..8].copy_from_slice(&MAGIC);
        let words = [
            self.map_width,
            self.map_depth,
            self.image_width,
            self.image_height,
            self.view_count as u32,
        ];
        for (slot, word) in out[8..VIEWS_AT].chunks_exact_mut(4).zip(words) {
            slot.copy_from_slice(&word.to_le_bytes());
        }
        for (slot, view) in out[VIEWS_AT..]
            .chunks_exact_mut(VIEW_BYTES)
            .zip(self.views())
        {
            let numbers = [
                view.eye[0],
                view.eye[1],
                view.eye[2],
                view.yaw_deg,
                view.pitch_deg,
                view.hfov_deg,
                view.roll_deg,
            ];
            for (s, n) in slot.chunks_exact_mut(4).zip(numbers) {
                s.copy_from_slice(&n.to_le_bytes());
            }
        }
        out
    }

    /// Reads a header from the start of a scene file.
    pub fn decode(bytes: &[u8]) -> Result<Self, SceneError> {
        if bytes.get(..MAGIC.len()) != Some(MAGIC.as_slice()) {
            return Err(SceneError::NotABoardScene);
        }
        let header = bytes.get(..HEADER_BYTES).ok_or(SceneError::Truncated)?;
        let word = |at: usize| {
            let mut b = [0u8; 4];
            b.copy_from_slice(&header[at..at + 4]);
            b
        };
        let number = |at: usize| u32::from_le_bytes(word(at));
        let view_count = number(24) as usize;
        if view_count > MAX_VIEWS {
            return Err(SceneError::TooManyViews);
        }
        let mut views = [Camera::default(); MAX_VIEWS];
        for (i, view) in views.iter_mut().enumerate().take(view_count) {
            let at = VIEWS_AT + i * VIEW_BYTES;
            let float = |k: usize| f32::from_le_bytes(word(at + 4 * k));
            *view = Camera {
                eye: [float(0), float(1), float(2)],
                yaw_deg: float(3),
                pitch_deg: float(4),
                roll_deg: float(6),
                hfov_deg: float(5),
            };
        }
        let header = Self {
            map_width: number(8),
            map_depth: number(12),
            image_width: number(16),
            image_height: number(20),
            views,
            view_count,
        };
        if header.map_width > terracast::config::MAX_MAP_SIDE
            || header.map_depth > terracast::config::MAX_MAP_SIDE
        {
            return Err(SceneError::Terrain(TerrainError::TooLarge));
        }
        Ok(header)
    }
}

/// Where the objects' section of a scene of `voxels` starts.
pub const fn objects_at(voxels: usize) -> usize {
    (HEADER_BYTES + 5 * voxels).next_multiple_of(4)
}

/// Where, past the objects' section's start, its stick table starts.
pub const fn sticks_at(voxels: usize) -> usize {
    (16 + 2 * voxels).next_multiple_of(4)
}

/// A stick's bytes in the file.
pub fn encode_stick(stick: &Stick) -> [u8; STICK_BYTES] {
    let mut out = [0u8; STICK_BYTES];
    out[..4].copy_from_slice(&stick.first.to_le_bytes());
    out[4..6].copy_from_slice(&stick.texels.to_le_bytes());
    out[6..].copy_from_slice(&stick.height.to_le_bytes());
    out
}

/// A scene file read in place: the terrain borrows the file's bytes.
#[derive(Debug, Clone, Copy)]
pub struct BoardScene<'a> {
    /// Sizes and views.
    pub header: Header,
    heights: &'a [u16],
    colors: &'a [Rgb],
    objects: Option<Objects<'a>>,
}

/// The objects' section, borrowed from the file.
#[derive(Debug, Clone, Copy)]
struct Objects<'a> {
    points: &'a [u16],
    sticks: &'a [u8],
    texels: &'a [Rgb],
    alphas: &'a [u8],
}

/// Why a scene file was refused.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SceneError {
    /// The file does not start with [`MAGIC`].
    NotABoardScene,
    /// The file is shorter than its header says.
    Truncated,
    /// More than [`MAX_VIEWS`] views.
    TooManyViews,
    /// The heights do not start on a 2-byte boundary (the file must be
    /// placed aligned), or the target is big-endian.
    Misaligned,
    /// The kernel refused the terrain.
    Terrain(TerrainError),
    /// The objects' section does not start with [`OBJECTS_MAGIC`].
    NotObjects,
    /// More than [`MAX_STICKS`] sticks, or more than the storage given.
    TooManySticks,
    /// The kernel refused the objects.
    Objects(StickError),
}

impl fmt::Display for SceneError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::NotABoardScene => f.write_str("not a board scene file (bad magic)"),
            Self::Truncated => f.write_str("board scene file is shorter than its header says"),
            Self::TooManyViews => write!(f, "board scene has more than {MAX_VIEWS} views"),
            Self::Misaligned => {
                f.write_str("board scene heights are not 2-byte aligned little-endian u16")
            }
            Self::Terrain(e) => write!(f, "board scene terrain refused: {e}"),
            Self::NotObjects => {
                f.write_str("board scene has bytes after its colors that are not objects")
            }
            Self::TooManySticks => write!(f, "board scene has more than {MAX_STICKS} sticks"),
            Self::Objects(e) => write!(f, "board scene objects refused: {e}"),
        }
    }
}

impl core::error::Error for SceneError {}

impl<'a> Objects<'a> {
    /// Reads the objects' section `bytes` of a scene of `voxels`.
    fn parse(bytes: &'a [u8], voxels: usize) -> Result<Self, SceneError> {
        if bytes.get(..OBJECTS_MAGIC.len()) != Some(OBJECTS_MAGIC.as_slice()) {
            return Err(SceneError::NotObjects);
        }
        let number = |at: usize| -> Result<usize, SceneError> {
            let word = bytes.get(at..at + 4).ok_or(SceneError::Truncated)?;
            Ok(u32::from_le_bytes([word[0], word[1], word[2], word[3]]) as usize)
        };
        let (sticks, texels) = (number(8)?, number(12)?);
        if sticks > MAX_STICKS {
            return Err(SceneError::TooManySticks);
        }
        let points = bytes
            .get(16..16 + 2 * voxels)
            .ok_or(SceneError::Truncated)?;
        let table = sticks_at(voxels);
        let sticks = bytes
            .get(table..table + sticks * STICK_BYTES)
            .ok_or(SceneError::Truncated)?;
        let texels_at = table + sticks.len();
        let texels_end = texels
            .checked_mul(3)
            .and_then(|len| texels_at.checked_add(len))
            .filter(|&end| end <= bytes.len())
            .ok_or(SceneError::Truncated)?;
        // The opacities: the rest of the section, none or one a texel.
        let alphas = &bytes[texels_end..];
        if !alphas.is_empty() && alphas.len() < texels {
            return Err(SceneError::Truncated);
        }
        if alphas.len() > texels {
            return Err(SceneError::Objects(StickError::AlphasLength));
        }
        Ok(Self {
            points: bytemuck::try_cast_slice(points).map_err(|_| SceneError::Misaligned)?,
            sticks,
            texels: bytemuck::try_cast_slice(&bytes[texels_at..texels_end])
                .map_err(|_| SceneError::Misaligned)?,
            alphas,
        })
    }
}

impl<'a> BoardScene<'a> {
    /// Reads a scene file without copying it.
    pub fn parse(bytes: &'a [u8]) -> Result<Self, SceneError> {
        let header = Header::decode(bytes)?;
        let voxels = header.voxels();
        let heights = bytes
            .get(HEADER_BYTES..HEADER_BYTES + 2 * voxels)
            .ok_or(SceneError::Truncated)?;
        let colors = bytes
            .get(HEADER_BYTES + 2 * voxels..HEADER_BYTES + 5 * voxels)
            .ok_or(SceneError::Truncated)?;
        if cfg!(target_endian = "big") {
            return Err(SceneError::Misaligned);
        }
        let heights: &[u16] =
            bytemuck::try_cast_slice(heights).map_err(|_| SceneError::Misaligned)?;
        let colors: &[Rgb] =
            bytemuck::try_cast_slice(colors).map_err(|_| SceneError::Misaligned)?;
        let objects = match bytes.get(objects_at(voxels)..) {
            None | Some([]) => None,
            Some(section) => Some(Objects::parse(section, voxels)?),
        };
        let scene = Self {
            header,
            heights,
            colors,
            objects,
        };
        scene.terrain()?;
        Ok(scene)
    }

    /// Sticks in the scene's table (0 without objects).
    pub fn stick_count(&self) -> usize {
        self.objects.map_or(0, |o| o.sticks.len() / STICK_BYTES)
    }

    /// The scene's objects over `terrain` (its [`BoardScene::terrain`]),
    /// their stick table decoded into `storage` (at least
    /// [`BoardScene::stick_count`] long); `None` for a scene without
    /// objects.
    pub fn objects<'s>(
        &self,
        terrain: &Terrain<'_>,
        storage: &'s mut [Stick],
    ) -> Result<Option<StickLayer<'s>>, SceneError>
    where
        'a: 's,
    {
        let Some(objects) = self.objects else {
            return Ok(None);
        };
        let count = objects.sticks.len() / STICK_BYTES;
        let sticks = storage.get_mut(..count).ok_or(SceneError::TooManySticks)?;
        for (stick, bytes) in sticks
            .iter_mut()
            .zip(objects.sticks.chunks_exact(STICK_BYTES))
        {
            let half = |at: usize| u16::from_le_bytes([bytes[at], bytes[at + 1]]);
            *stick = Stick {
                first: u32::from_le_bytes([bytes[0], bytes[1], bytes[2], bytes[3]]),
                texels: half(4),
                height: half(6),
            };
        }
        StickLayer::new(terrain, objects.points, sticks, objects.texels)
            .and_then(|layer| layer.with_alphas(objects.alphas))
            .map(Some)
            .map_err(SceneError::Objects)
    }

    /// The kernel's terrain over the file's voxels.
    pub fn terrain(&self) -> Result<Terrain<'a>, SceneError> {
        Terrain::new(
            self.header.map_width,
            self.header.map_depth,
            self.heights,
            self.colors,
        )
        .map_err(SceneError::Terrain)
    }
}
