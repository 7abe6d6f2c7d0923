//! MT19937 (Matsumoto & Nishimura, ACM TOMACS 8(1), 1998), seeded as in
//! `mt19937ar.c` (the 2002 initialisation).

/// Number of 32-bit words of state.
pub const N: usize = 624;
/// Offset of the middle word in the recurrence.
const M: usize = 397;
/// Last row of the twist matrix A.
const MATRIX_A: u32 = 0x9908_b0df;
/// Most significant w - r = 1 bit.
const UPPER_MASK: u32 = 0x8000_0000;
/// Least significant r = 31 bits.
const LOWER_MASK: u32 = 0x7fff_ffff;

/// The 32-bit Mersenne Twister with period 2^19937 - 1.
///
/// About 2.5 KiB of state: meant for the host (and for dcmt), not for
/// per-thread use on the GPU; see [`super::Mt607`] for that.
#[derive(Clone)]
pub struct Mt19937 {
    state: [u32; N],
    /// Next word to temper; `N` means the block must be regenerated first.
    index: usize,
}

impl Mt19937 {
    /// Seeds like `init_genrand(seed)`; `new(5489)` equals a default
    /// constructed C++ `std::mt19937`.
    pub const fn new(seed: u32) -> Self {
        Self {
            state: init_genrand(seed),
            index: N,
        }
    }

    /// Seeds like `init_by_array(key, key.len())`.
    ///
    /// # Panics
    /// If `key` is empty (the C original divides by its length).
    pub fn from_key(key: &[u32]) -> Self {
        assert!(!key.is_empty(), "Mt19937::from_key needs a non-empty key");
        let mut mt = Self::new(19_650_218);
        let s = &mut mt.state;
        let mut i = 1;
        let mut j = 0;
        // Mix every key word in at least once and touch every state word.
        for _ in 0..N.max(key.len()) {
            let prev = s[i - 1];
            s[i] = (s[i] ^ (prev ^ (prev >> 30)).wrapping_mul(1_664_525))
                .wrapping_add(key[j])
                .wrapping_add(j as u32);
            i += 1;
            j += 1;
            if i >= N {
                s[0] = s[N - 1];
                i = 1;
            }
            if j >= key.len() {
                j = 0;
            }
        }
        // Second pass diffuses the key over the whole state.
        for _ in 0..N - 1 {
            let prev = s[i - 1];
            s[i] =
                (s[i] ^ (prev ^ (prev >> 30)).wrapping_mul(1_566_083_941)).wrapping_sub(i as u32);
            i += 1;
            if i >= N {
                s[0] = s[N - 1];
                i = 1;
            }
        }
        // Only the top bit of word 0 is part of the state: make it non-zero
        // so the state can never be all zero.
        s[0] = 0x8000_0000;
        mt
    }

    /// Next output, like `genrand_int32()`.
    pub fn next_u32(&mut self) -> u32 {
        if self.index >= N {
            self.twist();
        }
        let mut y = self.state[self.index];
        self.index += 1;
        y ^= y >> 11;
        y ^= (y << 7) & 0x9d2c_5680;
        y ^= (y << 15) & 0xefc6_0000;
        y ^ (y >> 18)
    }

    /// Regenerates all N words; the sequence `x[k+N] = x[k+M] ^ twist(x[k], x[k+1])` is
    /// computed in place, so later words see updated ones.
    fn twist(&mut self) {
        let s = &mut self.state;
        for k in 0..N {
            let y = (s[k] & UPPER_MASK) | (s[(k + 1) % N] & LOWER_MASK);
            let mag = MATRIX_A & (y & 1).wrapping_neg();
            s[k] = s[(k + M) % N] ^ (y >> 1) ^ mag;
        }
        self.index = 0;
    }
}

/// `init_genrand`'s seeding of `W` state words, shared by MT19937 and MT607 (whose sample cuts
/// it down to 19 words).
pub const fn init_genrand<const W: usize>(seed: u32) -> [u32; W] {
    let mut state = [0u32; W];
    state[0] = seed;
    let mut i = 1;
    while i < W {
        let prev = state[i - 1];
        // Knuth's multiplier; `+ i` keeps equal high bits from repeating.
        state[i] = 1_812_433_253u32
            .wrapping_mul(prev ^ (prev >> 30))
            .wrapping_add(i as u32);
        i += 1;
    }
    state
}
