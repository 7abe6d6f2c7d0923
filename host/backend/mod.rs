//! One host interface over two backends: device buffers, upload/download, kernel launches and
//! synchronisation, on an NVIDIA GPU through the CUDA driver or on the CPU through an emulator
//! that runs the same kernel bodies.
//!
//! [`Device::select`] picks the backend at run time: `auto` takes the GPU when the driver and a
//! device are there and otherwise says once, on stderr, why it runs on the CPU.

pub mod floor;

mod cpu;
mod cuda;
mod interop;
mod plan;
mod ring;

use std::borrow::Cow;
use std::collections::BTreeMap;
use std::fmt;
use std::marker::PhantomData;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};

pub use gpuwars_kernels::data::Element;
use gpuwars_kernels::data::{Build, Convert, Store};
use gpuwars_kernels::{DevSlice, Kernel, KernelArgs};
use serde::Serialize;

pub use cpu::Schedule;
pub use cuda::GpuProperties;
pub use interop::GlBuffer;
pub use plan::{Binder, Op, Plan};
pub use ring::Ring;

/// The largest block the GPU accepts; the emulator enforces it too, so that a launch that runs
/// on one backend runs on the other.
pub const MAX_BLOCK: u32 = 1024;

/// One kernel launch: the kernel, `grid` blocks of `block` threads, and its arguments.
#[derive(Clone, Copy, Debug)]
pub struct Launch<A> {
    /// The kernel.
    pub kernel: Kernel<A>,
    /// Blocks (a launch of none does nothing).
    pub grid: u32,
    /// Threads per block (1 to [`MAX_BLOCK`]).
    pub block: u32,
    /// The kernel's argument struct.
    pub args: A,
}

/// What went wrong on the host side of a kernel or a transfer.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// `--backend cuda` was asked for, but no usable GPU is there.
    #[error("the CUDA backend is not available: {0}")]
    CudaUnavailable(String),
    /// A CUDA driver call failed.
    #[error("CUDA driver error while {during}: {source}")]
    Driver {
        /// What the host was doing.
        during: String,
        /// The driver's error.
        source: cudarc::driver::DriverError,
    },
    /// A kernel faulted: an out-of-bounds index under the emulator, a trap (or another fault)
    /// on the GPU. The emulator reports it from the launch, and the same device carries on.
    /// The GPU reports it from the next call that waits for it, and the driver then fails
    /// every later CUDA call of the process, on any device opened before or after, with the
    /// same fault: the process carries on on the CPU emulation (`Device::select` with `auto`
    /// falls back to it), and a new process has the whole GPU again.
    #[error("kernel `{kernel}` failed: {message}")]
    KernelFault {
        /// The kernel's entry-point name. On the GPU, which reports a fault only later and
        /// does not say which kernel it stopped, the names of the kernels queued since the
        /// host last saw the device finish its work (`a, b or c`), or `unknown` when none of
        /// this device's kernels was (the fault came earlier, from another device).
        kernel: Cow<'static, str>,
        /// What the backend reported, and on the GPU how to carry on.
        message: String,
    },
    /// A launch, buffer or size outside what the backends accept.
    #[error("invalid request: {0}")]
    Invalid(String),
    /// Drawing with OpenGL failed (or no GL context could be made).
    #[error("OpenGL: {during}: {message}")]
    Graphics {
        /// What was being done.
        during: String,
        /// What glium or the driver said.
        message: String,
    },
    /// A world larger than the device's free memory.
    #[error(
        "{what} needs {} bytes of {place} memory, but only {} are free",
        crate::files::thousands(*.needed),
        crate::files::thousands(*.free)
    )]
    OutOfMemory {
        /// What was being made.
        what: String,
        /// Bytes it needs.
        needed: u64,
        /// Bytes free.
        free: u64,
        /// "device" or "host".
        place: &'static str,
    },
    /// A file could not be written (a frame) or read.
    #[error(transparent)]
    File(#[from] crate::files::FileError),
}

/// Which backend runs the kernels.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum BackendKind {
    /// An NVIDIA GPU through the CUDA driver API.
    Cuda,
    /// The CPU emulation of the kernels.
    Cpu,
}

impl fmt::Display for BackendKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            BackendKind::Cuda => "cuda",
            BackendKind::Cpu => "cpu",
        })
    }
}

/// The backend the user asked for (`--backend`, or the `GPUWARS_BACKEND` variable).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum BackendRequest {
    /// The GPU when one is usable, otherwise the CPU emulation.
    #[default]
    Auto,
    /// The GPU, or an error.
    Cuda,
    /// The CPU emulation.
    Cpu,
}

/// An open backend: where buffers live and kernels run.
pub struct Device {
    imp: Imp,
    reason: String,
    /// Launches per kernel, counted only while [`Device::count_launches`] is on.
    launches: Option<Mutex<BTreeMap<&'static str, u64>>>,
    /// Bytes of buffers allocated since the device was opened (freed ones included).
    allocated: AtomicU64,
}

enum Imp {
    Cpu(cpu::Emulator),
    // Boxed: the GPU's handles are several times the emulator's.
    Cuda(Box<cuda::Gpu>),
}

/// A buffer of `T` in the device's memory (host memory under the emulator).
///
/// The host reads and writes it through the [`Device`] (`write`, `download`, `copy`), and
/// kernels through the views a [`Binder`] makes for an [`Op`]. The memory is shared with the
/// ops that view it ([`Buffer::hold`]): it is freed when the buffer and every op and plan
/// made with it are gone, not before.
///
/// Safe code cannot see the memory any other way: a buffer hands out no view of itself, so
/// this does not compile (a view would outlive the buffer it was made from, and read memory
/// the next upload reuses).
/// ```compile_fail,E0599
/// let dev = gpuwars::Device::cpu(Some(1), "probe").unwrap();
/// let view = dev.upload(&[7u32; 1024]).unwrap().view(); // the Buffer is dropped here
/// let _other = dev.upload(&[9u32; 1024]).unwrap();
/// println!("{}", view.get(0));
/// ```
pub struct Buffer<T: Element> {
    imp: Arc<BufferImp<T>>,
}

/// A share in a buffer's memory that keeps it allocated and gives no access to it: what an
/// [`Op`] holds of each buffer its arguments view.
#[derive(Clone)]
pub struct Hold {
    _memory: Arc<dyn Send + Sync>,
}

enum BufferImp<T: Element> {
    Cpu(cpu::HostBuffer<T>),
    /// Bytes on the GPU, `len` elements at `addr`; `T` is the type the bytes hold. cudarc's
    /// copies want the slice exclusively, which the lock gives while ops share the
    /// allocation.
    Cuda {
        bytes: Mutex<cudarc::driver::CudaSlice<u8>>,
        addr: u64,
        len: usize,
        _element: PhantomData<T>,
    },
    /// Page-locked host memory mapped into the GPU's address space, `len` elements: what the
    /// host and the steps in flight exchange without copies (see [`Ring`]).
    Mapped {
        memory: cuda::Mapped,
        len: usize,
        _element: PhantomData<T>,
    },
}

impl<T: Element> BufferImp<T> {
    fn cuda(bytes: cudarc::driver::CudaSlice<u8>) -> Self {
        BufferImp::Cuda {
            addr: cuda::address(&bytes),
            len: bytes.len() / size_of::<T>(),
            bytes: Mutex::new(bytes),
            _element: PhantomData,
        }
    }
}

/// The GPU bytes of a buffer, locked for a copy.
fn locked(
    bytes: &Mutex<cudarc::driver::CudaSlice<u8>>,
) -> std::sync::MutexGuard<'_, cudarc::driver::CudaSlice<u8>> {
    bytes.lock().unwrap_or_else(|e| e.into_inner())
}

impl<T: Element> Buffer<T> {
    /// Number of elements.
    pub fn len(&self) -> usize {
        match &*self.imp {
            BufferImp::Cpu(b) => b.len(),
            BufferImp::Cuda { len, .. } | BufferImp::Mapped { len, .. } => *len,
        }
    }

    /// Whether the buffer holds no element.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// A share in the buffer's memory, keeping it allocated for as long as it lives.
    pub fn hold(&self) -> Hold {
        Hold {
            _memory: self.imp.clone(),
        }
    }

    /// The device address of the first element (a host address under the emulator).
    fn addr(&self) -> u64 {
        match &*self.imp {
            BufferImp::Cpu(b) => b.addr(),
            BufferImp::Cuda { addr, .. } => *addr,
            BufferImp::Mapped { memory, .. } => memory.addr,
        }
    }

    /// The first `len` elements (clamped to the buffer's length) as a kernel argument.
    ///
    /// # Safety
    /// The view must be used only by launches that run while the memory is allocated, and in
    /// the device's order (see [`Binder`], the one caller).
    unsafe fn view_prefix(&self, len: u32) -> DevSlice<T> {
        let len = len.min(self.len() as u32);
        // SAFETY: `len` elements of this buffer from its start; the caller keeps its use in
        // the buffer's life.
        unsafe { DevSlice::from_raw_parts(self.addr(), len) }
    }
}

/// A group's arrays held as [`Buffer`]s on a device: `Group<Buffers>` for any group the
/// kernels declare with `device_data!`.
#[derive(Clone, Copy, Debug)]
pub struct Buffers;

impl Store for Buffers {
    type Array<T: Element> = Buffer<T>;
}

/// A group's arrays read back to the host: `Group<Vecs>`.
#[derive(Clone, Copy, Debug)]
pub struct Vecs;

impl Store for Vecs {
    type Array<T: Element> = Vec<T>;
}

/// Allocates a group's arrays, zeroed, on a device: `Group::<Buffers>::build(&mut device.zeroed(), ..)`.
pub struct Zeroed<'d>(&'d Device);

impl Build<Buffers> for Zeroed<'_> {
    type Error = Error;
    fn array<T: Element>(&mut self, _: &'static str, len: usize) -> Result<Buffer<T>, Error> {
        self.0.alloc_zeroed(len)
    }
}

/// Reads a group's arrays back: `group.convert(&mut device.reader())`.
pub struct Reader<'d>(&'d Device);

impl Convert<Buffers, Vecs> for Reader<'_> {
    type Error = Error;
    fn array<T: Element>(&mut self, _: &'static str, array: &Buffer<T>) -> Result<Vec<T>, Error> {
        self.0.download(array)
    }
}

impl Device {
    /// Opens the backend the request names; `Auto` falls back to the CPU and says why on
    /// stderr. `cpu_threads` sizes the emulator's pool (`None`: one per core).
    pub fn select(request: BackendRequest, cpu_threads: Option<usize>) -> Result<Device, Error> {
        match request {
            BackendRequest::Cpu => Device::cpu(cpu_threads, "asked for with --backend cpu"),
            BackendRequest::Cuda => Device::cuda("asked for with --backend cuda"),
            BackendRequest::Auto => match Device::cuda("a CUDA device was found") {
                Ok(device) => Ok(device),
                Err(e) => {
                    let why = match e {
                        Error::CudaUnavailable(why) => why,
                        other => format!("the GPU could not be used ({other})"),
                    };
                    eprintln!("gpuwars: running the kernels on the CPU emulation: {why}");
                    Device::cpu(cpu_threads, &why)
                }
            },
        }
    }

    /// The CPU emulation with `threads` workers (`None`: one per core).
    pub fn cpu(threads: Option<usize>, reason: &str) -> Result<Device, Error> {
        Device::cpu_scheduled(threads, Schedule::InOrder, reason)
    }

    /// The CPU emulation with `threads` workers, running blocks and threads as `schedule`
    /// says.
    pub fn cpu_scheduled(
        threads: Option<usize>,
        schedule: Schedule,
        reason: &str,
    ) -> Result<Device, Error> {
        Ok(Device {
            imp: Imp::Cpu(cpu::Emulator::new(threads, schedule)?),
            reason: reason.to_string(),
            launches: None,
            allocated: AtomicU64::new(0),
        })
    }

    /// The first CUDA device, with the kernels' PTX loaded.
    pub fn cuda(reason: &str) -> Result<Device, Error> {
        Ok(Device {
            imp: Imp::Cuda(Box::new(cuda::Gpu::open()?)),
            reason: reason.to_string(),
            launches: None,
            allocated: AtomicU64::new(0),
        })
    }

    /// Which backend this is.
    pub fn kind(&self) -> BackendKind {
        match self.imp {
            Imp::Cpu(_) => BackendKind::Cpu,
            Imp::Cuda(_) => BackendKind::Cuda,
        }
    }

    /// Why this backend was chosen.
    pub fn reason(&self) -> &str {
        &self.reason
    }

    /// The GPU's name, compute capability, memory and driver; `None` under the emulator.
    pub fn gpu_properties(&self) -> Option<&GpuProperties> {
        match &self.imp {
            Imp::Cuda(gpu) => Some(gpu.properties()),
            Imp::Cpu(_) => None,
        }
    }

    /// Whether kernels launched (or captured) from now on may start before the launch they
    /// follow ends: programmatic dependent launch, on by default on sm_90 and newer; never on
    /// older cards or the CPU emulation.
    pub fn dependent_launch(&self) -> bool {
        match &self.imp {
            Imp::Cuda(gpu) => gpu.dependent_launch(),
            Imp::Cpu(_) => false,
        }
    }

    /// Turns programmatic dependent launch on or off for the launches and plans made from
    /// now on (plans made before keep theirs); returns whether it is on, which it cannot be
    /// where [`Device::dependent_launch`] says never.
    pub fn set_dependent_launch(&self, on: bool) -> bool {
        match &self.imp {
            Imp::Cuda(gpu) => gpu.set_dependent_launch(on),
            Imp::Cpu(_) => false,
        }
    }

    /// Worker threads of the CPU emulation; `None` on the GPU.
    pub fn cpu_threads(&self) -> Option<usize> {
        match &self.imp {
            Imp::Cpu(emu) => Some(emu.threads()),
            Imp::Cuda(_) => None,
        }
    }

    /// Allocates groups of buffers, zeroed (see [`Zeroed`]).
    pub fn zeroed(&self) -> Zeroed<'_> {
        Zeroed(self)
    }

    /// Reads groups of buffers back (see [`Reader`]).
    pub fn reader(&self) -> Reader<'_> {
        Reader(self)
    }

    /// A buffer of `len` zeroed elements.
    pub fn alloc_zeroed<T: Element>(&self, len: usize) -> Result<Buffer<T>, Error> {
        check_len::<T>(len)?;
        self.note_allocation::<T>(len);
        let imp = match &self.imp {
            Imp::Cpu(_) => BufferImp::Cpu(cpu::HostBuffer::zeroed(len)),
            Imp::Cuda(gpu) => BufferImp::cuda(gpu.alloc_zeroed(len * size_of::<T>())?),
        };
        Ok(Buffer { imp: Arc::new(imp) })
    }

    /// A buffer of `len` zeroed elements that the host and the kernels share without copies:
    /// page-locked host memory mapped into the GPU's address space (plain host memory under
    /// the emulation). Kernels reach it across the bus, so it suits a few words a step. Its
    /// bytes are host memory, not counted as the device's. The host reaches it through a
    /// [`Ring`], or with [`Device::download`] and [`Device::write`], which wait for the GPU
    /// first.
    pub fn alloc_shared<T: Element>(&self, len: usize) -> Result<Buffer<T>, Error> {
        check_len::<T>(len)?;
        let imp = match &self.imp {
            Imp::Cpu(_) => BufferImp::Cpu(cpu::HostBuffer::zeroed(len)),
            Imp::Cuda(gpu) => BufferImp::Mapped {
                memory: gpu.mapped(len * size_of::<T>())?,
                len,
                _element: PhantomData,
            },
        };
        Ok(Buffer { imp: Arc::new(imp) })
    }

    /// A buffer holding a copy of `data`.
    pub fn upload<T: Element>(&self, data: &[T]) -> Result<Buffer<T>, Error> {
        check_len::<T>(data.len())?;
        self.note_allocation::<T>(data.len());
        let imp = match &self.imp {
            Imp::Cpu(_) => BufferImp::Cpu(cpu::HostBuffer::from_slice(data)),
            Imp::Cuda(gpu) => BufferImp::cuda(gpu.upload(data)?),
        };
        Ok(Buffer { imp: Arc::new(imp) })
    }

    /// Overwrites the start of `buffer` with `data`.
    pub fn write<T: Element>(&self, buffer: &mut Buffer<T>, data: &[T]) -> Result<(), Error> {
        if data.len() > buffer.len() {
            return Err(Error::Invalid(format!(
                "cannot write {} elements into a buffer of {}",
                data.len(),
                buffer.len()
            )));
        }
        match (&self.imp, &*buffer.imp) {
            (Imp::Cpu(emu), BufferImp::Cpu(b)) => {
                let _order = emu.in_order();
                // SAFETY: in the device's order (no launch runs), and `&mut buffer` excludes
                // the other host borrows.
                let slice = unsafe { b.as_mut_slice() };
                slice[..data.len()].copy_from_slice(data);
                Ok(())
            }
            (Imp::Cuda(gpu), BufferImp::Cuda { bytes, .. }) => gpu.write(&mut locked(bytes), data),
            (Imp::Cuda(gpu), BufferImp::Mapped { memory, .. }) => {
                gpu.synchronize()?;
                // SAFETY: no kernel runs (waited for above), `&mut buffer` excludes the other
                // host borrows, and the buffer holds at least `data.len()` elements.
                unsafe {
                    let dst = memory.ptr.cast::<T>();
                    std::ptr::copy_nonoverlapping(data.as_ptr(), dst, data.len());
                }
                Ok(())
            }
            _ => Err(foreign_buffer()),
        }
    }

    /// Copies the whole buffer back to the host (waits for the work queued before).
    pub fn download<T: Element>(&self, buffer: &Buffer<T>) -> Result<Vec<T>, Error> {
        match (&self.imp, &*buffer.imp) {
            (Imp::Cpu(emu), BufferImp::Cpu(b)) => {
                let _order = emu.in_order();
                // SAFETY: in the device's order: no launch writes meanwhile.
                Ok(unsafe { b.as_slice() }.to_vec())
            }
            (Imp::Cuda(gpu), BufferImp::Cuda { bytes, .. }) => gpu.download(&locked(bytes)),
            (Imp::Cuda(gpu), BufferImp::Mapped { memory, len, .. }) => {
                gpu.synchronize()?;
                // SAFETY: no kernel runs (waited for above); `len` elements of plain bytes.
                Ok(unsafe { std::slice::from_raw_parts(memory.ptr.cast::<T>(), *len) }.to_vec())
            }
            _ => Err(foreign_buffer()),
        }
    }

    /// Sets every element of `buffer` to zero.
    pub fn zero<T: Element>(&self, buffer: &mut Buffer<T>) -> Result<(), Error> {
        match (&self.imp, &*buffer.imp) {
            (Imp::Cpu(emu), BufferImp::Cpu(b)) => {
                let _order = emu.in_order();
                // SAFETY: as in `write`.
                unsafe { b.as_mut_slice() }.fill(T::zeroed());
                Ok(())
            }
            (Imp::Cuda(gpu), BufferImp::Cuda { bytes, .. }) => gpu.zero(&mut locked(bytes)),
            (Imp::Cuda(gpu), BufferImp::Mapped { memory, len, .. }) => {
                gpu.synchronize()?;
                // SAFETY: as in `write`.
                unsafe { std::ptr::write_bytes(memory.ptr.cast::<T>(), 0, *len) };
                Ok(())
            }
            _ => Err(foreign_buffer()),
        }
    }

    /// Copies `src` into the start of `dst`, device to device.
    pub fn copy<T: Element>(&self, src: &Buffer<T>, dst: &mut Buffer<T>) -> Result<(), Error> {
        if src.len() > dst.len() {
            return Err(Error::Invalid(format!(
                "cannot copy {} elements into a buffer of {}",
                src.len(),
                dst.len()
            )));
        }
        match (&self.imp, &*src.imp, &*dst.imp) {
            (Imp::Cpu(emu), BufferImp::Cpu(s), BufferImp::Cpu(d)) => {
                let _order = emu.in_order();
                // SAFETY: as in `write`; two buffers are two allocations.
                unsafe { d.as_mut_slice()[..s.len()].copy_from_slice(s.as_slice()) };
                Ok(())
            }
            (
                Imp::Cuda(gpu),
                BufferImp::Cuda { bytes: s, .. },
                BufferImp::Cuda { bytes: d, .. },
            ) => gpu.copy(&locked(s), &mut locked(d)),
            (Imp::Cuda(_), BufferImp::Mapped { .. }, _)
            | (Imp::Cuda(_), _, BufferImp::Mapped { .. }) => Err(Error::Invalid(
                "a device copy to or from shared memory (download or write it instead)".into(),
            )),
            _ => Err(foreign_buffer()),
        }
    }

    /// Runs one op now: queued on the GPU ([`Device::synchronize`] waits for it), done
    /// when it returns on the CPU. A launch of zero blocks does nothing.
    pub fn launch(&self, op: Op) -> Result<(), Error> {
        self.run(&self.plan(vec![op], false)?)
    }

    /// Issues `launch` on this device's backend, uncounted.
    ///
    /// # Safety
    /// As for [`Op::launch`], and the caller holds the emulator's order (see `Emulator::in_order`).
    unsafe fn issue<A: KernelArgs>(&self, launch: &Launch<A>) -> Result<(), Error> {
        let Launch {
            kernel,
            grid,
            block,
            ..
        } = *launch;
        if block == 0 || block > MAX_BLOCK {
            return Err(Error::Invalid(format!(
                "kernel `{}`: block of {block} threads (allowed 1..={MAX_BLOCK})",
                kernel.name
            )));
        }
        if grid == 0 {
            return Ok(());
        }
        match &self.imp {
            Imp::Cpu(emu) => emu.launch(launch),
            // SAFETY: forwarded from the caller.
            Imp::Cuda(gpu) => unsafe { gpu.launch(launch) },
        }
    }

    /// Adds one launch of each named kernel to the counts, if counting is on.
    fn count(&self, kernels: impl IntoIterator<Item = &'static str>) {
        if let Some(launches) = &self.launches {
            let mut launches = launches.lock().unwrap_or_else(|e| e.into_inner());
            for name in kernels {
                *launches.entry(name).or_default() += 1;
            }
        }
    }

    /// Starts counting launches per kernel (from zero), or stops when `on` is false. Off by
    /// default: then a launch pays nothing for it.
    pub fn count_launches(&mut self, on: bool) {
        self.launches = on.then(Mutex::default);
    }

    /// Launches per kernel name since counting started (empty when off), in name order.
    pub fn launch_counts(&self) -> BTreeMap<&'static str, u64> {
        self.launches
            .as_ref()
            .map_or_else(BTreeMap::new, |launches| {
                launches.lock().unwrap_or_else(|e| e.into_inner()).clone()
            })
    }

    /// Bytes of buffers allocated on this device since it was opened, freed ones included:
    /// what a world's set-up took, measured.
    pub fn allocated_bytes(&self) -> u64 {
        self.allocated.load(Ordering::Relaxed)
    }

    fn note_allocation<T>(&self, len: usize) {
        self.allocated
            .fetch_add((len * size_of::<T>()) as u64, Ordering::Relaxed);
    }

    /// Free and total memory, in bytes, where this device keeps its buffers: the GPU's
    /// memory, or the host's available memory for the emulation (`None` where the system
    /// does not say).
    pub fn memory(&self) -> Result<Option<(u64, u64)>, Error> {
        match &self.imp {
            Imp::Cuda(gpu) => gpu.memory().map(Some),
            Imp::Cpu(_) => Ok(host_memory()),
        }
    }

    /// Fails with [`Error::OutOfMemory`] unless `bytes` more bytes fit in the device's free
    /// memory; `what` names what needs them.
    pub fn check_fits(&self, what: &str, bytes: u64) -> Result<(), Error> {
        match self.memory()? {
            Some((free, _)) if bytes > free => Err(Error::OutOfMemory {
                what: what.to_string(),
                needed: bytes,
                free,
                place: match self.kind() {
                    BackendKind::Cuda => "device",
                    BackendKind::Cpu => "host",
                },
            }),
            _ => Ok(()),
        }
    }

    /// Queues the zeroing of every element `view` covers.
    ///
    /// # Safety
    /// As for [`Op::clear`], and the caller holds the emulator's order.
    unsafe fn clear<T: Element>(&self, view: DevSlice<T>) -> Result<(), Error> {
        let bytes = view.len() as usize * size_of::<T>();
        if bytes == 0 {
            return Ok(());
        }
        match &self.imp {
            // SAFETY: forwarded from the caller; in the device's order, so no kernel runs.
            Imp::Cpu(_) => unsafe {
                std::ptr::write_bytes(view.addr() as *mut u8, 0, bytes);
                Ok(())
            },
            // SAFETY: forwarded from the caller.
            Imp::Cuda(gpu) => unsafe { gpu.clear(view.addr(), bytes) },
        }
    }

    /// Bytes per second of a large device-to-device copy, read plus written: the
    /// bandwidth ceiling a memory-bound kernel is measured against.
    pub fn copy_bandwidth(&self) -> Result<f64, Error> {
        let (len, reps) = match self.kind() {
            BackendKind::Cuda => (1usize << 26, 20),
            BackendKind::Cpu => (1 << 23, 5),
        };
        let src = self.alloc_zeroed::<u32>(len)?;
        let mut dst = self.alloc_zeroed::<u32>(len)?;
        self.copy(&src, &mut dst)?;
        let start = self.mark()?;
        for _ in 0..reps {
            self.copy(&src, &mut dst)?;
        }
        let seconds = self.mark()?.seconds_since(&start)?;
        Ok((2 * len * size_of::<u32>() * reps) as f64 / seconds.max(f64::MIN_POSITIVE))
    }

    /// Waits until every queued launch and copy has finished, and reports a kernel fault.
    pub fn synchronize(&self) -> Result<(), Error> {
        match &self.imp {
            Imp::Cpu(_) => Ok(()),
            Imp::Cuda(gpu) => gpu.synchronize(),
        }
    }
}

/// A short description of the device.
pub fn device_name(device: &Device) -> String {
    match (device.gpu_properties(), device.cpu_threads()) {
        (Some(gpu), _) => gpu.name.clone(),
        (None, Some(threads)) => format!("CPU emulation, {threads} threads"),
        (None, None) => "CPU emulation".to_string(),
    }
}

/// Kernels index buffers with `u32`, and an element must take up memory.
fn check_len<T>(len: usize) -> Result<(), Error> {
    if size_of::<T>() == 0 {
        return Err(Error::Invalid(format!(
            "a buffer of the zero-sized type {}",
            std::any::type_name::<T>()
        )));
    }
    if len > u32::MAX as usize {
        return Err(Error::Invalid(format!(
            "a buffer of {len} elements (at most {} allowed)",
            u32::MAX
        )));
    }
    Ok(())
}

/// The host's available and total memory, from `/proc/meminfo`.
fn host_memory() -> Option<(u64, u64)> {
    let info = std::fs::read_to_string("/proc/meminfo").ok()?;
    let field = |name: &str| -> Option<u64> {
        let line = info.lines().find(|l| l.starts_with(name))?;
        let kib: u64 = line[name.len()..]
            .trim()
            .trim_end_matches("kB")
            .trim()
            .parse()
            .ok()?;
        Some(kib * 1024)
    };
    Some((field("MemAvailable:")?, field("MemTotal:")?))
}

fn foreign_buffer() -> Error {
    Error::Invalid("a buffer of another backend was passed to this device".into())
}
