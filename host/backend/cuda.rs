//! The CUDA backend: the kernels' PTX loaded into the first GPU through the driver API.
//!
//! `cudarc` loads libcuda at run time, so the binary starts without the NVIDIA driver; opening
//! this backend then fails with [`Error::CudaUnavailable`] and a reason, never a panic.
//!
//! A kernel that traps (a failed bounds check) or faults does not make its launch fail: the
//! GPU reports it to a later call, the next one that waits for the stream or any call after,
//! and from then on every CUDA call of the process fails the same way (the error is
//! "sticky"; checked on an H200 with driver 580: neither releasing nor resetting the primary
//! context, nor a new context, clears it). [`InFlight`] remembers which kernels were queued
//! since the host last saw the stream finish, so that [`InFlight::error`], the one place
//! driver errors are turned into [`Error`]s, can report such a failure as the
//! [`Error::KernelFault`] it is.

use std::borrow::Cow;
use std::collections::HashMap;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};
use std::thread::ThreadId;

use cudarc::driver::{
    CudaContext, CudaEvent, CudaFunction, CudaGraph, CudaSlice, CudaStream, DevicePtr, DeviceRepr,
    DriverError, LaunchConfig, PushKernelArg, result, sys,
};
use gpuwars_kernels::exec::Cooperative;
use gpuwars_kernels::{KernelArgs, registry};
use serde::Serialize;

mod driver;
mod order;

use super::{Element, Error, Launch};
use crate::ptx;
use driver::{cooperative, dependent, launch_with, load, properties};
use order::BRANCHES;
pub(super) use order::{Order, Sides};

/// What the driver reports about the GPU.
#[derive(Clone, Debug, Serialize)]
pub struct GpuProperties {
    /// Marketing name, e.g. "NVIDIA H200".
    pub name: String,
    /// Compute capability as "major.minor".
    pub compute_capability: String,
    /// Global memory in bytes.
    pub memory_bytes: u64,
    /// Multiprocessors.
    pub multiprocessors: u32,
    /// Threads one multiprocessor holds at once.
    pub threads_per_multiprocessor: u32,
    /// Driver's CUDA version, e.g. "13.0".
    pub driver_cuda_version: String,
    /// The architecture of the PTX module loaded: the baseline, or the Hopper one whose
    /// kernels can be launched before the launch they follow ends.
    pub ptx_arch: String,
}

/// An open GPU: context, stream and every kernel of the module.
pub(super) struct Gpu {
    ctx: Arc<CudaContext>,
    stream: Arc<CudaStream>,
    /// The kernels queued on `stream` that may not have finished.
    in_flight: Arc<InFlight>,
    /// The capture in progress, if any: the thread recording and its private stream.
    capture: Mutex<Option<(ThreadId, Arc<CudaStream>)>>,
    /// The device's order: held by whoever queues work on the device (a plan from its first
    /// op to its branches' join, a capture, a copy, a fence, a wait), so that no thread's
    /// work lands between another's fork and join; it owns the side streams, so only its
    /// holder forks onto them. The GL buffers registered here share it (see `GlBuffer`).
    order: Order,
    /// The thread issuing an op beside the others, if any, and its branch's stream: its
    /// launches go there.
    beside: Mutex<Option<(ThreadId, Arc<CudaStream>)>>,
    functions: HashMap<&'static str, CudaFunction>,
    /// The cooperative kernels, from their own module, loaded by the first that is asked
    /// for (the driver takes about a minute to compile it; see `ptx::PROGRAM_PTX`).
    cooperative: Mutex<Option<HashMap<&'static str, CudaFunction>>>,
    properties: GpuProperties,
    /// Whether launches carry programmatic stream serialization (start before the launch
    /// they follow ends); `None` when the card cannot (before sm_90).
    dependent_launch: Option<AtomicBool>,
}

/// The kernel's argument struct as its single by-value parameter.
#[repr(transparent)]
struct Param<A>(A);
// SAFETY: `KernelArgs` are repr(C) plain data, laid out as the PTX parameter expects.
unsafe impl<A: KernelArgs> DeviceRepr for Param<A> {}

/// The kernels queued on the device's stream that the host has not yet seen finish: those a
/// fault reported now can come from. Launches are numbered in queue order; waiting for a
/// fence or the stream tells which numbers are done.
#[derive(Default)]
pub(super) struct InFlight(Mutex<Launches>);

#[derive(Default)]
struct Launches {
    /// Launches queued so far (a graph replay counts as one).
    queued: u64,
    /// Every launch up to this number has finished without fault.
    finished: u64,
    /// Each kernel ever queued, with the number of its latest launch, in that order.
    latest: Vec<(&'static str, u64)>,
}

impl InFlight {
    fn lock(&self) -> std::sync::MutexGuard<'_, Launches> {
        self.0.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Notes one launch, of these kernels (several for a graph), just queued.
    fn queue(&self, kernels: impl IntoIterator<Item = &'static str>) {
        let mut launches = self.lock();
        launches.queued += 1;
        let number = launches.queued;
        for name in kernels {
            launches.latest.retain(|&(queued, _)| queued != name);
            launches.latest.push((name, number));
        }
    }

    /// The number of the latest launch queued: a fence recorded after this call follows it.
    fn ticket(&self) -> u64 {
        self.lock().queued
    }

    /// Notes that every launch up to `ticket` has finished without fault.
    fn finished(&self, ticket: u64) {
        let mut launches = self.lock();
        launches.finished = launches.finished.max(ticket);
    }

    /// The kernels queued but not seen finished, in the order of their latest launch.
    fn suspects(&self) -> Vec<&'static str> {
        let launches = self.lock();
        launches
            .latest
            .iter()
            .filter(|&&(_, number)| number > launches.finished)
            .map(|&(name, _)| name)
            .collect()
    }

    /// Turns a failed driver call into an error: one that means the process lost the GPU to
    /// a kernel fault becomes [`Error::KernelFault`], naming the kernels it can come from and
    /// how to carry on; any other is [`Error::Driver`], saying what the host was `during`.
    pub(super) fn error(&self, during: &str, source: DriverError) -> Error {
        if !is_kernel_fault(source) {
            return Error::Driver {
                during: during.to_string(),
                source,
            };
        }
        let suspects = self.suspects();
        Error::KernelFault {
            kernel: kernel_names(&suspects),
            message: fault_message(source, during, suspects.len()),
        }
    }

    /// [`InFlight::error`] as a closure for `map_err`.
    pub(super) fn failed<'a>(&'a self, during: &'a str) -> impl FnOnce(DriverError) -> Error + 'a {
        move |source| self.error(during, source)
    }
}

/// Whether a driver error says that a kernel faulted, after which every later CUDA call of
/// the process fails with the same error (cuda.h: "This leaves the process in an
/// inconsistent state and any further CUDA work will return the same error").
fn is_kernel_fault(error: DriverError) -> bool {
    use sys::CUresult::*;
    matches!(
        error.0,
        CUDA_ERROR_ILLEGAL_ADDRESS
            | CUDA_ERROR_LAUNCH_TIMEOUT
            | CUDA_ERROR_ASSERT
            | CUDA_ERROR_HARDWARE_STACK_ERROR
            | CUDA_ERROR_ILLEGAL_INSTRUCTION
            | CUDA_ERROR_MISALIGNED_ADDRESS
            | CUDA_ERROR_INVALID_ADDRESS_SPACE
            | CUDA_ERROR_INVALID_PC
            | CUDA_ERROR_LAUNCH_FAILED
            | CUDA_ERROR_TENSOR_MEMORY_LEAK
    )
}

/// The kernels a fault can come from, as [`Error::KernelFault`] names them: `a`, `a or b`,
/// `a, b or c`; `unknown` when none of this device's kernels is in flight.
fn kernel_names(suspects: &[&'static str]) -> Cow<'static, str> {
    match suspects {
        [] => Cow::Borrowed("unknown"),
        [one] => Cow::Borrowed(one),
        [first @ .., last] => Cow::Owned(format!("{} or {last}", first.join(", "))),
    }
}

/// What a kernel fault means for the user, and how to carry on.
fn fault_message(error: DriverError, during: &str, suspects: usize) -> String {
    let code = format!("{:?}", error.0);
    let text = error
        .error_string()
        .map_or_else(|_| "no description".into(), |s| s.to_string_lossy());
    // Checked on an H200 (driver 580): a trap is reported as a launch failure.
    let trap = if error.0 == sys::CUresult::CUDA_ERROR_LAUNCH_FAILED {
        ": how the GPU reports a trap, which a kernel that goes out of bounds makes"
    } else {
        ""
    };
    let what = match suspects {
        0 => format!(
            "the GPU reported {code} ({text}) while {during}, but no kernel of this device was \
             running: a kernel fault earlier in this process caused it"
        ),
        1 => format!("the GPU stopped it with {code} ({text}{trap}), reported while {during}"),
        _ => format!(
            "the GPU stopped one of these kernels, queued since the host last saw the device \
             finish its work, with {code} ({text}{trap}), reported while {during}; it does not \
             say which"
        ),
    };
    format!(
        "{what}. The GPU is lost to this process: the driver fails every later CUDA call in \
         it the same way, on this device or on one opened afresh. To carry on, use the CPU \
         emulation (`Device::select` with `auto` falls back to it; `--backend cpu` on the \
         command line), where the same fault names the index out of bounds, or run the \
         program again to use the GPU."
    )
}

fn unavailable(what: &str) -> impl FnOnce(DriverError) -> Error + '_ {
    move |e| Error::CudaUnavailable(format!("{what}: {e}"))
}

impl Gpu {
    pub(super) fn open() -> Result<Self, Error> {
        // SAFETY: only tries to load the driver's library.
        if !unsafe { sys::is_culib_present() } {
            return Err(Error::CudaUnavailable(format!(
                "the NVIDIA driver library ({}) was not found",
                super::CUDA_LIBRARY
            )));
        }
        let count = CudaContext::device_count().map_err(unavailable("CUDA initialisation"))?;
        if count < 1 {
            return Err(Error::CudaUnavailable(
                "the NVIDIA driver reports no CUDA device".into(),
            ));
        }
        // From here on a GPU is present: a failure is an error to report, not an absence.
        let in_flight = Arc::new(InFlight::default());
        let ctx = CudaContext::new(0).map_err(in_flight.failed("opening CUDA device 0"))?;
        // One stream orders every copy and free; the per-buffer events cudarc keeps for
        // multi-stream use would only cost time.
        // SAFETY: cudarc's buffers are only copied and freed on the device's stream; the
        // kernels a plan runs beside the others (on `sides`) view buffers through their
        // arguments, not through cudarc, and the plan joins them back into the device's
        // stream before anything queued after it.
        unsafe { ctx.disable_event_tracking() };
        // Our own stream rather than the legacy default one, which synchronises with every
        // other stream of the context and cannot be captured into a graph.
        let stream = ctx
            .new_stream()
            .map_err(in_flight.failed("creating a stream"))?;
        // A context that an earlier fault lost (another device of this process holds it)
        // would fail only at the first wait: find out now.
        stream
            .synchronize()
            .map_err(in_flight.failed("checking the device's context"))?;
        let (major, _) = ctx
            .compute_capability()
            .map_err(in_flight.failed("querying device 0"))?;
        // Hopper and newer get the module whose kernels wait for their predecessor.
        let dependent = major >= 9;
        let (source, arch) = if dependent {
            (ptx::DEPENDENT_PTX, ptx::DEPENDENT_ARCH)
        } else {
            (ptx::PTX, ptx::ARCH)
        };
        let functions = load(&ctx, source, registry::ALL)
            .map_err(in_flight.failed("loading the kernels' PTX"))?;
        let properties = properties(&ctx, arch).map_err(in_flight.failed("querying device 0"))?;
        let sides = (0..BRANCHES)
            .map(|_| {
                ctx.new_stream()
                    .map_err(in_flight.failed("creating a stream"))
            })
            .collect::<Result<_, _>>()
            .map(Sides)?;
        Ok(Gpu {
            ctx,
            stream,
            in_flight,
            capture: Mutex::new(None),
            order: Order::new(sides),
            beside: Mutex::new(None),
            functions,
            cooperative: Mutex::new(None),
            properties,
            dependent_launch: dependent.then(|| AtomicBool::new(true)),
        })
    }

    /// Whether launches made from now on start before the launch they follow ends
    /// (programmatic dependent launch); always `false` before sm_90.
    pub(super) fn dependent_launch(&self) -> bool {
        self.dependent_launch
            .as_ref()
            .is_some_and(|on| on.load(Ordering::Relaxed))
    }

    /// Turns programmatic dependent launch on or off for the launches (and captures) made
    /// from now on; returns whether it is on (never before sm_90).
    pub(super) fn set_dependent_launch(&self, on: bool) -> bool {
        if let Some(flag) = &self.dependent_launch {
            flag.store(on, Ordering::Relaxed);
        }
        self.dependent_launch()
    }

    pub(super) fn properties(&self) -> &GpuProperties {
        &self.properties
    }

    /// The context and the stream every launch and copy goes to, for raw driver calls that
    /// must be ordered with them, the order such a call holds (see [`Gpu::in_order`]), and
    /// the record of kernels in flight that their errors are classified by.
    pub(super) fn raw_access(&self) -> (Arc<CudaContext>, Arc<CudaStream>, Order, Arc<InFlight>) {
        (
            self.ctx.clone(),
            self.stream.clone(),
            self.order.clone(),
            self.in_flight.clone(),
        )
    }

    /// [`InFlight::failed`] for this device.
    fn failed<'a>(&'a self, during: &'a str) -> impl FnOnce(DriverError) -> Error + 'a {
        self.in_flight.failed(during)
    }

    // Buffers are untyped bytes here, so that any plain-data element type (including the
    // kernels' own structs) can live in device memory without cudarc's marker traits.

    pub(super) fn alloc_zeroed(&self, bytes: usize) -> Result<CudaSlice<u8>, Error> {
        let _order = self.in_order();
        self.stream
            .alloc_zeros(bytes)
            .map_err(self.failed("allocating device memory"))
    }

    pub(super) fn upload<T: Element>(&self, data: &[T]) -> Result<CudaSlice<u8>, Error> {
        let _order = self.in_order();
        self.stream
            .clone_htod(bytemuck::cast_slice::<T, u8>(data))
            .map_err(self.failed("copying to the device"))
    }

    pub(super) fn write<T: Element>(
        &self,
        dst: &mut CudaSlice<u8>,
        data: &[T],
    ) -> Result<(), Error> {
        let bytes = bytemuck::cast_slice::<T, u8>(data);
        let mut prefix = dst.slice_mut(..bytes.len());
        let _order = self.in_order();
        self.stream
            .memcpy_htod(bytes, &mut prefix)
            .map_err(self.failed("copying to the device"))
    }

    pub(super) fn download<T: Element>(&self, src: &CudaSlice<u8>) -> Result<Vec<T>, Error> {
        let mut out = vec![T::zeroed(); src.len() / size_of::<T>()];
        let _order = self.in_order();
        let ticket = self.in_flight.ticket();
        // A copy into pageable memory returns when it is done, so the launches queued before
        // it are done too.
        self.stream
            .memcpy_dtoh(src, bytemuck::cast_slice_mut::<T, u8>(&mut out))
            .map_err(self.failed("copying from the device"))?;
        self.in_flight.finished(ticket);
        Ok(out)
    }

    pub(super) fn zero(&self, dst: &mut CudaSlice<u8>) -> Result<(), Error> {
        let _order = self.in_order();
        self.stream
            .memset_zeros(dst)
            .map_err(self.failed("clearing device memory"))
    }

    pub(super) fn copy(&self, src: &CudaSlice<u8>, dst: &mut CudaSlice<u8>) -> Result<(), Error> {
        let mut prefix = dst.slice_mut(..src.len());
        let _order = self.in_order();
        self.stream
            .memcpy_dtod(src, &mut prefix)
            .map_err(self.failed("copying on the device"))
    }

    /// Queues `launch` on the device's stream (or the capture this thread records).
    ///
    /// # Safety
    /// See [`super::Op::launch`].
    pub(super) unsafe fn launch<A: KernelArgs>(&self, launch: &Launch<A>) -> Result<(), Error> {
        let Launch {
            kernel,
            grid,
            block,
            args,
        } = *launch;
        let function = self.function(kernel.name)?;
        let config = LaunchConfig {
            grid_dim: (grid, 1, 1),
            block_dim: (block, 1, 1),
            shared_mem_bytes: 0,
        };
        let param = Param(args);
        let (stream, aside) = self.issue_stream();
        // A launch beside the others follows an event, not a kernel: nothing to start early.
        let launched = if self.dependent_launch() && !aside {
            // SAFETY: as below; the sm_90 module's entries wait for their predecessor.
            unsafe { launch_with(function, &stream, config, &param, dependent()) }
        } else {
            let mut launch = stream.launch_builder(function);
            launch.arg(&param);
            // SAFETY: the parameter is the kernel's argument struct; the caller vouches for
            // the buffers it views.
            unsafe { launch.launch(config) }.map(drop)
        };
        launched.map_err(|e| {
            let during = format!("launching kernel `{}`", kernel.name);
            self.in_flight.error(&during, e)
        })?;
        // A launch into a capture runs only when the graph is replayed.
        if !self.capturing_here() {
            self.in_flight.queue([kernel.name]);
        }
        Ok(())
    }

    /// The most blocks of `block` threads of `kernel` the device holds at once: the largest
    /// grid a cooperative launch of it may have.
    pub(super) fn resident_blocks<A>(
        &self,
        kernel: &Cooperative<A>,
        block: u32,
    ) -> Result<u32, Error> {
        let function = self.cooperative_function(kernel.name)?;
        let per_multiprocessor = function
            .occupancy_max_active_blocks_per_multiprocessor(block, 0, None)
            .map_err(self.failed("asking how many blocks a multiprocessor holds"))?;
        Ok(per_multiprocessor * self.properties.multiprocessors)
    }

    /// Queues a cooperative launch of `grid` blocks (every block resident at once) on the
    /// device's stream (or the capture this thread records).
    ///
    /// # Safety
    /// See [`super::Op::launch`].
    pub(super) unsafe fn launch_cooperative<A: KernelArgs>(
        &self,
        kernel: &Cooperative<A>,
        grid: u32,
        block: u32,
        args: A,
    ) -> Result<(), Error> {
        let function = self.cooperative_function(kernel.name)?;
        let config = LaunchConfig {
            grid_dim: (grid, 1, 1),
            block_dim: (block, 1, 1),
            shared_mem_bytes: 0,
        };
        let (stream, _) = self.issue_stream();
        // SAFETY: forwarded from the caller.
        unsafe { launch_with(&function, &stream, config, &Param(args), cooperative()) }.map_err(
            |e| {
                let during = format!(
                    "launching kernel `{}` (cooperative, {grid} blocks)",
                    kernel.name
                );
                self.in_flight.error(&during, e)
            },
        )?;
        if !self.capturing_here() {
            self.in_flight.queue([kernel.name]);
        }
        Ok(())
    }

    /// The cooperative kernel `name`, its module loaded first if no cooperative kernel has
    /// been asked for yet.
    fn cooperative_function(&self, name: &str) -> Result<CudaFunction, Error> {
        let mut loaded = self.cooperative.lock().unwrap_or_else(|e| e.into_inner());
        if loaded.is_none() {
            let functions = load(&self.ctx, ptx::PROGRAM_PTX, registry::COOPERATIVE)
                .map_err(self.failed("loading the persistent step's PTX"))?;
            *loaded = Some(functions);
        }
        loaded
            .as_ref()
            .and_then(|functions| functions.get(name).cloned())
            .ok_or_else(|| Error::Invalid(format!("kernel `{name}` is not a cooperative kernel")))
    }

    /// The module's function `name`.
    fn function(&self, name: &str) -> Result<&CudaFunction, Error> {
        self.functions
            .get(name)
            .ok_or_else(|| Error::Invalid(format!("kernel `{name}` is not in the PTX module")))
    }

    /// Whether the calling thread is recording a capture.
    fn capturing_here(&self) -> bool {
        let capture = self.capture.lock().unwrap_or_else(|e| e.into_inner());
        capture
            .as_ref()
            .is_some_and(|(thread, _)| *thread == std::thread::current().id())
    }

    /// The device's order (see [`Gpu::order`]), for as long as the guard lives: the side
    /// streams come with it.
    pub(super) fn in_order(&self) -> MutexGuard<'_, Sides> {
        self.order.hold()
    }

    /// Issues what `issue` launches beside the work that follows it, as branch `branch` of
    /// the holder of `sides` (the device's order): on a stream of its own that first waits
    /// for the work queued so far (on the device's stream, or in the capture this thread
    /// records), until [`Gpu::rejoin`]. Branches past the [`BRANCHES`] streams share them,
    /// each after the one before on its stream.
    pub(super) fn beside(
        &self,
        sides: &Sides,
        branch: usize,
        issue: impl FnOnce() -> Result<(), Error>,
    ) -> Result<(), Error> {
        let side = &sides.0[branch % BRANCHES];
        side.join(&self.launch_stream())
            .map_err(self.failed("forking a stream"))?;
        let here = std::thread::current().id();
        *self.beside.lock().unwrap_or_else(|e| e.into_inner()) = Some((here, side.clone()));
        let issued = issue();
        *self.beside.lock().unwrap_or_else(|e| e.into_inner()) = None;
        issued
    }

    /// Makes the work queued from now on wait for everything issued [`Gpu::beside`] in
    /// the branches `branches` of the holder of `sides`.
    pub(super) fn rejoin(
        &self,
        sides: &Sides,
        branches: impl IntoIterator<Item = usize>,
    ) -> Result<(), Error> {
        let main = self.launch_stream();
        let mut joined = [false; BRANCHES];
        for branch in branches {
            let stream = branch % BRANCHES;
            if !std::mem::replace(&mut joined[stream], true) {
                main.join(&sides.0[stream])
                    .map_err(self.failed("joining a stream"))?;
            }
        }
        Ok(())
    }

    /// The stream this thread's launches and clears go to, and whether it is a branch's:
    /// the stream of the branch this thread issues, if it issues one, else
    /// [`Gpu::launch_stream`].
    fn issue_stream(&self) -> (Arc<CudaStream>, bool) {
        let here = std::thread::current().id();
        match &*self.beside.lock().unwrap_or_else(|e| e.into_inner()) {
            Some((thread, side)) if *thread == here => (side.clone(), true),
            _ => (self.launch_stream(), false),
        }
    }

    /// Queues a clear of `bytes` bytes at device address `addr`.
    ///
    /// # Safety
    /// The bytes belong to a live allocation that nothing else uses meanwhile.
    pub(super) unsafe fn clear(&self, addr: u64, bytes: usize) -> Result<(), Error> {
        self.bind()?;
        let (stream, _) = self.issue_stream();
        // SAFETY: forwarded from the caller.
        unsafe { result::memset_d8_async(addr, 0, bytes, stream.cu_stream()) }
            .map_err(self.failed("clearing device memory"))
    }

    /// The stream a branch forks from and joins: the device's stream, or the private stream
    /// of a capture this thread is recording.
    fn launch_stream(&self) -> Arc<CudaStream> {
        let capture = self.capture.lock().unwrap_or_else(|e| e.into_inner());
        match &*capture {
            Some((thread, stream)) if *thread == std::thread::current().id() => stream.clone(),
            _ => self.stream.clone(),
        }
    }

    /// Records what `issue` launches as a graph instead of running it. The recording uses a
    /// private stream, so that work other threads queue meanwhile (a buffer freed, another
    /// launch) neither lands in the graph nor breaks the capture; one capture at a time.
    pub(super) fn capture(
        &self,
        issue: impl FnOnce() -> Result<(), Error>,
    ) -> Result<CudaGraph, Error> {
        let mut capture = self.capture.lock().unwrap_or_else(|e| e.into_inner());
        while capture.is_some() {
            drop(capture);
            std::thread::yield_now();
            capture = self.capture.lock().unwrap_or_else(|e| e.into_inner());
        }
        let stream = self
            .ctx
            .new_stream()
            .map_err(self.failed("creating a stream"))?;
        stream
            .begin_capture(sys::CUstreamCaptureMode::CU_STREAM_CAPTURE_MODE_THREAD_LOCAL)
            .map_err(self.failed("starting a graph capture"))?;
        *capture = Some((std::thread::current().id(), stream.clone()));
        drop(capture);
        let issued = issue();
        // End the capture whatever happened, so that the stream is usable again.
        let graph = stream
            .end_capture(sys::CUgraphInstantiate_flags(0))
            .map_err(self.failed("capturing a graph"));
        *self.capture.lock().unwrap_or_else(|e| e.into_inner()) = None;
        issued?;
        let graph = graph?.ok_or_else(|| Error::Invalid("an empty graph was captured".into()))?;
        self.bind()?;
        // SAFETY: the executable graph is alive (owned by `graph`); the stream is ours.
        unsafe { result::graph::upload(graph.cu_graph_exec(), self.stream.cu_stream()) }
            .map_err(self.failed("uploading a graph"))?;
        Ok(graph)
    }

    /// Queues one replay of `graph`, whose launches are of `kernels`, on the device's stream
    /// (not the one it was recorded on).
    pub(super) fn replay(
        &self,
        graph: &CudaGraph,
        kernels: impl IntoIterator<Item = &'static str>,
    ) -> Result<(), Error> {
        self.bind()?;
        // SAFETY: as in `capture`.
        unsafe { result::graph::launch(graph.cu_graph_exec(), self.stream.cu_stream()) }
            .map_err(self.failed("launching a graph"))?;
        self.in_flight.queue(kernels);
        Ok(())
    }

    /// A new fence, with timing when `timed`, recorded after nothing yet.
    pub(super) fn fence(&self, timed: bool) -> Result<Fence, Error> {
        let flags = if timed {
            sys::CUevent_flags::CU_EVENT_DEFAULT
        } else {
            sys::CUevent_flags::CU_EVENT_DISABLE_TIMING
        };
        let event = self
            .ctx
            .new_event(Some(flags))
            .map_err(self.failed("creating an event"))?;
        Ok(Fence {
            event,
            after: 0,
            in_flight: self.in_flight.clone(),
        })
    }

    /// Records `fence` after the work queued so far.
    pub(super) fn record(&self, fence: &mut Fence) -> Result<(), Error> {
        let _order = self.in_order();
        let ticket = self.in_flight.ticket();
        fence
            .event
            .record(&self.stream)
            .map_err(self.failed("recording an event"))?;
        fence.after = ticket;
        Ok(())
    }

    /// Page-locked host memory of `bytes` bytes, zeroed, mapped into the GPU's address space:
    /// kernels read and write it directly, with no copy queued.
    pub(super) fn mapped(&self, bytes: usize) -> Result<Mapped, Error> {
        self.bind()?;
        let flags = cudarc::driver::sys::CU_MEMHOSTALLOC_DEVICEMAP;
        // SAFETY: a plain allocation; freed in `Mapped::drop`.
        let ptr = unsafe { result::malloc_host(bytes.max(1), flags) }
            .map_err(self.failed("allocating mapped host memory"))?;
        // SAFETY: `bytes` bytes were just allocated.
        unsafe { std::ptr::write_bytes(ptr.cast::<u8>(), 0, bytes) };
        let mut mapped = Mapped {
            ptr: ptr.cast(),
            addr: 0,
            ctx: self.ctx.clone(),
            stream: self.stream.clone(),
        };
        // SAFETY: `ptr` was allocated with the device-map flag, in this context (bound above).
        unsafe { cudarc::driver::sys::cuMemHostGetDevicePointer_v2(&mut mapped.addr, ptr, 0) }
            .result()
            .map_err(self.failed("mapping host memory"))?;
        Ok(mapped)
    }

    /// Makes the context current on the calling thread, as raw driver calls need.
    fn bind(&self) -> Result<(), Error> {
        self.ctx
            .bind_to_thread()
            .map_err(self.failed("binding the context"))
    }

    /// Free and total device memory in bytes.
    pub(super) fn memory(&self) -> Result<(u64, u64), Error> {
        self.bind()?;
        let (free, total) =
            result::mem_get_info().map_err(self.failed("querying device memory"))?;
        Ok((free as u64, total as u64))
    }

    /// Waits for every stream of the device (the holder of `sides` has joined its
    /// branches back, so the device's stream follows them; a branch left by an error may
    /// not be joined): the launches queued so far are done.
    pub(super) fn synchronize(&self, sides: &Sides) -> Result<(), Error> {
        let ticket = self.in_flight.ticket();
        for stream in std::iter::once(&self.stream).chain(&sides.0) {
            stream
                .synchronize()
                .map_err(self.failed("waiting for the GPU"))?;
        }
        self.in_flight.finished(ticket);
        Ok(())
    }
}

/// An event on the device's stream that knows which launches it follows: waiting for it
/// tells the record of kernels in flight that they are done, and the fault it may report
/// names them.
pub(super) struct Fence {
    event: CudaEvent,
    /// The latest launch queued before the event was recorded.
    after: u64,
    in_flight: Arc<InFlight>,
}

impl Fence {
    /// Waits until the GPU has passed the fence.
    pub(super) fn wait(&self) -> Result<(), Error> {
        self.event
            .synchronize()
            .map_err(self.in_flight.failed("waiting for the GPU"))?;
        self.in_flight.finished(self.after);
        Ok(())
    }

    /// Seconds from `earlier` to this fence, both timed (waits for the GPU to pass both).
    pub(super) fn seconds_since(&self, earlier: &Fence) -> Result<f64, Error> {
        let ms = earlier
            .event
            .elapsed_ms(&self.event)
            .map_err(self.in_flight.failed("timing events"))?;
        self.in_flight.finished(self.after.max(earlier.after));
        Ok(f64::from(ms) / 1e3)
    }
}

/// Page-locked host memory that kernels reach at a device address of their own, freed on
/// drop.
pub(super) struct Mapped {
    /// Where the host finds it.
    pub(super) ptr: *mut u8,
    /// Where kernels find it.
    pub(super) addr: u64,
    ctx: Arc<CudaContext>,
    /// The device's stream, which every launch that may reach it is on or joins.
    stream: Arc<CudaStream>,
}

// SAFETY: plain memory owned by this handle.
unsafe impl Send for Mapped {}
// SAFETY: as above; the host reaches it only while holding the device's order (`Gpu::order`):
// `Device::write`, `download` and `zero` after a wait for every stream, a ring's `send` and
// `oldest` on a slot whose fence has passed (see `Ring`).
unsafe impl Sync for Mapped {}

impl Drop for Mapped {
    fn drop(&mut self) {
        // Kernels still queued may reach it (the last op holding it can go while they run):
        // wait for the device's stream before the memory goes. Not the whole context,
        // whose wait would break a graph another thread is capturing meanwhile.
        let _ = self.stream.synchronize();
        let _ = self.ctx.bind_to_thread();
        // SAFETY: allocated by `malloc_host`; nothing reaches it any more (waited above).
        let _ = unsafe { result::free_host(self.ptr.cast()) };
    }
}

/// The device address of a buffer.
pub(super) fn address<T>(slice: &CudaSlice<T>) -> u64 {
    // Event tracking is off, so the returned guard records nothing.
    let (addr, _guard) = slice.device_ptr(slice.stream());
    addr
}
