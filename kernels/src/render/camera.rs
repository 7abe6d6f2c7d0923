//! The camera: which part of the field a frame shows, decided on the device from where
//! the ship is ([`frame`]), so that the host never waits for the GPU to know it: by a
//! one-thread kernel ([`camera`]), or, in the kernel renderer's frames of worlds up to
//! `FOLD_CAMERA_SLOTS` slots (see [`super`]), by every thread of its first launch for
//! itself.
//!
//! The maths is in plain functions ([`target`], [`approach`], [`clamp_centre`],
//! [`advance`]) that the host calls too: its view of a frame (to map a cursor to the
//! field, or to check the device) is then the device's, bit for bit.

use glam::Vec2;

use super::DrawnBodies;
use super::radar::{self, RadarBox};
use super::{Framing, NO_SHIP, Shown};
use crate::access::Read;
use crate::game::control::Input;
use crate::{DevSlice, Thread, kernel_args};

/// [`Lens::mode`]: the view follows the ship (the field when there is none).
pub const FOLLOW: u32 = 0;
/// [`Lens::mode`]: the whole field, centred.
pub const FIELD: u32 = 1;

/// Image height at which zoom 1 shows one field unit per pixel.
pub const REFERENCE_HEIGHT: f32 = 1080.0;
/// Largest zoom: pixels per unit at most this many times those of zoom 1.
pub const MAX_ZOOM: f32 = 8.0;
/// Time constant of the camera's smoothing, in seconds: after it the view has covered
/// 63% of the way to its target.
pub const TIME_CONSTANT: f32 = 0.12;

/// What the host asks of a frame: its size, what it shows and how fast the view moves.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct Lens {
    /// Size of the field (the world), in units.
    pub field: Vec2,
    /// Pixels per unit in [`FOLLOW`] mode, as a multiple of `height / 1080`.
    pub zoom: f32,
    /// Seconds since the previous frame; 0 snaps the view to its target.
    pub dt: f32,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Background colour, RGBA8.
    pub background: u32,
    /// [`FOLLOW`] or [`FIELD`].
    pub mode: u32,
    /// Nonzero: the radar is drawn in a corner.
    pub radar: u32,
    /// The ship's slot, or [`NO_SHIP`].
    pub ship: u32,
}

/// Where the camera is between frames (one element of device memory per pipeline).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct CameraState {
    /// The field position at the image's centre.
    pub centre: Vec2,
    /// Pixels per unit.
    pub scale: f32,
    /// Nonzero once a frame has set the state (the first frame snaps).
    pub primed: u32,
}

/// Pixels per unit at which the whole field fits a `width × height` image.
#[inline]
pub fn fit_scale(field: Vec2, width: u32, height: u32) -> f32 {
    (width as f32 / field.x).min(height as f32 / field.y)
}

/// The view the camera heads for: its centre (not yet kept inside the field) and scale.
/// [`FOLLOW`] centres the ship at `zoom × height / 1080` pixels per unit, kept between the
/// scale at which the field fits and [`MAX_ZOOM`] times zoom 1's; without a ship, and in
/// [`FIELD`] mode, the whole field.
#[inline]
pub fn target(lens: &Lens, ship: Option<Vec2>) -> CameraState {
    let fit = fit_scale(lens.field, lens.width, lens.height);
    let (centre, scale) = match ship {
        Some(ship) if lens.mode == FOLLOW => {
            let unit = lens.height as f32 / REFERENCE_HEIGHT;
            (ship, (unit * lens.zoom).min(unit * MAX_ZOOM).max(fit))
        }
        _ => (lens.field * 0.5, fit),
    };
    CameraState {
        centre,
        scale,
        primed: 1,
    }
}

/// One frame's step of an exponential approach from `current` to `target` with the time
/// constant [`TIME_CONSTANT`], after `dt` seconds; `dt` 0 (or less) snaps to the target.
#[inline]
pub fn approach(current: f32, target: f32, dt: f32) -> f32 {
    if dt <= 0.0 {
        return target;
    }
    let share = 1.0 - libm::expf(-dt / TIME_CONSTANT);
    current + (target - current) * share
}

/// `centre` moved so that a view `shown` units large stays inside `field`; along an axis
/// where the view is larger than the field, the field is centred.
#[inline]
pub fn clamp_centre(centre: Vec2, shown: Vec2, field: Vec2) -> Vec2 {
    let axis = |c: f32, shown: f32, field: f32| {
        let half = shown * 0.5;
        if shown >= field {
            field * 0.5
        } else {
            c.max(half).min(field - half)
        }
    };
    Vec2::new(
        axis(centre.x, shown.x, field.x),
        axis(centre.y, shown.y, field.y),
    )
}

/// The view of a `width × height` image centred on `centre` at `scale` pixels per unit.
#[inline]
pub fn view_at(centre: Vec2, scale: f32, width: u32, height: u32, background: u32) -> Framing {
    let shown = Vec2::new(width as f32, height as f32) / scale;
    Framing {
        origin: centre - shown * 0.5,
        scale,
        width,
        height,
        background,
    }
}

/// The camera after one frame: `state` moved towards the [`target`] of `lens` (snapped on
/// the first frame and when `lens.dt` is 0), and the frame's view, kept inside the field.
#[inline]
pub fn advance(lens: &Lens, ship: Option<Vec2>, state: CameraState) -> (CameraState, Framing) {
    let goal = target(lens, ship);
    let next = if state.primed == 0 {
        goal
    } else {
        CameraState {
            centre: Vec2::new(
                approach(state.centre.x, goal.centre.x, lens.dt),
                approach(state.centre.y, goal.centre.y, lens.dt),
            ),
            scale: approach(state.scale, goal.scale, lens.dt),
            primed: 1,
        }
    };
    let size = Vec2::new(lens.width as f32, lens.height as f32);
    let centre = clamp_centre(next.centre, size / next.scale, lens.field);
    let view = view_at(centre, next.scale, lens.width, lens.height, lens.background);
    (next, view)
}

kernel_args! {
    /// Arguments of [`camera`].
    pub struct CameraArgs {
        /// The bodies (read only: the ship's position).
        pub bodies: DrawnBodies,
        /// The last step's input (the ship's aim), one element; empty in a world without a
        /// game.
        pub input: DevSlice<Input, Read>,
        /// The camera before the frame (element 0, read and advanced) and after it (element
        /// 1, written too).
        pub state: DevSlice<CameraState>,
        /// Output: what this frame shows (one element), for the drawing kernels.
        pub shown: DevSlice<Shown>,
        /// The host's request.
        pub lens: Lens,
    }
}

/// Thread 0 advances the camera towards the ship (see [`advance`]) and writes the frame's
/// [`Shown`]. The state's element 0 is the camera before the frame, element 1 after it
/// (see `FirstSplatArgs::camera` in [`super`]): alone in its launch, it writes both.
#[inline(always)]
pub fn camera(t: Thread, args: &CameraArgs) {
    if t.global() != 0 {
        return;
    }
    let (state, shown) = frame(&args.bodies, &args.input, &args.lens, args.state.get(0));
    args.state.set(0, state);
    args.state.set(1, state);
    args.shown.set(0, shown);
}

/// The camera after one frame of `lens`, advanced from `state` towards the ship in `bodies`
/// (see [`advance`]), and what the frame shows, the ship aimed as the last step's `input`
/// says (one element; empty without a game). The [`camera`] kernel's one thread works it
/// out; each thread of `splat_bodies` works it out for itself, to the same bits, so that a
/// frame drawn by the kernel renderer needs no launch of its own for it.
#[inline(always)]
pub fn frame(
    bodies: &DrawnBodies,
    input: &DevSlice<Input, Read>,
    lens: &Lens,
    state: CameraState,
) -> (CameraState, Shown) {
    let ship = (lens.ship < bodies.slots() && bodies.is_alive(lens.ship))
        .then(|| (bodies.pos.get(lens.ship), bodies.kind.get(lens.ship)));
    let (state, view) = advance(lens, ship.map(|(pos, _)| pos), state);
    (state, shown(lens, view, ship, aim(input)))
}

/// The ship's aim from the last step's input (`+x` without a game).
#[inline(always)]
fn aim(input: &DevSlice<Input, Read>) -> Vec2 {
    if input.is_empty() {
        Vec2::X
    } else {
        input.get(0).aim_dir()
    }
}

/// What a frame of `lens` seen through `view` shows, the ship (position, kind) at `ship`
/// aiming along `aim`: what [`camera`] writes, for the host too.
#[inline]
pub fn shown(lens: &Lens, view: Framing, ship: Option<(Vec2, u32)>, aim: Vec2) -> Shown {
    Shown {
        view,
        radar: if lens.radar != 0 {
            radar::radar_box(lens.width, lens.height, lens.field)
        } else {
            RadarBox::NONE
        },
        field: lens.field,
        ship_pos: ship.map_or(Vec2::ZERO, |(pos, _)| pos),
        ship_aim: aim,
        ship: if ship.is_some() { lens.ship } else { NO_SHIP },
        ship_kind: ship.map_or(0, |(_, kind)| kind),
        backdrop: u32::from(lens.mode == FOLLOW && ship.is_some()),
        reserved: 0,
    }
}
