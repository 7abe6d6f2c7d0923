//! The keyboard, as in the paper: one set of keys moves the ship (WASD), another aims its
//! shots (the arrow keys, eight directions, firing while held).

use glam::Vec2;
use gpuwars_kernels::game::control::Input;
use winit::keyboard::KeyCode;

/// The movement and aiming keys held down.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Held {
    up: bool,
    down: bool,
    left: bool,
    right: bool,
    aim_up: bool,
    aim_down: bool,
    aim_left: bool,
    aim_right: bool,
}

impl Held {
    /// Notes that `key` went down (`pressed`) or up; returns whether it is a movement or an
    /// aiming key.
    pub fn set(&mut self, key: KeyCode, pressed: bool) -> bool {
        let held = match key {
            KeyCode::KeyW => &mut self.up,
            KeyCode::KeyS => &mut self.down,
            KeyCode::KeyA => &mut self.left,
            KeyCode::KeyD => &mut self.right,
            KeyCode::ArrowUp => &mut self.aim_up,
            KeyCode::ArrowDown => &mut self.aim_down,
            KeyCode::ArrowLeft => &mut self.aim_left,
            KeyCode::ArrowRight => &mut self.aim_right,
            _ => return false,
        };
        *held = pressed;
        true
    }

    /// Lets go of every key (the window lost the focus: its key-up events go elsewhere).
    pub fn release_all(&mut self) {
        *self = Held::default();
    }

    /// The step's input: WASD move (diagonals as fast as straight lines), the arrows aim in
    /// one of eight directions and fire while any is held. Opposite keys cancel; with no
    /// arrow held the ship keeps its last aim (`last_aim`) and does not fire.
    pub fn input(&self, last_aim: u32) -> Input {
        let axis = |plus: bool, minus: bool| f32::from(i8::from(plus) - i8::from(minus));
        let movement = Vec2::new(axis(self.right, self.left), axis(self.up, self.down));
        let (move_x, move_y) = Input::move_towards(movement.normalize_or_zero());
        let aim = Vec2::new(
            axis(self.aim_right, self.aim_left),
            axis(self.aim_up, self.aim_down),
        );
        let firing = aim != Vec2::ZERO;
        Input {
            move_x,
            move_y,
            aim: if firing {
                Input::aim_towards(aim)
            } else {
                last_aim
            },
            fire: u32::from(firing),
        }
    }
}

/// What the other keys do.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Action {
    /// P: pause or go on.
    Pause,
    /// M: sound off or on.
    Mute,
    /// F1: the help overlay.
    Help,
    /// R: a new game, once this one is over.
    Restart,
    /// F11: fullscreen or windowed.
    Fullscreen,
    /// Esc: the end.
    Quit,
}

impl Action {
    /// The action of `key`, if it has one.
    pub fn of(key: KeyCode) -> Option<Action> {
        Some(match key {
            KeyCode::KeyP => Action::Pause,
            KeyCode::KeyM => Action::Mute,
            KeyCode::F1 => Action::Help,
            KeyCode::KeyR => Action::Restart,
            KeyCode::F11 => Action::Fullscreen,
            KeyCode::Escape => Action::Quit,
            _ => return None,
        })
    }
}

/// The help overlay's lines.
pub const HELP: [&str; 8] = [
    "W A S D      move the ship",
    "arrow keys   aim and fire (8 directions)",
    "P            pause",
    "M            sound on/off",
    "F1           this help",
    "R            new game (after game over)",
    "F11          fullscreen",
    "Esc          quit",
];
