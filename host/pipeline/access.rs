//! What the step's kernels write, by buffer name (see `Binder::writing`): each op in a
//! branch's reach declares its writes with these, and reads the rest, so that making the
//! step's plan checks that no op beside the others meets what the ops it runs beside
//! write. Read off the kernels' code; a name that no view of the op has is refused.

/// The narrow phase (`collide*`): energy lost in contacts, each slot's response.
pub(super) const NARROW: &[&str] = &[
    "Bodies.energy",
    "Contacts.push",
    "Contacts.kick",
    "Contacts.count",
    "Contacts.damage",
    "Contacts.log",
    "Contacts.cursor",
];

/// The machines (`think*`): states, deaths, energy, the force they steer with, and the
/// generators they draw from.
pub(super) const THINK: &[&str] = &[
    "Bodies.state",
    "Bodies.alive",
    "Bodies.energy",
    "Bodies.force",
    "RngStreams.words",
    "RngStreams.index",
];

/// The integrator: where the bodies go, their ages and deaths, and their paths' starts.
pub(super) const INTEGRATE: &[&str] = &[
    "Bodies.pos",
    "Bodies.vel",
    "Bodies.dir",
    "Bodies.prev",
    "Bodies.age",
    "Bodies.alive",
];

/// The deaths a step counts, in games (kinds' and slots').
pub(super) const DEATHS: &[&str] = &["GameData.deaths", "GameData.slot_deaths"];

/// The tally: the status, the mailbox's post and the frozen flag of a game that ended.
pub(super) const TALLY: &[&str] = &[
    "GameData.status",
    "GameData.tallied",
    "Mailbox.statuses",
    "Bodies.frozen",
];

/// What the tally's arguments (the master's) view and the tally leaves alone: the free
/// lists, which the stage beside it rebuilds, and the autopilot's input, which the
/// autopilot beside it writes.
pub(super) const TALLY_IGNORES: &[&str] =
    &["FreeSlots.list", "FreeSlots.count", "GameData.steered"];

/// The explosions: the particles only.
pub(super) const EFFECTS: &[&str] = &[
    "Particles.pos",
    "Particles.vel",
    "Particles.life",
    "Particles.kind",
    "Particles.seen",
];

/// The autopilot: its input for the next step.
pub(super) const PILOT: &[&str] = &["GameData.steered"];

/// The free lists' marks: each slot's flag and each tile's count.
pub(super) const MARK_FREE: &[&str] = &["FreeMarks.flags", "FreeMarks.tiles"];

/// The integrator's marks of the slots whose freedom it changes: their flags, their tiles'
/// counts and the counts' sums.
pub(super) const MARKS: &[&str] = &["FreeMarks.flags", "FreeMarks.tiles", "FreeMarks.sums"];

/// The free lists' gather: the lists and their counts.
pub(super) const GATHER_FREE: &[&str] = &["FreeSlots.list", "FreeSlots.count"];

/// Marks and gather in one launch: the flags, the lists and their counts.
pub(super) const MARK_AND_GATHER_FREE: &[&str] =
    &["FreeMarks.flags", "FreeSlots.list", "FreeSlots.count"];

/// What the explosions' and the free lists' arguments view and they leave alone: the
/// frozen flag, which the tally beside them writes.
pub(super) const FROZEN_UNREAD: &[&str] = &["Bodies.frozen"];

/// The names in `lists`, and the deaths where the world plays a game (`game`).
pub(super) fn with_deaths(game: bool, lists: &[&[&'static str]]) -> Vec<&'static str> {
    let deaths: &[&str] = if game { DEATHS } else { &[] };
    lists
        .iter()
        .chain([&deaths])
        .flat_map(|l| l.iter().copied())
        .collect()
}
