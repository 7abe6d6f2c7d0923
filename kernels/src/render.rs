//! A renderer that is a kernel: every live body drawn into an RGBA image, with the same
//! source on the GPU and on the CPU emulation, so a frame is the same pixels on both (and
//! can be hashed like a state).
//!
//! Two launches, barrier-free:
//! 1. [`splat_bodies`]: each body covers the pixels of its shape with a key that says who
//!    is drawn there (layer, kind, shade). Overlaps are settled by an atomic maximum, which
//!    does not depend on the order threads arrive in: the highest layer wins, then the
//!    highest kind, then the brighter shade.
//! 2. [`resolve_pixels`]: each pixel turns its key into a colour from the kinds' looks (the
//!    background where nothing was drawn) and clears the key for the next frame.
//!
//! The GL renderer (the paper's way) draws from [`BodyVertex`]es instead, which
//! [`write_vertices`] writes straight into the vertex buffer GL draws from; its shaders
//! follow the same rules (shapes, shades, layers), so both renderers draw the same picture.

use glam::Vec2;

use crate::sim::kinds::SHAPE_RECT;
use crate::sim::{Bodies, KindInfo};
use crate::{DevSlice, KernelArgs, Thread};

/// Largest radius, in pixels, a body is drawn with: bounds the work of one thread.
pub const MAX_RADIUS_PX: f32 = 48.0;
/// Shade of a body's pixels: its colour.
pub const BODY: u32 = 0;
/// Shade of a body's pixels towards where it faces (its nose).
pub const NOSE: u32 = 1;
/// Shade of the body's pixels (its nose excepted) while it has lost energy: the hit effect.
pub const HURT: u32 = 2;
/// Fraction of the radius beyond which a pixel on the facing side is the nose.
pub const NOSE_FROM: f32 = 0.35;

/// Which part of the world the image shows: pixel `(x, y)` (row 0 at the top) covers the
/// world around `origin + ((x + ½) / scale, (height − y − ½) / scale)`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct View {
    /// World position of the image's bottom-left corner.
    pub origin: Vec2,
    /// Pixels per world unit.
    pub scale: f32,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Background colour, RGBA8 packed little-endian (red in the low byte).
    pub background: u32,
}

impl View {
    /// The whole world `size` centred in a `width × height` image, the same scale on both
    /// axes.
    pub fn whole(size: Vec2, width: u32, height: u32, background: u32) -> View {
        let scale = (width as f32 / size.x).min(height as f32 / size.y);
        let shown = Vec2::new(width as f32, height as f32) / scale;
        View {
            origin: (size - shown) * 0.5,
            scale,
            width,
            height,
            background,
        }
    }

    /// The image position (x to the right, y down, in pixels) of world position `pos`.
    #[inline(always)]
    pub fn to_image(&self, pos: Vec2) -> Vec2 {
        let p = (pos - self.origin) * self.scale;
        Vec2::new(p.x, self.height as f32 - p.y)
    }
}

/// How the bodies of one kind look.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct Look {
    /// Body colour, RGBA8 packed little-endian.
    pub colour: u32,
    /// Colour of the side it faces.
    pub nose: u32,
    /// Drawing order: a higher layer covers a lower one (0 to 255).
    pub layer: u32,
    /// Body colour while it has less energy than it was born with.
    pub hurt: u32,
}

impl Look {
    /// The colour of `shade` ([`BODY`], [`NOSE`] or [`HURT`]).
    #[inline(always)]
    pub fn colour_of(&self, shade: u32) -> u32 {
        match shade {
            NOSE => self.nose,
            HURT => self.hurt,
            _ => self.colour,
        }
    }
}

/// Whether the body in `slot` is drawn hurt: it has lost energy, and its kind has any.
#[inline(always)]
pub fn is_hurt(b: &Bodies, info: &KindInfo, slot: u32) -> bool {
    b.energy.get(slot) < info.energy
}

/// The key of an undrawn pixel.
pub const EMPTY: u32 = 0;

/// Bit 7 of every drawn key, so that none is [`EMPTY`].
const DRAWN: u32 = 0x80;
/// The shade's bits of a key.
const SHADE: u32 = DRAWN - 1;

/// A pixel's key: layer, then kind, then shade, so that the maximum is the body on top.
/// Never [`EMPTY`].
#[inline(always)]
pub fn key(layer: u32, kind: u32, shade: u32) -> u32 {
    ((layer & 0xff) << 24) | ((kind & 0xffff) << 8) | DRAWN | (shade & SHADE)
}

/// The kind and the shade a key was drawn with.
#[inline(always)]
pub fn unkey(key: u32) -> (u32, u32) {
    ((key >> 8) & 0xffff, key & SHADE)
}

/// Arguments of [`splat_bodies`].
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::NoUninit)]
pub struct SplatArgs {
    /// The bodies (read only).
    pub bodies: Bodies,
    /// Kind table (shapes and sizes).
    pub kinds: DevSlice<KindInfo>,
    /// Each kind's look.
    pub looks: DevSlice<Look>,
    /// What the image shows.
    pub view: View,
    /// One key per pixel, row-major; [`EMPTY`] before the first body draws there.
    pub keys: DevSlice<u32>,
}
// SAFETY: repr(C) plain data.
unsafe impl KernelArgs for SplatArgs {}

/// Thread `i` draws slot `i`'s body, if one lives there: every pixel whose centre lies in its
/// shape (and at least the pixel under its centre), the facing side in its nose colour.
#[inline(always)]
pub fn splat_bodies(t: Thread, args: &SplatArgs) {
    let b = &args.bodies;
    let slot = t.global();
    if slot >= b.slots() || !b.is_alive(slot) {
        return;
    }
    let view = &args.view;
    let kind = b.kind.get(slot);
    let info = args.kinds.get(kind);
    let layer = args.looks.get(kind).layer;
    let centre = view.to_image(b.pos.get(slot));
    let (w, h) = (view.width as f32, view.height as f32);
    let reach = (info.radius * view.scale).min(MAX_RADIUS_PX);
    // Off the image by more than its size: nothing to draw (and no huge loop bounds).
    let near_image = centre.x > -reach - 1.0
        && centre.x < w + reach + 1.0
        && centre.y > -reach - 1.0
        && centre.y < h + reach + 1.0;
    if !near_image {
        return;
    }
    let half = if info.shape == SHAPE_RECT {
        (info.half * view.scale).min(Vec2::splat(MAX_RADIUS_PX))
    } else {
        Vec2::splat(reach)
    };
    let body_shade = if is_hurt(b, &info, slot) { HURT } else { BODY };
    let facing = b.dir.get(slot);
    // Image y runs down: the facing direction flips its y.
    let facing = Vec2::new(facing.x, -facing.y);
    let x0 = (centre.x - half.x).max(0.0) as u32;
    let y0 = (centre.y - half.y).max(0.0) as u32;
    let x1 = ((centre.x + half.x) as u32).min(view.width - 1);
    let y1 = ((centre.y + half.y) as u32).min(view.height - 1);
    // The pixel under the centre, if the centre is on the image: a body smaller than a
    // pixel still shows.
    let on_image = centre.x >= 0.0 && centre.x < w && centre.y >= 0.0 && centre.y < h;
    let under = on_image.then_some((centre.x as u32, centre.y as u32));
    for y in y0..=y1 {
        for x in x0..=x1 {
            let d = Vec2::new(x as f32 + 0.5, y as f32 + 0.5) - centre;
            let inside = if info.shape == SHAPE_RECT {
                d.x.abs() <= half.x && d.y.abs() <= half.y
            } else {
                d.length_squared() <= reach * reach
            };
            if !inside && under != Some((x, y)) {
                continue;
            }
            let shade = if d.dot(facing) > NOSE_FROM * reach {
                NOSE
            } else {
                body_shade
            };
            let pixel = y * view.width + x;
            args.keys.atomic_max(pixel, key(layer, kind, shade));
        }
    }
}

/// Arguments of [`resolve_pixels`].
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::NoUninit)]
pub struct ResolveArgs {
    /// Each kind's look.
    pub looks: DevSlice<Look>,
    /// The keys of [`splat_bodies`]; cleared to [`EMPTY`] on the way.
    pub keys: DevSlice<u32>,
    /// Output: one RGBA8 colour per pixel, row-major.
    pub image: DevSlice<u32>,
    /// Background colour, RGBA8.
    pub background: u32,
    /// Keeps the struct free of implicit padding (checked by its `NoUninit` derive).
    pub reserved: u32,
}
// SAFETY: repr(C) plain data.
unsafe impl KernelArgs for ResolveArgs {}

/// Thread `p` colours pixel `p` from its key and clears the key.
#[inline(always)]
pub fn resolve_pixels(t: Thread, args: &ResolveArgs) {
    let pixel = t.global();
    if pixel >= args.image.len() {
        return;
    }
    let key = args.keys.get(pixel);
    let colour = if key == EMPTY {
        args.background
    } else {
        let (kind, shade) = unkey(key);
        args.looks.get(kind).colour_of(shade)
    };
    args.image.set(pixel, colour);
    args.keys.set(pixel, EMPTY);
}

/// [`BodyVertex::flags`]: a body lives in this slot (the others are not drawn).
pub const VERTEX_ALIVE: u32 = 1;
/// [`BodyVertex::flags`]: the body is hurt (see [`is_hurt`]).
pub const VERTEX_HURT: u32 = 2;

/// One slot as the GL renderer draws it: "the positions and type are put in a VBO" (paper,
/// section 5). The layout of the vertex buffer, for the kernel that writes it and the
/// shaders that read it.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct BodyVertex {
    /// World position.
    pub pos: Vec2,
    /// Unit direction the body faces.
    pub dir: Vec2,
    /// Kind index.
    pub kind: u32,
    /// [`VERTEX_ALIVE`] and [`VERTEX_HURT`] bits.
    pub flags: u32,
}

/// Arguments of [`write_vertices`].
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::NoUninit)]
pub struct VertexArgs {
    /// The bodies (read only).
    pub bodies: Bodies,
    /// Kind table (energies at birth).
    pub kinds: DevSlice<KindInfo>,
    /// Output: one vertex per slot (the GL vertex buffer, mapped, on the GPU).
    pub vertices: DevSlice<BodyVertex>,
}
// SAFETY: repr(C) plain data.
unsafe impl KernelArgs for VertexArgs {}

/// Thread `i` writes slot `i`'s vertex (flags 0 for a free slot).
#[inline(always)]
pub fn write_vertices(t: Thread, args: &VertexArgs) {
    let b = &args.bodies;
    let slot = t.global();
    if slot >= b.slots() || slot >= args.vertices.len() {
        return;
    }
    let vertex = if b.is_alive(slot) {
        let kind = b.kind.get(slot);
        let hurt = is_hurt(b, &args.kinds.get(kind), slot);
        BodyVertex {
            pos: b.pos.get(slot),
            dir: b.dir.get(slot),
            kind,
            flags: VERTEX_ALIVE | if hurt { VERTEX_HURT } else { 0 },
        }
    } else {
        BodyVertex::default()
    };
    args.vertices.set(slot, vertex);
}
