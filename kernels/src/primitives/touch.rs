//! The smallest kernel that does work: one read-modify-write a thread. The host replays a
//! chain of these over one array, as many as a step launches, to measure the launch floor a
//! step is compared with (`gpuwars demo --profile`, `gpuwars bench scale`).

use crate::{DevSlice, Thread, kernel_args};

kernel_args! {
    /// Arguments of [`touch`].
    pub struct TouchArgs {
        /// One element a thread.
        pub data: DevSlice<u32>,
    }
}

/// Thread `i` adds one to `data[i]` (wrapping). Each element has one writer.
#[inline(always)]
pub fn touch(t: Thread, args: &TouchArgs) {
    let i = t.global();
    if i < args.data.len() {
        args.data.set(i, args.data.get(i).wrapping_add(1));
    }
}
