//! The persistent step: a whole plan of launches run inside one launch whose blocks all stay
//! resident (a cooperative launch), a barrier across the grid where a launch boundary was.
//!
//! The host turns a plan's launches into a program: a list of [`Stage`]s (the kernel, its
//! grid and block, where its argument struct lies in the program's blob) that [`program`]
//! runs in order, `steps` times. Each stage's threads are the launch's own, virtual: the
//! launch's real threads share them out in a stride over the stage's grid, so a thread of
//! the stage sees exactly the coordinates, hence the work, that it had as a launch of its
//! own, and its warp's lanes are a warp's (stage blocks are whole warps, and the real grid a
//! whole number of warps). Kernels are barrier-free, so a stage's result does not depend on
//! which real thread runs which virtual one: the program's state is the launches', bit for
//! bit (the tests compare the two on both backends).
//!
//! The barrier ([`Runner::sync`]) is where the two targets differ, as atomics do: on the GPU
//! a count in device memory that every block's first thread adds to and watches (the scheme
//! of CUDA's cooperative groups: the top bit flips once every block has arrived), fenced on
//! both sides and wrapped in block barriers; on the CPU, where one host thread runs a whole
//! block, the emulator's own barrier across its threads. Both need every block resident at
//! once: the GPU's cooperative launch refuses a larger grid, and the emulator runs one block
//! a worker thread.

use crate::access::Read;
use crate::{DevSlice, Thread, kernel_args};

/// One launch of a program: which kernel (an index in the registry's `STAGES`), its grid and
/// block, and where its argument struct lies in the program's blob.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct Stage {
    /// Index of the kernel in the registry's `STAGES`.
    pub kernel: u32,
    /// Blocks of the launch it stands for.
    pub grid: u32,
    /// Threads per block of that launch: a multiple of 32 (whole warps).
    pub block: u32,
    /// First word of its argument struct in the blob (8-byte words).
    pub args: u32,
}

kernel_args! {
    /// Arguments of [`program`].
    pub struct ProgramArgs {
        /// The stages of one step, in order.
        pub stages: DevSlice<Stage, Read>,
        /// The stages' argument structs, each from its stage's word.
        pub blob: DevSlice<u64, Read>,
        /// The grid barrier's count (one word, any value to start with; the GPU's only).
        pub barrier: DevSlice<u32>,
        /// Steps run by the launch: the stages, in order, this many times.
        pub steps: u32,
        /// Keeps the struct free of implicit padding (checked by its `NoUninit` derive).
        pub reserved: u32,
    }
}

/// How the threads of one block of a persistent launch run a stage and wait for the grid.
pub trait Runner {
    /// Runs `body` with the stage's argument struct from `blob` for every virtual thread of
    /// `stage` that this block's threads hold (see [`share`]); a struct that does not lie
    /// wholly in the blob is a kernel fault.
    fn run<A: Copy>(&self, stage: &Stage, blob: &DevSlice<u64, Read>, body: impl Fn(Thread, &A));
    /// Waits until every block of the launch has arrived here, every write made before it
    /// visible to every read after it.
    fn sync(&self);
}

/// Calls `f` with each virtual thread of `stage` held by the real thread `first` of a grid
/// of `threads` real threads: `first`, `first + threads`, … below the stage's thread count.
/// With `threads` a multiple of 32 and the stage's blocks whole warps, the 32 lanes of a
/// real warp hold 32 lanes of one virtual warp, each its own lane, and loop alike.
#[inline(always)]
pub fn share(stage: &Stage, first: u32, threads: u32, mut f: impl FnMut(Thread)) {
    // The stride in the stage's blocks and threads, divided once: a virtual thread's
    // coordinates then advance by additions (no 64-bit division a virtual thread).
    let (Some(blocks), Some(rest)) = (
        threads.checked_div(stage.block),
        threads.checked_rem(stage.block),
    ) else {
        return;
    };
    let (mut block, mut thread) = (u64::from(first / stage.block), first % stage.block);
    while block < u64::from(stage.grid) {
        f(Thread {
            thread,
            block: block as u32,
            block_dim: stage.block,
            grid_dim: stage.grid,
        });
        // Both below `stage.block` (at most 1,024), so the sum cannot wrap.
        thread += rest;
        block += u64::from(blocks);
        if thread >= stage.block {
            thread -= stage.block;
            block += 1;
        }
    }
}

/// Runs the program: every stage of `args` in order (each by `run_stage`, the registry's
/// dispatch to its kernel), a grid barrier after each but the last of the last step,
/// `args.steps` times.
#[inline(always)]
pub fn program<R: Runner>(
    runner: &R,
    args: &ProgramArgs,
    run_stage: impl Fn(&Stage, &DevSlice<u64, Read>, &R),
) {
    let stages = args.stages.len();
    for step in 0..args.steps {
        for i in 0..stages {
            let stage = args.stages.get(i);
            run_stage(&stage, &args.blob, runner);
            if step + 1 < args.steps || i + 1 < stages {
                runner.sync();
            }
        }
    }
}

/// The address of a stage's argument struct `A` in `blob`, after checking that the whole
/// struct lies in it (a kernel fault otherwise).
#[inline(always)]
fn args_at<A>(stage: &Stage, blob: &DevSlice<u64, Read>) -> *const A {
    const { assert!(align_of::<A>() <= 8) };
    let words = size_of::<A>().div_ceil(8) as u32;
    blob.range(stage.args, words).addr() as *const A
}

/// The GPU's runner: the calling thread, and the grid barrier's count.
#[cfg(target_arch = "nvptx64")]
pub struct OnGpu {
    /// The calling thread's real coordinates.
    pub thread: Thread,
    /// The barrier's count.
    pub barrier: DevSlice<u32>,
}

#[cfg(target_arch = "nvptx64")]
impl Runner for OnGpu {
    #[inline(always)]
    fn run<A: Copy>(&self, stage: &Stage, blob: &DevSlice<u64, Read>, body: impl Fn(Thread, &A)) {
        // SAFETY: `args_at` checked that the struct lies in the blob (8-byte aligned, and
        // `A` asks no more), which the host wrote before the launch and nothing writes
        // during it.
        let args = unsafe { &*args_at::<A>(stage, blob) };
        let t = self.thread;
        share(stage, t.global(), t.block_dim * t.grid_dim, |v| {
            body(v, args)
        });
    }

    #[inline(always)]
    fn sync(&self) {
        let t = self.thread;
        block_barrier();
        if t.thread == 0 {
            // Block 0 adds what brings the count's top bit over once all have added one.
            let add = if t.block == 0 {
                0x8000_0000 - (t.grid_dim - 1)
            } else {
                1
            };
            fence();
            let before = self.barrier.atomic_add(0, add);
            while (before ^ load_relaxed(&self.barrier)) & 0x8000_0000 == 0 {}
            fence();
        }
        block_barrier();
    }
}

/// Every thread of the block waits here (the unaligned form, see `touch::touch_rounds`).
#[cfg(target_arch = "nvptx64")]
#[inline(always)]
fn block_barrier() {
    // SAFETY: every thread of the block reaches each barrier of the program alike (the
    // loops around it are the same for all); it only waits.
    unsafe { core::arch::asm!("barrier.sync 0;", options(nostack)) };
}

/// Orders this thread's memory accesses before it against those after it, for the whole
/// GPU (CUDA's `__threadfence`).
#[cfg(target_arch = "nvptx64")]
#[inline(always)]
fn fence() {
    // SAFETY: a fence; without `nomem`, no access moves across it.
    unsafe { core::arch::asm!("fence.acq_rel.gpu;", options(nostack)) };
}

/// The barrier's count as the GPU's memory holds it now (never a value kept in a register).
#[cfg(target_arch = "nvptx64")]
#[inline(always)]
fn load_relaxed(count: &DevSlice<u32>) -> u32 {
    let value: u32;
    // SAFETY: the count's first word, in bounds (`atomic_add` checked it); a load.
    unsafe {
        core::arch::asm!(
            "ld.relaxed.gpu.global.u32 {0}, [{1}];",
            out(reg32) value,
            in(reg64) count.addr(),
            options(nostack)
        )
    };
    value
}

/// The CPU emulator's runner: one host thread runs a whole block, and `wait` is the
/// emulator's barrier across the launch's blocks.
#[cfg(not(target_arch = "nvptx64"))]
pub struct OnCpu<'a> {
    /// The block this host thread runs.
    pub block: u32,
    /// Threads per block.
    pub block_dim: u32,
    /// Blocks of the launch.
    pub grid_dim: u32,
    /// Returns once every block has called it as often.
    pub wait: &'a (dyn Fn() + Sync),
}

#[cfg(not(target_arch = "nvptx64"))]
impl Runner for OnCpu<'_> {
    fn run<A: Copy>(&self, stage: &Stage, blob: &DevSlice<u64, Read>, body: impl Fn(Thread, &A)) {
        // SAFETY: as on the GPU; one copy a block, read by its threads in turn.
        let args = unsafe { args_at::<A>(stage, blob).read() };
        let threads = self.block_dim * self.grid_dim;
        for thread in 0..self.block_dim {
            share(stage, self.block * self.block_dim + thread, threads, |v| {
                body(v, &args)
            });
        }
    }

    fn sync(&self) {
        (self.wait)();
    }
}
