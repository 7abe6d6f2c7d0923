//! How many threads the neighbour queries give each body (the kernels' [`Teams`]).
//!
//! A body that expects many neighbours walks them with a team of lanes, so that a crowded
//! query no longer holds its warp (and at a small world's size, the whole launch) for
//! hundreds of steps. The results are the same bit for bit whatever the widths (the kernels
//! fold what the lanes find in the order of one thread, or merge exact sums), so the choice
//! is speed only.

use gpuwars_kernels::game::ai::{others_mask, sight_mask};
use gpuwars_kernels::game::fsm::Machine;
use gpuwars_kernels::sim::broad::kind_bit;
use gpuwars_kernels::sim::teams::{MAX_WIDTH, Teams};

use super::GameConfig;
use crate::sim::WorldSpec;
use crate::sim::layout::Layout;
use gpuwars_kernels::sim::Space;

/// How many lanes a body's neighbour queries get.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Lanes {
    /// Chosen from the neighbours a body of each kind expects, as far as the GPU has threads
    /// to spare; one thread a body on the CPU (where a team's lanes would only repeat its
    /// first lane's work).
    #[default]
    Auto,
    /// This many lanes (a power of two, 1 to 32) for every kind's bodies, on any backend.
    Fixed(u32),
}

/// Expected grid entries a lane of a team walks before the team grows (`Lanes::Auto`).
const ENTRIES_PER_LANE: f64 = 2.0;

/// Runs of entries a query reads per kind it looks for, in the usual case: one for each
/// row of its 3×3 cells (the block's three columns are one run unless it wraps).
const RUNS_PER_KIND: u32 = 3;

/// The team width of each kind of `first ..= last` under `lanes`, for queries looking for
/// the kinds `masks[k]`, on a GPU holding `resident` threads at once (`None`: the CPU).
///
/// `Auto` gives a kind a lane for each run of entries its query reads (the lanes load their
/// bounds side by side) or for every [`ENTRIES_PER_LANE`] entries it expects on an even
/// spread (its 3×3 cells' share of each kind it looks for), whichever is more; then it
/// halves the widest teams until the launch fits the threads the GPU holds at once: past
/// that, the extra lanes would only queue behind the other bodies' threads (at a million
/// bodies, teams of 4 made `think` 3 times slower on the H200).
fn widths(
    lanes: Lanes,
    resident: Option<u64>,
    layout: &Layout,
    space: &Space,
    masks: &[u32],
    (first, last): (usize, usize),
) -> Vec<u32> {
    let kinds = masks.len();
    let resident = match (lanes, resident) {
        (Lanes::Fixed(width), _) => return vec![width.clamp(1, MAX_WIDTH); kinds],
        (Lanes::Auto, None) => return vec![1; kinds],
        (Lanes::Auto, Some(resident)) => resident,
    };
    // A query reads 3×3 cells: that share of each kind, on an even spread.
    let share = (9.0 / f64::from(space.cols * space.rows)).min(1.0);
    let mut widths: Vec<u32> = masks
        .iter()
        .map(|&mask| {
            let expected = expected(layout, mask, share);
            let runs = RUNS_PER_KIND * mask.count_ones();
            let lanes = ((expected / ENTRIES_PER_LANE).ceil() as u32).max(runs);
            lanes.max(1).next_power_of_two().min(MAX_WIDTH)
        })
        .collect();
    let threads = |widths: &[u32]| {
        Teams::new((first as u32, last as u32 + 1), (0, 0), |k| {
            widths[k as usize]
        })
        .threads(&layout.ranges)
    };
    while threads(&widths) > resident {
        let Some(&widest) = widths[first..=last].iter().max().filter(|&&w| w > 1) else {
            break;
        };
        for w in &mut widths[first..=last] {
            if *w == widest {
                *w /= 2;
            }
        }
    }
    widths
}

/// The bodies of the kinds of `mask` in a `share` of the world, on an even spread.
fn expected(layout: &Layout, mask: u32, share: f64) -> f64 {
    (0..layout.ranges.len() as u32)
        .filter(|&k| mask & kind_bit(k) != 0)
        .map(|k| f64::from(layout.ranges[k as usize].capacity) * share)
        .sum()
}

/// The slots of kinds `first ..= last`, padding included.
fn padded(layout: &Layout, first: usize, last: usize) -> (u32, u32) {
    (layout.ranges[first].start, layout.ranges[last].padded_end())
}

/// The narrow phase's teams: every kind, looking for the kinds it collides with.
pub(super) fn narrow(
    lanes: Lanes,
    resident: Option<u64>,
    spec: &WorldSpec,
    layout: &Layout,
    space: &Space,
) -> Teams {
    let masks = spec.collision_masks();
    let kinds = layout.ranges.len();
    let widths = widths(lanes, resident, layout, space, &masks, (0, kinds - 1));
    Teams::new((0, kinds as u32), padded(layout, 0, kinds - 1), |k| {
        widths[k as usize]
    })
}

/// The machines' teams: the kinds from the first with a machine to the last, each looking
/// for the ship, and unless a kamikaze for its own kind and the shots it dodges; `None` if
/// no kind has a machine.
pub(super) fn think(
    lanes: Lanes,
    resident: Option<u64>,
    game: &GameConfig,
    layout: &Layout,
    space: &Space,
) -> Option<Teams> {
    let rules = &game.rules;
    let masks: Vec<u32> = game
        .brains
        .iter()
        .map(|brain| match Machine::from_u32(brain.machine) {
            Machine::None => 0,
            machine => sight_mask(brain, machine, rules.ship_kind, rules.shot_kind),
        })
        .collect();
    let first = masks.iter().position(|&m| m != 0)?;
    let last = masks.iter().rposition(|&m| m != 0)?;
    let widths = widths(lanes, resident, layout, space, &masks, (first, last));
    Some(Teams::new(
        (first as u32, last as u32 + 1),
        padded(layout, first, last),
        |k| widths[k as usize],
    ))
}

/// Whether the machines' launch of `teams` takes its blocks from the last
/// (`ThinkArgs::from_the_end`): where the bodies of the later half of its slots expect more
/// bodies within their vision than those of the earlier half (a kamikaze, which looks at
/// the ship alone, none). The GPU starts a launch's blocks in increasing order, and the
/// blocks of kinds that walk their neighbours take longest: started last, they would leave
/// the GPU to a few of them at the launch's end. `scale-1m`, its kamikazes first, went from
/// 4,058 to 4,303 steps/s on an H200 taken from the end; with its kinds listed the other
/// way round, from 4,269 (in order) to 4,114 (from the end). The integrator's launch after
/// it then runs the other way (see `Config::integrate_from_the_end`).
pub(super) fn think_from_the_end(
    teams: &Teams,
    game: &GameConfig,
    layout: &Layout,
    space: &Space,
) -> bool {
    let area = f64::from(space.size.x) * f64::from(space.size.y);
    // Bodies a body of kind `k` expects within the square of side twice its vision.
    let seen = |k: u32| {
        let Some(brain) = game.brains.get(k as usize) else {
            return 0.0;
        };
        let machine = Machine::from_u32(brain.machine);
        if machine == Machine::None {
            return 0.0;
        }
        let reach = 2.0 * f64::from(brain.vision);
        let share = (reach * reach / area).min(1.0);
        expected(
            layout,
            others_mask(brain, machine, game.rules.shot_kind),
            share,
        )
    };
    // Each half's sum over its slots.
    let middle = (teams.first_slot + teams.end_slot) / 2;
    let (mut early, mut late) = (0.0, 0.0);
    for k in teams.first_kind..teams.end_kind {
        let range = layout.ranges[k as usize];
        let (start, end) = (range.start, range.start + range.capacity);
        let before = end.min(middle).saturating_sub(start);
        early += f64::from(before) * seen(k);
        late += f64::from(range.capacity - before) * seen(k);
    }
    late > early
}
