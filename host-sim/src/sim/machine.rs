//! The machine description: a TOML file whose every field has a default,
//! the defaults being the IBM Power Visualization System that ran Cohen-Or's
//! flythrough (§3.1).
//!
//! ```toml
//! processors = 32           # one of them the master
//! clock_mhz = 40.0          # i860XR
//!
//! [cycles]
//! per_ray = 689             # a ray's set-up, as far as a sky ray goes
//! per_step = 262            # one traversal step or bound test
//! per_color = 610           # one color fetch: a terrain ray's shading
//! per_local_fetch = 2       # a voxel from local memory
//! pool_lock = 100           # take a column under the pool's semaphore
//! view_setup = 20000        # master: the next frame's view
//! per_footprint_tile = 200  # master: test one tile against the footprint
//!
//! [local_memory]
//! mib = 16                  # per processor; caches terrain tiles
//!
//! [global_memory]
//! cards = 4
//! banks_per_card = 4        # interleaved
//! interleave_bytes = 256
//! card_mb_per_s = 640.0     # shared by the card's banks
//! latency_ns = 250.0
//! mib = 2048
//!
//! [tiles]
//! side = 64                 # voxels
//! bytes_per_voxel = 4       # height and color, as Cohen-Or stored them
//!
//! [disk]
//! mb_per_s = 70.0
//! latency_ms = 8.0
//!
//! [frame]
//! deadline_ms = 100.0
//! ```
//!
//! The work costs are our kernel's, not Cohen-Or's: the least-squares fit
//! of the kernel's instructions per pixel to its color fetches and steps
//! per pixel over the eight renders of `scripts/board-check` (Cortex-M7;
//! four views, each with the default coherence and with every ray cast from
//! the eye; the `cost fit` line it prints) was 689 instructions a ray plus
//! 610 a color fetch plus 262 a step while the kernel divided 64-bit values
//! in software, taken as i860 cycles at one instruction a cycle. The board
//! now divides them with its 32-bit hardware divide (594 + 586 + 264), but
//! the i860 has no integer divide at all, so the software-division fit stays
//! the model of it. A sky ray costs its 689 alone; a terrain ray, shaded
//! from two grid lines, about 1900 before its steps. Change them to model
//! another processor or a faster kernel.

use crate::error::{Error, Result};
use serde::Deserialize;
use terracast::Prices;

/// A whole machine. `Default` is the PVS.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Machine {
    /// Processors, the master included (at least 2).
    pub processors: u32,
    /// Clock of every processor.
    pub clock_mhz: f64,
    /// Work costs.
    pub cycles: Cycles,
    /// Each processor's local memory.
    pub local_memory: LocalMemory,
    /// The shared global memory.
    pub global_memory: GlobalMemory,
    /// How terrain is cut for paging.
    pub tiles: Tiles,
    /// The disk array.
    pub disk: Disk,
    /// The display.
    pub frame: FrameTiming,
}

/// Cycle costs of the kernel's work and the master's duties.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Cycles {
    /// Setting up one ray: what a ray that sees sky costs.
    pub per_ray: u64,
    /// One traversal step (or one bound test of the first hit).
    pub per_step: u64,
    /// One color fetch. A ray that sees terrain makes one or two (see
    /// `terracast::MAX_COLOR_FETCHES_A_RAY`); this carries the rest of its
    /// set-up and its shading, which a sky ray skips.
    pub per_color: u64,
    /// One voxel fetched from local memory.
    pub per_local_fetch: u64,
    /// Taking a column from the pool, lock held.
    pub pool_lock: u64,
    /// The master's set-up of a frame's view.
    pub view_setup: u64,
    /// The master's test of one tile against a frame's footprint.
    pub per_footprint_tile: u64,
}

/// A processor's local memory: a cache of terrain tiles.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct LocalMemory {
    /// Size in MiB.
    pub mib: u64,
}

/// Global memory: cards of interleaved banks.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct GlobalMemory {
    /// Memory cards (interleaved with each other too).
    pub cards: u32,
    /// Banks on a card.
    pub banks_per_card: u32,
    /// Consecutive bytes on one bank before the next bank.
    pub interleave_bytes: u64,
    /// A card's bandwidth, shared evenly by its banks.
    pub card_mb_per_s: f64,
    /// Time from a bank starting a transfer to its data arriving.
    pub latency_ns: f64,
    /// Size in MiB.
    pub mib: u64,
}

/// Terrain tiles.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Tiles {
    /// Side in voxels (every pyramid level uses the same side).
    pub side: u32,
    /// Bytes a voxel occupies in memory and on disk.
    pub bytes_per_voxel: u64,
}

/// The disk array.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Disk {
    /// Sustained bandwidth.
    pub mb_per_s: f64,
    /// Time to start a read.
    pub latency_ms: f64,
}

/// The display's demand.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct FrameTiming {
    /// Each frame must be done within this of the one before.
    pub deadline_ms: f64,
}

impl Default for Machine {
    fn default() -> Self {
        Self {
            processors: 32,
            clock_mhz: 40.0,
            cycles: Cycles::default(),
            local_memory: LocalMemory::default(),
            global_memory: GlobalMemory::default(),
            tiles: Tiles::default(),
            disk: Disk::default(),
            frame: FrameTiming::default(),
        }
    }
}

impl Default for Cycles {
    fn default() -> Self {
        Self {
            per_ray: 689,
            per_step: 262,
            per_color: 610,
            per_local_fetch: 2,
            pool_lock: 100,
            view_setup: 20_000,
            per_footprint_tile: 200,
        }
    }
}

impl Default for LocalMemory {
    fn default() -> Self {
        Self { mib: 16 }
    }
}

impl Default for GlobalMemory {
    fn default() -> Self {
        Self {
            cards: 4,
            banks_per_card: 4,
            interleave_bytes: 256,
            card_mb_per_s: 640.0,
            latency_ns: 250.0,
            mib: 2048,
        }
    }
}

impl Default for Tiles {
    fn default() -> Self {
        Self {
            side: 64,
            bytes_per_voxel: 4,
        }
    }
}

impl Default for Disk {
    fn default() -> Self {
        Self {
            mb_per_s: 70.0,
            latency_ms: 8.0,
        }
    }
}

impl Default for FrameTiming {
    fn default() -> Self {
        Self { deadline_ms: 100.0 }
    }
}

/// Picoseconds: the simulator's integer clock.
pub type Ps = u64;

impl Machine {
    /// Reads a machine description; fields left out keep their defaults.
    pub fn from_toml(text: &str) -> Result<Self> {
        let machine: Self = toml::from_str(text)
            .map_err(|e| Error::new(format!("bad machine description: {}", e.message())))?;
        machine.check()?;
        Ok(machine)
    }

    /// Refuses machines the simulator cannot run.
    pub fn check(&self) -> Result<()> {
        let positive = |v: f64| v.is_finite() && v > 0.0;
        let non_negative = |v: f64| v.is_finite() && v >= 0.0;
        let problem = if self.processors < 2 || self.processors > 1024 {
            Some("processors must be between 2 (a master and a worker) and 1024")
        } else if !positive(self.clock_mhz) {
            Some("clock_mhz must be positive")
        } else if self.global_memory.cards == 0 || self.global_memory.banks_per_card == 0 {
            Some("global_memory needs at least one card and one bank")
        } else if self.global_memory.interleave_bytes == 0 {
            Some("global_memory.interleave_bytes must be positive")
        } else if !positive(self.global_memory.card_mb_per_s) {
            Some("global_memory.card_mb_per_s must be positive")
        } else if !(self.global_memory.latency_ns >= 0.0
            && self.global_memory.latency_ns.is_finite())
        {
            Some("global_memory.latency_ns must be zero or positive")
        } else if self.tiles.side == 0 || self.tiles.side > 4096 || self.tiles.bytes_per_voxel == 0
        {
            Some("tiles.side must be 1 to 4096 and tiles.bytes_per_voxel positive")
        } else if !positive(self.disk.mb_per_s) || !non_negative(self.disk.latency_ms) {
            Some("disk.mb_per_s must be positive and disk.latency_ms zero or positive")
        } else if !positive(self.frame.deadline_ms) {
            Some("frame.deadline_ms must be positive")
        } else {
            None
        };
        match problem {
            Some(p) => Err(Error::new(format!("bad machine description: {p}"))),
            None => Ok(()),
        }
    }

    /// Workers: every processor but the master.
    pub fn workers(&self) -> usize {
        self.processors as usize - 1
    }

    /// Time of `cycles` processor cycles.
    pub fn cycles(&self, cycles: u64) -> Ps {
        (cycles as f64 * 1e6 / self.clock_mhz).round() as Ps
    }

    /// Bytes of one tile.
    pub fn tile_bytes(&self) -> u64 {
        u64::from(self.tiles.side).pow(2) * self.tiles.bytes_per_voxel
    }

    /// Tiles a processor's local memory holds.
    pub fn local_tiles(&self) -> usize {
        ((self.local_memory.mib << 20) / self.tile_bytes()).max(1) as usize
    }

    /// Tiles global memory holds.
    pub fn global_tiles(&self) -> usize {
        ((self.global_memory.mib << 20) / self.tile_bytes()).max(1) as usize
    }

    /// Banks in all.
    pub fn banks(&self) -> u64 {
        u64::from(self.global_memory.cards) * u64::from(self.global_memory.banks_per_card)
    }

    /// Time one bank is busy moving one interleave unit.
    pub fn bank_occupancy(&self) -> Ps {
        let bank_bytes_per_s =
            self.global_memory.card_mb_per_s * 1e6 / f64::from(self.global_memory.banks_per_card);
        (self.global_memory.interleave_bytes as f64 / bank_bytes_per_s * 1e12).round() as Ps
    }

    /// Bank latency.
    pub fn bank_latency(&self) -> Ps {
        (self.global_memory.latency_ns * 1e3).round() as Ps
    }

    /// Time to read one tile from disk, latency included.
    pub fn disk_read(&self) -> Ps {
        self.disk_read_bytes(self.tile_bytes())
    }

    /// Time to read `bytes` from disk in one read, latency included.
    pub fn disk_read_bytes(&self, bytes: u64) -> Ps {
        let transfer = bytes as f64 / (self.disk.mb_per_s * 1e6);
        ((self.disk.latency_ms * 1e-3 + transfer) * 1e12).round() as Ps
    }

    /// Tile slots that `bytes` of data held whole for a run take (in
    /// global memory and in every processor's local memory): the
    /// objects' stick table, which every stick point's voxel indexes.
    pub fn resident_tiles(&self, bytes: u64) -> usize {
        bytes.div_ceil(self.tile_bytes()) as usize
    }

    /// Refused when `bytes` held whole leave a processor's local memory
    /// (or global memory) no room for a tile.
    pub fn check_resident(&self, bytes: u64) -> Result<()> {
        let slots = self.resident_tiles(bytes);
        if slots >= self.local_tiles() || slots >= self.global_tiles() {
            return Err(Error::new(format!(
                "the objects' stick table ({} KiB) leaves no room for a {} KiB tile in a processor's {} MiB of local memory; give the machine more local_memory.mib",
                bytes.div_ceil(1024),
                self.tile_bytes() / 1024,
                self.local_memory.mib
            )));
        }
        Ok(())
    }

    /// The frame deadline.
    pub fn deadline(&self) -> Ps {
        (self.frame.deadline_ms * 1e9).round() as Ps
    }

    /// The kernel governor's prices on this machine, in its cycles: a
    /// ray's set-up, a step and a color fetch, as [`Cycles`] gives them.
    pub fn compute_prices(&self) -> Result<Prices> {
        let c = &self.cycles;
        let price = |cycles: u64, what: &str| {
            u32::try_from(cycles).map_err(|_| {
                Error::new(format!(
                    "cycles.{what} of {cycles} is more than a 32-bit count"
                ))
            })
        };
        Ok(Prices {
            per_pixel: 0,
            per_straight_pixel: 0,
            per_line: 0,
            per_ray: price(c.per_ray, "per_ray")?,
            per_step: price(c.per_step, "per_step")?,
            per_color: price(c.per_color, "per_color")?,
            // The model prices every color fetch alike.
            per_color_square: 0,
            per_hit: 0,
            per_hit_level: 0,
        })
    }

    /// [`Machine::compute_prices`] with the local-memory reads that the
    /// simulator charges a worker beside them (`cycles.per_local_fetch` a
    /// voxel: two a step, at most four a color fetch): the prices of
    /// frames the simulator replays, so that a governed frame's cost is at
    /// least its workers' computing time.
    pub fn replay_prices(&self) -> Result<Prices> {
        let mut prices = self.compute_prices()?;
        let fetch = u32::try_from(self.cycles.per_local_fetch).unwrap_or(u32::MAX);
        prices.per_step = prices.per_step.saturating_add(fetch.saturating_mul(2));
        prices.per_color = prices.per_color.saturating_add(fetch.saturating_mul(4));
        Ok(prices)
    }

    /// Cycles of `seconds` on all the workers together.
    pub fn worker_cycles(&self, seconds: f64) -> f64 {
        self.clock_mhz * 1e6 * self.workers() as f64 * seconds
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_documented_example_is_the_default_machine() {
        let doc = include_str!("machine.rs");
        let example: String = doc
            .lines()
            .skip_while(|l| !l.starts_with("//! ```toml"))
            .skip(1)
            .take_while(|l| !l.starts_with("//! ```"))
            .map(|l| l.trim_start_matches("//!").trim_start())
            .map(|l| format!("{l}\n"))
            .collect();
        assert_eq!(Machine::from_toml(&example).unwrap(), Machine::default());
        assert_eq!(Machine::from_toml("").unwrap(), Machine::default());
    }

    #[test]
    fn partial_files_keep_defaults_and_bad_ones_are_named() {
        let m = Machine::from_toml("processors = 8\n[disk]\nmb_per_s = 35.0\n").unwrap();
        assert_eq!(
            (m.processors, m.disk.mb_per_s, m.disk.latency_ms),
            (8, 35.0, 8.0)
        );
        let e = Machine::from_toml("processor = 8").unwrap_err().to_string();
        assert!(e.contains("unknown field `processor`"), "{e}");
        let e = Machine::from_toml("processors = 1")
            .unwrap_err()
            .to_string();
        assert!(e.contains("processors must be between 2"), "{e}");
        let e = Machine::from_toml("[disk]\nmb_per_s = -1.0")
            .unwrap_err()
            .to_string();
        assert!(e.contains("disk.mb_per_s"), "{e}");
    }

    #[test]
    fn the_default_work_costs_are_the_fit_of_the_board_figures() {
        // Color fetches, steps and instructions a pixel of the eight
        // renders of scripts/board-check (README, "The board"): each view
        // with the default coherence, then from the eye.
        let board = [
            (1.16, 1.41, 1739.0),
            (0.92, 1.31, 1513.0),
            (1.99, 1.60, 2373.0),
            (2.00, 1.46, 2350.0),
            (1.16, 13.77, 5391.0),
            (0.92, 12.95, 4453.0),
            (1.99, 17.97, 6581.0),
            (2.00, 13.69, 5356.0),
        ];
        let points: Vec<_> = board.iter().map(|&(c, s, i)| ([c, s], i)).collect();
        let [per_ray, per_color, per_step] = crate::fit::least_squares(&points);
        let cycles = Machine::default().cycles;
        // The table's figures are rounded (to 0.01 a pixel, up to 3
        // instructions of color fetches and 1.3 of steps); the board fits
        // the exact counts. Rounding moves the intercept and the color
        // term most.
        assert!((per_ray - cycles.per_ray as f64).abs() <= 10.0, "{per_ray}");
        assert!(
            (per_color - cycles.per_color as f64).abs() <= 10.0,
            "{per_color}"
        );
        assert!(
            (per_step - cycles.per_step as f64).abs() <= 2.0,
            "{per_step}"
        );
    }

    #[test]
    fn derived_times_follow_the_numbers() {
        let m = Machine::default();
        assert_eq!(m.cycles(40), 1_000_000); // 40 cycles at 40 MHz: 1 µs
        assert_eq!(m.tile_bytes(), 16384);
        assert_eq!(m.local_tiles(), 1024);
        assert_eq!(m.banks(), 16);
        // 256 bytes at 160 MB/s a bank: 1.6 µs.
        assert_eq!(m.bank_occupancy(), 1_600_000);
        assert_eq!(m.deadline(), 100_000_000_000);
    }
}
