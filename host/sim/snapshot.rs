//! A world's state read back to the host, and the hash that proves two runs agree.

use glam::Vec2;
use xxhash_rust::xxh3::Xxh3;

use gpuwars_kernels::rng::mt607;

/// Every per-slot array of a world (slot order), plus its step count and free lists.
#[derive(Clone, Debug, PartialEq)]
pub struct Snapshot {
    /// Steps taken.
    pub steps: u64,
    /// Positions.
    pub pos: Vec<Vec2>,
    /// Velocities.
    pub vel: Vec<Vec2>,
    /// Forces.
    pub force: Vec<Vec2>,
    /// Facing directions.
    pub dir: Vec<Vec2>,
    /// Kind of each slot.
    pub kind: Vec<u32>,
    /// Energies.
    pub energy: Vec<i32>,
    /// Masses.
    pub mass: Vec<f32>,
    /// 1 where a body lives.
    pub alive: Vec<u32>,
    /// Finite-state-machine states.
    pub state: Vec<u32>,
    /// Steps lived.
    pub age: Vec<u32>,
    /// Generator state words, word-major (`mt607::N` rows of one word per slot).
    pub rng_words: Vec<u32>,
    /// Generator positions.
    pub rng_index: Vec<u32>,
    /// Contacts of each slot in the last step.
    pub contacts: Vec<u32>,
    /// Free slots per kind.
    pub free_counts: Vec<u32>,
    /// The free lists (kind `k`'s at its range's start).
    pub free_list: Vec<u32>,
}

impl Snapshot {
    /// Slots holding a live body, in order.
    pub fn live(&self) -> impl Iterator<Item = usize> + '_ {
        (0..self.alive.len()).filter(|&s| self.alive[s] != 0)
    }

    /// Number of slots.
    pub fn slots(&self) -> usize {
        self.alive.len()
    }

    /// Generator word `k` of `slot`.
    pub fn rng_word(&self, slot: usize, k: usize) -> u32 {
        self.rng_words[k * self.slots() + slot]
    }

    /// XXH3-64 over the step count, then, for every live body in slot order, its slot and the
    /// exact bits of every field (generator included), then the free counts. Two runs agree
    /// on it only if they agree bit for bit.
    pub fn state_hash(&self) -> u64 {
        let mut h = Xxh3::new();
        h.update(&self.steps.to_le_bytes());
        let mut word = |w: u32| h.update(&w.to_le_bytes());
        for s in self.live() {
            word(s as u32);
            word(self.kind[s]);
            for v in [self.pos[s], self.vel[s], self.force[s], self.dir[s]] {
                word(v.x.to_bits());
                word(v.y.to_bits());
            }
            word(self.energy[s] as u32);
            word(self.mass[s].to_bits());
            word(self.state[s]);
            word(self.age[s]);
            word(self.rng_index[s]);
            for k in 0..mt607::N {
                word(self.rng_word(s, k));
            }
        }
        self.free_counts.iter().for_each(|&c| word(c));
        h.digest()
    }
}
