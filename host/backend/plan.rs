//! Launch plans: a step's kernel launches and clears, made once with their arguments and
//! issued again every step: in order on the CPU emulation, from inside its pool, and on the
//! GPU either one by one on the stream or replayed as a CUDA graph.
//!
//! An op owns a share ([`Hold`]) of every buffer its arguments view, taken by the [`Binder`]
//! that made the views, so a plan keeps its buffers allocated for as long as it exists,
//! whatever happened to the handles it was made from. What keeps the memory a launch uses
//! from being freed *while it runs* is the device's order: every launch, copy, clear and
//! free of a device happens in one order, on the GPU that of its one stream (cudarc frees a
//! buffer on the stream it was allocated on, after the work queued before), on the CPU under
//! the emulator's order lock, each operation done before the next begins.

use std::sync::Arc;
use std::time::Instant;

use cudarc::driver::CudaGraph;
use gpuwars_kernels::data::{Convert, View};
use gpuwars_kernels::{DevSlice, KernelArgs};

use super::cuda::Fence;
use super::{Buffer, Buffers, Device, Element, Error, Hold, Imp, Launch};

/// Makes the views of buffers that go into one op's arguments, and takes a [`Hold`] of
/// each, which the op keeps: views and holds go together.
///
/// Making one is the unsafe step, since safe code could read through its views; this does
/// not compile:
/// ```compile_fail,E0133
/// let dev = gpuwars::Device::cpu(Some(1), "probe").unwrap();
/// let buffer = dev.upload(&[7u32; 1024]).unwrap();
/// let view = gpuwars::backend::Binder::new().view(&buffer);
/// println!("{}", view.get(0));
/// ```
pub struct Binder {
    holds: Vec<Hold>,
}

impl Binder {
    /// A binder with no view made yet.
    ///
    /// # Safety
    /// Every view it makes goes into the arguments of ops made with it ([`Op::launch`],
    /// [`Op::clear`]) and nowhere else: read on the host, a view would reach memory the
    /// host must not touch (device memory on the GPU, memory a kernel may be writing on the
    /// CPU), and outside its op nothing holds its buffer.
    pub unsafe fn new() -> Binder {
        Binder { holds: Vec::new() }
    }

    /// The whole of `buffer`.
    pub fn view<T: Element>(&mut self, buffer: &Buffer<T>) -> DevSlice<T> {
        self.view_prefix(buffer, u32::MAX)
    }

    /// The first `len` elements of `buffer` (clamped to its length).
    pub fn view_prefix<T: Element>(&mut self, buffer: &Buffer<T>, len: u32) -> DevSlice<T> {
        self.holds.push(buffer.hold());
        // SAFETY: the view goes only into this binder's ops (`new`'s contract), which hold
        // the buffer (pushed above).
        unsafe { buffer.view_prefix(len) }
    }
}

impl Convert<Buffers, View> for Binder {
    type Error = std::convert::Infallible;
    fn array<T: Element>(
        &mut self,
        _: &'static str,
        array: &Buffer<T>,
    ) -> Result<DevSlice<T>, Self::Error> {
        Ok(self.view(array))
    }
}

/// What an [`Op`] does.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum OpKind {
    Launch,
    Clear,
}

/// How an op is issued: on the device it runs on, in the device's order.
type Issue = Arc<dyn Fn(&Device) -> Result<(), Error> + Send + Sync>;

/// One operation of a plan: a kernel launch or a clear of a buffer, its arguments fixed
/// when it was made, holding the buffers they view.
#[derive(Clone)]
pub struct Op {
    name: &'static str,
    kind: OpKind,
    /// Blocks launched (a launch of none does nothing).
    grid: u32,
    bytes: u64,
    issue: Issue,
    /// Whether it runs beside the plan's ops after it (see [`Op::beside`]).
    beside: bool,
    /// Whether it waits for the ops before it that run beside (see [`Op::after_branches`]).
    joins: bool,
    /// The buffers the arguments view.
    _holds: Arc<[Hold]>,
}

impl Op {
    /// `launch`, which moves about `bytes` bytes of device memory (the caller's count, for
    /// the profile); its views come from `binder`, whose holds the op keeps.
    ///
    /// # Safety
    /// Every [`DevSlice`] in the arguments was made by `binder` from a buffer of the device
    /// that will run the op, or views memory of that device that no buffer owns (an OpenGL
    /// buffer mapped for CUDA) and that stays valid, and untouched by the host, for every
    /// run of the op; their sizes, and which of them may be the same buffer, are
    /// those the kernel's documentation asks for (its promise that no two threads write
    /// one element holds only then; its bounds checks turn a wrong size into
    /// [`Error::KernelFault`]).
    pub unsafe fn launch<A: KernelArgs>(launch: Launch<A>, binder: Binder, bytes: u64) -> Op {
        Op {
            name: launch.kernel.name,
            kind: OpKind::Launch,
            grid: launch.grid,
            bytes,
            beside: false,
            joins: false,
            _holds: binder.holds.into(),
            // SAFETY: the caller's promise covers every run of the op, and the op holds the
            // buffers its views are of.
            issue: Arc::new(move |device| unsafe { device.issue(&launch) }),
        }
    }

    /// Zeroes every element of `view`.
    ///
    /// # Safety
    /// `view` was made by `binder` from a buffer of the device that will run the op.
    pub unsafe fn clear<T: Element>(view: DevSlice<T>, binder: Binder) -> Op {
        Op {
            name: "clear",
            kind: OpKind::Clear,
            grid: 0,
            bytes: u64::from(view.len()) * size_of::<T>() as u64,
            beside: false,
            joins: false,
            _holds: binder.holds.into(),
            // SAFETY: as in `launch`.
            issue: Arc::new(move |device| unsafe { device.clear(view) }),
        }
    }

    /// The same op, run beside the ops after it in its plan: on the GPU on a stream of its
    /// own (another op beside the others gets another), which the plan joins back at its
    /// end (a graph branch), so that it costs the step nothing while they run longer; in
    /// order on the CPU.
    ///
    /// # Safety
    /// It reads nothing that the ops after it in its plan write, and writes nothing that
    /// they read or write, up to the first after it made [`Op::after_branches`]: on the
    /// GPU they run at the same time.
    pub unsafe fn beside(self) -> Op {
        Op {
            beside: true,
            ..self
        }
    }

    /// The same op, run once the ops before it in its plan that run beside the others
    /// ([`Op::beside`]) are done: on the GPU the branches join the device's stream before
    /// it (and again at the plan's end); on the CPU, where they ran in order, it changes
    /// nothing. So an op beside the others need only stay off what the ops up to here write.
    pub fn after_branches(self) -> Op {
        Op {
            joins: true,
            ..self
        }
    }

    /// The kernel's entry-point name, or "clear".
    pub fn name(&self) -> &'static str {
        self.name
    }

    /// Whether the op launches a kernel (not a clear, nor a launch of no blocks).
    pub fn is_launch(&self) -> bool {
        self.kind == OpKind::Launch && self.grid > 0
    }

    /// Bytes of device memory the op moves, by its maker's count.
    pub fn bytes(&self) -> u64 {
        self.bytes
    }
}

/// Ops issued in order; on the GPU, optionally captured once as a CUDA graph and replayed.
pub struct Plan {
    /// The ops recorded as a CUDA graph (GPU only), with the device addresses of the
    /// buffers the ops hold: declared first, so that it goes before they may.
    graph: Option<CudaGraph>,
    ops: Vec<Op>,
}

impl Plan {
    /// The ops, in order.
    pub fn ops(&self) -> &[Op] {
        &self.ops
    }

    /// Whether the plan replays as a CUDA graph.
    pub fn is_graph(&self) -> bool {
        self.graph.is_some()
    }

    /// Kernel launches per run.
    pub fn launches(&self) -> usize {
        self.launched().count()
    }

    /// The kernel of each launch of a run, in order.
    fn launched(&self) -> impl Iterator<Item = &'static str> + '_ {
        self.ops.iter().filter(|op| op.is_launch()).map(Op::name)
    }

    /// Bytes moved per run, by the ops' counts.
    pub fn bytes(&self) -> u64 {
        self.ops.iter().map(Op::bytes).sum()
    }
}

/// A point in the device's queue, for timing: a timed event on the GPU, a clock reading on
/// the CPU (where launches return when they are done).
pub struct Mark {
    imp: MarkImp,
}

enum MarkImp {
    Clock(Instant),
    Event(Fence),
}

impl Mark {
    /// Seconds from `earlier` to this mark (waits for the GPU to reach it).
    pub fn seconds_since(&self, earlier: &Mark) -> Result<f64, Error> {
        match (&earlier.imp, &self.imp) {
            (MarkImp::Clock(a), MarkImp::Clock(b)) => Ok(b.duration_since(*a).as_secs_f64()),
            (MarkImp::Event(a), MarkImp::Event(b)) => b.seconds_since(a),
            _ => Err(Error::Invalid("marks of two different backends".into())),
        }
    }
}

impl Device {
    /// A plan of `ops`. With `graph` on the GPU, they are captured once as a CUDA graph that
    /// every run replays; otherwise each run issues them one by one (the CPU emulation
    /// always does).
    pub fn plan(&self, ops: Vec<Op>, graph: bool) -> Result<Plan, Error> {
        let graph = match &self.imp {
            Imp::Cuda(gpu) if graph && !ops.is_empty() => {
                Some(gpu.capture(|| self.issue_all(&ops))?)
            }
            _ => None,
        };
        Ok(Plan { graph, ops })
    }

    /// Issues `ops` in order, each marked [`Op::beside`] on a side stream of its own (a
    /// branch), joined back before each op marked [`Op::after_branches`] and after the last.
    fn issue_all(&self, ops: &[Op]) -> Result<(), Error> {
        let mut branches = 0;
        for op in ops {
            if let Imp::Cuda(gpu) = &self.imp
                && op.joins
                && branches > 0
            {
                gpu.rejoin(branches)?;
            }
            match &self.imp {
                Imp::Cuda(gpu) if op.beside => {
                    gpu.beside(branches, || (op.issue)(self))?;
                    branches += 1;
                }
                _ => (op.issue)(self)?,
            }
        }
        match &self.imp {
            Imp::Cuda(gpu) if branches > 0 => gpu.rejoin(branches),
            _ => Ok(()),
        }
    }

    /// Queues one run of `plan`.
    pub fn run(&self, plan: &Plan) -> Result<(), Error> {
        self.count(plan.launched());
        match (&self.imp, &plan.graph) {
            (Imp::Cuda(gpu), Some(graph)) => gpu.replay(graph, plan.launched()),
            (Imp::Cuda(_), None) => self.issue_all(&plan.ops),
            // From inside the pool, each launch starts its blocks at once.
            (Imp::Cpu(emu), _) => {
                let _order = emu.in_order();
                let ops = &plan.ops;
                emu.run(|| ops.iter().try_for_each(|op| (op.issue)(self)))
            }
        }
    }

    /// A mark after the work queued so far.
    pub fn mark(&self) -> Result<Mark, Error> {
        let imp = match &self.imp {
            Imp::Cpu(_) => MarkImp::Clock(Instant::now()),
            Imp::Cuda(gpu) => {
                let mut fence = gpu.fence(true)?;
                gpu.record(&mut fence)?;
                MarkImp::Event(fence)
            }
        };
        Ok(Mark { imp })
    }
}
