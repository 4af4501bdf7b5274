//! Memories of the simulated machine: interleaved global memory banks, tile
//! caches (each processor's local memory, and global memory itself), and
//! the disk channel. Times are integer picoseconds, so every run of the same
//! inputs gives the same result.

use super::machine::{Machine, Ps};
use std::collections::{BTreeMap, HashMap};
use std::hash::Hash;

/// Global memory's banks: `count` of them, each `interleave` bytes wide in
/// the address space, in turn.
#[derive(Debug, Clone)]
pub struct Banks {
    interleave: u64,
    occupancy: Ps,
    latency: Ps,
    /// When each bank finishes the transfers booked so far.
    free_at: Vec<Ps>,
    /// Time each bank spent transferring.
    pub busy: Vec<Ps>,
    /// Time transfers waited for a bank busy with another processor's
    /// transfer.
    pub contention: Ps,
}

impl Banks {
    /// The banks of `machine`.
    pub fn new(machine: &Machine) -> Self {
        let count = machine.banks() as usize;
        Self {
            interleave: machine.global_memory.interleave_bytes,
            occupancy: machine.bank_occupancy(),
            latency: machine.bank_latency(),
            free_at: vec![0; count],
            busy: vec![0; count],
            contention: 0,
        }
    }

    /// A processor reads `bytes` from `address` starting at `now`; returns
    /// when the last byte has arrived. Each interleave unit occupies its
    /// bank for one occupancy time; units on different banks move in
    /// parallel, units on one bank one after another. Waiting behind this
    /// same transfer's units is not contention; waiting behind another
    /// transfer is.
    pub fn read(&mut self, now: Ps, address: u64, bytes: u64) -> (Ps, Ps) {
        let count = self.free_at.len() as u64;
        let first = address / self.interleave;
        let last = (address + bytes.max(1) - 1) / self.interleave;
        let mut own_free = vec![now; self.free_at.len()];
        let (mut done, mut waited) = (now, 0);
        for unit in first..=last {
            let bank = (unit % count) as usize;
            let ready = own_free[bank];
            let start = ready.max(self.free_at[bank]);
            waited += start - ready;
            let end = start + self.occupancy;
            self.free_at[bank] = end;
            own_free[bank] = end;
            self.busy[bank] += self.occupancy;
            done = done.max(end + self.latency);
        }
        self.contention += waited;
        (done, waited)
    }
}

/// A cache of up to `capacity` keys, least recently used out first. Each
/// key gets a slot number, reused by the key that evicts it (the slot is
/// where the tile lies in that memory).
#[derive(Debug, Clone)]
pub struct LruCache<K> {
    tick: u64,
    entries: HashMap<K, (u64, usize)>,
    by_age: BTreeMap<u64, K>,
    free_slots: Vec<usize>,
}

impl<K: Copy + Eq + Hash> LruCache<K> {
    /// An empty cache of `capacity` keys (at least one).
    pub fn new(capacity: usize) -> Self {
        let capacity = capacity.max(1);
        Self {
            tick: 0,
            entries: HashMap::new(),
            by_age: BTreeMap::new(),
            free_slots: (0..capacity).rev().collect(),
        }
    }

    /// The key's slot, marking it used, if it is resident.
    pub fn touch(&mut self, key: K) -> Option<usize> {
        let (age, slot) = self.entries.get(&key).copied()?;
        self.tick += 1;
        self.by_age.remove(&age);
        self.by_age.insert(self.tick, key);
        self.entries.insert(key, (self.tick, slot));
        Some(slot)
    }

    /// Whether the key is resident (without marking it used).
    pub fn contains(&self, key: K) -> bool {
        self.entries.contains_key(&key)
    }

    /// Makes the key resident (evicting the least recently used key when
    /// full) and returns its slot.
    pub fn insert(&mut self, key: K) -> usize {
        if let Some(slot) = self.touch(key) {
            return slot;
        }
        if self.free_slots.is_empty() {
            if let Some((_, old)) = self.by_age.pop_first() {
                if let Some((_, slot)) = self.entries.remove(&old) {
                    self.free_slots.push(slot);
                }
            }
        }
        let slot = self.free_slots.pop().unwrap_or(0);
        self.tick += 1;
        self.by_age.insert(self.tick, key);
        self.entries.insert(key, (self.tick, slot));
        slot
    }

    /// Resident keys.
    pub fn len(&self) -> usize {
        self.entries.len()
    }

    /// Whether nothing is resident.
    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }
}

/// The disk channel: one read at a time.
#[derive(Debug, Clone, Default)]
pub struct DiskChannel {
    free_at: Ps,
    /// Time spent reading.
    pub busy: Ps,
    /// Tiles read.
    pub reads: u64,
}

impl DiskChannel {
    /// Reads one tile, queued behind earlier reads; returns when it is in
    /// memory.
    pub fn read(&mut self, now: Ps, duration: Ps) -> Ps {
        let start = now.max(self.free_at);
        self.free_at = start + duration;
        self.busy += duration;
        self.reads += 1;
        self.free_at
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn machine(banks_per_card: u32, cards: u32) -> Machine {
        let mut m = Machine::default();
        m.global_memory.cards = cards;
        m.global_memory.banks_per_card = banks_per_card;
        m
    }

    #[test]
    fn one_processor_never_sees_contention() {
        let m = machine(4, 4);
        let mut banks = Banks::new(&m);
        let mut now = 0;
        for tile in 0..100u64 {
            let (done, waited) = banks.read(now, tile * 16384, 16384);
            assert_eq!(waited, 0);
            now = done;
        }
        assert_eq!(banks.contention, 0);
    }

    #[test]
    fn processors_on_one_bank_serialize() {
        let m = machine(1, 1);
        let mut banks = Banks::new(&m);
        let unit = m.bank_occupancy();
        // Four processors each read one unit at time 0: they go one by one.
        let finishes: Vec<Ps> = (0..4).map(|_| banks.read(0, 0, 256).0).collect();
        for (i, done) in finishes.iter().enumerate() {
            assert_eq!(*done, (i as u64 + 1) * unit + m.bank_latency());
        }
        assert_eq!(banks.contention, unit * (1 + 2 + 3));
    }

    #[test]
    fn interleaving_spreads_sequential_addresses() {
        // 16 units of 256 bytes: on 16 banks they move at once; on one bank
        // they queue.
        let wide = machine(4, 4);
        let (done_wide, _) = Banks::new(&wide).read(0, 0, 16 * 256);
        let narrow = machine(1, 1);
        let (done_narrow, _) = Banks::new(&narrow).read(0, 0, 16 * 256);
        let unit = wide.bank_occupancy();
        assert_eq!(done_wide, unit + wide.bank_latency());
        // One bank of a one-bank card has the card's whole bandwidth: its
        // unit is four times shorter than a quarter-card bank's.
        assert_eq!(
            done_narrow,
            16 * narrow.bank_occupancy() + narrow.bank_latency()
        );
        let mut banks = Banks::new(&wide);
        banks.read(0, 0, 16 * 256);
        assert!(banks.busy.iter().all(|&b| b == unit));
    }

    #[test]
    fn the_least_recently_used_key_goes_first_and_its_slot_is_reused() {
        let mut cache = LruCache::new(2);
        let a = cache.insert('a');
        let b = cache.insert('b');
        assert_ne!(a, b);
        assert!(cache.touch('a').is_some());
        let c = cache.insert('c'); // evicts b, the least recently used
        assert_eq!(c, b);
        assert!(cache.contains('a') && cache.contains('c') && !cache.contains('b'));
        assert_eq!(cache.len(), 2);
    }

    #[test]
    fn disk_reads_queue() {
        let mut disk = DiskChannel::default();
        assert_eq!(disk.read(0, 10), 10);
        assert_eq!(disk.read(5, 10), 20);
        assert_eq!(disk.read(100, 10), 110);
        assert_eq!((disk.busy, disk.reads), (30, 3));
    }
}
