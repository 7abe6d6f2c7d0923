//! A frame drawn beside the next step: one launch keeps a still of what the renderers read
//! of the world, and the frame's launches read the still on a branch of their own while
//! the step writes the world. On the GPU the two run at once, so a loop of a step and a
//! frame costs about the longer of them, not their sum; on the CPU the frame runs first.
//! The frame is the one [`Pipeline::render`] would draw before the step, pixel for pixel,
//! and the step the one [`Pipeline::step`] takes, bit for bit.

use gpuwars_kernels::registry;
use gpuwars_kernels::render::Look;
use gpuwars_kernels::render::camera::Lens;
use gpuwars_kernels::render::still::{StillArgs, still_threads};

use super::Pipeline;
use super::draw::{FrameKey, KeptFrames};
use super::still::{Source, Still};
use crate::backend::{Binder, Plan};
use crate::primitives::threads;
use crate::sim::state::made;
use crate::{Error, Op};

impl Pipeline<'_> {
    /// The launch that copies what the renderers read of the world into `still`.
    fn keep_op(&self, still: &Still) -> Op {
        // SAFETY: the views go into the op made with the binder.
        let mut b = unsafe { Binder::new() };
        let (bodies, input) = (
            self.drawn_bodies(Source::World, &mut b),
            self.drawn_input(Source::World, &mut b),
        );
        // A world without particles copies none: the still's own (empty) stand in.
        let particles = self.drawn_particles(Source::World, &mut b);
        let particles =
            particles.map_or_else(|| made(still.particles.0.convert(&mut b)), |(p, _)| p);
        let args = StillArgs {
            bodies,
            particles,
            input,
            still: made(still.bodies.convert(&mut b)),
            still_particles: made(still.particles.0.convert(&mut b)),
            still_input: b.view(&still.input),
        };
        let n = still_threads(bodies.slots(), particles.len());
        let bytes = 2 * size_of::<StillArgs>() as u64 + 32 * u64::from(n);
        // SAFETY: the world's buffers and the still's, made for the same slots, particles
        // and input (`Still::new`).
        unsafe { threads(registry::KEEP_STILL, n, args, b, bytes) }
    }

    /// Queues one step and, beside it, the frame of `lens` of the world as the steps before
    /// left it, each kind as `looks` says: what [`Pipeline::render`] then
    /// [`Pipeline::step`] queue, bit for bit and pixel for pixel, in about the time of the
    /// longer of the two on the GPU. A persistent step (one launch whose blocks must all be
    /// resident) runs no frame beside it: its frame is drawn first. As for frames, the
    /// launches replay as a CUDA graph once the same lens comes twice in a row.
    pub fn render_beside_step(&mut self, lens: &Lens, looks: &[Look]) -> Result<(), Error> {
        if self.persistent.0 {
            self.render(lens, looks)?;
            return self.step();
        }
        self.ready(lens, looks)?;
        let (device, renumbers) = (self.device, self.renumbers_next());
        let key = FrameKey::of(lens, None);
        if self.canvas()?.still.is_none() {
            let still = Still::new(device, &self.world)?;
            self.canvas_mut().still = Some(still);
        }
        let kept = self.canvas_mut().beside.take();
        let (kept, ran) = KeptFrames::run(kept, key, usize::from(renumbers), device, |graph| {
            self.beside_plan(lens, renumbers, graph)
        });
        self.canvas_mut().beside = kept;
        ran?;
        self.steps += 1;
        Ok(())
    }

    /// The plan of [`Pipeline::render_beside_step`]: the still kept, the frame's launches
    /// beside the step's (the renumbering step's if `renumbers`), as a graph if `graph` and
    /// the step replays as one.
    fn beside_plan(&self, lens: &Lens, renumbers: bool, graph: bool) -> Result<Plan, Error> {
        let step = self.step_plan(renumbers);
        let still = self.canvas()?.still.as_ref().expect("made first");
        // SAFETY: no outside image.
        let frame = unsafe { self.frame_ops(lens, None, Source::Still(still)) };
        let mut ops = vec![self.keep_op(still), Op::chain(frame)?.beside_to_the_end()];
        ops.extend(step.ops().iter().cloned());
        self.device.plan(ops, graph && step.is_graph())
    }
}
