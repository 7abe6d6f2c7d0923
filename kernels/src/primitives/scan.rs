//! Exclusive prefix sum of `u32` (wrapping, i.e. modulo 2^32), in tiles of a warp.
//!
//! One pass of the multi-launch scan: [`reduce_tiles`] writes the sum of every tile of
//! [`TILE`] elements; the host scans those sums (recursively, with the same two kernels) into
//! per-tile starting offsets; [`scan_tiles`] then scans each tile once more from its offset.
//! A problem of `n` elements takes `2·⌈log_TILE n⌉ - 1` launches and no barrier.
//!
//! Up to [`FLAT_TILES`] tiles, [`scan_tiles_after_sums`] replaces the recursion: each warp
//! adds up the sums of the tiles before its own (a warp collective) and scans its own, so
//! the scan takes two launches.
//!
//! A warp takes a tile, row by row: each row of 32 elements is one coalesced access (see
//! [`warp::exclusive_scan_tile`]). On the CPU the warp's lane 0 takes it alone.

use crate::warp::{WARP, is_copy_of_lane0};
use crate::{DevSlice, Thread, kernel_args, warp};

/// Elements per tile: a warp's, 32 rows of 32. A million buckets are 1,024 tiles or fewer,
/// which [`scan_tiles_after_sums`] scans in two launches.
pub const TILE: u32 = WARP * WARP;

/// Most tiles [`scan_tiles_after_sums`] takes: a lane reads at most `FLAT_TILES / 32` tile
/// sums.
pub const FLAT_TILES: u32 = 1024;

/// Number of tiles covering `n` elements.
#[inline(always)]
pub const fn tiles(n: u32) -> u32 {
    n.div_ceil(TILE)
}

/// Threads of a launch that gives each of `n` elements' tiles its warp.
#[inline(always)]
pub const fn threads(n: u32) -> u32 {
    tiles(n) * WARP
}

/// The calling thread's tile (its warp's) and lane, if its warp has a tile of `n` elements
/// and the thread does its share of it (on the CPU, lane 0 takes the whole tile).
#[inline(always)]
fn tile_of(t: Thread, n: u32) -> Option<(u32, u32)> {
    let (tile, lane) = (t.global() / WARP, t.lane());
    (tile < tiles(n) && !is_copy_of_lane0(lane)).then_some((tile, lane))
}

/// Tile `tile`'s first element and its length (of `n` elements).
#[inline(always)]
fn tile_range(tile: u32, n: u32) -> (u32, u32) {
    let start = tile * TILE;
    (start, (n - start).min(TILE))
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

/// Warp `w` writes the wrapping sum of tile `w` of the input: each lane adds up a column
/// (its element of every row, loads in flight together), and the warp the columns.
#[inline(always)]
pub fn reduce_tiles(t: Thread, args: &ReduceArgs) {
    let Some((tile, lane)) = tile_of(t, args.n) else {
        return;
    };
    let (start, len) = tile_range(tile, args.n);
    let input = args.input.range(start, len);
    let column = |l: u32| {
        let values: [u32; WARP as usize] = core::array::from_fn(|row| {
            let i = row as u32 * WARP + l;
            if i < len { input.get(i) } else { 0 }
        });
        values.into_iter().fold(0u32, u32::wrapping_add)
    };
    let sum = warp::sum_u32(lane, column);
    if lane == 0 {
        args.tile_sums.set(tile, sum);
    }
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

/// Warp `w` writes the exclusive prefix sums of tile `w`, starting from its tile offset.
/// Every value of the tile is read before the first is written, and a warp touches only its
/// own tile, so scanning in place is safe.
#[inline(always)]
pub fn scan_tiles(t: Thread, args: &ScanArgs) {
    let Some((tile, lane)) = tile_of(t, args.n) else {
        return;
    };
    let offset = if args.tile_offsets.is_empty() {
        0
    } else {
        args.tile_offsets.get(tile)
    };
    scan_tile(args, (tile, lane), offset);
}

/// [`scan_tiles`] where `tile_offsets` holds the tile sums themselves (of [`reduce_tiles`],
/// at most [`FLAT_TILES`] of them, not scanned): the warp of tile `w` adds up the sums before
/// `w` together, each lane every 32nd (at most `FLAT_TILES / 32` reads a lane, all in flight
/// at once, instead of up to `FLAT_TILES` for the last tile alone), and scans its tile from
/// their sum. Integer sums: the result does not depend on their order.
#[inline(always)]
pub fn scan_tiles_after_sums(t: Thread, args: &ScanArgs) {
    let Some((tile, lane)) = tile_of(t, args.n) else {
        return;
    };
    let sums = args.tile_offsets.range(0, tile);
    let before = warp::sum_u32(lane, |l| {
        // On the CPU one thread adds up every lane's share: only the sums there are read.
        if cfg!(not(target_arch = "nvptx64")) {
            return sums.fold_every((l, tile, WARP), 0, u32::wrapping_add);
        }
        let column: [u32; (FLAT_TILES / WARP) as usize] = core::array::from_fn(|k| {
            let i = k as u32 * WARP + l;
            if i < tile { sums.get(i) } else { 0 }
        });
        column.into_iter().fold(0u32, u32::wrapping_add)
    });
    scan_tile(args, (tile, lane), before);
}

/// Writes the exclusive prefix sums of tile `tile`, from `offset`, the calling thread
/// taking lane `lane`'s share.
#[inline(always)]
fn scan_tile(args: &ScanArgs, (tile, lane): (u32, u32), offset: u32) {
    let (start, len) = tile_range(tile, args.n);
    let (input, output) = (args.input.range(start, len), args.output.range(start, len));
    warp::exclusive_scan_tile(
        lane,
        (len, offset),
        |i| input.get(i),
        |i, v| output.set(i, v),
    );
}
