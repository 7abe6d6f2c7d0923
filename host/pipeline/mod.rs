//! The step pipeline: one ordered list of typed stages ([`Stage`]), written once, that both
//! the simulation-only world ([`Simulation`]) and the game (`crate::game::Game`) configure.
//!
//! A step runs these stages, in order (the paper's game loop, with the AI after the narrow
//! phase):
//!
//! | stage | launches | in |
//! |---|---|---|
//! | `master` | the master before the physics: the step's input (the player's, or the one the autopilot left), ship, shots, spawns (one warp) | games |
//! | `births` | the enemies the master thread ordered come alive | games of more than 2¹⁸ slots (in smaller ones, inside the broad phase's first launch: `births_and_count`) |
//! | `broad` | the grid: bucket counts (with the births in small games), their prefix sum, placement, canonical order | games, and worlds where something collides |
//! | `renumber` | every few steps, the bodies move to slots in the grid's order within their kinds' ranges (gather, settle) | worlds with a grid of 8,192 slots or more, or as the scene's physics says |
//! | `pilot` | the autopilot's input for the next step (one warp), from the grid as it was built, beside the stages after it where they leave the grid alone and it keeps its entries' velocities (on the GPU a branch of the step's graph) | games |
//! | `narrow` | contacts and their response (`collide_circles` without rectangles; in small games of circles whose machines run in teams, inside `think`'s launch) | worlds where something collides |
//! | `think` | every enemy's machine, in one launch over the enemy kinds' slots, on the GPU from its last block where the kinds that walk the most lie at the end (or over every kind's, with the narrow phase and the integrator: `collide_think_integrate`) | games with enemies |
//! | `integrate` | Euler, the boundary rule, deaths (inside `think`'s launch where the narrow phase is); in a game's step that does not renumber, the free lists' marks of the slots whose freedom it changed | always |
//! | `substeps` | broad, narrow and integrate again for each further substep | worlds with substeps |
//! | `effects` | kills (the deaths the physics counted in their slots) burst into particles, the others move and fade, beside the stages after it (on the GPU a branch of the step's graph) | games with explosions |
//! | `tally` | the master after the physics (one warp): counts from the free slots the master found, its births and the physics' deaths, beside the free lists (a branch) | games |
//! | `free` | the free lists: flags, their prefix sum, gather (in a game's step that does not renumber, only of the kinds whose bodies died or were born, and from the integrator's marks: the prefix sum's last launch and the gather) | always |
//!
//! The scene decides which stages exist and which kernels they launch; every step of a
//! scene then launches the same sequence, since per-step choices (who flies, whether a wave
//! is due, whether the game is over) are made on the device. So the sequence is recorded
//! once as a [`Plan`]: on the GPU a CUDA graph on the device's own stream, replayed each
//! step without the host waiting; on the CPU emulation the same ops in order, issued from
//! inside the emulator's pool.
//!
//! A [`Pipeline`] is the world's data (`world::World`: its buffers, the game's) and the
//! step's plans, whose ops hold the buffers they view. Each stage's ops are made in its own
//! file under `stages/`.

mod beside;
pub mod draw;
mod handmade;
mod persistent;
mod profile;
mod simulation;
mod stage;
mod stages;
mod still;
mod teams;
pub(crate) mod world;

pub use draw::{Drawing, Frame};
pub use persistent::Persistent;
pub use profile::{Profile, StageTimes};
pub use simulation::Simulation;
pub use stage::{Stage, StagePlan};
pub use teams::Lanes;
pub use world::bytes_needed;

use gpuwars_kernels::game::control::{Order, Status};
use gpuwars_kernels::game::effects::{Burst, Particles};
use gpuwars_kernels::game::rules::{Brain, Rules, Wave};
use gpuwars_kernels::sim::{Space, Touched};

use crate::backend::Vecs;
use crate::sim::layout::Layout;
use crate::sim::{Snapshot, WorldSpec};
use crate::{Buffer, Device, Error, Plan};
use world::World;

/// What a game adds to a world: its rules, its enemies' brains and the spawn schedule.
#[derive(Clone, Debug)]
pub struct GameConfig {
    /// The rules in the kernels' terms.
    pub rules: Rules,
    /// Each kind's brain (machine 0 for kinds that have none).
    pub brains: Vec<Brain>,
    /// The spawn schedule.
    pub waves: Vec<Wave>,
    /// How kills burst into particles, if the scene has explosions (the slots owning
    /// particles are filled in by the pipeline).
    pub effects: Option<Burst>,
    /// Steps the host may have in flight: the depth of the mailbox through which commands
    /// go up and statuses come back (at least 1).
    pub in_flight: usize,
}

impl GameConfig {
    /// The slots of the kinds with a machine (see [`mind_slots`]).
    fn mind_slots(&self, layout: &Layout) -> Option<(u32, u32)> {
        let machines: Vec<bool> = self.brains.iter().map(|b| b.machine != 0).collect();
        mind_slots(layout, &machines)
    }
}

/// The slots `first .. end` from the first kind with a machine (`machines`, per kind) to the
/// last, padding included: the enemies whose machines think, and whose kills own explosion
/// particles. `None` if no kind has a machine.
pub fn mind_slots(layout: &Layout, machines: &[bool]) -> Option<(u32, u32)> {
    let mut kinds = (0..machines.len()).filter(|&k| machines[k]);
    let first = kinds.next()?;
    let last = kinds.next_back().unwrap_or(first);
    Some((layout.ranges[first].start, layout.ranges[last].end()))
}

/// The plans of a world's step: the whole step, the step that also renumbers (in worlds
/// that do), and each stage alone (for the profile).
struct Plans {
    step: Plan,
    /// Launches of a step that does not renumber, as its plan of launches makes them.
    launches: usize,
    renumbering: Option<Plan>,
    stages: Vec<StagePlan>,
}

/// A world on a device and the plans of its step.
pub struct Pipeline<'d> {
    plans: Plans,
    /// Whether the step runs as one persistent launch, and why (see [`Persistent`]).
    persistent: (bool, &'static str),
    world: World,
    /// The kernel renderer's buffers, made by the first frame drawn.
    canvas: Option<draw::Canvas>,
    device: &'d Device,
    /// Steps queued since creation: the one step counter of a world.
    steps: u64,
}

impl<'d> Pipeline<'d> {
    /// A world of `spec` with every slot free, its generators seeded from `seed`, and the
    /// game `game` if given; its step replays as a CUDA graph on the GPU when `graphs`, its
    /// neighbour queries with `lanes` threads a body, as one persistent launch as
    /// `persistent` chooses.
    /// Fails with [`Error::OutOfMemory`] before allocating anything if its buffers do not
    /// fit the device.
    pub fn configured(
        device: &'d Device,
        spec: &WorldSpec,
        seed: u32,
        game: Option<GameConfig>,
        (graphs, lanes, persistent): (bool, Lanes, Persistent),
    ) -> Result<Self, Error> {
        let world = World::new(device, spec, seed, game, lanes)?;
        let persistent = persistent.choose(device);
        // The whole step's ops, as one persistent launch where chosen.
        let whole = |ops: Vec<_>| match persistent.0 {
            true => device.plan(vec![device.program(&ops, 1)?], graphs),
            false => device.plan(ops, graphs),
        };
        // Every stage's ops, and those of the steps that do not renumber.
        let (mut all, mut plain) = (Vec::new(), Vec::new());
        let mut stages = Vec::new();
        for stage in Stage::ALL {
            let ops = stage.ops(&world);
            if ops.is_empty() {
                continue;
            }
            // The same ops serve the stage's own plan (for the profile) and the whole step;
            // but the free lists of a step that does not renumber are remade only for the
            // kinds that changed, from the integrator's marks where it makes them (the
            // stage's own plan, for a world's first lists and after bodies are placed,
            // remakes them all, as renumbering does): those two stages have a tracked plan
            // too, which the profile runs in the steps that do not renumber.
            all.extend(ops.iter().cloned());
            let tracked = match stage {
                Stage::Integrate if world.config.marks_in_integrate => {
                    Some(stages::integrate::ops(&world, 0, true))
                }
                Stage::Free if world.game.is_some() => Some(stages::free::ops(&world, true)),
                _ => None,
            };
            match (stage, &tracked) {
                (Stage::Renumber, _) => {}
                (_, Some(tracked)) => plain.extend(tracked.iter().cloned()),
                (_, None) => plain.extend(ops.iter().cloned()),
            }
            stages.push(StagePlan {
                stage,
                plan: device.plan(ops, graphs)?,
                tracked: tracked.map(|ops| device.plan(ops, graphs)).transpose()?,
            });
        }
        let renumbering = match world.config.renumber_every {
            0 => None,
            _ => Some(whole(all)?),
        };
        let launches = plain.iter().filter(|op| op.is_launch()).count();
        let pipeline = Pipeline {
            persistent,
            plans: Plans {
                step: whole(plain)?,
                launches,
                renumbering,
                stages,
            },
            world,
            canvas: None,
            device,
            steps: 0,
        };
        // The free lists, and the autopilot's input for the first step (none: the ship is
        // born in it), as a step would have left them.
        pipeline.run_stage(Stage::Free)?;
        pipeline.run_stage(Stage::Pilot)?;
        device.synchronize()?;
        Ok(pipeline)
    }

    /// Runs the plan of `stage` once (nothing if the world has no such stage).
    fn run_stage(&self, stage: Stage) -> Result<(), Error> {
        match self.plans.stages.iter().find(|s| s.stage == stage) {
            Some(s) => self.device.run(&s.plan),
            None => Ok(()),
        }
    }

    /// Whether the next step renumbers the bodies: every `renumber_every` steps from the
    /// first, counted on the host (the same count on every backend).
    pub fn renumbers_next(&self) -> bool {
        let every = u64::from(self.world.config.renumber_every);
        every != 0 && self.steps.is_multiple_of(every)
    }

    /// The plan of a step: the renumbering one's if `renumbers` (and the world renumbers).
    fn step_plan(&self, renumbers: bool) -> &Plan {
        match &self.plans.renumbering {
            Some(plan) if renumbers => plan,
            _ => &self.plans.step,
        }
    }

    /// Queues one step, without waiting for it.
    pub fn step(&mut self) -> Result<(), Error> {
        self.device.run(self.step_plan(self.renumbers_next()))?;
        self.steps += 1;
        Ok(())
    }

    /// Queues one step stage by stage, timing each (device events on the GPU, clocks on
    /// the CPU), and adds the times to `profile`; it waits for the step.
    pub fn step_profiled(&mut self, profile: &mut Profile) -> Result<(), Error> {
        let device = self.device;
        let renumbers = self.renumbers_next();
        let mut marks = vec![device.mark()?];
        let mut ran = Vec::with_capacity(self.plans.stages.len());
        for stage in &self.plans.stages {
            // The renumbering's time is counted in the steps that renumber only (nothing in
            // the others): its mean over the steps is its share of each.
            let runs = stage.stage != Stage::Renumber || renumbers;
            if runs {
                device.run(stage.in_step(renumbers))?;
            }
            ran.push(runs);
            marks.push(device.mark()?);
        }
        for ((stage, pair), ran) in self.plans.stages.iter().zip(marks.windows(2)).zip(ran) {
            profile.add(stage, pair[1].seconds_since(&pair[0])?, ran);
        }
        profile.end_step();
        self.steps += 1;
        Ok(())
    }

    /// The stages this world's step runs, in order, with their plans.
    pub fn stages(&self) -> &[StagePlan] {
        &self.plans.stages
    }

    /// Kernel launches per step (of a step that does not renumber).
    pub fn launches_per_step(&self) -> usize {
        self.plans.launches
    }

    /// Whether the step runs as one persistent launch, and why.
    pub fn persistent(&self) -> (bool, &'static str) {
        self.persistent
    }

    /// Whether the step replays as a CUDA graph.
    pub fn uses_graphs(&self) -> bool {
        self.plans.step.is_graph()
    }

    /// The slot ranges.
    pub fn layout(&self) -> &Layout {
        &self.world.layout
    }

    /// The world and grid the kernels use.
    pub fn space(&self) -> &Space {
        &self.world.space
    }

    /// Steps queued since creation.
    pub fn steps(&self) -> u64 {
        self.steps
    }

    /// The device the world lives on.
    pub fn device(&self) -> &'d Device {
        self.device
    }

    /// The whole state after the steps queued so far, read back (waits for them).
    pub fn snapshot(&self) -> Result<Snapshot, Error> {
        let (state, contacts) = (&self.world.state, &self.world.scratch.contacts);
        state.snapshot(self.device, self.steps, contacts)
    }

    /// The contacts the narrow phase logged since its log's cursor was at `since` (see
    /// `Contacts::log`; the cursor starts at 0), sorted by slot, partner and time, and the
    /// cursor now; waits for the steps queued. Fails where the world keeps no log
    /// ([`crate::sim::Physics::trace_paths`]), or more contacts were logged since than it
    /// holds.
    pub fn contact_log(&self, since: u32) -> Result<(Vec<Touched>, u32), Error> {
        let contacts = &self.world.scratch.contacts;
        let cursor = self.contact_log_cursor()?;
        let ring = self.device.download(&contacts.log)?;
        let new = cursor.wrapping_sub(since) as usize;
        if new > ring.len() {
            return Err(Error::ContactLogFull {
                logged: new,
                room: ring.len(),
                per_slot: self.world.spec.physics.logged_per_slot(),
            });
        }
        let mask = ring.len() - 1;
        let mut log: Vec<Touched> = (0..new)
            .map(|i| ring[(since as usize).wrapping_add(i) & mask])
            .collect();
        log.sort_unstable_by(|a, b| {
            (a.slot, a.other, a.time.to_bits()).cmp(&(b.slot, b.other, b.time.to_bits()))
        });
        Ok((log, cursor))
    }

    /// The contact log's cursor after the steps queued (see [`Pipeline::contact_log`]);
    /// waits for them. Fails where the world keeps no log.
    pub fn contact_log_cursor(&self) -> Result<u32, Error> {
        match self.device.download(&self.world.scratch.contacts.cursor)?[..] {
            [cursor] => Ok(cursor),
            _ => Err(Error::Invalid(
                "the contact log of a world that keeps none (an audit's world keeps one)".into(),
            )),
        }
    }

    /// The state hash after the steps so far (see [`Snapshot::state_hash`]).
    pub fn state_hash(&self) -> Result<u64, Error> {
        Ok(self.snapshot()?.state_hash())
    }
}

impl Drop for Pipeline<'_> {
    fn drop(&mut self) {
        // Not needed for memory (the plans hold their buffers, and frees are queued behind
        // the steps), but a step's fault is better reported here than lost.
        let _ = self.device.synchronize();
    }
}

/// The explosions' particles as read back: one element each, as [`Particles`] holds them.
#[derive(Clone, Debug, PartialEq)]
pub struct ParticleSnapshot {
    /// Positions, velocities, lives and kinds.
    pub particles: Particles<Vecs>,
    /// How kills burst, with the owning slots.
    pub burst: Burst,
}

impl ParticleSnapshot {
    /// Particles shown (with life left).
    pub fn shown(&self) -> usize {
        self.particles.life.iter().filter(|&&l| l > 0).count()
    }

    /// XXH3-64 of every particle's bytes: equal only if two runs agree bit for bit.
    pub fn hash(&self) -> u64 {
        let mut h = xxhash_rust::xxh3::Xxh3::new();
        let p = &self.particles;
        h.update(bytemuck::cast_slice(&p.pos));
        h.update(bytemuck::cast_slice(&p.vel));
        h.update(bytemuck::cast_slice(&p.life));
        h.update(bytemuck::cast_slice(&p.kind));
        h.digest()
    }
}

/// The game's side of a pipeline: commands up, statuses back, spawn counts.
impl Pipeline<'_> {
    /// The mailbox's shared buffers: the commands the steps read, the statuses they leave
    /// (a ring over them is the host's side, see `Device::ring`).
    pub(crate) fn mailbox(&self) -> Result<(&Buffer<Order>, &Buffer<Status>), Error> {
        let game = self.world.game()?;
        Ok((&game.commands, &game.statuses))
    }

    /// Enemies spawned so far, per kind.
    pub(crate) fn spawned(&self) -> Result<Vec<u32>, Error> {
        self.device.download(&self.world.game()?.data.spawned)
    }

    /// The explosions' particles, read back (waits for the queued steps); `None` for a
    /// world without explosions.
    pub fn particles(&self) -> Result<Option<ParticleSnapshot>, Error> {
        let Some((p, burst)) = self.world.game.as_ref().and_then(|g| g.effects.as_ref()) else {
            return Ok(None);
        };
        Ok(Some(ParticleSnapshot {
            particles: p.convert(&mut self.device.reader())?,
            burst: *burst,
        }))
    }
}
