//! The host halves of the parallel primitives: which kernels run, in which order, on which
//! scratch buffers. The device halves are in `gpuwars_kernels::primitives`.
//!
//! Scratch buffers are allocated once for a capacity ([`PrefixSum::new`],
//! [`CountingSort::new`]) so that a game step allocates nothing.

use gpuwars_kernels::primitives::{histogram as hist, scan, sort};
use gpuwars_kernels::{DevSlice, registry};

use crate::{Buffer, Device, Error, Op};

/// Threads per block of every primitive's launches.
pub const BLOCK: u32 = 256;

fn grid(threads: u32) -> u32 {
    threads.div_ceil(BLOCK)
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
        // SAFETY: the views are of live buffers of `device`, `n` within each (checked), and
        // the ops run before this borrow of them ends.
        let ops = unsafe { self.ops(input.view_prefix(n), output.view_prefix(n)) }?;
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
        let view = data.view_prefix(n);
        // SAFETY: as in `run`; `scan_tiles` supports input == output.
        let ops = unsafe { self.ops(view, view) }?;
        device.run(&device.plan(ops, false)?)
    }

    /// The launches that write the exclusive prefix sums of `input` to `output` (which may
    /// be `input` itself), for a plan.
    ///
    /// # Safety
    /// As for [`Op::launch`]: `input` and `output` view buffers of the device that will run
    /// the ops, of the same length, and outlive them; so does this scratch.
    pub unsafe fn ops(
        &self,
        input: DevSlice<u32>,
        output: DevSlice<u32>,
    ) -> Result<Vec<Op>, Error> {
        if input.len() != output.len() || input.len() as usize > self.capacity {
            return Err(Error::Invalid(format!(
                "a prefix sum of {} elements into {} (capacity {})",
                input.len(),
                output.len(),
                self.capacity
            )));
        }
        let mut ops = Vec::new();
        // SAFETY: forwarded from the caller.
        unsafe { self.push_ops(input, output, 0, &mut ops) };
        Ok(ops)
    }

    /// # Safety
    /// As for [`PrefixSum::ops`]; `level` indexes the scratch that matches their length.
    unsafe fn push_ops(
        &self,
        input: DevSlice<u32>,
        output: DevSlice<u32>,
        level: usize,
        ops: &mut Vec<Op>,
    ) {
        let n = input.len();
        let tiles = scan::tiles(n);
        // Few tiles: each adds up the sums before its own (two launches); else recurse.
        let flat = n > scan::TILE && tiles <= scan::FLAT_TILES;
        let tile_offsets = if n <= scan::TILE {
            DevSlice::EMPTY
        } else {
            let sums = self.levels[level].view_prefix(tiles);
            let args = scan::ReduceArgs {
                input,
                tile_sums: sums,
                n,
                reserved: 0,
            };
            let bytes = 4 * u64::from(n + tiles);
            // SAFETY: forwarded; the scratch level holds `tiles` elements.
            unsafe {
                ops.push(Op::launch(
                    registry::SCAN_REDUCE,
                    grid(tiles),
                    BLOCK,
                    args,
                    bytes,
                ));
                if !flat {
                    self.push_ops(sums, sums, level + 1, ops);
                }
            }
            sums
        };
        let args = scan::ScanArgs {
            input,
            tile_offsets,
            output,
            n,
            reserved: 0,
        };
        let bytes = 4 * u64::from(2 * n + tile_offsets.len());
        let kernel = if flat {
            registry::SCAN_TILES_AFTER_SUMS
        } else {
            registry::SCAN_TILES
        };
        // SAFETY: forwarded.
        ops.push(unsafe { Op::launch(kernel, grid(tiles), BLOCK, args, bytes) });
    }
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
    let args = hist::HistogramArgs {
        keys: keys.view_prefix(n),
        counts: counts.view(),
        n,
        reserved: 0,
    };
    // SAFETY: live buffers of `device`, `n` keys in view.
    unsafe { device.launch(registry::HISTOGRAM, grid(n), BLOCK, &args) }
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
        let matrix = self.counts.view_prefix(sort::RADIX * tiles);
        let passes = sort::passes(key_bound);
        let mut keys_in = keys.view_prefix(n);
        let mut indices_in = DevSlice::EMPTY;
        for pass in 0..passes {
            // Alternate so that the last pass lands in the caller's buffers.
            let (k_out, i_out) = if (passes - 1 - pass).is_multiple_of(2) {
                (keys_out.view_prefix(n), indices_out.view_prefix(n))
            } else {
                (
                    self.keys_tmp.view_prefix(n),
                    self.indices_tmp.view_prefix(n),
                )
            };
            let shift = pass * sort::DIGIT_BITS;
            let count = sort::CountArgs {
                keys: keys_in,
                counts: matrix,
                n,
                shift,
            };
            let scatter = sort::ScatterArgs {
                keys_in,
                indices_in,
                offsets: matrix,
                keys_out: k_out,
                indices_out: i_out,
                n,
                shift,
            };
            // SAFETY: every view is of a live buffer of `device` sized for `n` keys (checked
            // above or allocated for the capacity); input and output of a pass are distinct;
            // the ops run before this call returns.
            unsafe {
                device.launch(registry::SORT_COUNT, grid(tiles), BLOCK, &count)?;
                device.run(&device.plan(self.scan.ops(matrix, matrix)?, false)?)?;
                device.launch(registry::SORT_SCATTER, grid(tiles), BLOCK, &scatter)?;
            }
            keys_in = k_out;
            indices_in = i_out;
        }
        Ok(())
    }
}
