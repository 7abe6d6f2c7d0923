//! The swept test at its edges: starts exactly touching, one ulp either side, within 1e-5 of
//! touching, grazing, on rectangles' corners, with zero relative speed, at tiny and huge
//! sizes. Each case is checked against an f64 reference written apart from the kernels: the
//! signed distance from the set of overlapping offsets, minimised along the path (it is
//! convex) and bisected before its minimum.
//!
//! What the kernels count for one motion from `d0` to `d1` (see `contact::Swept`): a pair
//! overlapping at `d0` was counted at the end of the motion before (time 0 of this one);
//! one apart or touching there is swept; a contact found at `d1` alone comes at time 1. The
//! reference's moment is the first at which the path is inside the open set. A case is
//! judged where f32 can decide it: its verdict, and its moment within [`TIME_TOLERANCE`],
//! stay the same when the set grows or shrinks by a few units in the last place of the
//! case's coordinates ([`band`]). The others are counted and printed, never dropped
//! silently; the exact-touching families must have none.
//!
//! Each family runs on both backends through the `sweep_cases` kernel; on the GPU every
//! verdict is also the CPU's, bit for bit.

mod common;

use glam::{DVec2, Vec2};
use gpuwars::backend::{Binder, Launch, Op};
use gpuwars::kernels::registry;
use gpuwars::kernels::sim::contact::{
    SweepCase, SweepCasesArgs, SweepVerdict, contact, first_overlap,
};
use gpuwars::kernels::sim::kinds::Bound;
use gpuwars::{BackendKind, Device};
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};

/// How far (a fraction of the motion) a found moment may be from the reference's.
const TIME_TOLERANCE: f64 = 1e-4;

/// The set of offsets (from `a` to `b`) at which two bounds overlap, in f64.
#[derive(Clone, Copy, Debug)]
enum Set {
    Disk(f64),
    Rounded { half: DVec2, radius: f64 },
    Box(DVec2),
}

impl Set {
    fn of(a: Bound, b: Bound) -> Set {
        match (a, b) {
            (Bound::Circle(ra), Bound::Circle(rb)) => Set::Disk(f64::from(ra) + f64::from(rb)),
            (Bound::Circle(radius), Bound::Rect(half))
            | (Bound::Rect(half), Bound::Circle(radius)) => Set::Rounded {
                half: half.as_dvec2(),
                radius: f64::from(radius),
            },
            (Bound::Rect(ha), Bound::Rect(hb)) => Set::Box(ha.as_dvec2() + hb.as_dvec2()),
        }
    }

    /// Signed distance of `p` from the set's boundary: negative inside.
    fn distance(self, p: DVec2) -> f64 {
        let from_box = |half: DVec2| {
            let q = p.abs() - half;
            q.max(DVec2::ZERO).length() + q.max_element().min(0.0)
        };
        match self {
            Set::Disk(reach) => p.length() - reach,
            Set::Rounded { half, radius } => from_box(half) - radius,
            Set::Box(half) => from_box(half),
        }
    }

    /// Half extents of its bounding box.
    fn extent(self) -> f64 {
        match self {
            Set::Disk(reach) => reach,
            Set::Rounded { half, radius } => half.max_element() + radius,
            Set::Box(half) => half.max_element(),
        }
    }
}

/// The first moment in `[0, 1]` at which the path from `d0` to `d1` is inside the set grown by
/// `grow` (its distance below `grow`), or `None`: 0 for a start inside; for one outside or
/// on the boundary, the first moment it is inside where it gets deeper than `REFERENCE`
/// times the case's size (f64's own rounding makes an exact graze come out a hair inside
/// or out).
fn entry(set: Set, d0: DVec2, d1: DVec2, grow: f64) -> Option<f64> {
    let f = |t: f64| set.distance(d0 + (d1 - d0) * t) - grow;
    if f(0.0) < 0.0 {
        return Some(0.0);
    }
    let deeper = REFERENCE * scale(set, d0, d1);
    // The distance is convex along a line: a ternary search finds its minimum.
    let (mut lo, mut hi) = (0.0f64, 1.0f64);
    for _ in 0..200 {
        let (m1, m2) = (lo + (hi - lo) / 3.0, hi - (hi - lo) / 3.0);
        if f(m1) <= f(m2) {
            hi = m2;
        } else {
            lo = m1;
        }
    }
    let lowest = [0.5 * (lo + hi), 1.0]
        .into_iter()
        .min_by(|x, y| f(*x).total_cmp(&f(*y)))
        .unwrap();
    if f(lowest) >= -deeper {
        return None;
    }
    let (mut out, mut inside) = (0.0, lowest);
    for _ in 0..200 {
        let mid = 0.5 * (out + inside);
        if f(mid) < 0.0 {
            inside = mid;
        } else {
            out = mid;
        }
    }
    Some(inside)
}

/// The precision of the reference, relative to a case's size: far below f32's, far above
/// f64's.
const REFERENCE: f64 = 1e-12;

/// The case's largest coordinate or size.
fn scale(set: Set, d0: DVec2, d1: DVec2) -> f64 {
    [d0.abs().max_element(), d1.abs().max_element(), set.extent()]
        .into_iter()
        .fold(0.0, f64::max)
}

/// A few units in the last place of the case's largest coordinate or size: what f32
/// arithmetic on it may be off by.
fn band(set: Set, d0: DVec2, d1: DVec2) -> f64 {
    8.0 * f64::from(f32::EPSILON) * scale(set, d0, d1)
}

/// One motion to judge: the bounds, the f32 offsets the kernels see, the exact ones the
/// reference takes (the f32 ones where those are exact), and how far f32 may be off (0 where
/// every input and the kernels' arithmetic on it are exact).
#[derive(Clone, Copy, Debug)]
struct Case {
    bounds: (Bound, Bound),
    offsets: (Vec2, Vec2),
    exact: (DVec2, DVec2),
    band: f64,
}

impl Case {
    /// The f32 offsets as they are, judged everywhere (`exact`: no rounding band) or where
    /// f32 decides.
    fn of_offsets(bounds: (Bound, Bound), d0: Vec2, d1: Vec2, exact: bool) -> Case {
        let (e0, e1) = (d0.as_dvec2(), d1.as_dvec2());
        let band = match exact {
            true => 0.0,
            false => band(Set::of(bounds.0, bounds.1), e0, e1),
        };
        Case {
            bounds,
            offsets: (d0, d1),
            exact: (e0, e1),
            band,
        }
    }

    fn plain(&self) -> SweepCase {
        SweepCase {
            a: self.bounds.0.into(),
            b: self.bounds.1.into(),
            d0: self.offsets.0,
            d1: self.offsets.1,
        }
    }
}

/// The kernels' verdicts on `cases`, from the `sweep_cases` kernel on `device`. On the GPU
/// they must be those of the same functions compiled for this machine, bit for bit.
fn judged(device: &Device, cases: &[Case]) -> Vec<SweepVerdict> {
    let plain: Vec<SweepCase> = cases.iter().map(Case::plain).collect();
    let input = device.upload(&plain).unwrap();
    let output = device.alloc_zeroed::<SweepVerdict>(plain.len()).unwrap();
    // SAFETY: the views go into this op only.
    let mut b = unsafe { Binder::new() };
    let args = SweepCasesArgs {
        cases: b.view(&input),
        verdicts: b.view(&output),
    };
    let launch = Launch {
        kernel: registry::SWEEP_CASES,
        grid: (plain.len() as u32).div_ceil(128),
        block: 128,
        args,
    };
    // SAFETY: a thread a case; each verdict has one writer.
    device.launch(unsafe { Op::launch(launch, b, 0) }).unwrap();
    let verdicts = device.download(&output).unwrap();
    if device.kind() == BackendKind::Cuda {
        for (case, verdict) in plain.iter().zip(&verdicts) {
            let here = SweepVerdict::of(case);
            assert_eq!(
                bytemuck::bytes_of(&here),
                bytemuck::bytes_of(verdict),
                "{case:?}: the GPU's {verdict:?}, the CPU's {here:?}"
            );
        }
    }
    verdicts
}

/// A sweep's time and normal from a verdict's (a time of −1: none).
fn swept(time: f32, normal: Vec2) -> Option<(f32, Vec2)> {
    (time != -1.0).then_some((time, normal))
}

/// One family's tally.
#[derive(Debug, Default)]
struct Tally {
    cases: u64,
    contacts: u64,
    undecidable: u64,
    failures: Vec<String>,
}

impl Tally {
    /// Judges every case of a family on `device` and tallies them.
    fn of_family(device: &Device, cases: &[Case]) -> Tally {
        let mut tally = Tally::default();
        for (case, verdict) in cases.iter().zip(judged(device, cases)) {
            tally.check(case, &verdict);
        }
        tally
    }

    /// Checks the kernels' verdict on one case against the reference.
    fn check(&mut self, case: &Case, verdict: &SweepVerdict) {
        let ((a, b), (d0, d1), (e0, e1)) = (case.bounds, case.offsets, case.exact);
        self.cases += 1;
        let set = Set::of(a, b);
        let truth = entry(set, e0, e1, 0.0);
        let (shrunk, grown) = (
            entry(set, e0, e1, -case.band),
            entry(set, e0, e1, case.band),
        );
        let verdict_decided =
            shrunk.is_some() == truth.is_some() && grown.is_some() == truth.is_some();
        let time_decided = match (shrunk, grown) {
            (Some(s), Some(g)) => (s - g).abs() <= 0.5 * TIME_TOLERANCE,
            _ => false,
        };
        let kernels = (verdict.counted != -1.0).then_some(verdict.counted);
        let case = || format!("{a:?} {b:?} from {d0:?} to {d1:?}");
        self.contacts += u64::from(truth.is_some());
        if !verdict_decided {
            self.undecidable += 1;
        } else if kernels.is_some() != truth.is_some() {
            self.failures
                .push(format!("{}: found {kernels:?}, truly {truth:?}", case()));
        } else if let (Some(k), Some(t), true) = (kernels, truth, time_decided)
            && (f64::from(k) - t).abs() > TIME_TOLERANCE
        {
            self.failures
                .push(format!("{}: at {k}, truly at {t}", case()));
        } else if !time_decided && truth.is_some() {
            self.undecidable += 1;
        }
        // Both bodies find the same moment, bit for bit, with opposite normals.
        let ab = swept(verdict.ab_time, verdict.ab_normal);
        let ba = swept(verdict.ba_time, verdict.ba_normal);
        if ab.map(|(t, n)| (t.to_bits(), -n)) != ba.map(|(t, n)| (t.to_bits(), n)) {
            self.failures
                .push(format!("{}: not antisymmetric: {ab:?} {ba:?}", case()));
        }
        if let Some((time, normal)) = ab.filter(|_| verdict.started_overlapping == 0) {
            // Going back to that moment never places the pair inside each other (beyond
            // the rounding of the offset there), and the normal is a unit vector.
            let at = e0 + (e1 - e0) * f64::from(time);
            if set.distance(at) < -self::band(set, e0, e1) {
                self.failures.push(format!(
                    "{}: at {time} the pair is {} inside",
                    case(),
                    -set.distance(at)
                ));
            }
            if (normal.length() - 1.0).abs() > 1e-5 || !(0.0..1.0).contains(&time) {
                self.failures
                    .push(format!("{}: at {time} along {normal}", case()));
            }
        }
    }

    fn report(&self, family: &str) {
        eprintln!(
            "{family}: {} cases, {} contacts, {} undecidable in f32",
            self.cases, self.contacts, self.undecidable
        );
        assert!(
            self.failures.is_empty(),
            "{family}: {} of {} cases wrong, first: {:#?}",
            self.failures.len(),
            self.cases,
            &self.failures[..self.failures.len().min(8)]
        );
    }
}

/// A start exactly on the boundary of the set of `bounds` (every coordinate, and the
/// kernels' arithmetic on it, exact in f32), with an outward direction there (exact, not
/// unit): on a face of each rectangle pair and circle–rectangle pair, on a rounded corner,
/// where a face meets its corner, on a circle along an axis and along (3, 4).
fn touching_starts() -> Vec<((Bound, Bound), Vec2, Vec2)> {
    let mut starts = Vec::new();
    for scale in [1.0 / 64.0, 1.0, 8.0, 4096.0] {
        let r = 1.25 * scale; // 5/4: a (3, 4, 5) triangle of quarters
        let half = Vec2::new(2.0, 1.5) * scale;
        let circle = (Bound::Circle(r), Bound::Circle(r));
        let circle_rect = (Bound::Circle(r), Bound::Rect(half));
        let rect_circle = (Bound::Rect(half), Bound::Circle(r));
        let rects = (Bound::Rect(half), Bound::Rect(Vec2::new(0.5, 0.25) * scale));
        let diagonal = Vec2::new(0.75, 1.0);
        for sign in [
            Vec2::ONE,
            Vec2::NEG_ONE,
            Vec2::new(1.0, -1.0),
            Vec2::new(-1.0, 1.0),
        ] {
            starts.push((circle, Vec2::new(2.0 * r, 0.0) * sign, Vec2::X * sign));
            starts.push((circle, Vec2::new(0.0, 2.0 * r) * sign, Vec2::Y * sign));
            starts.push((circle, Vec2::new(1.5, 2.0) * scale * sign, diagonal * sign));
            for bounds in [circle_rect, rect_circle] {
                let face = Vec2::new(half.x + r, 0.5 * half.y);
                starts.push((bounds, face * sign, Vec2::X * sign));
                let top = Vec2::new(-0.25 * half.x, half.y + r);
                starts.push((bounds, top * sign, Vec2::Y * sign));
                // On the rounded corner, along (3, 4) from it.
                let arc = half + Vec2::new(0.75, 1.0) * scale;
                starts.push((bounds, arc * sign, diagonal * sign));
                // Where a face meets the corner's arc.
                starts.push((bounds, Vec2::new(half.x + r, half.y) * sign, Vec2::X * sign));
            }
            let reach = Vec2::new(2.5, 1.75) * scale;
            starts.push((
                rects,
                Vec2::new(reach.x, 0.5 * reach.y) * sign,
                Vec2::X * sign,
            ));
            starts.push((
                rects,
                Vec2::new(0.25 * reach.x, reach.y) * sign,
                Vec2::Y * sign,
            ));
            // The corner: both faces at once.
            starts.push((rects, reach * sign, Vec2::ONE * sign));
        }
    }
    starts
}

/// The motions from a start on the boundary with outward direction `n`, its set's size
/// `size`: straight through and beyond, slowly in, in at a slant, nearly along the tangent,
/// along the tangent (a graze), away, and not at all.
fn motions(n: Vec2, size: f32) -> [Vec2; 7] {
    let tangent = n.perp();
    [
        -n * 3.0 * size,
        -n * 0.01 * size,
        (-n + 0.5 * tangent) * 2.0 * size,
        (-n * 0.001 + tangent) * size,
        tangent * 4.0 * size,
        n * size,
        Vec2::ZERO,
    ]
}

fn size_of(bounds: (Bound, Bound)) -> f32 {
    let extent = |b: Bound| match b {
        Bound::Circle(r) => r,
        Bound::Rect(h) => h.max_element(),
    };
    extent(bounds.0) + extent(bounds.1)
}

/// The cases: two circles of radius 1 touching at (2, 0), the second moving to
/// (−2.5, 0): through the first, apart at both ends. The same for two rectangles.
#[test]
fn a_touching_pair_moving_through_each_other_is_swept_at_once() {
    let circles = (Bound::Circle(1.0), Bound::Circle(1.0));
    let (d0, d1) = (Vec2::new(2.0, 0.0), Vec2::new(-2.5, 0.0));
    assert_eq!(contact(circles.0, circles.1, d0, Vec2::X), None);
    assert_eq!(contact(circles.0, circles.1, d1, Vec2::X), None);
    let s = first_overlap(circles.0, circles.1, d0, d1).expect("swept at the start");
    assert_eq!((s.time.to_bits(), s.normal), (0, Vec2::X));
    let rects = (Bound::Rect(Vec2::ONE), Bound::Rect(Vec2::ONE));
    let s = first_overlap(rects.0, rects.1, d0, d1).expect("swept at the start");
    assert_eq!((s.time.to_bits(), s.normal), (0, Vec2::X));
    // Mirrored, the face is reached with v < 0 and the time is +0, not −0.
    let s = first_overlap(rects.0, rects.1, -d0, -d1).expect("swept at the start");
    assert_eq!((s.time.to_bits(), s.normal), (0, Vec2::NEG_X));
    // Touching and moving away, or along the face: nothing.
    assert_eq!(first_overlap(rects.0, rects.1, d0, d0 * 2.0), None);
    assert_eq!(
        first_overlap(circles.0, circles.1, d0, d0 + Vec2::Y * 0.5),
        None
    );
    assert_eq!(
        first_overlap(rects.0, rects.1, d0, d0 + Vec2::Y * 0.5),
        None
    );
}

fn touching_starts_of_every_shape_pair_are_found_at_once_when_they_close_in(device: &Device) {
    let mut cases = Vec::new();
    for (bounds, d0, n) in touching_starts() {
        for v in motions(n, size_of(bounds)) {
            cases.push(Case::of_offsets(bounds, d0, d0 + v, true));
        }
    }
    Tally::of_family(device, &cases).report("touching starts");
}

/// `x` moved by `ulps` units in the last place (negative: towards −∞).
fn ulps(x: f32, ulps: i32) -> f32 {
    (0..ulps.unsigned_abs()).fold(x, |x, _| if ulps > 0 { x.next_up() } else { x.next_down() })
}

fn starts_one_ulp_either_side_of_touching_are_found_where_f32_decides(device: &Device) {
    let mut cases = Vec::new();
    for (bounds, d0, n) in touching_starts() {
        for (dx, dy) in [(1, 0), (-1, 0), (0, 1), (0, -1), (1, 1), (-1, -1), (2, -2)] {
            let start = Vec2::new(ulps(d0.x, dx), ulps(d0.y, dy));
            for v in motions(n, size_of(bounds)) {
                cases.push(Case::of_offsets(bounds, start, start + v, false));
            }
        }
    }
    Tally::of_family(device, &cases).report("one ulp either side");
}

/// A random shape pair of sizes from `1e-3` to `1e4` (a world's sizes go up to 1e6).
fn random_bounds(rng: &mut StdRng) -> (Bound, Bound) {
    let one = |rng: &mut StdRng| {
        let size = 10f32.powf(rng.random_range(-3.0..4.0));
        match rng.random_bool(0.5) {
            true => Bound::Circle(size),
            false => Bound::Rect(Vec2::new(size, size * rng.random_range(0.1..10.0))),
        }
    };
    (one(rng), one(rng))
}

/// A point on the boundary of `set` in a random direction from its centre, with the
/// boundary's outward normal there (the set's distance's gradient, numerically).
fn boundary_point(rng: &mut StdRng, set: Set) -> (DVec2, DVec2) {
    let angle = rng.random_range(0.0..std::f64::consts::TAU);
    let dir = DVec2::new(angle.cos(), angle.sin());
    let (mut inside, mut outside) = (0.0, 2.0 * set.extent() + 1.0);
    for _ in 0..200 {
        let mid = 0.5 * (inside + outside);
        if set.distance(dir * mid) < 0.0 {
            inside = mid;
        } else {
            outside = mid;
        }
    }
    let p = dir * outside;
    let h = 1e-7 * set.extent();
    let grad = DVec2::new(
        set.distance(p + DVec2::X * h) - set.distance(p - DVec2::X * h),
        set.distance(p + DVec2::Y * h) - set.distance(p - DVec2::Y * h),
    );
    (p, grad.normalize())
}

fn fast_passes_starting_within_1e_5_of_touching_are_found_at_once(device: &Device) {
    let mut rng = StdRng::seed_from_u64(57);
    let mut cases = Vec::new();
    while cases.len() < 200_000 {
        let bounds = random_bounds(&mut rng);
        let set = Set::of(bounds.0, bounds.1);
        let (p, n) = boundary_point(&mut rng, set);
        // Gaps of exactly 0, 1e-7, 2.4e-7 (an ulp at 2), 1e-6 .. 1e-4, and any below 1e-5.
        let gap = match rng.random_range(0..8) {
            0 => 0.0,
            1 => 1e-7,
            2 => 2.4e-7,
            3 => 1e-6,
            4 => 1e-4,
            _ => rng.random_range(0.0..1e-5),
        };
        let d0 = (p + n * gap).as_vec2();
        // Through a point well inside: clearly across the set, and out the far side.
        let target = -p * rng.random_range(0.0..0.5);
        let d1 = (d0.as_dvec2() + (target - d0.as_dvec2()) * rng.random_range(2.5..4.0)).as_vec2();
        cases.push(Case::of_offsets(bounds, d0, d1, false));
    }
    let tally = Tally::of_family(device, &cases);
    tally.report("fast passes within 1e-5 of touching");
    assert!(tally.contacts > 190_000, "{tally:?}");
}

fn boundary_starts_in_every_direction_agree_with_the_reference(device: &Device) {
    let mut rng = StdRng::seed_from_u64(5757);
    let mut cases = Vec::new();
    while cases.len() < 100_000 {
        let bounds = random_bounds(&mut rng);
        let set = Set::of(bounds.0, bounds.1);
        let (p, _) = boundary_point(&mut rng, set);
        let angle = rng.random_range(0.0..std::f64::consts::TAU);
        let travel = set.extent() * 10f64.powf(rng.random_range(-2.0..1.0));
        let d0 = p.as_vec2();
        let d1 = (p + DVec2::new(angle.cos(), angle.sin()) * travel).as_vec2();
        cases.push(Case::of_offsets(bounds, d0, d1, false));
    }
    Tally::of_family(device, &cases).report("boundary starts in every direction");
}

/// Both bodies moving, the offsets made from their positions in f32 as the narrow phase
/// makes them, far from the origin (up to a world's side, 1e6) and at every speed; the
/// reference takes the positions' exact differences.
fn both_bodies_moving_anywhere_in_a_world_agree_with_the_reference(device: &Device) {
    let mut rng = StdRng::seed_from_u64(575757);
    let mut cases = Vec::new();
    while cases.len() < 100_000 {
        let bounds = random_bounds(&mut rng);
        let set = Set::of(bounds.0, bounds.1);
        let (p, _) = boundary_point(&mut rng, set);
        let gap = set.extent() * 10f64.powf(rng.random_range(-7.0..0.0));
        let offset = p * (1.0 + gap / p.length());
        let origin = DVec2::new(rng.random_range(-1e6..1e6), rng.random_range(-1e6..1e6));
        let speed = set.extent() * 10f64.powf(rng.random_range(-3.0..2.0));
        let mut velocity = || {
            let angle = rng.random_range(0.0..std::f64::consts::TAU);
            DVec2::new(angle.cos(), angle.sin()) * speed
        };
        let (va, vb) = (velocity(), velocity());
        let a0 = origin.as_vec2();
        let b0 = (origin + offset).as_vec2();
        let (a1, b1) = (
            (a0.as_dvec2() + va).as_vec2(),
            (b0.as_dvec2() + vb).as_vec2(),
        );
        let exact = |a: Vec2, b: Vec2| b.as_dvec2() - a.as_dvec2();
        let (e0, e1) = (exact(a0, b0), exact(a1, b1));
        cases.push(Case {
            bounds,
            offsets: (b0 - a0, b1 - a1),
            exact: (e0, e1),
            band: band(set, e0, e1),
        });
    }
    Tally::of_family(device, &cases).report("both bodies moving");
}

on_both_backends!(
    touching_starts_of_every_shape_pair_are_found_at_once_when_they_close_in,
    starts_one_ulp_either_side_of_touching_are_found_where_f32_decides,
    fast_passes_starting_within_1e_5_of_touching_are_found_at_once,
    boundary_starts_in_every_direction_agree_with_the_reference,
    both_bodies_moving_anywhere_in_a_world_agree_with_the_reference,
);
