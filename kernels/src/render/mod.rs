//! A renderer that is a kernel: every live body drawn into an RGBA image, with the same
//! source on the GPU and on the CPU emulation, so a frame is the same pixels on both (and
//! can be hashed like a state).
//!
//! Three launches (four with explosions), barrier-free:
//! 1. [`splat_bodies`]: each thread first works out where the view is, from the ship's
//!    position and the camera's state between frames ([`camera::frame`]; thread 0 writes
//!    it as the frame's [`Shown`] for the launches after; a world of more than
//!    [`FOLD_CAMERA_SLOTS`] slots runs [`camera::camera`] first instead, as a launch of its
//!    own, where so many threads would cost more), and counts its body on the radar
//!    ([`radar::count`]: atomic adds and maxima). Then each body covers the pixels of its
//!    silhouette ([`shapes`]) with a key that says who is drawn there (layer, kind, shade).
//!    Overlaps are settled by an atomic maximum, which does not depend on the order threads
//!    arrive in: the highest layer wins, then the highest kind, then the higher shade.
//! 2. [`splat_large`]: a body whose box covers more than [`LARGE_PIXELS`] pixels of the
//!    image was listed instead, and is drawn here by [`LARGE_LANES`] threads over the
//!    pixels of its box: a GPU thread's loop is bound by latency, so one thread walking the
//!    ship's halo close up set the whole frame's time (about 0.6 ms at 1080p on an H200).
//!    With explosions, [`particles::splat_particles`] then draws each shown particle's disc
//!    the same way, in the lowest layer.
//! 3. [`resolve_pixels`]: each pixel turns its key into a colour from the kinds' looks (the
//!    backdrop's, [`backdrop::on_grid`], or the background where nothing was drawn), or the
//!    radar's colour in its corner, and clears the key for the next frame.
//!
//! The GL renderer (the paper's way) draws from [`BodyVertex`]es instead, which
//! [`write_vertices`] writes straight into the vertex buffer GL draws from, in image
//! coordinates of the same view (after [`camera::camera`] and [`radar::radar_bodies`], the
//! same work as the first launch's above, as launches of their own); its shaders follow the
//! same rules (silhouettes, shades, layers), so both renderers draw the same picture.
//!
//! Key format: layer (8 bits), kind (16 bits), a drawn bit, shade (7 bits). Shades:
//! [`BODY`], [`NOSE`], [`HURT`], [`HALO`], and [`PARTICLE`]`..`[`PARTICLE`]` + 16` for
//! particles at fade levels 0 to 15 ([`particle_key`], [`fade`]).

pub mod backdrop;
pub mod camera;
pub mod particles;
pub mod radar;
pub mod shapes;
pub mod still;

use glam::Vec2;

use crate::access::{Read, Unused};
use crate::data::View;
use crate::game::control::Input;
use crate::sim::kinds::SHAPE_RECT;
use crate::sim::{Bodies, BodiesAccess, KindInfo};
use crate::warp::WARP;
use crate::{DevSlice, Thread, access, kernel_args};
use camera::{CameraState, Lens};
use radar::{RadarBox, RadarCounts};
use shapes::{DISC, RECT};

access! {
    /// What the renderers read of the bodies: where each is and faces, its kind, its
    /// energy (the hurt shade) and whether it lives.
    pub struct Drawing: BodiesAccess {
        pos: Read, vel: Unused, force: Unused, dir: Read, kind: Read, energy: Read,
        mass: Unused, alive: Read, state: Unused, age: Unused, prev: Unused, frozen: Unused,
        rng: Unused,
    }
}

/// The bodies as the renderers read them.
pub type DrawnBodies = Bodies<View, Drawing>;

/// Largest radius, in pixels, a body is drawn with: bounds the work of one thread.
pub const MAX_RADIUS_PX: f32 = 48.0;
/// Shade of a body's pixels: its colour.
pub const BODY: u32 = 0;
/// Shade of a body's pixels towards where it faces (its nose).
pub const NOSE: u32 = 1;
/// Shade of the body's pixels (its nose excepted) while it has lost energy: the hit effect.
pub const HURT: u32 = 2;
/// Shade of the ship's halo: its colour faded [`HALO_FADE`] sixteenths of the way to the
/// background.
pub const HALO: u32 = 3;
/// First shade of particles: shade `PARTICLE + level` is fade level `level` (0 to
/// [`PARTICLE_LEVELS`] − 1).
pub const PARTICLE: u32 = 64;
/// Fade levels of particles.
pub const PARTICLE_LEVELS: u32 = 16;
/// Fraction of the radius beyond which a pixel on the facing side is the nose.
pub const NOSE_FROM: f32 = 0.35;
/// Layer of the ship's halo: under every body.
pub const HALO_LAYER: u32 = 1;
/// Layer of particles: the lowest.
pub const PARTICLE_LAYER: u32 = 0;
/// The halo's fade towards the background, in sixteenths.
pub const HALO_FADE: u32 = 11;
/// Inner radius of the ship's halo, in the ship's radii.
pub const HALO_FROM: f32 = 1.45;
/// Outer radius of the ship's halo, in the ship's radii.
pub const HALO_TO: f32 = 1.7;

/// Which part of the world the image shows: pixel `(x, y)` (row 0 at the top) covers the
/// world around `origin + ((x + ½) / scale, (height − y − ½) / scale)`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct Framing {
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

impl Framing {
    /// The whole world `size` centred in a `width × height` image, the same scale on both
    /// axes (what the camera shows in its field mode).
    pub fn whole(size: Vec2, width: u32, height: u32, background: u32) -> Framing {
        let scale = camera::fit_scale(size, width, height);
        camera::view_at(size * 0.5, scale, width, height, background)
    }

    /// The image position (x to the right, y down, in pixels) of world position `pos`.
    #[inline(always)]
    pub fn to_image(&self, pos: Vec2) -> Vec2 {
        let p = (pos - self.origin) * self.scale;
        Vec2::new(p.x, self.height as f32 - p.y)
    }

    /// The world position at image position `p` (x to the right, y down, in pixels): the
    /// inverse of [`Framing::to_image`].
    #[inline(always)]
    pub fn to_world(&self, p: Vec2) -> Vec2 {
        self.origin + Vec2::new(p.x, self.height as f32 - p.y) / self.scale
    }
}

/// [`Shown::ship`] (and [`camera::Lens::ship`]) of a world without a ship.
pub const NO_SHIP: u32 = u32::MAX;

/// What one frame shows, written by the camera kernel for the drawing kernels.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct Shown {
    /// The part of the world in the frame.
    pub view: Framing,
    /// Where the radar is ([`RadarBox::NONE`]: no radar).
    pub radar: RadarBox,
    /// Size of the field.
    pub field: Vec2,
    /// The ship's position (when there is a ship).
    pub ship_pos: Vec2,
    /// The ship's aim, a unit vector: the way its chevron points.
    pub ship_aim: Vec2,
    /// The ship's slot, or [`NO_SHIP`].
    pub ship: u32,
    /// The ship's kind.
    pub ship_kind: u32,
    /// Nonzero: the backdrop ([`backdrop::on_grid`]) is drawn where nothing else is (a
    /// camera following a ship).
    pub backdrop: u32,
    /// Keeps the struct free of implicit padding.
    pub reserved: u32,
}

/// How the bodies of one kind look.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct Look {
    /// Body colour, RGBA8 packed little-endian.
    pub colour: u32,
    /// Colour of the side it faces.
    pub nose: u32,
    /// Drawing order: a higher layer covers a lower one (2 to 255; 0 and 1 are the
    /// particles' and the halo's).
    pub layer: u32,
    /// Body colour while it has less energy than it was born with.
    pub hurt: u32,
    /// Its shape when large enough (one of the [`shapes`] constants; circles only, a
    /// rectangle kind is always a [`shapes::RECT`]).
    pub silhouette: u32,
    /// Nonzero: the radar shows bodies of this kind.
    pub radar: u32,
}

impl Look {
    /// The colour of `shade` (see the key format in the module's doc) over `background`.
    #[inline(always)]
    pub fn colour_of(&self, shade: u32, background: u32) -> u32 {
        match shade {
            NOSE => self.nose,
            HURT => self.hurt,
            HALO => fade(self.colour, background, HALO_FADE),
            s if s >= PARTICLE => fade(self.colour, background, s - PARTICLE),
            _ => self.colour,
        }
    }
}

/// `colour` moved `level` sixteenths of the way to `background` (level 0: `colour`; at
/// most 15), channel by channel, alpha included, in exact integer steps.
#[inline(always)]
pub fn fade(colour: u32, background: u32, level: u32) -> u32 {
    let level = level.min(PARTICLE_LEVELS - 1) as i32;
    let (c, b) = (colour.to_le_bytes(), background.to_le_bytes());
    let mix = |i: usize| (c[i] as i32 + (b[i] as i32 - c[i] as i32) * level / 16) as u8;
    u32::from_le_bytes([mix(0), mix(1), mix(2), mix(3)])
}

/// Whether the body in `slot` is drawn hurt: it has lost energy, and its kind has any.
#[inline(always)]
pub fn is_hurt(b: &DrawnBodies, info: &KindInfo, slot: u32) -> bool {
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

/// The key of a particle of `kind` at fade `level` (0: the kind's colour; 15: nearly the
/// background; larger levels are 15), in `layer`, or under every body ([`PARTICLE_LAYER`])
/// when `None`. Its colour is [`fade`] of the kind's colour towards the background.
#[inline(always)]
pub fn particle_key(layer: Option<u32>, kind: u32, level: u32) -> u32 {
    let level = level.min(PARTICLE_LEVELS - 1);
    key(layer.unwrap_or(PARTICLE_LAYER), kind, PARTICLE + level)
}

/// The kind and the shade a key was drawn with.
#[inline(always)]
pub fn unkey(key: u32) -> (u32, u32) {
    ((key >> 8) & 0xffff, key & SHADE)
}

/// A live body as both renderers draw it, in image coordinates.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sprite {
    /// Image position of the centre (pixels, y down).
    pub centre: Vec2,
    /// The way it faces, a unit vector in image coordinates (y down).
    pub facing: Vec2,
    /// Half extents in pixels: a rectangle's; `(radius, radius)` otherwise.
    pub half: Vec2,
    /// Radius in pixels (a rectangle's: of the circle around it), at most
    /// [`MAX_RADIUS_PX`]: the silhouette's size, and where the nose starts.
    pub radius: f32,
    /// Half side of the square its pixels lie in (its halo included).
    pub bound: f32,
    /// The silhouette drawn (see [`shapes::drawn`]).
    pub silhouette: u32,
    /// [`BODY`], or [`HURT`] when it has lost energy.
    pub shade: u32,
    /// Whether a halo rings it (the ship, drawn with its silhouette).
    pub halo: bool,
}

/// How the body in live `slot` is drawn in `shown`'s view.
#[inline(always)]
pub fn sprite(
    b: &DrawnBodies,
    kinds: &DevSlice<KindInfo, Read>,
    look: &Look,
    shown: &Shown,
    slot: u32,
) -> Sprite {
    let info = kinds.get(b.kind.get(slot));
    outline(b, &info, look, shown, slot).dressed(b, &info, shown, slot)
}

/// Where and how large the body in live `slot` (of kind `info`) is drawn, from its
/// position and kind alone: enough to skip a body off the image before reading more of
/// it. Its facing and shade are left for [`Sprite::dressed`].
#[inline(always)]
fn outline(b: &DrawnBodies, info: &KindInfo, look: &Look, shown: &Shown, slot: u32) -> Sprite {
    let view = &shown.view;
    let reach = (info.reach * view.scale).min(MAX_RADIUS_PX);
    let (silhouette, half) = if info.shape == SHAPE_RECT {
        (
            RECT,
            (info.half * view.scale).min(Vec2::splat(MAX_RADIUS_PX)),
        )
    } else {
        (shapes::drawn(look.silhouette, reach), Vec2::splat(reach))
    };
    let halo = slot == shown.ship && silhouette != DISC && silhouette != RECT;
    let bound = if halo {
        reach * HALO_TO
    } else {
        half.x.max(half.y) * shapes::extent(silhouette)
    };
    Sprite {
        centre: view.to_image(b.pos.get(slot)),
        facing: Vec2::X,
        half,
        radius: reach,
        bound,
        silhouette,
        shade: BODY,
        halo,
    }
}

impl Sprite {
    /// This outline of the body in `slot` (of kind `info`) with its facing (the ship's: its
    /// aim) and its shade.
    #[inline(always)]
    fn dressed(self, b: &DrawnBodies, info: &KindInfo, shown: &Shown, slot: u32) -> Sprite {
        let heading = if slot == shown.ship {
            shown.ship_aim
        } else {
            b.dir.get(slot)
        };
        Sprite {
            // Image y runs down: the facing direction flips its y.
            facing: Vec2::new(heading.x, -heading.y),
            shade: if is_hurt(b, info, slot) { HURT } else { BODY },
            ..self
        }
    }
}

/// The shade `sprite` gives the pixel at offset `d` from its centre, if it covers it:
/// inside its silhouette, the nose or its body shade; in its halo, [`HALO`].
#[inline(always)]
pub fn shade_at(sprite: &Sprite, d: Vec2) -> Option<u32> {
    let (reach, half) = (sprite.radius, sprite.half);
    let inside = match sprite.silhouette {
        RECT => d.x.abs() <= half.x && d.y.abs() <= half.y,
        DISC => d.length_squared() <= reach * reach,
        s => shapes::inside(s, shapes::local(d, sprite.facing), reach),
    };
    if inside {
        let nose = d.dot(sprite.facing) > NOSE_FROM * reach;
        return Some(if nose { NOSE } else { sprite.shade });
    }
    if sprite.halo {
        let (from, to) = (HALO_FROM * reach, HALO_TO * reach);
        let d2 = d.length_squared();
        if d2 >= from * from && d2 <= to * to {
            return Some(HALO);
        }
    }
    None
}

kernel_args! {
    /// Arguments of [`splat_bodies`] and [`splat_large`].
    pub struct SplatArgs {
        /// The bodies (read only).
        pub bodies: DrawnBodies,
        /// Kind table (shapes and sizes).
        pub kinds: DevSlice<KindInfo, Read>,
        /// Each kind's look.
        pub looks: DevSlice<Look>,
        /// What the image shows (one element, from the camera).
        pub shown: DevSlice<Shown>,
        /// One key per pixel, row-major; [`EMPTY`] before the first body draws there.
        pub keys: DevSlice<u32>,
        /// The slots of the bodies too large for one thread, for [`splat_large`]; room for
        /// every slot.
        pub large: DevSlice<u32>,
        /// How many of [`SplatArgs::large`] are filled (one element, 0 before the launch).
        pub large_count: DevSlice<u32>,
    }
}

kernel_args! {
    /// Arguments of [`splat_bodies`]: [`splat_large`]'s, and the camera's and the radar's,
    /// whose work it does first.
    pub struct FirstSplatArgs {
        /// What [`splat_large`] takes too ([`SplatArgs::shown`] written here, by thread 0).
        pub splat: SplatArgs,
        /// The last step's input (the ship's aim), one element; empty in a world without a
        /// game.
        pub input: DevSlice<Input, Read>,
        /// The camera: element 0 between frames (read), element 1 after this frame
        /// (written by thread 0; [`resolve_pixels`] moves it to element 0, once no thread
        /// of this frame reads it).
        pub camera: DevSlice<CameraState>,
        /// The radar's counts (see [`radar::count`]).
        pub radar: RadarCounts,
        /// The host's request.
        pub lens: Lens,
        /// The radar counts every `stride`-th slot (see [`radar::stride`]).
        pub stride: u32,
        /// Nonzero: the camera ran as a launch of its own before this one
        /// ([`camera::camera`], for a world of more than [`FOLD_CAMERA_SLOTS`] slots), and
        /// [`SplatArgs::shown`] holds this frame's view.
        pub camera_ready: u32,
    }
}

/// The most slots a world may have for its frames' first launch to work the camera out in
/// every thread rather than after a launch of its own: some 500 instructions a warp, a
/// microsecond or two at 131,072 threads on an H200, where the launch costs more; at 16
/// million slots they cost twice a followed frame's time.
pub const FOLD_CAMERA_SLOTS: u32 = 1 << 17;

/// A sprite whose box covers more pixels of the image than this is drawn by
/// [`splat_large`], [`LARGE_LANES`] threads a body, instead of by its own thread. Pixels,
/// not rows: a large body cut by the image's top or bottom edge spans few rows but may
/// still be a hundred pixels wide, and one thread walking those took a followed frame's
/// `splat_bodies` from a few microseconds to 60.
pub const LARGE_PIXELS: u32 = 64;
/// Threads that draw one large body together (four warps), each every `LARGE_LANES`-th
/// pixel of its box: the ship's halo close up is some 2,600 pixels, and a thread's loop is
/// bound by latency.
pub const LARGE_LANES: u32 = 128;

/// A live body ready to draw: its sprite, the half extents of the pixels it may cover, its
/// kind and its layer.
struct Drawn {
    sprite: Sprite,
    reach: Vec2,
    kind: u32,
    layer: u32,
}

/// How the body in `slot` is drawn in this frame, or `None` if no body lives there or it is
/// off the image by more than its size (checked before its heading and energy are read).
#[inline(always)]
fn drawn(args: &SplatArgs, shown: &Shown, slot: u32) -> Option<Drawn> {
    let b = &args.bodies;
    if slot >= b.slots() || !b.is_alive(slot) {
        return None;
    }
    let kind = b.kind.get(slot);
    let look = args.looks.get(kind);
    let info = args.kinds.get(kind);
    let sprite = outline(b, &info, &look, shown, slot);
    if !near_image(&shown.view, sprite.centre, sprite.bound) {
        return None;
    }
    let sprite = sprite.dressed(b, &info, shown, slot);
    let reach = if sprite.silhouette == RECT {
        sprite.half
    } else {
        Vec2::splat(sprite.bound)
    };
    Some(Drawn {
        sprite,
        reach,
        kind,
        layer: look.layer,
    })
}

/// Draws every `step`-th pixel of `body`'s box (row-major) from its `first` (0-based) into
/// the keys.
#[inline(always)]
fn plot(args: &SplatArgs, view: &Framing, body: &Drawn, first: u32, step: u32) {
    let sprite = &body.sprite;
    cover_part(
        view,
        sprite.centre,
        body.reach,
        first,
        step,
        |pixel, d, under| {
            let shade = match shade_at(sprite, d) {
                Some(shade) => shade,
                None if under => sprite.shade,
                None => return,
            };
            let layer = if shade == HALO {
                HALO_LAYER
            } else {
                body.layer
            };
            args.keys.atomic_max(pixel, key(layer, body.kind, shade));
        },
    );
}

/// Thread `i` draws slot `i`'s body, if one lives there: every pixel whose centre lies in its
/// silhouette (and at least the pixel under its centre), the facing side in its nose colour.
///
/// Every thread first works out the frame's camera for itself ([`camera::frame`]: the same
/// bits in each; in a world of up to [`FOLD_CAMERA_SLOTS`] slots), thread 0 writing it and
/// the frame's [`Shown`] for the launches after, and counts its slot on the radar when the
/// radar samples it: the frame needs no launch of its own for either.
///
/// A GPU thread's loop is bound by latency, so the frame takes as long as its longest
/// thread: a body covering more than [`LARGE_PIXELS`] pixels (close up, or the ship's
/// halo) is not drawn here but listed for [`splat_large`]. The list's order depends on which
/// thread arrives first; the picture does not, since every pixel keeps the maximum of its
/// keys.
#[inline(always)]
pub fn splat_bodies(t: Thread, args: &FirstSplatArgs) {
    let splat = &args.splat;
    let slot = t.global();
    let shown = if args.camera_ready != 0 {
        splat.shown.get(0)
    } else {
        let (next, shown) =
            camera::frame(&splat.bodies, &args.input, &args.lens, args.camera.get(0));
        if slot == 0 {
            args.camera.set(1, next);
            splat.shown.set(0, shown);
        }
        shown
    };
    if slot.is_multiple_of(args.stride) {
        radar::count(&splat.bodies, &splat.looks, &shown, &args.radar, slot);
    }
    let Some(body) = drawn(splat, &shown, slot) else {
        return;
    };
    let covered = Span::of(&shown.view, body.sprite.centre, body.reach).map_or(0, |s| s.pixels());
    if covered > LARGE_PIXELS {
        let at = splat.large_count.atomic_add(0, 1);
        splat.large.set(at, slot);
        return;
    }
    plot(splat, &shown.view, &body, 0, 1);
}

/// The bodies [`splat_bodies`] listed as large, each drawn by [`LARGE_LANES`] threads,
/// thread `l` of them drawing the pixels `l`, `l + LARGE_LANES`, … of its box; the groups
/// of threads take the list's bodies in turn, however many the launch has.
#[inline(always)]
pub fn splat_large(t: Thread, args: &SplatArgs) {
    let shown = args.shown.get(0);
    let (group, lane) = (t.global() / LARGE_LANES, t.global() % LARGE_LANES);
    let groups = (t.grid_dim * t.block_dim) / LARGE_LANES;
    let listed = args.large_count.get(0).min(args.large.len());
    let mut at = group;
    while at < listed {
        if let Some(body) = drawn(args, &shown, args.large.get(at)) {
            plot(args, &shown.view, &body, lane, LARGE_LANES);
        }
        at += groups;
    }
}

/// Whether something centred at image position `centre` and `bound` pixels across (each
/// way) may cover a pixel of `view`'s image.
#[inline(always)]
fn near_image(view: &Framing, centre: Vec2, bound: f32) -> bool {
    let (w, h) = (view.width as f32, view.height as f32);
    centre.x > -bound - 1.0
        && centre.x < w + bound + 1.0
        && centre.y > -bound - 1.0
        && centre.y < h + bound + 1.0
}

/// Calls `f(pixel, d, under)` for every pixel of `view`'s image within `reach` (half
/// extents, in pixels) of image position `centre`: its row-major index, the offset of its
/// centre from `centre`, and whether it is the pixel under `centre` (which a drawing
/// covers however small it is). Nothing for a `centre` far off the image.
#[inline(always)]
fn cover(view: &Framing, centre: Vec2, reach: Vec2, f: impl FnMut(u32, Vec2, bool)) {
    cover_part(view, centre, reach, 0, 1, f);
}

/// The pixels of an image within some reach of a centre (see [`cover`]): columns `x0..=x1`
/// of rows `y0..=y1`, never empty.
#[derive(Clone, Copy)]
struct Span {
    x0: u32,
    x1: u32,
    y0: u32,
    y1: u32,
}

impl Span {
    /// The pixels of `view`'s image within `reach` (half extents) of `centre`; `None` when
    /// there are none.
    #[inline(always)]
    fn of(view: &Framing, centre: Vec2, reach: Vec2) -> Option<Span> {
        if !near_image(view, centre, reach.max_element()) {
            return None;
        }
        let x0 = (centre.x - reach.x).max(0.0) as u32;
        let x1 = ((centre.x + reach.x) as u32).min(view.width - 1);
        let y0 = (centre.y - reach.y).max(0.0) as u32;
        let y1 = ((centre.y + reach.y) as u32).min(view.height - 1);
        (x0 <= x1 && y0 <= y1).then_some(Span { x0, x1, y0, y1 })
    }

    /// How many pixels it holds.
    #[inline(always)]
    fn pixels(&self) -> u32 {
        (self.x1 - self.x0 + 1) * (self.y1 - self.y0 + 1)
    }
}

/// [`cover`] for every `step`-th of its pixels (row-major) from its `first` (0-based) only.
#[inline(always)]
fn cover_part(
    view: &Framing,
    centre: Vec2,
    reach: Vec2,
    first: u32,
    step: u32,
    mut f: impl FnMut(u32, Vec2, bool),
) {
    let Some(Span { x0, x1, y0, y1 }) = Span::of(view, centre, reach) else {
        return;
    };
    let (w, h) = (view.width as f32, view.height as f32);
    let on_image = centre.x >= 0.0 && centre.x < w && centre.y >= 0.0 && centre.y < h;
    let under = on_image.then_some((centre.x as u32, centre.y as u32));
    let width = x1 - x0 + 1;
    let (mut x, mut y) = (x0 + first % width, y0 + first / width);
    let (rows, across) = (step / width, step % width);
    while y <= y1 {
        let d = Vec2::new(x as f32 + 0.5, y as f32 + 0.5) - centre;
        f(y * view.width + x, d, under == Some((x, y)));
        // The next pixel `step` on in the box, row-major.
        x += across;
        y += rows;
        if x > x1 {
            x -= width;
            y += 1;
        }
    }
}

kernel_args! {
    /// Arguments of [`resolve_pixels`].
    pub struct ResolveArgs {
        /// Each kind's look.
        pub looks: DevSlice<Look>,
        /// The keys of [`splat_bodies`]; cleared to [`EMPTY`] on the way.
        pub keys: DevSlice<u32>,
        /// Output: one RGBA8 colour per pixel, row-major.
        pub image: DevSlice<u32>,
        /// What the image shows (one element, from the camera).
        pub shown: DevSlice<Shown>,
        /// The radar's counts (cleared on the way).
        pub radar: RadarCounts,
        /// The camera: element 1, this frame's, becomes element 0 (see
        /// [`FirstSplatArgs::camera`]).
        pub camera: DevSlice<CameraState>,
        /// How many bodies [`splat_bodies`] listed as large: cleared for the next frame.
        pub large_count: DevSlice<u32>,
        /// The stride the radar was sampled with.
        pub stride: u32,
        /// Keeps the struct free of implicit padding (checked by its `NoUninit` derive).
        pub reserved: u32,
    }
}

/// Pixels one thread of [`resolve_pixels`] colours: a warp takes `32 ×` this many pixels
/// in a row-major run, each lane every 32nd of them (so that each load of the warp's is one
/// span of memory), and reads the frame's [`Shown`] once for them all.
pub const RESOLVED_A_THREAD: u32 = 4;

/// Threads [`resolve_pixels`] needs for a frame of `pixels`: whole warps, each for a run
/// of `32 ×` [`RESOLVED_A_THREAD`] pixels.
#[inline]
pub fn resolve_threads(pixels: u32) -> u32 {
    pixels.div_ceil(WARP * RESOLVED_A_THREAD) * WARP
}

/// Each thread colours its pixels (see [`RESOLVED_A_THREAD`]) from their keys, or from the
/// radar where it lies, and clears the keys; thread 0 readies the camera and the list of
/// large bodies for the next frame.
#[inline(always)]
pub fn resolve_pixels(t: Thread, args: &ResolveArgs) {
    if t.global() == 0 {
        args.camera.set(0, args.camera.get(1));
        args.large_count.set(0, 0);
    }
    let pixels = args.image.len();
    let (warp, lane) = (t.global() / WARP, t.global() % WARP);
    let first = warp as u64 * u64::from(WARP * RESOLVED_A_THREAD) + u64::from(lane);
    if first >= u64::from(pixels) {
        return;
    }
    let shown = args.shown.get(0);
    let (width, background) = (shown.view.width, shown.view.background);
    let mut pixel = first as u32;
    let (mut x, mut y) = (pixel % width, pixel / width);
    // The backdrop's mark of the row last met: a run spans a row or two.
    let mut row = (u32::MAX, backdrop::Row::OUT);
    for _ in 0..RESOLVED_A_THREAD {
        let key = args.keys.get(pixel);
        let radar = shown
            .radar
            .contains(x, y)
            .then(|| radar::radar_colour(&shown, &args.radar, &args.looks, args.stride, x, y));
        let colour = match radar {
            Some(colour) => colour,
            None if key == EMPTY && shown.backdrop != 0 => {
                if row.0 != y {
                    row = (y, backdrop::row(&shown.view, shown.field, y));
                }
                backdrop::on_row(&shown.view, shown.field, row.1, x).unwrap_or(background)
            }
            None if key == EMPTY => background,
            None => {
                let (kind, shade) = unkey(key);
                args.looks.get(kind).colour_of(shade, background)
            }
        };
        args.image.set(pixel, colour);
        // Most pixels of a frame are empty: their keys stay as they are, not written again.
        if key != EMPTY {
            args.keys.set(pixel, EMPTY);
        }
        if pixels - pixel <= WARP {
            return;
        }
        pixel += WARP;
        x += WARP;
        while x >= width {
            x -= width;
            y += 1;
        }
    }
}

/// [`BodyVertex::flags`]: a body lives in this slot (the others are not drawn).
pub const VERTEX_ALIVE: u32 = 1;
/// [`BodyVertex::flags`]: the body is hurt (see [`is_hurt`]).
pub const VERTEX_HURT: u32 = 2;
/// [`BodyVertex::flags`]: a halo rings the body.
pub const VERTEX_HALO: u32 = 4;
/// [`BodyVertex::flags`]: an explosion's particle, a disc under every body, faded by its
/// level (from bit [`VERTEX_LEVEL_SHIFT`] up).
pub const VERTEX_PARTICLE: u32 = 16;
/// [`BodyVertex::flags`]: the backdrop's vertex ([`backdrop_vertex`]), when it is drawn;
/// never with [`VERTEX_ALIVE`].
pub const VERTEX_BACKDROP: u32 = 32;
/// [`BodyVertex::flags`]: the silhouette drawn, from this bit up.
pub const VERTEX_SILHOUETTE_SHIFT: u32 = 8;
/// [`BodyVertex::flags`]: a particle's fade level, from this bit up.
pub const VERTEX_LEVEL_SHIFT: u32 = 16;

/// One slot as the GL renderer draws it: "the positions and type are put in a VBO" (paper,
/// section 5), here already in image coordinates of the frame's view (the same f32
/// arithmetic as [`splat_bodies`]). The layout of the vertex buffer, for the kernel that
/// writes it and the shaders that read it.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct BodyVertex {
    /// Image position of the centre (pixels, y down).
    pub centre: Vec2,
    /// Unit direction the body faces, in image coordinates.
    pub facing: Vec2,
    /// Half extents in pixels (see [`Sprite::half`]).
    pub half: Vec2,
    /// Radius in pixels (see [`Sprite::radius`]).
    pub radius: f32,
    /// Half side of the square its pixels lie in.
    pub bound: f32,
    /// Kind index.
    pub kind: u32,
    /// [`VERTEX_ALIVE`], [`VERTEX_HURT`], [`VERTEX_HALO`] and the silhouette; or
    /// [`VERTEX_PARTICLE`] and the fade level; or [`VERTEX_BACKDROP`].
    pub flags: u32,
}

kernel_args! {
    /// Arguments of [`write_vertices`].
    pub struct VertexArgs {
        /// The bodies (read only).
        pub bodies: DrawnBodies,
        /// Kind table (sizes and energies at birth).
        pub kinds: DevSlice<KindInfo, Read>,
        /// Each kind's look (silhouettes).
        pub looks: DevSlice<Look>,
        /// What the image shows (one element, from the camera).
        pub shown: DevSlice<Shown>,
        /// Output: one vertex per slot, then the backdrop's (the GL vertex buffer, mapped, on
        /// the GPU).
        pub vertices: DevSlice<BodyVertex>,
    }
}

/// The vertex the GL renderer draws the backdrop from (see [`backdrop::on_grid`]):
/// `centre` is the view's origin, `facing` the field's size, `radius` the view's scale;
/// flags [`VERTEX_BACKDROP`] when `shown` has a backdrop, else 0.
#[inline(always)]
pub fn backdrop_vertex(shown: &Shown) -> BodyVertex {
    let view = &shown.view;
    BodyVertex {
        centre: view.origin,
        facing: shown.field,
        half: Vec2::splat(view.scale),
        radius: view.scale,
        bound: 0.0,
        kind: 0,
        flags: if shown.backdrop != 0 {
            VERTEX_BACKDROP
        } else {
            0
        },
    }
}

/// Thread `i` writes slot `i`'s vertex (flags 0 for a free slot); thread `slots` writes
/// the [`backdrop_vertex`] after them.
#[inline(always)]
pub fn write_vertices(t: Thread, args: &VertexArgs) {
    let b = &args.bodies;
    let slot = t.global();
    if slot > b.slots() || slot >= args.vertices.len() {
        return;
    }
    if slot == b.slots() {
        args.vertices.set(slot, backdrop_vertex(&args.shown.get(0)));
        return;
    }
    let vertex = if b.is_alive(slot) {
        let shown = args.shown.get(0);
        let kind = b.kind.get(slot);
        let s = sprite(b, &args.kinds, &args.looks.get(kind), &shown, slot);
        let hurt = if s.shade == HURT { VERTEX_HURT } else { 0 };
        let halo = if s.halo { VERTEX_HALO } else { 0 };
        BodyVertex {
            centre: s.centre,
            facing: s.facing,
            half: s.half,
            radius: s.radius,
            bound: s.bound,
            kind,
            flags: VERTEX_ALIVE | hurt | halo | (s.silhouette << VERTEX_SILHOUETTE_SHIFT),
        }
    } else {
        BodyVertex::default()
    };
    args.vertices.set(slot, vertex);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn particles_fade_towards_the_background_in_sixteenths() {
        let (colour, background) = (0xff_20_80_f0, 0xff_00_00_10);
        for level in 0..PARTICLE_LEVELS {
            let key = particle_key(None, 5, level);
            assert_eq!(key >> 24, PARTICLE_LAYER, "under every body");
            let (kind, shade) = unkey(key);
            assert_eq!((kind, shade), (5, PARTICLE + level));
            let look = Look {
                colour,
                nose: 0,
                layer: 100,
                hurt: 0,
                silhouette: 0,
                radar: 0,
            };
            // Each channel: c + (b − c)·level/16, truncated towards c.
            let expected = u32::from_le_bytes([
                (0xf0 - (0xf0 - 0x10) * level / 16) as u8,
                (0x80 - 0x80 * level / 16) as u8,
                (0x20 - 0x20 * level / 16) as u8,
                0xff,
            ]);
            assert_eq!(look.colour_of(shade, background), expected, "level {level}");
        }
        assert_eq!(fade(colour, background, 0), colour);
        assert_eq!(particle_key(None, 5, 99), particle_key(None, 5, 15));
        assert!(particle_key(Some(3), 0, 0) > key(2, 0xffff, HALO));
        assert!(particle_key(None, 0xffff, 0) < key(HALO_LAYER, 0, HALO));
    }
}
