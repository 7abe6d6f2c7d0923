//! The launch floor, measured on the device and in the run it is compared with: a chain of
//! as many launches as a step makes, each doing one read-modify-write a thread over as many
//! threads as the step has slots (the least a stage of the step does), replayed as one CUDA
//! graph (as the step is) and launched one by one. What the step takes above it is its
//! kernels' own work and latency.

use serde::{Deserialize, Serialize};

use gpuwars_kernels::primitives::touch::TouchArgs;
use gpuwars_kernels::registry;

use crate::backend::Binder;
use crate::primitives::threads;
use crate::{BackendKind, Buffer, Device, Error, Op};

/// What a chain of `launches` one-touch launches over `threads` threads costs a step.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Floor {
    /// Launches a step.
    pub launches: usize,
    /// Threads a launch.
    pub threads: u32,
    /// Seconds a step, the chain replayed as one CUDA graph (issued one by one on the CPU).
    pub graph_s: f64,
    /// Seconds a step, the chain launched one by one.
    pub stream_s: f64,
}

/// One launch of the chain: a touch of every element of `data`.
fn touch(data: &Buffer<u32>) -> Op {
    // SAFETY: the view goes into this op only.
    let mut b = unsafe { Binder::new() };
    let args = TouchArgs { data: b.view(data) };
    // SAFETY: one buffer, one element a thread.
    unsafe { threads(registry::TOUCH, data.len() as u32, args, b, 8) }
}

/// Measures the floor of a step of `launches` launches over `threads` threads on `device`;
/// checks that every launch of every step ran.
pub fn measure(device: &Device, launches: usize, threads: u32) -> Result<Floor, Error> {
    if launches == 0 || threads == 0 {
        return Err(Error::Invalid(format!(
            "a launch floor of {launches} launches of {threads} threads (allowed: at least 1 \
             of each)"
        )));
    }
    let data = device.alloc_zeroed::<u32>(threads as usize)?;
    let ops: Vec<Op> = (0..launches).map(|_| touch(&data)).collect();
    let (warm, reps) = match device.kind() {
        BackendKind::Cuda => (200, 2_000),
        BackendKind::Cpu => (5, 50),
    };
    let time = |graph: bool| -> Result<f64, Error> {
        let plan = device.plan(ops.clone(), graph)?;
        for _ in 0..warm {
            device.run(&plan)?;
        }
        let start = device.mark()?;
        for _ in 0..reps {
            device.run(&plan)?;
        }
        Ok(device.mark()?.seconds_since(&start)? / f64::from(reps))
    };
    let (graph_s, stream_s) = (time(true)?, time(false)?);
    let runs = 2 * (warm + reps) * launches as u32;
    if let Some(i) = device.download(&data)?.iter().position(|&v| v != runs) {
        return Err(Error::Invalid(format!(
            "the launch floor's element {i} was touched a number of times other than the \
             {runs} launches that ran"
        )));
    }
    Ok(Floor {
        launches,
        threads,
        graph_s,
        stream_s,
    })
}

impl Floor {
    /// One line saying what the floor is, beside a step of `step_s` seconds.
    pub fn describe(&self, step_s: f64) -> String {
        format!(
            "launch floor (measured here): {} dependent launches of one read-modify-write over \
             {} threads take {:.1} µs a step as a graph, {:.1} one by one; the step takes {:.1}",
            self.launches,
            crate::files::thousands(self.threads),
            self.graph_s * 1e6,
            self.stream_s * 1e6,
            step_s * 1e6
        )
    }
}
