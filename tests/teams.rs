//! The threads of a stage with teams (`Teams`) cover every slot of its kinds once: on the
//! CPU, where a team's first lane does its work alone, each padded slot of the kinds gets
//! exactly one thread and lane 0, and nothing past them gets any.

use gpuwars::kernels::DevSlice;
use gpuwars::kernels::Thread;
use gpuwars::kernels::access::Read;
use gpuwars::kernels::sim::SlotRange;
use gpuwars::kernels::sim::teams::Teams;
use proptest::prelude::*;

/// Slot ranges for `capacities`, each starting on a multiple of 32 (as the layout makes them).
fn ranges(capacities: &[u32]) -> Vec<SlotRange> {
    let mut start = 0;
    capacities
        .iter()
        .map(|&capacity| {
            let range = SlotRange { start, capacity };
            start += capacity.next_multiple_of(32);
            range
        })
        .collect()
}

proptest! {
    #[test]
    fn every_slot_of_the_kinds_gets_one_team(
        kinds in prop::collection::vec((1u32..300, 0u32..6), 1..7),
        cut in (0usize..7, 0usize..7),
    ) {
        let capacities: Vec<u32> = kinds.iter().map(|k| k.0).collect();
        let widths: Vec<u32> = kinds.iter().map(|k| 1 << k.1).collect();
        let table = ranges(&capacities);
        let n = table.len();
        let (first, last) = (cut.0.min(n - 1), cut.1.min(n - 1));
        let (first, last) = (first.min(last), first.max(last));
        let (first_slot, end_slot) = (
            table[first].start,
            table[last].start + table[last].capacity.next_multiple_of(32),
        );
        let teams = Teams::new(
            (first as u32, last as u32 + 1),
            (first_slot, end_slot),
            |k| widths[k as usize],
        );
        for (k, &width) in widths.iter().enumerate().take(last + 1).skip(first) {
            prop_assert_eq!(teams.width(k as u32), width);
        }
        let threads = teams.threads(&table);
        let expected: u64 = (first..=last)
            .map(|k| u64::from(capacities[k].next_multiple_of(32)) * u64::from(widths[k]))
            .sum();
        prop_assert_eq!(threads, expected);
        let warps: Vec<u32> = teams.warp_table(&table).collect();
        prop_assert_eq!(warps.len() as u64, threads / 32);
        // SAFETY: the table outlives every use of the view, and nothing writes it meanwhile.
        let view: DevSlice<u32, Read> =
            unsafe { DevSlice::from_raw_parts(warps.as_ptr() as u64, warps.len() as u32) };
        let block_dim = 128;
        let mut seen = vec![0u32; end_slot as usize];
        // One block more than the threads, as a launch rounds up.
        for global in 0..threads as u32 + block_dim {
            let t = Thread {
                thread: global % block_dim,
                block: global / block_dim,
                block_dim,
                grid_dim: (threads as u32).div_ceil(block_dim) + 1,
            };
            if let Some((slot, team)) = teams.member(t, &view) {
                prop_assert!(global < threads as u32, "thread {} past the last", global);
                prop_assert!((first_slot..end_slot).contains(&slot));
                prop_assert_eq!(team.lane(), 0);
                seen[slot as usize] += 1;
            }
        }
        prop_assert!(seen[first_slot as usize..].iter().all(|&c| c == 1), "{:?}", seen);
    }
}

proptest! {
    /// Teams put within wider ones (`Teams::within`) span the wider ones' kinds and slots,
    /// each of their own kinds keeping its width and the others taking the wider teams'.
    #[test]
    fn teams_within_wider_ones_keep_their_own_widths(
        logs in prop::collection::vec((0u32..6, 0u32..6), 1..9),
        cut in (0usize..9, 0usize..9),
    ) {
        let n = logs.len();
        let table = ranges(&vec![40; n]);
        let (first, last) = (cut.0.min(n - 1), cut.1.min(n - 1));
        let (first, last) = (first.min(last), first.max(last));
        let span = |a: usize, b: usize| (table[a].start, table[b].start + 64);
        let wide = Teams::new((0, n as u32), span(0, n - 1), |k| 1 << logs[k as usize].0);
        let own = Teams::new(
            (first as u32, last as u32 + 1),
            span(first, last),
            |k| 1 << logs[k as usize].1,
        );
        let within = own.within(&wide);
        prop_assert_eq!((within.first_kind, within.end_kind), (0, n as u32));
        prop_assert_eq!((within.first_slot, within.end_slot), span(0, n - 1));
        for (k, &(w, o)) in logs.iter().enumerate() {
            let expected = if (first..=last).contains(&k) { 1 << o } else { 1 << w };
            prop_assert_eq!(within.width(k as u32), expected, "kind {}", k);
        }
    }
}
