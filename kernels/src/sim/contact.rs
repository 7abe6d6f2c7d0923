//! Narrow-phase geometry (paper 6.2): does a pair of bounds overlap, along which normal and
//! by how much. Pure functions of the two bounds and their offset, shared by the kernels and
//! by the host's checks.
//!
//! Every test is antisymmetric: swapping the two bodies (and negating the offset and the
//! tie-break direction) gives the same depth and the opposite normal, bit for bit. So the two
//! threads of a pair, each computing its own response, agree exactly.

use glam::Vec2;

use super::kinds::Bound;

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
        let dist = libm::sqrtf(dist2);
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
        let dist = libm::sqrtf(dist2);
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
