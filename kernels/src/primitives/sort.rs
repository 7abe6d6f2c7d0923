//! Deterministic counting sort of `(key, index)` pairs: equal keys come out in index order.
//!
//! Keys are sorted [`DIGIT_BITS`] bits at a time from the least significant digit (a stable
//! counting sort per digit, i.e. an LSD radix sort), which is what makes the result
//! independent of thread scheduling without any barrier:
//! 1. [`count_digits`]: thread `t` counts the digits of its tile of [`TILE`] keys into column
//!    `t` of a digit-major matrix (`counts[digit · tiles + t]`): no atomics, no sharing.
//! 2. the host takes the exclusive prefix sum of that matrix: entry `(d, t)` becomes the first
//!    output slot of the tile's keys with digit `d`, after every smaller digit and every
//!    earlier tile with the same digit;
//! 3. [`scatter_digits`]: thread `t` walks its tile in order and moves each pair to the next
//!    slot of its digit. Within a digit, earlier tiles and earlier elements come first: stable.
//!
//! A sort of keys below `2^b` takes `⌈b / DIGIT_BITS⌉` such passes.

use crate::{DevSlice, Thread, kernel_args};

/// Bits of the key sorted by one pass.
pub const DIGIT_BITS: u32 = 4;
/// Distinct digits per pass.
pub const RADIX: u32 = 1 << DIGIT_BITS;
/// Keys per thread. 64 keeps the count matrix at a quarter of the input (`RADIX / TILE`).
pub const TILE: u32 = 64;

/// Number of tiles covering `n` keys.
#[inline(always)]
pub const fn tiles(n: u32) -> u32 {
    n.div_ceil(TILE)
}

/// Number of passes that sort keys below `key_bound` (at least one, so that the output is
/// always written).
#[inline]
pub const fn passes(key_bound: u32) -> u32 {
    let bits = u32::BITS - key_bound.saturating_sub(1).leading_zeros();
    if bits == 0 {
        1
    } else {
        bits.div_ceil(DIGIT_BITS)
    }
}

#[inline(always)]
fn digit(key: u32, shift: u32) -> u32 {
    (key >> shift) & (RADIX - 1)
}

kernel_args! {
    /// Arguments of [`count_digits`].
    pub struct CountArgs {
        /// The keys of this pass, `n` of them used.
        pub keys: DevSlice<u32>,
        /// Digit-major count matrix: `RADIX · tiles(n)` elements.
        pub counts: DevSlice<u32>,
        /// Number of keys.
        pub n: u32,
        /// Position of this pass's digit in the key.
        pub shift: u32,
    }
}

/// Thread `t` writes column `t` of the count matrix: how many keys of tile `t` have each digit.
#[inline(always)]
pub fn count_digits(t: Thread, args: &CountArgs) {
    let tile = t.global();
    let tile_count = tiles(args.n);
    if tile >= tile_count {
        return;
    }
    let start = tile * TILE;
    let end = args.n.min(start + TILE);
    let mut counts = [0u32; RADIX as usize];
    args.keys
        .for_each_in::<{ TILE as usize }>(start, end, |_, key| {
            counts[digit(key, args.shift) as usize] += 1;
        });
    for (d, &count) in counts.iter().enumerate() {
        args.counts.set(d as u32 * tile_count + tile, count);
    }
}

kernel_args! {
    /// Arguments of [`scatter_digits`].
    pub struct ScatterArgs {
        /// The keys of this pass.
        pub keys_in: DevSlice<u32>,
        /// The indices travelling with the keys, or empty on the first pass, where the index of a
        /// key is its position.
        pub indices_in: DevSlice<u32>,
        /// The exclusive prefix sum of [`count_digits`]'s matrix.
        pub offsets: DevSlice<u32>,
        /// Receives the keys, stably sorted by this pass's digit.
        pub keys_out: DevSlice<u32>,
        /// Receives the indices in the same order as `keys_out`.
        pub indices_out: DevSlice<u32>,
        /// Number of keys.
        pub n: u32,
        /// Position of this pass's digit in the key.
        pub shift: u32,
    }
}

/// Thread `t` moves the pairs of tile `t` to their slots, in order. The offsets give every
/// (digit, tile) a disjoint range of slots, so no two threads write the same element.
#[inline(always)]
pub fn scatter_digits(t: Thread, args: &ScatterArgs) {
    let tile = t.global();
    let tile_count = tiles(args.n);
    if tile >= tile_count {
        return;
    }
    let mut next = [0u32; RADIX as usize];
    for (d, slot) in next.iter_mut().enumerate() {
        *slot = args.offsets.get(d as u32 * tile_count + tile);
    }
    let start = tile * TILE;
    let end = args.n.min(start + TILE);
    // One key at a time: a whole tile read up front would sit in local memory beside `next`
    // (measured slower on the H200 at 2^20 keys).
    for i in start..end {
        let key = args.keys_in.get(i);
        let index = if args.indices_in.is_empty() {
            i
        } else {
            args.indices_in.get(i)
        };
        let slot = &mut next[digit(key, args.shift) as usize];
        args.keys_out.set(*slot, key);
        args.indices_out.set(*slot, index);
        *slot += 1;
    }
}

#[cfg(test)]
mod tests {
    use super::passes;

    #[test]
    fn passes_cover_the_key_bits() {
        assert_eq!(passes(0), 1);
        assert_eq!(passes(1), 1);
        assert_eq!(passes(2), 1);
        assert_eq!(passes(16), 1);
        assert_eq!(passes(17), 2);
        assert_eq!(passes(256), 2);
        assert_eq!(passes(257), 3);
        assert_eq!(passes(u32::MAX), 8);
    }
}
