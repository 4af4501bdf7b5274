//! Voids (no data) filled from their valid neighbours, a row at a time.
//!
//! A void point with a known one among its eight neighbours takes their
//! mean, ring by ring from the edges of each void inward, the next ring
//! seeing the last as known. Every filled height is a mean of known
//! heights, so none lies below the lowest valid height around its void
//! (no pits) or above the highest.
//!
//! A void's fill depends only on its own points and the known points
//! around it: two voids that touch (of the eight neighbours) are one.
//! [`VoidFill`] takes the rows in order, finds the voids as they arrive
//! (union-find over the rows' void points), and fills each as soon as a
//! row comes in that does not continue it; a row goes out as soon as its
//! voids are filled. It holds the rows from the top of the oldest void
//! not yet filled (and the row above it): a few rows for SRTM's small
//! voids, the whole map only for a void as tall as the map. Loading a map
//! whole and streaming it into `pack` fill the same heights, bit for bit.

use std::collections::{BTreeSet, VecDeque};

/// A void's extent: columns and rows, inclusive.
#[derive(Debug, Clone, Copy)]
struct Extent {
    x: (usize, usize),
    y: (u32, u32),
}

impl Extent {
    fn merge(self, other: Self) -> Self {
        Self {
            x: (self.x.0.min(other.x.0), self.x.1.max(other.x.1)),
            y: (self.y.0.min(other.y.0), self.y.1.max(other.y.1)),
        }
    }
}

/// Fills the voids (NaN) of a `width`-point-wide height grid whose rows
/// come in one at a time (see the module).
#[derive(Debug)]
pub struct VoidFill {
    width: usize,
    /// Rows from `first` on as they are now (NaN where still void), and
    /// each row's void labels (0: none).
    rows: VecDeque<Vec<f32>>,
    labels: VecDeque<Vec<u32>>,
    /// The map row of `rows[0]`, the next row to hand out, rows received.
    first: u32,
    next_out: u32,
    received: u32,
    /// Union-find over void labels (label 0 unused) and each root's extent.
    parent: Vec<u32>,
    extent: Vec<Extent>,
    /// Roots of the voids not filled yet.
    open: BTreeSet<u32>,
    /// Void points seen, and rows held at most.
    voids: u64,
    rows_held_at_most: usize,
}

impl VoidFill {
    /// A fill for rows `width` points wide.
    pub fn new(width: usize) -> Self {
        Self {
            width,
            rows: VecDeque::new(),
            labels: VecDeque::new(),
            first: 0,
            next_out: 0,
            received: 0,
            parent: vec![0],
            extent: vec![Extent {
                x: (0, 0),
                y: (0, 0),
            }],
            open: BTreeSet::new(),
            voids: 0,
            rows_held_at_most: 0,
        }
    }

    /// The rows of a `width`-wide grid with their voids filled, row by row
    /// as they would stream, and the most rows held at once.
    pub fn fill_grid(width: usize, heights: &[f32]) -> (Vec<f32>, usize) {
        let mut fill = Self::new(width);
        let mut filled = Vec::with_capacity(heights.len());
        for row in heights.chunks_exact(width) {
            fill.push(row);
            while let Some(row) = fill.pop() {
                filled.extend(row);
            }
        }
        fill.finish();
        while let Some(row) = fill.pop() {
            filled.extend(row);
        }
        (filled, fill.rows_held_at_most())
    }

    /// Void points seen so far.
    pub fn voids(&self) -> u64 {
        self.voids
    }

    /// Most rows held at once so far.
    pub fn rows_held_at_most(&self) -> usize {
        self.rows_held_at_most
    }

    fn find(&mut self, mut label: u32) -> u32 {
        while self.parent[label as usize] != label {
            let up = self.parent[label as usize];
            self.parent[label as usize] = self.parent[up as usize];
            label = up;
        }
        label
    }

    fn union(&mut self, a: u32, b: u32) -> u32 {
        let (a, b) = (self.find(a), self.find(b));
        if a != b {
            self.parent[b as usize] = a;
            self.extent[a as usize] = self.extent[a as usize].merge(self.extent[b as usize]);
            self.open.remove(&b);
        }
        a
    }

    /// Takes the next row (NaN for no data).
    pub fn push(&mut self, row: &[f32]) {
        let y = self.received;
        let above = self.labels.back().cloned();
        let mut labels = vec![0u32; self.width];
        for (x, &h) in row.iter().enumerate().take(self.width) {
            if !h.is_nan() {
                continue;
            }
            self.voids += 1;
            let mut neighbours = [0u32; 4];
            if x > 0 {
                neighbours[0] = labels[x - 1];
            }
            if let Some(above) = &above {
                neighbours[1] = if x > 0 { above[x - 1] } else { 0 };
                neighbours[2] = above[x];
                neighbours[3] = above.get(x + 1).copied().unwrap_or(0);
            }
            let mut root = 0;
            for n in neighbours.into_iter().filter(|&n| n != 0) {
                root = if root == 0 {
                    self.find(n)
                } else {
                    self.union(root, n)
                };
            }
            let here = Extent {
                x: (x, x),
                y: (y, y),
            };
            if root == 0 {
                root = self.parent.len() as u32;
                self.parent.push(root);
                self.extent.push(here);
                self.open.insert(root);
            } else {
                self.extent[root as usize] = self.extent[root as usize].merge(here);
            }
            labels[x] = root;
        }
        self.rows.push_back(row.to_vec());
        self.labels.push_back(labels);
        self.received += 1;
        // A void of the row above that this row does not continue is
        // complete, and every row around it has arrived.
        if let Some(above) = above {
            let mut ended: Vec<u32> = above
                .iter()
                .filter(|&&l| l != 0)
                .map(|&l| self.find(l))
                .collect();
            ended.sort_unstable();
            ended.dedup();
            for root in ended {
                if self.extent[root as usize].y.1 < y && self.open.contains(&root) {
                    self.fill(root);
                }
            }
        }
        self.rows_held_at_most = self.rows_held_at_most.max(self.rows.len());
    }

    /// After the last row: fills the voids that reach it.
    pub fn finish(&mut self) {
        let roots: Vec<u32> = self.open.iter().copied().collect();
        for root in roots {
            self.fill(root);
        }
    }

    /// The next row with its voids filled, when it is ready.
    pub fn pop(&mut self) -> Option<Vec<f32>> {
        let at = (self.next_out - self.first) as usize;
        let row = self.rows.get(at)?;
        if row.iter().any(|h| h.is_nan()) {
            return None;
        }
        let row = row.clone();
        self.next_out += 1;
        // Keep the rows an open void still needs (from the row above its
        // top) and the last row received (a void that starts in the next
        // needs the row above it).
        let keep_from = self
            .open
            .iter()
            .map(|&root| self.extent[root as usize].y.0.saturating_sub(1))
            .min()
            .unwrap_or(u32::MAX)
            .min(self.next_out)
            .min(self.received.saturating_sub(1));
        while self.first < keep_from && !self.rows.is_empty() {
            self.rows.pop_front();
            self.labels.pop_front();
            self.first += 1;
        }
        Some(row)
    }

    /// Fills void `root`, ring by ring, from the rows held.
    fn fill(&mut self, root: u32) {
        self.open.remove(&root);
        let Extent { x, y } = self.extent[root as usize];
        let first = self.first;
        let mut pending: Vec<(usize, u32)> = Vec::new();
        for row in y.0..=y.1 {
            let at = (row - first) as usize;
            for column in x.0..=x.1 {
                let label = self.labels[at][column];
                if label != 0 && self.find(label) == root {
                    pending.push((column, row));
                }
            }
        }
        for &(column, row) in &pending {
            self.labels[(row - first) as usize][column] = 0;
        }
        let last_row = self.received - 1;
        let mut ring: Vec<(usize, u32, f32)> = Vec::new();
        while !pending.is_empty() {
            ring.clear();
            for &(px, py) in &pending {
                let (mut sum, mut n) = (0.0f64, 0u32);
                for ny in py.saturating_sub(1)..=(py + 1).min(last_row) {
                    let row = &self.rows[(ny - first) as usize];
                    let columns = px.saturating_sub(1)..=(px + 1).min(self.width - 1);
                    for &h in &row[columns] {
                        if !h.is_nan() {
                            sum += f64::from(h);
                            n += 1;
                        }
                    }
                }
                if n > 0 {
                    ring.push((px, py, (sum / f64::from(n)) as f32));
                }
            }
            if ring.is_empty() {
                // A void with no known point around it: the whole map is
                // void, which the callers refuse.
                break;
            }
            for &(px, py, h) in &ring {
                self.rows[(py - first) as usize][px] = h;
            }
            pending.retain(|&(px, py)| self.rows[(py - first) as usize][px].is_nan());
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The ring fill over a whole grid at once: what loading a map whole
    /// did before the fill streamed, kept as the definition.
    fn whole(width: usize, depth: usize, heights: &mut [f32]) {
        let mut pending: Vec<usize> = (0..heights.len())
            .filter(|&i| heights[i].is_nan())
            .collect();
        let mut ring: Vec<(usize, f32)> = Vec::new();
        while !pending.is_empty() {
            ring.clear();
            for &i in &pending {
                let (x, y) = (i % width, i / width);
                let (mut sum, mut n) = (0.0f64, 0u32);
                for ny in y.saturating_sub(1)..=(y + 1).min(depth - 1) {
                    for nx in x.saturating_sub(1)..=(x + 1).min(width - 1) {
                        let h = heights[ny * width + nx];
                        if !h.is_nan() {
                            sum += f64::from(h);
                            n += 1;
                        }
                    }
                }
                if n > 0 {
                    ring.push((i, (sum / f64::from(n)) as f32));
                }
            }
            if ring.is_empty() {
                break;
            }
            for &(i, h) in &ring {
                heights[i] = h;
            }
            pending.retain(|&i| heights[i].is_nan());
        }
    }

    fn streamed(width: usize, heights: &[f32]) -> (Vec<f32>, usize) {
        VoidFill::fill_grid(width, heights)
    }

    /// A rolling grid with voids: a block, a ring around a known island,
    /// a diagonal thread that joins two blobs, one on an edge, and scattered
    /// single points.
    fn voided(width: usize, depth: usize, seed: u64) -> Vec<f32> {
        let mut state = seed;
        let mut random = move || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 33) as usize
        };
        let mut heights: Vec<f32> = (0..width * depth)
            .map(|i| {
                let (x, y) = ((i % width) as f32, (i / width) as f32);
                100.0 + 30.0 * (x * 0.21).sin() + 20.0 * (y * 0.13).cos() + (x * y * 0.01).sin()
            })
            .collect();
        let mut void = |x: usize, y: usize| {
            if x < width && y < depth {
                heights[y * width + x] = f32::NAN;
            }
        };
        for y in 5..12 {
            for x in 8..20 {
                void(x, y);
            }
        }
        for y in 20..30 {
            for x in 20..30 {
                if !(23..27).contains(&x) || !(23..27).contains(&y) {
                    void(x, y);
                }
            }
        }
        for i in 0..15 {
            void(40 + i, 3 + i);
        }
        for y in 0..6 {
            for x in 0..4 {
                void(x, depth - 1 - y);
            }
        }
        for _ in 0..60 {
            void(random() % width, random() % depth);
        }
        heights
    }

    #[test]
    fn the_streamed_fill_is_the_whole_grids_bit_for_bit() {
        for (width, depth, seed) in [(64, 48, 1), (57, 70, 2), (90, 33, 3)] {
            let heights = voided(width, depth, seed);
            let mut expected = heights.clone();
            whole(width, depth, &mut expected);
            let (got, held) = streamed(width, &heights);
            assert_eq!(got.len(), expected.len());
            assert!(
                got.iter()
                    .zip(&expected)
                    .all(|(a, b)| a.to_bits() == b.to_bits()),
                "{width} x {depth}"
            );
            assert!(got.iter().all(|h| !h.is_nan()));
            assert!(held < depth, "{held} rows held of {depth}");
        }
    }

    #[test]
    fn a_void_as_tall_as_the_map_holds_the_map_and_small_ones_a_few_rows() {
        let (width, depth) = (20, 200);
        let mut heights = vec![5.0f32; width * depth];
        for y in 0..depth {
            heights[y * width + 10] = f32::NAN;
        }
        let (got, held) = streamed(width, &heights);
        assert!(got.iter().all(|&h| h == 5.0));
        assert_eq!(held, depth);
        // Single points every few rows: two or three rows at a time.
        let mut heights = vec![5.0f32; width * depth];
        for y in (0..depth).step_by(7) {
            heights[y * width + y % width] = f32::NAN;
        }
        let (got, held) = streamed(width, &heights);
        assert!(got.iter().all(|&h| h == 5.0));
        assert!(held <= 3, "{held}");
    }
}
