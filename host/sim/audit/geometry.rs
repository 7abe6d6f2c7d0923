//! The geometry of the audit: which pairs of bodies met during a step, their offset followed
//! in a straight line (across a wrapping world's seams) against the set of offsets at which
//! their shapes overlap, in closed form and in f64.

use glam::DVec2;
use rayon::prelude::*;

use super::{MARGIN, StepEnd};
use crate::sim::spec::{Boundary, Shape, WorldSpec};

/// How a pair of bodies relates to a step's motion, in the order a slot's partners are
/// attributed missed contacts (then extra ones).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub(super) enum Link {
    /// A certain contact whose paths met between the step's ends only.
    Tunnelling,
    /// A certain contact that overlaps at the step's end.
    End,
    /// Contact or not depending on sizes within the margin.
    Uncertain,
}

/// A pair of live bodies that made contact during the step or may have.
pub(super) struct Found {
    pub(super) a: usize,
    pub(super) b: usize,
    pub(super) link: Link,
    /// The penetration at the step's end of a certain contact that overlaps there.
    pub(super) depth: Option<f64>,
    /// When a certain contact began, as the kernels report a swept pair's: the first moment
    /// of the motion (a fraction in `[0, 1)`) at which the pair overlaps, or 1 where it
    /// overlapped from the start (a contact at the end); `None` where sizes within the
    /// margin move it by more than [`TIME_TOLERANCE`].
    pub(super) moment: Option<f64>,
}

/// How many widths of the margin's band (the sizes within the margin) a path that starts in
/// the band may run inside it before it grazes the set rather than leaves it: a path leaving
/// straight out crosses the band within one width.
const GRAZE: f64 = 4.0;

/// How far (a fraction of the motion) a swept contact's moment may be from the audit's
/// before it is late.
pub const TIME_TOLERANCE: f64 = 1e-4;

/// Every pair of live bodies of `this` whose kinds collide and whose verdict is a contact or
/// uncertain, in a fixed order (so the depths' sum is reproducible).
pub(super) fn scan(spec: &WorldSpec, this: &StepEnd) -> Vec<Found> {
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
                    let moment = match link {
                        Link::Uncertain => None,
                        _ => moment(overlap, d0, end),
                    };
                    Some(Found {
                        a,
                        b,
                        link,
                        depth,
                        moment,
                    })
                })
            }));
        }
    }
    found
}

/// The verdict on a pair whose offset went from `d0` to `end` in a straight line (`d1`: the
/// same end as the world measures it, its image nearest zero), and its depth at the end for a
/// certain contact that overlaps there; `None` for a certain non-contact.
///
/// A verdict is certain when both ends of the margin's sizes give it, with one exception: a
/// start within the margin of touching whose path then runs along the boundary (the state a
/// swept contact's rewind leaves, and a body sliding along a wall). The grown set holds its
/// start (a contact counted at the motion before) and the shrunk one is never met, but at
/// the size in between the path grazes the set, and whether it enters is decided by the
/// roundings of f32: undecidable.
fn judge(overlap: Overlap, d0: DVec2, end: DVec2, d1: DVec2) -> Option<(Link, Option<f64>)> {
    let contact = |o: Overlap| o.contains(d1) || (!o.contains(d0) && o.meets(d0, end));
    let verdict = contact(overlap);
    let [shrunk, grown] = [1.0 - MARGIN, 1.0 + MARGIN].map(|scale| overlap.scaled(scale));
    let grazes = || !shrunk.contains(d0) && grown.runs_along(overlap, d0, end);
    if contact(shrunk) != verdict || contact(grown) != verdict || (!verdict && grazes()) {
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

/// When the contact of a pair whose offset went from `d0` to `end` began (see
/// [`Found::moment`]), if sizes within the margin agree on it.
fn moment(overlap: Overlap, d0: DVec2, end: DVec2) -> Option<f64> {
    let at = |o: Overlap| match o.contains(d0) {
        true => 1.0,
        false => o.entry(d0, end).unwrap_or(1.0),
    };
    let [shrunk, grown] = [1.0 - MARGIN, 1.0 + MARGIN].map(|scale| at(overlap.scaled(scale)));
    ((shrunk - grown).abs() <= TIME_TOLERANCE).then(|| at(overlap))
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

    /// Whether the path from `from` (inside this set, the grown one) to `to` stays in it
    /// for more than [`GRAZE`] of the margin's band around `exact`'s boundary: it runs along
    /// that boundary rather than leaving it. The set is convex, so the path is inside it over
    /// one interval from its start, whose end is bisected.
    fn runs_along(self, exact: Overlap, from: DVec2, to: DVec2) -> bool {
        if !self.contains(from) {
            return false;
        }
        let band = 2.0 * MARGIN * exact.extent().max_element();
        let length = (to - from).length();
        if self.contains(to) {
            return length > GRAZE * band;
        }
        let (mut inside, mut outside) = (0.0, 1.0);
        for _ in 0..60 {
            let mid = 0.5 * (inside + outside);
            match self.contains(from.lerp(to, mid)) {
                true => inside = mid,
                false => outside = mid,
            }
        }
        inside * length > GRAZE * band
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
        self.entry(from, to).is_some()
    }

    /// The first moment `t` in `[0, 1]` at which `from + (to - from) t` is in the set (the
    /// infimum: the set is open), or `None` where the closed segment does not meet it.
    fn entry(self, from: DVec2, to: DVec2) -> Option<f64> {
        match self {
            Overlap::Disk(reach) => disk_entry(DVec2::ZERO, reach, from, to),
            // A union of open sets: a cross of two rectangles and a disk at each corner.
            Overlap::Rounded { half, radius } => [
                rect_entry(half + DVec2::new(radius, 0.0), from, to),
                rect_entry(half + DVec2::new(0.0, radius), from, to),
            ]
            .into_iter()
            .chain(
                [(1.0, 1.0), (1.0, -1.0), (-1.0, 1.0), (-1.0, -1.0)]
                    .map(|(x, y)| disk_entry(half * DVec2::new(x, y), radius, from, to)),
            )
            .flatten()
            .reduce(f64::min),
            Overlap::Rect(half) => rect_entry(half, from, to),
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

/// The first moment in `[0, 1]` at which `from + (to - from) t` is in the open disk of
/// `radius` around `centre`: where the path crosses the circle (the root of a quadratic,
/// written without cancellation), or 0 for a start inside.
fn disk_entry(centre: DVec2, radius: f64, from: DVec2, to: DVec2) -> Option<f64> {
    let (p, along) = (from - centre, to - from);
    let c = p.length_squared() - radius * radius;
    if c < 0.0 {
        return Some(0.0);
    }
    let (a, b) = (along.length_squared(), p.dot(along));
    let disc = b * b - a * c;
    if !(b < 0.0 && disc > 0.0) {
        return None;
    }
    let t = c / (-b + disc.sqrt());
    (t < 1.0).then_some(t)
}

/// The first moment in `[0, 1]` at which `from + (to - from) t` is in the open rectangle of
/// half extents `half` around zero: where the open parameter intervals in which each axis
/// is inside overlap each other and `[0, 1]`.
fn rect_entry(half: DVec2, from: DVec2, to: DVec2) -> Option<f64> {
    let (x0, x1) = slab(from.x, to.x, half.x);
    let (y0, y1) = slab(from.y, to.y, half.y);
    let (lo, hi) = (x0.max(y0), x1.min(y1));
    (lo < hi && lo < 1.0 && hi > 0.0).then_some(lo.max(0.0))
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

    /// A set of each shape whose boundary passes through (5, 0), with the normal along x.
    fn reaching_five() -> [Overlap; 3] {
        [
            Overlap::Disk(5.0),
            Overlap::Rounded {
                half: DVec2::new(4.0, 3.0),
                radius: 1.0,
            },
            Overlap::Rect(DVec2::new(5.0, 3.0)),
        ]
    }

    #[test]
    fn paths_that_meet_a_set_near_one_end_only() {
        let sets = reaching_five();
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

    #[test]
    fn a_path_along_the_boundary_from_touching_is_undecidable() {
        let sets = reaching_five();
        for set in sets {
            // Each set's boundary passes through (5, 0) with the normal along x.
            let touching = DVec2::new(5.0, 0.0);
            let verdict = |from: DVec2, to: DVec2| judge(set, from, to, to).map(|(l, _)| l);
            // Sliding from touching along the boundary's tangent: f32 decides it.
            let along = touching + DVec2::new(0.0, 2.0);
            assert_eq!(verdict(touching, along), Some(Link::Uncertain), "{set:?}");
            // Leaving straight out from touching, or sliding parallel well outside: none.
            assert_eq!(verdict(touching, DVec2::new(7.0, 0.0)), None, "{set:?}");
            let outside = DVec2::new(5.0 + 100.0 * MARGIN * 5.0, 0.0);
            assert_eq!(verdict(outside, outside + DVec2::Y * 2.0), None, "{set:?}");
            // Going straight in from touching and staying in: certain.
            let inside = DVec2::new(4.0, 0.0);
            assert_eq!(verdict(touching, inside).map(|_| ()), Some(()), "{set:?}");
            assert_ne!(verdict(touching, inside), Some(Link::Uncertain), "{set:?}");
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
