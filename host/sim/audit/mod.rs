//! An independent audit of the contacts a step's motion made, to compare with the contacts
//! the kernels counted. Brute force over every pair of live bodies whose kinds collide, in
//! f64 and continuous in time: a pair whose paths met between two step ends is a contact
//! even if it overlaps at neither end. It shares no code with the kernels, so it checks their
//! narrow phase (swept or not) rather than repeating it.
//!
//! It compares sets, not counts: each slot's partners and moments against the contacts the
//! kernels logged (`Contacts::log`), so that a spurious contact cannot hide a missed one, and
//! a wrong partner or a late moment shows.

mod geometry;
#[cfg(test)]
mod tests;

use std::collections::BTreeMap;

use glam::Vec2;
use gpuwars_kernels::sim::Touched;

use super::spec::{KindSpec, WorldSpec};
pub use geometry::TIME_TOLERANCE;
use geometry::{Link, scan};

/// Class of the contacts of shots with enemies, counted from the shots.
pub const SHOT_ENEMY: &str = "shot→enemy";
/// Class of the contacts of enemies with the ship, counted from the ship.
pub const ENEMY_SHIP: &str = "enemy→ship";
/// Class of the contacts of movable bodies with walls, counted from the movable bodies.
pub const BODY_WALL: &str = "body→wall";

/// Relative change of every contact size (and tolerance of the speed limits) that a verdict
/// must survive: f32 positions leave a pair that grazes within it undecided.
const MARGIN: f64 = 1e-5;

/// One step end of a world as read back: every slice has one element per slot, in slot
/// order.
#[derive(Clone, Copy, Debug)]
pub struct StepEnd<'a> {
    /// Non-zero where the slot holds a live body.
    pub alive: &'a [u32],
    /// Each body's kind (an index into the spec's kinds).
    pub kind: &'a [u32],
    /// Where each body was at the start of the step that ended here.
    pub prev: &'a [Vec2],
    /// Where it is at the end.
    pub pos: &'a [Vec2],
    /// Its velocity at the end.
    pub vel: &'a [Vec2],
    /// Its energy at the end.
    pub energy: &'a [i32],
    /// The contacts the kernels counted in this step's narrow phase, which tests the motion
    /// of the step before (see [`Accuracy::add_step`]), sorted by slot then partner (as
    /// `Pipeline::contact_log` gives them).
    pub log: &'a [Touched],
    /// Whether this step moved bodies to other slots (renumbering) before its narrow phase:
    /// then no slot holds the body it held at the step before's end.
    pub renumbered: bool,
}

impl StepEnd<'_> {
    /// Number of slots.
    ///
    /// # Panics
    ///
    /// If the slices differ in length.
    pub fn slots(&self) -> usize {
        let n = self.alive.len();
        let lengths = [
            self.kind.len(),
            self.prev.len(),
            self.pos.len(),
            self.vel.len(),
            self.energy.len(),
        ];
        assert!(
            lengths.iter().all(|&l| l == n),
            "a step end's slices differ in length ({n} slots, then {lengths:?})"
        );
        n
    }
}

/// Which kinds play which part in the game, to sort contacts into classes.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Roles {
    /// The ship's kind.
    pub ship: Option<u32>,
    /// The shots' kind.
    pub shot: Option<u32>,
    /// Enemy kinds, one bit per kind.
    pub enemies: u32,
    /// Wall kinds (immovable), one bit per kind.
    pub walls: u32,
}

impl Roles {
    /// The roles of a game's world: the given ship and shot kinds, the controlled kinds as
    /// enemies and the kinds of infinite mass as walls.
    pub fn of(spec: &WorldSpec, ship: Option<u32>, shot: Option<u32>) -> Roles {
        let mask = |keep: fn(&KindSpec) -> bool| {
            (spec.kinds.iter().enumerate())
                .filter(|(_, kind)| keep(kind))
                .fold(0, |mask, (k, _)| mask | 1 << k)
        };
        Roles {
            ship,
            shot,
            enemies: mask(|kind| kind.controlled),
            walls: mask(|kind| kind.mass == f32::INFINITY),
        }
    }

    /// The class of the contacts a body of kind `a` makes with bodies of kind `b` when they
    /// are tallied from `a`'s side; `None` when they are tallied from `b`'s side only.
    fn class(&self, spec: &WorldSpec, a: usize, b: usize) -> Option<String> {
        if let Some(class) = self.special(a, b) {
            return Some(class.to_owned());
        }
        // A pair of kinds belongs to one class, seen from one side (or both, for a kind with
        // itself, which leaves the ratios unchanged).
        if self.special(b, a).is_some() || a > b {
            return None;
        }
        Some(format!("{}→{}", spec.kinds[a].name, spec.kinds[b].name))
    }

    /// The named class of `a`'s contacts with `b`, if any.
    fn special(&self, a: usize, b: usize) -> Option<&'static str> {
        let is = |mask: u32, k: usize| mask >> k & 1 != 0;
        let kind = |role: Option<u32>| role.is_some_and(|r| r as usize == a);
        if kind(self.shot) && is(self.enemies, b) {
            Some(SHOT_ENEMY)
        } else if kind(self.ship) && is(self.enemies, b) {
            Some(ENEMY_SHIP)
        } else if is(self.walls, b) && !is(self.walls, a) {
            Some(BODY_WALL)
        } else {
            None
        }
    }
}

/// Contacts of one class (or of all audited slots), each seen from the slot that counts it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Tally {
    /// Certain contacts the audit found.
    pub expected: u64,
    /// Of those, how many the kernels did not count with that partner.
    pub missed: u64,
    /// Contacts the kernels counted with a partner the audit finds no contact with (nor an
    /// undecidable one), or counted twice.
    pub extra: u64,
    /// A slot's missed contact and extra one taken as a pair: counted, but with another body
    /// (each such pair is one here and neither missed nor extra).
    pub wrong_partner: u64,
    /// Expected contacts of swept pairs counted at a moment more than [`TIME_TOLERANCE`] of
    /// the motion from the audit's.
    pub late: u64,
    /// Expected contacts that overlapped at neither step end: their paths met in between.
    pub tunnelling: u64,
    /// Pairs whose verdict sizes within the margin change (f32 cannot decide them): left out
    /// of the expected and extra contacts, whatever the kernels counted.
    pub undecidable: u64,
    /// Expected contacts of swept pairs whose moment sizes within the margin move by more
    /// than the tolerance: never late.
    pub moment_undecidable: u64,
}

impl Tally {
    /// Missed contacts per thousand expected; `None` when none were expected.
    pub fn missed_per_thousand(&self) -> Option<f64> {
        self.per_thousand(self.missed)
    }

    /// `count` per thousand expected contacts; `None` when none were expected.
    pub fn per_thousand(&self, count: u64) -> Option<f64> {
        (self.expected > 0).then(|| 1000.0 * count as f64 / self.expected as f64)
    }

    fn add(&mut self, other: Tally) {
        self.expected += other.expected;
        self.missed += other.missed;
        self.extra += other.extra;
        self.wrong_partner += other.wrong_partner;
        self.late += other.late;
        self.tunnelling += other.tunnelling;
        self.undecidable += other.undecidable;
        self.moment_undecidable += other.moment_undecidable;
    }
}

/// Penetration depths of the certain contacts that overlap at a step's end.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Depths {
    /// Contacts measured, each pair once.
    pub count: u64,
    /// Sum of their depths.
    pub sum: f64,
    /// The deepest.
    pub max: f64,
}

impl Depths {
    /// Mean depth; `None` when none was measured.
    pub fn mean(&self) -> Option<f64> {
        (self.count > 0).then(|| self.sum / self.count as f64)
    }

    fn add(&mut self, depth: f64) {
        self.count += 1;
        self.sum += depth;
        self.max = self.max.max(depth);
    }
}

/// The audit of a run, step after step: contacts expected, missed and extra by class, and
/// the bodies that broke their kinds' limits.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Accuracy {
    /// Tallies by class ([`SHOT_ENEMY`], [`ENEMY_SHIP`], [`BODY_WALL`], or `A→B` with the
    /// kinds' names), each colliding pair of kinds in one class.
    pub classes: BTreeMap<String, Tally>,
    /// Every audited slot's contacts, whatever the class: each contact between two audited
    /// slots counts from both.
    pub all: Tally,
    /// Of `all`, the contacts of pairs of kinds the world sweeps ([`WorldSpec::pair_sweeps`]).
    pub swept: Tally,
    /// Of `all`, the contacts of pairs of kinds tested at step ends only.
    pub unswept: Tally,
    /// Steps audited.
    pub steps: u64,
    /// Slots audited (body-steps): alive at the step's end and holding the same body at the
    /// next step's narrow phase.
    pub slots_audited: u64,
    /// Live slots left out because the next step moved bodies to other slots.
    pub slots_skipped: u64,
    /// Contacts the kernels counted with bodies born after the step began (no path to
    /// audit).
    pub partners_born: u64,
    /// Depths of the certain contacts at the audited steps' ends, between any live bodies
    /// (audited or not).
    pub depth: Depths,
    /// Audited body-steps faster than their kind's speed limit at the step's end.
    pub speed_violations: u64,
    /// Audited body-steps with more energy than their kind's bodies have at birth.
    pub energy_violations: u64,
}

impl Accuracy {
    /// Audits the motion of one step. `this` is its end (`prev`: where the bodies started,
    /// `pos`: where they ended) and `next` the end of the step after, whose `log` holds the
    /// contacts the kernels counted for that motion. A slot is audited when it holds the same body at both
    /// ends: alive at `this`, and `next` did not renumber. A body that dies in `next` still
    /// had its contacts counted there (it dies after the narrow phase, as a shot does on
    /// the enemy it hits), and a body is born only into a slot that was free. Its partners
    /// are all the live bodies of `this`.
    ///
    /// # Panics
    ///
    /// If the step ends differ in slots, a step end's slices differ in length, or a live
    /// body's kind is not the spec's.
    pub fn add_step(&mut self, spec: &WorldSpec, roles: &Roles, this: &StepEnd, next: &StepEnd) {
        let n = this.slots();
        assert_eq!(next.slots(), n, "two step ends of different worlds");
        let same = |s: usize| this.alive[s] != 0 && !next.renumbered;
        let audited: Vec<bool> = (0..n).map(same).collect();
        self.steps += 1;

        let kinds = spec.kinds.len();
        let masks = spec.collision_masks();
        let classes: Vec<Option<String>> = (0..kinds * kinds)
            .map(|x| {
                let (a, b) = (x / kinds, x % kinds);
                (masks[a] >> b & 1 != 0)
                    .then(|| roles.class(spec, a, b))
                    .flatten()
            })
            .collect();
        for name in classes.iter().flatten() {
            self.classes.entry(name.clone()).or_default();
        }

        // (audited slot, partner, link, moment): sorted, each slot's partners in order.
        let mut links = Vec::new();
        for found in scan(spec, this) {
            if let Some(depth) = found.depth {
                self.depth.add(depth);
            }
            for (s, partner) in [(found.a, found.b), (found.b, found.a)] {
                if audited[s] {
                    links.push((s, partner, found.link, found.moment));
                }
            }
        }
        links.sort_unstable_by_key(|&(s, partner, ..)| (s, partner));

        let swept = spec.sweep_masks();
        let pairs = Pairs {
            kinds,
            classes: &classes,
            swept: &swept,
            end: this,
        };
        let (mut rest, mut log) = (&links[..], next.log);
        for (s, &same) in audited.iter().enumerate() {
            let (mine, tail) = rest.split_at(rest.partition_point(|l| l.0 == s));
            rest = tail;
            let (counted, tail) = log.split_at(log.partition_point(|t| t.slot as usize <= s));
            log = tail;
            let counted = &counted[counted.partition_point(|t| (t.slot as usize) < s)..];
            if !same {
                self.slots_skipped += u64::from(this.alive[s] != 0);
                continue;
            }
            self.add_slot(&pairs, s, mine, counted);
            self.check_limits(&spec.kinds[this.kind[s] as usize], this, s);
        }
    }

    /// Tallies audited slot `s`: the audit's `links` of it (by partner) against the
    /// kernels' records of it (`counted`, by partner).
    fn add_slot(&mut self, pairs: &Pairs, s: usize, links: &[AuditLink], counted: &[Touched]) {
        self.slots_audited += 1;
        let mut records = counted.iter().peekable();
        // Missed and extra contacts by partner, to pair up as wrong partners.
        let (mut missed, mut extra) = (Vec::new(), Vec::new());
        let add = |me: &mut Self, partner: usize, tally: Tally| {
            me.all.add(tally);
            match pairs.swept(s, partner) {
                true => me.swept.add(tally),
                false => me.unswept.add(tally),
            }
            if let Some(t) = pairs.class(s, partner).and_then(|c| me.classes.get_mut(c)) {
                t.add(tally);
            }
        };
        for &(_, partner, link, moment) in links {
            // The records of partners before this one that the audit does not find.
            while let Some(r) = records.next_if(|r| (r.other as usize) < partner) {
                extra.push(r.other as usize);
            }
            let record = records.next_if(|r| r.other as usize == partner);
            let mut tally = Tally::default();
            if link == Link::Uncertain {
                tally.undecidable = 1;
            } else {
                tally.expected = 1;
                tally.tunnelling = u64::from(link == Link::Tunnelling);
                match (record, moment) {
                    (None, _) => missed.push(partner),
                    (Some(_), _) if !pairs.swept(s, partner) => {}
                    (Some(_), None) => tally.moment_undecidable = 1,
                    (Some(r), Some(m)) => {
                        tally.late = u64::from((f64::from(r.time) - m).abs() > TIME_TOLERANCE);
                    }
                }
            }
            add(self, partner, tally);
            // Counted more than once.
            while let Some(r) = records.next_if(|r| r.other as usize == partner) {
                extra.push(r.other as usize);
            }
        }
        extra.extend(records.map(|r| r.other as usize));
        extra.retain(|&partner| {
            let born = pairs.end.alive.get(partner).is_none_or(|&a| a == 0);
            self.partners_born += u64::from(born);
            !born
        });
        let wrong = missed.len().min(extra.len());
        for (i, &partner) in missed.iter().enumerate() {
            let (wrong_partner, missed) = (u64::from(i < wrong), u64::from(i >= wrong));
            add(
                self,
                partner,
                Tally {
                    wrong_partner,
                    missed,
                    ..Tally::default()
                },
            );
        }
        for &partner in &extra[wrong..] {
            add(
                self,
                partner,
                Tally {
                    extra: 1,
                    ..Tally::default()
                },
            );
        }
    }

    /// Counts the limits of its kind that the body in `slot` breaks.
    fn check_limits(&mut self, kind: &KindSpec, end: &StepEnd, slot: usize) {
        let speed = end.vel[slot].as_dvec2().length();
        if kind.max_speed.is_finite() && speed > f64::from(kind.max_speed) * (1.0 + MARGIN) {
            self.speed_violations += 1;
        }
        self.energy_violations += u64::from(end.energy[slot] > kind.energy);
    }

    /// Missed contacts per thousand expected in `class`; `None` when the class is unknown or
    /// none were expected.
    pub fn missed_per_thousand(&self, class: &str) -> Option<f64> {
        self.classes.get(class)?.missed_per_thousand()
    }

    /// Missed contacts per thousand expected over every audited slot; `None` when none were
    /// expected.
    pub fn total_missed_per_thousand(&self) -> Option<f64> {
        self.all.missed_per_thousand()
    }
}

/// One of the audit's links: (audited slot, partner, link, moment).
type AuditLink = (usize, usize, Link, Option<f64>);

/// What a step end's pairs of slots are to the audit: their class and whether swept.
struct Pairs<'a> {
    /// Number of kinds.
    kinds: usize,
    /// The class of kind `a`'s contacts with kind `b`, at `a * kinds + b`.
    classes: &'a [Option<String>],
    /// Each kind's mask of the kinds its contacts with are swept.
    swept: &'a [u32],
    /// The step end whose motion is audited.
    end: &'a StepEnd<'a>,
}

impl Pairs<'_> {
    /// The class of slot `s`'s contacts with `partner`, if tallied from `s`'s side.
    fn class(&self, s: usize, partner: usize) -> Option<&str> {
        let kind = |slot: usize| self.end.kind[slot] as usize;
        self.classes[kind(s) * self.kinds + kind(partner)].as_deref()
    }

    /// Whether slot `s`'s contacts with `partner` are swept.
    fn swept(&self, s: usize, partner: usize) -> bool {
        self.swept[self.end.kind[s] as usize] >> self.end.kind[partner] & 1 != 0
    }
}
