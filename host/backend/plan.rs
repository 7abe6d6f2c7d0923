//! Launch plans: a step's kernel launches and clears, made once with their arguments and
//! issued again every step: in order on the CPU emulation, from inside its pool, and on the
//! GPU either one by one on the stream or replayed as a CUDA graph.
//!
//! An op owns a share ([`Hold`]) of every buffer its arguments view, taken by the [`Binder`]
//! that made the views, so a plan keeps its buffers allocated for as long as it exists,
//! whatever happened to the handles it was made from. The binder also notes the device of
//! every buffer it views and how the kernel uses it (the access of the view's type): a plan refuses an op of
//! another device, and an op run beside the others ([`Op::beside`]) that touches what the
//! ops it runs beside write, or writes what they touch. Several ops can run beside the
//! others as one branch, in order ([`Op::chain`]). What keeps the memory a launch uses
//! from being freed *while it runs* is the device's order: every launch, copy, clear and
//! free of a device is ordered by its stream on the GPU (an op beside the others goes on a
//! side stream that forks from it and joins it again before the plan ends; cudarc frees a
//! buffer on the stream it was allocated on, after the work queued before), and on the CPU
//! by the emulator's order lock, held for a whole run.

mod program;

use std::fmt;
use std::sync::Arc;
use std::time::Instant;

use cudarc::driver::CudaGraph;
use gpuwars_kernels::access::{Access, Use};
use gpuwars_kernels::data::{Convert, View};
use gpuwars_kernels::{DevSlice, KernelArgs};

use super::cuda::{Fence, Gpu, Sides};
use super::{Buffer, Buffers, Device, DeviceId, Element, Error, Hold, Imp, Launch};

/// Makes the views of buffers that go into one op's arguments, and takes a [`Hold`] of
/// each, which the op keeps: views and holds go together. Each view is of the access its
/// type asks for ([`DevSlice<T, A>`](DevSlice), the argument struct's field it goes into
/// chooses `A`), and the binder notes that access for the plan's checks: what an op
/// declares is what its kernel's types let it do (see `gpuwars_kernels::access`).
///
/// Making one is the unsafe step, since safe code could read through its views; this does
/// not compile:
/// ```compile_fail,E0133
/// let dev = gpuwars::Device::cpu(Some(1), "probe").unwrap();
/// let buffer = dev.upload(&[7u32; 1024]).unwrap();
/// let view: gpuwars_kernels::DevSlice<u32> = gpuwars::backend::Binder::new().view(&buffer);
/// println!("{}", view.get(0));
/// ```
pub struct Binder {
    holds: Vec<Hold>,
    touches: Vec<Touch>,
    /// The devices of the buffers viewed.
    home: Home,
}

/// One buffer an op views, and how its kernel may use it (never [`Use::Unused`]: an unused
/// view is of no buffer).
#[derive(Clone, Debug)]
struct Touch {
    /// The buffer's allocation (see `Buffer::key`).
    key: usize,
    access: Use,
    /// The buffer's name (see `Buffer::named`).
    name: &'static str,
}

impl fmt::Display for Touch {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} `{}`", verb(self.access), self.name)
    }
}

/// What an op does with a buffer it may use as `access`, in a word.
fn verb(access: Use) -> &'static str {
    match access {
        Use::Unused => "leaves alone",
        Use::Read => "reads",
        Use::Write => "writes",
    }
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
        Binder {
            holds: Vec::new(),
            touches: Vec::new(),
            home: Home::default(),
        }
    }

    /// The whole of `buffer`, of access `A`: read and written ([`Write`]), read only
    /// ([`Read`]), or not at all ([`Unused`]: an empty view of no buffer, which the op
    /// neither holds nor declares).
    ///
    /// [`Write`]: gpuwars_kernels::access::Write
    /// [`Read`]: gpuwars_kernels::access::Read
    /// [`Unused`]: gpuwars_kernels::access::Unused
    pub fn view<T: Element, A: Access>(&mut self, buffer: &Buffer<T>) -> DevSlice<T, A> {
        self.view_prefix(buffer, u32::MAX)
    }

    /// The first `len` elements of `buffer` (clamped to its length), as [`Binder::view`].
    pub fn view_prefix<T: Element, A: Access>(
        &mut self,
        buffer: &Buffer<T>,
        len: u32,
    ) -> DevSlice<T, A> {
        self.home.note(buffer.device());
        if A::USE == Use::Unused {
            return DevSlice::EMPTY;
        }
        self.touches.push(Touch {
            key: buffer.key(),
            access: A::USE,
            name: buffer.name(),
        });
        self.holds.push(buffer.hold());
        // SAFETY: the view goes only into this binder's ops (`new`'s contract), which hold
        // the buffer (pushed above).
        unsafe { buffer.view_prefix(len) }
    }
}

impl Convert<Buffers, View> for Binder {
    type Error = std::convert::Infallible;
    fn array<T: Element, In: Access, Out: Access>(
        &mut self,
        _: &'static str,
        array: &Buffer<T>,
    ) -> Result<DevSlice<T, Out>, Self::Error> {
        Ok(self.view(array))
    }
}

/// Where an op's buffers are: checked when a plan is made.
#[derive(Clone, Debug, Default)]
struct Home {
    /// The device of its first view (none if it views nothing).
    device: Option<DeviceId>,
    /// Another device, if a view was of another's buffer.
    foreign: Option<DeviceId>,
}

impl Home {
    /// Notes a view of a buffer of device `id`.
    fn note(&mut self, id: DeviceId) {
        if *self.device.get_or_insert(id) != id {
            self.foreign = Some(id);
        }
    }
}

/// What an [`Op`] does.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum OpKind {
    Launch,
    Clear,
    /// Ops issued in order as one (see [`Op::chain`]).
    Chain,
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
    /// Whether, run beside, it runs beside every op after it, joined at the plan's end
    /// only (see [`Op::beside_to_the_end`]).
    to_the_end: bool,
    /// Whether it waits for the ops before it that run beside (see [`Op::after_branches`]).
    joins: bool,
    /// The buffers the arguments view.
    _holds: Arc<[Hold]>,
    /// How the kernel uses each.
    touches: Arc<[Touch]>,
    home: Home,
    /// The launch as a persistent step's stage takes it (none for a clear or a chain).
    stage: Option<Arc<StageSource>>,
    /// A chain's ops, in order (none for a launch or a clear).
    parts: Arc<[Op]>,
}

/// What a persistent program needs of a launch beside the op's name and grid: its block and
/// the bytes of its argument struct.
struct StageSource {
    block: u32,
    args: Box<[u8]>,
}

/// An op's holds, touches and home, taken from the binder that made its views.
fn bound(binder: Binder) -> (Arc<[Hold]>, Arc<[Touch]>, Home) {
    (binder.holds.into(), binder.touches.into(), binder.home)
}

impl Op {
    /// `launch`, which moves about `bytes` bytes of device memory (the caller's count, for
    /// the profile); its views come from `binder`, whose holds the op keeps.
    ///
    /// # Safety
    /// Every [`DevSlice`] in the arguments was made by `binder` (from a buffer of any
    /// device: a plan of another device refuses the op), or views memory of the device that
    /// will run the op that no buffer owns (an OpenGL buffer mapped for CUDA) and that stays
    /// valid, untouched by the host and by the ops beside it, for every run of the op;
    /// their sizes, and which of them may be the same buffer, are
    /// those the kernel's documentation asks for (its promise that no two threads write
    /// one element holds only then; its bounds checks turn a wrong size into
    /// [`Error::KernelFault`]).
    pub unsafe fn launch<A: KernelArgs>(launch: Launch<A>, binder: Binder, bytes: u64) -> Op {
        let (holds, touches, home) = bound(binder);
        let stage = StageSource {
            block: launch.block,
            args: bytemuck::bytes_of(&launch.args).into(),
        };
        Op {
            name: launch.kernel.name,
            kind: OpKind::Launch,
            grid: launch.grid,
            bytes,
            beside: false,
            to_the_end: false,
            joins: false,
            _holds: holds,
            touches,
            home,
            stage: Some(Arc::new(stage)),
            parts: Arc::new([]),
            // SAFETY: the caller's promise covers every run of the op, and the op holds the
            // buffers its views are of.
            issue: Arc::new(move |device| unsafe { device.issue(&launch) }),
        }
    }

    /// Zeroes every element of `view`.
    ///
    /// # Safety
    /// `view` was made by `binder`.
    pub unsafe fn clear<T: Element>(view: DevSlice<T>, binder: Binder) -> Op {
        let (holds, touches, home) = bound(binder);
        Op {
            name: "clear",
            kind: OpKind::Clear,
            grid: 0,
            bytes: u64::from(view.len()) * size_of::<T>() as u64,
            beside: false,
            to_the_end: false,
            joins: false,
            _holds: holds,
            touches,
            home,
            stage: None,
            parts: Arc::new([]),
            // SAFETY: as in `launch`.
            issue: Arc::new(move |device| unsafe { device.clear(view) }),
        }
    }

    /// `ops` issued in order as one op, whose views are all theirs: a branch of several
    /// launches beside the others (see [`Op::beside`]). None of `ops` may run beside or
    /// join branches itself, and an empty chain is refused.
    pub fn chain(ops: Vec<Op>) -> Result<Op, Error> {
        let Some(name) = ops.first().map(|op| op.name) else {
            return Err(Error::Invalid("a chain of no ops".into()));
        };
        if let Some(op) = ops.iter().find(|op| op.beside || op.joins) {
            return Err(Error::Invalid(format!(
                "op `{}` of a chain runs beside or joins branches: a chain's ops run in order",
                op.name
            )));
        }
        let mut home = Home::default();
        let ids = ops.iter().flat_map(|op| [op.home.device, op.home.foreign]);
        ids.flatten().for_each(|id| home.note(id));
        let parts: Arc<[Op]> = ops.into();
        let issued = parts.clone();
        Ok(Op {
            name,
            kind: OpKind::Chain,
            grid: parts.iter().map(|op| op.grid).max().unwrap_or(0),
            bytes: parts.iter().map(Op::bytes).sum(),
            beside: false,
            to_the_end: false,
            joins: false,
            _holds: parts
                .iter()
                .flat_map(|op| op._holds.iter().cloned())
                .collect(),
            touches: parts
                .iter()
                .flat_map(|op| op.touches.iter().cloned())
                .collect(),
            home,
            stage: None,
            issue: Arc::new(move |device| issued.iter().try_for_each(|op| (op.issue)(device))),
            parts,
        })
    }

    /// The kernels this op launches, in order: its own, or its chain's.
    fn launched(&self) -> Vec<&'static str> {
        match self.kind {
            OpKind::Chain => self.parts.iter().flat_map(Op::launched).collect(),
            _ if self.is_launch() => vec![self.name],
            _ => Vec::new(),
        }
    }

    /// The same op, run beside the ops after it in its plan, up to the first made
    /// [`Op::after_branches`]: on the GPU on a stream of its own (another op beside the
    /// others gets another), which the plan joins back there or at its end (a graph
    /// branch), so that it costs the step nothing while they run longer; on the CPU in
    /// order, or on a thread of its own under [`super::Schedule::Shuffled`]. Making the
    /// plan checks that it reads nothing that those ops write, and writes nothing that they
    /// read or write (by the access of its binder's views and theirs: their kernels' types).
    pub fn beside(self) -> Op {
        Op {
            beside: true,
            ..self
        }
    }

    /// The same op, run beside every op after it in its plan, as [`Op::beside`] but joined
    /// at the plan's end only: an op [`Op::after_branches`] does not wait for it. Making the
    /// plan checks it against every op after it.
    pub fn beside_to_the_end(self) -> Op {
        Op {
            beside: true,
            to_the_end: true,
            ..self
        }
    }

    /// The same op, run once the ops before it in its plan that run beside the others
    /// ([`Op::beside`], not [`Op::beside_to_the_end`]) are done: on the GPU the branches
    /// join the device's stream before it (and again at the plan's end); on the CPU, where
    /// they ran in order, it changes nothing. So an op beside the others need only stay off
    /// what the ops up to here write.
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

    /// `Ok` if every buffer the op views is of device `on`.
    fn check_home(&self, on: DeviceId) -> Result<(), Error> {
        let what = format!("op `{}`, made with a buffer", self.name);
        match self.home {
            Home {
                foreign: Some(other),
                device: Some(first),
                ..
            } => Err(Error::Invalid(format!(
                "{what} of {first} and one of {other}: an op's buffers are one device's"
            ))),
            Home {
                device: Some(device),
                ..
            } => device.check(on, &what),
            Home { device: None, .. } => Ok(()),
        }
    }

    /// `Ok` unless this op, run beside `other`, touches a buffer that one of the two writes.
    fn check_beside(&self, other: &Op) -> Result<(), Error> {
        for mine in self.touches.iter() {
            for theirs in other.touches.iter().filter(|t| t.key == mine.key) {
                if mine.access == Use::Write || theirs.access == Use::Write {
                    return Err(Error::Invalid(format!(
                        "op `{}` runs beside op `{}` (after it in the plan, before the \
                         branches join) and {mine}, which `{}` {}: one of them must wait \
                         for the other (Op::after_branches), or not run beside",
                        self.name,
                        other.name,
                        other.name,
                        verb(theirs.access)
                    )));
                }
            }
        }
        Ok(())
    }
}

/// `Ok` if every op of `ops` is of device `on` and no op beside the others touches what
/// the ops it runs beside write, or writes what they touch.
fn check_plan(ops: &[Op], on: DeviceId) -> Result<(), Error> {
    for op in ops {
        op.check_home(on)?;
    }
    for (i, op) in ops.iter().enumerate().filter(|(_, op)| op.beside) {
        let joined = |other: &&Op| !op.to_the_end && other.joins;
        for other in ops[i + 1..].iter().take_while(|other| !joined(other)) {
            op.check_beside(other)?;
        }
    }
    Ok(())
}

/// Ops issued in order; on the GPU, optionally captured once as a CUDA graph and replayed.
pub struct Plan {
    /// The ops recorded as a CUDA graph (GPU only), with the device addresses of the
    /// buffers the ops hold: declared first, so that it goes before they may.
    graph: Option<CudaGraph>,
    ops: Vec<Op>,
    /// The device that made it, the only one that runs it.
    device: DeviceId,
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
        self.ops.iter().flat_map(Op::launched)
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
        check_plan(&ops, self.id)?;
        let graph = match &self.imp {
            Imp::Cuda(gpu) if graph && !ops.is_empty() => {
                let sides = gpu.in_order();
                Some(gpu.capture(|| issue_all(self, gpu, &sides, &ops))?)
            }
            _ => None,
        };
        Ok(Plan {
            graph,
            ops,
            device: self.id,
        })
    }

    /// Queues one run of `plan`.
    pub fn run(&self, plan: &Plan) -> Result<(), Error> {
        plan.device.check(self.id, "a plan")?;
        self.count(plan.launched());
        match (&self.imp, &plan.graph) {
            (Imp::Cuda(gpu), Some(graph)) => {
                let _order = gpu.in_order();
                gpu.replay(graph, plan.launched())
            }
            (Imp::Cuda(gpu), None) => issue_all(self, gpu, &gpu.in_order(), &plan.ops),
            // From inside the pool, each launch starts its blocks at once.
            (Imp::Cpu(emu), _) => {
                let _order = emu.in_order();
                let ops = &plan.ops;
                match emu.branch_starts() {
                    None => emu.run(|| ops.iter().try_for_each(|op| (op.issue)(self))),
                    // From outside the pool: a worker waiting for a branch's thread would
                    // hold back the pool the branch's launches need (with one worker, for
                    // ever).
                    Some(mut starts) => self.issue_branching(ops, &mut starts),
                }
            }
        }
    }

    /// Issues `ops` on the CPU emulation with each op beside the others on a thread of its
    /// own, truly beside the ops after it: started where it forks, or (as `starts` picks)
    /// only where its branch joins, once the ops it runs beside are done. A result that
    /// depends on the order of an op and the ops beside it (an access its binder did not
    /// declare) then changes from run to run, on the CPU as it would on the GPU.
    fn issue_branching(&self, ops: &[Op], starts: &mut impl rand::Rng) -> Result<(), Error> {
        std::thread::scope(|scope| {
            // Branches an op after the branches joins, and those joined at the end only.
            let (mut running, mut waiting) = (Vec::new(), Vec::new());
            let (mut running_on, mut waiting_on) = (Vec::new(), Vec::new());
            for op in ops {
                if op.joins {
                    join_branches(scope, self, &mut running, &mut waiting)?;
                }
                let (running, waiting) = match op.to_the_end {
                    true => (&mut running_on, &mut waiting_on),
                    false => (&mut running, &mut waiting),
                };
                match (op.beside, starts.random::<bool>()) {
                    (true, true) => running.push(scope.spawn(move || (op.issue)(self))),
                    (true, false) => waiting.push(op),
                    (false, _) => (op.issue)(self)?,
                }
            }
            running.append(&mut running_on);
            waiting.append(&mut waiting_on);
            join_branches(scope, self, &mut running, &mut waiting)
        })
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

/// Issues `ops` on `device`'s GPU, whose order the caller holds (`sides`), in order, each
/// marked [`Op::beside`] on a side stream of its own (a branch), joined back before each op
/// marked [`Op::after_branches`] and after the last: on every path, an error's too, so that
/// nothing queued after the plan runs beside a branch of it.
fn issue_all(device: &Device, gpu: &Gpu, sides: &Sides, ops: &[Op]) -> Result<(), Error> {
    // Every branch forked so far, and those an op after the branches joins.
    let (mut branches, mut joinable) = (0, Vec::new());
    let issued = ops.iter().try_for_each(|op| {
        if op.joins && !joinable.is_empty() {
            gpu.rejoin(sides, joinable.iter().copied())?;
        }
        match op.beside {
            true => {
                if !op.to_the_end {
                    joinable.push(branches);
                }
                branches += 1;
                gpu.beside(sides, branches - 1, || (op.issue)(device))
            }
            false => (op.issue)(device),
        }
    });
    match branches {
        0 => issued,
        _ => issued.and(gpu.rejoin(sides, 0..branches)),
    }
}

/// Starts the ops `waiting` for their branches' join on threads of `scope`, and waits for
/// them and those `running`: a join of the CPU emulation's branches.
fn join_branches<'scope, 'env>(
    scope: &'scope std::thread::Scope<'scope, 'env>,
    device: &'env Device,
    running: &mut Vec<std::thread::ScopedJoinHandle<'scope, Result<(), Error>>>,
    waiting: &mut Vec<&'env Op>,
) -> Result<(), Error> {
    for op in waiting.drain(..) {
        running.push(scope.spawn(move || (op.issue)(device)));
    }
    let mut result = Ok(());
    for branch in running.drain(..) {
        let done = branch
            .join()
            .unwrap_or_else(|_| Err(Error::Invalid("an op beside the others panicked".into())));
        result = result.and(done);
    }
    result
}
