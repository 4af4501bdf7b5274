//! The simulation: a master and workers in simulated time (Cohen-Or §3.2).
//!
//! - The **master** sets up each frame's view, tests the map's tiles against
//!   the frame's footprint, loads the footprint's missing tiles from disk
//!   into global memory, and publishes the frame to the line pool. It
//!   works one frame ahead: it prepares frame `f + 1` once the workers have
//!   started on frame `f`.
//! - Each **worker** takes an image line from the kernel's [`LinePool`]
//!   (one processor at a time holds its lock), replays the line's recorded
//!   events, and takes the next; past the last line of a frame it goes on
//!   with the next frame. The pool has as many lines a frame as the frame
//!   with the most; a frame's lines past its own last are empty. A tile not in its local memory is copied from
//!   global memory through the banks; a tile not in global memory either is
//!   a critical load from disk, waited for.
//!
//! The actor with the earliest clock always acts next (ties by number), one
//! event at a time, so bank and disk requests are served in time order.

use super::machine::{Machine, Ps};
use super::memory::{Banks, DiskChannel, LruCache};
use super::trace::{Event, FrameTrace, TileKey};
use terracast::{LinePool, Task, Wait};

/// Why a frame missed its deadline.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MissReason {
    /// The work would fit, but waiting for the disk (critical loads, or
    /// the master's loads holding the frame back) made it late.
    Disk,
    /// The work would fit, but waiting for banks busy with other
    /// processors made it late (more than waiting for the disk).
    BankContention,
    /// The work alone (rays, steps, fetches), spread over the workers,
    /// takes longer than the deadline.
    Steps,
}

impl MissReason {
    /// A word for tables.
    pub fn as_str(self) -> &'static str {
        match self {
            Self::Disk => "disk",
            Self::BankContention => "bank contention",
            Self::Steps => "steps",
        }
    }
}

/// One frame's outcome.
#[derive(Debug, Clone, PartialEq)]
pub struct FrameResult {
    /// When its last line was done.
    pub done: Ps,
    /// Since the previous frame was done (since the start for frame 0).
    pub time: Ps,
    /// `None` when the frame met the deadline.
    pub miss: Option<MissReason>,
    /// Worker time spent computing (rays, steps, colors, local fetches).
    pub compute: Ps,
    /// Worker time copying tiles from global memory (contention included).
    pub transfer: Ps,
    /// Of `transfer`, waiting for banks busy with other processors.
    pub bank_wait: Ps,
    /// Worker time waiting for critical disk loads and for the frame to be
    /// published.
    pub disk_wait: Ps,
    /// Tiles read from disk for this frame by the master (prefetch) and by
    /// workers (critical loads).
    pub disk_reads: u64,
    /// Of `disk_reads`, the critical loads.
    pub critical_loads: u64,
}

/// A whole run's outcome.
#[derive(Debug, Clone, PartialEq)]
pub struct SimResult {
    /// Per frame.
    pub frames: Vec<FrameResult>,
    /// Each worker's busy share of the run (master excluded).
    pub utilization: Vec<f64>,
    /// The master's busy share.
    pub master_utilization: f64,
    /// Each bank's busy share.
    pub bank_utilization: Vec<f64>,
    /// Total waiting for banks busy with other processors.
    pub bank_contention: Ps,
}

impl SimResult {
    /// Frames a second in steady state: frames after the first over the
    /// time they took (the first frame's start-up is not a rate).
    pub fn fps(&self) -> f64 {
        match self.frames.as_slice() {
            [] => 0.0,
            [only] => 1e12 / only.time.max(1) as f64,
            [first, .., last] => {
                (self.frames.len() - 1) as f64 * 1e12 / (last.done - first.done).max(1) as f64
            }
        }
    }

    /// Frames that missed the deadline.
    pub fn misses(&self) -> usize {
        self.frames.iter().filter(|f| f.miss.is_some()).count()
    }
}

#[derive(Debug)]
struct Worker {
    clock: Ps,
    busy: Ps,
    /// The line being replayed and the next event's index.
    line: Option<(Task, usize)>,
    /// Waiting for a frame to be published.
    waiting: bool,
    /// Whether its local memory holds the stick table (or there is none).
    holds_table: bool,
    finished: bool,
    local: LruCache<TileKey>,
}

#[derive(Debug, Default)]
struct FrameBook {
    published_at: Option<Ps>,
    started_at: Option<Ps>,
    lines_done: u32,
    done: Ps,
    compute: Ps,
    transfer: Ps,
    bank_wait: Ps,
    disk_wait: Ps,
    disk_reads: u64,
    critical_loads: u64,
}

/// Runs `frames` (all of one image size) on `machine`.
pub fn simulate(machine: &Machine, frames: &[FrameTrace]) -> SimResult {
    simulate_with_sticks(machine, frames, 0)
}

/// Runs `frames` of a scene with objects on `machine`: its stick table,
/// `stick_table_bytes`, is read from disk by the master before the first
/// frame's tiles, and held whole in global memory and in every worker's
/// local memory (each copies it through the banks before its first
/// line), where it takes the room of as many tiles
/// ([`Machine::resident_tiles`]; [`Machine::check_resident`] says whether
/// it fits). A stick point's voxel holds its stick's index in place of a
/// color, so tiles keep their size.
pub fn simulate_with_sticks(
    machine: &Machine,
    frames: &[FrameTrace],
    stick_table_bytes: u64,
) -> SimResult {
    let lines = frames.iter().map(|f| f.lines.len()).max().unwrap_or(0) as u32;
    let pool = LinePool::new(lines, frames.len() as u32);
    let mut banks = Banks::new(machine);
    let mut disk = DiskChannel::default();
    let table_slots = machine.resident_tiles(stick_table_bytes);
    let global_slots = machine.global_tiles().saturating_sub(table_slots).max(1);
    let mut global: LruCache<TileKey> = LruCache::new(global_slots);
    let tile_bytes = machine.tile_bytes();
    // The table lies in global memory after the tiles' slots.
    let table_address = global_slots as u64 * tile_bytes;
    let disk_read = machine.disk_read();
    let mut workers: Vec<Worker> = (0..machine.workers())
        .map(|_| Worker {
            clock: 0,
            busy: 0,
            line: None,
            waiting: false,
            finished: false,
            holds_table: stick_table_bytes == 0,
            local: LruCache::new(machine.local_tiles().saturating_sub(table_slots).max(1)),
        })
        .collect();
    let mut books: Vec<FrameBook> = frames.iter().map(|_| FrameBook::default()).collect();
    let (mut master_clock, mut master_busy, mut master_next) = (0 as Ps, 0 as Ps, 0usize);
    let mut lock_free_at: Ps = 0;
    let lock_time = machine.cycles(machine.cycles.pool_lock);

    loop {
        // The master may prepare frame f once frame f − 1 has started.
        let master_ready = master_next < frames.len()
            && (master_next == 0 || books[master_next - 1].started_at.is_some());
        let earliest_worker = workers
            .iter()
            .enumerate()
            .filter(|(_, w)| !w.finished && !w.waiting)
            .min_by_key(|(i, w)| (w.clock, *i))
            .map(|(i, w)| (i, w.clock));
        let master_first = match earliest_worker {
            None => master_ready,
            Some((_, clock)) => master_ready && master_clock <= clock,
        };
        if master_first {
            let f = master_next;
            if f > 0 {
                master_clock = master_clock.max(books[f - 1].started_at.unwrap_or(0));
            }
            let start = master_clock;
            if f == 0 && stick_table_bytes > 0 {
                master_clock = disk.read(master_clock, machine.disk_read_bytes(stick_table_bytes));
                books[f].disk_reads += 1;
            }
            let trace = &frames[f];
            master_clock += machine.cycles(
                machine.cycles.view_setup + trace.tiles_tested * machine.cycles.per_footprint_tile,
            );
            for &tile in &trace.footprint {
                if global.touch(tile).is_none() {
                    master_clock = disk.read(master_clock, disk_read);
                    global.insert(tile);
                    books[f].disk_reads += 1;
                }
            }
            master_busy += master_clock - start;
            books[f].published_at = Some(master_clock);
            pool.publish(f as u32);
            for w in workers.iter_mut().filter(|w| w.waiting) {
                w.waiting = false;
                if master_clock > w.clock {
                    books[f].disk_wait += master_clock - w.clock;
                    w.clock = master_clock;
                }
            }
            master_next += 1;
            continue;
        }
        let Some((index, _)) = earliest_worker else {
            break;
        };
        let worker = &mut workers[index];
        let Some((task, next_event)) = worker.line else {
            // Take a line, under the pool's lock.
            let start = worker.clock.max(lock_free_at);
            lock_free_at = start + lock_time;
            worker.clock = lock_free_at;
            match pool.take() {
                Ok(task) => {
                    let book = &mut books[task.frame as usize];
                    let published = book.published_at.unwrap_or(0);
                    if published > worker.clock {
                        book.disk_wait += published - worker.clock;
                        worker.clock = published;
                    }
                    if task.line == 0 {
                        book.started_at = Some(worker.clock);
                    }
                    if !worker.holds_table {
                        let (arrived, waited) =
                            banks.read(worker.clock, table_address, stick_table_bytes);
                        book.transfer += arrived - worker.clock;
                        book.bank_wait += waited;
                        worker.busy += arrived - worker.clock;
                        worker.clock = arrived;
                        worker.holds_table = true;
                    }
                    worker.line = Some((task, 0));
                }
                Err(Wait::NotPublished { .. }) => worker.waiting = true,
                Err(Wait::Finished) => worker.finished = true,
            }
            continue;
        };
        let book = &mut books[task.frame as usize];
        let events = frames[task.frame as usize].lines.get(task.line as usize);
        match events.and_then(|e| e.get(next_event)) {
            Some(event) => {
                let before = worker.clock;
                if worker.local.touch(event.tile).is_none() {
                    if !global.contains(event.tile) {
                        // Critical load: the footprint missed this tile.
                        let arrived = disk.read(worker.clock, disk_read);
                        book.disk_wait += arrived - worker.clock;
                        book.disk_reads += 1;
                        book.critical_loads += 1;
                        worker.clock = arrived;
                    }
                    let slot = global.insert(event.tile) as u64;
                    let (arrived, waited) = banks.read(worker.clock, slot * tile_bytes, tile_bytes);
                    book.transfer += arrived - worker.clock;
                    book.bank_wait += waited;
                    worker.clock = arrived;
                    worker.local.insert(event.tile);
                }
                let compute = machine.cycles(work_cycles(machine, event));
                worker.clock += compute;
                book.compute += compute;
                worker.busy += worker.clock - before;
                worker.line = Some((task, next_event + 1));
            }
            None => {
                worker.line = None;
                book.lines_done += 1;
                if book.lines_done == lines {
                    book.done = worker.clock;
                }
            }
        }
    }

    let deadline = machine.deadline();
    let workers_count = workers.len().max(1) as u64;
    let mut previous_done = 0;
    let results: Vec<FrameResult> = books
        .iter()
        .map(|book| {
            let time = book.done.saturating_sub(previous_done);
            previous_done = book.done;
            let miss = (time > deadline).then(|| {
                // Too much work even with no waiting at all: steps. Else
                // the larger wait, spread over the workers, is to blame.
                if book.compute / workers_count > deadline {
                    MissReason::Steps
                } else if book.disk_wait >= book.bank_wait {
                    MissReason::Disk
                } else {
                    MissReason::BankContention
                }
            });
            FrameResult {
                done: book.done,
                time,
                miss,
                compute: book.compute,
                transfer: book.transfer,
                bank_wait: book.bank_wait,
                disk_wait: book.disk_wait,
                disk_reads: book.disk_reads,
                critical_loads: book.critical_loads,
            }
        })
        .collect();
    let makespan = results.iter().map(|f| f.done).max().unwrap_or(0).max(1) as f64;
    SimResult {
        utilization: workers.iter().map(|w| w.busy as f64 / makespan).collect(),
        master_utilization: master_busy as f64 / makespan,
        bank_utilization: banks.busy.iter().map(|&b| b as f64 / makespan).collect(),
        bank_contention: banks.contention,
        frames: results,
    }
}

/// A worker's computing cycles for `event`: its rays, steps, color
/// fetches and local-memory reads.
pub(crate) fn work_cycles(machine: &Machine, event: &Event) -> u64 {
    let c = &machine.cycles;
    u64::from(event.rays) * c.per_ray
        + u64::from(event.steps) * c.per_step
        + u64::from(event.colors) * c.per_color
        + u64::from(event.fetches) * c.per_local_fetch
}
