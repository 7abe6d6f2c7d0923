//! MT607: a Mersenne Twister with period 2^607 - 1 and 19 words of state,
//! run one per GPU thread as in V. Podlozhnyuk, "Parallel Mersenne Twister"
//! (NVIDIA CUDA SDK, 2007). Each thread gets its own dcmt parameter set
//! ([`Mt607Params`]), which makes the streams independent.
//!
//! The generator is a plain `Copy` struct; the free functions work on a
//! borrowed state so a structure-of-arrays layout can use them directly.

use crate::elementary::{ln, sin_cos_turns};

/// Words of state: n = floor(607 / 32) + 1.
pub const N: usize = 19;
/// Offset of the middle word in the recurrence (`MT_MM`).
pub const M: usize = 9;
/// Most significant w - r = 31 bits, r = 32 * 19 - 607 = 1 (`MT_UMASK`).
pub const UPPER_MASK: u32 = 0xffff_fffe;
/// Least significant r = 1 bit (`MT_LMASK`).
pub const LOWER_MASK: u32 = 0x0000_0001;
/// First tempering right shift u (`MT_SHIFT0`).
pub const SHIFT_U: u32 = 12;
/// Tempering left shift s, paired with `mask_b` (`MT_SHIFTB`).
pub const SHIFT_S: u32 = 7;
/// Tempering left shift t, paired with `mask_c` (`MT_SHIFTC`).
pub const SHIFT_T: u32 = 15;
/// Last tempering right shift l (`MT_SHIFT1`).
pub const SHIFT_L: u32 = 18;

/// One dcmt parameter set; same layout as the first three words of the
/// CUDA sample's `mt_struct_stripped` records.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct Mt607Params {
    /// Last row of the twist matrix; dcmt puts the id in the low 16 bits.
    pub matrix_a: u32,
    /// Tempering mask used with the shift by 7.
    pub mask_b: u32,
    /// Tempering mask used with the shift by 15.
    pub mask_c: u32,
}

impl Mt607Params {
    /// Bundles the three words.
    pub const fn new(matrix_a: u32, mask_b: u32, mask_c: u32) -> Self {
        Self {
            matrix_a,
            mask_b,
            mask_c,
        }
    }
}

/// Initial state for `seed`, as the sample (and dcmt's `sgenrand_mt`) do:
/// `init_genrand` cut down to 19 words.
pub const fn seed_state(seed: u32) -> [u32; N] {
    super::mt19937::init_genrand(seed)
}

/// The recurrence: the word that replaces `oldest`, from it, the word after it and the
/// word `M` places after it.
#[inline(always)]
pub const fn twist(oldest: u32, next: u32, middle: u32, matrix_a: u32) -> u32 {
    let y = (oldest & UPPER_MASK) | (next & LOWER_MASK);
    middle ^ (y >> 1) ^ (matrix_a & (y & 1).wrapping_neg())
}

/// Positions of the word after `index` and of the word `M` after it, in a circular state.
#[inline(always)]
pub const fn neighbours(index: u32) -> (u32, u32) {
    // Conditional wrap instead of `%`: integer division is slow on the GPU.
    let n = N as u32;
    let next = if index + 1 >= n {
        index + 1 - n
    } else {
        index + 1
    };
    let middle = if index + M as u32 >= n {
        index + M as u32 - n
    } else {
        index + M as u32
    };
    (next, middle)
}

/// Advances the recurrence by one word and returns the new, untempered word.
///
/// `index` (< [`N`]) names the oldest word, which is overwritten. The
/// one-word-at-a-time update yields the same sequence as regenerating all 19
/// words at once, without a refill branch.
#[inline]
pub fn step(state: &mut [u32; N], index: &mut u32, matrix_a: u32) -> u32 {
    let (next, middle) = neighbours(*index);
    let i = *index as usize;
    let x = twist(
        state[i],
        state[next as usize],
        state[middle as usize],
        matrix_a,
    );
    state[i] = x;
    *index = next;
    x
}

/// Tempering, which improves the k-distribution of the output bits.
#[inline]
pub const fn temper(mut x: u32, params: &Mt607Params) -> u32 {
    x ^= x >> SHIFT_U;
    x ^= (x << SHIFT_S) & params.mask_b;
    x ^= (x << SHIFT_T) & params.mask_c;
    x ^ (x >> SHIFT_L)
}

/// Next 32-bit output of the generator whose state is borrowed.
#[inline]
pub fn next_u32_in(state: &mut [u32; N], index: &mut u32, params: &Mt607Params) -> u32 {
    temper(step(state, index, params.matrix_a), params)
}

/// Maps an output to (0, 1] exactly as the sample: `((float)x + 1.0f) /
/// 4294967296.0f` (the sum rounds, so large `x` give exactly 1.0).
#[inline]
pub fn to_unit_f32(x: u32) -> f32 {
    (x as f32 + 1.0) / 4_294_967_296.0
}

/// Box–Muller transform of two uniforms in (0, 1], as the sample's `BoxMuller`:
/// r = sqrt(-2 ln u1), phi = 2 pi u2, returns (r cos phi, r sin phi). `u1 > 0` keeps the
/// logarithm finite. The sine and cosine are of `u2` turns, and they and the logarithm are
/// [`crate::elementary`]'s (the same bits on both targets, no call on the GPU).
#[inline]
pub fn box_muller(u1: f32, u2: f32) -> (f32, f32) {
    let r = radius(u1);
    let (sin, cos) = sin_cos_turns(u2);
    (r * cos, r * sin)
}

/// The first normal of [`box_muller`]'s pair alone, bit for bit: `r cos phi`.
#[inline]
pub fn box_muller_first(u1: f32, u2: f32) -> f32 {
    radius(u1) * sin_cos_turns(u2).1
}

/// Box–Muller's radius for a uniform in (0, 1].
#[inline(always)]
fn radius(u1: f32) -> f32 {
    crate::math::sqrt(-2.0 * ln(u1))
}

/// An MT607 generator: its parameters, 19 words of state and the position of
/// the oldest word.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Mt607 {
    /// dcmt parameters of this stream.
    pub params: Mt607Params,
    /// The last 19 words of the recurrence, circularly.
    pub state: [u32; N],
    /// Position of the oldest word in `state`; always < [`N`].
    pub index: u32,
}

impl Mt607 {
    /// Generator with `params`, seeded like the sample (see [`seed_state`]).
    pub const fn new(params: Mt607Params, seed: u32) -> Self {
        Self {
            params,
            state: seed_state(seed),
            index: 0,
        }
    }

    /// Next 32-bit output.
    #[inline]
    pub fn next_u32(&mut self) -> u32 {
        next_u32_in(&mut self.state, &mut self.index, &self.params)
    }

    /// Next uniform float in (0, 1] (see [`to_unit_f32`]).
    #[inline]
    pub fn next_f32(&mut self) -> f32 {
        to_unit_f32(self.next_u32())
    }

    /// Two independent standard normals from two consecutive uniforms (see
    /// [`box_muller`]), like the sample pairing outputs k and k + 1.
    #[inline]
    pub fn next_normal_pair(&mut self) -> (f32, f32) {
        let u1 = self.next_f32();
        let u2 = self.next_f32();
        box_muller(u1, u2)
    }
}
