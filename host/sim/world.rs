//! A world on a device, and the step that advances it.
//!
//! [`Simulation`] owns every buffer a world needs, sized once from its [`WorldSpec`]: the
//! bodies (a structure of arrays, slots grouped by kind), the kind table, the free lists, and
//! the scratch of the broad and narrow phases. A step allocates nothing. Its stages, in
//! order (see `gpuwars_kernels::sim`):
//!
//! 1. broad phase: cell keys, counting sort by cell, cell bounds;
//! 2. narrow phase: contacts and their response;
//! 3. integration and the boundary rule;
//! 4. free lists.
//!
//! A world whose kinds never collide skips the first two.

use glam::Vec2;
use gpuwars_kernels::game::master::FreeSlots;
use gpuwars_kernels::rng::Mt607Params;
use gpuwars_kernels::rng::RngStreams;
use gpuwars_kernels::sim::broad::{AssignArgs, BoundsArgs, CellIndex};
use gpuwars_kernels::sim::free_list::{GatherArgs, MarkArgs};
use gpuwars_kernels::sim::integrate::IntegrateArgs;
use gpuwars_kernels::sim::narrow::CollideArgs;
use gpuwars_kernels::sim::scatter::ScatterArgs;
use gpuwars_kernels::sim::{Bodies, Contacts, KindInfo, SlotRange, Space};
use gpuwars_kernels::{DevSlice, Kernel, KernelArgs, registry};

use super::layout::{self, Layout};
use super::rng;
use super::snapshot::Snapshot;
use super::spec::WorldSpec;
use crate::primitives::{BLOCK, CountingSort, PrefixSum};
use crate::{Buffer, Device, Error};

/// The per-slot arrays of the bodies.
struct BodyBuffers {
    pos: Buffer<Vec2>,
    vel: Buffer<Vec2>,
    force: Buffer<Vec2>,
    dir: Buffer<Vec2>,
    kind: Buffer<u32>,
    energy: Buffer<i32>,
    mass: Buffer<f32>,
    alive: Buffer<u32>,
    state: Buffer<u32>,
    age: Buffer<u32>,
    rng_params: Buffer<Mt607Params>,
    rng_words: Buffer<u32>,
    rng_index: Buffer<u32>,
}

impl BodyBuffers {
    fn view(&self) -> Bodies {
        Bodies {
            pos: self.pos.view(),
            vel: self.vel.view(),
            force: self.force.view(),
            dir: self.dir.view(),
            kind: self.kind.view(),
            energy: self.energy.view(),
            mass: self.mass.view(),
            alive: self.alive.view(),
            state: self.state.view(),
            age: self.age.view(),
            rng: RngStreams {
                params: self.rng_params.view(),
                words: self.rng_words.view(),
                index: self.rng_index.view(),
            },
        }
    }
}

/// The narrow phase's per-slot response.
struct ContactBuffers {
    push: Buffer<Vec2>,
    kick: Buffer<Vec2>,
    count: Buffer<u32>,
    damage: Buffer<i32>,
}

impl ContactBuffers {
    fn view(&self) -> Contacts {
        Contacts {
            push: self.push.view(),
            kick: self.kick.view(),
            count: self.count.view(),
            damage: self.damage.view(),
        }
    }
}

/// The sorted grid of the broad phase.
struct BroadPhase {
    keys: Buffer<u32>,
    sorted_keys: Buffer<u32>,
    sorted_slots: Buffer<u32>,
    start: Buffer<u32>,
    end: Buffer<u32>,
    sort: CountingSort,
}

impl BroadPhase {
    fn index(&self) -> CellIndex {
        CellIndex {
            slots: self.sorted_slots.view(),
            keys: self.sorted_keys.view(),
            start: self.start.view(),
            end: self.end.view(),
        }
    }
}

/// Each kind's free slots.
struct FreeLists {
    flags: Buffer<u32>,
    ranks: Buffer<u32>,
    list: Buffer<u32>,
    count: Buffer<u32>,
    scan: PrefixSum,
}

/// Views of a world's device buffers, for the game's kernels.
pub(crate) struct Views {
    pub bodies: Bodies,
    pub kinds: DevSlice<KindInfo>,
    pub ranges: DevSlice<SlotRange>,
    pub contacts: Contacts,
    pub grid: CellIndex,
    pub free: FreeSlots,
}

/// A world on a device: its bodies and the scratch its step needs.
pub struct Simulation<'d> {
    device: &'d Device,
    spec: WorldSpec,
    layout: Layout,
    space: Space,
    collisions: bool,
    collide: Kernel<CollideArgs>,
    kinds: Buffer<KindInfo>,
    ranges: Buffer<SlotRange>,
    bodies: BodyBuffers,
    contacts: ContactBuffers,
    broad: BroadPhase,
    free: FreeLists,
    steps: u64,
}

/// Blocks of [`BLOCK`] threads covering `n` threads.
fn grid(n: u32) -> u32 {
    n.div_ceil(BLOCK)
}

impl<'d> Simulation<'d> {
    /// An empty world (every slot free) for `spec`, its generators seeded from `seed`.
    pub fn new(device: &'d Device, spec: &WorldSpec, seed: u32) -> Result<Self, Error> {
        spec.validate()?;
        let layout = Layout::new(spec);
        let slots = layout.slots;
        let n = slots as usize;
        let kind_of = layout.slot_kinds();
        let mass: Vec<f32> = kind_of
            .iter()
            .map(|&k| spec.kinds[k as usize].mass)
            .collect();
        let seeds = rng::slot_seeds(seed, slots);
        let space = layout::space(spec);
        let cells = space.cells() as usize;
        let bodies = BodyBuffers {
            pos: device.alloc_zeroed(n)?,
            vel: device.alloc_zeroed(n)?,
            force: device.alloc_zeroed(n)?,
            dir: device.alloc_zeroed(n)?,
            kind: device.upload(&kind_of)?,
            energy: device.alloc_zeroed(n)?,
            mass: device.upload(&mass)?,
            alive: device.alloc_zeroed(n)?,
            state: device.alloc_zeroed(n)?,
            age: device.alloc_zeroed(n)?,
            rng_params: device.upload(&rng::slot_params(slots))?,
            rng_words: device.upload(&rng::word_major_states(&seeds))?,
            rng_index: device.alloc_zeroed(n)?,
        };
        let mut sim = Simulation {
            device,
            spec: spec.clone(),
            space,
            collisions: spec.collision_masks().iter().any(|&m| m != 0),
            // No rectangles: the narrow phase without the rectangle tests.
            collide: if spec.has_rects() {
                registry::COLLIDE
            } else {
                registry::COLLIDE_CIRCLES
            },
            kinds: device.upload(&layout::kind_table(spec))?,
            ranges: device.upload(&layout.ranges)?,
            bodies,
            contacts: ContactBuffers {
                push: device.alloc_zeroed(n)?,
                kick: device.alloc_zeroed(n)?,
                count: device.alloc_zeroed(n)?,
                damage: device.alloc_zeroed(n)?,
            },
            broad: BroadPhase {
                keys: device.alloc_zeroed(n)?,
                sorted_keys: device.alloc_zeroed(n)?,
                sorted_slots: device.alloc_zeroed(n)?,
                start: device.alloc_zeroed(cells)?,
                end: device.alloc_zeroed(cells)?,
                sort: CountingSort::new(device, n)?,
            },
            free: FreeLists {
                flags: device.alloc_zeroed(n)?,
                ranks: device.alloc_zeroed(n)?,
                list: device.alloc_zeroed(n)?,
                count: device.alloc_zeroed(spec.kinds.len())?,
                scan: PrefixSum::new(device, n)?,
            },
            layout,
            steps: 0,
        };
        sim.rebuild_free_lists()?;
        Ok(sim)
    }

    /// The world's description.
    pub fn spec(&self) -> &WorldSpec {
        &self.spec
    }

    /// The slot ranges.
    pub fn layout(&self) -> &Layout {
        &self.layout
    }

    /// The world and grid the kernels use.
    pub fn space(&self) -> &Space {
        &self.space
    }

    /// Steps taken since creation.
    pub fn steps(&self) -> u64 {
        self.steps
    }

    /// The device the world lives on.
    pub fn device(&self) -> &'d Device {
        self.device
    }

    /// Number of free slots of each kind.
    pub fn free_counts(&self) -> Result<Vec<u32>, Error> {
        self.device.download(&self.free.count)
    }

    /// Brings `count` bodies of kind `kind` to life in its lowest free slots, at uniformly
    /// random positions with normal velocities of deviation `speed` per axis, drawn from each
    /// slot's own generator.
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
            bodies: self.bodies.view(),
            slots: self.free.list.view().range(start, count),
            space: self.space,
            speed,
            energy: spec.energy,
        };
        self.launch(registry::SCATTER, count, &args)?;
        self.rebuild_free_lists()
    }

    /// Advances the world by one time step.
    pub fn step(&mut self) -> Result<(), Error> {
        if self.collisions {
            self.build_grid()?;
            self.collide()?;
        }
        self.finish_step()
    }

    /// Whether any two kinds collide (else the narrow phase is never launched).
    pub(crate) fn collides(&self) -> bool {
        self.collisions
    }

    /// Narrow phase: contacts and their response, on this step's grid.
    pub(crate) fn collide(&self) -> Result<(), Error> {
        let collide = CollideArgs {
            bodies: self.bodies.view(),
            kinds: self.kinds.view(),
            space: self.space,
            grid: self.broad.index(),
            contacts: self.contacts.view(),
        };
        self.launch(self.collide, self.layout.slots, &collide)
    }

    /// Integration, deaths, the free lists, and the step count.
    pub(crate) fn finish_step(&mut self) -> Result<(), Error> {
        let integrate = IntegrateArgs {
            bodies: self.bodies.view(),
            kinds: self.kinds.view(),
            contacts: self.contacts.view(),
            space: self.space,
            dt: self.spec.dt,
            reserved: 0,
        };
        self.launch(registry::INTEGRATE, self.layout.slots, &integrate)?;
        self.rebuild_free_lists()?;
        self.steps += 1;
        Ok(())
    }

    /// The device views the game's kernels take.
    pub(crate) fn views(&self) -> Views {
        Views {
            bodies: self.bodies.view(),
            kinds: self.kinds.view(),
            ranges: self.ranges.view(),
            contacts: self.contacts.view(),
            grid: self.broad.index(),
            free: FreeSlots {
                list: self.free.list.view(),
                count: self.free.count.view(),
            },
        }
    }

    /// Broad phase: keys, sort, cell bounds.
    pub(crate) fn build_grid(&mut self) -> Result<(), Error> {
        let slots = self.layout.slots;
        let assign = AssignArgs {
            bodies: self.bodies.view(),
            space: self.space,
            keys: self.broad.keys.view(),
        };
        self.launch(registry::ASSIGN_CELLS, slots, &assign)?;
        let broad = &mut self.broad;
        broad.sort.run(
            self.device,
            &broad.keys,
            slots as usize,
            self.space.cells() + 1,
            &mut broad.sorted_keys,
            &mut broad.sorted_slots,
        )?;
        // An empty cell needs only `end` = 0: its run `start..0` is empty whatever `start`.
        self.device.zero(&mut broad.end)?;
        let bounds = BoundsArgs {
            grid: broad.index(),
            cells: self.space.cells(),
            reserved: 0,
        };
        self.launch(registry::CELL_BOUNDS, slots, &bounds)
    }

    /// Free lists: flags, their prefix sums, the lists and counts.
    fn rebuild_free_lists(&mut self) -> Result<(), Error> {
        let slots = self.layout.slots;
        let mark = MarkArgs {
            bodies: self.bodies.view(),
            ranges: self.ranges.view(),
            flags: self.free.flags.view(),
        };
        self.launch(registry::MARK_FREE, slots, &mark)?;
        let free = &mut self.free;
        free.scan
            .run(self.device, &free.flags, &mut free.ranks, slots as usize)?;
        self.device.zero(&mut free.count)?;
        let gather = GatherArgs {
            kind: self.bodies.kind.view(),
            ranges: self.ranges.view(),
            flags: free.flags.view(),
            ranks: free.ranks.view(),
            list: free.list.view(),
            count: free.count.view(),
        };
        self.launch(registry::GATHER_FREE, slots, &gather)
    }

    /// Launches `kernel` with one thread per item.
    pub(crate) fn launch<A: KernelArgs>(
        &self,
        kernel: Kernel<A>,
        items: u32,
        args: &A,
    ) -> Result<(), Error> {
        // SAFETY: every view in the argument structs of this module is of a buffer owned by
        // `self` and sized from the layout for the kernel's contract; nothing else touches
        // them during the launch.
        unsafe { self.device.launch(kernel, grid(items), BLOCK, args) }
    }

    /// A copy of the whole state, read back from the device.
    pub fn snapshot(&self) -> Result<Snapshot, Error> {
        let d = self.device;
        let b = &self.bodies;
        Ok(Snapshot {
            steps: self.steps,
            pos: d.download(&b.pos)?,
            vel: d.download(&b.vel)?,
            force: d.download(&b.force)?,
            dir: d.download(&b.dir)?,
            kind: d.download(&b.kind)?,
            energy: d.download(&b.energy)?,
            mass: d.download(&b.mass)?,
            alive: d.download(&b.alive)?,
            state: d.download(&b.state)?,
            age: d.download(&b.age)?,
            rng_words: d.download(&b.rng_words)?,
            rng_index: d.download(&b.rng_index)?,
            contacts: d.download(&self.contacts.count)?,
            free_counts: d.download(&self.free.count)?,
            free_list: d.download(&self.free.list)?,
        })
    }

    /// The state hash after the steps so far (see [`Snapshot::state_hash`]).
    pub fn state_hash(&self) -> Result<u64, Error> {
        Ok(self.snapshot()?.state_hash())
    }

    /// Brings bodies to life at exact places, for scenarios set up by hand: `bodies` lists
    /// `(slot, position, velocity)`, and those slots come alive with their kind's energy, no
    /// force, and state 0.
    pub fn place(&mut self, bodies: &[(u32, Vec2, Vec2)]) -> Result<(), Error> {
        let mut snapshot = self.snapshot()?;
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
            snapshot.force[s] = Vec2::ZERO;
            snapshot.dir[s] = vel.try_normalize().unwrap_or(Vec2::X);
            snapshot.energy[s] = self.spec.kinds[kind as usize].energy;
            snapshot.alive[s] = 1;
            snapshot.state[s] = 0;
            snapshot.age[s] = 0;
        }
        let (d, b) = (self.device, &mut self.bodies);
        d.write(&mut b.pos, &snapshot.pos)?;
        d.write(&mut b.vel, &snapshot.vel)?;
        d.write(&mut b.force, &snapshot.force)?;
        d.write(&mut b.dir, &snapshot.dir)?;
        d.write(&mut b.energy, &snapshot.energy)?;
        d.write(&mut b.alive, &snapshot.alive)?;
        d.write(&mut b.state, &snapshot.state)?;
        d.write(&mut b.age, &snapshot.age)?;
        self.rebuild_free_lists()
    }

    /// Sets the force on each listed slot: `(slot, force)`.
    pub fn set_forces(&mut self, forces: &[(u32, Vec2)]) -> Result<(), Error> {
        let mut all = self.device.download(&self.bodies.force)?;
        for &(slot, force) in forces {
            let Some(f) = all.get_mut(slot as usize) else {
                return Err(Error::Invalid(format!("slot {slot} does not exist")));
            };
            *f = force;
        }
        self.device.write(&mut self.bodies.force, &all)
    }
}
