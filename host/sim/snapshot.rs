//! A world's state read back to the host, and the hash that proves two runs agree.

use gpuwars_kernels::rng::mt607;
use gpuwars_kernels::sim::Bodies;
use gpuwars_kernels::sim::free_list::FreeSlots;
use xxhash_rust::xxh3::Xxh3;

use crate::backend::Vecs;

/// Every per-slot array of a world (slot order), plus its step count and free lists.
#[derive(Clone, Debug, PartialEq)]
pub struct Snapshot {
    /// Steps taken.
    pub steps: u64,
    /// Every body array, generators included (their words word-major: `mt607::N` rows of
    /// one word per slot).
    pub bodies: Bodies<Vecs>,
    /// Contacts of each slot in the last step.
    pub contacts: Vec<u32>,
    /// The free lists (kind `k`'s at its range's start) and free slots per kind.
    pub free: FreeSlots<Vecs>,
}

impl Snapshot {
    /// Slots holding a live body, in order.
    pub fn live(&self) -> impl Iterator<Item = usize> + '_ {
        let alive = &self.bodies.alive;
        (0..alive.len()).filter(|&s| alive[s] != 0)
    }

    /// Number of slots.
    pub fn slots(&self) -> usize {
        self.bodies.alive.len()
    }

    /// Generator word `k` of `slot`.
    pub fn rng_word(&self, slot: usize, k: usize) -> u32 {
        self.bodies.rng.words[k * self.slots() + slot]
    }

    /// XXH3-64 over the step count, then, for every live body in slot order, its slot and the
    /// exact bits of every field (generator included), then the free counts. Two runs agree
    /// on it only if they agree bit for bit.
    pub fn state_hash(&self) -> u64 {
        let mut h = Xxh3::new();
        h.update(&self.steps.to_le_bytes());
        let mut word = |w: u32| h.update(&w.to_le_bytes());
        let b = &self.bodies;
        for s in self.live() {
            word(s as u32);
            word(b.kind[s]);
            for v in [b.pos[s], b.vel[s], b.force[s], b.dir[s]] {
                word(v.x.to_bits());
                word(v.y.to_bits());
            }
            word(b.energy[s] as u32);
            word(b.mass[s].to_bits());
            word(b.state[s]);
            word(b.age[s]);
            word(b.rng.index[s]);
            for k in 0..mt607::N {
                word(self.rng_word(s, k));
            }
        }
        self.free.count.iter().for_each(|&c| word(c));
        h.digest()
    }
}
