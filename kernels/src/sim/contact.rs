//! Narrow-phase geometry (paper 6.2): does a pair of bounds overlap, along which normal and
//! by how much. Pure functions of the two bounds and their offset, shared by the kernels and
//! by the host's checks.
//!
//! Every test is antisymmetric: swapping the two bodies (and negating the offset and the
//! tie-break direction) gives the same depth and the opposite normal, bit for bit. So the two
//! threads of a pair, each computing its own response, agree exactly.

use glam::Vec2;

use super::kinds::{Bound, PlainBound};
use crate::access::Read;
use crate::math::{length, sqrt};
use crate::{DevSlice, Thread, kernel_args};

/// An overlap between bodies `a` and `b`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Contact {
    /// Unit normal pointing from `a` towards `b`: the direction `b` must move to separate.
    pub normal: Vec2,
    /// Penetration depth along the normal (> 0).
    pub depth: f32,
}

/// The deterministic normal used when geometry leaves the direction undefined (two bodies on
/// the same spot): `+x` from the lower slot to the higher one, `-x` the other way.
#[inline(always)]
pub fn tie_break(a: u32, b: u32) -> Vec2 {
    if a < b { Vec2::X } else { Vec2::NEG_X }
}

/// The overlap of `a` and `b`, where `d` is the offset from `a`'s position to `b`'s and `tie`
/// the normal to use when the direction is undefined (see [`tie_break`]). Touching is not
/// overlapping; any NaN input gives `None`.
#[inline(always)]
pub fn contact(a: Bound, b: Bound, d: Vec2, tie: Vec2) -> Option<Contact> {
    match (a, b) {
        (Bound::Circle(ra), Bound::Circle(rb)) => circle_circle(ra + rb, d, tie),
        (Bound::Circle(r), Bound::Rect(half)) => circle_rect(r, half, d, tie),
        (Bound::Rect(half), Bound::Circle(r)) => circle_rect(r, half, -d, -tie).map(flip),
        (Bound::Rect(ha), Bound::Rect(hb)) => rect_rect(ha + hb, d, tie),
    }
}

#[inline(always)]
fn flip(c: Contact) -> Contact {
    Contact {
        normal: -c.normal,
        depth: c.depth,
    }
}

/// Circles whose radii sum to `reach`.
#[inline(always)]
fn circle_circle(reach: f32, d: Vec2, tie: Vec2) -> Option<Contact> {
    let dist2 = d.length_squared();
    // Written so that NaN fails the test.
    (dist2 < reach * reach).then(|| {
        let dist = sqrt(dist2);
        let normal = if dist > 0.0 { d / dist } else { tie };
        Contact {
            normal,
            depth: reach - dist,
        }
    })
}

/// A circle of radius `r` at the origin and a rectangle of half extents `half` at `d`.
#[inline(always)]
fn circle_rect(r: f32, half: Vec2, d: Vec2, tie: Vec2) -> Option<Contact> {
    // The circle's centre in the rectangle's frame, and the rectangle's closest point to it.
    let p = -d;
    let closest = p.clamp(-half, half);
    if closest == p {
        // The centre is inside: leave through the nearest side, the circle going outwards.
        let gap = half - p.abs();
        return Some(if gap.x <= gap.y {
            Contact {
                normal: Vec2::new(outward(-p.x, tie.x), 0.0),
                depth: gap.x + r,
            }
        } else {
            Contact {
                normal: Vec2::new(0.0, outward(-p.y, tie.x)),
                depth: gap.y + r,
            }
        });
    }
    let towards = closest - p;
    let dist2 = towards.length_squared();
    (dist2 < r * r).then(|| {
        let dist = sqrt(dist2);
        Contact {
            normal: towards / dist,
            depth: r - dist,
        }
    })
}

/// Rectangles whose half extents sum to `reach`, overlapping along the axis of least depth.
#[inline(always)]
fn rect_rect(reach: Vec2, d: Vec2, tie: Vec2) -> Option<Contact> {
    let overlap = reach - d.abs();
    if !(overlap.x > 0.0 && overlap.y > 0.0) {
        return None;
    }
    Some(if overlap.x <= overlap.y {
        Contact {
            normal: Vec2::new(outward(d.x, tie.x), 0.0),
            depth: overlap.x,
        }
    } else {
        Contact {
            normal: Vec2::new(0.0, outward(d.y, tie.x)),
            depth: overlap.y,
        }
    })
}

/// The sign of `x` as ±1, or `tie` (±1) when `x` is zero.
#[inline(always)]
fn outward(x: f32, tie: f32) -> f32 {
    if x > 0.0 {
        1.0
    } else if x < 0.0 {
        -1.0
    } else {
        tie
    }
}

/// A contact that begins during a step's motion: the pair was apart or touching when the
/// motion began (a test at the motion's end alone misses it if the pair is apart again
/// there, and resolves it the wrong way if the bodies passed each other's middles).
///
/// What counts, so that the test at the motion's end ([`contact`]) and this one together
/// see every path once: the bounds are open sets (touching is not overlapping). A motion
/// that starts overlapping was counted at the end of the motion before; one that starts
/// apart or touching and enters the overlap at any moment `t` in `[0, 1)` is swept, at the
/// first such moment (0 for a touching start that closes in); one that only reaches
/// touching at its end, or grazes (touches without entering), is no contact; the next
/// motion starts touching and counts it if it closes in.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Swept {
    /// When the bounds first overlap, as a fraction of the motion, in `[0, 1)` (never
    /// `-0.0`).
    pub time: f32,
    /// Unit normal at that moment, pointing from `a` towards `b`.
    pub normal: Vec2,
}

/// The first moment at which `a` and `b` overlap while the offset from `a` to `b` moves
/// linearly from `d0` (where the motion began) to `d1` (where it ended), for a pair apart
/// or touching at `d0` (the caller tests it with [`contact`]): a touching start that
/// closes in enters at 0, one that grazes or moves away does not enter (see [`Swept`]).
/// Any NaN gives `None`.
///
/// Like [`contact`] it is antisymmetric: swapping the bodies (negating both offsets) gives
/// the same time, bit for bit, and the opposite normal, so both threads of a pair agree.
#[inline(always)]
pub fn first_overlap(a: Bound, b: Bound, d0: Vec2, d1: Vec2) -> Option<Swept> {
    match (a, b) {
        (Bound::Circle(ra), Bound::Circle(rb)) => disk_entry(d0, d1 - d0, ra + rb),
        (Bound::Circle(r), Bound::Rect(half)) => circle_rect_sweep(r, half, d0, d1),
        (Bound::Rect(half), Bound::Circle(r)) => {
            circle_rect_sweep(r, half, -d0, -d1).map(|s| Swept {
                time: s.time,
                normal: -s.normal,
            })
        }
        (Bound::Rect(ha), Bound::Rect(hb)) => rect_rect_sweep(ha + hb, d0, d1),
    }
}

/// Rectangles whose half extents sum to `reach`: the offset entering the box of that reach.
/// Not inlined, like [`circle_rect_sweep`]: the narrow phase's query stays small enough to
/// be inlined whole, where the rare rectangle sweeps would otherwise spill its arguments.
#[inline(never)]
fn rect_rect_sweep(reach: Vec2, d0: Vec2, d1: Vec2) -> Option<Swept> {
    box_entry(d0, d1 - d0, reach)
}

/// A circle of radius `r` at the origin and a rectangle of half extents `half` whose centre
/// moves from `d0` to `d1`. They overlap while the centre lies in the rectangle grown by
/// `r` with rounded corners: the union of two boxes (the rectangle grown along one axis)
/// and four disks (one on each corner), whose earliest entry is the earliest of the pieces'
/// (a touching start lies on the boundary of one piece at least, and enters at 0 where it
/// closes in on that piece). Not inlined (see [`rect_rect_sweep`]).
#[inline(never)]
fn circle_rect_sweep(r: f32, half: Vec2, d0: Vec2, d1: Vec2) -> Option<Swept> {
    let v = d1 - d0;
    // The disk around the corner at `-c` holds the centres whose rectangle has that corner
    // within `r` of the circle: the path shifted by the corner. Written out, not looped
    // over a list, so that the kernel keeps everything in registers.
    let corner = |c: Vec2| disk_entry(d0 + c, v, r);
    let faces = earliest(
        box_entry(d0, v, Vec2::new(half.x + r, half.y)),
        box_entry(d0, v, Vec2::new(half.x, half.y + r)),
    );
    let low = earliest(
        corner(Vec2::new(-half.x, -half.y)),
        corner(Vec2::new(half.x, -half.y)),
    );
    let high = earliest(corner(Vec2::new(-half.x, half.y)), corner(half));
    earliest(faces, earliest(low, high))
}

/// The earlier of two entries, `a` on a tie (a fixed order, whatever the schedule).
#[inline(always)]
fn earliest(a: Option<Swept>, b: Option<Swept>) -> Option<Swept> {
    match (a, b) {
        (Some(x), Some(y)) => Some(if y.time < x.time { y } else { x }),
        (x, None) => x,
        (None, y) => y,
    }
}

/// When the point `p0 + v t` first enters the open disk of radius `reach` around the
/// origin, for `t` in `[0, 1)`, with the outward normal there. A start on the circle (or
/// inside it by a rounding the caller's test of the start did not make: a corner's disk of
/// [`circle_rect_sweep`]) enters at 0 if it closes in. Every term is a product of two of the
/// inputs' components, so negating `p0` and `v` changes no bit of the time.
#[inline(always)]
fn disk_entry(p0: Vec2, v: Vec2, reach: f32) -> Option<Swept> {
    let a = v.length_squared();
    let b = p0.dot(v);
    let c = p0.length_squared() - reach * reach;
    // b² − a·c by Lagrange's identity: a·reach² − (p0 × v)². A path grazing the circle
    // gives two equal products here, not a difference of terms each rounded (c above all,
    // whose rounding made tangents to a rectangle's corner cross it).
    let cross = p0.perp_dot(v);
    let disc = a * (reach * reach) - cross * cross;
    // Moving (a > 0), closing in (b < 0), and passing closer than the reach (disc > 0, so
    // the path crosses the circle rather than grazing it). NaN fails.
    if !(a > 0.0 && b < 0.0 && disc > 0.0) {
        return None;
    }
    // The smaller root (−b − √disc) / a, written as c / (−b + √disc): the same number, but
    // a quotient of a sum of two positive terms, where the difference cancels for a start
    // near the circle (a gap of 1e-7 at a reach of 2 came out as no entry). A start on the
    // circle (c = 0) or inside it by rounding (c < 0) enters at once.
    let time = if c > 0.0 { c / (-b + sqrt(disc)) } else { 0.0 };
    if time >= 1.0 {
        return None;
    }
    let at = p0 + v * time;
    let dist = length(at);
    (dist > 0.0).then(|| Swept {
        time,
        normal: at / dist,
    })
}

/// When the point `p0 + v t` first enters the open box `|x| < half` (per axis), for `t` in
/// `[0, 1)`, with the normal of the face it crosses, pointing from the box's centre to the
/// point. The slab times of each axis swap, not change, when `p0` and `v` are negated. A
/// start on a face enters at 0 if it moves in; one inside the box by a rounding the
/// caller's test did not make (a face's box of [`circle_rect_sweep`]) enters at 0 if it
/// moves in across the face nearest it.
#[inline(always)]
fn box_entry(p0: Vec2, v: Vec2, half: Vec2) -> Option<Swept> {
    let (enter_x, leave_x) = slab(p0.x, v.x, half.x);
    let (enter_y, leave_y) = slab(p0.y, v.y, half.y);
    let (time, normal) = if enter_y > enter_x {
        (enter_y, Vec2::new(0.0, -sign(v.y)))
    } else {
        (enter_x, Vec2::new(-sign(v.x), 0.0))
    };
    // Written so that NaN fails.
    if !(time < leave_x.min(leave_y) && time < 1.0) {
        return None;
    }
    if time >= 0.0 {
        // `+ 0.0` makes a time of −0 (a start on a face, `(half − p) / v` with v < 0) +0,
        // as its mirror image computes it.
        return Some(Swept {
            time: time + 0.0,
            normal,
        });
    }
    if leave_x.min(leave_y) <= 0.0 {
        return None;
    }
    // Inside at the start: it enters at once if it moves in across its nearest face.
    let gap = half - p0.abs();
    let (p, v, normal) = match gap.y < gap.x {
        true => (p0.y, v.y, Vec2::new(0.0, sign(p0.y))),
        false => (p0.x, v.x, Vec2::new(sign(p0.x), 0.0)),
    };
    (p * v < 0.0).then_some(Swept { time: 0.0, normal })
}
/// The times at which `p + v t` enters and leaves `|x| < half`: all time for a point that
/// does not move and lies inside, none for one that lies outside.
#[inline(always)]
fn slab(p: f32, v: f32, half: f32) -> (f32, f32) {
    if v == 0.0 {
        return match p.abs() < half {
            true => (f32::NEG_INFINITY, f32::INFINITY),
            false => (f32::INFINITY, f32::NEG_INFINITY),
        };
    }
    let (t1, t2) = ((-half - p) / v, (half - p) / v);
    (t1.min(t2), t1.max(t2))
}

/// The sign of `x` as ±1 (`x` non-zero).
#[inline(always)]
fn sign(x: f32) -> f32 {
    if x > 0.0 { 1.0 } else { -1.0 }
}

/// The moment the narrow phase counts the contact of one motion of a pair, as a fraction of
/// the motion (see [`Swept`]): 0 for a pair overlapping where the motion began (the motion
/// before counted it), the swept moment for one apart or touching there, 1 for a contact
/// reached at the end alone; `None` for no contact.
#[inline(always)]
pub fn counted(a: Bound, b: Bound, d0: Vec2, d1: Vec2) -> Option<f32> {
    if contact(a, b, d0, Vec2::X).is_some() {
        return Some(0.0);
    }
    if let Some(s) = first_overlap(a, b, d0, d1) {
        return Some(s.time);
    }
    contact(a, b, d1, Vec2::X).map(|_| 1.0)
}

/// One motion of a pair for [`sweep_cases`]: the offset from `a` to `b` goes from `d0` to
/// `d1`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct SweepCase {
    /// The first body's bound.
    pub a: PlainBound,
    /// The second body's bound.
    pub b: PlainBound,
    /// The offset where the motion began.
    pub d0: Vec2,
    /// The offset where it ended.
    pub d1: Vec2,
}

/// What the narrow phase's geometry makes of a [`SweepCase`]; a time of −1 stands for none.
/// (The vectors first: on the GPU they are aligned to 8 bytes.)
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct SweepVerdict {
    /// The normal of [`first_overlap`] of `a` and `b` from `d0` to `d1`.
    pub ab_normal: Vec2,
    /// The normal of [`first_overlap`] of `b` and `a` from `−d0` to `−d1`: the other body's view.
    pub ba_normal: Vec2,
    /// The time of the first sweep.
    pub ab_time: f32,
    /// The time of the other body's.
    pub ba_time: f32,
    /// 1 where the pair overlaps at `d0` ([`contact`]), else 0.
    pub started_overlapping: u32,
    /// [`counted`]'s moment.
    pub counted: f32,
}

impl SweepVerdict {
    /// The verdict on `case`.
    #[inline(always)]
    pub fn of(case: &SweepCase) -> SweepVerdict {
        let (a, b) = (case.a.bound(), case.b.bound());
        let (d0, d1) = (case.d0, case.d1);
        let swept = |s: Option<Swept>| s.map_or((-1.0, Vec2::ZERO), |s| (s.time, s.normal));
        let (ab_time, ab_normal) = swept(first_overlap(a, b, d0, d1));
        let (ba_time, ba_normal) = swept(first_overlap(b, a, -d0, -d1));
        SweepVerdict {
            started_overlapping: u32::from(contact(a, b, d0, Vec2::X).is_some()),
            counted: counted(a, b, d0, d1).unwrap_or(-1.0),
            ab_time,
            ab_normal,
            ba_time,
            ba_normal,
        }
    }
}

kernel_args! {
    /// Arguments of [`sweep_cases`].
    pub struct SweepCasesArgs {
        /// The motions judged.
        pub cases: DevSlice<SweepCase, Read>,
        /// Output: one verdict a case.
        pub verdicts: DevSlice<SweepVerdict>,
    }
}

/// Thread `i` writes the [`SweepVerdict`] of case `i`: the contact geometry on the device, for
/// the checks that compare it with a higher-precision reference and with the CPU's, bit for
/// bit.
#[inline(always)]
pub fn sweep_cases(t: Thread, args: &SweepCasesArgs) {
    let i = t.global();
    if i < args.cases.len() {
        args.verdicts.set(i, SweepVerdict::of(&args.cases.get(i)));
    }
}
