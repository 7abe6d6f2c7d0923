//! The world's data on a device: its description, its state and scratch buffers, and the
//! game's. The stages' ops view these buffers; each op holds those it views.
//!
//! Every buffer is allocated once in [`World::new`] for the sizes the kernels' contracts
//! ask (a slot's arrays for every slot, a bucket's for every bucket plus the total, a
//! kind's for every kind) and never replaced, which is what each stage's `SAFETY` note
//! relies on.

use gpuwars_kernels::access::Access;
use gpuwars_kernels::data::{Sizes, Unmade, View};
use gpuwars_kernels::game::GameData;
use gpuwars_kernels::game::control::{Mailbox, Order, Status};
use gpuwars_kernels::game::effects::{Burst, Particles, ParticlesAccess};
use gpuwars_kernels::game::master::{BirthArgs, MasterArgs, TallyArgs};
use gpuwars_kernels::registry;
use gpuwars_kernels::sim::broad::CellIndex;
use gpuwars_kernels::sim::free_list;
use gpuwars_kernels::sim::narrow::CollideArgs;
use gpuwars_kernels::sim::teams::Teams;
use gpuwars_kernels::sim::{Deaths, Space};
use gpuwars_kernels::{DevSlice, Kernel};

use super::GameConfig;
use super::teams::{self, Lanes};
use crate::Buffer;
use crate::backend::{Binder, Buffers};
use crate::sim::layout::{self, Layout};
use crate::sim::state::{self, Extras, Scratch, WorldState, made};
use crate::sim::{SpecError, WorldSpec};
use crate::{Device, Error};

/// What a world's scene makes its step launch.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Config {
    /// The narrow phase's kernel, if anything collides.
    pub collide: Option<Kernel<CollideArgs>>,
    /// Whether a pair of kinds is swept, so that the narrow phase runs its swept kernels.
    pub swept: bool,
    /// Whether the narrow phase logs every contact it counts (`Physics::trace_paths`), so
    /// that it runs its logged kernels: the others carry no log's code.
    pub logged: bool,
    /// Whether the grid is built (something collides, looks around, or the autopilot may fly).
    pub grid: bool,
    /// The narrow phase's threads per body of each kind.
    pub narrow_teams: Teams,
    /// The machines' threads per body of each kind, if a kind has a machine; where the
    /// bodies take their step in one launch, every kind's (a kind with a machine keeping
    /// its machine's width, the others taking their narrow phase's: see `Teams::within`).
    pub think_teams: Option<Teams>,
    /// Whether the machines' own launch takes its blocks from the last (see
    /// `teams::think_from_the_end`): on the GPU only, whose blocks start in order. The CPU
    /// emulation, whose workers walk the slots' arrays block after block, lost 17% at a
    /// million enemies taken from the end (`scale-1m` 9.86 -> 8.16 steps/s on 2 threads).
    pub think_from_the_end: bool,
    /// Whether the integrator's first launch, just after the machines' own, does: the
    /// other way from it, so that it starts on the slots they touched last (the GPU's
    /// only, likewise).
    pub integrate_from_the_end: bool,
    /// Whether one launch runs the narrow phase, the machines and the integrator
    /// (`collide_think_integrate`), whose grid then keeps its entries' velocities: in games
    /// of circles of at most [`ONE_LAUNCH_SLOTS`] slots whose machines run in teams (on the
    /// GPU), where it saves two launches on the step's chain. The `narrow` and `integrate`
    /// stages then launch nothing in the first substep.
    pub one_launch: bool,
    /// Whether the enemies the master ordered come alive in the grid's count
    /// (`births_and_count`, one launch fewer) rather than in a launch of their own: in
    /// games of at most [`ONE_LAUNCH_SLOTS`] slots. In larger ones the count's millions of
    /// threads would carry the births' registers for nothing (16.76 million slots: 2.5%
    /// slower a step on an H200).
    pub births_in_count: bool,
    /// Every how many steps the bodies move to slots in the grid's order (0: never).
    pub renumber_every: u32,
    /// Whether the free lists are rebuilt in one launch (`mark_and_gather_free`): where
    /// every range is small enough, on the GPU, and on the CPU in tiny worlds only. Its
    /// warps count their range's free slots before them redundantly, which costs the GPU's
    /// idle lanes little but the CPU emulation, where each thread counts for all 32 lanes,
    /// far more than the scan once a world has more than a few warps.
    pub free_in_one_launch: bool,
    /// Whether the integrator marks the slots whose freedom it changes, so that a game's
    /// step that does not renumber rebuilds its free lists without a launch that marks
    /// every slot (`free_list::Marks`): in games whose integrator has a launch of its own
    /// and whose free lists are not rebuilt in one launch.
    pub marks_in_integrate: bool,
}

/// The most slots of a world whose bodies may take their step (but the grid) in one launch
/// (see `Config::one_launch`); larger worlds run their machines one thread a body, whose
/// registers the narrow phase and the integrator would crowd.
pub const ONE_LAUNCH_SLOTS: u32 = 1 << 18;

/// The most slots of a world whose free lists the CPU emulation rebuilds in one launch (see
/// `Config::free_in_one_launch`): a few warps, whose redundant counts cost less than two
/// more launches.
const CPU_ONE_LAUNCH_SLOTS: u32 = 1024;

/// The game's buffers on the device.
pub(crate) struct GameState {
    pub config: GameConfig,
    pub data: GameData<Buffers>,
    /// The mailbox's commands and statuses, one per step in flight, in shared memory.
    pub commands: Buffer<Order>,
    pub statuses: Buffer<Status>,
    /// The explosions' particles and how kills burst, if the scene has explosions.
    pub effects: Option<(Particles<Buffers>, Burst)>,
}

/// The warp tables (`Teams::warp_table`) of the launches whose bodies get teams: none where
/// every body gets one thread.
pub(crate) struct TeamWarps {
    /// The narrow phase's (`Config::narrow_teams`).
    pub narrow: Option<Buffer<u32>>,
    /// The machines' (`Config::think_teams`), or the bodies' step's where it is one launch.
    pub think: Option<Buffer<u32>>,
}

impl TeamWarps {
    /// The teams of `config` that need a table.
    fn teamed(config: &Config) -> [Option<Teams>; 2] {
        [Some(config.narrow_teams), config.think_teams].map(|t| t.filter(|t| !t.single()))
    }

    /// The tables of `config`'s teams over the slot ranges of `layout`, on `device`.
    fn new(device: &Device, config: &Config, layout: &Layout) -> Result<Self, Error> {
        let [narrow, think] = Self::teamed(config).map(|teams| {
            teams.map(|teams| {
                let table: Vec<u32> = teams.warp_table(&layout.ranges).collect();
                device.upload(&table)
            })
        });
        Ok(TeamWarps {
            narrow: narrow.transpose()?,
            think: think.transpose()?,
        })
    }

    /// Bytes the tables of `config`'s teams take: a word a warp (at most a few tens of
    /// kilobytes: teams are given only where their threads fit the GPU at once).
    fn bytes(config: &Config, layout: &Layout) -> u64 {
        let teamed = Self::teamed(config).into_iter().flatten();
        teamed
            .map(|teams| 4 * teams.threads(&layout.ranges) / 32)
            .sum()
    }

    /// The view of `table`, made by `b`; empty where there is none.
    pub fn view<A: Access>(b: &mut Binder, table: &Option<Buffer<u32>>) -> DevSlice<u32, A> {
        table
            .as_ref()
            .map_or(DevSlice::EMPTY, |table| b.view(table))
    }
}

/// A world on a device: description, buffers, and the game's if it plays one.
pub(crate) struct World {
    pub spec: WorldSpec,
    pub layout: Layout,
    pub space: Space,
    pub config: Config,
    pub state: WorldState,
    pub scratch: Scratch,
    pub warps: TeamWarps,
    pub game: Option<GameState>,
}

/// Bytes of device memory a world of `spec` takes, with a game of `waves` waves whose
/// explosions have `particles` particles, if `game` is `Some((particles, waves))`; on a GPU
/// that gives its bodies teams, a few tens of kilobytes more for their warp tables.
pub fn bytes_needed(spec: &WorldSpec, game: Option<(u32, usize)>) -> u64 {
    let layout = Layout::new(spec);
    let kinds = spec.kinds.len();
    let mut sizes = Sizes::default();
    if let Some((particles, waves)) = game {
        let burst_slots = burst_slots(&layout, particles);
        made(GameData::<Unmade>::build(
            &mut sizes,
            kinds,
            waves,
            burst_slots,
        ));
        made(Particles::<Unmade>::build(&mut sizes, particles as usize));
    }
    let plays = game.is_some();
    let extras = Extras {
        renumbers: renumber_every(spec, &layout, plays) != 0,
        moving: moves_in_one_launch(spec, &layout, plays),
        traces: spec.traces(),
        logs: spec.physics.logged_per_slot(),
    };
    state::bytes_needed(&layout, &layout::space(spec), kinds, extras) + sizes.bytes
}

/// The slots whose deaths a game counts for its explosions (`GameData::slot_deaths`): every
/// slot where kills burst into `particles` particles, none without explosions.
fn burst_slots(layout: &Layout, particles: u32) -> usize {
    if particles > 0 {
        layout.slots as usize
    } else {
        0
    }
}

/// Whether a world of `spec` builds the grid: something collides, or a game's autopilot may
/// look through it.
fn builds_grid(spec: &WorldSpec, plays: bool) -> bool {
    plays || spec.collision_masks().iter().any(|&m| m != 0)
}

/// Whether a world of `spec` may move its bodies in the launch that queries its grid (see
/// `Config::one_launch`), and so its grid keeps its entries' velocities: a game (`plays`)
/// of circles, something colliding, of at most [`ONE_LAUNCH_SLOTS`] slots.
fn moves_in_one_launch(spec: &WorldSpec, layout: &Layout, plays: bool) -> bool {
    plays
        && !spec.has_rects()
        && spec.collision_masks().iter().any(|&m| m != 0)
        && layout.slots <= ONE_LAUNCH_SLOTS
}

/// Every how many steps a world renumbers its bodies (0: never): as its physics says, in
/// worlds with a grid, whose order it takes.
fn renumber_every(spec: &WorldSpec, layout: &Layout, plays: bool) -> u32 {
    if builds_grid(spec, plays) {
        spec.physics.renumber_period(layout.slots)
    } else {
        0
    }
}

impl World {
    /// A world of `spec` with every slot free, its generators seeded from `seed`, and the
    /// game `game` if given. Fails with [`Error::OutOfMemory`] before allocating anything
    /// if its buffers do not fit the device.
    pub fn new(
        device: &Device,
        spec: &WorldSpec,
        seed: u32,
        game: Option<GameConfig>,
        lanes: Lanes,
    ) -> Result<Self, Error> {
        spec.validate().map_err(invalid_world)?;
        let layout = Layout::new(spec);
        let space = layout::space(spec);
        let kinds = spec.kinds.len();
        let mut game = game;
        if let Some(g) = game.as_mut() {
            let slots = g.mind_slots(&layout).unwrap_or((0, 0));
            if let Some(burst) = g.effects.as_mut() {
                (burst.first_slot, burst.end_slot) = slots;
            }
        }
        let sized = game
            .as_ref()
            .map(|g| (g.effects.map_or(0, |b| b.particles()), g.waves.len()));
        let collides = spec.collision_masks().iter().any(|&m| m != 0);
        // Threads the GPU holds at once: teams only fill lanes that would otherwise idle.
        let resident = device
            .gpu_properties()
            .map(|p| u64::from(p.multiprocessors) * u64::from(p.threads_per_multiprocessor));
        let think_teams = game
            .as_ref()
            .and_then(|g| teams::think(lanes, resident, g, &layout, &space));
        let moving = moves_in_one_launch(spec, &layout, game.is_some());
        let narrow_teams = teams::narrow(lanes, resident, spec, &layout, &space);
        let one_launch = moving && think_teams.is_some_and(|teams| !teams.single());
        let free_in_one_launch = (resident.is_some() || layout.slots <= CPU_ONE_LAUNCH_SLOTS)
            && (layout.ranges.iter()).all(|r| r.capacity <= free_list::ONE_LAUNCH_RANGE);
        let (think_from_the_end, integrate_from_the_end) =
            match (resident, one_launch, think_teams, &game) {
                (Some(_), false, Some(teams), Some(game)) => {
                    let think = teams::think_from_the_end(&teams, game, &layout, &space);
                    (think, !think)
                }
                _ => (false, false),
            };
        // Only worlds with a swept pair run the swept narrow phase, and only audit runs the
        // logged one.
        let swept = spec.has_swept_pairs();
        let logged = spec.physics.logged_per_slot() != 0;
        let config = Config {
            // No rectangles: the narrow phase without the rectangle tests.
            collide: collides.then_some(match (spec.has_rects(), swept, logged) {
                (true, false, false) => registry::COLLIDE,
                (false, false, false) => registry::COLLIDE_CIRCLES,
                (true, true, false) => registry::COLLIDE_SWEPT,
                (false, true, false) => registry::COLLIDE_CIRCLES_SWEPT,
                (true, false, true) => registry::COLLIDE_LOGGED,
                (false, false, true) => registry::COLLIDE_CIRCLES_LOGGED,
                (true, true, true) => registry::COLLIDE_SWEPT_LOGGED,
                (false, true, true) => registry::COLLIDE_CIRCLES_SWEPT_LOGGED,
            }),
            swept,
            logged,
            // A game's autopilot looks through the grid whenever it flies.
            grid: builds_grid(spec, game.is_some()),
            narrow_teams,
            think_teams: match one_launch {
                true => think_teams.map(|teams| teams.within(&narrow_teams)),
                false => think_teams,
            },
            think_from_the_end,
            integrate_from_the_end,
            one_launch,
            births_in_count: game.is_some() && layout.slots <= ONE_LAUNCH_SLOTS,
            renumber_every: renumber_every(spec, &layout, game.is_some()),
            free_in_one_launch,
            marks_in_integrate: game.is_some() && !one_launch && !free_in_one_launch,
        };
        device.check_fits(
            &format!(
                "a world of {} slots on a {}x{} grid",
                layout.slots, space.cols, space.rows
            ),
            bytes_needed(spec, sized) + TeamWarps::bytes(&config, &layout),
        )?;
        let state = WorldState::new(device, spec, &layout, seed)?;
        let extras = Extras {
            renumbers: config.renumber_every != 0,
            moving,
            traces: spec.traces(),
            logs: spec.physics.logged_per_slot(),
        };
        let scratch = Scratch::new(device, &layout, &space, kinds, extras)?;
        let warps = TeamWarps::new(device, &config, &layout)?;
        let game = match game {
            Some(config) => {
                let particles = sized.map_or(0, |(particles, _)| particles);
                let burst_slots = burst_slots(&layout, particles);
                let mut data =
                    GameData::build(&mut device.zeroed(), kinds, config.waves.len(), burst_slots)?;
                device.write(&mut data.brains, &config.brains)?;
                device.write(&mut data.waves, &config.waves)?;
                let effects = match config.effects {
                    Some(burst) => Some((
                        Particles::build(&mut device.zeroed(), burst.particles() as usize)?,
                        burst,
                    )),
                    None => None,
                };
                if config.in_flight == 0 {
                    return Err(Error::Invalid(
                        "a game with no step in flight (allowed: 1 or more)".into(),
                    ));
                }
                Some(GameState {
                    commands: device
                        .alloc_shared(config.in_flight)?
                        .named("Mailbox.commands"),
                    statuses: device
                        .alloc_shared(config.in_flight)?
                        .named("Mailbox.statuses"),
                    config,
                    data,
                    effects,
                })
            }
            None => None,
        };
        Ok(World {
            spec: spec.clone(),
            layout,
            space,
            config,
            state,
            scratch,
            warps,
            game,
        })
    }

    /// The grid as the world's queries see it (capped as its physics says), made by `b`.
    pub fn cells(&self, b: &mut Binder) -> CellIndex {
        let cap = self.spec.physics.neighbour_cap;
        self.scratch.cell_index(b, cap, self.config.one_launch)
    }

    /// Where the physics counts its deaths, made by `b`: in games, for the tally and the
    /// explosions; elsewhere nowhere.
    pub fn deaths(&self, b: &mut Binder) -> Deaths {
        match &self.game {
            Some(game) => Deaths {
                per_kind: b.view(&game.data.deaths),
                per_slot: b.view(&game.data.slot_deaths),
            },
            None => Deaths::NONE,
        }
    }

    /// The master's arguments, made by `b`, in games.
    pub fn master_args(&self, b: &mut Binder) -> Option<MasterArgs> {
        let game = self.game.as_ref()?;
        let data = &game.data;
        Some(MasterArgs {
            bodies: self.state.bodies(b),
            kinds: b.view(&self.state.tables.info),
            free: self.state.free(b),
            status: b.view(&data.status),
            mailbox: self.mailbox(b)?,
            input: b.view(&data.input),
            steered: b.view(&data.steered),
            spawned: b.view(&data.spawned),
            births: b.view(&data.births),
            birth_speed: b.view(&data.birth_speed),
            free_before: b.view(&data.free_before),
            deaths: b.view(&data.deaths),
            waves: b.view(&data.waves),
            space: self.space,
            rules: game.config.rules,
            reserved: 0,
        })
    }

    /// The tally's arguments, made by `b`, in games.
    pub fn tally_args(&self, b: &mut Binder) -> Option<TallyArgs> {
        let game = self.game.as_ref()?;
        let data = &game.data;
        Some(TallyArgs {
            bodies: self.state.bodies(b),
            kinds: b.view(&self.state.tables.info),
            ranges: b.view(&self.state.tables.ranges),
            contacts: self.scratch.contacts(b),
            status: b.view(&data.status),
            mailbox: self.mailbox(b)?,
            spawned: b.view(&data.spawned),
            births: b.view(&data.births),
            free_before: b.view(&data.free_before),
            deaths: b.view(&data.deaths),
            rules: game.config.rules,
            reserved: 0,
        })
    }

    /// The births' arguments, made by `b`, in games.
    pub fn birth_args(&self, b: &mut Binder) -> Option<BirthArgs> {
        let game = self.game.as_ref()?;
        Some(BirthArgs {
            bodies: self.state.bodies(b),
            kinds: b.view(&self.state.tables.info),
            ranges: b.view(&self.state.tables.ranges),
            free: self.state.free(b),
            flags: b.view(&self.scratch.marks.flags),
            births: b.view(&game.data.births),
            birth_speed: b.view(&game.data.birth_speed),
            space: self.space,
            rules: game.config.rules,
            reserved: 0,
        })
    }

    /// The game's mailbox as kernels take it (each part of the access its kernel's field
    /// asks for), made by `b`, if the world plays a game.
    pub fn mailbox<C: Access, S: Access, T: Access>(
        &self,
        b: &mut Binder,
    ) -> Option<Mailbox<C, S, T>> {
        let game = self.game.as_ref()?;
        Some(Mailbox {
            commands: b.view(&game.commands),
            statuses: b.view(&game.statuses),
            tallied: b.view(&game.data.tallied),
        })
    }

    /// The game's buffers, or an error for a world without a game.
    pub fn game(&self) -> Result<&GameState, Error> {
        self.game
            .as_ref()
            .ok_or_else(|| Error::Invalid("this world plays no game".into()))
    }

    /// The kernels' view of the explosions' particles, made by `b`, and their lifetime in
    /// steps, if the world has any particles.
    pub fn particles<M: ParticlesAccess>(
        &self,
        b: &mut Binder,
    ) -> Option<(Particles<View, M>, u32)> {
        let (p, burst) = self.game.as_ref()?.effects.as_ref()?;
        (burst.particles() > 0).then(|| (made(p.convert(b)), burst.lifetime))
    }
}

/// A world description that breaks a rule, as the backend's error.
fn invalid_world(e: SpecError) -> Error {
    Error::Invalid(format!("invalid world: {e}"))
}
