//! Launch plans: a step's kernel launches and clears, made once with their arguments and
//! issued again every step: in order on the CPU emulation, from inside its pool, and on the
//! GPU either one by one on the stream or replayed as a CUDA graph.

use std::sync::Arc;
use std::time::Instant;

use cudarc::driver::CudaGraph;
use gpuwars_kernels::{DevSlice, Kernel, KernelArgs};

use super::cuda::Fence;
use super::{Device, Element, Error, Imp};

/// What an [`Op`] does.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum OpKind {
    Launch,
    Clear,
}

/// How an op is issued: on the device it runs on.
type Issue = Arc<dyn Fn(&Device) -> Result<(), Error> + Send + Sync>;

/// One operation of a plan: a kernel launch or a clear of a buffer, its arguments fixed
/// when it was made.
#[derive(Clone)]
pub struct Op {
    name: &'static str,
    kind: OpKind,
    /// Blocks launched (a launch of none does nothing).
    grid: u32,
    bytes: u64,
    issue: Issue,
}

impl Op {
    /// A launch of `kernel` on `grid` blocks of `block` threads with `args`, which moves
    /// about `bytes` bytes of device memory (the caller's count, for the profile).
    ///
    /// # Safety
    /// Every [`DevSlice`] in `args` must view a buffer of the device that will run the op,
    /// allocated for as long as the op or a [`Plan`] made of it exists, and touched by
    /// nothing else while it runs; the sizes in `args` must be those the kernel's
    /// documentation asks for.
    pub unsafe fn launch<A: KernelArgs>(
        kernel: Kernel<A>,
        grid: u32,
        block: u32,
        args: A,
        bytes: u64,
    ) -> Op {
        Op {
            name: kernel.name,
            kind: OpKind::Launch,
            grid,
            bytes,
            // SAFETY: the caller's promise covers every run of the op.
            issue: Arc::new(move |device| unsafe { device.issue(kernel, grid, block, &args) }),
        }
    }

    /// Zeroes every element of `view`.
    ///
    /// # Safety
    /// As for [`Op::launch`], for `view`.
    pub unsafe fn clear<T: Element>(view: DevSlice<T>) -> Op {
        Op {
            name: "clear",
            kind: OpKind::Clear,
            grid: 0,
            bytes: u64::from(view.len()) * size_of::<T>() as u64,
            // SAFETY: the caller's promise covers every run of the op.
            issue: Arc::new(move |device| unsafe { device.clear(view) }),
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
    ops: Vec<Op>,
    /// The ops recorded as a CUDA graph (GPU only). It holds the same device addresses as
    /// the ops, so the plan's owner must drop it before the buffers they view.
    graph: Option<CudaGraph>,
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
                Some(gpu.capture(|| ops.iter().try_for_each(|op| (op.issue)(self)))?)
            }
            _ => None,
        };
        Ok(Plan { ops, graph })
    }

    /// Queues one run of `plan`.
    pub fn run(&self, plan: &Plan) -> Result<(), Error> {
        self.count(plan.launched());
        match (&self.imp, &plan.graph) {
            (Imp::Cuda(gpu), Some(graph)) => gpu.replay(graph, plan.launched()),
            (Imp::Cuda(_), None) => plan.ops.iter().try_for_each(|op| (op.issue)(self)),
            // From inside the pool, each launch starts its blocks at once.
            (Imp::Cpu(emu), _) => {
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
