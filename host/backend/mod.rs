//! One host interface over two backends: device buffers, upload/download, kernel launches and
//! synchronisation, on an NVIDIA GPU through the CUDA driver or on the CPU through an emulator
//! that runs the same kernel bodies.
//!
//! [`Device::select`] picks the backend at run time: `auto` takes the GPU when the driver and a
//! device are there and otherwise says once, on stderr, why it runs on the CPU.

pub mod floor;

/// The NVIDIA driver's library, by the name each OS gives it.
#[cfg(windows)]
const CUDA_LIBRARY: &str = "nvcuda.dll";
/// The NVIDIA driver's library, by the name each OS gives it.
#[cfg(not(windows))]
const CUDA_LIBRARY: &str = "libcuda.so.1";

mod buffer;
mod cpu;
mod cuda;
mod interop;
mod plan;
mod ring;

use std::borrow::Cow;
use std::collections::BTreeMap;
use std::fmt;
use std::sync::Mutex;
use std::sync::atomic::{AtomicU64, Ordering};

pub use gpuwars_kernels::data::Element;
use gpuwars_kernels::exec::Cooperative;
use gpuwars_kernels::{DevSlice, Kernel, KernelArgs};
use serde::Serialize;

use buffer::BufferImp;
pub use buffer::{Buffer, Buffers, Hold, Reader, Vecs, Zeroed};
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
    /// More contacts were logged since the contact log's last read than it holds (see
    /// `Pipeline::contact_log`): its world's contacts are denser than its room a slot.
    #[error(
        "{logged} contacts logged since the last read, more than the contact log holds \
         ({room}, {per_slot} a slot)"
    )]
    ContactLogFull {
        /// Contacts logged since the read before.
        logged: usize,
        /// Records the log holds.
        room: usize,
        /// Its room a slot ([`crate::sim::Physics::log_room`]).
        per_slot: usize,
    },
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

/// Which [`Device`] made a buffer, an op, a plan or a ring: each device opened in the
/// process has its own, so work never meets memory of another device unnoticed (two CPU
/// emulators are two devices, with two orders).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct DeviceId(u64);

impl fmt::Display for DeviceId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "device #{}", self.0)
    }
}

impl DeviceId {
    /// An id no device had before.
    fn next() -> DeviceId {
        static NEXT: AtomicU64 = AtomicU64::new(1);
        DeviceId(NEXT.fetch_add(1, Ordering::Relaxed))
    }

    /// `Ok` if `what`, of this device, is used on device `on`; else the error that says so.
    pub fn check(self, on: DeviceId, what: &str) -> Result<(), Error> {
        match self == on {
            true => Ok(()),
            false => Err(Error::Invalid(format!(
                "{what} of {self} used on {on}: buffers, ops, plans and rings work only on \
                 the device that made them"
            ))),
        }
    }
}

/// An open backend: where buffers live and kernels run.
pub struct Device {
    id: DeviceId,
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
            id: DeviceId::next(),
            imp: Imp::Cpu(cpu::Emulator::new(threads, schedule)?),
            reason: reason.to_string(),
            launches: None,
            allocated: AtomicU64::new(0),
        })
    }

    /// The first CUDA device, with the kernels' PTX loaded.
    pub fn cuda(reason: &str) -> Result<Device, Error> {
        Ok(Device {
            id: DeviceId::next(),
            imp: Imp::Cuda(Box::new(cuda::Gpu::open()?)),
            reason: reason.to_string(),
            launches: None,
            allocated: AtomicU64::new(0),
        })
    }

    /// This device's id, which its buffers, ops, plans and rings carry.
    pub fn id(&self) -> DeviceId {
        self.id
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
        Zeroed {
            device: self,
            used_only: false,
        }
    }

    /// Allocates groups of buffers, zeroed, of the arrays their access uses only (see
    /// [`Zeroed`]): `Group::<Buffers, Access>::build(&mut device.zeroed_used(), ..)`.
    pub fn zeroed_used(&self) -> Zeroed<'_> {
        Zeroed {
            device: self,
            used_only: true,
        }
    }

    /// Reads groups of buffers back (see [`Reader`]).
    pub fn reader(&self) -> Reader<'_> {
        Reader(self)
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

    /// Issues a cooperative launch of `kernel`, `grid` blocks of `block` threads all resident
    /// at once, on this device's backend, uncounted.
    ///
    /// # Safety
    /// As for [`Op::launch`], and the caller holds the emulator's order.
    unsafe fn issue_cooperative<A: KernelArgs>(
        &self,
        kernel: &Cooperative<A>,
        grid: u32,
        block: u32,
        args: A,
    ) -> Result<(), Error> {
        match &self.imp {
            Imp::Cpu(emu) => emu.launch_cooperative(kernel, grid, block, &args),
            // SAFETY: forwarded from the caller.
            Imp::Cuda(gpu) => unsafe { gpu.launch_cooperative(kernel, grid, block, args) },
        }
    }

    /// The most blocks of `block` threads of `kernel` this device runs at once: the largest
    /// grid of a cooperative launch (on the CPU, one block a worker thread).
    pub fn resident_blocks<A>(&self, kernel: &Cooperative<A>, block: u32) -> Result<u32, Error> {
        match &self.imp {
            Imp::Cpu(emu) => Ok(u32::try_from(emu.threads()).unwrap_or(u32::MAX)),
            Imp::Cuda(gpu) => gpu.resident_blocks(kernel, block),
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
                    BackendKind::Cpu => HOST_MEMORY,
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

    /// Bytes per second of a device-to-device copy that moves `bytes` (read plus written,
    /// so half of them each way; at most 512 MiB on the GPU and 64 MiB on the CPU, past
    /// which a copy runs at the memory's own rate): the ceiling of a kernel that moves as
    /// many, whose bytes stay in the same caches as the copy's do.
    pub fn copy_bandwidth(&self, bytes: u64) -> Result<f64, Error> {
        // The largest copy, and the bytes copied in all, enough to time the smallest.
        let (most, total) = match self.kind() {
            BackendKind::Cuda => (1u64 << 26, 1u64 << 33),
            BackendKind::Cpu => (1 << 23, 1 << 28),
        };
        let len = (bytes / (2 * size_of::<u32>() as u64)).clamp(1, most);
        let moved = 2 * len * size_of::<u32>() as u64;
        let reps = (total / moved).clamp(5, 2_000);
        let len = len as usize;
        let src = self.alloc_zeroed::<u32>(len)?;
        let mut dst = self.alloc_zeroed::<u32>(len)?;
        self.copy(&src, &mut dst)?;
        let start = self.mark()?;
        for _ in 0..reps {
            self.copy(&src, &mut dst)?;
        }
        let seconds = self.mark()?.seconds_since(&start)?;
        Ok((moved * reps) as f64 / seconds.max(f64::MIN_POSITIVE))
    }

    /// Waits until every queued launch and copy has finished, and reports a kernel fault.
    pub fn synchronize(&self) -> Result<(), Error> {
        match &self.imp {
            Imp::Cpu(_) => Ok(()),
            Imp::Cuda(gpu) => gpu.synchronize(&gpu.in_order()),
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

/// The host memory this process can still have, and the host's total: what `/proc/meminfo`
/// says is available, less where this process's address-space or data limit (`ulimit -v`,
/// `ulimit -d`) leaves less room than that. `None` where the system has no `/proc` (macOS):
/// nothing is checked before the allocations, and a shortage is then the allocations' own
/// error in words (the host buffers reserve with `try_reserve_exact`).
#[cfg(not(windows))]
fn host_memory() -> Option<(u64, u64)> {
    let kib_field = |text: &str, name: &str| -> Option<u64> {
        let line = text.lines().find(|l| l.starts_with(name))?;
        let kib: u64 = line[name.len()..]
            .trim()
            .trim_end_matches("kB")
            .trim()
            .parse()
            .ok()?;
        Some(kib * 1024)
    };
    let info = std::fs::read_to_string("/proc/meminfo").ok()?;
    let available = kib_field(&info, "MemAvailable:")?;
    let total = kib_field(&info, "MemTotal:")?;
    let limits = std::fs::read_to_string("/proc/self/limits").unwrap_or_default();
    let status = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    let room = |limit: &str, used: &str| -> Option<u64> {
        let line = limits.lines().find(|l| l.starts_with(limit))?;
        let soft: u64 = line[limit.len()..]
            .split_whitespace()
            .next()?
            .parse()
            .ok()?;
        Some(soft.saturating_sub(kib_field(&status, used).unwrap_or(0)))
    };
    let free = [
        room("Max address space", "VmSize:"),
        room("Max data size", "VmData:"),
    ]
    .into_iter()
    .flatten()
    .fold(available, u64::min);
    Some((free, total))
}

/// The host memory this process can still have, and the host's total, as Windows counts
/// them (`GlobalMemoryStatusEx`): the physical memory available. `None` where the call
/// fails or leaves no memory available at all (seen once under Wine): nothing is then
/// checked before the allocations, which fail in words themselves.
#[cfg(windows)]
fn host_memory() -> Option<(u64, u64)> {
    use windows_sys::Win32::System::SystemInformation::{GlobalMemoryStatusEx, MEMORYSTATUSEX};
    let mut status = MEMORYSTATUSEX {
        dwLength: std::mem::size_of::<MEMORYSTATUSEX>() as u32,
        ..Default::default()
    };
    // SAFETY: `status` is a MEMORYSTATUSEX whose length field says so, as the call asks.
    let answered = unsafe { GlobalMemoryStatusEx(&mut status) } != 0;
    (answered && status.ullAvailPhys > 0).then_some((status.ullAvailPhys, status.ullTotalPhys))
}

/// Where [`host_memory`]'s figure comes from, for a shortage's error.
#[cfg(windows)]
const HOST_MEMORY: &str = "host (the physical memory Windows says is available)";
/// Where [`host_memory`]'s figure comes from, for a shortage's error.
#[cfg(not(windows))]
const HOST_MEMORY: &str =
    "host (what the machine has available, within this process's ulimit -v and -d)";
