//! The launch floor, measured on the device and in the run it is compared with: a chain of
//! as many launches as a step makes, each doing one read-modify-write a thread over as many
//! threads as the step has slots (the least a stage of the step does), in the block size
//! that runs it fastest (blocks of 128 threads took 3 times as long as blocks of 512 at
//! 16.76M threads on an H200: starting blocks, not memory, bound them), replayed as one CUDA
//! graph (as the step is), as the same graph with programmatic dependent launch (on sm_90
//! and newer), launched one by one, and run as rounds of one block with a barrier between
//! them (the floor of a step that would run in one block); and the graph with the game's
//! ring around it, as `Game::submit` queues each step (its input written to shared memory
//! before, its fence recorded after). What the step takes above it is its kernels' own work
//! and latency.

use serde::{Deserialize, Serialize};

use gpuwars_kernels::primitives::touch::{TouchArgs, TouchRoundsArgs};
use gpuwars_kernels::registry;

use super::{BackendKind, Binder, Buffer, Device, Error, Launch, MAX_BLOCK, Op};

/// What a chain of `launches` one-touch launches over `threads` threads costs a step.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Floor {
    /// Launches a step.
    pub launches: usize,
    /// Threads a launch.
    pub threads: u32,
    /// Threads per block of the fastest chain as a graph, which every figure below uses:
    /// the floor is the least over [`BLOCKS`].
    #[serde(default)]
    pub block: u32,
    /// Seconds a step, the chain replayed as one CUDA graph, each launch waiting for the
    /// end of the one before (issued one by one on the CPU).
    pub graph_s: f64,
    /// Seconds a step, the same graph with programmatic dependent launch: each kernel
    /// starts before the one before ends and waits for it on the GPU. `None` where the
    /// device cannot (before sm_90, the CPU emulation).
    pub dependent_s: Option<f64>,
    /// Seconds a step, the chain launched one by one.
    pub stream_s: f64,
    /// Seconds a step, the chain run as `launches` rounds of one block of up to 1,024
    /// threads with a barrier between rounds: one launch a step. `None` above
    /// [`ONE_BLOCK_MAX_THREADS`] threads, where one block is no way to run a step.
    pub one_block_s: Option<f64>,
    /// Seconds a step, the graph as the step launches it (with dependent launch where the
    /// device can) in a ring of 4 steps in flight, as a game queues each step.
    pub ring_s: f64,
    /// Seconds a step, the chain as one persistent launch a step: its launches as stages of
    /// one cooperative launch, a barrier across the grid between them (`Device::program`).
    #[serde(default)]
    pub persistent_s: Option<f64>,
    /// Seconds a step, [`BATCH`] steps of the chain in one persistent launch: the barriers'
    /// own floor, with no launch a step.
    #[serde(default)]
    pub batched_s: Option<f64>,
}

/// Steps a launch of the batched persistent floor runs ([`Floor::batched_s`]).
pub const BATCH: u32 = 16;

/// The most threads whose one-block floor is measured: a block runs 64 of them a thread a
/// round at this size, already far slower than a graph of whole-GPU launches (at a million,
/// 3.3 ms against 0.2 on an H100), so larger worlds would only spend the run's time on it.
pub const ONE_BLOCK_MAX_THREADS: u32 = 65_536;

/// The block sizes whose chains are timed; the fastest is the floor's.
pub const BLOCKS: [u32; 4] = [128, 256, 512, MAX_BLOCK];

/// One launch of the chain: a touch of every element of `data`, in blocks of `block`.
fn touch(data: &Buffer<u32>, block: u32) -> Op {
    // SAFETY: the view goes into this op only.
    let mut b = unsafe { Binder::new() };
    let args = TouchArgs { data: b.view(data) };
    let threads = data.len() as u32;
    let launch = Launch {
        kernel: registry::TOUCH,
        grid: threads.div_ceil(block),
        block,
        args,
    };
    // SAFETY: one buffer, one element a thread (the kernel skips the threads past it).
    unsafe { Op::launch(launch, b, 8 * u64::from(threads)) }
}

/// The whole chain in one launch: `rounds` touches of every element of `data` by one block.
fn touch_rounds(data: &Buffer<u32>, rounds: u32) -> Op {
    // SAFETY: the view goes into this op only.
    let mut b = unsafe { Binder::new() };
    let args = TouchRoundsArgs {
        data: b.view(data),
        rounds,
        reserved: 0,
    };
    let launch = Launch {
        kernel: registry::TOUCH_ROUNDS,
        grid: 1,
        block: (data.len() as u32).min(MAX_BLOCK),
        args,
    };
    // SAFETY: one buffer; each element has one thread, whatever the block's size.
    unsafe { Op::launch(launch, b, 8 * u64::from(rounds) * data.len() as u64) }
}

/// Measures the floor of a step of `launches` launches over `threads` threads on `device`;
/// checks that every launch of every step ran. The device's dependent-launch setting is
/// the same after as before.
pub fn measure(device: &Device, launches: usize, threads: u32) -> Result<Floor, Error> {
    let rounds = u32::try_from(launches).ok().filter(|&n| n > 0);
    let Some(rounds) = rounds.filter(|_| threads > 0) else {
        return Err(Error::Invalid(format!(
            "a launch floor of {launches} launches of {threads} threads (allowed: 1 to {} \
             launches, at least 1 thread)",
            u32::MAX
        )));
    };
    let data = device.alloc_zeroed::<u32>(threads as usize)?;
    let chain = |block: u32| -> Vec<Op> { (0..launches).map(|_| touch(&data, block)).collect() };
    let (warm, reps) = match device.kind() {
        BackendKind::Cuda => (200, 2_000),
        BackendKind::Cpu => (5, 50),
    };
    let mut timed_runs = 0;
    let mut time = |ops: &[Op], graph: bool| -> Result<f64, Error> {
        let plan = device.plan(ops.to_vec(), graph)?;
        timed_runs += 1;
        seconds_a_run(device, (warm, reps), || device.run(&plan))
    };
    let was_dependent = device.dependent_launch();
    let mut times = || -> Result<_, Error> {
        device.set_dependent_launch(false);
        let mut fastest = (f64::INFINITY, BLOCKS[0]);
        for block in BLOCKS {
            let s = time(&chain(block), true)?;
            if s < fastest.0 {
                fastest = (s, block);
            }
        }
        let (graph_s, block) = fastest;
        let chain = chain(block);
        let dependent_s = if device.set_dependent_launch(true) {
            Some(time(&chain, true)?)
        } else {
            None
        };
        device.set_dependent_launch(false);
        let stream_s = time(&chain, false)?;
        let one_block_s = if threads <= ONE_BLOCK_MAX_THREADS {
            Some(time(&[touch_rounds(&data, rounds)], true)?)
        } else {
            None
        };
        device.set_dependent_launch(dependent_s.is_some());
        let ring_s = time_in_ring(device, &chain, (warm, reps))?;
        let persistent_s = time(&[device.program(&chain, 1)?], false)?;
        let batched_s = time(&[device.program(&chain, BATCH)?], false)? / f64::from(BATCH);
        Ok(Floor {
            launches,
            threads,
            block,
            graph_s,
            dependent_s,
            stream_s,
            one_block_s,
            ring_s,
            persistent_s: Some(persistent_s),
            batched_s: Some(batched_s),
        })
    };
    let floor = times();
    device.set_dependent_launch(was_dependent);
    let floor = floor?;
    // The timed plans' runs, the ring's, and the batched program's further steps.
    let timed_runs = timed_runs + 1 + (BATCH - 1);

    let runs = timed_runs * (warm + reps) * rounds;
    if let Some(i) = device.download(&data)?.iter().position(|&v| v != runs) {
        return Err(Error::Invalid(format!(
            "the launch floor's element {i} was touched a number of times other than the \
             {runs} launches that ran"
        )));
    }
    Ok(floor)
}

/// Seconds a step of `chain` as a graph queued through a ring of 4 steps in flight
/// (`Game`'s default lag): `warm` steps, then `reps` timed.
fn time_in_ring(device: &Device, chain: &[Op], (warm, reps): (u32, u32)) -> Result<f64, Error> {
    let plan = device.plan(chain.to_vec(), true)?;
    let (inputs, outputs) = (
        device.alloc_shared::<u32>(4)?,
        device.alloc_shared::<u32>(4)?,
    );
    let mut ring = device.ring(&inputs, &outputs)?;
    let seconds = seconds_a_run(device, (warm, reps), || {
        ring.reserve(device)?;
        ring.send(device, 1)?;
        device.run(&plan)?;
        ring.receive(device)
    })?;
    while ring.oldest(device)?.is_some() {}
    Ok(seconds)
}

/// Seconds `run` takes on the device, the mean of `reps` runs timed by device marks after
/// `warm` untimed ones.
fn seconds_a_run(
    device: &Device,
    (warm, reps): (u32, u32),
    mut run: impl FnMut() -> Result<(), Error>,
) -> Result<f64, Error> {
    for _ in 0..warm {
        run()?;
    }
    let start = device.mark()?;
    for _ in 0..reps {
        run()?;
    }
    Ok(device.mark()?.seconds_since(&start)? / f64::from(reps))
}

impl Floor {
    /// Seconds a step of the graph launched as the step's own is: with programmatic
    /// dependent launch when `dependent` (and the device could), else without.
    pub fn graph_like_step_s(&self, dependent: bool) -> f64 {
        match self.dependent_s {
            Some(s) if dependent => s,
            _ => self.graph_s,
        }
    }

    /// One line saying what the floor is, beside a step of `step_s` seconds.
    pub fn describe(&self, step_s: f64) -> String {
        let dependent = self.dependent_s.map_or(String::new(), |s| {
            format!(", {:.1} with dependent launch", s * 1e6)
        });
        let one_block = self.one_block_s.map_or(String::new(), |s| {
            format!(", {:.1} as rounds of one block", s * 1e6)
        });
        let persistent = match (self.persistent_s, self.batched_s) {
            (Some(one), Some(batched)) => format!(
                ", {:.1} as one persistent launch a step ({:.1} with {BATCH} steps a launch)",
                one * 1e6,
                batched * 1e6
            ),
            _ => String::new(),
        };
        format!(
            "launch floor (measured here): {} dependent launches of one read-modify-write over \
             {} threads in blocks of {} take {:.1} µs a step as a graph{dependent}, {:.1} one by \
             one{one_block}{persistent}, {:.1} in a game's ring; the step takes {:.1}",
            self.launches,
            crate::files::thousands(self.threads),
            self.block,
            self.graph_s * 1e6,
            self.stream_s * 1e6,
            self.ring_s * 1e6,
            step_s * 1e6
        )
    }
}
