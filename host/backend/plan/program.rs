//! The persistent step on the host: the launches of a plan turned into one cooperative
//! launch of [`registry::PROGRAM`], which runs them in order with a barrier across the grid
//! between them (`gpuwars_kernels::persistent`), for one step or several.

use std::sync::Arc;

use gpuwars_kernels::persistent::{ProgramArgs, Stage};
use gpuwars_kernels::registry;

use super::{Binder, Op, OpKind, bound, check_plan};
use crate::backend::{Device, Error, MAX_BLOCK};

/// Threads per block of a persistent launch: the heavier kernels' blocks (see
/// docs/pipeline.md, "Block sizes").
const PROGRAM_BLOCK: u32 = 128;

impl Device {
    /// One op that runs the launches of `ops` in order, `steps` times, inside one
    /// cooperative launch, each launch's threads run as its own (so the result is the ops',
    /// bit for bit) and a barrier across the grid where each launch ended. Ops beside the
    /// others run in their place in the order. Its grid is the most blocks the device holds
    /// at once, or fewer where no launch has that many threads.
    ///
    /// An error names what cannot be a stage: a clear, a kernel outside
    /// [`registry::STAGES`], a block that is not whole warps; and no steps, or no launch.
    pub fn program(&self, ops: &[Op], steps: u32) -> Result<Op, Error> {
        check_plan(ops, self.id)?;
        let mut stages = Vec::new();
        let mut blob: Vec<u64> = Vec::new();
        let mut threads = 0u64;
        for op in ops {
            let source = op.stage.as_ref().ok_or_else(|| {
                Error::Invalid(format!(
                    "op `{}` cannot be a stage of a persistent step: only launches can",
                    op.name
                ))
            })?;
            if op.grid == 0 {
                continue;
            }
            let kernel = registry::STAGES
                .iter()
                .position(|&k| k == op.name)
                .ok_or_else(|| {
                    Error::Invalid(format!(
                        "kernel `{}` cannot be a stage of a persistent step (the stage kernels: \
                         {})",
                        op.name,
                        registry::STAGES.join(", ")
                    ))
                })?;
            if source.block % 32 != 0 || source.block > MAX_BLOCK {
                return Err(Error::Invalid(format!(
                    "kernel `{}`: a stage's blocks must be whole warps (32 to {MAX_BLOCK} \
                     threads, a multiple of 32), not {}",
                    op.name, source.block
                )));
            }
            let args = u32::try_from(blob.len()).map_err(|_| {
                Error::Invalid("a persistent step's arguments exceed 32 GiB".into())
            })?;
            let mut words = vec![0u64; source.args.len().div_ceil(8)];
            bytemuck::cast_slice_mut::<u64, u8>(&mut words)[..source.args.len()]
                .copy_from_slice(&source.args);
            blob.extend(words);
            stages.push(Stage {
                kernel: kernel as u32,
                grid: op.grid,
                block: source.block,
                args,
            });
            threads = threads.max(u64::from(op.grid) * u64::from(source.block));
        }
        if steps == 0 || stages.is_empty() {
            return Err(Error::Invalid(format!(
                "a persistent step of {steps} steps and {} launches (allowed: at least one of each)",
                stages.len()
            )));
        }
        let stage_list = self.upload(&stages)?.named("program.stages");
        let blob = self.upload(&blob)?.named("program.args");
        let barrier = self.alloc_zeroed::<u32>(1)?.named("program.barrier");
        let resident = self.resident_blocks(&registry::PROGRAM, PROGRAM_BLOCK)?;
        let wanted = threads.div_ceil(u64::from(PROGRAM_BLOCK));
        let grid = u32::try_from(wanted)
            .unwrap_or(u32::MAX)
            .min(resident)
            .max(1);

        // SAFETY: the views go into this op only.
        let mut b = unsafe { Binder::new() };
        let args = ProgramArgs {
            stages: b.view(&stage_list),
            blob: b.view(&blob),
            barrier: b.view(&barrier),
            steps,
            reserved: 0,
        };
        let (holds, touches, home) = bound(b);
        let holds = holds
            .iter()
            .chain(ops.iter().flat_map(|op| op._holds.iter()));
        let touches = touches
            .iter()
            .chain(ops.iter().flat_map(|op| op.touches.iter()));
        let bytes = ops.iter().map(Op::bytes).sum::<u64>() * u64::from(steps);
        Ok(Op {
            name: registry::PROGRAM.name,
            kind: OpKind::Launch,
            grid,
            bytes,
            beside: false,
            to_the_end: false,
            joins: false,
            _holds: holds.cloned().collect(),
            touches: touches.cloned().collect(),
            home,
            stage: None,
            parts: Arc::new([]),
            // SAFETY: every stage's views are its op's (held above, with their buffers),
            // valid for the launches the ops stand for, which the program runs in their
            // order with a barrier between them: each as it would run alone.
            issue: Arc::new(move |device| unsafe {
                device.issue_cooperative(&registry::PROGRAM, grid, PROGRAM_BLOCK, args)
            }),
        })
    }
}
