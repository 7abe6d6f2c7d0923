//! `DevSlice::fold_every` visits exactly the elements `first, first + stride, …` below
//! `end`, in that order, whatever the length of its last batch: checked against the same
//! walk written as a plain loop, over every small case.

use gpuwars_kernels::DevSlice;

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
        let view = unsafe { DevSlice::from_raw_parts(data.as_ptr() as u64, len) };
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
