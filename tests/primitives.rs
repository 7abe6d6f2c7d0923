//! Parity of the parallel primitives with plain host references, on every backend.

mod common;

use common::{EDGE_SIZES, random_below, rng_for};
use gpuwars::Device;
use gpuwars::backend::floor;
use gpuwars::primitives::{CountingSort, PrefixSum, histogram};
use proptest::prelude::*;
use proptest::test_runner::{Config, TestRunner};

/// Sizes around the scan's tiles (1,024 elements) and its levels (one launch of tile sums
/// up to 1,024 tiles, a recursion past them) on top of the edge sizes.
const SCAN_SIZES: &[usize] = &[
    1023,
    1024,
    1025,
    1024 * 1024,
    1024 * 1024 + 1,
    1024 * 1100 + 7,
];
/// Sizes around the sort's tiles of 64.
const SORT_SIZES: &[usize] = &[63, 64, 65, 4097];

fn check_scan(device: &Device, input: &[u32]) {
    let mut scan = PrefixSum::new(device, input.len()).unwrap();
    let src = device.upload(input).unwrap();
    let mut dst = device.upload(&vec![0xdead_beef; input.len()]).unwrap();
    scan.run(device, &src, &mut dst, input.len()).unwrap();
    let got = device.download(&dst).unwrap();
    assert_eq!(
        got,
        common::exclusive_scan(input),
        "prefix sum of {} elements",
        input.len()
    );
    // The input is left alone.
    assert_eq!(device.download(&src).unwrap(), input);
}

fn prefix_sum_matches_reference(device: &Device) {
    for &n in EDGE_SIZES.iter().chain(SCAN_SIZES) {
        let mut rng = rng_for("prefix_sum", n);
        // Small values and full-range values (whose sums wrap).
        check_scan(device, &random_below(&mut rng, n, 1000));
        check_scan(device, &random_below(&mut rng, n, u32::MAX));
    }
}

fn prefix_sum_in_place_and_reused(device: &Device) {
    let mut scan = PrefixSum::new(device, 5000).unwrap();
    for n in [5000, 33, 0, 4096] {
        let input = random_below(&mut rng_for("in_place", n), n, 1 << 20);
        let mut data = device.upload(&input).unwrap();
        scan.run_in_place(device, &mut data, n).unwrap();
        assert_eq!(
            device.download(&data).unwrap(),
            common::exclusive_scan(&input)
        );
    }
}

/// The scan from tile sums held outside its scratch: the same prefix sums whether it works
/// the sums out itself (where it must also leave them there: the free lists' rebuild keeps
/// them after) or is handed them kept up to date, through one launch and past it.
fn prefix_sum_with_sums_matches_reference(device: &Device) {
    for &n in EDGE_SIZES.iter().chain(SCAN_SIZES) {
        let input = random_below(&mut rng_for("with_sums", n), n, u32::MAX);
        let scan = PrefixSum::new(device, n).unwrap();
        let tile_sums: Vec<u32> = input
            .chunks(1024)
            .map(|c| c.iter().fold(0u32, |a, &v| a.wrapping_add(v)))
            .collect();
        let src = device.upload(&input).unwrap();
        for kept in [false, true] {
            let start = match kept {
                true => tile_sums.clone(),
                false => vec![0xdead_beef; tile_sums.len()],
            };
            let sums = device.upload(&start.iter().copied().chain([7]).collect::<Vec<_>>());
            let sums = sums.unwrap();
            let dst = device.upload(&vec![0xdead_beef; n]).unwrap();
            let ops = scan.ops_with_sums(&src, &dst, n as u32, (&sums, kept));
            device
                .run(&device.plan(ops.unwrap(), false).unwrap())
                .unwrap();
            let what = format!("{n} elements, sums kept: {kept}");
            assert_eq!(
                device.download(&dst).unwrap(),
                common::exclusive_scan(&input),
                "{what}"
            );
            // A single tile needs no sums and leaves them alone.
            let left = device.download(&sums).unwrap();
            if n > 1024 {
                assert_eq!(left[..tile_sums.len()], tile_sums[..], "{what}");
            }
            assert_eq!(left[tile_sums.len()], 7, "{what}: past the sums");
        }
    }
}

fn prefix_sum_property(device: &Device) {
    let mut runner = TestRunner::new(Config::with_cases(48));
    let strategy = prop::collection::vec(any::<u32>(), 0..5000);
    runner
        .run(&strategy, |input| {
            check_scan(device, &input);
            Ok(())
        })
        .unwrap();
}

fn check_histogram(device: &Device, keys: &[u32], bins: usize) {
    let src = device.upload(keys).unwrap();
    // Poisoned, to see that the primitive clears it.
    let mut counts = device.upload(&vec![7u32; bins]).unwrap();
    histogram(device, &src, keys.len(), &mut counts).unwrap();
    let got = device.download(&counts).unwrap();
    assert_eq!(
        got,
        common::histogram(keys, bins),
        "{} keys in {bins} bins",
        keys.len()
    );
}

fn histogram_matches_reference(device: &Device) {
    for &n in EDGE_SIZES {
        let mut rng = rng_for("histogram", n);
        for bins in [1usize, 7, 1000, 65_536] {
            check_histogram(device, &random_below(&mut rng, n, bins as u32), bins);
        }
        // All keys in one bin: maximum contention on one counter.
        check_histogram(device, &vec![3; n], 5);
        // Keys out of range are ignored.
        check_histogram(device, &random_below(&mut rng, n, 200), 100);
    }
}

fn check_sort(device: &Device, keys: &[u32], key_bound: u32) {
    let n = keys.len();
    let mut sort = CountingSort::new(device, n).unwrap();
    let src = device.upload(keys).unwrap();
    let mut keys_out = device.upload(&vec![u32::MAX; n]).unwrap();
    let mut indices_out = device.upload(&vec![u32::MAX; n]).unwrap();
    sort.run(device, &src, n, key_bound, &mut keys_out, &mut indices_out)
        .unwrap();
    let (want_keys, want_indices) = common::sort_pairs(keys);
    assert_eq!(
        device.download(&keys_out).unwrap(),
        want_keys,
        "{n} keys below {key_bound}"
    );
    assert_eq!(
        device.download(&indices_out).unwrap(),
        want_indices,
        "{n} keys below {key_bound}"
    );
}

fn counting_sort_matches_reference(device: &Device) {
    for &n in EDGE_SIZES.iter().chain(SORT_SIZES) {
        let mut rng = rng_for("sort", n);
        // One pass, two, three (odd and even pass counts end in different buffers), and
        // full 32-bit keys (eight passes).
        for bound in [1u32, 16, 17, 4096, 1 << 12 | 1, u32::MAX] {
            check_sort(device, &random_below(&mut rng, n, bound), bound);
        }
        // Every key equal (every body in one cell): output must be the identity.
        check_sort(device, &vec![9; n], 10);
        // Descending keys: every pair moves.
        let descending: Vec<u32> = (0..n as u32).rev().collect();
        check_sort(device, &descending, n.max(1) as u32);
    }
}

fn counting_sort_property(device: &Device) {
    let mut runner = TestRunner::new(Config::with_cases(48));
    let strategy = (1u32..100_000)
        .prop_flat_map(|bound| (Just(bound), prop::collection::vec(0..bound, 0..3000)));
    runner
        .run(&strategy, |(bound, keys)| {
            check_sort(device, &keys, bound);
            Ok(())
        })
        .unwrap();
}

fn counting_sort_keeps_a_permutation_for_keys_above_the_bound(device: &Device) {
    let keys = random_below(&mut rng_for("bad_keys", 3000), 3000, u32::MAX);
    let mut sort = CountingSort::new(device, keys.len()).unwrap();
    let src = device.upload(&keys).unwrap();
    let mut keys_out = device.alloc_zeroed(keys.len()).unwrap();
    let mut indices_out = device.alloc_zeroed(keys.len()).unwrap();
    sort.run(
        device,
        &src,
        keys.len(),
        256,
        &mut keys_out,
        &mut indices_out,
    )
    .unwrap();
    let keys_out = device.download(&keys_out).unwrap();
    let mut indices = device.download(&indices_out).unwrap();
    for (k, &i) in keys_out.iter().zip(&indices) {
        assert_eq!(*k, keys[i as usize]);
    }
    // Ordered by the low byte (the bits the bound asks for), stably.
    assert!(keys_out.windows(2).all(|w| w[0] & 0xff <= w[1] & 0xff));
    indices.sort_unstable();
    assert_eq!(indices, (0..keys.len() as u32).collect::<Vec<_>>());
}

fn primitives_reject_sizes_beyond_their_buffers(device: &Device) {
    let small = device.upload(&[1u32, 2, 3]).unwrap();
    let mut out = device.alloc_zeroed::<u32>(3).unwrap();
    let mut scan = PrefixSum::new(device, 10).unwrap();
    let err = scan
        .run(device, &small, &mut out, 4)
        .unwrap_err()
        .to_string();
    assert!(err.contains("holds only 3"), "{err}");
    let err = scan
        .run(device, &small, &mut out, 11)
        .unwrap_err()
        .to_string();
    assert!(err.contains("capacity 10"), "{err}");
    let mut counts = device.alloc_zeroed::<u32>(4).unwrap();
    let err = histogram(device, &small, 5, &mut counts)
        .unwrap_err()
        .to_string();
    assert!(err.contains("keys buffer holds only 3"), "{err}");
    let mut sort = CountingSort::new(device, 3).unwrap();
    let mut indices = device.alloc_zeroed::<u32>(2).unwrap();
    let err = sort
        .run(device, &small, 3, 4, &mut out, &mut indices)
        .unwrap_err()
        .to_string();
    assert!(err.contains("indices_out buffer holds only 2"), "{err}");
}

/// The launch floor runs every launch of every variant and block size (it checks each
/// element's count itself), in one of its block sizes, over more threads than one block has, and leaves the device's launch mode as
/// it found it.
fn launch_floor_runs_every_variant(device: &Device) {
    let was = device.dependent_launch();
    let past_one_block = floor::ONE_BLOCK_MAX_THREADS + 1;
    for (launches, threads) in [(1, 1), (5, 3_000), (2, past_one_block)] {
        let floor = floor::measure(device, launches, threads).expect("the floor runs");
        assert_eq!((floor.launches, floor.threads), (launches, threads));
        assert!(floor::BLOCKS.contains(&floor.block), "{floor:?}");
        for s in [floor.graph_s, floor.stream_s, floor.ring_s]
            .into_iter()
            .chain(floor.one_block_s)
        {
            assert!(s > 0.0 && s.is_finite(), "{floor:?}");
        }
        assert_eq!(floor.one_block_s.is_some(), threads < past_one_block);
        // Dependent launch is measured exactly where the device can turn it on.
        let can = device.set_dependent_launch(true);
        device.set_dependent_launch(was);
        assert_eq!(floor.dependent_s.is_some(), can, "{floor:?}");
        assert_eq!(device.dependent_launch(), was);
    }
    assert!(floor::measure(device, 0, 10).is_err());
    assert!(floor::measure(device, 3, 0).is_err());
}

on_both_backends!(
    launch_floor_runs_every_variant,
    prefix_sum_matches_reference,
    prefix_sum_in_place_and_reused,
    prefix_sum_with_sums_matches_reference,
    prefix_sum_property,
    histogram_matches_reference,
    counting_sort_matches_reference,
    counting_sort_property,
    counting_sort_keeps_a_permutation_for_keys_above_the_bound,
    primitives_reject_sizes_beyond_their_buffers,
);
