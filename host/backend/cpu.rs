//! The CPU emulation: runs the kernel bodies of `gpuwars-kernels`, compiled natively.
//!
//! Blocks run in parallel on a rayon pool and the threads of a block run one after another,
//! in order (or, under [`Schedule::Shuffled`], both in a shuffled order, and the ops beside
//! the others on threads of their own). Since kernels are barrier-free, this is exactly the
//! GPU's semantics; atomics are real atomics. A launch returns when the whole grid has run.

use std::panic::{AssertUnwindSafe, catch_unwind};
use std::ptr::NonNull;
use std::sync::atomic::{AtomicBool, AtomicU64, AtomicUsize, Ordering};
use std::sync::{Mutex, MutexGuard};

use gpuwars_kernels::exec::Cooperative;
use gpuwars_kernels::{KernelArgs, Thread};
use rand::rngs::StdRng;
use rand::seq::SliceRandom;
use rand::{Rng, SeedableRng};
use rayon::prelude::*;

use super::{Element, Error, Launch};

/// The order in which the emulator runs a launch's blocks and a block's threads.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Schedule {
    /// Blocks in parallel as the pool takes them, the threads of a block in order: the
    /// fast way.
    #[default]
    InOrder,
    /// Every launch runs its blocks, and each block its threads, in an order shuffled from
    /// this seed (and the launch's count), and every op beside the others
    /// ([`super::Op::beside`]) on a thread of its own, started where it forks or where its
    /// branch joins: a result that depends on scheduling changes under it, so the
    /// determinism tests catch it on the CPU rather than on the GPU.
    Shuffled {
        /// Seed of the shuffles.
        seed: u64,
    },
}

/// The emulator: a pool of worker threads.
pub(super) struct Emulator {
    pool: rayon::ThreadPool,
    schedule: Schedule,
    /// Launches so far, so that each shuffled launch gets its own order.
    launches: AtomicU64,
    /// Plans run so far, so that each shuffled run starts its branches its own way.
    runs: AtomicU64,
    /// Held by whatever touches the device's memory (a plan's run, a copy, a read-back), so
    /// that they happen one after another, as on the GPU's stream.
    order: Mutex<()>,
}

impl Emulator {
    pub(super) fn new(threads: Option<usize>, schedule: Schedule) -> Result<Self, Error> {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads.unwrap_or(0))
            .thread_name(|i| format!("gpuwars-emu-{i}"))
            .build()
            .map_err(|e| Error::Invalid(format!("cannot start the emulator's threads: {e}")))?;
        Ok(Emulator {
            pool,
            schedule,
            launches: AtomicU64::new(0),
            runs: AtomicU64::new(0),
            order: Mutex::new(()),
        })
    }

    pub(super) fn threads(&self) -> usize {
        self.pool.current_num_threads()
    }

    /// Runs `work` on a worker of the pool: the launches it issues then start their blocks
    /// without waking another thread first (a launch from outside the pool costs two
    /// cross-thread wake-ups).
    pub(super) fn run<R: Send>(&self, work: impl FnOnce() -> R + Send) -> R {
        self.pool.install(work)
    }

    /// Waits for the device's memory to be free of other work, and keeps it until the guard
    /// goes: the emulator's stream order.
    pub(super) fn in_order(&self) -> MutexGuard<'_, ()> {
        self.order.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Under [`Schedule::Shuffled`], where a plan's run starts each op beside the others
    /// (drawn from it: where it forks, or where it joins), a source of its own for every
    /// run; `None` in order, where every op runs in the plan's order.
    pub(super) fn branch_starts(&self) -> Option<StdRng> {
        match self.schedule {
            Schedule::InOrder => None,
            Schedule::Shuffled { seed } => {
                let run = self.runs.fetch_add(1, Ordering::Relaxed);
                Some(StdRng::seed_from_u64(
                    seed ^ run.wrapping_mul(0xd1b5_4a32_d192_ed03) ^ 0x6272_616e_6368,
                ))
            }
        }
    }

    /// Runs every thread of `launch` and returns when all are done (the caller holds the
    /// order).
    pub(super) fn launch<A: KernelArgs>(&self, launch: &Launch<A>) -> Result<(), Error> {
        let Launch {
            kernel,
            grid,
            block,
            ref args,
        } = *launch;
        let thread = |t: u32, b: u32| Thread {
            thread: t,
            block: b,
            block_dim: block,
            grid_dim: grid,
        };
        // A failed bounds check panics inside a worker; turn it into an error, as a trap is
        // one on the GPU.
        catch_unwind(AssertUnwindSafe(|| match self.schedule {
            Schedule::InOrder => self.pool.install(|| {
                (0..grid)
                    .into_par_iter()
                    .for_each(|b| (kernel.block)(b, block, grid, args))
            }),
            Schedule::Shuffled { seed } => {
                let launch = self.launches.fetch_add(1, Ordering::Relaxed);
                let mut rng =
                    StdRng::seed_from_u64(seed ^ launch.wrapping_mul(0x9e37_79b9_7f4a_7c15));
                let mut blocks: Vec<(u32, u64)> = (0..grid).map(|b| (b, rng.random())).collect();
                blocks.shuffle(&mut rng);
                self.pool.install(|| {
                    blocks.into_par_iter().for_each(|(b, block_seed)| {
                        let mut order: Vec<u32> = (0..block).collect();
                        order.shuffle(&mut StdRng::seed_from_u64(block_seed));
                        for t in order {
                            (kernel.body)(thread(t, b), args);
                        }
                    })
                })
            }
        }))
        .map_err(|payload| Error::KernelFault {
            kernel: kernel.name.into(),
            message: panic_message(payload.as_ref()),
        })
    }
}

impl Emulator {
    /// Runs a cooperative launch of `grid` blocks of `block` threads, each block whole on a
    /// worker of its own (at most [`Emulator::threads`] blocks, all at once), and returns
    /// when all are done (the caller holds the order). A block that faults breaks the
    /// barrier, so the others stop at it rather than wait for ever.
    pub(super) fn launch_cooperative<A: KernelArgs>(
        &self,
        kernel: &Cooperative<A>,
        grid: u32,
        block: u32,
        args: &A,
    ) -> Result<(), Error> {
        if grid as usize > self.threads() {
            return Err(Error::Invalid(format!(
                "kernel `{}`: a cooperative launch of {grid} blocks on an emulation of {} \
                 threads (its barrier needs every block running at once: at most one a thread)",
                kernel.name,
                self.threads()
            )));
        }
        let barrier = Rendezvous::new(grid as usize);
        let wait = || barrier.wait();
        let first_fault = Mutex::new(None);
        self.pool.broadcast(|context| {
            let Ok(b) = u32::try_from(context.index()) else {
                return;
            };
            if b >= grid {
                return;
            }
            let ran = catch_unwind(AssertUnwindSafe(|| {
                (kernel.block)(b, block, grid, args, &wait)
            }));
            if let Err(payload) = ran {
                barrier.break_it();
                let mut fault = first_fault.lock().unwrap_or_else(|e| e.into_inner());
                if fault.is_none() && !payload.is::<BrokenBarrier>() {
                    *fault = Some(panic_message(payload.as_ref()));
                }
            }
        });
        match first_fault.into_inner().unwrap_or_else(|e| e.into_inner()) {
            None => Ok(()),
            Some(message) => Err(Error::KernelFault {
                kernel: kernel.name.into(),
                message,
            }),
        }
    }
}

/// What a fault's panic said.
fn panic_message(payload: &(dyn std::any::Any + Send)) -> String {
    payload
        .downcast_ref::<String>()
        .map(String::as_str)
        .or_else(|| payload.downcast_ref::<&str>().copied())
        .unwrap_or("panic")
        .to_string()
}

/// The panic of a block that found its barrier broken by another block's fault.
struct BrokenBarrier;

/// The emulator's barrier across a cooperative launch's blocks: each waits until all have
/// arrived, spinning briefly and then yielding its core (the emulation may share the
/// machine with other work); broken by a block's fault, it sends every waiter out (with a
/// [`BrokenBarrier`] panic) instead of keeping them for ever.
struct Rendezvous {
    blocks: usize,
    arrived: AtomicUsize,
    /// Barriers passed: a waiter leaves when it changes.
    generation: AtomicU64,
    broken: AtomicBool,
}

impl Rendezvous {
    fn new(blocks: usize) -> Self {
        Rendezvous {
            blocks,
            arrived: AtomicUsize::new(0),
            generation: AtomicU64::new(0),
            broken: AtomicBool::new(false),
        }
    }

    /// Returns once every block has arrived as often; what each wrote before it is seen by
    /// every block after it (the last arrival's release, each waiter's acquire).
    fn wait(&self) {
        let generation = self.generation.load(Ordering::Acquire);
        if self.arrived.fetch_add(1, Ordering::AcqRel) + 1 == self.blocks {
            self.arrived.store(0, Ordering::Relaxed);
            self.generation.store(generation + 1, Ordering::Release);
            return;
        }
        let mut spins = 0u32;
        while self.generation.load(Ordering::Acquire) == generation {
            if self.broken.load(Ordering::Relaxed) {
                std::panic::panic_any(BrokenBarrier);
            }
            if spins < 1_000 {
                spins += 1;
                std::hint::spin_loop();
            } else {
                std::thread::yield_now();
            }
        }
    }

    /// Sends every block waiting now or later out of the barrier.
    fn break_it(&self) {
        self.broken.store(true, Ordering::Relaxed);
    }
}

/// Host memory standing in for device memory.
///
/// Kernels write through raw addresses while the host holds only a shared borrow, so the
/// memory is owned through a raw pointer rather than a `Vec` (whose shared borrows promise
/// that nothing writes).
pub(super) struct HostBuffer<T> {
    ptr: NonNull<T>,
    len: usize,
}

// SAFETY: the buffer owns its elements like a `Box<[T]>`.
unsafe impl<T: Send> Send for HostBuffer<T> {}
// SAFETY: as above; concurrent writes happen only inside launches, under the kernels' contract.
unsafe impl<T: Sync> Sync for HostBuffer<T> {}

impl<T: Element> HostBuffer<T> {
    /// `len` zeroed elements, or [`Error::OutOfMemory`] where the host cannot give them
    /// (an allocation that fails is an error, not an abort).
    pub(super) fn zeroed(len: usize) -> Result<Self, Error> {
        let mut data = Self::reserved(len)?;
        data.resize(len, T::zeroed());
        Ok(Self::from_box(data.into_boxed_slice()))
    }

    /// A copy of `data`, or [`Error::OutOfMemory`] as for [`HostBuffer::zeroed`].
    pub(super) fn from_slice(data: &[T]) -> Result<Self, Error> {
        let mut copy = Self::reserved(data.len())?;
        copy.extend_from_slice(data);
        Ok(Self::from_box(copy.into_boxed_slice()))
    }

    /// An empty vector with room for exactly `len` elements.
    fn reserved(len: usize) -> Result<Vec<T>, Error> {
        let mut data = Vec::new();
        data.try_reserve_exact(len)
            .map_err(|_| Error::OutOfMemory {
                what: format!("a buffer of {len} elements of {} bytes", size_of::<T>()),
                needed: (len * size_of::<T>()) as u64,
                free: super::host_memory().map_or(0, |(free, _)| free),
                place: "host",
            })?;
        Ok(data)
    }

    fn from_box(data: Box<[T]>) -> Self {
        let len = data.len();
        let ptr = NonNull::new(Box::into_raw(data) as *mut T).expect("Box pointers are non-null");
        HostBuffer { ptr, len }
    }

    pub(super) fn len(&self) -> usize {
        self.len
    }

    pub(super) fn addr(&self) -> u64 {
        self.ptr.as_ptr() as u64
    }

    /// The elements.
    ///
    /// # Safety
    /// Nothing writes them while the slice lives: the caller holds the emulator's order, so
    /// no launch runs.
    pub(super) unsafe fn as_slice(&self) -> &[T] {
        // SAFETY: `len` initialised elements; no writer (the caller's promise).
        unsafe { std::slice::from_raw_parts(self.ptr.as_ptr(), self.len) }
    }

    /// The elements, for writing.
    ///
    /// # Safety
    /// As for [`HostBuffer::as_slice`], and nothing else reads them while the slice lives
    /// (the caller has the buffer's only host handle mutably).
    #[allow(clippy::mut_from_ref)]
    pub(super) unsafe fn as_mut_slice(&self) -> &mut [T] {
        // SAFETY: as above, the caller's promise.
        unsafe { std::slice::from_raw_parts_mut(self.ptr.as_ptr(), self.len) }
    }
}

impl<T> Drop for HostBuffer<T> {
    fn drop(&mut self) {
        let slice = std::ptr::slice_from_raw_parts_mut(self.ptr.as_ptr(), self.len);
        // SAFETY: made by `Box::into_raw` of a boxed slice of this length.
        drop(unsafe { Box::from_raw(slice) });
    }
}
