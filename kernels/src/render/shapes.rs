//! Silhouettes: the shape a body is drawn with, turned to its heading, so that kinds can be
//! told apart by shape as well as by colour.
//!
//! Each silhouette is one inside test, [`inside`], of a pixel's offset from the body's
//! centre in the body's own frame (`u` along the heading, `v` across it) and the body's
//! radius in pixels. The kernel renderer calls it; the GL renderer's fragment shader is a
//! line-for-line copy (`host/graphics/bodies.rs`), so both draw the same shapes. Every
//! silhouette lies inside the circle of the radius (so the pixels a body covers are found
//! in its bounding square), except [`STREAK`], which trails [`STREAK_LENGTH`] radii behind.

use glam::Vec2;

/// A disc: bodies smaller than [`SHAPE_FROM_PX`], and kinds with no silhouette.
pub const DISC: u32 = 0;
/// A square of side 1.4 radii (its corners just inside the circle).
pub const SQUARE: u32 = 1;
/// A square standing on a corner, its corners on the circle.
pub const DIAMOND: u32 = 2;
/// A triangle pointing along the heading.
pub const TRIANGLE: u32 = 3;
/// A ring: the circle less the middle, out to [`RING_HOLE`] radii.
pub const RING: u32 = 4;
/// An arrowhead pointing along the heading, its back corners on the circle at
/// `(−0.8, ±0.6)` radii, notched back to `−0.5` (the ship).
pub const CHEVRON: u32 = 5;
/// A plus sign whose arms are 0.6 radii wide and reach 0.95 radii.
pub const CROSS: u32 = 6;
/// A regular hexagon, its corners on the circle.
pub const HEXAGON: u32 = 7;
/// Two triangles meeting at the centre, open to the sides.
pub const BOWTIE: u32 = 8;
/// A capsule trailing [`STREAK_LENGTH`] radii behind the centre (shots).
pub const STREAK: u32 = 9;
/// An axis-aligned rectangle of the kind's half extents (obstacles); never turned.
pub const RECT: u32 = 10;
/// The number of silhouettes.
pub const COUNT: u32 = 11;

/// Radius in pixels from which a body is drawn with its silhouette; smaller ones are
/// discs, as a silhouette a few pixels across is not readable anyway.
pub const SHAPE_FROM_PX: f32 = 3.0;
/// The hole of a [`RING`], in radii.
pub const RING_HOLE: f32 = 0.55;
/// How far behind its centre a [`STREAK`] trails, in radii.
pub const STREAK_LENGTH: f32 = 3.0;
/// √3 / 2: the [`HEXAGON`]'s half height.
pub const HALF_SQRT3: f32 = 0.866_025_4;
/// 1 / √3: the slope of the [`HEXAGON`]'s slanted sides.
pub const INV_SQRT3: f32 = 0.577_350_26;

/// The silhouette a body of `silhouette` is drawn with at `radius_px` pixels: a disc below
/// [`SHAPE_FROM_PX`] (except rectangles, which stay rectangles).
#[inline(always)]
pub fn drawn(silhouette: u32, radius_px: f32) -> u32 {
    if silhouette == RECT || radius_px >= SHAPE_FROM_PX {
        silhouette
    } else {
        DISC
    }
}

/// How far the silhouette reaches from the centre, in radii (its bounding square's half
/// side).
#[inline(always)]
pub fn extent(silhouette: u32) -> f32 {
    if silhouette == STREAK {
        1.0 + STREAK_LENGTH
    } else {
        1.0
    }
}

/// The offset `d` (image pixels) in a body's frame: `u` along `heading` (a unit vector in
/// image coordinates), `v` across it.
#[inline(always)]
pub fn local(d: Vec2, heading: Vec2) -> Vec2 {
    Vec2::new(
        d.x * heading.x + d.y * heading.y,
        d.y * heading.x - d.x * heading.y,
    )
}

/// Whether offset `p` (in the body's frame, see [`local`]) lies inside `silhouette` of
/// radius `r` pixels. [`DISC`] and [`RECT`] are tested by the caller (they need no turn).
#[inline(always)]
pub fn inside(silhouette: u32, p: Vec2, r: f32) -> bool {
    let (u, v) = (p.x, p.y.abs());
    match silhouette {
        SQUARE => u.abs() <= 0.7 * r && v <= 0.7 * r,
        DIAMOND => u.abs() + v <= r,
        TRIANGLE => u >= -0.6 * r && v <= (r - u) * 0.5,
        RING => {
            let d2 = u * u + v * v;
            d2 <= r * r && d2 >= RING_HOLE * RING_HOLE * r * r
        }
        CHEVRON => 3.0 * v <= r - u && u >= -0.5 * r - 0.5 * v,
        CROSS => {
            let (a, b) = (u.abs(), v);
            (a <= 0.3 * r && b <= 0.95 * r) || (b <= 0.3 * r && a <= 0.95 * r)
        }
        HEXAGON => v <= HALF_SQRT3 * r && u.abs() + v * INV_SQRT3 <= r,
        BOWTIE => u.abs() <= 0.75 * r && v <= u.abs() * 0.8,
        STREAK => {
            // The segment from the centre back to STREAK_LENGTH radii behind, thickened
            // by the radius.
            let along = u.min(0.0).max(-STREAK_LENGTH * r);
            let du = u - along;
            du * du + v * v <= r * r
        }
        _ => u * u + v * v <= r * r,
    }
}
