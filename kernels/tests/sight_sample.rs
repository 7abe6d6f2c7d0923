//! A look under a budget (`CellIndex::merge_near_in` with a `Sample`) takes, of each run of
//! cells it reads (a row of its block, one kind), exactly every stride-th entry from the
//! phase on, the stride being `⌈entries / ⌈budget / 3⌉⌉`, in visiting order, each with its
//! stride as the weight: never more than `⌈budget / 3⌉` of a run, and where no run exceeds
//! that, every entry of the plain query (`for_each_near`). Checked against the runs listed
//! from the block's rows and columns by hand, over random small grids, with and without a
//! cap.

use glam::Vec2;
use gpuwars_kernels::DevSlice;
use gpuwars_kernels::access::Access;
use gpuwars_kernels::sim::Space;
use gpuwars_kernels::sim::broad::{CellIndex, Near, Sample, kinds_mask};
use gpuwars_kernels::warp::{Handed, Team};

/// A small deterministic generator (64-bit LCG, high bits).
struct Lcg(u64);

impl Lcg {
    fn below(&mut self, n: u32) -> u32 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((self.0 >> 33) % u64::from(n)) as u32
    }
}

/// What a look folded: the entries it took in order, as one order-sensitive number, how
/// many, and the sum of their weights.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct Taken {
    mix: u64,
    count: u32,
    weights: u64,
}

impl Handed for Taken {}

impl Taken {
    fn add(self, weight: u32, slot: u32, entry: u32) -> Taken {
        let mix = self.mix.wrapping_mul(1_000_003).wrapping_add(
            u64::from(slot) << 40 | u64::from(entry) << 8 | u64::from(weight.min(255)),
        );
        Taken {
            mix,
            count: self.count + 1,
            weights: self.weights + u64::from(weight),
        }
    }
}

/// A view of `data` for the test's lifetime.
fn view<T: Copy, A: Access>(data: &[T]) -> DevSlice<T, A> {
    // SAFETY: every vector viewed outlives its views (they live in the same test), and
    // nothing writes them while they are read.
    unsafe { DevSlice::from_raw_parts(data.as_ptr() as u64, data.len() as u32) }
}

#[test]
fn a_sampled_look_takes_every_strided_entry_of_each_kind_within_the_budget() {
    let mut rng = Lcg(7);
    for case in 0..400 {
        let (cols, rows, kinds) = (1 + rng.below(5), 1 + rng.below(4), 1 + rng.below(3));
        let wraps = rng.below(2) == 1;
        let space = Space {
            size: Vec2::new(cols as f32 * 10.0, rows as f32 * 10.0),
            inv_cell: Vec2::splat(0.1),
            cols,
            rows,
            wrap: u32::from(wraps),
            reserved: 0,
        };
        let cells = cols * rows;
        // Buckets of 0 to 3 entries, or now and then a crowd of up to 90.
        let counts: Vec<u32> = (0..kinds * cells)
            .map(|_| match rng.below(6) {
                0 => rng.below(90),
                _ => rng.below(4),
            })
            .collect();
        let mut start = vec![0u32];
        for c in &counts {
            start.push(start.last().unwrap() + c);
        }
        let entries = *start.last().unwrap();
        let slots: Vec<u32> = (0..entries).map(|e| e * 3 + 1).collect();
        // Each entry in its bucket's cell, as a built grid has it.
        let pos: Vec<Vec2> = (0..kinds * cells)
            .flat_map(|bucket| {
                let cell = bucket % cells;
                let at = Vec2::new((cell % cols) as f32 + 0.5, (cell / cols) as f32 + 0.5);
                (start[bucket as usize]..start[bucket as usize + 1]).map(move |_| at * 10.0)
            })
            .collect();
        // Each kind's first and last row with an entry, as the grid's ordering notes them
        // (the queries skip the rows outside them).
        let kind_rows: Vec<u32> = (0..kinds)
            .flat_map(|k| {
                let rows_with = (0..cells)
                    .filter(|&c| counts[(k * cells + c) as usize] > 0)
                    .map(|c| c / cols);
                [rows_with.clone().min(), rows_with.max()].map(|r| r.unwrap_or(0))
            })
            .collect();
        let cap = [0, 0, 1 + rng.below(150)][rng.below(3) as usize];
        let none: Vec<Vec2> = Vec::new();
        let grid = CellIndex {
            slots: view(&slots),
            pos: view(&pos),
            vel: view(&none),
            prev: view(&none),
            start: view(&start),
            rows: view(&kind_rows),
            kinds,
            cells,
            cap,
            reserved: 0,
        };
        let near = Near {
            pos: Vec2::new(
                rng.below(cols * 10) as f32 + 0.5,
                rng.below(rows * 10) as f32 + 0.5,
            ),
            reach: None,
            mask: 1 + rng.below((1 << kinds) - 1),
        };
        // The runs the look reads, in visiting order, cut at the cap.
        let (rows, columns) = space.neighbourhood(near.pos);
        let mut runs = Vec::new();
        let mut left = if cap == 0 { u32::MAX } else { cap };
        'kinds: for kind in 0..kinds {
            if near.mask & kinds_mask(kinds) & (1 << kind) == 0 {
                continue;
            }
            for k in 0..rows.count {
                let row = kind * cells + rows.at(k) * cols;
                for r in 0..columns.runs() {
                    let (first, last) = columns.run(r);
                    let begin = start[(row + first) as usize];
                    let end = start[(row + last + 1) as usize].min(begin.saturating_add(left));
                    if begin < end {
                        runs.push((begin, end));
                    }
                    left -= end.saturating_sub(begin);
                    if left == 0 {
                        break 'kinds;
                    }
                }
            }
        }
        let mut plain = Taken::default();
        grid.for_each_near(&space, near, |slot, _, _, entry| {
            plain = plain.add(1, slot, entry)
        });
        for budget in [0, 1, 2, 5, 17, 64, 200] {
            let phase = rng.below(1000);
            let sample = Sample { budget, phase };
            let got = grid.merge_near_in(
                Team::new(0, 1),
                &space,
                (near, sample, 0),
                Taken::default(),
                |taken, weight, _, _, entry| taken.add(weight, slots[entry as usize], entry),
                |a, _| a,
            );
            let share = budget.div_ceil(3);
            let mut expected = Taken::default();
            let mut crowded = false;
            for &(begin, end) in &runs {
                let len = end - begin;
                let stride = match budget {
                    0 => 1,
                    _ => len.div_ceil(share).max(1),
                };
                crowded |= stride > 1;
                let mut taken = 0;
                for entry in begin..end {
                    if (entry - begin) % stride == phase % stride {
                        expected = expected.add(stride, slots[entry as usize], entry);
                        taken += 1;
                    }
                }
                if budget != 0 {
                    assert!(taken <= share, "case {case}: {taken} of a run of {len}");
                }
            }
            if !crowded {
                assert_eq!(got, plain, "case {case}, budget {budget}: the plain look");
            }
            assert_eq!(got, expected, "case {case}, budget {budget}, cap {cap}");
        }
    }
}
