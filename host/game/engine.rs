//! A game on a device: the pipeline configured with a [`Scene`]'s game (see
//! `crate::pipeline`), and the ring through which commands go up and statuses come back.

use std::collections::VecDeque;

use bytemuck::Zeroable;
use gpuwars_kernels::game::control::{Input, Order, Status};
use gpuwars_kernels::game::effects::Burst;
use gpuwars_kernels::game::rules::{Brain, Rules, Wave};
use gpuwars_kernels::math::Divisor;
use gpuwars_kernels::render::camera::Lens;
use xxhash_rust::xxh3::Xxh3;

use super::looks;
use super::spec::{Behaviour, EffectsSpec, GameSpec, Machine, Scene};
use crate::backend::Ring;
use crate::camera::Camera;
use crate::pipeline::{
    Drawing, Frame, GameConfig, Lanes, Persistent, Pipeline, Profile, bytes_needed, mind_slots,
};
use crate::sim::layout::{Layout, steps};
use crate::sim::{Snapshot, WorldSpec};
use crate::{Device, Error};

/// How a game runs on its device.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Options {
    /// Steps that may be in flight before the host reads a status back (1: it waits for
    /// every step).
    pub lag: usize,
    /// Record the step as a CUDA graph (on the GPU).
    pub graphs: bool,
    /// Threads a body's neighbour queries get (speed only: the results are the same).
    pub lanes: Lanes,
    /// Whether the step runs as one persistent launch (speed only: the results are the
    /// same).
    pub persistent: Persistent,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            lag: 4,
            graphs: true,
            lanes: Lanes::Auto,
            persistent: Persistent::Auto,
        }
    }
}

/// A game in progress on a device.
pub struct Game<'d> {
    /// The host's side of the mailbox the steps read their commands from and post their
    /// statuses to.
    ring: Ring<Order, Status>,
    pipeline: Pipeline<'d>,
    scene: Scene,
    /// Statuses read back and not yet handed out, oldest first.
    arrived: VecDeque<Status>,
    last: Status,
}

/// The world a game of `scene` runs in. The enemies and the autopilot look through the
/// grid: its cells must be as large as the farthest sight.
fn game_world(scene: &Scene) -> WorldSpec {
    let mut world = scene.world.clone();
    let enemies = scene
        .game
        .behaviours
        .iter()
        .flatten()
        .map(|b| vision(scene, b));
    world.vision = enemies.fold(world.vision.max(scene.game.ship.autopilot_sight), f32::max);
    world
}

/// How far an enemy of behaviour `b` sees: its vision scaled by the scene's physics.
fn vision(scene: &Scene, b: &Behaviour) -> f32 {
    b.vision * scene.world.physics.vision_scale
}

/// The slots of a game of `scene` (padding included) and the bytes of device memory its
/// world takes: what [`Game::new`] checks against the device's free memory before it
/// allocates anything.
pub fn footprint(scene: &Scene) -> (u32, u64) {
    let world = game_world(scene);
    let particles = u32::try_from(particles(&world, &scene.game)).unwrap_or(u32::MAX);
    let game = (particles, waves(scene).len());
    let bytes = bytes_needed(&world, Some(game));
    (Layout::new(&world).slots, bytes)
}

/// How many explosion particles a game of `world` and `game` has: every enemy slot (from
/// the first kind with a machine to the last, padding included) owns a kill's worth.
pub(crate) fn particles(world: &WorldSpec, game: &GameSpec) -> u64 {
    let Some(effects) = &game.effects else {
        return 0;
    };
    let machines: Vec<bool> = (game.behaviours.iter())
        .map(|b| b.is_some_and(|b| b.machine != Machine::None))
        .collect();
    let owners = mind_slots(&Layout::new(world), &machines).map_or(0, |(first, end)| end - first);
    u64::from(owners) * u64::from(effects.particles)
}

/// The rules of `scene` in the kernels' terms (steps instead of seconds, kind indices).
fn rules(scene: &Scene, layout: &Layout) -> Rules {
    let (world, game) = (&scene.world, &scene.game);
    let dt = world.dt;
    let kind = |name: &str| world.kind_index(name).expect("validated scene") as u32;
    let ship_kind = kind(&game.ship.kind);
    let ship_energy = world.kinds[ship_kind as usize].energy;
    // FPS per second → energy points per second → steps per point.
    let points_per_second = game.fps.recovery * ship_energy as f32 / game.fps.start;
    Rules {
        ship_kind,
        shot_kind: kind(&game.ship.shot),
        ship: layout.ranges[ship_kind as usize],
        shots: layout.ranges[kind(&game.ship.shot) as usize],
        ship_speed: game.ship.speed,
        shot_speed: game.ship.shot_speed,
        fire_period: steps(1.0 / game.ship.fire_rate, dt),
        recover_every: steps(1.0 / points_per_second, dt),
        ship_energy,
        fps_start: game.fps.start,
        fps_min: game.fps.min,
        spawn_distance: game.spawn.distance,
        autopilot_sight: game.ship.autopilot_sight,
    }
}

/// The spawn schedule in steps.
fn waves(scene: &Scene) -> Vec<Wave> {
    let (world, dt) = (&scene.world, scene.world.dt);
    scene
        .game
        .spawn
        .waves
        .iter()
        .map(|w| {
            let first = (w.at / dt).round() as u32;
            let every = w.every.map_or(0, |every| steps(every, dt));
            Wave {
                kind: world.kind_index(&w.kind).expect("validated scene") as u32,
                count: w.count,
                first,
                every,
                last: first.saturating_add(every.saturating_mul(w.times - 1)),
                speed: w.speed,
            }
        })
        .collect()
}

/// How kills burst, in the kernels' terms; the slots owning particles are the pipeline's.
fn burst(effects: &EffectsSpec, dt: f32) -> Burst {
    Burst {
        per_kill: Divisor::new(effects.particles),
        lifetime: steps(effects.lifetime, dt),
        speed: effects.speed,
        // The fraction kept after a second, spread over its steps.
        keep: effects.speed_kept.powf(dt),
        dt,
        first_slot: 0,
        end_slot: 0,
    }
}

/// Each kind's brain; kinds without a behaviour get machine 0 (none).
fn brains(scene: &Scene) -> Vec<Brain> {
    let dt = scene.world.dt;
    scene
        .game
        .behaviours
        .iter()
        .enumerate()
        .map(|(k, behaviour)| match *behaviour {
            Some(b) if b.machine != Machine::None => Brain {
                machine: b.machine as u32,
                kind: k as u32,
                vision: vision(scene, &b),
                speed: b.speed,
                low_energy: b.low_energy,
                recover_every: steps(1.0 / b.recovery, dt),
                avoid_bullets: u32::from(b.avoid_bullets),
                sight_budget: scene.world.physics.sight_budget,
            },
            _ => Brain {
                kind: k as u32,
                ..Brain::zeroed()
            },
        })
        .collect()
}

impl<'d> Game<'d> {
    /// A new game of `scene` (validated by the scene loader) with generators seeded from
    /// `seed`; the ship is born on the first step.
    pub fn new(device: &'d Device, scene: &Scene, seed: u32) -> Result<Self, Error> {
        Self::with_options(device, scene, seed, Options::default())
    }

    /// A new game, run as `options` say.
    pub fn with_options(
        device: &'d Device,
        scene: &Scene,
        seed: u32,
        options: Options,
    ) -> Result<Self, Error> {
        let world = game_world(scene);
        let layout = Layout::new(&world);
        let game = GameConfig {
            rules: rules(scene, &layout),
            brains: brains(scene),
            waves: waves(scene),
            effects: scene
                .game
                .effects
                .as_ref()
                .map(|e| burst(e, scene.world.dt)),
            in_flight: options.lag,
        };
        let pipeline = Pipeline::configured(
            device,
            &world,
            seed,
            Some(game),
            (options.graphs, options.lanes, options.persistent),
        )?;
        let (commands, statuses) = pipeline.mailbox()?;
        Ok(Game {
            ring: device.ring(commands, statuses)?,
            pipeline,
            scene: scene.clone(),
            arrived: VecDeque::new(),
            last: Status::default(),
        })
    }

    /// The scene being played.
    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    /// The world and its step pipeline.
    pub fn pipeline(&self) -> &Pipeline<'d> {
        &self.pipeline
    }

    /// The world's drawing (its renderers keep their buffers in the pipeline): the game's
    /// steps go through its ring only, so nothing that draws can step it.
    pub fn drawing(&mut self) -> Drawing<'_, 'd> {
        self.pipeline.drawing()
    }

    /// The latest status read back.
    pub fn status(&self) -> Status {
        self.last
    }

    /// Queues one step with `input`, or with the autopilot's when `None`, without waiting
    /// for it. The statuses of earlier steps that had to be read back to make room are
    /// kept for [`Game::next_status`].
    pub fn submit(&mut self, input: Option<Input>) -> Result<(), Error> {
        self.queue(input, Queued::Step)
    }

    /// As [`Game::submit`], with the frame [`Game::render`] draws of the world before the
    /// step drawn beside it (see [`Pipeline::render_beside_step`]): on the GPU a step and a
    /// frame then cost about the longer of the two, not their sum.
    pub fn submit_beside_frame(
        &mut self,
        input: Option<Input>,
        (width, height): (u32, u32),
        camera: &Camera,
    ) -> Result<(), Error> {
        let lens = self.lens(camera, width, height, 0.0);
        self.queue(input, Queued::BesideFrame(&lens))
    }

    /// As [`Game::submit`], stage by stage, timing each stage into `profile` (waits for
    /// the step).
    pub fn submit_profiled(
        &mut self,
        input: Option<Input>,
        profile: &mut Profile,
    ) -> Result<(), Error> {
        self.queue(input, Queued::Profiled(profile))
    }

    fn queue(&mut self, input: Option<Input>, queued: Queued) -> Result<(), Error> {
        let command = match input {
            Some(input) => {
                if let Some((field, allowed)) = input.problem() {
                    return Err(Error::Invalid(format!(
                        "input {field} is out of range (allowed {allowed}): {input:?}"
                    )));
                }
                Order::input(input)
            }
            None => Order::autopilot(),
        };
        // One count of the steps: the kernels find each step's slot of the ring by theirs,
        // which is the pipeline's.
        if self.ring.queued() != self.pipeline.steps() {
            return Err(Error::Invalid(format!(
                "the game's ring queued {} steps and its world took {}",
                self.ring.queued(),
                self.pipeline.steps()
            )));
        }
        if let Some(status) = self.ring.reserve(self.pipeline.device())? {
            self.arrived.push_back(status);
        }
        let device = self.pipeline.device();
        self.ring.send(device, command)?;
        match queued {
            Queued::Step => self.pipeline.step()?,
            Queued::Profiled(profile) => self.pipeline.step_profiled(profile)?,
            Queued::BesideFrame(lens) => {
                let looks = looks::looks(&self.scene);
                self.pipeline.render_beside_step(lens, &looks)?
            }
        }
        self.ring.receive(device)
    }

    /// The status of the oldest step not yet handed out, waiting for it if it is still in
    /// flight; `None` when every queued step's status has been handed out.
    pub fn next_status(&mut self) -> Result<Option<Status>, Error> {
        let status = match self.arrived.pop_front() {
            Some(status) => Some(status),
            None => self.ring.oldest(self.pipeline.device())?,
        };
        status.map(|status| self.hand_out(status)).transpose()
    }

    /// The status of a step that [`Game::submit`] already made room for, without waiting.
    pub fn ready_status(&mut self) -> Result<Option<Status>, Error> {
        let status = self.arrived.pop_front();
        status.map(|status| self.hand_out(status)).transpose()
    }

    /// `status`, the next step's, as handed out, once the device's count of the steps is
    /// checked against the host's: each status of a game under way counts one step more
    /// than the one before (the tally's count, which the kernels find their ring slots by),
    /// and once the game is over the status stays.
    fn hand_out(&mut self, status: Status) -> Result<Status, Error> {
        let expected = self.last.step.saturating_add(1);
        if !self.last.is_over() && status.step != expected {
            return Err(Error::Invalid(format!(
                "the device tallied step {} where the ring's count makes it {expected}",
                status.step
            )));
        }
        self.last = status;
        Ok(status)
    }

    /// Plays one step with `input`, or with the autopilot's when `None`, and returns its
    /// status (waits for it, and hands out every earlier status first).
    pub fn step(&mut self, input: Option<Input>) -> Result<Status, Error> {
        self.submit(input)?;
        self.settle()?;
        Ok(self.last)
    }

    /// Waits for every queued step and takes the last status.
    fn settle(&mut self) -> Result<(), Error> {
        while self.next_status()?.is_some() {}
        Ok(())
    }

    /// The whole state of the world, read back after every queued step. Its step count is
    /// the steps the game played (steps queued after the game ended change nothing).
    pub fn snapshot(&mut self) -> Result<Snapshot, Error> {
        self.settle()?;
        let mut snapshot = self.pipeline.snapshot()?;
        snapshot.steps = u64::from(self.last.step);
        Ok(snapshot)
    }

    /// What the device is asked for a `width × height` frame through `camera`, `dt`
    /// seconds after the previous frame (0 snaps the view to the ship).
    pub fn lens(&self, camera: &Camera, width: u32, height: u32, dt: f32) -> Lens {
        let (field, ship) = (self.scene.world.size, self.pipeline.ship());
        camera.lens(field, (width, height), ship, dt, looks::BACKGROUND)
    }

    /// The world after every queued step as `camera` shows it (snapped to the ship), drawn
    /// by the kernel renderer in a `width × height` frame.
    pub fn draw(&mut self, width: u32, height: u32, camera: &Camera) -> Result<Frame, Error> {
        self.settle()?;
        self.render(width, height, camera, 0.0)?;
        self.pipeline.frame()
    }

    /// Queues the drawing of the world after the queued steps, as `camera` shows it
    /// `frame_dt` seconds after the previous frame (0 snaps the view), left in device
    /// memory (see [`Pipeline::render`]).
    pub fn render(
        &mut self,
        width: u32,
        height: u32,
        camera: &Camera,
        frame_dt: f32,
    ) -> Result<(), Error> {
        let lens = self.lens(camera, width, height, frame_dt);
        self.pipeline.render(&lens, &looks::looks(&self.scene))
    }

    /// As [`Game::render`], the pixels written into `image` (see [`Pipeline::render_into`]).
    ///
    /// # Safety
    /// As for [`Pipeline::render_into`].
    pub unsafe fn render_into(
        &mut self,
        width: u32,
        height: u32,
        camera: &Camera,
        frame_dt: f32,
        image: gpuwars_kernels::DevSlice<u32>,
    ) -> Result<(), Error> {
        let lens = self.lens(camera, width, height, frame_dt);
        // SAFETY: forwarded.
        unsafe {
            self.pipeline
                .render_into(&lens, &looks::looks(&self.scene), image)
        }
    }

    /// XXH3-64 over the world's state hash, the status and the spawn counts: equal only if
    /// two games agree bit for bit.
    pub fn state_hash(&mut self) -> Result<u64, Error> {
        let world = self.snapshot()?.state_hash();
        let mut h = Xxh3::new();
        h.update(&world.to_le_bytes());
        h.update(bytemuck::bytes_of(&self.last));
        h.update(bytemuck::cast_slice(&self.pipeline.spawned()?));
        Ok(h.digest())
    }
}

/// How [`Game::queue`] queues its step.
enum Queued<'a> {
    /// The step alone.
    Step,
    /// Stage by stage, timed into the profile.
    Profiled(&'a mut Profile),
    /// With the frame of this lens beside it.
    BesideFrame(&'a Lens),
}
