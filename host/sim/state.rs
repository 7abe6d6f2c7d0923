//! A world's device buffers, in two parts: the `WorldState` that a step advances and a
//! snapshot reads, and the `Scratch` that a step rebuilds from it. Both are sized once from
//! the world's layout and grid; a step allocates nothing. The arrays themselves are the
//! kernels' groups (`Bodies`, `Grid`, ...), each declared once in the kernels crate.

use std::convert::Infallible;

use glam::Vec2;
use gpuwars_kernels::DevSlice;
use gpuwars_kernels::access::{Access, Write};
use gpuwars_kernels::data::{Build, Sizes, Unmade, View};
use gpuwars_kernels::registry;
use gpuwars_kernels::rng::Mt607Params;
use gpuwars_kernels::rng::streams::SeedArgs;
use gpuwars_kernels::sim::broad::{CellIndex, Grid};
use gpuwars_kernels::sim::free_list::{FreeMarks, FreeSlots, FreeSlotsAccess};
use gpuwars_kernels::sim::renumber::Moved;
use gpuwars_kernels::sim::{Bodies, BodiesAccess, Contacts, ContactsAccess, KindTables, Space};

use super::layout::{self, Layout};
use super::rng;
use super::snapshot::Snapshot;
use super::spec::WorldSpec;
use crate::backend::{Binder, Buffers, Launch};
use crate::primitives::{BLOCK, PrefixSum};
use crate::{Device, Error, Op};

/// What a step advances: the bodies, the kind tables, the free lists.
pub(crate) struct WorldState {
    pub bodies: Bodies<Buffers>,
    pub tables: KindTables<Buffers>,
    pub free: FreeSlots<Buffers>,
}

/// What a step rebuilds: the narrow phase's response, the grid, the free lists' marks, the
/// prefix sums' scratch of the last two, and the renumbering's buffers in worlds that
/// renumber.
pub(crate) struct Scratch {
    pub contacts: Contacts<Buffers>,
    pub grid: Grid<Buffers>,
    pub grid_scan: PrefixSum,
    pub marks: FreeMarks<Buffers>,
    pub marks_scan: PrefixSum,
    pub moved: Option<Moved<Buffers>>,
    /// Kinds and cells of the grid's buckets.
    pub kinds: u32,
    pub cells: u32,
}

/// Buckets of a grid: one per (kind, cell), and one more for the total.
fn buckets(space: &Space, kinds: usize) -> usize {
    space.cells() as usize * kinds + 1
}

/// The value of a group's `build` or `convert` that cannot fail (sizes, views).
pub(crate) fn made<T>(result: Result<T, Infallible>) -> T {
    let Ok(value) = result;
    value
}

/// Bytes of device memory the buffers of a world of this layout and grid take, the
/// generators' set-up (seeds and parameter table) included, the renumbering's buffers if it
/// `renumbers`, its grid entries' velocities if its bodies are `moving` in the launch
/// that queries the grid, the bodies' last paths if it `traces` them, and the contact log if
/// it `logs` its contacts.
pub fn bytes_needed(
    layout: &Layout,
    space: &Space,
    kinds: usize,
    Extras {
        renumbers,
        moving,
        traces,
        logs,
    }: Extras,
) -> u64 {
    let (slots, buckets) = (layout.slots as usize, buckets(space, kinds));
    let traced = per_slot(slots, traces);
    let mut sizes = Sizes::default();
    let s = &mut sizes;
    made(Bodies::<Unmade>::build(s, slots, traced));
    made(KindTables::<Unmade>::build(s, kinds));
    made(FreeSlots::<Unmade>::build(s, slots, kinds));
    let (logged, logging) = log_sizes(slots, logs);
    made(Contacts::<Unmade>::build(s, slots, logged, logging));
    made(Grid::<Unmade>::build(
        s,
        slots,
        buckets,
        per_slot(slots, moving),
        per_slot(slots, moving && traces),
        2 * kinds,
    ));
    let tiles = FreeMarks::tiles_for(layout.slots) as usize;
    let groups = FreeMarks::groups_for(layout.slots) as usize;
    made(FreeMarks::<Unmade>::build(s, slots, tiles, groups));
    if renumbers {
        made(Moved::<Unmade>::build(s, slots, traced));
    }
    made(s.array::<u32, Write>("seeds", slots));
    made(s.array::<Mt607Params, Write>("table", rng::TABLE.len()));
    made(s.array::<u32, Write>("grid scan", PrefixSum::scratch_len(buckets)));
    made(s.array::<u32, Write>("free scan", PrefixSum::scratch_len(tiles)));
    sizes.bytes
}

impl WorldState {
    /// A world with every slot free, its generators seeded from `seed`.
    pub fn new(
        device: &Device,
        spec: &WorldSpec,
        layout: &Layout,
        seed: u32,
    ) -> Result<Self, Error> {
        let (slots, kinds) = (layout.slots as usize, spec.kinds.len());
        let traced = per_slot(slots, spec.traces());
        let mut bodies = Bodies::build(&mut device.zeroed(), slots, traced)?;
        let kind_of = layout.slot_kinds();
        let mass: Vec<f32> = kind_of
            .iter()
            .map(|&k| spec.kinds[k as usize].mass)
            .collect();
        device.write(&mut bodies.kind, &kind_of)?;
        device.write(&mut bodies.mass, &mass)?;
        let mut tables = KindTables::build(&mut device.zeroed(), kinds)?;
        device.write(&mut tables.info, &layout::kind_table(spec))?;
        device.write(&mut tables.ranges, &layout.ranges)?;
        let state = WorldState {
            bodies,
            tables,
            free: FreeSlots::build(&mut device.zeroed(), slots, kinds)?,
        };
        // The generators are set up on the device: the host only draws the seeds.
        let seeds = device.upload(&rng::slot_seeds(seed, layout.slots))?;
        let table: Vec<Mt607Params> = (0..rng::TABLE.len()).map(rng::table_params).collect();
        let table = device.upload(&table)?;
        // SAFETY: the views go into this op only.
        let mut b = unsafe { Binder::new() };
        let args = SeedArgs {
            streams: made(state.bodies.rng.convert(&mut b)),
            seeds: b.view(&seeds),
            table: b.view(&table),
        };
        let launch = Launch {
            kernel: registry::SEED_STREAMS,
            grid: layout.slots.div_ceil(BLOCK),
            block: BLOCK,
            args,
        };
        // SAFETY: the views are of `b`'s buffers, a generator per slot and the table the
        // kernel takes modulo its length.
        device.launch(unsafe { Op::launch(launch, b, 0) })?;
        device.synchronize()?;
        Ok(state)
    }

    /// The bodies as kernels take them, of the access `M` declares, made by `b`.
    pub fn bodies<M: BodiesAccess>(&self, b: &mut Binder) -> Bodies<View, M> {
        made(self.bodies.convert(b))
    }

    /// The free lists as kernels take them, of the access `M` declares, made by `b`.
    pub fn free<M: FreeSlotsAccess>(&self, b: &mut Binder) -> FreeSlots<View, M> {
        made(self.free.convert(b))
    }

    /// Every per-slot array, read back; `steps` and the contacts' counts come from the
    /// caller.
    pub fn snapshot(
        &self,
        device: &Device,
        steps: u64,
        contacts: &Contacts<Buffers>,
    ) -> Result<Snapshot, Error> {
        Ok(Snapshot {
            steps,
            bodies: self.bodies.convert(&mut device.reader())?,
            contacts: device.download(&contacts.count)?,
            free: self.free.convert(&mut device.reader())?,
        })
    }
}

/// The buffers a world needs beyond every world's (see [`bytes_needed`]).
#[derive(Clone, Copy, Debug)]
pub struct Extras {
    /// The renumbering's.
    pub renumbers: bool,
    /// The grid entries' velocities, where the bodies move in the launch that queries it.
    pub moving: bool,
    /// The bodies' last paths (and the grid entries' copies of them, where `moving`).
    pub traces: bool,
    /// Records a slot of the narrow phase's log of every contact it counts, for an audit
    /// (see [`Contacts::log`]); 0 for no log.
    pub logs: usize,
}

impl Scratch {
    /// Scratch for a world of this layout and grid with `kinds` kinds and the `extras` it
    /// needs.
    pub fn new(
        device: &Device,
        layout: &Layout,
        space: &Space,
        kinds: usize,
        Extras {
            renumbers,
            moving,
            traces,
            logs,
        }: Extras,
    ) -> Result<Self, Error> {
        let slots = layout.slots as usize;
        let traced = per_slot(slots, traces);
        let buckets = buckets(space, kinds);
        let tiles = FreeMarks::tiles_for(layout.slots) as usize;
        Ok(Scratch {
            contacts: {
                let (logged, logging) = log_sizes(slots, logs);
                Contacts::build(&mut device.zeroed(), slots, logged, logging)?
            },
            grid: Grid::build(
                &mut device.zeroed(),
                slots,
                buckets,
                per_slot(slots, moving),
                per_slot(slots, moving && traces),
                2 * kinds,
            )?,
            grid_scan: PrefixSum::new(device, buckets)?,
            marks: FreeMarks::build(
                &mut device.zeroed(),
                slots,
                tiles,
                FreeMarks::groups_for(layout.slots) as usize,
            )?,
            marks_scan: PrefixSum::new(device, tiles)?,
            moved: match renumbers {
                true => Some(Moved::build(&mut device.zeroed(), slots, traced)?),
                false => None,
            },
            kinds: kinds as u32,
            cells: space.cells(),
        })
    }

    /// The contacts as kernels take them, of the access `M` declares, made by `b`.
    pub fn contacts<M: ContactsAccess>(&self, b: &mut Binder) -> Contacts<View, M> {
        made(self.contacts.convert(b))
    }

    /// The grid as kernels query it, each query examining at most `cap` entries (0: all),
    /// with its entries' velocities if `moving` (see [`CellIndex::vel`]), made by `b`.
    pub fn cell_index(&self, b: &mut Binder, cap: u32, moving: bool) -> CellIndex {
        CellIndex {
            slots: b.view(&self.grid.slots),
            pos: b.view(&self.grid.pos),
            vel: self.entry_velocities(b, moving),
            prev: b.view(&self.grid.prev),
            start: b.view(&self.grid.start),
            rows: b.view(&self.grid.rows),
            kinds: self.kinds,
            cells: self.cells,
            cap,
            reserved: 0,
        }
    }

    /// The grid entries' velocities if `moving` (the world keeps them), else none, made
    /// by `b`.
    pub fn entry_velocities<A: Access>(&self, b: &mut Binder, moving: bool) -> DevSlice<Vec2, A> {
        match moving {
            true => b.view(&self.grid.vel),
            false => DevSlice::EMPTY,
        }
    }
}

/// The contact log's records (a power of two) and cursors where a world logs its contacts,
/// `per_slot` records a slot (see [`Contacts::log`]); none where `per_slot` is 0.
fn log_sizes(slots: usize, per_slot: usize) -> (usize, usize) {
    match per_slot {
        0 => (0, 0),
        _ => (slots.saturating_mul(per_slot).next_power_of_two(), 1),
    }
}

/// Elements of an array a world has only if it needs it (`wanted`): one a slot, or none.
fn per_slot(slots: usize, wanted: bool) -> usize {
    if wanted { slots } else { 0 }
}
