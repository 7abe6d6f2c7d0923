//! Histogram by atomics: how many keys fall in each bin (e.g. bodies per grid cell).

use crate::access::Read;
use crate::{DevSlice, Thread, kernel_args};

kernel_args! {
    /// Arguments of [`count_keys`].
    pub struct HistogramArgs {
        /// The keys, `n` of them used.
        pub keys: DevSlice<u32, Read>,
        /// One counter per bin, zeroed by the host before the launch. Keys not below
        /// `counts.len()` are not counted.
        pub counts: DevSlice<u32>,
        /// Number of keys.
        pub n: u32,
        /// Keeps the struct free of implicit padding (checked by its `NoUninit` derive).
        pub reserved: u32,
    }
}

/// Thread `i` adds one to the bin of key `i`. Counters are only touched through atomic adds,
/// whose final sums do not depend on the order of arrival.
#[inline(always)]
pub fn count_keys(t: Thread, args: &HistogramArgs) {
    let i = t.global();
    if i >= args.n {
        return;
    }
    let key = args.keys.get(i);
    if key < args.counts.len() {
        args.counts.atomic_add(key, 1);
    }
}
