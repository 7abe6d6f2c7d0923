//! A game on a device: the world of a [`Scene`], the master thread's state, and the order in
//! which a game step's kernels run (see `gpuwars_kernels::game`).

use gpuwars_kernels::game::ai::ThinkArgs;
use gpuwars_kernels::game::autopilot::AutopilotArgs;
use gpuwars_kernels::game::control::{Input, Status};
use gpuwars_kernels::game::fsm::Machine;
use gpuwars_kernels::game::master::{BirthArgs, MasterArgs};
use gpuwars_kernels::game::rules::{Brain, Rules, Wave};
use gpuwars_kernels::sim::SlotRange;
use gpuwars_kernels::{Kernel, registry};
use xxhash_rust::xxh3::Xxh3;

use super::spec::Scene;
use crate::sim::layout::steps;
use crate::sim::{Simulation, Snapshot};
use crate::{Buffer, Device, Error};

/// One enemy kind's AI launch: its slots, its brain, its machine's kernel.
struct Mind {
    range: SlotRange,
    brain: Brain,
    kernel: Kernel<ThinkArgs>,
}

/// A game in progress on a device.
pub struct Game<'d> {
    sim: Simulation<'d>,
    scene: Scene,
    rules: Rules,
    minds: Vec<Mind>,
    waves: Vec<Wave>,
    wave_table: Buffer<Wave>,
    status: Buffer<Status>,
    input: Buffer<Input>,
    spawned: Buffer<u32>,
    births: Buffer<u32>,
    birth_speed: Buffer<f32>,
    last: Status,
}

/// The rules of `scene` in the kernels' terms (steps instead of seconds, kind indices).
fn rules(scene: &Scene, sim: &Simulation) -> Rules {
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
        ship: sim.layout().ranges[ship_kind as usize],
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

/// One AI launch per kind with a behaviour.
fn minds(scene: &Scene, sim: &Simulation) -> Vec<Mind> {
    let dt = scene.world.dt;
    scene
        .world
        .kinds
        .iter()
        .enumerate()
        .filter_map(|(k, kind)| {
            let b = kind.behaviour?;
            let kernel = match b.machine {
                Machine::None => return None,
                Machine::Kamikaze => registry::THINK_KAMIKAZE,
                Machine::Group => registry::THINK_GROUP,
                Machine::Tricky => registry::THINK_TRICKY,
            };
            Some(Mind {
                range: sim.layout().ranges[k],
                brain: Brain {
                    machine: b.machine as u32,
                    kind: k as u32,
                    vision: b.vision,
                    speed: b.speed,
                    low_energy: b.low_energy,
                    recover_every: steps(1.0 / b.recovery, dt),
                    avoid_bullets: u32::from(b.avoid_bullets),
                    reserved: 0,
                },
                kernel,
            })
        })
        .collect()
}

impl<'d> Game<'d> {
    /// A new game of `scene` (validated by the scene loader) with generators seeded from
    /// `seed`; the ship is born on the first step.
    pub fn new(device: &'d Device, scene: &Scene, seed: u32) -> Result<Self, Error> {
        let mut world = scene.world.clone();
        // The autopilot looks through the grid too.
        world.vision = world.vision.max(scene.game.ship.autopilot_sight);
        let sim = Simulation::new(device, &world, seed)?;
        let kinds = world.kinds.len();
        let rules = rules(scene, &sim);
        let minds = minds(scene, &sim);
        let waves = waves(scene);
        Ok(Game {
            wave_table: device.upload(&waves)?,
            status: device.alloc_zeroed(1)?,
            input: device.alloc_zeroed(1)?,
            spawned: device.alloc_zeroed(kinds)?,
            births: device.alloc_zeroed(kinds)?,
            birth_speed: device.alloc_zeroed(kinds)?,
            last: Status::default(),
            scene: scene.clone(),
            sim,
            rules,
            minds,
            waves,
        })
    }

    /// The scene being played.
    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    /// The world underneath.
    pub fn simulation(&self) -> &Simulation<'d> {
        &self.sim
    }

    /// The status after the last step.
    pub fn status(&self) -> Status {
        self.last
    }

    /// The master thread's arguments.
    fn master_args(&self) -> MasterArgs {
        let v = self.sim.views();
        MasterArgs {
            bodies: v.bodies,
            kinds: v.kinds,
            ranges: v.ranges,
            free: v.free,
            contacts: v.contacts,
            status: self.status.view(),
            input: self.input.view(),
            spawned: self.spawned.view(),
            births: self.births.view(),
            birth_speed: self.birth_speed.view(),
            waves: self.wave_table.view(),
            space: *self.sim.space(),
            rules: self.rules,
        }
    }

    /// Plays one step with `input`, or with the autopilot's when `None`, and returns the
    /// status read back after it.
    pub fn step(&mut self, input: Option<Input>) -> Result<Status, Error> {
        let device = self.sim.device();
        let v = self.sim.views();
        let space = *self.sim.space();
        match input {
            Some(input) => {
                if let Some((field, allowed)) = input.problem() {
                    return Err(Error::Invalid(format!(
                        "input {field} is out of range (allowed {allowed}): {input:?}"
                    )));
                }
                device.write(&mut self.input, &[input])?;
            }
            None => {
                let args = AutopilotArgs {
                    bodies: v.bodies,
                    kinds: v.kinds,
                    space,
                    grid: v.grid,
                    input: self.input.view(),
                    rules: self.rules,
                };
                self.sim.launch(registry::AUTOPILOT, 1, &args)?;
            }
        }
        let master = self.master_args();
        self.sim.launch(registry::MASTER, 1, &master)?;
        let step = self.sim.steps() as u32;
        if !self.last.is_over() && self.waves.iter().any(|w| w.due(step)) {
            let births = BirthArgs {
                bodies: v.bodies,
                kinds: v.kinds,
                ranges: v.ranges,
                free: v.free,
                births: self.births.view(),
                birth_speed: self.birth_speed.view(),
                space,
                rules: self.rules,
            };
            self.sim
                .launch(registry::BIRTHS, self.sim.layout().slots, &births)?;
        }
        // The grid serves the contacts, the enemies' vision and the autopilot's (next step).
        if self.sim.collides() || !self.minds.is_empty() || input.is_none() {
            self.sim.build_grid()?;
        }
        if self.sim.collides() {
            self.sim.collide()?;
        }
        for mind in &self.minds {
            let args = ThinkArgs {
                bodies: v.bodies,
                kinds: v.kinds,
                space,
                grid: v.grid,
                contacts: v.contacts,
                range: mind.range,
                brain: mind.brain,
                ship: self.rules.ship.start,
                shot_kind: self.rules.shot_kind,
            };
            self.sim.launch(mind.kernel, mind.range.capacity, &args)?;
        }
        self.sim.finish_step()?;
        self.sim.launch(registry::TALLY, 1, &master)?;
        self.last = device.download(&self.status)?[0];
        Ok(self.last)
    }

    /// The whole state of the world, read back.
    pub fn snapshot(&self) -> Result<Snapshot, Error> {
        self.sim.snapshot()
    }

    /// XXH3-64 over the world's state hash, the status and the spawn counts: equal only if
    /// two games agree bit for bit.
    pub fn state_hash(&self) -> Result<u64, Error> {
        let device = self.sim.device();
        let mut h = Xxh3::new();
        h.update(&self.sim.state_hash()?.to_le_bytes());
        // `last` is the device's status as read back after the step.
        h.update(bytemuck::bytes_of(&self.last));
        h.update(bytemuck::cast_slice(&device.download(&self.spawned)?));
        Ok(h.digest())
    }
}
