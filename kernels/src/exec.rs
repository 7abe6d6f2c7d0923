//! The execution model shared by the GPU and the CPU emulator.
//!
//! A kernel is a [`Kernel<A>`]: the name of its PTX entry point and its body, a function of the
//! calling [`Thread`] and a reference to the argument struct `A`. On the GPU a thin
//! `extern "ptx-kernel"` entry point (generated in [`crate::registry`]) calls the body; on the CPU
//! the emulator calls the same body for every thread of the grid.
//!
//! Device memory is reached through [`DevSlice`], a bounds-checked view made of a raw address
//! and a length. Building one is `unsafe` (the host promises the memory is valid for every
//! launch that uses it; its backend makes views only for the ops that hold their buffers, and
//! hands none to safe code); using one inside a kernel is not, because every access checks
//! its index. What no type can check is the kernel's own promise that two threads of one
//! launch never write the same element (except through atomics): every kernel states how it
//! keeps it.

use core::marker::PhantomData;
use core::sync::atomic::{AtomicU32, Ordering};

use crate::access::{Access, Readable, Unused, Within, Write};

/// Coordinates of the calling thread inside a one-dimensional launch.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Thread {
    /// Index of the thread inside its block (`threadIdx.x`).
    pub thread: u32,
    /// Index of the block inside the grid (`blockIdx.x`).
    pub block: u32,
    /// Threads per block (`blockDim.x`).
    pub block_dim: u32,
    /// Blocks in the grid (`gridDim.x`).
    pub grid_dim: u32,
}

impl Thread {
    /// Index of this thread in the whole grid.
    #[inline(always)]
    pub fn global(&self) -> u32 {
        self.block * self.block_dim + self.thread
    }

    /// Index of this thread inside its warp (its lane, 0 to 31).
    #[inline(always)]
    pub fn lane(&self) -> u32 {
        self.thread % crate::warp::WARP
    }

    /// The same thread with its launch's blocks taken from the last: block `grid_dim - 1 -
    /// block`. The GPU starts a launch's blocks in increasing order, so the work of the last
    /// blocks starts first.
    #[inline(always)]
    pub fn from_last_block(self) -> Thread {
        Thread {
            block: self.grid_dim - 1 - self.block,
            ..self
        }
    }

    /// The calling GPU thread's coordinates, read from the special registers.
    #[cfg(target_arch = "nvptx64")]
    #[inline(always)]
    pub fn current() -> Self {
        use core::arch::nvptx;
        // SAFETY: reading the special registers has no preconditions inside a kernel.
        unsafe {
            Thread {
                thread: nvptx::_thread_idx_x() as u32,
                block: nvptx::_block_idx_x() as u32,
                block_dim: nvptx::_block_dim_x() as u32,
                grid_dim: nvptx::_grid_dim_x() as u32,
            }
        }
    }
}

/// Programmatic dependent launch (sm_90 module only): waits until the launch before this one
/// in the stream has finished and its writes are visible, then lets the launch after this one
/// start its blocks, which wait here in turn.
///
/// Every entry of the sm_90 module calls it first, before any load or store, so a kernel
/// launched early (with the programmatic stream serialization attribute) never reads what
/// its predecessor still writes nor writes what it still reads: only the launch's start-up
/// overlaps the predecessor's tail. Without the attribute, the wait returns at once.
///
/// A kernel entered through a registry line marked `waits` calls it itself, after reading
/// only what its predecessor cannot be writing: the world's own tables, made with it, or
/// what a launch two or more before it wrote (that launch ended before the predecessor's
/// blocks passed this same wait, so before this launch started). Those loads then overlap
/// the predecessor's tail. Elsewhere (the CPU, other modules) it does nothing.
#[inline(always)]
pub fn follow_previous_launch() {
    #[cfg(all(target_arch = "nvptx64", gpuwars_dependent_launch))]
    // SAFETY: both instructions only order this grid against its neighbours in the stream;
    // without `nomem`, the compiler moves no memory access above them.
    unsafe {
        core::arch::asm!(
            "griddepcontrol.wait;",
            "griddepcontrol.launch_dependents;",
            options(nostack)
        );
    }
}

/// `value`, whose loads the compiler must issue before this point: it may not move them
/// towards their first use (behind a branch, or after a wait for another load), so that a
/// thread asks for everything it needs at once and waits for memory once. Nothing waits
/// here: the GPU stalls only where a value is first used. On the CPU it does nothing.
#[inline(always)]
pub fn asked<T: bytemuck::Pod>(value: T) -> T {
    #[cfg(target_arch = "nvptx64")]
    {
        // Each whole 32-bit word of the value is an input of an empty instruction with
        // effects, which the compiler can neither drop nor move below a branch.
        let words = core::mem::size_of::<T>() / 4;
        let at = core::ptr::from_ref(&value).cast::<u32>();
        for i in 0..words {
            // SAFETY: word `i` lies inside `value` (a `Pod`: every byte initialised).
            let word = unsafe { at.add(i).read_unaligned() };
            // SAFETY: a comment, no instruction: it names a register and changes nothing.
            unsafe { core::arch::asm!("/* {0} */", in(reg32) word, options(nomem, nostack)) };
        }
    }
    value
}

/// `value`, which the compiler may not assume equal to the `value` it came from: on the GPU
/// a register copy it cannot see through, so that a load indexed by it is issued where it is
/// written, not served from a register that an earlier load of the same element filled and
/// that would then be held (or spilled) until here. On the CPU it does nothing.
#[inline(always)]
pub fn unseen(value: u32) -> u32 {
    #[cfg(target_arch = "nvptx64")]
    {
        let copy: u32;
        // SAFETY: a register move; it reads and writes no memory.
        unsafe {
            core::arch::asm!(
                "mov.u32 {0}, {1};",
                out(reg32) copy,
                in(reg32) value,
                options(pure, nomem, nostack)
            )
        };
        copy
    }
    #[cfg(not(target_arch = "nvptx64"))]
    value
}

/// A kernel argument struct: plain data passed by value as the kernel's single parameter.
///
/// `NoUninit` is checked at compile time by its derive: the struct is `#[repr(C)]` and has
/// no padding (whose bytes would be undefined in the parameter the GPU reads), and neither
/// have its fields.
///
/// # Safety
/// The type must hold no references or host-only pointers (device memory is passed as
/// [`DevSlice`]), and be valid for any bit pattern the host writes into it.
pub unsafe trait KernelArgs: bytemuck::NoUninit + Sync + Send + 'static {}

/// A typed kernel identity: the PTX entry point's name and the body both backends run.
pub struct Kernel<A> {
    /// Name of the `.entry` in the PTX module.
    pub name: &'static str,
    /// The kernel body, called once per thread.
    pub body: fn(Thread, &A),
    /// The body for every thread of block `block` in order, `(block, block_dim, grid_dim,
    /// args)`: the emulator's way to run a block with one call, the body inlined into the
    /// loop ([`run_block`]).
    pub block: fn(u32, u32, u32, &A),
}

/// Runs `body` for the threads `0 .. block_dim` of block `block`, in order: what a kernel's
/// [`Kernel::block`] does, with the body known at compile time so that it is inlined.
#[inline(always)]
pub fn run_block<A>(
    body: impl Fn(Thread, &A),
    block: u32,
    block_dim: u32,
    grid_dim: u32,
    args: &A,
) {
    for thread in 0..block_dim {
        body(
            Thread {
                thread,
                block,
                block_dim,
                grid_dim,
            },
            args,
        );
    }
}

/// A kernel whose blocks wait for one another (a cooperative launch: every block resident
/// at once). On the GPU its PTX entry point runs each thread; the emulator runs each block
/// whole on a thread of its own, `block`'s last argument being its barrier across them.
pub struct Cooperative<A> {
    /// Name of the `.entry` in the PTX module.
    pub name: &'static str,
    /// Runs every thread of block `block`, `(block, block_dim, grid_dim, args, wait)`, where
    /// `wait` returns once every block of the launch has called it as often (the CPU's).
    pub block: fn(u32, u32, u32, &A, &(dyn Fn() + Sync)),
}

impl<A> Clone for Cooperative<A> {
    fn clone(&self) -> Self {
        *self
    }
}
impl<A> Copy for Cooperative<A> {}

impl<A> Clone for Kernel<A> {
    fn clone(&self) -> Self {
        *self
    }
}
impl<A> Copy for Kernel<A> {}

impl<A> core::fmt::Debug for Kernel<A> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("Kernel").field("name", &self.name).finish()
    }
}

/// What the host may know about a kernel without its argument type (for listings and checks).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct KernelInfo {
    /// Name of the `.entry` in the PTX module.
    pub name: &'static str,
    /// One line saying what the kernel does.
    pub summary: &'static str,
    /// Whether it reads before it waits for the launch before it what that launch cannot
    /// be writing (its registry line says `waits`; see [`follow_previous_launch`]): it may
    /// load, but neither store nor call, before the wait.
    pub reads_before_waiting: bool,
}

/// A bounds-checked view of `len` elements of device memory (host memory under the emulator),
/// which a kernel uses as its access `A` allows ([`Write`], the default, [`Read`](crate::access::Read) or
/// [`Unused`]: see [`mod@crate::access`]).
///
/// `#[repr(C)]`, 16 bytes whatever the access: the address and the length travel inside
/// kernel argument structs.
#[repr(C)]
pub struct DevSlice<T, A = Write> {
    addr: u64,
    len: u32,
    _reserved: u32,
    _element: PhantomData<(T, A)>,
}

impl<T, A> Clone for DevSlice<T, A> {
    fn clone(&self) -> Self {
        *self
    }
}
impl<T, A> Copy for DevSlice<T, A> {}

// SAFETY: `repr(C)`: a u64, two u32 and a zero-sized marker, 16 bytes with no padding
// (checked below); every field is plain data.
unsafe impl<T: 'static, A: Access> bytemuck::NoUninit for DevSlice<T, A> {}
const _: () = assert!(size_of::<DevSlice<u8>>() == 16);
const _: () = assert!(size_of::<DevSlice<u8, Unused>>() == 16);

/// Runs [`DevSlice::fold_runs`] reads at a time: four runs of four words are 16 loads in
/// flight a thread.
pub const RUNS_IN_FLIGHT: usize = 4;

// SAFETY: a `DevSlice` is an address and a length; the data races it could allow are excluded
// by each kernel's contract (disjoint writes, atomics for shared counters), stated at launch.
unsafe impl<T: Send, A: Access> Send for DevSlice<T, A> {}
// SAFETY: as above.
unsafe impl<T: Sync, A: Access> Sync for DevSlice<T, A> {}

impl<T, A: Access> core::fmt::Debug for DevSlice<T, A> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("DevSlice")
            .field("addr", &self.addr)
            .field("len", &self.len)
            .field("use", &A::USE)
            .finish()
    }
}

impl<T: Copy, A: Access> DevSlice<T, A> {
    /// A view of `len` elements starting at device address `addr`.
    ///
    /// # Safety
    /// `addr` must point to `len` initialised, aligned elements of `T` that stay allocated, and
    /// are accessed by nothing but the launch, for as long as any kernel uses the view.
    #[inline(always)]
    pub const unsafe fn from_raw_parts(addr: u64, len: u32) -> Self {
        DevSlice {
            addr,
            len,
            _reserved: 0,
            _element: PhantomData,
        }
    }

    /// The empty view: every index is out of bounds.
    pub const EMPTY: Self = DevSlice {
        addr: 0,
        len: 0,
        _reserved: 0,
        _element: PhantomData,
    };

    /// The device address of the first element.
    #[inline(always)]
    pub fn addr(&self) -> u64 {
        self.addr
    }

    /// The same elements, of an access that allows no more than this one's.
    #[inline(always)]
    pub fn restrict<B: Within<A>>(self) -> DevSlice<T, B> {
        DevSlice {
            addr: self.addr,
            len: self.len,
            _reserved: 0,
            _element: PhantomData,
        }
    }
}

impl<T: Copy, A: Readable> DevSlice<T, A> {
    /// Number of elements in view.
    #[inline(always)]
    pub fn len(&self) -> u32 {
        self.len
    }

    /// Whether the view holds no element.
    #[inline(always)]
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    #[inline(always)]
    fn ptr(&self, index: u32) -> *mut T {
        if index >= self.len {
            out_of_bounds(index, self.len);
        }
        (self.addr as *mut T).wrapping_add(index as usize)
    }

    /// The `len` elements from `start`; traps (GPU) or panics (CPU) unless they are all in
    /// view.
    #[inline(always)]
    pub fn range(&self, start: u32, len: u32) -> Self {
        if start as u64 + len as u64 > self.len as u64 {
            out_of_bounds(start.saturating_add(len), self.len);
        }
        DevSlice {
            addr: self.addr + start as u64 * size_of::<T>() as u64,
            len,
            _reserved: 0,
            _element: PhantomData,
        }
    }

    /// Reads element `index`; traps (GPU) or panics (CPU) when it is out of bounds.
    #[inline(always)]
    pub fn get(&self, index: u32) -> T
    where
        T: bytemuck::Pod,
    {
        // SAFETY: in bounds (checked), and valid per `from_raw_parts`.
        unsafe { memory::load(self.ptr(index)) }
    }

    /// Pointer to `N` elements from `start`, after one bounds check for all of them.
    #[inline(always)]
    fn run_ptr<const N: usize>(&self, start: u32) -> *mut [T; N] {
        if start as u64 + N as u64 > self.len as u64 {
            out_of_bounds(start.saturating_add(N as u32 - 1), self.len);
        }
        (self.addr as *mut T).wrapping_add(start as usize).cast()
    }

    /// Reads the `N` elements from `start` with a single bounds check: independent loads the
    /// GPU can keep in flight together, where a loop of [`DevSlice::get`] waits on each check.
    #[inline(always)]
    pub fn get_run<const N: usize>(&self, start: u32) -> [T; N]
    where
        T: bytemuck::Pod,
    {
        // SAFETY: in bounds (checked); `[T; N]` has the alignment of `T`.
        unsafe { memory::load(self.run_ptr::<N>(start)) }
    }

    /// Calls `f(i, element i)` for each `i` in `start..end`, in order. A range of exactly `N`
    /// elements (a full tile) is read with [`DevSlice::get_run`].
    #[inline(always)]
    pub fn for_each_in<const N: usize>(&self, start: u32, end: u32, mut f: impl FnMut(u32, T))
    where
        T: bytemuck::Pod,
    {
        if end.wrapping_sub(start) == N as u32 {
            let values: [T; N] = self.get_run(start);
            for (k, value) in values.into_iter().enumerate() {
                f(start + k as u32, value);
            }
        } else {
            for i in start..end {
                f(i, self.get(i));
            }
        }
    }

    /// Folds `f` over the elements `first, first + stride, …` below `end`, in that order,
    /// with a single bounds check: four loads at a time, which the GPU keeps in flight
    /// together, the last one to three too: in place of those past the end the last
    /// element is read and folded again, and the result dropped, so `f` must be a function
    /// of its arguments alone. `stride` must not be zero.
    #[inline(always)]
    pub fn fold_every<Acc: Copy>(
        &self,
        (first, end, stride): (u32, u32, u32),
        init: Acc,
        f: impl Fn(Acc, T) -> Acc,
    ) -> Acc
    where
        T: bytemuck::Pod,
    {
        let Some((base, end, stride)) = self.strided((first, end, stride)) else {
            return init;
        };
        // SAFETY (both loops): every index read is below `end`, at most the length (checked).
        let read = |i: u64| unsafe { memory::load(base.wrapping_add(i as usize)) };
        let (mut acc, mut i) = (init, u64::from(first));
        while i + 3 * stride < end {
            let values = [
                read(i),
                read(i + stride),
                read(i + 2 * stride),
                read(i + 3 * stride),
            ];
            for value in values {
                acc = f(acc, value);
            }
            i += 4 * stride;
        }
        if i < end {
            // Every load before the first use, so that the thread waits once, not once an
            // element (a branch around `f` would let the compiler sink each load into it).
            let last = end - 1;
            let values = asked([
                read(i),
                read((i + stride).min(last)),
                read((i + 2 * stride).min(last)),
            ]);
            for (j, value) in (0..).zip(values) {
                let folded = f(acc, value);
                acc = if i + j * stride < end { folded } else { acc };
            }
        }
        acc
    }

    /// The first element's address, `end` and `stride` (at least 1) of a walk from `first`
    /// by `stride` below `end`, after one bounds check for all of it; `None` if it reads
    /// nothing.
    #[inline(always)]
    fn strided(&self, (first, end, stride): (u32, u32, u32)) -> Option<(*const T, u64, u64)> {
        if first >= end {
            return None;
        }
        if end > self.len {
            out_of_bounds(end - 1, self.len);
        }
        let base = self.addr as *const T;
        Some((base, u64::from(end), u64::from(stride.max(1))))
    }

    /// Folds `f` over the runs of `N` elements from `first`, `first + stride`, … below `end`,
    /// in that order, with a single bounds check: [`RUNS_IN_FLIGHT`] runs at a time, whose
    /// loads the GPU keeps in flight together (where [`DevSlice::fold_every`] keeps four
    /// elements). `first`, `end` and `stride` must be multiples of `N` (checked, like the
    /// bounds: a kernel fault otherwise), so that a run starting below `end` ends by it; a
    /// zero `stride` counts as `N`. In place of the runs past the end, the last run is read
    /// and folded again, and the result dropped, so `f` must be a function of its arguments
    /// alone.
    #[inline(always)]
    pub fn fold_runs<const N: usize, Acc: Copy>(
        &self,
        (first, end, stride): (u32, u32, u32),
        init: Acc,
        f: impl Fn(Acc, [T; N]) -> Acc,
    ) -> Acc
    where
        T: bytemuck::Pod,
    {
        let n = N as u32;
        if first % n != 0 || end % n != 0 || stride % n != 0 {
            // A run could cross `end`, or (with `end` below `N`) the view's end.
            misaligned_runs(n, (first, end, stride));
        }
        let Some((base, end, stride)) = self.strided((first, end, stride.max(n))) else {
            return init;
        };
        let last = end - N as u64;
        // SAFETY: every run read ends by `end`, at most the length (checked).
        let read = |i: u64| unsafe { memory::load(base.wrapping_add(i as usize).cast::<[T; N]>()) };
        let (mut acc, mut i) = (init, u64::from(first));
        while i < end {
            // Every load before the first use, and no branch around `f`: the thread waits
            // once a round. Written out, so that the runs stay in registers.
            let at = |j: u64| (i + j * stride).min(last);
            let runs = [read(at(0)), read(at(1)), read(at(2)), read(at(3))];
            for (j, run) in runs.into_iter().enumerate() {
                let folded = f(acc, run);
                acc = if i + j as u64 * stride < end {
                    folded
                } else {
                    acc
                };
            }
            i += RUNS_IN_FLIGHT as u64 * stride;
        }
        acc
    }
}

impl<T: Copy> DevSlice<T, Write> {
    /// Writes element `index`; traps (GPU) or panics (CPU) when it is out of bounds.
    #[inline(always)]
    pub fn set(&self, index: u32, value: T)
    where
        T: bytemuck::Pod,
    {
        // SAFETY: in bounds (checked), and valid per `from_raw_parts`; the kernel's contract
        // gives each element at most one writing thread per launch (and a breach of it is a
        // race of relaxed atomics on the CPU, see `memory`).
        unsafe { memory::store(self.ptr(index), value) }
    }
}

impl DevSlice<u32> {
    /// Atomically adds `value` to element `index` (wrapping) and returns the previous value.
    ///
    /// A real atomic on both targets (`atom.global.add.u32` on the GPU). Only use results whose
    /// meaning does not depend on the order in which threads arrive (counts, not slots).
    #[inline(always)]
    pub fn atomic_add(&self, index: u32, value: u32) -> u32 {
        let ptr = self.ptr(index);
        // SAFETY: in bounds and aligned; concurrent accesses to this element in the launch are
        // all atomic by the kernel's contract.
        let atomic = unsafe { AtomicU32::from_ptr(ptr) };
        // The ordering is irrelevant here (and not honoured on nvptx): nothing in the same
        // launch reads the counter.
        atomic.fetch_add(value, Ordering::Relaxed)
    }

    /// Atomically sets element `index` to the larger of it and `value`; returns the previous
    /// value. The final value does not depend on the order in which threads arrive.
    #[inline(always)]
    pub fn atomic_max(&self, index: u32, value: u32) -> u32 {
        let ptr = self.ptr(index);
        // SAFETY: as in `atomic_add`.
        let atomic = unsafe { AtomicU32::from_ptr(ptr) };
        atomic.fetch_max(value, Ordering::Relaxed)
    }
}

/// Device memory as the CPU emulation models it: every element read and written as relaxed
/// atomic words, each as wide as the element's alignment allows (up to 8 bytes). Threads of
/// a launch that race on an element against their kernel's contract then each read some
/// value, as on a GPU, instead of making the host program's behaviour undefined: such a race
/// stays a logic error, which the shuffled schedules and the determinism tests can show and
/// which Miri and ThreadSanitizer accept as defined. On x86-64 relaxed loads and stores are
/// the plain instructions; on the GPU the accesses are the plain ones.
mod memory {
    #[cfg(not(target_arch = "nvptx64"))]
    use core::sync::atomic::{AtomicU8, AtomicU16, AtomicU32, AtomicU64, Ordering::Relaxed};

    /// The width of the words a `T` is accessed in: the widest of 8, 4, 2 and 1 bytes that its
    /// alignment and size are multiples of.
    #[cfg(not(target_arch = "nvptx64"))]
    const fn word<T>() -> usize {
        let mut width = 8;
        while width > 1 && (align_of::<T>() < width || !size_of::<T>().is_multiple_of(width)) {
            width /= 2;
        }
        width
    }

    /// Reads the `T` at `ptr`.
    ///
    /// # Safety
    /// `ptr` is aligned and points to an initialised `T` without padding bytes (a plain
    /// element, or an array of them), which stays allocated meanwhile and is accessed
    /// concurrently by these functions and `DevSlice`'s atomics alone.
    #[inline(always)]
    pub(super) unsafe fn load<T: Copy>(ptr: *const T) -> T {
        #[cfg(target_arch = "nvptx64")]
        {
            // SAFETY: as the caller promises.
            unsafe { ptr.read() }
        }
        #[cfg(not(target_arch = "nvptx64"))]
        {
            let mut value = core::mem::MaybeUninit::<T>::uninit();
            let to = value.as_mut_ptr().cast::<u8>();
            macro_rules! words {
                ($atomic:ty, $n:literal) => {
                    for k in 0..size_of::<T>() / $n {
                        // SAFETY: word `k` of the aligned `T` (its alignment is a multiple of
                        // the word's), accessed atomically by every thread; written into
                        // `value`'s bytes, which it fits.
                        unsafe {
                            let word =
                                <$atomic>::from_ptr(ptr.cast::<u8>().add(k * $n).cast_mut().cast());
                            to.add(k * $n)
                                .cast::<[u8; $n]>()
                                .write_unaligned(word.load(Relaxed).to_ne_bytes());
                        }
                    }
                };
            }
            match word::<T>() {
                8 => words!(AtomicU64, 8),
                4 => words!(AtomicU32, 4),
                2 => words!(AtomicU16, 2),
                _ => words!(AtomicU8, 1),
            }
            // SAFETY: every byte copied from an initialised `T` without padding.
            unsafe { value.assume_init() }
        }
    }

    /// Writes `value` to the `T` at `ptr`.
    ///
    /// # Safety
    /// As for [`load`].
    #[inline(always)]
    pub(super) unsafe fn store<T: Copy>(ptr: *mut T, value: T) {
        #[cfg(target_arch = "nvptx64")]
        {
            // SAFETY: as the caller promises.
            unsafe { ptr.write(value) }
        }
        #[cfg(not(target_arch = "nvptx64"))]
        {
            let from = (&raw const value).cast::<u8>();
            macro_rules! words {
                ($atomic:ty, $int:ty, $n:literal) => {
                    for k in 0..size_of::<T>() / $n {
                        // SAFETY: as in `load`; `value` has no padding, so its bytes are
                        // initialised.
                        unsafe {
                            let bytes = from.add(k * $n).cast::<[u8; $n]>().read_unaligned();
                            let word = <$atomic>::from_ptr(ptr.cast::<u8>().add(k * $n).cast());
                            word.store(<$int>::from_ne_bytes(bytes), Relaxed);
                        }
                    }
                };
            }
            match word::<T>() {
                8 => words!(AtomicU64, u64, 8),
                4 => words!(AtomicU32, u32, 4),
                2 => words!(AtomicU16, u16, 2),
                _ => words!(AtomicU8, u8, 1),
            }
        }
    }
}

#[cold]
#[inline(never)]
fn out_of_bounds(index: u32, len: u32) -> ! {
    #[cfg(target_arch = "nvptx64")]
    {
        let _ = (index, len);
        // SAFETY: `trap` aborts the kernel; it has no preconditions.
        unsafe { core::arch::nvptx::trap() }
    }
    #[cfg(not(target_arch = "nvptx64"))]
    panic!("device index {index} out of bounds for a buffer of {len} elements")
}

/// A persistent program's stage names kernel `kernel`, but only `stages` are known.
#[cold]
#[inline(never)]
pub(crate) fn no_such_stage(kernel: u32, stages: u32) -> ! {
    #[cfg(target_arch = "nvptx64")]
    {
        let _ = (kernel, stages);
        // SAFETY: `trap` aborts the kernel; it has no preconditions.
        unsafe { core::arch::nvptx::trap() }
    }
    #[cfg(not(target_arch = "nvptx64"))]
    panic!("a persistent stage names kernel {kernel}, but there are {stages} stage kernels")
}

#[cold]
#[inline(never)]
fn misaligned_runs(n: u32, (first, end, stride): (u32, u32, u32)) -> ! {
    #[cfg(target_arch = "nvptx64")]
    {
        let _ = (n, first, end, stride);
        // SAFETY: `trap` aborts the kernel; it has no preconditions.
        unsafe { core::arch::nvptx::trap() }
    }
    #[cfg(not(target_arch = "nvptx64"))]
    panic!("runs of {n} elements from {first} by {stride} below {end}: not multiples of {n}")
}
