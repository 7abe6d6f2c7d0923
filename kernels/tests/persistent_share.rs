//! How the persistent step's real threads share a stage's virtual threads
//! (`persistent::share`): every real thread gets exactly the virtual threads `first`,
//! `first + threads`, … below the stage's count, each with the block and thread that a
//! 64-bit division of its index gives, at the edges of every argument.

use gpuwars_kernels::Thread;
use gpuwars_kernels::persistent::{Stage, share};

/// The virtual threads of `stage` that real thread `first` of `threads` holds, by the
/// definition: each index of the stride below the stage's count, divided in 64 bits.
fn by_division(stage: &Stage, first: u32, threads: u32) -> Vec<(u32, u32)> {
    let total = u64::from(stage.grid) * u64::from(stage.block);
    (u64::from(first)..total)
        .step_by(threads as usize)
        .map(|v| {
            let block = u64::from(stage.block);
            ((v / block) as u32, (v % block) as u32)
        })
        .collect()
}

/// What `share` calls `f` with, as (block, thread), each call checked to carry the stage's
/// dimensions.
fn shared(stage: &Stage, first: u32, threads: u32) -> Vec<(u32, u32)> {
    let mut got = Vec::new();
    share(stage, first, threads, |t: Thread| {
        assert_eq!((t.block_dim, t.grid_dim), (stage.block, stage.grid));
        got.push((t.block, t.thread));
    });
    got
}

#[test]
fn every_real_thread_holds_the_virtual_threads_of_its_stride() {
    // Blocks of one warp to the most; grids empty, of one block and beyond the real
    // threads; real grids narrower and wider than a stage block, and not multiples of it.
    for block in [32, 64, 96, 128, 512, 1024] {
        for grid in [0, 1, 2, 3, 7, 65, 130] {
            for threads in [32, 64, 96, 128, 160, 1024, 1056, 4096, 8320] {
                let stage = Stage {
                    kernel: 0,
                    grid,
                    block,
                    args: 0,
                };
                let total = u64::from(grid) * u64::from(block);
                // Every real thread, where there are few; else the first, the last and
                // those around each stage block's edge.
                let firsts: Vec<u32> = match threads <= 160 {
                    true => (0..threads).collect(),
                    false => [0, 1, 31, block - 1, block, block + 1, threads - 1]
                        .into_iter()
                        .filter(|&f| f < threads)
                        .collect(),
                };
                for first in firsts {
                    let want = by_division(&stage, first, threads);
                    assert_eq!(
                        shared(&stage, first, threads),
                        want,
                        "grid {grid} × block {block}, real thread {first} of {threads}"
                    );
                    assert_eq!(want.is_empty(), u64::from(first) >= total);
                }
            }
        }
    }
}

#[test]
fn a_stage_past_four_billion_threads_is_walked_without_wrapping() {
    // The stage's count does not fit 32 bits: the last virtual threads lie beyond it.
    let stage = Stage {
        kernel: 0,
        grid: u32::MAX,
        block: 1024,
        args: 0,
    };
    let threads = 1 << 31;
    let first = (1 << 31) - 32;
    let got = shared(&stage, first, threads);
    assert_eq!(got, by_division(&stage, first, threads));
    // The walk went past the 2^32nd virtual thread (block 2^22 of 1,024 threads).
    assert!(got.last().is_some_and(|&(block, _)| block >= 1 << 22));
}

#[test]
fn a_stage_of_no_threads_gives_none() {
    let stage = Stage {
        kernel: 0,
        grid: 5,
        block: 0,
        args: 0,
    };
    assert!(shared(&stage, 0, 128).is_empty());
}
