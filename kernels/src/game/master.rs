//! The master thread (paper section 5): the game's sequential logic, run by one dedicated
//! warp in one-warp launches, [`master`] before the physics of each step and [`tally`] after
//! it, and the parallel [`births`] it orders.
//!
//! Why its own launch: everything it decides (slot allocation, spawn counts, score, game
//! over) must be made in one fixed order to stay deterministic, and every other kernel of the
//! step reads what it wrote. A launch boundary is the only barrier the design allows between
//! warps, so the master gets a launch of its own, before the broad phase.
//!
//! The paper's master is one thread; here it is one warp, so that its loops over kinds,
//! waves and shots take one pass of 32 lanes instead of a thread's walk: each lane owns some
//! kinds (or shots), and the lanes' counts meet in warp reductions whose results do not
//! depend on their order (integer sums, saturating sums). What stays sequential (the ship,
//! its shot, the status) is lane 0's.
//!
//! Its work is small on purpose: it moves the ship, fires at most one shot, writes how many
//! enemies of each kind to spawn ([`births`] brings them to life in parallel, each from its
//! own slot's generator), and, once the step's physics is done, counts.

use glam::Vec2;

use super::control::{DESTROYED, Events, Input, PLAYING, Posting, Reading, Status, TOO_SLOW};
use super::rules::{Rules, Wave};
use crate::access::{Read, Unused, Write};
use crate::data::View;
use crate::exec::follow_previous_launch;
use crate::sim::broad::{CountArgs, count_slot};
use crate::sim::free_list::{FREE, FreeSlots, free_rank};
use crate::sim::scatter::{Place, birth, random_place};
use crate::sim::{Bodies, BodiesAccess, Contacts, KindInfo, SlotRange, Space};
use crate::{DevSlice, Thread, access, asked, kernel_args, warp};

access! {
    /// What the master does with the bodies: reads the ship's, flies it, and brings a new
    /// shot (or, at step 0, the ship) to life.
    pub struct Commanding: BodiesAccess {
        pos: Write, vel: Write, force: Write, dir: Write, kind: Unused, energy: Write,
        mass: Unused, alive: Write, state: Write, age: Write, prev: Write, frozen: Unused,
        rng: Unused,
    }
}

kernel_args! {
    /// Arguments of [`master`].
    pub struct MasterArgs {
        /// The bodies (the ship and new shots are written).
        pub bodies: Bodies<View, Commanding>,
        /// Kind table.
        pub kinds: DevSlice<KindInfo, Read>,
        /// Free slots after the previous step.
        pub free: FreeSlots<View, Read>,
        /// The game's state: read, advanced, written back (one element).
        pub status: DevSlice<Status>,
        /// Where the host left the step's command.
        pub mailbox: Reading,
        /// Output of [`master`]: this step's input, the player's or the autopilot's (one
        /// element).
        pub input: DevSlice<Input>,
        /// The autopilot's input for this step, left by the step before (one element; see
        /// [`super::autopilot`]).
        pub steered: DevSlice<Input, Read>,
        /// Enemies spawned so far, per kind.
        pub spawned: DevSlice<u32>,
        /// Output: enemies to spawn this step, per kind (for [`births`]).
        pub births: DevSlice<u32>,
        /// Output: birth velocity deviation per kind, from the last due wave of the kind.
        pub birth_speed: DevSlice<f32>,
        /// Output of [`master`]: each kind's free slots before this step's births, for
        /// [`tally`] (which runs beside the free lists' rebuild).
        pub free_before: DevSlice<u32>,
        /// Each kind's deaths in this step's physics (see [`crate::sim::Deaths`]): set to
        /// zero by [`master`], read by [`tally`] and by the free lists' rebuild beside it.
        pub deaths: DevSlice<u32>,
        /// The spawn schedule.
        pub waves: DevSlice<Wave, Read>,
        /// The world.
        pub space: Space,
        /// The scene's rules.
        pub rules: Rules,
        /// Keeps the struct free of implicit padding (checked by its `NoUninit` derive).
        pub reserved: u32,
    }
}

/// The master warp before the physics:
/// 1. at step 0, the ship is born in the middle of the world;
/// 2. the ship takes the input's movement as its velocity, and recovers energy;
/// 3. a shot leaves the ship along the aim if the fire key is held and the gun is ready,
///    in the shot kind's first free slot;
/// 4. the schedule's due waves claim free slots, in wave order, for [`births`].
///
/// After game over nothing moves, fires or spawns, and the status is left as it is.
#[inline(always)]
pub fn master(t: Thread, args: &MasterArgs) {
    if t.global() >= warp::WARP {
        return;
    }
    let lane = t.lane();
    let rules = &args.rules;
    // Everything the master reads is asked for before anything waits on it: the command
    // first (it crosses the bus from host memory, the longest wait), then the rest while
    // it travels. The stores that follow keep the compiler from sinking a load towards its
    // use behind a branch, so the warp waits for memory a few times, not once a branch.
    let command = args.mailbox.command();
    let steered = args.steered.get(0);
    let before = args.status.get(0);
    let aboard = Aboard::read(args);
    let (step, over) = (before.step, before.is_over());
    // Spawns, a kind a lane: each due wave takes what its kind has left, in wave order.
    // After game over nothing spawns.
    let kinds = args.births.len();
    let mut mine = Spawns::default();
    let mut k = lane;
    while k < kinds {
        let free = args.free.count.get(k);
        let kind = spawns(args, (k, free), step);
        let spawned = args.spawned.get(k);
        let births = if over { 0 } else { kind.births };
        args.births.set(k, births);
        // The step's deaths count from zero: the last step's were read by its tally and
        // its free lists' rebuild, which ended before this step began.
        args.deaths.set(k, 0);
        args.free_before.set(k, free);
        if let (Some(speed), false) = (kind.speed, over) {
            args.birth_speed.set(k, speed);
        }
        // Saturates rather than wraps (after 4,294,967,295 spawns of one kind), so that the
        // dead counted from it never drop to 0.
        args.spawned.set(k, spawned.saturating_add(births));
        // At most the world's slots (2^24): no overflow.
        mine.births += kind.births;
        mine.waves += kind.waves;
        k += warp::WARP;
    }
    // The warp's totals (used only while playing); another lane's share is recomputed
    // without writing.
    let theirs = |l: u32| {
        let mut theirs = Spawns::default();
        let mut k = l;
        while k < kinds {
            let kind = spawns(args, (k, args.free.count.get(k)), step);
            theirs.births += kind.births;
            theirs.waves += kind.waves;
            k += warp::WARP;
        }
        theirs.packed()
    };
    let totals = warp::reduce(
        lane,
        warp::own_or(lane, mine.packed(), theirs),
        u64::wrapping_add,
    );
    // The step's input, whatever the game's state: the command's, or the autopilot's if it
    // flies.
    let input = if command.autopilot == 0 {
        command.input
    } else {
        steered
    };
    if lane == 0 {
        args.input.set(0, input);
    }
    // After game over nothing moves or fires, and the status is left as it is.
    if lane != 0 || over {
        return;
    }
    let mut st = before;
    st.events = Events::default();
    st.input = input;
    let aboard = if step == 0 {
        let place = Place {
            pos: args.space.size * 0.5,
            vel: Vec2::ZERO,
            facing: Vec2::X,
        };
        birth(
            &args.bodies,
            &args.space,
            rules.ship.start,
            place,
            rules.ship_energy,
        );
        Aboard::read(args)
    } else {
        aboard
    };
    if aboard.ship_alive {
        // Where the ship is as the step's grid is built (what the machines look at).
        st.ship = aboard.ship_pos;
        fly_ship(args, &input, step, aboard.ship_energy);
        st.cooldown = st.cooldown.saturating_sub(1);
        if input.firing() && st.cooldown == 0 && aboard.shots_free > 0 {
            fire(args, &input, &aboard);
            st.cooldown = rules.fire_period;
            st.events.shots_fired = 1;
        }
    }
    st.events.spawned = totals as u32;
    st.events.waves = (totals >> 32) as u32;
    args.status.set(0, st);
}

/// What the master reads of the ship and its gun.
#[derive(Clone, Copy)]
struct Aboard {
    /// Whether the ship lives.
    ship_alive: bool,
    /// The ship's energy.
    ship_energy: i32,
    /// Where the ship is.
    ship_pos: Vec2,
    /// The shots' kind (radius and birth energy).
    shot: KindInfo,
    /// The ship's radius.
    ship_radius: f32,
    /// The shot kind's free slots.
    shots_free: u32,
    /// The first entry of the shot kind's free list (every kind has at least one slot):
    /// its first free slot, if it has one.
    shot_slot: u32,
}

impl Aboard {
    /// Reads them, in loads that do not wait for one another.
    #[inline(always)]
    fn read(args: &MasterArgs) -> Aboard {
        let (b, rules) = (&args.bodies, &args.rules);
        let ship = rules.ship.start;
        Aboard {
            ship_alive: b.is_alive(ship),
            ship_energy: b.energy.get(ship),
            ship_pos: b.pos.get(ship),
            shot: args.kinds.get(rules.shot_kind),
            ship_radius: args.kinds.get(rules.ship_kind).reach,
            shots_free: args.free.count.get(rules.shot_kind),
            shot_slot: args.free.list.get(rules.shots.start),
        }
    }
}

/// One kind's spawns this step, or a lane's total of them.
#[derive(Clone, Copy, Default)]
struct Spawns {
    /// Enemies to bring to life.
    births: u32,
    /// Due waves that brought at least one.
    waves: u32,
    /// The birth velocity deviation of the kind's last due wave, if one was due.
    speed: Option<f32>,
}

impl Spawns {
    /// The counts in one word for a warp sum (both stay below 2^32: births are at most the
    /// world's slots, waves at most the schedule's length).
    #[inline(always)]
    fn packed(self) -> u64 {
        u64::from(self.waves) << 32 | u64::from(self.births)
    }
}

/// Kind `kind`'s spawns at step `step`, with `free` free slots: each due wave of the kind,
/// in schedule order, takes what the kind's free slots have left.
#[inline(always)]
fn spawns(args: &MasterArgs, (kind, free): (u32, u32), step: u32) -> Spawns {
    let every_wave = (0, args.waves.len(), 1);
    args.waves
        .fold_every(every_wave, Spawns::default(), |mut out, wave| {
            // Without a branch, so that each wave is read whole, in one wait for all.
            let ours = (wave.kind == kind) & wave.due(step);
            let taken = if ours {
                wave.count.min(free - out.births)
            } else {
                0
            };
            out.births += taken;
            out.waves += u32::from(taken > 0);
            out.speed = if ours { Some(wave.speed) } else { out.speed };
            out
        })
}

/// The master warp after the physics, beside the free lists' rebuild (it counts the bodies
/// alive from the free slots the master found, its births and the deaths the physics
/// counted):
/// 1. counts and score: an enemy kind's dead are those spawned minus those alive, each
///    worth its birth energy; the kills and the score saturate at `u32::MAX` instead of
///    wrapping, and never go back (a saturated spawn count would undercount the dead);
/// 2. the ship's hits this step, the shots that struck an enemy (those that took damage:
///    obstacles such as crates do none), and where the ship is;
/// 3. the FPS meter from the ship's energy; game over below the minimum, or without a ship,
///    and then the world is frozen (see [`Bodies::frozen`]);
/// 4. the status is posted to the host through the mailbox, every step (after game over,
///    the last one again).
#[inline(always)]
pub fn tally(t: Thread, args: &TallyArgs) {
    let lane = t.lane();
    // Only lane 0 writes.
    if t.global() >= warp::WARP || warp::is_copy_of_lane0(lane) {
        return;
    }
    let (b, rules) = (&args.bodies, &args.rules);
    // Everything the tally reads is asked for before anything waits on it: no branch stands
    // between the loads and the status they make, so the compiler keeps them together and
    // the warp waits for memory a few times, not once a branch. A finished game's tally
    // counts too, and posts its status unchanged.
    let before = args.status.get(0);
    let ship = rules.ship.start;
    let (ship_alive, ship_at) = (b.is_alive(ship), b.pos.get(ship));
    let (energy, ship_hits) = (b.energy.get(ship), args.contacts.count.get(ship));
    let shots = rules.shots;
    // The bodies of kind `k` alive now: those alive as the step began, those the master
    // brought to life (births, its shot), less the physics' deaths.
    let alive = |k: u32| {
        let fired = if k == rules.shot_kind {
            before.events.shots_fired
        } else {
            0
        };
        let (range, free) = (args.ranges.get(k), args.free_before.get(k));
        let born = args.births.get(k) + fired;
        range.capacity - free + born - args.deaths.get(k)
    };
    // A kind a lane; the sums saturate, which keeps them independent of their order.
    let counts = warp::reduce(
        lane,
        |l| {
            let mut counts = Counts::default();
            let mut k = l;
            while k < args.kinds.len() {
                let info = args.kinds.get(k);
                let now = alive(k);
                let dead = args.spawned.get(k).saturating_sub(now);
                // Birth energies are at least 1.
                let worth = dead.saturating_mul(info.energy as u32);
                let enemies = match info.dies_at_zero_energy() {
                    true => Counts::default(),
                    false => Counts {
                        alive: now,
                        killed: dead,
                        score: worth,
                    },
                };
                counts = counts.merge(enemies);
                k += warp::WARP;
            }
            counts
        },
        Counts::merge,
    );
    // The shots that struck, a slot a lane at a time.
    let shot_hits = warp::sum_u32(lane, |l| {
        let every_32nd = (shots.start + l, shots.end(), warp::WARP);
        let hit = |hits: u32, damage: i32| hits + u32::from(damage > 0);
        args.contacts.damage.fold_every(every_32nd, 0, hit)
    });
    let shots_alive = alive(rules.shot_kind);
    if lane != 0 {
        return;
    }
    let mut st = before;
    let killed = counts.killed.max(st.enemies_killed);
    st.events.kills = killed - st.enemies_killed;
    st.enemies_alive = counts.alive;
    st.enemies_killed = killed;
    st.score = counts.score.max(st.score);
    st.shots_alive = shots_alive;
    st.events.shot_hits = shot_hits;
    st.events.ship_hits = if ship_alive { ship_hits } else { 0 };
    if ship_alive {
        st.ship = ship_at;
    }
    st.fps_meter = rules.fps_meter(if ship_alive { energy } else { 0 });
    st.game_over = if !ship_alive {
        DESTROYED
    } else if st.fps_meter < rules.fps_min {
        TOO_SLOW
    } else {
        PLAYING
    };
    st.step = st.step.saturating_add(1);
    // After game over the status stays as the last step left it.
    let st = if before.is_over() { before } else { st };
    args.status.set(0, st);
    args.mailbox.post(st);
    if st.is_over() {
        b.frozen.set(0, 1);
    }
}

access! {
    /// What the tally does with the bodies: reads the ship's place, energy and liveness,
    /// and freezes the world when the game ends.
    pub struct Tallying: BodiesAccess {
        pos: Read, vel: Unused, force: Unused, dir: Unused, kind: Unused, energy: Read,
        mass: Unused, alive: Read, state: Unused, age: Unused, prev: Unused, frozen: Write,
        rng: Unused,
    }
}

kernel_args! {
    /// Arguments of [`tally`]: of the master's buffers, those it counts from and those it
    /// posts to. It runs beside the free lists' rebuild, so it counts from what
    /// [`master`] left (the free slots before the births, the births, the physics'
    /// deaths), not from the lists.
    pub struct TallyArgs {
        /// The bodies: the ship's, and the world's frozen flag.
        pub bodies: Bodies<View, Tallying>,
        /// Kind table.
        pub kinds: DevSlice<KindInfo, Read>,
        /// Slot range of each kind.
        pub ranges: DevSlice<SlotRange, Read>,
        /// This step's contacts: the ship's hits, the shots' damage.
        pub contacts: Contacts<View, Read>,
        /// The game's state: read, advanced, written back (one element).
        pub status: DevSlice<Status>,
        /// Where the step's status is posted for the host.
        pub mailbox: Posting,
        /// Enemies spawned so far, per kind.
        pub spawned: DevSlice<u32, Read>,
        /// Enemies born this step, per kind (see [`MasterArgs::births`]).
        pub births: DevSlice<u32, Read>,
        /// Each kind's free slots before this step's births (see
        /// [`MasterArgs::free_before`]).
        pub free_before: DevSlice<u32, Read>,
        /// Each kind's deaths in this step's physics.
        pub deaths: DevSlice<u32, Read>,
        /// The scene's rules.
        pub rules: Rules,
        /// Keeps the struct free of implicit padding (checked by its `NoUninit` derive).
        pub reserved: u32,
    }
}

/// The enemies alive, killed and the score they are worth, over some kinds.
#[derive(Clone, Copy, Default)]
struct Counts {
    alive: u32,
    killed: u32,
    score: u32,
}

impl Counts {
    /// Both sets of kinds: alive at most the world's slots (2^24, no overflow), killed and
    /// score saturating at `u32::MAX` (a saturating sum of counts is the same in any order).
    #[inline(always)]
    fn merge(self, other: Counts) -> Counts {
        Counts {
            alive: self.alive + other.alive,
            killed: self.killed.saturating_add(other.killed),
            score: self.score.saturating_add(other.score),
        }
    }
}

impl warp::Exchanged for Counts {
    #[cfg(target_arch = "nvptx64")]
    #[inline(always)]
    fn shuffle_xor(self, mask: u32) -> Self {
        Counts {
            alive: self.alive.shuffle_xor(mask),
            killed: self.killed.shuffle_xor(mask),
            score: self.score.shuffle_xor(mask),
        }
    }
}

/// The ship, of energy `energy`, goes where the stick points, at the scene's speed, and
/// recovers energy.
#[inline(always)]
fn fly_ship(args: &MasterArgs, input: &Input, step: u32, energy: i32) {
    let (b, rules) = (&args.bodies, &args.rules);
    let ship = rules.ship.start;
    b.vel.set(ship, input.movement() * rules.ship_speed);
    b.force.set(ship, Vec2::ZERO);
    if rules.recover_every != 0 && step.is_multiple_of(rules.recover_every) {
        // A ship at the largest energy allowed (i32::MAX) stays there, rather than wrapping
        // to the most negative and dying.
        b.energy
            .set(ship, energy.saturating_add(1).min(rules.ship_energy));
    }
}

/// A shot in the first free slot of the shot kind, just outside the ship along the aim.
#[inline(always)]
fn fire(args: &MasterArgs, input: &Input, aboard: &Aboard) {
    let aim = input.aim_dir();
    let gap = aboard.ship_radius + aboard.shot.reach;
    let place = Place {
        pos: aboard.ship_pos + aim * (gap * 1.01),
        vel: aim * args.rules.shot_speed,
        facing: aim,
    };
    birth(
        &args.bodies,
        &args.space,
        aboard.shot_slot,
        place,
        aboard.shot.energy,
    );
}

kernel_args! {
    /// Arguments of [`births`] (and of [`births_and_count`]'s births).
    pub struct BirthArgs {
        /// The bodies.
        pub bodies: Bodies,
        /// Kind table (birth energies).
        pub kinds: DevSlice<KindInfo, Read>,
        /// Slot range of each kind.
        pub ranges: DevSlice<SlotRange>,
        /// The free lists the master thread counted from.
        pub free: FreeSlots,
        /// The free-list flags of the same rebuild: which slots are free, and their ranks
        /// in their kinds' lists.
        pub flags: DevSlice<u32>,
        /// Bodies to spawn per kind (from [`master`]).
        pub births: DevSlice<u32>,
        /// Birth velocity deviation per kind (from [`master`]).
        pub birth_speed: DevSlice<f32>,
        /// The world.
        pub space: Space,
        /// The ship's slot and the spawn distance.
        pub rules: Rules,
        /// Keeps the struct free of implicit padding (checked by its `NoUninit` derive).
        pub reserved: u32,
    }
}

/// Tries at a position far enough from the ship before the last one is taken as it is.
pub const PLACE_TRIES: u32 = 8;

/// Thread `i` of the launch's `n` takes the births `i`, `i + n`, … of each kind in turn:
/// birth `j` of kind `k` is the slot at entry `j` of its free list (one of the first
/// `births[k]`), which comes alive at a random place at least the spawn distance from the
/// ship (up to [`PLACE_TRIES`] draws from the slot's generator). The work follows the births
/// ordered, not the slots: most steps order none. Large worlds only: small ones bring their
/// births to life in the grid's count ([`births_and_count`]), one launch fewer, where a
/// launch of millions of threads would carry the births' registers for nothing.
#[inline(always)]
pub fn births(t: Thread, args: &BirthArgs) {
    let threads = t.grid_dim * t.block_dim;
    // The kinds with births first, from loads that do not wait for one another (a kind mask
    // has 32 bits, as many as a world has kinds at most).
    let mut pending = 0u32;
    for kind in 0..args.births.len().min(u32::BITS) {
        pending |= u32::from(args.births.get(kind) != 0) << kind;
    }
    while pending != 0 {
        let kind = pending.trailing_zeros();
        pending &= pending - 1;
        let range = args.ranges.get(kind);
        let count = args.births.get(kind).min(range.capacity);
        let mut j = t.global();
        while j < count {
            birth_in(args, args.free.list.get(range.start + j), kind);
            j += threads;
        }
    }
}

kernel_args! {
    /// Arguments of [`births_and_count`].
    pub struct BirthCountArgs {
        /// The births the master ordered.
        pub births: BirthArgs,
        /// The grid's count (see [`crate::sim::broad::count_cells`]).
        pub count: CountArgs,
    }
}

/// [`births`] and the grid's count of every slot ([`crate::sim::broad::count_cells`]) in
/// one launch, in small worlds: thread `i` takes slot `i`. A free slot whose rank in its
/// kind's list ([`free_rank`]) is below the kind's births is one of the births ordered: it
/// comes alive as [`births`] would bring it, and is counted where it is born. Births write
/// only their own slots, and the ship (the master's, in the launch before) holds its place
/// for the whole launch.
#[inline(always)]
pub fn births_and_count(t: Thread, args: &BirthCountArgs) {
    let (a, b) = (&args.births, &args.births.bodies);
    let slot = t.global();
    if slot >= args.count.keys.len() {
        return;
    }
    // A slot's kind is the world's, and its flag the last step's: both read while the
    // master ends. The rest is asked for at once: most slots are not born, and wait for
    // memory once.
    let [kind, flag] = asked([b.kind.get(slot), a.flags.get(slot)]);
    follow_previous_launch();
    let [alive, ordered] = asked([b.alive.get(slot), a.births.get(kind)]);
    let pos = asked(b.pos.get(slot));
    let born = flag & FREE != 0 && free_rank(flag) < ordered;
    let body = match born {
        true => (true, kind, birth_in(a, slot, kind)),
        false => (alive != 0, kind, pos),
    };
    count_slot(&args.count, slot, body);
}

/// Brings free slot `slot` of kind `kind` to life at a random place, at least the spawn
/// distance from the ship if one of [`PLACE_TRIES`] draws finds one; its place.
#[inline(always)]
fn birth_in(args: &BirthArgs, slot: u32, kind: u32) -> Vec2 {
    let b = &args.bodies;
    let ship = args.rules.ship.start;
    let far = args.rules.spawn_distance * args.rules.spawn_distance;
    let ship_pos = b.pos.get(ship);
    let speed = args.birth_speed.get(kind);
    let mut place = random_place(b, slot, &args.space, speed);
    let mut tries = 1;
    while tries < PLACE_TRIES
        && b.is_alive(ship)
        && args.space.offset(ship_pos, place.pos).length_squared() < far
    {
        place = random_place(b, slot, &args.space, speed);
        tries += 1;
    }
    birth(b, &args.space, slot, place, args.kinds.get(kind).energy);
    b.pos.get(slot)
}
