//! `DevSlice::fold_every` visits exactly the elements `first, first + stride, …` below
//! `end`, in that order, whatever the length of its last batch, and `DevSlice::fold_runs`
//! the runs that start there: checked against the same walks written as plain loops, over
//! every small case.

use gpuwars_kernels::DevSlice;
use gpuwars_kernels::access::Read;

/// An order-sensitive fold: any element missed, repeated or out of place changes it.
fn mix(acc: u64, value: u32) -> u64 {
    acc.wrapping_mul(1_000_003)
        .wrapping_add(u64::from(value) + 1)
}

#[test]
fn folds_every_strided_element_in_order_once() {
    for len in 0u32..14 {
        let data: Vec<u32> = (0..len).map(|i| i * 7 + 3).collect();
        // SAFETY: `data` outlives every use of the view, and nothing writes it meanwhile.
        let view = unsafe { DevSlice::<u32, Read>::from_raw_parts(data.as_ptr() as u64, len) };
        for end in 0..=len {
            for first in 0..end + 2 {
                for stride in 1..6 {
                    let mut expected = 17u64;
                    let mut i = first;
                    while i < end {
                        expected = mix(expected, data[i as usize]);
                        i += stride;
                    }
                    let got = view.fold_every((first, end, stride), 17u64, mix);
                    assert_eq!(got, expected, "len {len}, {first}..{end} by {stride}");
                }
            }
        }
    }
}

/// Runs of four: every first, end and stride that are multiples of four, over lengths
/// that leave the last round of runs anywhere from full to nearly empty.
#[test]
fn folds_every_strided_run_in_order_once() {
    const N: u32 = 4;
    let mix_run = |acc: u64, run: [u32; N as usize]| run.into_iter().fold(acc, mix);
    for len in (0u32..=160).step_by(N as usize) {
        let data: Vec<u32> = (0..len).map(|i| i * 7 + 3).collect();
        // SAFETY: `data` outlives every use of the view, and nothing writes it meanwhile.
        let view = unsafe { DevSlice::<u32, Read>::from_raw_parts(data.as_ptr() as u64, len) };
        for end in (0..=len).step_by(N as usize) {
            for first in (0..end + 2 * N).step_by(N as usize) {
                for stride in (N..=3 * N).step_by(N as usize) {
                    let mut expected = 17u64;
                    let mut i = first;
                    while i < end {
                        let run = data[i as usize..(i + N) as usize].iter();
                        expected = run.fold(expected, |acc, &v| mix(acc, v));
                        i += stride;
                    }
                    let got = view.fold_runs::<4, _>((first, end, stride), 17u64, mix_run);
                    assert_eq!(got, expected, "len {len}, {first}..{end} by {stride}");
                }
            }
        }
    }
}

/// A walk whose runs could cross its end is refused, never read past the view: the two
/// elements of a view of two (past them, other memory) are not runs of four.
#[test]
fn refuses_runs_that_are_not_multiples_of_their_length() {
    let data: Vec<u32> = vec![1, 2, 0xdead_beef, 0xcafe_f00d];
    // SAFETY: `data` outlives every use of the view, and nothing writes it meanwhile.
    let view = unsafe { DevSlice::<u32, Read>::from_raw_parts(data.as_ptr() as u64, 2) };
    for walk in [(0, 2, 4), (0, 4, 4), (2, 4, 4), (0, 4, 2)] {
        let read = std::panic::catch_unwind(|| {
            view.fold_runs::<4, _>(walk, 17u64, |acc, run: [u32; 4]| {
                run.into_iter().fold(acc, mix)
            })
        });
        assert!(read.is_err(), "{walk:?} read {read:?}");
    }
}
