//! An independent audit of the contacts a step's motion made, to compare with the contacts
//! the kernels counted. Brute force over every pair of live bodies whose kinds collide, in
//! f64 and continuous in time: a pair whose paths met between two step ends is a contact
//! even if it overlaps at neither end. It shares no code with the kernels, so it checks their
//! narrow phase (swept or not) rather than repeating it.

use std::collections::BTreeMap;

use glam::{DVec2, Vec2};
use rayon::prelude::*;

use super::spec::{Boundary, KindSpec, Shape, WorldSpec};

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
    /// The contacts the kernels counted for each slot in this step's narrow phase, which
    /// tests the motion of the step before (see [`Accuracy::add_step`]).
    pub counted: &'a [u32],
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
            self.counted.len(),
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
    /// Of those, how many the kernels' counts lack.
    pub missed: u64,
    /// Contacts the kernels counted beyond the expected ones (in a class: those its
    /// uncertain pairs may explain; the rest only in [`Accuracy::all`]).
    pub extra: u64,
    /// Expected contacts that overlapped at neither step end: their paths met in between.
    pub tunnelling: u64,
}

impl Tally {
    /// Missed contacts per thousand expected; `None` when none were expected.
    pub fn missed_per_thousand(&self) -> Option<f64> {
        (self.expected > 0).then(|| 1000.0 * self.missed as f64 / self.expected as f64)
    }

    fn add(&mut self, other: Tally) {
        self.expected += other.expected;
        self.missed += other.missed;
        self.extra += other.extra;
        self.tunnelling += other.tunnelling;
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
    /// Steps audited.
    pub steps: u64,
    /// Slots audited (body-steps): alive at the step's end and holding the same body at the
    /// next step's narrow phase.
    pub slots_audited: u64,
    /// Live slots left out because the next step moved bodies to other slots.
    pub slots_skipped: u64,
    /// Pairs of an audited slot and a partner whose verdict the margin leaves undecided (left
    /// out of the expected and missed contacts).
    pub uncertain: u64,
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
    /// `pos`: where they ended) and `next` the end of the step after, whose `counted` are the
    /// kernels' counts for that motion. A slot is audited when it holds the same body at both
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

        // (audited slot, link, partner): sorted, each slot's partners come in the order its
        // missed contacts are attributed, then its uncertain ones.
        let mut links = Vec::new();
        for found in scan(spec, this) {
            if let Some(depth) = found.depth {
                self.depth.add(depth);
            }
            for (s, partner) in [(found.a, found.b), (found.b, found.a)] {
                if audited[s] {
                    links.push((s, found.link, partner));
                }
            }
        }
        links.sort_unstable();

        let mut rest = &links[..];
        for (s, &same) in audited.iter().enumerate() {
            if !same {
                self.slots_skipped += u64::from(this.alive[s] != 0);
                continue;
            }
            let (mine, tail) = rest.split_at(rest.partition_point(|&(t, ..)| t == s));
            rest = tail;
            let class = |partner: usize| {
                classes[this.kind[s] as usize * kinds + this.kind[partner] as usize].as_deref()
            };
            self.add_slot(mine, next.counted[s], class);
            self.check_limits(&spec.kinds[this.kind[s] as usize], this, s);
        }
    }

    /// Tallies an audited slot: its links (in attribution order) and the contacts the
    /// kernels counted for it; `class` names the class of a partner's contacts with it.
    fn add_slot<'c>(
        &mut self,
        links: &[(usize, Link, usize)],
        counted: u32,
        class: impl Fn(usize) -> Option<&'c str>,
    ) {
        self.slots_audited += 1;
        let certain = links.iter().filter(|l| l.1 != Link::Uncertain).count();
        let missed = certain.saturating_sub(counted as usize);
        let extra = (counted as usize).saturating_sub(certain);
        for (i, &(_, link, partner)) in links.iter().enumerate() {
            let mut add = Tally::default();
            if link == Link::Uncertain {
                self.uncertain += 1;
                add.extra = u64::from(i - certain < extra);
            } else {
                add.expected = 1;
                add.missed = u64::from(i < missed);
                add.tunnelling = u64::from(link == Link::Tunnelling);
                self.all.add(add);
            }
            if let Some(tally) = class(partner).and_then(|c| self.classes.get_mut(c)) {
                tally.add(add);
            }
        }
        self.all.extra += extra as u64;
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

/// How a pair of bodies relates to a step's motion, in the order a slot's partners are
/// attributed missed contacts (then extra ones).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
enum Link {
    /// A certain contact whose paths met between the step's ends only.
    Tunnelling,
    /// A certain contact that overlaps at the step's end.
    End,
    /// Contact or not depending on sizes within the margin.
    Uncertain,
}

/// A pair of live bodies that made contact during the step or may have.
struct Found {
    a: usize,
    b: usize,
    link: Link,
    /// The penetration at the step's end of a certain contact that overlaps there.
    depth: Option<f64>,
}

/// Every pair of live bodies of `this` whose kinds collide and whose verdict is a contact or
/// uncertain, in a fixed order (so the depths' sum is reproducible).
fn scan(spec: &WorldSpec, this: &StepEnd) -> Vec<Found> {
    let frame = Frame::of(spec);
    let masks = spec.collision_masks();
    let kinds = spec.kinds.len();
    let mut members = vec![Vec::new(); kinds];
    for s in (0..this.slots()).filter(|&s| this.alive[s] != 0) {
        members[this.kind[s] as usize].push(s);
    }
    let prev: Vec<DVec2> = this.prev.iter().map(|p| p.as_dvec2()).collect();
    let pos: Vec<DVec2> = this.pos.iter().map(|p| p.as_dvec2()).collect();

    let mut found = Vec::new();
    for i in 0..kinds {
        for j in (i..kinds).filter(|&j| masks[i] >> j & 1 != 0) {
            let overlap = Overlap::of(spec.kinds[i].shape, spec.kinds[j].shape);
            // Nothing outside this box overlaps at any size within the margin.
            let reach = overlap.extent() * (1.0 + 2.0 * MARGIN);
            let (first, second) = (&members[i], &members[j]);
            let (prev, pos) = (&prev, &pos);
            found.par_extend((0..first.len()).into_par_iter().flat_map_iter(|x| {
                let a = first[x];
                let partners = if i == j { &second[x + 1..] } else { second };
                partners.iter().filter_map(move |&b| {
                    let d0 = frame.offset(prev[a], prev[b]);
                    let d1 = frame.offset(pos[a], pos[b]);
                    let end = frame.nearest(d1, d0);
                    let (lo, hi) = (d0.min(d1).min(end), d0.max(d1).max(end));
                    if lo.cmpge(reach).any() || hi.cmple(-reach).any() {
                        return None;
                    }
                    let (link, depth) = judge(overlap, d0, end, d1)?;
                    Some(Found { a, b, link, depth })
                })
            }));
        }
    }
    found
}

/// The verdict on a pair whose offset went from `d0` to `end` in a straight line (`d1`: the
/// same end as the world measures it, its image nearest zero), and its depth at the end for a
/// certain contact that overlaps there; `None` for a certain non-contact.
fn judge(overlap: Overlap, d0: DVec2, end: DVec2, d1: DVec2) -> Option<(Link, Option<f64>)> {
    let contact = |o: Overlap| o.contains(d1) || (!o.contains(d0) && o.meets(d0, end));
    let verdict = contact(overlap);
    if [1.0 - MARGIN, 1.0 + MARGIN]
        .into_iter()
        .any(|scale| contact(overlap.scaled(scale)) != verdict)
    {
        return Some((Link::Uncertain, None));
    }
    if !verdict {
        None
    } else if overlap.contains(d1) {
        Some((Link::End, Some(overlap.depth(d1))))
    } else {
        Some((Link::Tunnelling, None))
    }
}

/// How a world measures the offset between two positions.
#[derive(Clone, Copy, Debug)]
struct Frame {
    /// The world's size, where it wraps around.
    period: Option<DVec2>,
}

impl Frame {
    fn of(spec: &WorldSpec) -> Frame {
        Frame {
            period: (spec.boundary == Boundary::Wrap).then(|| spec.size.as_dvec2()),
        }
    }

    /// `to - from`, on a wrapping world each axis at its image nearest zero.
    fn offset(self, from: DVec2, to: DVec2) -> DVec2 {
        self.nearest(to - from, DVec2::ZERO)
    }

    /// On a wrapping world, the image of `d` nearest `to` along each axis (one period away at
    /// most); `d` itself otherwise. Two bodies' offset at a step's end is taken as the image
    /// nearest their offset at its start: offsets near half the world jump by a period when
    /// they cross it, and the straight path between the two images would cross the whole
    /// world, through contacts that never happened.
    fn nearest(self, d: DVec2, to: DVec2) -> DVec2 {
        let Some(period) = self.period else {
            return d;
        };
        // Without branches: whether a pair's offset wraps is a coin toss, often mispredicted.
        let gap = d - to;
        let half = 0.5 * period;
        let shift = DVec2::select(gap.cmpgt(half), period, DVec2::ZERO)
            - DVec2::select(gap.cmplt(-half), period, DVec2::ZERO);
        d - shift
    }
}

/// The set of offsets (from one body to the other) at which two bounds overlap: one bound
/// grown by the other. Each is symmetric about zero, so the offset's direction does not
/// matter; each is open (touching is not overlapping).
#[derive(Clone, Copy, Debug, PartialEq)]
enum Overlap {
    /// Two circles: a disk of the radii's sum.
    Disk(f64),
    /// A circle and a rectangle: the rectangle with corners rounded by the circle's radius.
    Rounded { half: DVec2, radius: f64 },
    /// Two rectangles: a rectangle of the half extents' sum.
    Rect(DVec2),
}

impl Overlap {
    fn of(a: Shape, b: Shape) -> Overlap {
        match (a, b) {
            (Shape::Circle { radius: ra }, Shape::Circle { radius: rb }) => {
                Overlap::Disk(f64::from(ra) + f64::from(rb))
            }
            (Shape::Circle { radius }, Shape::Rect { half })
            | (Shape::Rect { half }, Shape::Circle { radius }) => Overlap::Rounded {
                half: half.as_dvec2(),
                radius: f64::from(radius),
            },
            (Shape::Rect { half: ha }, Shape::Rect { half: hb }) => {
                Overlap::Rect(ha.as_dvec2() + hb.as_dvec2())
            }
        }
    }

    /// The set for every contact size multiplied by `scale`.
    fn scaled(self, scale: f64) -> Overlap {
        match self {
            Overlap::Disk(reach) => Overlap::Disk(reach * scale),
            Overlap::Rounded { half, radius } => Overlap::Rounded {
                half: half * scale,
                radius: radius * scale,
            },
            Overlap::Rect(half) => Overlap::Rect(half * scale),
        }
    }

    /// Half extents of the set's bounding box.
    fn extent(self) -> DVec2 {
        match self {
            Overlap::Disk(reach) => DVec2::splat(reach),
            Overlap::Rounded { half, radius } => half + radius,
            Overlap::Rect(half) => half,
        }
    }

    fn contains(self, d: DVec2) -> bool {
        match self {
            Overlap::Disk(reach) => d.length_squared() < reach * reach,
            Overlap::Rounded { half, radius } => {
                (d - d.clamp(-half, half)).length_squared() < radius * radius
            }
            Overlap::Rect(half) => d.abs().cmplt(half).all(),
        }
    }

    /// Whether the closed segment from `from` to `to` meets the set.
    fn meets(self, from: DVec2, to: DVec2) -> bool {
        match self {
            Overlap::Disk(reach) => disk_meets(DVec2::ZERO, reach, from, to),
            // A union of open sets: a cross of two rectangles and a disk at each corner.
            Overlap::Rounded { half, radius } => {
                rect_meets(half + DVec2::new(radius, 0.0), from, to)
                    || rect_meets(half + DVec2::new(0.0, radius), from, to)
                    || [(1.0, 1.0), (1.0, -1.0), (-1.0, 1.0), (-1.0, -1.0)]
                        .into_iter()
                        .any(|(x, y)| disk_meets(half * DVec2::new(x, y), radius, from, to))
            }
            Overlap::Rect(half) => rect_meets(half, from, to),
        }
    }

    /// The penetration at `d` (inside the set), measured as the kernels do: by the distance
    /// between the circles' centres, or the least overlap along an axis when the centres are
    /// inside rectangles, or the circle's distance to the rectangle.
    fn depth(self, d: DVec2) -> f64 {
        match self {
            Overlap::Disk(reach) => reach - d.length(),
            Overlap::Rounded { half, radius } => {
                let closest = d.clamp(-half, half);
                if closest == d {
                    (half - d.abs()).min_element() + radius
                } else {
                    radius - (d - closest).length()
                }
            }
            Overlap::Rect(half) => (half - d.abs()).min_element(),
        }
    }
}

/// Whether the closed segment from `from` to `to` meets the open disk of `radius` around
/// `centre`: its point nearest the centre is inside.
fn disk_meets(centre: DVec2, radius: f64, from: DVec2, to: DVec2) -> bool {
    let along = to - from;
    let length2 = along.length_squared();
    let t = if length2 > 0.0 {
        ((centre - from).dot(along) / length2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (from + along * t - centre).length_squared() < radius * radius
}

/// Whether the closed segment from `from` to `to` meets the open rectangle of half extents
/// `half` around zero: the open parameter intervals in which each axis is inside overlap
/// each other and `[0, 1]`.
fn rect_meets(half: DVec2, from: DVec2, to: DVec2) -> bool {
    let (x0, x1) = slab(from.x, to.x, half.x);
    let (y0, y1) = slab(from.y, to.y, half.y);
    let (lo, hi) = (x0.max(y0), x1.min(y1));
    lo < hi && lo < 1.0 && hi > 0.0
}

/// The open interval of `t` in which `|a + (b - a) t| < half`. When `a == b`, dividing by
/// zero gives every `t` inside and none outside (infinities of one sign; and where `a` is
/// `±half`, a NaN that `min` and `max` drop).
fn slab(a: f64, b: f64, half: f64) -> (f64, f64) {
    let v = b - a;
    let (t0, t1) = ((-half - a) / v, (half - a) / v);
    (t0.min(t1), t0.max(t1))
}

#[cfg(test)]
mod tests {
    use proptest::prelude::*;

    use super::*;

    /// A kind of the given shape colliding with `with`: mass 1, energy 100, no limits.
    fn kind(name: &str, shape: Shape, with: &[&str]) -> KindSpec {
        KindSpec {
            name: name.into(),
            shape,
            mass: 1.0,
            capacity: 64,
            energy: 100,
            damage: 0,
            restitution: 0.5,
            max_speed: f32::INFINITY,
            collides_with: with.iter().map(|s| s.to_string()).collect(),
            lifetime: f32::INFINITY,
            controlled: false,
            sweep: super::super::spec::Sweep::Off,
            top_speed: f32::INFINITY,
        }
    }

    fn circle(radius: f32) -> Shape {
        Shape::Circle { radius }
    }

    fn rect(x: f32, y: f32) -> Shape {
        Shape::Rect {
            half: Vec2::new(x, y),
        }
    }

    fn world(side: f32, boundary: Boundary, kinds: Vec<KindSpec>) -> WorldSpec {
        let spec = WorldSpec {
            size: Vec2::splat(side),
            dt: 1.0 / 60.0,
            boundary,
            vision: 0.0,
            kinds,
            physics: Default::default(),
            field: Default::default(),
        };
        spec.validate().unwrap();
        spec
    }

    /// A shot (radius 1) and a controlled enemy (radius 5) that collide.
    fn shots_and_enemies(side: f32, boundary: Boundary) -> (WorldSpec, Roles) {
        let mut enemy = kind("enemy", circle(5.0), &[]);
        enemy.controlled = true;
        let spec = world(
            side,
            boundary,
            vec![kind("shot", circle(1.0), &["enemy"]), enemy],
        );
        let roles = Roles::of(&spec, None, Some(0));
        (spec, roles)
    }

    /// A body over one step.
    #[derive(Clone, Copy)]
    struct Body {
        kind: u32,
        from: Vec2,
        to: Vec2,
        vel: Vec2,
        energy: i32,
    }

    fn moving(kind: u32, from: (f32, f32), to: (f32, f32)) -> Body {
        Body {
            kind,
            from: from.into(),
            to: to.into(),
            vel: Vec2::ZERO,
            energy: 1,
        }
    }

    fn still(kind: u32, at: (f32, f32)) -> Body {
        moving(kind, at, at)
    }

    /// The arrays of a step end.
    #[derive(Clone)]
    struct Arrays {
        alive: Vec<u32>,
        kind: Vec<u32>,
        prev: Vec<Vec2>,
        pos: Vec<Vec2>,
        vel: Vec<Vec2>,
        energy: Vec<i32>,
        counted: Vec<u32>,
        renumbered: bool,
    }

    impl Arrays {
        fn end(&self) -> StepEnd<'_> {
            StepEnd {
                alive: &self.alive,
                kind: &self.kind,
                prev: &self.prev,
                pos: &self.pos,
                vel: &self.vel,
                energy: &self.energy,
                counted: &self.counted,
                renumbered: self.renumbered,
            }
        }
    }

    /// The end of the bodies' step, one body a slot, and the end of the next, in which they
    /// rest and the kernels counted `counted` for the step's motion.
    fn ends(bodies: &[Body], counted: &[u32]) -> (Arrays, Arrays) {
        let this = Arrays {
            alive: vec![1; bodies.len()],
            kind: bodies.iter().map(|b| b.kind).collect(),
            prev: bodies.iter().map(|b| b.from).collect(),
            pos: bodies.iter().map(|b| b.to).collect(),
            vel: bodies.iter().map(|b| b.vel).collect(),
            energy: bodies.iter().map(|b| b.energy).collect(),
            counted: vec![0; bodies.len()],
            renumbered: false,
        };
        let next = Arrays {
            prev: this.pos.clone(),
            counted: counted.to_vec(),
            ..this.clone()
        };
        (this, next)
    }

    fn audit(spec: &WorldSpec, roles: &Roles, bodies: &[Body], counted: &[u32]) -> Accuracy {
        let (this, next) = ends(bodies, counted);
        let mut accuracy = Accuracy::default();
        accuracy.add_step(spec, roles, &this.end(), &next.end());
        accuracy
    }

    fn tally(expected: u64, missed: u64, extra: u64, tunnelling: u64) -> Tally {
        Tally {
            expected,
            missed,
            extra,
            tunnelling,
        }
    }

    #[test]
    fn a_shot_through_an_enemy_between_step_ends_is_a_tunnelling_contact() {
        let (spec, roles) = shots_and_enemies(100.0, Boundary::Clamp);
        // 10 units from the enemy's centre at both ends (radii sum to 6), through it between.
        let bodies = [
            moving(0, (40.0, 50.0), (60.0, 50.0)),
            still(1, (50.0, 50.0)),
        ];

        let missed = audit(&spec, &roles, &bodies, &[0, 0]);
        assert_eq!(missed.classes[SHOT_ENEMY], tally(1, 1, 0, 1));
        // The enemy's side counts too, in no class.
        assert_eq!(missed.all, tally(2, 2, 0, 2));
        assert_eq!(missed.missed_per_thousand(SHOT_ENEMY), Some(1000.0));
        assert_eq!(missed.total_missed_per_thousand(), Some(1000.0));
        assert_eq!((missed.slots_audited, missed.slots_skipped), (2, 0));
        assert_eq!(missed.uncertain, 0);
        // No overlap at the end, so no depth.
        assert_eq!(missed.depth.count, 0);

        let found = audit(&spec, &roles, &bodies, &[1, 1]);
        assert_eq!(found.classes[SHOT_ENEMY], tally(1, 0, 0, 1));
        assert_eq!(found.missed_per_thousand(SHOT_ENEMY), Some(0.0));

        let twice = audit(&spec, &roles, &bodies, &[2, 1]);
        assert_eq!(twice.all, tally(2, 0, 1, 2));
        // Nothing uncertain explains the extra one, so it stays out of the class.
        assert_eq!(twice.classes[SHOT_ENEMY].extra, 0);
    }

    #[test]
    fn a_shot_that_stops_short_or_ends_inside() {
        let (spec, roles) = shots_and_enemies(100.0, Boundary::Clamp);
        let short = [
            moving(0, (30.0, 50.0), (43.5, 50.0)),
            still(1, (50.0, 50.0)),
        ];
        assert_eq!(audit(&spec, &roles, &short, &[0, 0]).all, Tally::default());
        // Ends 4 from the centre: a contact at the step's end, 2 deep.
        let inside = [
            moving(0, (30.0, 50.0), (46.0, 50.0)),
            still(1, (50.0, 50.0)),
        ];
        let accuracy = audit(&spec, &roles, &inside, &[1, 0]);
        assert_eq!(accuracy.classes[SHOT_ENEMY], tally(1, 0, 0, 0));
        assert_eq!(accuracy.all, tally(2, 1, 0, 0));
        assert_eq!(accuracy.depth.count, 1);
        assert!((accuracy.depth.sum - 2.0).abs() < 1e-12);
        assert_eq!(accuracy.depth.max, accuracy.depth.sum);
    }

    #[test]
    fn a_grazing_pair_is_uncertain_and_may_explain_an_extra() {
        let (spec, roles) = shots_and_enemies(100.0, Boundary::Clamp);
        // Passes exactly 6 from the centre: touching, at the radii's sum.
        let grazing = [
            moving(0, (40.0, 56.0), (60.0, 56.0)),
            still(1, (50.0, 50.0)),
        ];
        let accuracy = audit(&spec, &roles, &grazing, &[1, 0]);
        assert_eq!(accuracy.uncertain, 2);
        assert_eq!(accuracy.all, tally(0, 0, 1, 0));
        assert_eq!(accuracy.classes[SHOT_ENEMY], tally(0, 0, 1, 0));
        assert_eq!(accuracy.missed_per_thousand(SHOT_ENEMY), None);

        // Half a unit either side decides it.
        let clear = [
            moving(0, (40.0, 56.5), (60.0, 56.5)),
            still(1, (50.0, 50.0)),
        ];
        let accuracy = audit(&spec, &roles, &clear, &[0, 0]);
        assert_eq!((accuracy.uncertain, accuracy.all), (0, Tally::default()));
        let through = [
            moving(0, (40.0, 55.5), (60.0, 55.5)),
            still(1, (50.0, 50.0)),
        ];
        let accuracy = audit(&spec, &roles, &through, &[0, 0]);
        assert_eq!((accuracy.uncertain, accuracy.all), (0, tally(2, 2, 0, 2)));
    }

    #[test]
    fn a_pair_that_overlapped_at_the_start_and_separated_is_no_contact() {
        let (spec, roles) = shots_and_enemies(100.0, Boundary::Clamp);
        let bodies = [
            still(1, (50.0, 50.0)),
            moving(0, (52.0, 50.0), (60.0, 50.0)),
        ];
        let accuracy = audit(&spec, &roles, &bodies, &[1, 1]);
        assert_eq!(accuracy.all, tally(0, 0, 2, 0));
        assert_eq!(accuracy.uncertain, 0);
    }

    #[test]
    fn contacts_reach_across_a_wrapping_worlds_seam() {
        let (wrapping, roles) = shots_and_enemies(100.0, Boundary::Wrap);
        // From x = 94 the shot goes 14 units to the right, across the seam to x = 8, through
        // the enemy at x = 1 (7 away at both ends; the radii sum to 6).
        let bodies = [moving(0, (94.0, 50.0), (8.0, 50.0)), still(1, (1.0, 50.0))];
        let accuracy = audit(&wrapping, &roles, &bodies, &[0, 1]);
        assert_eq!(accuracy.classes[SHOT_ENEMY], tally(1, 1, 0, 1));
        assert_eq!(accuracy.all, tally(2, 1, 0, 2));

        // The same numbers in a clamped world: 93 to 7 units away, never closer.
        let (clamped, roles) = shots_and_enemies(100.0, Boundary::Clamp);
        assert_eq!(
            audit(&clamped, &roles, &bodies, &[0, 0]).all,
            Tally::default()
        );
    }

    #[test]
    fn an_offset_crossing_half_the_world_is_no_path_through_zero() {
        let (spec, roles) = shots_and_enemies(100.0, Boundary::Wrap);
        // 49.75 apart, then 50.25 (measured as -49.75 the other way round): they stayed half
        // the world apart.
        let bodies = [
            still(1, (10.0, 50.0)),
            moving(0, (59.75, 50.0), (60.25, 50.0)),
        ];
        let accuracy = audit(&spec, &roles, &bodies, &[0, 0]);
        assert_eq!((accuracy.all, accuracy.uncertain), (Tally::default(), 0));
    }

    /// An immovable crate (half extents 10 × 5) and a ball of radius 2.
    fn crates_and_balls() -> (WorldSpec, Roles) {
        let mut crate_ = kind("crate", rect(10.0, 5.0), &[]);
        crate_.mass = f32::INFINITY;
        let spec = world(
            200.0,
            Boundary::Clamp,
            vec![crate_, kind("ball", circle(2.0), &["crate"])],
        );
        let roles = Roles::of(&spec, None, None);
        (spec, roles)
    }

    /// The ball's contacts with a crate at (50, 50), whichever slot comes first.
    fn ball_and_crate(ball: Body) -> Tally {
        let (spec, roles) = crates_and_balls();
        let crate_ = still(0, (50.0, 50.0));
        let first = audit(&spec, &roles, &[crate_, ball], &[0, 0]);
        let second = audit(&spec, &roles, &[ball, crate_], &[0, 0]);
        assert_eq!(first, second);
        assert_eq!(first.uncertain, 0);
        // Counted from the ball's side only.
        assert_eq!(first.classes.keys().collect::<Vec<_>>(), [BODY_WALL]);
        first.classes[BODY_WALL]
    }

    #[test]
    fn a_ball_past_a_crates_corner() {
        // Along x + y = 117: 1/√2 from the corner (60, 55), closer than the radius, while
        // 6 and 4 from the crate at its ends.
        let cut = moving(1, (56.0, 61.0), (64.0, 53.0));
        assert_eq!(ball_and_crate(cut), tally(1, 1, 0, 1));
        // Along x + y = 118: 3/√2 > 2 from the corner, though inside the crate's box grown
        // by the radius.
        let clear = moving(1, (57.0, 61.0), (65.0, 53.0));
        assert_eq!(ball_and_crate(clear), tally(0, 0, 0, 0));
    }

    #[test]
    fn a_ball_through_or_along_a_crates_faces() {
        let through = moving(1, (50.0, 40.0), (50.0, 60.0));
        assert_eq!(ball_and_crate(through), tally(1, 1, 0, 1));
        // 1.5 above the top face.
        let along = moving(1, (30.0, 56.5), (70.0, 56.5));
        assert_eq!(ball_and_crate(along), tally(1, 1, 0, 1));
        let above = moving(1, (30.0, 57.5), (70.0, 57.5));
        assert_eq!(ball_and_crate(above), tally(0, 0, 0, 0));
    }

    #[test]
    fn a_ball_resting_near_a_crates_corner() {
        let (spec, roles) = crates_and_balls();
        let crate_ = still(0, (50.0, 50.0));
        // 1.2 and 1.8 beyond the corner (60, 55) along both axes: inside the grown box both
        // times, within the radius of the corner the first time only.
        let near = audit(&spec, &roles, &[crate_, still(1, (61.2, 56.2))], &[0, 1]);
        assert_eq!(near.classes[BODY_WALL], tally(1, 0, 0, 0));
        let gap = (f64::from(61.2f32) - 60.0).hypot(f64::from(56.2f32) - 55.0);
        assert_eq!(near.depth.count, 1);
        assert!((near.depth.sum - (2.0 - gap)).abs() < 1e-12);
        let far = audit(&spec, &roles, &[crate_, still(1, (61.8, 56.8))], &[0, 0]);
        assert_eq!((far.all, far.depth.count), (Tally::default(), 0));
        // A centre inside: the nearest face (2 away) plus the radius.
        let inside = audit(&spec, &roles, &[crate_, still(1, (58.0, 51.0))], &[1, 1]);
        assert_eq!(inside.all, tally(2, 0, 0, 0));
        assert_eq!((inside.depth.count, inside.depth.max), (1, 4.0));
    }

    /// Rectangles of half extents 2 × 2 and 3 × 1 (overlapping within 5 × 3 of each other),
    /// the first at (50, 50), the second moving.
    fn rect_pair(second: Body) -> Accuracy {
        let spec = world(
            100.0,
            Boundary::Clamp,
            vec![
                kind("a", rect(2.0, 2.0), &["b"]),
                kind("b", rect(3.0, 1.0), &[]),
            ],
        );
        let roles = Roles::of(&spec, None, None);
        audit(&spec, &roles, &[still(0, (50.0, 50.0)), second], &[0, 0])
    }

    #[test]
    fn rectangles_meet_by_their_slabs() {
        let straight = rect_pair(moving(1, (40.0, 52.0), (60.0, 52.0)));
        assert_eq!(straight.classes.keys().collect::<Vec<_>>(), ["a→b"]);
        assert_eq!(straight.classes["a→b"], tally(1, 1, 0, 1));
        let above = rect_pair(moving(1, (40.0, 53.5), (60.0, 53.5)));
        assert_eq!(above.classes["a→b"], Tally::default());
        // Offset from (-7.5, 0) to (0, 7.5): inside at (-4.9, 2.6).
        let diagonal = rect_pair(moving(1, (42.5, 50.0), (50.0, 57.5)));
        assert_eq!(diagonal.classes["a→b"], tally(1, 1, 0, 1));
        // From (-9, 0) to (0, 9): 1/√2 from the corner (-5, 3), yet outside.
        let past = rect_pair(moving(1, (41.0, 50.0), (50.0, 59.0)));
        assert_eq!(past.classes["a→b"], Tally::default());
        assert_eq!(past.uncertain, 0);
        // From (-8, 0) to (0, 8): through the corner exactly.
        let corner = rect_pair(moving(1, (42.0, 50.0), (50.0, 58.0)));
        assert_eq!(
            (corner.classes["a→b"], corner.uncertain),
            (Tally::default(), 2)
        );
        // At rest 4 × 1 apart: overlaps of 1 and 2, the least is the depth.
        let resting = rect_pair(still(1, (54.0, 51.0)));
        assert_eq!(resting.classes["a→b"], tally(1, 1, 0, 0));
        assert_eq!((resting.depth.count, resting.depth.max), (1, 1.0));
    }

    #[test]
    fn bodies_that_die_after_counting_are_audited_and_renumbered_steps_skipped() {
        let spec = world(
            100.0,
            Boundary::Clamp,
            vec![kind("rock", circle(3.0), &["rock"])],
        );
        let roles = Roles::of(&spec, None, None);
        let bodies = [
            still(0, (50.0, 50.0)),
            still(0, (54.0, 50.0)),
            still(0, (46.0, 50.0)),
            still(0, (50.0, 55.0)),
            still(0, (0.0, 10.0)),
        ];
        let (this, mut next) = ends(&bodies, &[0; 5]);
        // Slot 2's body died in the next step, after its narrow phase counted its contacts.
        next.alive[2] = 0;
        let mut accuracy = Accuracy::default();
        accuracy.add_step(&spec, &roles, &this.end(), &next.end());
        assert_eq!((accuracy.slots_audited, accuracy.slots_skipped), (5, 0));
        // Slot 0 touches slots 1, 2 and 3 (4, 4 and 5 away; the radii sum to 6), each of
        // those only slot 0, slot 4 nothing.
        assert_eq!(accuracy.all, tally(6, 6, 0, 0));
        assert_eq!(accuracy.classes["rock→rock"], accuracy.all);
        // Every pair's depth: 2, 2 and 1.
        assert_eq!(accuracy.depth.count, 3);
        assert_eq!((accuracy.depth.sum, accuracy.depth.max), (5.0, 2.0));
        assert_eq!(accuracy.steps, 1);
        // A step that renumbered: no slot holds its body of the step before.
        next.alive[2] = 1;
        next.renumbered = true;
        let mut renumbered = Accuracy::default();
        renumbered.add_step(&spec, &roles, &this.end(), &next.end());
        assert_eq!((renumbered.slots_audited, renumbered.slots_skipped), (0, 5));
        assert_eq!(renumbered.all, Tally::default());
    }

    #[test]
    fn contacts_are_sorted_into_classes() {
        let mut wall = kind("wall", rect(20.0, 20.0), &[]);
        wall.mass = f32::INFINITY;
        let mut enemy = kind("enemy", circle(5.0), &["enemy", "rock"]);
        enemy.controlled = true;
        let spec = world(
            400.0,
            Boundary::Clamp,
            vec![
                kind("ship", circle(8.0), &["enemy", "wall"]),
                kind("shot", circle(1.0), &["enemy", "wall"]),
                wall,
                enemy,
                kind("rock", circle(3.0), &[]),
            ],
        );
        let roles = Roles::of(&spec, Some(0), Some(1));
        assert_eq!(
            roles,
            Roles {
                ship: Some(0),
                shot: Some(1),
                enemies: 1 << 3,
                walls: 1 << 2
            }
        );
        let bodies = [
            // The ship and an enemy 5 apart.
            still(0, (300.0, 300.0)),
            // The shot ends inside the wall and 4 from the enemy of slot 3, having passed
            // through the enemy of slot 4.
            moving(1, (140.0, 100.0), (119.0, 100.0)),
            still(2, (100.0, 100.0)),
            still(3, (119.0, 104.0)),
            still(3, (130.0, 100.0)),
            still(3, (305.0, 300.0)),
            // A rock and an enemy 5 apart, two enemies 8 apart.
            still(4, (300.0, 250.0)),
            still(3, (300.0, 245.0)),
            still(3, (200.0, 300.0)),
            still(3, (208.0, 300.0)),
        ];
        // The ship missed its contact; the shot one of three.
        let counted = [0, 2, 1, 1, 1, 1, 1, 1, 1, 1];
        let accuracy = audit(&spec, &roles, &bodies, &counted);
        let names: Vec<&str> = accuracy.classes.keys().map(String::as_str).collect();
        let mut expected_names = [
            BODY_WALL,
            ENEMY_SHIP,
            SHOT_ENEMY,
            "enemy→enemy",
            "enemy→rock",
        ];
        expected_names.sort();
        assert_eq!(names, expected_names);
        // The missed one goes to the tunnelling partner first, though the wall's slot is
        // lower.
        assert_eq!(accuracy.classes[SHOT_ENEMY], tally(2, 1, 0, 1));
        assert_eq!(accuracy.classes[BODY_WALL], tally(1, 0, 0, 0));
        assert_eq!(accuracy.classes[ENEMY_SHIP], tally(1, 1, 0, 0));
        assert_eq!(accuracy.classes["enemy→rock"], tally(1, 0, 0, 0));
        assert_eq!(accuracy.classes["enemy→enemy"], tally(2, 0, 0, 0));
        // Every slot's view: the shot's 3, one each for the other nine.
        assert_eq!(accuracy.all, tally(12, 2, 0, 2));

        // Without the tunnelling partner, the lower slot's partner takes the miss.
        let mut slower = bodies;
        slower[1] = still(1, (119.0, 100.0));
        let accuracy = audit(&spec, &roles, &slower, &[0, 1, 1, 1, 0, 1, 1, 1, 1, 1]);
        assert_eq!(accuracy.classes[SHOT_ENEMY], tally(1, 0, 0, 0));
        assert_eq!(accuracy.classes[BODY_WALL], tally(1, 1, 0, 0));
    }

    #[test]
    fn limits_are_checked_on_audited_bodies() {
        let mut limited = kind("limited", circle(1.0), &[]);
        limited.max_speed = 10.0;
        let spec = world(100.0, Boundary::Clamp, vec![limited]);
        let roles = Roles::of(&spec, None, None);
        let body = |x: f32, vel: (f32, f32), energy: i32| Body {
            vel: vel.into(),
            energy,
            ..still(0, (x, 50.0))
        };
        let bodies = [
            body(10.0, (0.0, 10.0), 100),
            // Within the margin.
            body(20.0, (10.00005, 0.0), 1),
            body(30.0, (6.0, 8.1), 100),
            body(40.0, (0.0, 0.0), 101),
            body(50.0, (-20.0, 0.0), 102),
            // Not audited: dead at the step's end.
            body(60.0, (-20.0, 0.0), 102),
        ];
        let (mut this, next) = ends(&bodies, &[0; 6]);
        this.alive[5] = 0;
        let mut accuracy = Accuracy::default();
        accuracy.add_step(&spec, &roles, &this.end(), &next.end());
        assert_eq!(accuracy.slots_audited, 5);
        assert_eq!(
            (accuracy.speed_violations, accuracy.energy_violations),
            (2, 2)
        );
    }

    #[test]
    fn paths_that_meet_a_set_near_one_end_only() {
        let sets = [
            Overlap::Disk(5.0),
            Overlap::Rounded {
                half: DVec2::new(4.0, 3.0),
                radius: 1.0,
            },
            Overlap::Rect(DVec2::new(5.0, 3.0)),
        ];
        // Each reaches 5 along x: a path from 100 away enters it in its last 0.5%, or
        // leaves it in its first.
        let far = DVec2::new(-100.0, 0.0);
        for set in sets {
            for (near, meets) in [(-4.5, true), (-5.5, false)] {
                let near = DVec2::new(near, 0.0);
                assert_eq!(set.meets(far, near), meets, "{set:?} {near}");
                assert_eq!(set.meets(near, far), meets, "{set:?} {near}");
                assert_eq!(set.meets(near, near), meets, "{set:?} {near}");
            }
            assert!(!set.meets(far, far + DVec2::Y), "{set:?}");
            // Along x = 5 it touches each set, along x = 4.5 it enters.
            for (x, meets) in [(5.0, false), (4.5, true), (-5.0, false), (-4.5, true)] {
                let (from, to) = (DVec2::new(x, -10.0), DVec2::new(x, 10.0));
                assert_eq!(set.meets(from, to), meets, "{set:?} {x}");
            }
        }
    }

    /// Whether `d` lies in the set: the distance from the grown shape, worked out apart from
    /// the code under test.
    fn inside(overlap: Overlap, d: DVec2) -> bool {
        match overlap {
            Overlap::Disk(reach) => d.x.hypot(d.y) < reach,
            Overlap::Rounded { half, radius } => {
                (d.abs() - half).max(DVec2::ZERO).length() < radius
            }
            Overlap::Rect(half) => d.x.abs() < half.x && d.y.abs() < half.y,
        }
    }

    const SAMPLES: u32 = 20_000;

    /// Whether any of the path's samples (ends included) lies in the set.
    fn sampled_meets(overlap: Overlap, from: DVec2, to: DVec2) -> bool {
        (0..=SAMPLES).any(|i| inside(overlap, from.lerp(to, f64::from(i) / f64::from(SAMPLES))))
    }

    fn overlaps() -> impl Strategy<Value = Overlap> {
        prop_oneof![
            (1.0..20.0).prop_map(Overlap::Disk),
            (0.5..10.0, 0.5..10.0, 0.5..10.0).prop_map(|(x, y, radius)| Overlap::Rounded {
                half: DVec2::new(x, y),
                radius
            }),
            (1.0..20.0, 1.0..20.0).prop_map(|(x, y)| Overlap::Rect(DVec2::new(x, y))),
        ]
    }

    /// A set and two points around it, within 1.6 times its extent along each axis.
    fn cases() -> impl Strategy<Value = (Overlap, DVec2, DVec2)> {
        overlaps().prop_flat_map(|overlap| {
            let point = move || {
                (-1.6..1.6, -1.6..1.6).prop_map(move |(x, y)| DVec2::new(x, y) * overlap.extent())
            };
            (Just(overlap), point(), point())
        })
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(1000))]

        /// The closed forms agree with dense sampling wherever every test is decided by a
        /// margin of 2%: a set shrunk by 2% lies at least 0.01 inside the whole one, more
        /// than the samples' spacing (at most 91 / 20,000), so a path that meets it has a
        /// sample inside the whole one.
        #[test]
        fn closed_forms_agree_with_sampling((overlap, d0, d1) in cases()) {
            let decided = |test: &dyn Fn(Overlap) -> bool| {
                test(overlap.scaled(0.98)) == test(overlap.scaled(1.02))
            };
            prop_assume!(decided(&|o| o.meets(d0, d1)));
            prop_assume!(decided(&|o| o.contains(d0)) && decided(&|o| o.contains(d1)));

            prop_assert_eq!(overlap.meets(d0, d1), sampled_meets(overlap, d0, d1));
            let sampled = if inside(overlap, d1) {
                Some(Link::End)
            } else if !inside(overlap, d0) && sampled_meets(overlap, d0, d1) {
                Some(Link::Tunnelling)
            } else {
                None
            };
            prop_assert_eq!(judge(overlap, d0, d1, d1).map(|(link, _)| link), sampled);
        }
    }
}
