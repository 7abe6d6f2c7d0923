//! A world's device buffers, in two parts: the `WorldState` that a step advances and a
//! snapshot reads, and the `Scratch` that a step rebuilds from it. Both are sized once from
//! the world's layout and grid; a step allocates nothing.

use glam::Vec2;
use gpuwars_kernels::registry;
use gpuwars_kernels::rng::streams::SeedArgs;
use gpuwars_kernels::rng::{Mt607Params, RngStreams, mt607};
use gpuwars_kernels::sim::broad::CellIndex;
use gpuwars_kernels::sim::free_list::FreeSlots;
use gpuwars_kernels::sim::{Bodies, Contacts, KindInfo, SlotRange, Space};

use super::layout::{self, Layout};
use super::rng;
use super::snapshot::Snapshot;
use super::spec::WorldSpec;
use crate::primitives::{BLOCK, PrefixSum};
use crate::{Buffer, Device, Error};

/// Bytes per slot of every per-slot buffer below (the generators' 19 words included).
const SLOT_BYTES: u64 = {
    let vec2 = size_of::<Vec2>() as u64;
    let word = 4;
    let bodies = 4 * vec2 + 6 * word + size_of::<Mt607Params>() as u64 + 20 * word;
    let contacts = 2 * vec2 + 2 * word;
    let grid = 4 * word + vec2;
    let free = 3 * word;
    bodies + contacts + grid + free
};

/// The per-slot arrays of the bodies.
pub(crate) struct BodyBuffers {
    pub pos: Buffer<Vec2>,
    pub vel: Buffer<Vec2>,
    pub force: Buffer<Vec2>,
    pub dir: Buffer<Vec2>,
    pub kind: Buffer<u32>,
    pub energy: Buffer<i32>,
    pub mass: Buffer<f32>,
    pub alive: Buffer<u32>,
    pub state: Buffer<u32>,
    pub age: Buffer<u32>,
    pub rng_params: Buffer<Mt607Params>,
    pub rng_words: Buffer<u32>,
    pub rng_index: Buffer<u32>,
    pub frozen: Buffer<u32>,
}

/// What a step advances: the bodies, the kind table and slot ranges, the free lists.
pub(crate) struct WorldState {
    pub bodies: BodyBuffers,
    pub kinds: Buffer<KindInfo>,
    pub ranges: Buffer<SlotRange>,
    /// Each kind's free slots, from its range's start.
    pub free_list: Buffer<u32>,
    /// Free slots per kind.
    pub free_count: Buffer<u32>,
}

/// What a step rebuilds: the narrow phase's response, the grid, the free lists' flags.
pub(crate) struct Scratch {
    pub contacts: ContactBuffers,
    pub grid: GridBuffers,
    pub free: FreeScratch,
}

/// The narrow phase's per-slot response.
pub(crate) struct ContactBuffers {
    pub push: Buffer<Vec2>,
    pub kick: Buffer<Vec2>,
    pub count: Buffer<u32>,
    pub damage: Buffer<i32>,
}

/// The bucketed grid of the broad phase (see `gpuwars_kernels::sim::broad`).
pub(crate) struct GridBuffers {
    /// Each slot's bucket.
    pub keys: Buffer<u32>,
    /// Each slot's arrival rank in its bucket.
    pub ranks: Buffer<u32>,
    /// Bodies per bucket; scanned in place into each bucket's start.
    pub start: Buffer<u32>,
    /// Slots by bucket, in arrival order.
    pub unordered: Buffer<u32>,
    /// Slots by bucket, in slot order.
    pub slots: Buffer<u32>,
    /// Each entry's position.
    pub pos: Buffer<Vec2>,
    pub scan: PrefixSum,
    pub kinds: u32,
    pub cells: u32,
}

/// The free-list rebuild's flags and ranks.
pub(crate) struct FreeScratch {
    pub flags: Buffer<u32>,
    pub ranks: Buffer<u32>,
    pub scan: PrefixSum,
}

/// Buckets of a grid: one per (kind, cell), and one more for the total.
fn buckets(space: &Space, kinds: usize) -> usize {
    space.cells() as usize * kinds + 1
}

/// Bytes of device memory the buffers of a world of this layout and grid take, the
/// generators' set-up (seeds and parameter table) included.
pub fn bytes_needed(layout: &Layout, space: &Space, kinds: usize) -> u64 {
    let slots = u64::from(layout.slots);
    let buckets = buckets(space, kinds) as u64;
    let kind_tables = kinds as u64 * (size_of::<KindInfo>() + size_of::<SlotRange>() + 4) as u64;
    let seeding = 4 * slots + (rng::TABLE.len() * size_of::<Mt607Params>()) as u64;
    slots * SLOT_BYTES
        + 4 * (buckets + PrefixSum::scratch_len(buckets as usize) as u64)
        + 4 * PrefixSum::scratch_len(slots as usize) as u64
        + kind_tables
        + seeding
        + 4
}

impl WorldState {
    /// A world with every slot free, its generators seeded from `seed`.
    pub fn new(
        device: &Device,
        spec: &WorldSpec,
        layout: &Layout,
        seed: u32,
    ) -> Result<Self, Error> {
        let n = layout.slots as usize;
        let kind_of = layout.slot_kinds();
        let mass: Vec<f32> = kind_of
            .iter()
            .map(|&k| spec.kinds[k as usize].mass)
            .collect();
        let seeds = device.upload(&rng::slot_seeds(seed, layout.slots))?;
        let table: Vec<Mt607Params> = (0..rng::TABLE.len()).map(rng::table_params).collect();
        let table = device.upload(&table)?;
        let state = WorldState {
            bodies: BodyBuffers {
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
                rng_params: device.alloc_zeroed(n)?,
                rng_words: device.alloc_zeroed(n * mt607::N)?,
                rng_index: device.alloc_zeroed(n)?,
                frozen: device.alloc_zeroed(1)?,
            },
            kinds: device.upload(&layout::kind_table(spec))?,
            ranges: device.upload(&layout.ranges)?,
            free_list: device.alloc_zeroed(n)?,
            free_count: device.alloc_zeroed(spec.kinds.len())?,
        };
        // The generators are set up on the device: the host only draws the seeds.
        let args = SeedArgs {
            streams: state.bodies().rng,
            seeds: seeds.view(),
            table: table.view(),
        };
        let threads = layout.slots.div_ceil(BLOCK);
        // SAFETY: the views are of buffers allocated above for `slots` generators, alive
        // until the launch is done (synchronised below).
        unsafe { device.launch(registry::SEED_STREAMS, threads, BLOCK, &args)? };
        device.synchronize()?;
        Ok(state)
    }

    /// The bodies as kernels take them.
    pub fn bodies(&self) -> Bodies {
        let b = &self.bodies;
        Bodies {
            pos: b.pos.view(),
            vel: b.vel.view(),
            force: b.force.view(),
            dir: b.dir.view(),
            kind: b.kind.view(),
            energy: b.energy.view(),
            mass: b.mass.view(),
            alive: b.alive.view(),
            state: b.state.view(),
            age: b.age.view(),
            rng: RngStreams {
                params: b.rng_params.view(),
                words: b.rng_words.view(),
                index: b.rng_index.view(),
            },
            frozen: b.frozen.view(),
        }
    }

    /// The free lists as kernels take them.
    pub fn free(&self) -> FreeSlots {
        FreeSlots {
            list: self.free_list.view(),
            count: self.free_count.view(),
        }
    }

    /// Every per-slot array, read back; `steps` and the contacts come from the caller.
    pub fn snapshot(
        &self,
        device: &Device,
        steps: u64,
        contacts: &Buffer<u32>,
    ) -> Result<Snapshot, Error> {
        let (d, b) = (device, &self.bodies);
        Ok(Snapshot {
            steps,
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
            contacts: d.download(contacts)?,
            free_counts: d.download(&self.free_count)?,
            free_list: d.download(&self.free_list)?,
        })
    }
}

impl Scratch {
    /// Scratch for a world of this layout and grid with `kinds` kinds.
    pub fn new(
        device: &Device,
        layout: &Layout,
        space: &Space,
        kinds: usize,
    ) -> Result<Self, Error> {
        let n = layout.slots as usize;
        let buckets = buckets(space, kinds);
        Ok(Scratch {
            contacts: ContactBuffers {
                push: device.alloc_zeroed(n)?,
                kick: device.alloc_zeroed(n)?,
                count: device.alloc_zeroed(n)?,
                damage: device.alloc_zeroed(n)?,
            },
            grid: GridBuffers {
                keys: device.alloc_zeroed(n)?,
                ranks: device.alloc_zeroed(n)?,
                start: device.alloc_zeroed(buckets)?,
                unordered: device.alloc_zeroed(n)?,
                slots: device.alloc_zeroed(n)?,
                pos: device.alloc_zeroed(n)?,
                scan: PrefixSum::new(device, buckets)?,
                kinds: kinds as u32,
                cells: space.cells(),
            },
            free: FreeScratch {
                flags: device.alloc_zeroed(n)?,
                ranks: device.alloc_zeroed(n)?,
                scan: PrefixSum::new(device, n)?,
            },
        })
    }

    /// The contacts as kernels take them.
    pub fn contacts(&self) -> Contacts {
        let c = &self.contacts;
        Contacts {
            push: c.push.view(),
            kick: c.kick.view(),
            count: c.count.view(),
            damage: c.damage.view(),
        }
    }

    /// The grid as kernels query it, each query examining at most `cap` entries (0: all).
    pub fn grid(&self, cap: u32) -> CellIndex {
        CellIndex {
            slots: self.grid.slots.view(),
            pos: self.grid.pos.view(),
            start: self.grid.start.view(),
            kinds: self.grid.kinds,
            cells: self.grid.cells,
            cap,
            reserved: 0,
        }
    }
}
