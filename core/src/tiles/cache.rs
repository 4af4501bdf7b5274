//! The tile cache: `N` slots of `T × T` tiles in the caller's storage, a
//! directory from tile key to slot, and least-recently-used eviction that
//! never evicts a tile pinned by the frame being rendered.

use super::{PhotoKey, PhotoTile, Tile, TileError, TileKey, TileSource, World};
use core::hash::BuildHasherDefault;
use heapless::index_map::IndexMap;
use heapless::Vec;
use rustc_hash::FxHasher;

/// The directory's map. Fx hashes a tile key in three multiplies where FNV
/// takes one a byte (nine); the caster looks a key up for every height
/// pair and color pair it reads.
type Directory<K, const N: usize> = IndexMap<K, u16, BuildHasherDefault<FxHasher>, N>;

/// What a cache slot holds: a tile of a pyramid level ([`Tile`]), or of
/// a photo's fine level ([`PhotoTile`]). One cache holds one kind.
pub trait Payload<const T: usize> {
    /// The key that names one.
    type Key: Copy + Eq + core::hash::Hash + core::fmt::Debug;
    /// Bytes of terrain it holds.
    const BYTES: usize;
    /// Whether `key` may name one of `world`'s: a load of any other is
    /// refused before a slot is given up for it.
    fn exists(world: &World, key: &Self::Key) -> bool;
    /// Fills `into` with `key` from `source`; returns the bytes read.
    fn load<S: TileSource<T> + ?Sized>(
        source: &mut S,
        key: Self::Key,
        into: &mut Self,
    ) -> Result<usize, TileError>;
    /// The highest height bound it holds (0 where it has none).
    fn peak(&self) -> u16;
}

impl<const T: usize> Payload<T> for Tile<T> {
    type Key = TileKey;
    const BYTES: usize = Tile::<T>::BYTES;
    fn exists(world: &World, key: &TileKey) -> bool {
        world.contains(*key, T as u32)
    }
    fn load<S: TileSource<T> + ?Sized>(
        source: &mut S,
        key: TileKey,
        into: &mut Self,
    ) -> Result<usize, TileError> {
        source.load(key, into)
    }
    fn peak(&self) -> u16 {
        self.bounds.iter().flatten().copied().max().unwrap_or(0)
    }
}

impl<const T: usize> Payload<T> for PhotoTile<T> {
    type Key = PhotoKey;
    const BYTES: usize = PhotoTile::<T>::BYTES;
    fn exists(_: &World, _: &PhotoKey) -> bool {
        // The world does not know the photos: the source refuses a key
        // it has no tile for.
        true
    }
    fn load<S: TileSource<T> + ?Sized>(
        source: &mut S,
        key: PhotoKey,
        into: &mut Self,
    ) -> Result<usize, TileError> {
        source.load_photo(key, into)
    }
    fn peak(&self) -> u16 {
        0
    }
}

/// A cache of photo tiles ([`TileCache`] of [`PhotoTile`]s): the texels of
/// photos finer than level 0, paged by fine level as the pyramid's tiles
/// are by level.
pub type PhotoCache<'a, const T: usize, const N: usize> = TileCache<'a, T, N, PhotoTile<T>>;

/// What the cache has done since it was made.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct CacheStats {
    /// Tiles loaded into a slot.
    pub loads: u64,
    /// Loads that failed (missing or I/O), the slot left empty.
    pub failures: u64,
    /// Tiles rejected for a bad checksum.
    pub rejected: u64,
    /// Tiles evicted to make room.
    pub evictions: u64,
    /// Bytes the source read.
    pub bytes_read: u64,
}

/// `N` tile slots with `O(1)` lookup by key: of pyramid tiles by default,
/// of photo tiles as a [`PhotoCache`].
///
/// # Eviction
/// Each slot is stamped with the last frame that used it: pinned by
/// [`TileCache::require`] or [`TileCache::pin`] (stamped with the current
/// frame), or prefetched by [`TileCache::prefetch`] (stamped with the frame
/// before, so it is used but not pinned). A load takes an empty slot if there
/// is one, else the slot with the oldest stamp among those not pinned by the
/// current frame (ties: the lowest slot). A pinned tile is never evicted
/// while its frame is being drawn; when every slot is pinned a load fails
/// with [`TileError::CacheFull`] and the frame falls back on coarser tiles.
///
/// `N` must be a power of two (the directory's hash table) and below 65536.
#[derive(Debug)]
pub struct TileCache<'a, const T: usize, const N: usize, P: Payload<T> = Tile<T>> {
    slots: &'a mut [P; N],
    keys: [Option<P::Key>; N],
    stamps: [u32; N],
    /// The highest bound of each slot's tile (0 for level 0).
    peaks: [u16; N],
    directory: Directory<P::Key, N>,
    frame: u32,
    world: World,
    stats: CacheStats,
}

impl<'a, const T: usize, const N: usize, P: Payload<T>> TileCache<'a, T, N, P> {
    const VALID: () = assert!(
        T.is_power_of_two() && T >= 2 && N < 65_536,
        "tile side must be a power of two of at least 2, and the slots fewer than 65536"
    );

    /// An empty cache for `world`, its tiles kept in `slots` (a `static`
    /// on a board, a boxed array on a host).
    pub fn new(world: World, slots: &'a mut [P; N]) -> Self {
        #[allow(clippy::let_unit_value)]
        let () = Self::VALID;
        Self {
            slots,
            keys: [None; N],
            stamps: [0; N],
            peaks: [0; N],
            directory: Directory::default(),
            frame: 1,
            world,
            stats: CacheStats::default(),
        }
    }

    /// The terrain the tiles belong to.
    pub fn world(&self) -> World {
        self.world
    }

    /// Starts a new frame: every pin of the frame before is released.
    pub fn begin_frame(&mut self) {
        self.frame = self.frame.wrapping_add(1).max(2);
    }

    /// The slot holding `key`, if resident.
    #[inline]
    fn slot(&self, key: &P::Key) -> Option<usize> {
        self.directory.get(key).map(|&s| usize::from(s))
    }

    /// The tile `key`, if resident.
    #[inline]
    pub fn get(&self, key: &P::Key) -> Option<&P> {
        self.lookup(key).map(|(_, tile)| tile)
    }

    /// The slot and tile of `key`, if resident.
    #[inline]
    pub(crate) fn lookup(&self, key: &P::Key) -> Option<(usize, &P)> {
        let slot = self.slot(key)?;
        Some((slot, self.slots.get(slot)?))
    }

    /// Whether `key` is resident.
    pub fn contains(&self, key: &P::Key) -> bool {
        self.directory.contains_key(key)
    }

    /// Pins `key` for the current frame if it is resident; false if not.
    pub fn pin(&mut self, key: P::Key) -> bool {
        match self.slot(&key) {
            Some(s) => {
                self.stamps[s] = self.frame;
                true
            }
            None => false,
        }
    }

    /// Makes `key` resident and pins it for the current frame, loading it
    /// from `source` if needed.
    pub fn require<S: TileSource<T> + ?Sized>(
        &mut self,
        key: P::Key,
        source: &mut S,
    ) -> Result<(), TileError> {
        self.fetch(key, source, self.frame)
    }

    /// Makes `key` resident for a later frame without pinning it: it may be
    /// evicted by this frame's own needs, before older tiles are not. A
    /// resident tile is left as it is.
    pub fn prefetch<S: TileSource<T> + ?Sized>(
        &mut self,
        key: P::Key,
        source: &mut S,
    ) -> Result<(), TileError> {
        if self.contains(&key) {
            return Ok(());
        }
        self.fetch(key, source, self.frame - 1)
    }

    fn fetch<S: TileSource<T> + ?Sized>(
        &mut self,
        key: P::Key,
        source: &mut S,
        stamp: u32,
    ) -> Result<(), TileError> {
        if let Some(s) = self.slot(&key) {
            self.stamps[s] = self.stamps[s].max(stamp);
            return Ok(());
        }
        if !P::exists(&self.world, &key) {
            return Err(TileError::Missing);
        }
        let slot = self.victim().ok_or(TileError::CacheFull)?;
        if let Some(old) = self.keys[slot].take() {
            self.directory.remove(&old);
            self.stats.evictions += 1;
        }
        match P::load(source, key, &mut self.slots[slot]) {
            Ok(bytes) => {
                self.stats.loads += 1;
                self.stats.bytes_read += bytes as u64;
                // The directory has N entries of room and holds only the
                // keys of the N slots, one of which was just freed.
                let _ = self.directory.insert(key, slot as u16);
                self.keys[slot] = Some(key);
                self.peaks[slot] = self.slots[slot].peak();
                self.stamps[slot] = stamp;
                Ok(())
            }
            Err(error) => {
                if error == TileError::Checksum {
                    self.stats.rejected += 1;
                } else {
                    self.stats.failures += 1;
                }
                self.stamps[slot] = 0;
                Err(error)
            }
        }
    }

    /// An empty slot, else the least recently used one not pinned now.
    fn victim(&self) -> Option<usize> {
        if let Some(empty) = self.keys.iter().position(Option::is_none) {
            return Some(empty);
        }
        (0..N)
            .filter(|&s| self.stamps[s] != self.frame)
            .min_by_key(|&s| self.stamps[s])
    }

    /// Drops every tile neither pinned by the current frame nor kept by
    /// `keep`: what a cache does to hold no more than the view needs
    /// (its footprint and prefetch).
    pub fn retain(&mut self, mut keep: impl FnMut(&P::Key) -> bool) {
        for slot in 0..N {
            let Some(key) = self.keys[slot] else {
                continue;
            };
            if self.stamps[slot] != self.frame && !keep(&key) {
                self.directory.remove(&key);
                self.keys[slot] = None;
                self.stats.evictions += 1;
            }
        }
    }

    /// Tiles resident now.
    pub fn resident(&self) -> usize {
        self.directory.len()
    }

    /// Bytes of terrain resident now.
    pub fn resident_bytes(&self) -> usize {
        self.resident() * P::BYTES
    }

    /// Tiles pinned by the current frame.
    pub fn pinned(&self) -> usize {
        self.keys
            .iter()
            .zip(&self.stamps)
            .filter(|(k, &s)| k.is_some() && s == self.frame)
            .count()
    }

    /// What the cache has done so far.
    pub fn stats(&self) -> CacheStats {
        self.stats
    }
}

impl<const T: usize, const N: usize> TileCache<'_, T, N> {
    /// The highest height (U12.4) of levels `0..=key.level` in tile
    /// `key`'s area and one cell around it, from the resident tiles of the
    /// level above (their bounds); `None` when one of them is not resident
    /// or `key` is on the top level. Lets [`super::footprint_under`] cut
    /// the footprint to the terrain that is really there.
    pub fn ceiling(&self, key: TileKey) -> Option<u16> {
        let parents = ceiling_tiles::<T>(&self.world, key);
        if parents.is_empty() {
            return None;
        }
        let mut peak = 0u16;
        for parent in &parents {
            peak = peak.max(self.peaks[self.slot(parent)?]);
        }
        Some(peak)
    }
}

/// The tiles of the level above whose bounds cover tile `key`'s points
/// and one cell around them (one to four; none on the top level).
pub(crate) fn ceiling_tiles<const T: usize>(world: &World, key: TileKey) -> Vec<TileKey, 4> {
    let mut out = Vec::new();
    let Some(parent) = key.level.checked_add(1).filter(|&l| l < world.levels()) else {
        return out;
    };
    let t = T as i64;
    // The child's points and one cell around, in parent points.
    let span = |c: u32| {
        let lo = (i64::from(c) * t - 1).div_euclid(2) - 1;
        let hi = ((i64::from(c) + 1) * t + 1) / 2 + 1;
        (lo.max(0) / t, hi / t)
    };
    let ((x0, x1), (y0, y1)) = (span(key.x), span(key.y));
    let (tiles_x, tiles_y) = world.tiles(parent, T as u32);
    for y in y0..=y1.min(i64::from(tiles_y) - 1) {
        for x in x0..=x1.min(i64::from(tiles_x) - 1) {
            let _ = out.push(TileKey {
                level: parent,
                x: x as u32,
                y: y as u32,
            });
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Tiles whose first height is a code of their key; fails on request.
    struct Coded {
        fail: Option<TileError>,
        loads: u32,
    }

    fn code(key: TileKey) -> u16 {
        (key.level as u16) << 12 | (key.y as u16) << 6 | key.x as u16
    }

    impl TileSource<4> for Coded {
        fn world(&self) -> World {
            World::new(64, 64, 100).unwrap()
        }
        fn load(&mut self, key: TileKey, tile: &mut Tile<4>) -> Result<usize, TileError> {
            self.loads += 1;
            if let Some(e) = self.fail {
                return Err(e);
            }
            tile.heights[0][0] = code(key);
            Ok(Tile::<4>::BYTES)
        }
    }

    fn coded() -> Coded {
        Coded {
            fail: None,
            loads: 0,
        }
    }

    fn key(x: u32, y: u32) -> TileKey {
        TileKey { level: 0, x, y }
    }

    #[test]
    fn loads_once_and_finds_by_key() {
        let mut slots = [Tile::<4>::EMPTY; 4];
        let mut source = coded();
        let mut cache = TileCache::<4, 4>::new(source.world(), &mut slots);
        cache.begin_frame();
        for (x, y) in [(1, 2), (3, 0), (1, 2)] {
            cache.require(key(x, y), &mut source).unwrap();
        }
        assert_eq!(source.loads, 2);
        assert_eq!(
            cache.get(&key(1, 2)).unwrap().heights[0][0],
            code(key(1, 2))
        );
        assert_eq!(
            cache.get(&key(3, 0)).unwrap().heights[0][0],
            code(key(3, 0))
        );
        assert!(cache.get(&key(0, 0)).is_none());
        assert_eq!(cache.resident_bytes(), 2 * Tile::<4>::BYTES);
        assert_eq!(cache.stats().loads, 2);
    }

    #[test]
    fn evicts_the_least_recently_used_and_never_a_pinned_tile() {
        let mut slots = [Tile::<4>::EMPTY; 4];
        let mut source = coded();
        let mut cache = TileCache::<4, 4>::new(source.world(), &mut slots);
        // Frame 1 uses four tiles; frame 2 uses two of them again.
        cache.begin_frame();
        for x in 0..4 {
            cache.require(key(x, 0), &mut source).unwrap();
        }
        cache.begin_frame();
        assert!(cache.pin(key(2, 0)) && cache.pin(key(0, 0)));
        // Two new tiles take the slots of the two not pinned.
        cache.require(key(0, 1), &mut source).unwrap();
        cache.require(key(1, 1), &mut source).unwrap();
        assert!(cache.contains(&key(0, 0)) && cache.contains(&key(2, 0)));
        assert!(!cache.contains(&key(1, 0)) && !cache.contains(&key(3, 0)));
        assert_eq!(cache.pinned(), 4);
        // Everything is pinned now: a fifth tile cannot come in.
        assert_eq!(
            cache.require(key(2, 2), &mut source),
            Err(TileError::CacheFull)
        );
        assert_eq!(
            cache.prefetch(key(2, 2), &mut source),
            Err(TileError::CacheFull)
        );
        assert_eq!(cache.resident(), 4);
        // Next frame, the oldest (frame 2's pins are all equal: lowest slot).
        cache.begin_frame();
        cache.require(key(3, 3), &mut source).unwrap();
        assert_eq!(cache.stats().evictions, 3);
        // Keeping only one tile (and the pinned one) frees the rest.
        cache.retain(|k| *k == key(0, 1));
        assert_eq!(cache.resident(), 2);
        assert!(cache.contains(&key(0, 1)) && cache.contains(&key(3, 3)));
    }

    #[test]
    fn a_prefetched_tile_goes_before_the_current_frame_and_after_older_ones() {
        let mut slots = [Tile::<4>::EMPTY; 2];
        let mut source = coded();
        let mut cache = TileCache::<4, 2>::new(source.world(), &mut slots);
        cache.begin_frame();
        cache.require(key(0, 0), &mut source).unwrap();
        cache.begin_frame();
        cache.prefetch(key(1, 0), &mut source).unwrap();
        // Not pinned: the frame's own need evicts the prefetch before
        // giving up.
        cache.require(key(2, 0), &mut source).unwrap();
        cache.require(key(3, 0), &mut source).unwrap();
        assert!(cache.contains(&key(2, 0)) && cache.contains(&key(3, 0)));
    }

    #[test]
    fn failed_and_corrupt_loads_leave_the_slot_empty_and_are_counted() {
        let mut slots = [Tile::<4>::EMPTY; 2];
        let mut source = Coded {
            fail: Some(TileError::Io),
            ..coded()
        };
        let mut cache = TileCache::<4, 2>::new(source.world(), &mut slots);
        cache.begin_frame();
        assert_eq!(cache.require(key(0, 0), &mut source), Err(TileError::Io));
        source.fail = Some(TileError::Checksum);
        assert_eq!(
            cache.require(key(0, 0), &mut source),
            Err(TileError::Checksum)
        );
        assert!(!cache.contains(&key(0, 0)));
        let stats = cache.stats();
        assert_eq!((stats.failures, stats.rejected, stats.loads), (1, 1, 0));
        // Outside the world: refused without asking the source.
        let loads = source.loads;
        assert_eq!(
            cache.require(key(16, 0), &mut source),
            Err(TileError::Missing)
        );
        assert_eq!(source.loads, loads);
    }
}
