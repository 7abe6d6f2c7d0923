//! Every device's commands merged into one [`Input`] a step, so that a replay records (and
//! plays back) the keyboard, the mouse and the gamepad alike.
//!
//! Movement adds the keys, the left stick and the D-pad, clamped to full speed. Aiming and
//! firing follow the device used last to aim: the arrow keys, the mouse (it aims at the
//! cursor and fires while the left button is held) or the right stick (it aims and fires
//! beyond its dead zone). Pure: the window and the gamepad poller feed it plain values.

use glam::Vec2;
use gpuwars_kernels::game::control::Input;
use winit::keyboard::KeyCode;

use super::keys::Held;

/// Sticks deflected less than this (of full deflection) count as centred: worn sticks rest
/// a little off centre.
pub const DEAD_ZONE: f32 = 0.25;

/// The device that aims and fires.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Aimer {
    /// The arrow keys.
    #[default]
    Keys,
    /// The mouse.
    Mouse,
    /// The gamepad's right stick.
    Stick,
}

/// A direction of the D-pad.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Pad {
    /// Up.
    Up,
    /// Down.
    Down,
    /// Left.
    Left,
    /// Right.
    Right,
}

/// The state of every device, and which one aims.
#[derive(Clone, Debug, Default)]
pub struct Controls {
    keys: Held,
    /// The cursor in window pixels (x right, y down), once it has been over the window.
    cursor: Option<Vec2>,
    /// The left mouse button is down.
    clicking: bool,
    left_stick: Vec2,
    right_stick: Vec2,
    /// D-pad up, down, left, right.
    pad: [bool; 4],
    aimer: Aimer,
    last_aim: u32,
}

impl Controls {
    /// Nothing held, the keys aiming, the ship aiming along `+x`.
    pub fn new() -> Self {
        Controls::default()
    }

    /// Which device aims now.
    pub fn aimer(&self) -> Aimer {
        self.aimer
    }

    /// Notes that `key` went down (`pressed`) or up; returns whether it moves or aims. An
    /// arrow going down gives the aim back to the keys.
    pub fn key(&mut self, key: KeyCode, pressed: bool) -> bool {
        let known = self.keys.set(key, pressed);
        if known && pressed && self.keys.aim().is_some() {
            self.aimer = Aimer::Keys;
        }
        known
    }

    /// The cursor moved to `at` (window pixels, y down): the mouse aims from now on.
    pub fn cursor(&mut self, at: Vec2) {
        self.cursor = Some(at);
        self.aimer = Aimer::Mouse;
    }

    /// The left mouse button went down or up; pressing it gives the aim to the mouse.
    pub fn click(&mut self, down: bool) {
        self.clicking = down;
        if down {
            self.aimer = Aimer::Mouse;
        }
    }

    /// The left stick's deflection, each axis in `[-1, 1]`, y up.
    pub fn left_stick(&mut self, at: Vec2) {
        self.left_stick = at;
    }

    /// The right stick's deflection, each axis in `[-1, 1]`, y up: beyond the dead zone it
    /// takes the aim.
    pub fn right_stick(&mut self, at: Vec2) {
        self.right_stick = at;
        if beyond_dead_zone(at) != Vec2::ZERO {
            self.aimer = Aimer::Stick;
        }
    }

    /// A D-pad direction went down or up.
    pub fn pad(&mut self, direction: Pad, down: bool) {
        self.pad[direction as usize] = down;
    }

    /// Lets go of every key and button, and centres the sticks (the window lost the focus,
    /// or a gamepad went away: their releases will not arrive).
    pub fn release_all(&mut self) {
        *self = Controls {
            cursor: self.cursor,
            aimer: self.aimer,
            last_aim: self.last_aim,
            ..Controls::default()
        };
    }

    /// The next step's input, `ship` being where the ship is in window pixels (the mouse aims
    /// from there). Without an aim (no arrow held, the stick centred) the ship keeps its last
    /// aim and does not fire.
    pub fn input(&mut self, ship: Vec2) -> Input {
        let [up, down, left, right] = self.pad.map(f32::from);
        let pad = Vec2::new(right - left, up - down).normalize_or_zero();
        let movement = self.keys.movement() + beyond_dead_zone(self.left_stick) + pad;
        let (move_x, move_y) = Input::move_towards(movement.clamp_length_max(1.0));
        let aim = match self.aimer {
            Aimer::Keys => self.keys.aim().map(|aim| (aim, true)),
            Aimer::Mouse => self.cursor.map(|cursor| {
                // Window pixels point down, the world's y up.
                let towards = (cursor - ship) * Vec2::new(1.0, -1.0);
                (towards, self.clicking)
            }),
            Aimer::Stick => Some(beyond_dead_zone(self.right_stick))
                .filter(|&aim| aim != Vec2::ZERO)
                .map(|aim| (aim, true)),
        };
        let (aim, fire) = match aim {
            Some((towards, fire)) if towards != Vec2::ZERO => (Input::aim_towards(towards), fire),
            Some((_, fire)) => (self.last_aim, fire),
            None => (self.last_aim, false),
        };
        self.last_aim = aim;
        Input {
            move_x,
            move_y,
            aim,
            fire: u32::from(fire),
        }
    }
}

/// A stick's deflection with the dead zone cut out: zero inside it, then rising from zero at
/// its edge to full at full deflection, in the same direction (no longer than 1).
pub fn beyond_dead_zone(at: Vec2) -> Vec2 {
    let length = at.length();
    if length.is_nan() || length <= DEAD_ZONE {
        return Vec2::ZERO;
    }
    let scaled = ((length - DEAD_ZONE) / (1.0 - DEAD_ZONE)).min(1.0);
    at / length * scaled
}
