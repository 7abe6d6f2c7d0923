//! The host halves of the parallel primitives: which kernels run, in which order, on which
//! scratch buffers. The device halves are in `gpuwars_kernels::primitives`.
//!
//! Scratch buffers are allocated once for a capacity ([`PrefixSum::new`],
//! [`CountingSort::new`]) so that a game step allocates nothing.

use gpuwars_kernels::primitives::{histogram as hist, scan, sort};
use gpuwars_kernels::{DevSlice, Kernel, KernelArgs, registry};

use crate::backend::{Binder, Launch};
use crate::{Buffer, Device, Error, Op};

/// Threads per block of the primitives' launches (and of the step's): 128 measured faster
/// than 256 at a million slots on the H200 (1,683 -> 1,731 steps/s with the scans below),
/// within 1.4% at 8K.
pub const BLOCK: u32 = 128;

/// Threads per block of the launches whose threads each make a few loads and a store or two
/// (marking and gathering the free lists, placing the bodies in their cells): their blocks
/// end so soon that starting blocks bounds them, and blocks of 256 halve the blocks
/// (at 16.76M slots on the H200: `mark_free` 160 -> 94 µs, `gather_free` 159 -> 100,
/// `place_in_cells` 159 -> 100; blocks of 512 were slower again). The heavier kernels keep
/// [`BLOCK`]: with 256 they lose occupancy (`think` 1,753 -> 1,922 µs, `collide_circles`
/// 574 -> 667).
pub const LIGHT_BLOCK: u32 = 256;

/// Threads per block of the narrow phase's launches, whose warps take very different times
/// (the few bodies near the ship and its shots test their contacts, the rest return at
/// once): blocks of two warps give their multiprocessor's room back two warps at a time. At
/// 16.76M slots on the H200, `collide_circles_swept` 437.7 -> 422.8 µs a step against
/// [`BLOCK`] (`think`'s time did not move in blocks of 64).
pub const UNEVEN_BLOCK: u32 = 64;

/// Threads per block of the prefix sum's launches: a warp a tile of 1,024 elements, so few
/// warps (9 for 8,288 elements), spread over more of the GPU's multiprocessors in blocks of
/// one warp (with a thread a tile of 32: the free lists 22 -> 11 µs, the broad phase 24 -> 15
/// µs at 8K).
const SCAN_BLOCK: u32 = 32;

/// A launch of `kernel` on at least `threads` threads, in blocks of [`BLOCK`]: see
/// [`Op::launch`].
///
/// # Safety
/// As for [`Op::launch`].
pub(crate) unsafe fn threads<A: KernelArgs>(
    kernel: Kernel<A>,
    threads: u32,
    args: A,
    binder: Binder,
    bytes: u64,
) -> Op {
    // SAFETY: forwarded.
    unsafe { threads_in(kernel, threads, BLOCK, args, binder, bytes) }
}

/// [`threads`] in blocks of `block` threads ([`LIGHT_BLOCK`] for kernels whose threads do
/// little).
///
/// # Safety
/// As for [`Op::launch`].
pub(crate) unsafe fn threads_in<A: KernelArgs>(
    kernel: Kernel<A>,
    threads: u32,
    block: u32,
    args: A,
    binder: Binder,
    bytes: u64,
) -> Op {
    let launch = Launch {
        kernel,
        grid: threads.div_ceil(block),
        block,
        args,
    };
    // SAFETY: forwarded.
    unsafe { Op::launch(launch, binder, bytes) }
}

/// `n` as a kernel size, after checking it fits the buffers and the scratch capacity (if any).
fn checked_n(
    what: &str,
    n: usize,
    capacity: Option<usize>,
    buffers: &[(&str, usize)],
) -> Result<u32, Error> {
    if let Some(capacity) = capacity.filter(|&c| n > c) {
        return Err(Error::Invalid(format!(
            "{what} of {n} elements exceeds the capacity {capacity} it was created for"
        )));
    }
    for (name, len) in buffers {
        if n > *len {
            return Err(Error::Invalid(format!(
                "{what} of {n} elements: the {name} buffer holds only {len}"
            )));
        }
    }
    u32::try_from(n).map_err(|_| Error::Invalid(format!("{what} of {n} elements (too many)")))
}

/// Exclusive prefix sum of `u32` (wrapping): `output[i] = input[0] + … + input[i-1]`.
pub struct PrefixSum {
    /// One buffer of tile sums per recursion level.
    levels: Vec<Buffer<u32>>,
    capacity: usize,
}

impl PrefixSum {
    /// Scratch for sums of up to `capacity` elements.
    pub fn new(device: &Device, capacity: usize) -> Result<Self, Error> {
        let levels = Self::level_lens(capacity)?
            .into_iter()
            .map(|len| device.alloc_zeroed(len))
            .collect::<Result<_, _>>()?;
        Ok(PrefixSum { levels, capacity })
    }

    /// The length of each level of tile sums for `capacity` elements.
    fn level_lens(capacity: usize) -> Result<Vec<usize>, Error> {
        let mut n = u32::try_from(capacity)
            .map_err(|_| Error::Invalid(format!("a prefix sum of {capacity} elements")))?;
        let mut lens = Vec::new();
        while n > scan::TILE {
            n = scan::tiles(n);
            lens.push(n as usize);
        }
        Ok(lens)
    }

    /// Elements of scratch that [`PrefixSum::new`] allocates for `capacity` elements.
    pub fn scratch_len(capacity: usize) -> usize {
        Self::level_lens(capacity).map_or(0, |lens| lens.iter().sum())
    }

    /// The most elements one call can scan.
    pub fn capacity(&self) -> usize {
        self.capacity
    }

    /// Writes the exclusive prefix sums of the first `n` elements of `input` to `output`.
    pub fn run(
        &mut self,
        device: &Device,
        input: &Buffer<u32>,
        output: &mut Buffer<u32>,
        n: usize,
    ) -> Result<(), Error> {
        let n = checked_n(
            "a prefix sum",
            n,
            Some(self.capacity),
            &[("input", input.len()), ("output", output.len())],
        )?;
        let ops = self.ops(input, output, n)?;
        device.run(&device.plan(ops, false)?)
    }

    /// Replaces the first `n` elements of `data` by their exclusive prefix sums.
    pub fn run_in_place(
        &mut self,
        device: &Device,
        data: &mut Buffer<u32>,
        n: usize,
    ) -> Result<(), Error> {
        let n = checked_n(
            "a prefix sum",
            n,
            Some(self.capacity),
            &[("data", data.len())],
        )?;
        // `scan_tiles` supports input == output.
        let ops = self.ops(data, data, n)?;
        device.run(&device.plan(ops, false)?)
    }

    /// The launches that write the exclusive prefix sums of the first `n` elements of
    /// `input` to `output` (which may be `input` itself), for a plan; they hold both
    /// buffers and this scratch.
    pub fn ops(&self, input: &Buffer<u32>, output: &Buffer<u32>, n: u32) -> Result<Vec<Op>, Error> {
        if n as usize > input.len().min(output.len()) || n as usize > self.capacity {
            return Err(Error::Invalid(format!(
                "a prefix sum of {n} elements from {} into {} (capacity {})",
                input.len(),
                output.len(),
                self.capacity
            )));
        }
        let mut ops = Vec::new();
        self.push_ops(input, output, n, (None, 0), &mut ops);
        Ok(ops)
    }

    /// The launches of [`PrefixSum::ops`] with the first level's tile sums in `sums`, one per
    /// [`scan::TILE`] elements, rather than in this scratch: worked out there first unless
    /// `kept` (whoever writes `input` keeps them up to date), then each tile's warp adds up
    /// those before its own (one launch, where they are few enough: [`scan::FLAT_TILES`]),
    /// or they are scanned on this scratch's levels first.
    pub fn ops_with_sums(
        &self,
        input: &Buffer<u32>,
        output: &Buffer<u32>,
        n: u32,
        (sums, kept): (&Buffer<u32>, bool),
    ) -> Result<Vec<Op>, Error> {
        // A single tile reads no sums.
        let single = n <= scan::TILE;
        if n as usize > input.len().min(output.len())
            || (!single && scan::tiles(n) as usize > sums.len())
            || n as usize > self.capacity
        {
            return Err(Error::Invalid(format!(
                "a prefix sum of {n} elements from {} into {} with {} tile sums (capacity {})",
                input.len(),
                output.len(),
                sums.len(),
                self.capacity
            )));
        }
        let mut ops = Vec::new();
        self.push_ops(input, output, n, (Some((sums, kept)), 0), &mut ops);
        Ok(ops)
    }

    /// The launch that writes the sum of each tile of the first `n` elements of `input` to
    /// `sums`.
    fn reduce_op(input: &Buffer<u32>, sums: &Buffer<u32>, n: u32) -> Op {
        let tiles = scan::tiles(n);
        // SAFETY: the views go into the op made with the binder.
        let mut b = unsafe { Binder::new() };
        let args = scan::ReduceArgs {
            input: b.view_prefix(input, n),
            tile_sums: b.view_prefix(sums, tiles),
            n,
            reserved: 0,
        };
        let bytes = 4 * u64::from(n + tiles);
        // SAFETY: `n` elements in the input's view, a sum a tile (checked by the callers).
        unsafe {
            threads_in(
                registry::SCAN_REDUCE,
                scan::threads(n),
                SCAN_BLOCK,
                args,
                b,
                bytes,
            )
        }
    }

    /// The launch that scans each tile of the first `n` elements of `input` into `output`,
    /// from its offset (see [`TileOffsets`]), or from zero without them (a single tile).
    fn tiles_op(
        input: &Buffer<u32>,
        output: &Buffer<u32>,
        n: u32,
        offsets: Option<TileOffsets>,
    ) -> Op {
        // SAFETY: the views go into the op made with the binder.
        let mut b = unsafe { Binder::new() };
        let tile_offsets = match offsets {
            Some(TileOffsets::Sums(s) | TileOffsets::Scanned(s)) => {
                b.view_prefix(s, scan::tiles(n))
            }
            None => DevSlice::EMPTY,
        };
        let args = scan::ScanArgs {
            input: b.view_prefix(input, n),
            tile_offsets,
            output: b.view_prefix(output, n),
            n,
            reserved: 0,
        };
        let bytes = 4 * u64::from(2 * n + tile_offsets.len());
        let kernel = match offsets {
            Some(TileOffsets::Sums(_)) => registry::SCAN_TILES_AFTER_SUMS,
            _ => registry::SCAN_TILES,
        };
        // SAFETY: `n` elements in each view and a sum a tile (checked by the callers); the
        // scan supports `input == output`.
        unsafe { threads_in(kernel, scan::threads(n), SCAN_BLOCK, args, b, bytes) }
    }

    /// The launches that scan the first `n` elements of `input` into `output`, with their
    /// tiles' sums `given` (and, if so, kept up to date by whoever writes `input`), else in
    /// this scratch's level `level`; the scratch's levels from `level` on (past the one
    /// used) are free for the scan of the sums, which is done in place in the scratch and
    /// into the next free level where the sums are given (they are left as they are).
    fn push_ops(
        &self,
        input: &Buffer<u32>,
        output: &Buffer<u32>,
        n: u32,
        (given, level): (Option<(&Buffer<u32>, bool)>, usize),
        ops: &mut Vec<Op>,
    ) {
        if n <= scan::TILE {
            ops.push(Self::tiles_op(input, output, n, None));
            return;
        }
        let (sums, kept, free) = match given {
            Some((sums, kept)) => (sums, kept, level),
            None => (&self.levels[level], false, level + 1),
        };
        if !kept {
            ops.push(Self::reduce_op(input, sums, n));
        }
        let tiles = scan::tiles(n);
        // Few tiles: each adds up the sums before its own; else the sums are scanned first.
        let offsets = if tiles <= scan::FLAT_TILES {
            TileOffsets::Sums(sums)
        } else {
            let (scanned, free) = match given {
                Some(_) => (&self.levels[free], free + 1),
                None => (sums, free),
            };
            self.push_ops(sums, scanned, tiles, (None, free), ops);
            TileOffsets::Scanned(scanned)
        };
        ops.push(Self::tiles_op(input, output, n, Some(offsets)));
    }
}

/// Where each tile of a scan starts from.
#[derive(Clone, Copy)]
enum TileOffsets<'a> {
    /// The tiles' sums, which each tile's warp adds up before its own.
    Sums(&'a Buffer<u32>),
    /// Their exclusive prefix sums: each tile's offset itself.
    Scanned(&'a Buffer<u32>),
}

/// Counts how many of the first `n` keys fall in each bin: `counts[k]` becomes the number of
/// keys equal to `k`. Keys not below `counts.len()` are not counted.
pub fn histogram(
    device: &Device,
    keys: &Buffer<u32>,
    n: usize,
    counts: &mut Buffer<u32>,
) -> Result<(), Error> {
    let n = checked_n("a histogram", n, None, &[("keys", keys.len())])?;
    device.zero(counts)?;
    // SAFETY: the views go into this op only.
    let mut b = unsafe { Binder::new() };
    let args = hist::HistogramArgs {
        keys: b.view_prefix(keys, n),
        counts: b.view(counts),
        n,
        reserved: 0,
    };
    // SAFETY: `n` keys in view; the keys and the counts are two buffers.
    device.launch(unsafe { threads(registry::HISTOGRAM, n, args, b, 0) })
}

/// Deterministic counting sort of `(key, index)` pairs: sorts keys below a bound and returns,
/// for each output slot, the key and its position in the input. Equal keys come out in index
/// order, whatever the backend or thread count.
pub struct CountingSort {
    counts: Buffer<u32>,
    scan: PrefixSum,
    keys_tmp: Buffer<u32>,
    indices_tmp: Buffer<u32>,
    capacity: usize,
}

impl CountingSort {
    /// Scratch for sorts of up to `capacity` keys.
    pub fn new(device: &Device, capacity: usize) -> Result<Self, Error> {
        let tiles = u32::try_from(capacity)
            .map(sort::tiles)
            .map_err(|_| Error::Invalid(format!("a sort of {capacity} keys")))?;
        let matrix = sort::RADIX as usize * tiles as usize;
        Ok(CountingSort {
            counts: device.alloc_zeroed(matrix)?,
            scan: PrefixSum::new(device, matrix)?,
            keys_tmp: device.alloc_zeroed(capacity)?,
            indices_tmp: device.alloc_zeroed(capacity)?,
            capacity,
        })
    }

    /// The most keys one call can sort.
    pub fn capacity(&self) -> usize {
        self.capacity
    }

    /// Sorts the first `n` keys, all below `key_bound`, into `keys_out` and writes each sorted
    /// key's input position to `indices_out`. A key not below the bound is still moved (the
    /// output stays a permutation) but is ordered by its low bits only.
    pub fn run(
        &mut self,
        device: &Device,
        keys: &Buffer<u32>,
        n: usize,
        key_bound: u32,
        keys_out: &mut Buffer<u32>,
        indices_out: &mut Buffer<u32>,
    ) -> Result<(), Error> {
        let n = checked_n(
            "a sort",
            n,
            Some(self.capacity),
            &[
                ("keys", keys.len()),
                ("keys_out", keys_out.len()),
                ("indices_out", indices_out.len()),
            ],
        )?;
        let tiles = sort::tiles(n);
        let matrix = sort::RADIX * tiles;
        let passes = sort::passes(key_bound);
        let (mut keys_in, mut indices_in) = (keys, None);
        for pass in 0..passes {
            // Alternate so that the last pass lands in the caller's buffers.
            let (k_out, i_out): (&Buffer<u32>, &Buffer<u32>) =
                if (passes - 1 - pass).is_multiple_of(2) {
                    (keys_out, indices_out)
                } else {
                    (&self.keys_tmp, &self.indices_tmp)
                };
            let shift = pass * sort::DIGIT_BITS;
            // SAFETY (both binders): their views go into the op made with each.
            let mut b = unsafe { Binder::new() };
            let count = sort::CountArgs {
                keys: b.view_prefix(keys_in, n),
                counts: b.view_prefix(&self.counts, matrix),
                n,
                shift,
            };
            // SAFETY: `n` keys (checked), the counts sized for the tiles; two buffers.
            let count = unsafe { threads(registry::SORT_COUNT, tiles, count, b, 0) };
            let mut b = unsafe { Binder::new() };
            let scatter = sort::ScatterArgs {
                keys_in: b.view_prefix(keys_in, n),
                indices_in: indices_in.map_or(DevSlice::EMPTY, |i| b.view_prefix(i, n)),
                offsets: b.view_prefix(&self.counts, matrix),
                keys_out: b.view_prefix(k_out, n),
                indices_out: b.view_prefix(i_out, n),
                n,
                shift,
            };
            // SAFETY: as above; a pass's inputs and outputs are distinct buffers.
            let scatter = unsafe { threads(registry::SORT_SCATTER, tiles, scatter, b, 0) };
            let mut ops = vec![count];
            ops.extend(self.scan.ops(&self.counts, &self.counts, matrix)?);
            ops.push(scatter);
            device.run(&device.plan(ops, false)?)?;
            keys_in = k_out;
            indices_in = Some(i_out);
        }
        Ok(())
    }
}
