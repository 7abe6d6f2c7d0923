//! Exclusive prefix sum of `u32` (wrapping, i.e. modulo 2^32), in tiles.
//!
//! One pass of the multi-launch scan: [`reduce_tiles`] writes the sum of every tile of
//! [`TILE`] elements; the host scans those sums (recursively, with the same two kernels) into
//! per-tile starting offsets; [`scan_tiles`] then walks each tile once more from its offset.
//! A problem of `n` elements takes `2·⌈log_TILE n⌉ - 1` launches and no barrier.
//!
//! Up to [`FLAT_TILES`] tiles, [`scan_tiles_after_sums`] replaces the recursion: each warp
//! adds up the sums of the tiles before its own (a warp collective) and scans its own, so
//! the scan takes two launches.

use crate::{DevSlice, Thread, asked, kernel_args, warp};

/// Elements per thread. 32 keeps a tile in one 128-byte line and leaves 2^19 threads at n = 2^24.
pub const TILE: u32 = 32;

/// Most tiles [`scan_tiles_after_sums`] takes: a thread reads at most this many tile sums.
pub const FLAT_TILES: u32 = 1024;

/// Number of tiles covering `n` elements.
#[inline(always)]
pub const fn tiles(n: u32) -> u32 {
    n.div_ceil(TILE)
}

kernel_args! {
    /// Arguments of [`reduce_tiles`].
    pub struct ReduceArgs {
        /// The values to sum, `n` of them used.
        pub input: DevSlice<u32>,
        /// One sum per tile: `tiles(n)` elements.
        pub tile_sums: DevSlice<u32>,
        /// Number of input elements.
        pub n: u32,
        /// Keeps the struct free of implicit padding (checked by its `NoUninit` derive).
        pub reserved: u32,
    }
}

/// Thread `t` writes the wrapping sum of tile `t` of the input. Each thread writes one element.
#[inline(always)]
pub fn reduce_tiles(t: Thread, args: &ReduceArgs) {
    let tile = t.global();
    if tile >= tiles(args.n) {
        return;
    }
    let start = tile * TILE;
    let end = args.n.min(start + TILE);
    let mut sum = 0u32;
    args.input
        .for_each_in::<{ TILE as usize }>(start, end, |_, v| sum = sum.wrapping_add(v));
    args.tile_sums.set(tile, sum);
}

kernel_args! {
    /// Arguments of [`scan_tiles`].
    pub struct ScanArgs {
        /// The values to scan, `n` of them used.
        pub input: DevSlice<u32>,
        /// Exclusive scan of the tile sums (the value each tile starts from), or empty when the
        /// input is a single tile, which then starts from zero.
        pub tile_offsets: DevSlice<u32>,
        /// Receives the exclusive prefix sums; may be the same memory as `input`.
        pub output: DevSlice<u32>,
        /// Number of elements.
        pub n: u32,
        /// Keeps the struct free of implicit padding (checked by its `NoUninit` derive).
        pub reserved: u32,
    }
}

/// Thread `t` writes the exclusive prefix sums of tile `t`, starting from its tile offset.
/// Each thread reads an element before writing it and touches only its own tile, so scanning
/// in place is safe.
#[inline(always)]
pub fn scan_tiles(t: Thread, args: &ScanArgs) {
    let tile = t.global();
    if tile >= tiles(args.n) {
        return;
    }
    let offset = if args.tile_offsets.is_empty() {
        0
    } else {
        args.tile_offsets.get(tile)
    };
    scan_tile(args, tile, offset);
}

/// [`scan_tiles`] where `tile_offsets` holds the tile sums themselves (of [`reduce_tiles`],
/// at most [`FLAT_TILES`] of them, not scanned). The warp of tiles `w .. w + 32` adds up the
/// sums before `w` together, each lane runs of four, every `4 · 32`-th (at most
/// `FLAT_TILES / 32` reads a lane, in flight together, instead of up to `FLAT_TILES` for the
/// last tile alone), and scans its own 32 sums across its lanes. Integer sums: the result
/// does not depend on their order. A full tile's values are asked for first, so that the
/// thread waits for memory once.
#[inline(always)]
pub fn scan_tiles_after_sums(t: Thread, args: &ScanArgs) {
    let tile = t.global();
    let lane = t.lane();
    // The warp's first tile: the same in all its lanes, which all take part below.
    let first = tile - lane;
    let count = tiles(args.n);
    let sums = args.tile_offsets;
    let start = tile * TILE;
    let full = start + TILE <= args.n;
    let values = match full {
        true => asked(args.input.get_run::<{ TILE as usize }>(start)),
        false => [0; TILE as usize],
    };
    // A warp wholly past the last tile (its block's tail) sums nothing: it writes nothing.
    let before_end = if first < count { first } else { 0 };
    let before = warp::sum_u32(lane, |l| {
        let add = |sum: u32, [a, b, c, d]: [u32; 4]| {
            sum.wrapping_add(a)
                .wrapping_add(b)
                .wrapping_add(c)
                .wrapping_add(d)
        };
        sums.fold_runs((4 * l, before_end, 4 * warp::WARP), 0u32, add)
    });
    let within = warp::exclusive_sum_u32(lane, |l| {
        if first + l < count {
            sums.get(first + l)
        } else {
            0
        }
    });
    if tile >= count {
        return;
    }
    let running = before.wrapping_add(within);
    match full {
        true => scan_run(args, start, values, running),
        false => scan_tile(args, tile, running),
    }
}

/// Writes the exclusive prefix sums of tile `tile`, from `running`.
#[inline(always)]
fn scan_tile(args: &ScanArgs, tile: u32, mut running: u32) {
    let start = tile * TILE;
    let end = args.n.min(start + TILE);
    if end - start == TILE {
        scan_run(args, start, args.input.get_run(start), running);
    } else {
        for i in start..end {
            let value = args.input.get(i);
            args.output.set(i, running);
            running = running.wrapping_add(value);
        }
    }
}

/// Writes the exclusive prefix sums of the full tile from `start`, whose values are
/// `values`, from `running`.
#[inline(always)]
fn scan_run(args: &ScanArgs, start: u32, mut values: [u32; TILE as usize], mut running: u32) {
    for value in &mut values {
        (*value, running) = (running, running.wrapping_add(*value));
    }
    args.output.set_run(start, values);
}
