//! The radar: the whole field at low resolution in a corner of the frame, so that a player
//! who sees only the ship's surroundings knows where the enemies are.
//!
//! [`radar_bodies`] counts bodies per radar pixel (atomic adds: the counts do not depend on
//! the order threads arrive in) and keeps the key of the highest-layer kind there (atomic
//! maximum). At 16 million bodies a radar pixel covers thousands of them and its
//! brightness is only a logarithm of its count, so one slot in [`stride`] is sampled: the
//! launch stays at most [`SAMPLES`] threads, a few microseconds, instead of a second pass
//! over every slot (the broad phase's grid counts would be cheaper still, but not every
//! world builds a grid). The sampled slots are fixed, so the picture is deterministic.
//!
//! [`radar_colour`] turns the counts into a pixel of the frame: the density in the kind's
//! colour, the ship's mark, the view's outline and a 1-pixel frame. The kernel renderer
//! calls it in `resolve_pixels`; [`radar_image`] writes the same pixels into a small image
//! for the GL renderer to show over its frame.

use glam::Vec2;

use super::DrawnBodies;
use super::{Look, NO_SHIP, Shown, key, unkey};
use crate::{DevSlice, Thread, kernel_args};

/// Most slots sampled per frame (see [`stride`]).
pub const SAMPLES: u32 = 262_144;
/// Largest side of the radar's inside, in pixels.
pub const MAX_SIDE: u32 = 220;
/// Smallest side of the radar's inside; a frame too small for it has no radar.
pub const MIN_SIDE: u32 = 24;
/// The radar's side as a share of the frame's smaller side.
pub const SHARE: f32 = 0.2;
/// Pixels between the radar's frame and the frame's edges.
pub const MARGIN: u32 = 8;
/// Colour of the radar's 1-pixel frame.
pub const FRAME: u32 = u32::from_le_bytes([110, 120, 150, 255]);
/// Colour of the radar where nothing is.
pub const EMPTY_COLOUR: u32 = u32::from_le_bytes([3, 4, 10, 255]);
/// Colour of the outline of the part of the field the frame shows.
pub const OUTLINE: u32 = u32::from_le_bytes([190, 195, 215, 255]);
/// Half length, in radar pixels, of the arms of the ship's cross.
pub const MARK_ARM: i32 = 2;

/// Where the radar lies in the frame: its frame included, top-left corner at
/// `(left, top)`. Width 0: no radar.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct RadarBox {
    /// Column of the box's left edge.
    pub left: u32,
    /// Row of the box's top edge.
    pub top: u32,
    /// Width, the 1-pixel frame included.
    pub width: u32,
    /// Height, the 1-pixel frame included.
    pub height: u32,
}

impl RadarBox {
    /// No radar.
    pub const NONE: RadarBox = RadarBox {
        left: 0,
        top: 0,
        width: 0,
        height: 0,
    };

    /// Pixels of the inside (the frame excluded): the length of the count buffers used.
    #[inline(always)]
    pub fn inner(&self) -> (u32, u32) {
        (self.width.saturating_sub(2), self.height.saturating_sub(2))
    }

    /// Whether image pixel `(x, y)` lies in the box.
    #[inline(always)]
    pub fn contains(&self, x: u32, y: u32) -> bool {
        x >= self.left && x - self.left < self.width && y >= self.top && y - self.top < self.height
    }
}

/// The radar of a `width × height` frame of a `field`-sized world: in the top-right
/// corner, its longer side [`SHARE`] of the frame's smaller side (at most [`MAX_SIDE`]),
/// the field's proportions kept; [`RadarBox::NONE`] when that is below [`MIN_SIDE`].
#[inline]
pub fn radar_box(width: u32, height: u32, field: Vec2) -> RadarBox {
    let side = ((width.min(height) as f32 * SHARE) as u32).min(MAX_SIDE);
    if side < MIN_SIDE {
        return RadarBox::NONE;
    }
    let (w, h) = if field.x >= field.y {
        (side, ((side as f32 * field.y / field.x) as u32).max(1))
    } else {
        (((side as f32 * field.x / field.y) as u32).max(1), side)
    };
    RadarBox {
        left: width - MARGIN - (w + 2),
        top: MARGIN,
        width: w + 2,
        height: h + 2,
    }
}

/// One slot in this many is counted on the radar: all of them up to [`SAMPLES`] slots.
#[inline(always)]
pub fn stride(slots: u32) -> u32 {
    slots.div_ceil(SAMPLES).max(1)
}

/// The radar pixel (inside the frame, row 0 at the top) of field position `pos`, for a
/// radar whose inside is `inner` pixels; positions off the field go to its edge.
#[inline(always)]
pub fn cell(pos: Vec2, field: Vec2, inner: (u32, u32)) -> (i32, i32) {
    let (w, h) = (inner.0 as i32, inner.1 as i32);
    let x = ((pos.x / field.x * inner.0 as f32) as i32).clamp(0, w - 1);
    let y = ((pos.y / field.y * inner.1 as f32) as i32).clamp(0, h - 1);
    (x, h - 1 - y)
}

crate::device_data! {
    /// The radar's per-pixel buffers, one element per pixel of its inside (row-major).
    pub struct RadarCounts(cells): RadarCountsAccess {
        /// Sampled bodies per pixel.
        counts: [u32; cells],
        /// The key ([`key`], shade 0) of the highest-layer kind counted there.
        top: [u32; cells],
    }
}

kernel_args! {
    /// Arguments of [`radar_bodies`].
    pub struct RadarArgs {
        /// The bodies (read only).
        pub bodies: DrawnBodies,
        /// Each kind's look (which kinds the radar shows).
        pub looks: DevSlice<Look>,
        /// What the frame shows (the radar's box, the field, the ship), from the camera.
        pub shown: DevSlice<Shown>,
        /// Output: counts and top kinds, zero before the launch.
        pub radar: RadarCounts,
        /// Thread `i` samples slot `i × stride` (see [`stride`]).
        pub stride: u32,
        /// Keeps the struct free of implicit padding (checked by its `NoUninit` derive).
        pub reserved: u32,
    }
}

/// Thread `i` counts the body in slot `i × stride`, if one lives there, its kind is shown
/// on the radar ([`Look::radar`]) and it is not the ship.
#[inline(always)]
pub fn radar_bodies(t: Thread, args: &RadarArgs) {
    let slot = t.global() as u64 * args.stride as u64;
    if slot < args.bodies.slots() as u64 {
        let shown = args.shown.get(0);
        count(&args.bodies, &args.looks, &shown, &args.radar, slot as u32);
    }
}

/// Counts the body in `slot`, if one lives there, in the radar pixel it lies in, and keeps
/// the highest layer's kind there (nothing without a radar, for the ship, or for a kind the
/// radar does not show).
#[inline(always)]
pub fn count(
    b: &DrawnBodies,
    looks: &DevSlice<Look>,
    shown: &Shown,
    radar: &RadarCounts,
    slot: u32,
) {
    if shown.radar.width == 0 || slot >= b.slots() || !b.is_alive(slot) || slot == shown.ship {
        return;
    }
    let kind = b.kind.get(slot);
    let look = looks.get(kind);
    if look.radar == 0 {
        return;
    }
    let inner = shown.radar.inner();
    let (x, y) = cell(b.pos.get(slot), shown.field, inner);
    let pixel = y as u32 * inner.0 + x as u32;
    radar.counts.atomic_add(pixel, 1);
    radar.top.atomic_max(pixel, key(look.layer, kind, 0));
}

/// `colour` at brightness `level` from 1 to 8 (5 twelfths of full at 1: a lone body shows).
#[inline(always)]
fn dimmed(colour: u32, level: u32) -> u32 {
    let [r, g, b, a] = colour.to_le_bytes();
    let scale = |c: u8| (c as u32 * (4 + level) / 12) as u8;
    u32::from_le_bytes([scale(r), scale(g), scale(b), a])
}

/// The radar's colour at image pixel `(x, y)`, which its box covers
/// ([`RadarBox::contains`]), and clears that pixel's counts for the next frame (each pixel
/// has one caller per launch). Natively a call of its own: inlined, the compiler worked out
/// its cells of the ship and the view (divisions, saturating conversions) for every thread
/// of `resolve_pixels` before it looked at a pixel, radar or not, and the CPU's frame of
/// the whole field took 1.7 times as long. On the GPU inlined, as everything is.
#[cfg_attr(target_arch = "nvptx64", inline(always))]
#[cfg_attr(not(target_arch = "nvptx64"), inline(never))]
pub fn radar_colour(
    shown: &Shown,
    radar: &RadarCounts,
    looks: &DevSlice<Look>,
    stride: u32,
    x: u32,
    y: u32,
) -> u32 {
    let bx = &shown.radar;
    let (ix, iy) = ((x - bx.left) as i32 - 1, (y - bx.top) as i32 - 1);
    let inner = bx.inner();
    if ix < 0 || iy < 0 || ix >= inner.0 as i32 || iy >= inner.1 as i32 {
        return FRAME;
    }
    let pixel = iy as u32 * inner.0 + ix as u32;
    let (count, top) = (radar.counts.get(pixel), radar.top.get(pixel));
    radar.counts.set(pixel, 0);
    radar.top.set(pixel, 0);
    if shown.ship != NO_SHIP {
        let (sx, sy) = cell(shown.ship_pos, shown.field, inner);
        let (dx, dy) = ((ix - sx).abs(), (iy - sy).abs());
        if (dx == 0 && dy <= MARK_ARM) || (dy == 0 && dx <= MARK_ARM) {
            return looks.get(shown.ship_kind).colour;
        }
    }
    let view = &shown.view;
    let seen = Vec2::new(view.width as f32, view.height as f32) / view.scale;
    let (x0, y1) = cell(view.origin, shown.field, inner);
    let (x1, y0) = cell(view.origin + seen, shown.field, inner);
    let on_columns = (ix == x0 || ix == x1) && iy >= y0 && iy <= y1;
    let on_rows = (iy == y0 || iy == y1) && ix >= x0 && ix <= x1;
    if on_columns || on_rows {
        return OUTLINE;
    }
    if count == 0 {
        return EMPTY_COLOUR;
    }
    let (kind, _) = unkey(top);
    // Brightness: the bit length of the bodies the samples stand for, from 1 to 8.
    let level = (32 - count.saturating_mul(stride).leading_zeros()).min(8);
    dimmed(looks.get(kind).colour, level)
}

kernel_args! {
    /// Arguments of [`radar_image`].
    pub struct RadarImageArgs {
        /// Each kind's look.
        pub looks: DevSlice<Look>,
        /// What the frame shows, from the camera.
        pub shown: DevSlice<Shown>,
        /// The counts of [`radar_bodies`]; cleared on the way.
        pub radar: RadarCounts,
        /// Output: the radar's box, row-major from its top-left corner.
        pub image: DevSlice<u32>,
        /// The stride [`radar_bodies`] sampled with.
        pub stride: u32,
        /// Keeps the struct free of implicit padding (checked by its `NoUninit` derive).
        pub reserved: u32,
    }
}

/// Thread `p` writes pixel `p` of the radar's box (for a renderer that shows the radar
/// over a frame of its own).
#[inline(always)]
pub fn radar_image(t: Thread, args: &RadarImageArgs) {
    let shown = args.shown.get(0);
    let bx = shown.radar;
    let p = t.global();
    if p >= bx.width * bx.height || p >= args.image.len() {
        return;
    }
    let (x, y) = (bx.left + p % bx.width, bx.top + p / bx.width);
    let colour = radar_colour(&shown, &args.radar, &args.looks, args.stride, x, y);
    args.image.set(p, colour);
}
