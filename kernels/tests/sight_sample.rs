//! A look under a budget (`CellIndex::merge_near_in` with a `Sample`) takes, of each kind,
//! exactly every stride-th entry of the plain query's visiting order from the phase on, the
//! stride being `⌈entries / budget⌉`, so never more than the budget; each with its stride as
//! the weight; and, where a kind has no more entries than the budget, every entry, as the
//! plain query does. Checked against the plain query's list over random small grids, with
//! and without a cap.

use glam::Vec2;
use gpuwars_kernels::DevSlice;
use gpuwars_kernels::sim::Space;
use gpuwars_kernels::sim::broad::{CellIndex, Near, Sample};
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
fn view<T: Copy>(data: &[T]) -> DevSlice<T> {
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
        let pos: Vec<Vec2> = (0..entries).map(|e| Vec2::splat(e as f32)).collect();
        let cap = [0, 0, 1 + rng.below(150)][rng.below(3) as usize];
        let none: Vec<Vec2> = Vec::new();
        let grid = CellIndex {
            slots: view(&slots),
            pos: view(&pos),
            vel: view(&none),
            prev: view(&none),
            start: view(&start),
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
        // The plain query's entries, kind by kind, in visiting order.
        let mut listed: Vec<Vec<(u32, u32)>> = vec![Vec::new(); kinds as usize];
        grid.for_each_near(&space, near, |slot, kind, _, entry| {
            listed[kind as usize].push((slot, entry));
        });
        // The cap cuts the visiting order; a kind's stride counts its whole block.
        let mut whole: Vec<u32> = vec![0; kinds as usize];
        let uncapped = CellIndex { cap: 0, ..grid };
        uncapped.for_each_near(&space, near, |_, kind, _, _| whole[kind as usize] += 1);
        for budget in [0, 1, 2, 5, 17, 64, 200] {
            let phase = rng.below(1000);
            let sample = Sample { budget, phase };
            let got = grid.merge_near_in(
                Team::new(0, 1),
                &space,
                (near, sample),
                Taken::default(),
                |taken, weight, slot, _, _, entry| taken.add(weight, slot, entry),
                |a, _| a,
            );
            let mut expected = Taken::default();
            for (kind, list) in listed.iter().enumerate() {
                let n = whole[kind];
                let stride = match budget {
                    0 => 1,
                    b => n.div_ceil(b).max(1),
                };
                let mut taken = 0u32;
                for (i, &(slot, entry)) in list.iter().enumerate() {
                    if i as u32 % stride == phase % stride {
                        expected = expected.add(stride, slot, entry);
                        taken += 1;
                    }
                }
                if budget != 0 {
                    assert!(taken <= budget, "case {case}: kind {kind} took {taken}");
                }
                if budget >= n || budget == 0 {
                    assert_eq!(
                        taken as usize,
                        list.len(),
                        "case {case}: kind {kind} within budget"
                    );
                }
            }
            assert_eq!(got, expected, "case {case}, budget {budget}, cap {cap}");
        }
    }
}
