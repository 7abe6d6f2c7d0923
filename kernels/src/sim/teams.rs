//! How a stage's threads map to bodies when a kind's bodies each get a team of lanes.
//!
//! A query of the grid costs its body as many steps as it has neighbours, and a warp waits
//! for its slowest thread: the ship in a swarm, or an enemy inside its group's cluster, walks
//! hundreds of entries while the rest of the launch is done. A kind whose bodies expect many
//! neighbours gets `width` threads a body (a [`Team`]), which split the walk
//! ([`crate::sim::broad::CellIndex::for_each_near_in`]) and fold what they find in the
//! order one thread would, or merge exact sums
//! ([`crate::sim::broad::CellIndex::merge_near_in`]). Each kind keeps its own range of
//! threads, so a warp still runs one kind's code (the paper's grouped warps).

use crate::access::Readable;
use crate::warp::{Team, WARP};
use crate::{DevSlice, Thread};

use super::SlotRange;

/// Most kinds [`Teams`] holds a width for: a mask of kinds has 32 bits.
pub const MAX_KINDS: u32 = 32;

/// The widest team: a warp.
pub const MAX_WIDTH: u32 = WARP;

/// The team width of each kind of `first_kind .. end_kind`, over whose slot ranges (padding
/// included) a stage's threads run kind by kind: kind `k`'s padded range times its width.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct Teams {
    /// `log2(width)` of kinds 0 to 15, four bits each from bit 0 (two words rather than an
    /// array: indexing a kernel parameter by a variable would copy it to local memory).
    low: u64,
    /// The same for kinds 16 to 31.
    high: u64,
    /// The first kind the stage runs.
    pub first_kind: u32,
    /// One past the last kind it runs.
    pub end_kind: u32,
    /// The first slot of the first kind.
    pub first_slot: u32,
    /// One past the last (padded) slot of the last kind.
    pub end_slot: u32,
}

impl Teams {
    /// Every kind of `first_kind .. end_kind`, whose padded ranges are `first_slot ..
    /// end_slot`, with teams of `width(k)` lanes (rounded down to a power of two, 1 to
    /// [`MAX_WIDTH`]).
    pub fn new(
        (first_kind, end_kind): (u32, u32),
        (first_slot, end_slot): (u32, u32),
        width: impl Fn(u32) -> u32,
    ) -> Self {
        let (mut low, mut high) = (0u64, 0u64);
        for k in first_kind..end_kind.min(MAX_KINDS) {
            let log2 = u64::from(width(k).clamp(1, MAX_WIDTH).ilog2());
            if k < 16 {
                low |= log2 << (4 * k);
            } else {
                high |= log2 << (4 * (k - 16));
            }
        }
        Teams {
            low,
            high,
            first_kind,
            end_kind,
            first_slot,
            end_slot,
        }
    }

    /// `self` over the kinds and slots of `wider` (which hold `self`'s): `self`'s widths for
    /// its kinds, `wider`'s for the others.
    pub fn within(&self, wider: &Teams) -> Teams {
        let own = |k: u32| (self.first_kind..self.end_kind).contains(&k);
        Teams::new(
            (wider.first_kind, wider.end_kind),
            (wider.first_slot, wider.end_slot),
            |k| {
                if own(k) {
                    self.width(k)
                } else {
                    wider.width(k)
                }
            },
        )
    }

    /// Lanes a body of kind `kind` gets.
    #[inline(always)]
    pub fn width(&self, kind: u32) -> u32 {
        // Selects, not branches: [`Teams::member`] reads every kind's range before it asks.
        let word = if kind < 16 { self.low } else { self.high };
        let log2 = if kind < MAX_KINDS {
            (word >> (4 * (kind % 16))) & 0xf
        } else {
            0
        };
        1 << log2
    }

    /// Whether every body gets one thread.
    #[inline(always)]
    pub fn single(&self) -> bool {
        self.low == 0 && self.high == 0
    }

    /// Threads the stage launches for slot ranges `ranges` (indexed by kind).
    pub fn threads(&self, ranges: &[SlotRange]) -> u64 {
        (self.first_kind..self.end_kind)
            .map(|k| {
                let span = ranges[k as usize].span();
                u64::from(span) * u64::from(self.width(k))
            })
            .sum()
    }

    /// Each warp's first slot and its bodies' team width, packed as `slot << 3 | log2(width)`,
    /// for slot ranges `ranges` (indexed by kind): the table [`Teams::member`] reads, one
    /// word a warp of the stage's [`Teams::threads`]. A kind's threads fill whole warps (its
    /// padded range is a multiple of 32 slots), so a warp's lanes are one kind's.
    pub fn warp_table<'a>(&'a self, ranges: &'a [SlotRange]) -> impl Iterator<Item = u32> + 'a {
        (self.first_kind..self.end_kind).flat_map(move |k| {
            let range = ranges[k as usize];
            let log2 = self.width(k).trailing_zeros();
            let slots = range.start..range.start + range.span();
            slots
                .step_by((WARP >> log2) as usize)
                .map(move |slot| slot << 3 | log2)
        })
    }

    /// The slot the calling thread works on and its team, or `None` past the last slot and,
    /// on the CPU, for every lane but a team's first (which does the team's work alone).
    /// `warps` is [`Teams::warp_table`]'s (unread where every body gets one thread): one
    /// load a warp, where walking the kinds' ranges took hundreds of instructions.
    #[inline(always)]
    pub fn member(&self, t: Thread, warps: &DevSlice<u32, impl Readable>) -> Option<(u32, Team)> {
        let global = t.global();
        if self.single() {
            let slot = self.first_slot.checked_add(global)?;
            return (slot < self.end_slot).then_some((slot, Team::new(t.lane(), 1)));
        }
        let warp = global / WARP;
        if warp >= warps.len() {
            return None;
        }
        let entry = warps.get(warp);
        let log2 = entry & 7;
        let team = Team::new(t.lane(), 1 << log2);
        let slot = (entry >> 3) + (t.lane() >> log2);
        (!team.is_copy()).then_some((slot, team))
    }
}
