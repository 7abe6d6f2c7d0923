//! The step pipeline: one ordered list of named stages, written once, that both the
//! simulation-only world ([`Simulation`]) and the game (`crate::game::Game`) configure.
//!
//! A step runs these stages, in order (DESIGN's loop, with the AI after the narrow phase):
//!
//! | stage | launches | in |
//! |---|---|---|
//! | `pilot` | the autopilot, or the player's input passed through (one warp) | games |
//! | `master` | the master before the physics (one warp) | games |
//! | `births` | the enemies the master thread ordered come alive | games |
//! | `broad` | the grid: bucket counts, their prefix sum, placement, canonical order | games, and worlds where something collides |
//! | `narrow` | contacts and their response (`collide_circles` without rectangles) | worlds where something collides |
//! | `think` | every enemy's machine, in one launch over the enemy kinds' slots | games with enemies |
//! | `integrate` | Euler, the boundary rule, deaths | always |
//! | `substeps` | broad, narrow and integrate again for each further substep | worlds with substeps |
//! | `effects` | kills burst into particles, the others move and fade (before `free` rebuilds the flags it reads) | games with explosions |
//! | `free` | the free lists: flags, their prefix sum, gather | always |
//! | `tally` | the master after the physics (one warp) | games |
//!
//! The scene decides which stages exist and which kernels they launch; every step of a
//! scene then launches the same sequence, since per-step choices (who flies, whether a wave
//! is due, whether the game is over) are made on the device. So the sequence is recorded
//! once as a [`Plan`]: on the GPU a CUDA graph on the device's own stream, replayed each
//! step without the host waiting; on the CPU emulation the same ops in order, issued from
//! inside the emulator's pool.
//!
//! State (`sim::state::WorldState`, the game's buffers), scratch (`sim::state::Scratch`)
//! and configuration ([`Config`]) are separate things. The pipeline owns all three, and the
//! plans that view their buffers: that ownership is what makes replaying a plan sound.

pub mod draw;
mod profile;

pub use draw::Frame;
pub use profile::{Profile, StageTimes};

use glam::Vec2;
use gpuwars_kernels::game::ai::ThinkArgs;
use gpuwars_kernels::game::autopilot::AutopilotArgs;
use gpuwars_kernels::game::control::{Command, Input, Status};
use gpuwars_kernels::game::effects::{Burst, EffectsArgs, Particles};
use gpuwars_kernels::game::master::{BirthArgs, MasterArgs};
use gpuwars_kernels::game::rules::{Brain, Rules, Wave};
use gpuwars_kernels::sim::Space;
use gpuwars_kernels::sim::broad::{self, CountArgs, MergeArgs, OrderArgs, PlaceArgs};
use gpuwars_kernels::sim::free_list::{GatherArgs, MarkArgs};
use gpuwars_kernels::sim::integrate::IntegrateArgs;
use gpuwars_kernels::sim::narrow::{CollideArgs, Relaxation};
use gpuwars_kernels::sim::scatter::ScatterArgs;
use gpuwars_kernels::{Kernel, KernelArgs, registry, warp};

use crate::primitives::BLOCK;
use crate::sim::layout::{self, Layout};
use crate::sim::state::{self, Scratch, WorldState};
use crate::sim::{Snapshot, SpecError, WorldSpec};
use crate::{Buffer, Device, Error, Op, Plan};

pub use world::Simulation;

mod world;

/// The stages of a step, in order.
pub const STAGES: [&str; 11] = [
    "pilot",
    "master",
    "births",
    "broad",
    "narrow",
    "think",
    "integrate",
    "substeps",
    "effects",
    "free",
    "tally",
];

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

/// Device bytes of one explosion particle (position, velocity, life, kind).
pub const PARTICLE_BYTES: u64 = 24;

/// The game's buffers on the device.
struct GameState {
    config: GameConfig,
    brains: Buffer<Brain>,
    waves: Buffer<Wave>,
    status: Buffer<Status>,
    command: Buffer<Command>,
    input: Buffer<Input>,
    spawned: Buffer<u32>,
    births: Buffer<u32>,
    birth_speed: Buffer<f32>,
    /// The explosions' particles and how kills burst, if the scene has explosions.
    effects: Option<(ParticleBuffers, Burst)>,
}

/// The explosions' particles on the device.
struct ParticleBuffers {
    pos: Buffer<Vec2>,
    vel: Buffer<Vec2>,
    life: Buffer<u32>,
    kind: Buffer<u32>,
}

impl ParticleBuffers {
    /// `count` particles, none shown.
    fn new(device: &Device, count: u32) -> Result<Self, Error> {
        let n = count as usize;
        Ok(ParticleBuffers {
            pos: device.alloc_zeroed(n)?,
            vel: device.alloc_zeroed(n)?,
            life: device.alloc_zeroed(n)?,
            kind: device.alloc_zeroed(n)?,
        })
    }

    /// The kernels' view of them.
    fn view(&self) -> Particles {
        Particles {
            pos: self.pos.view(),
            vel: self.vel.view(),
            life: self.life.view(),
            kind: self.kind.view(),
        }
    }
}

/// How a world is stepped: what its scene makes it launch, and how.
#[derive(Clone, Copy, Debug)]
pub struct Config {
    /// The narrow phase's kernel, if anything collides.
    collide: Option<Kernel<CollideArgs>>,
    /// Whether the grid is built (something collides, looks around, or the autopilot may fly).
    grid: bool,
}

/// A stage of the step and its plan.
pub struct Stage {
    /// The stage's name (one of [`STAGES`]).
    pub name: &'static str,
    plan: Plan,
}

impl Stage {
    /// Kernel launches per step.
    pub fn launches(&self) -> usize {
        self.plan.launches()
    }

    /// Bytes the stage moves per step, by our count.
    pub fn bytes(&self) -> u64 {
        self.plan.bytes()
    }
}

/// A world on a device, its scratch, its configuration, and the plans of its step.
pub struct Pipeline<'d> {
    // The plans view the buffers below: declared first, so they are dropped first.
    step: Plan,
    stages: Vec<Stage>,
    device: &'d Device,
    spec: WorldSpec,
    layout: Layout,
    space: Space,
    config: Config,
    state: WorldState,
    scratch: Scratch,
    game: Option<GameState>,
    /// The kernel renderer's buffers, made by the first frame drawn.
    canvas: Option<draw::Canvas>,
    /// Steps queued since creation.
    steps: u64,
}

/// Blocks of [`BLOCK`] threads covering `n` threads.
fn grid(n: u32) -> u32 {
    n.div_ceil(BLOCK)
}

/// A launch of one thread per item.
///
/// # Safety
/// As for [`Op::launch`].
unsafe fn op<A: KernelArgs>(kernel: Kernel<A>, items: u32, args: A, bytes_per_item: u64) -> Op {
    // SAFETY: forwarded.
    unsafe {
        Op::launch(
            kernel,
            grid(items),
            BLOCK,
            args,
            bytes_per_item * u64::from(items),
        )
    }
}

impl<'d> Pipeline<'d> {
    /// A world of `spec` with every slot free, its generators seeded from `seed`, and the
    /// game `game` if given. Fails with [`Error::OutOfMemory`] before allocating anything
    /// if its buffers do not fit the device.
    pub fn new(
        device: &'d Device,
        spec: &WorldSpec,
        seed: u32,
        game: Option<GameConfig>,
        graphs: bool,
    ) -> Result<Self, Error> {
        spec.validate().map_err(invalid_world)?;
        let layout = layout::Layout::new(spec);
        let space = layout::space(spec);
        let kinds = spec.kinds.len();
        let mut game = game;
        if let Some(g) = game.as_mut() {
            let slots = g.mind_slots(&layout).unwrap_or((0, 0));
            if let Some(burst) = g.effects.as_mut() {
                (burst.first_slot, burst.end_slot) = slots;
            }
        }
        let particles = game
            .as_ref()
            .and_then(|g| g.effects)
            .map_or(0, |burst| burst.particles());
        device.check_fits(
            &format!(
                "a world of {} slots on a {}x{} grid",
                layout.slots, space.cols, space.rows
            ),
            state::bytes_needed(&layout, &space, kinds) + u64::from(particles) * PARTICLE_BYTES,
        )?;
        let collides = spec.collision_masks().iter().any(|&m| m != 0);
        let config = Config {
            collide: collides.then_some(if spec.has_rects() {
                registry::COLLIDE
            } else {
                // No rectangles: the narrow phase without the rectangle tests.
                registry::COLLIDE_CIRCLES
            }),
            // A game's autopilot looks through the grid whenever it flies.
            grid: collides || game.is_some(),
        };
        let state = WorldState::new(device, spec, &layout, seed)?;
        let scratch = Scratch::new(device, &layout, &space, kinds)?;
        let game = match game {
            Some(config) => Some(GameState {
                effects: match config.effects {
                    Some(burst) => Some((ParticleBuffers::new(device, particles)?, burst)),
                    None => None,
                },
                brains: device.upload(&config.brains)?,
                waves: device.upload(&config.waves)?,
                status: device.alloc_zeroed(1)?,
                command: device.alloc_zeroed(1)?,
                input: device.alloc_zeroed(1)?,
                spawned: device.alloc_zeroed(kinds)?,
                births: device.alloc_zeroed(kinds)?,
                birth_speed: device.alloc_zeroed(kinds)?,
                config,
            }),
            None => None,
        };
        let mut pipeline = Pipeline {
            step: device.plan(Vec::new(), false)?,
            stages: Vec::new(),
            device,
            spec: spec.clone(),
            layout,
            space,
            config,
            state,
            scratch,
            game,
            canvas: None,
            steps: 0,
        };
        let mut all = Vec::new();
        for name in STAGES {
            let ops = pipeline.ops(name);
            if ops.is_empty() {
                continue;
            }
            // The same ops serve the stage's own plan (for the profile) and the whole step.
            all.extend(ops.iter().cloned());
            let plan = device.plan(ops, graphs)?;
            pipeline.stages.push(Stage { name, plan });
        }
        pipeline.step = device.plan(all, graphs)?;
        pipeline.run_stage("free")?;
        device.synchronize()?;
        Ok(pipeline)
    }

    /// The ops of stage `name` for this world (none if it has no such stage).
    fn ops(&self, name: &str) -> Vec<Op> {
        let slots = self.layout.slots;
        let bodies = self.state.bodies();
        let kinds = self.state.kinds.view();
        let ranges = self.state.ranges.view();
        let contacts = self.scratch.contacts();
        let physics = &self.spec.physics;
        let cells = self.scratch.grid(physics.neighbour_cap);
        let space = self.space;
        let master = self.game.as_ref().map(|g| MasterArgs {
            bodies,
            kinds,
            ranges,
            free: self.state.free(),
            contacts,
            status: g.status.view(),
            input: g.input.view(),
            spawned: g.spawned.view(),
            births: g.births.view(),
            birth_speed: g.birth_speed.view(),
            waves: g.waves.view(),
            space,
            rules: g.config.rules,
            reserved: 0,
        });
        let game = self.game.as_ref();
        // SAFETY (every op below): each view is of a buffer owned by this pipeline (its
        // state, scratch or game state), allocated in `new` for the sizes the kernels'
        // contracts ask and never replaced; the plans holding the ops are fields of the
        // pipeline declared before those buffers, so no op outlives them.
        unsafe {
            match name {
                "pilot" => game
                    .map(|g| {
                        let args = AutopilotArgs {
                            bodies,
                            kinds,
                            space,
                            grid: cells,
                            command: g.command.view(),
                            input: g.input.view(),
                            rules: g.config.rules,
                            reserved: 0,
                        };
                        vec![op(registry::AUTOPILOT, warp::WARP, args, 64)]
                    })
                    .unwrap_or_default(),
                "master" => master
                    .map(|m| vec![op(registry::MASTER, warp::WARP, m, 128)])
                    .unwrap_or_default(),
                "births" => match (game, master) {
                    (Some(g), Some(m)) => {
                        let args = BirthArgs {
                            bodies,
                            kinds,
                            ranges,
                            free: m.free,
                            births: g.births.view(),
                            birth_speed: g.birth_speed.view(),
                            space,
                            rules: g.config.rules,
                            reserved: 0,
                        };
                        vec![op(registry::BIRTHS, slots, args, 8)]
                    }
                    _ => Vec::new(),
                },
                "broad" => self.grid_ops(),
                "narrow" => self.narrow_ops(0),
                "think" => game
                    .and_then(|g| g.config.mind_slots(&self.layout).map(|slots| (g, slots)))
                    .map(|(g, (first_slot, end_slot))| {
                        let args = ThinkArgs {
                            bodies,
                            kinds,
                            space,
                            grid: cells,
                            contacts,
                            brains: g.brains.view(),
                            first_slot,
                            end_slot,
                            ship: g.config.rules.ship.start,
                            shot_kind: g.config.rules.shot_kind,
                        };
                        let threads = end_slot - first_slot;
                        vec![op(registry::THINK, threads, args, 56)]
                    })
                    .unwrap_or_default(),
                "integrate" => self.integrate_ops(0),
                "substeps" => (1..physics.substeps)
                    .flat_map(|k| {
                        let mut ops = self.grid_ops();
                        ops.extend(self.narrow_ops(k));
                        ops.extend(self.integrate_ops(k));
                        ops
                    })
                    .collect(),
                "effects" => game
                    .and_then(|g| g.effects.as_ref().map(|e| (g, e)))
                    .filter(|(_, (_, burst))| burst.particles() > 0)
                    .map(|(g, (particles, burst))| {
                        let args = EffectsArgs {
                            bodies,
                            ranges,
                            brains: g.brains.view(),
                            was_free: self.scratch.free.flags.view(),
                            particles: particles.view(),
                            burst: *burst,
                        };
                        vec![op(registry::BURST_AND_FADE, burst.particles(), args, 28)]
                    })
                    .unwrap_or_default(),
                "free" => self.free_ops(),
                "tally" => master
                    .map(|m| vec![op(registry::TALLY, warp::WARP, m, 128)])
                    .unwrap_or_default(),
                _ => Vec::new(),
            }
        }
    }

    /// The narrow phase of substep `substep`, if anything collides.
    ///
    /// # Safety
    /// As in [`Pipeline::ops`].
    unsafe fn narrow_ops(&self, substep: u32) -> Vec<Op> {
        let Some(kernel) = self.config.collide else {
            return Vec::new();
        };
        let physics = &self.spec.physics;
        let args = CollideArgs {
            bodies: self.state.bodies(),
            kinds: self.state.kinds.view(),
            space: self.space,
            grid: self.scratch.grid(physics.neighbour_cap),
            contacts: self.scratch.contacts(),
            relax: Relaxation {
                fraction: physics.relaxation,
                averaged: u32::from(physics.averaged),
            },
            substep,
            reserved: 0,
        };
        // SAFETY: as in `ops`.
        unsafe { vec![op(kernel, self.layout.slots, args, 52)] }
    }

    /// The integrator of substep `substep`.
    ///
    /// # Safety
    /// As in [`Pipeline::ops`].
    unsafe fn integrate_ops(&self, substep: u32) -> Vec<Op> {
        let physics = &self.spec.physics;
        let args = IntegrateArgs {
            bodies: self.state.bodies(),
            kinds: self.state.kinds.view(),
            contacts: self.scratch.contacts(),
            space: self.space,
            field: self.spec.field,
            dt: self.spec.dt / physics.substeps as f32,
            integrator: physics.integrator.code(),
            substep,
            reserved: 0,
        };
        // SAFETY: as in `ops`.
        unsafe { vec![op(registry::INTEGRATE, self.layout.slots, args, 88)] }
    }

    /// The broad phase, if the world has a grid: bucket counts, their prefix sum into
    /// starts, placement, order.
    ///
    /// # Safety
    /// As in [`Pipeline::ops`].
    unsafe fn grid_ops(&self) -> Vec<Op> {
        if !self.config.grid {
            return Vec::new();
        }
        let slots = self.layout.slots;
        let g = &self.scratch.grid;
        let start = g.start.view();
        let count = CountArgs {
            bodies: self.state.bodies(),
            space: self.space,
            keys: g.keys.view(),
            ranks: g.ranks.view(),
            counts: start,
        };
        let place = PlaceArgs {
            keys: g.keys.view(),
            ranks: g.ranks.view(),
            start,
            unordered: g.unordered.view(),
        };
        // With a cap, crowded buckets are ordered in runs and merged, so that their cost
        // stays O(n log n): the passes a bucket of the largest kind's capacity needs.
        let bounded = self.spec.physics.neighbour_cap != 0;
        let order = OrderArgs {
            pos: self.state.bodies.pos.view(),
            keys: g.keys.view(),
            start,
            unordered: g.unordered.view(),
            slots: g.slots.view(),
            entry_pos: g.pos.view(),
            runs: g.ranks.view(),
            bounded: u32::from(bounded),
            reserved: 0,
        };
        let largest = self
            .layout
            .ranges
            .iter()
            .map(|r| r.capacity)
            .max()
            .unwrap_or(0);
        let merges = if bounded {
            largest
                .div_ceil(broad::RUN)
                .next_power_of_two()
                .trailing_zeros()
        } else {
            0
        };
        // SAFETY: as in `ops`; the scan runs in place over the starts.
        unsafe {
            let mut ops = vec![
                Op::clear(start),
                op(registry::COUNT_CELLS, slots, count, 28),
            ];
            ops.extend(
                g.scan
                    .ops(start, start)
                    .expect("the scan was made for the buckets"),
            );
            ops.push(op(registry::PLACE_IN_CELLS, slots, place, 16));
            ops.push(op(registry::ORDER_CELLS, slots, order, 36));
            // The runs go back and forth between the ranks (free after placement) and the
            // arrival-ordered slots (free after ordering).
            let (mut src, mut dst) = (g.ranks.view(), g.unordered.view());
            for pass in 0..merges {
                let merge = MergeArgs {
                    pos: self.state.bodies.pos.view(),
                    start,
                    src,
                    dst,
                    slots: g.slots.view(),
                    entry_pos: g.pos.view(),
                    run: broad::RUN << pass,
                    reserved: 0,
                };
                ops.push(op(registry::MERGE_RUNS, slots, merge, 24));
                (src, dst) = (dst, src);
            }
            ops
        }
    }

    /// The free lists: flags, their prefix sum into ranks, the lists and counts (each kind's
    /// last slot writes its count, so they need no clearing).
    ///
    /// # Safety
    /// As in [`Pipeline::ops`].
    unsafe fn free_ops(&self) -> Vec<Op> {
        let slots = self.layout.slots;
        let f = &self.scratch.free;
        let mark = MarkArgs {
            bodies: self.state.bodies(),
            ranges: self.state.ranges.view(),
            flags: f.flags.view(),
        };
        let gather = GatherArgs {
            kind: self.state.bodies.kind.view(),
            ranges: self.state.ranges.view(),
            flags: f.flags.view(),
            ranks: f.ranks.view(),
            list: self.state.free_list.view(),
            count: self.state.free_count.view(),
        };
        // SAFETY: as in `ops`.
        unsafe {
            let mut ops = vec![op(registry::MARK_FREE, slots, mark, 12)];
            ops.extend(
                f.scan
                    .ops(f.flags.view(), f.ranks.view())
                    .expect("the scan was made for the slots"),
            );
            ops.push(op(registry::GATHER_FREE, slots, gather, 16));
            ops
        }
    }

    /// Runs the plan of stage `name` once (nothing if the world has no such stage).
    fn run_stage(&self, name: &str) -> Result<(), Error> {
        match self.stages.iter().find(|s| s.name == name) {
            Some(stage) => self.device.run(&stage.plan),
            None => Ok(()),
        }
    }

    /// Queues one step: the whole plan, without waiting for it.
    pub fn step(&mut self) -> Result<(), Error> {
        self.device.run(&self.step)?;
        self.steps += 1;
        Ok(())
    }

    /// Runs one step stage by stage, timing each (device events on the GPU, clocks on the
    /// CPU), and adds the times to `profile`. It waits for the step.
    pub fn step_profiled(&mut self, profile: &mut Profile) -> Result<(), Error> {
        let device = self.device;
        let mut marks = vec![device.mark()?];
        for stage in &self.stages {
            device.run(&stage.plan)?;
            marks.push(device.mark()?);
        }
        for (stage, pair) in self.stages.iter().zip(marks.windows(2)) {
            profile.add(stage, pair[1].seconds_since(&pair[0])?);
        }
        profile.steps += 1;
        self.steps += 1;
        Ok(())
    }

    /// Kernel launches per step.
    pub fn launches_per_step(&self) -> usize {
        self.step.launches()
    }

    /// Whether the step replays as a CUDA graph.
    pub fn uses_graphs(&self) -> bool {
        self.step.is_graph()
    }

    /// The slot ranges.
    pub fn layout(&self) -> &Layout {
        &self.layout
    }

    /// The world and grid the kernels use.
    pub fn space(&self) -> &Space {
        &self.space
    }

    /// Steps queued since creation.
    pub fn steps(&self) -> u64 {
        self.steps
    }

    /// The device the world lives on.
    pub fn device(&self) -> &'d Device {
        self.device
    }

    /// The whole state, read back, with `steps` as its step count.
    pub fn snapshot_at(&self, steps: u64) -> Result<Snapshot, Error> {
        self.state
            .snapshot(self.device, steps, &self.scratch.contacts.count)
    }

    /// The game's buffers, or an error for a world without a game.
    fn game(&self) -> Result<&GameState, Error> {
        self.game
            .as_ref()
            .ok_or_else(|| Error::Invalid("this world plays no game".into()))
    }
}

impl Drop for Pipeline<'_> {
    fn drop(&mut self) {
        // Steps may still be queued: let them finish before their graphs and buffers go.
        let _ = self.device.synchronize();
    }
}

/// The explosions' particles as read back: one element each, as [`Particles`] holds them.
#[derive(Clone, Debug, PartialEq)]
pub struct ParticleSnapshot {
    /// World positions.
    pub pos: Vec<Vec2>,
    /// Velocities.
    pub vel: Vec<Vec2>,
    /// Steps left to live (0: not shown).
    pub life: Vec<u32>,
    /// The kind whose death made each.
    pub kind: Vec<u32>,
    /// How kills burst, with the owning slots.
    pub burst: Burst,
}

impl ParticleSnapshot {
    /// Particles shown (with life left).
    pub fn shown(&self) -> usize {
        self.life.iter().filter(|&&l| l > 0).count()
    }

    /// XXH3-64 of every particle's bytes: equal only if two runs agree bit for bit.
    pub fn hash(&self) -> u64 {
        let mut h = xxhash_rust::xxh3::Xxh3::new();
        h.update(bytemuck::cast_slice(&self.pos));
        h.update(bytemuck::cast_slice(&self.vel));
        h.update(bytemuck::cast_slice(&self.life));
        h.update(bytemuck::cast_slice(&self.kind));
        h.digest()
    }
}

/// A world description that breaks a rule, as the backend's error.
fn invalid_world(e: SpecError) -> Error {
    Error::Invalid(format!("invalid world: {e}"))
}

/// The game's side of a pipeline: commands up, statuses back, spawn counts.
impl Pipeline<'_> {
    /// The buffer the step reads its command from.
    pub(crate) fn command(&self) -> Result<&Buffer<Command>, Error> {
        Ok(&self.game()?.command)
    }

    /// The buffer the step leaves its status in.
    pub(crate) fn status(&self) -> Result<&Buffer<Status>, Error> {
        Ok(&self.game()?.status)
    }

    /// Enemies spawned so far, per kind.
    pub(crate) fn spawned(&self) -> Result<Vec<u32>, Error> {
        self.device.download(&self.game()?.spawned)
    }

    /// The kernels' view of the explosions' particles and their lifetime in steps, if the
    /// world has any particles.
    fn particle_view(&self) -> Option<(Particles, u32)> {
        let (p, burst) = self.game.as_ref()?.effects.as_ref()?;
        (burst.particles() > 0).then(|| (p.view(), burst.lifetime))
    }

    /// The explosions' particles, read back (waits for the queued steps); `None` for a
    /// world without explosions.
    pub fn particles(&self) -> Result<Option<ParticleSnapshot>, Error> {
        let Some((p, burst)) = self.game.as_ref().and_then(|g| g.effects.as_ref()) else {
            return Ok(None);
        };
        let d = self.device;
        Ok(Some(ParticleSnapshot {
            pos: d.download(&p.pos)?,
            vel: d.download(&p.vel)?,
            life: d.download(&p.life)?,
            kind: d.download(&p.kind)?,
            burst: *burst,
        }))
    }
}

/// Hand-made worlds for tests and scenarios: bodies brought to life outside a step.
impl Pipeline<'_> {
    /// Number of free slots of each kind.
    pub fn free_counts(&self) -> Result<Vec<u32>, Error> {
        self.device.download(&self.state.free_count)
    }

    /// Brings `count` bodies of kind `kind` to life in its lowest free slots, at uniformly
    /// random positions with normal velocities of deviation `speed` per axis, drawn from
    /// each slot's own generator.
    pub fn scatter(&mut self, kind: usize, count: u32, speed: f32) -> Result<(), Error> {
        let Some(spec) = self.spec.kinds.get(kind) else {
            return Err(Error::Invalid(format!(
                "kind {kind} does not exist (the world has {})",
                self.spec.kinds.len()
            )));
        };
        if !speed.is_finite() || speed < 0.0 {
            return Err(Error::Invalid(format!(
                "scatter speed {speed} (allowed: finite, at least 0)"
            )));
        }
        let free = self.free_counts()?[kind];
        if count > free {
            return Err(Error::Invalid(format!(
                "cannot scatter {count} bodies of kind `{}`: {free} of its {} slots are free",
                spec.name, spec.capacity
            )));
        }
        let start = self.layout.ranges[kind].start;
        let args = ScatterArgs {
            bodies: self.state.bodies(),
            slots: self.state.free_list.view().range(start, count),
            space: self.space,
            speed,
            energy: spec.energy,
        };
        // SAFETY: the views are of this pipeline's buffers, and the op runs (and is
        // dropped) before this borrow of them ends.
        let scatter = unsafe { op(registry::SCATTER, count, args, 0) };
        self.device.run(&self.device.plan(vec![scatter], false)?)?;
        self.run_stage("free")
    }

    /// Brings bodies to life at exact places: `bodies` lists `(slot, position, velocity)`,
    /// and those slots come alive with their kind's energy, no force, and state 0.
    pub fn place(&mut self, bodies: &[(u32, glam::Vec2, glam::Vec2)]) -> Result<(), Error> {
        let mut snapshot = self.snapshot_at(self.steps)?;
        for &(slot, pos, vel) in bodies {
            let Some(kind) = snapshot.kind.get(slot as usize).copied() else {
                return Err(Error::Invalid(format!(
                    "slot {slot} does not exist (the world has {})",
                    self.layout.slots
                )));
            };
            let range = self.layout.ranges[kind as usize];
            if slot >= range.end() {
                return Err(Error::Invalid(format!(
                    "slot {slot} is padding, not a usable slot"
                )));
            }
            let s = slot as usize;
            snapshot.pos[s] = pos;
            snapshot.vel[s] = vel;
            snapshot.force[s] = glam::Vec2::ZERO;
            snapshot.dir[s] = vel.try_normalize().unwrap_or(glam::Vec2::X);
            snapshot.energy[s] = self.spec.kinds[kind as usize].energy;
            snapshot.alive[s] = 1;
            snapshot.state[s] = 0;
            snapshot.age[s] = 0;
        }
        let (d, b) = (self.device, &mut self.state.bodies);
        d.write(&mut b.pos, &snapshot.pos)?;
        d.write(&mut b.vel, &snapshot.vel)?;
        d.write(&mut b.force, &snapshot.force)?;
        d.write(&mut b.dir, &snapshot.dir)?;
        d.write(&mut b.energy, &snapshot.energy)?;
        d.write(&mut b.alive, &snapshot.alive)?;
        d.write(&mut b.state, &snapshot.state)?;
        d.write(&mut b.age, &snapshot.age)?;
        self.run_stage("free")
    }

    /// Sets the force on each listed slot: `(slot, force)`.
    pub fn set_forces(&mut self, forces: &[(u32, glam::Vec2)]) -> Result<(), Error> {
        let mut all = self.device.download(&self.state.bodies.force)?;
        for &(slot, force) in forces {
            let Some(f) = all.get_mut(slot as usize) else {
                return Err(Error::Invalid(format!("slot {slot} does not exist")));
            };
            *f = force;
        }
        self.device.write(&mut self.state.bodies.force, &all)
    }
}
