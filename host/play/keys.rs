//! The keyboard, as in the paper: one set of keys moves the ship (WASD), another aims its
//! shots (the arrow keys, eight directions, firing while held); what the other keys and the
//! gamepad's buttons do; the help's lines.

use glam::Vec2;
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

    /// The movement WASD ask for, no longer than 1 (diagonals as fast as straight lines);
    /// opposite keys cancel.
    pub fn movement(&self) -> Vec2 {
        Vec2::new(axis(self.right, self.left), axis(self.up, self.down)).normalize_or_zero()
    }

    /// The direction the arrows held point to (one of eight), or `None` with none held or
    /// opposite ones cancelling.
    pub fn aim(&self) -> Option<Vec2> {
        let aim = Vec2::new(
            axis(self.aim_right, self.aim_left),
            axis(self.aim_up, self.aim_down),
        );
        (aim != Vec2::ZERO).then_some(aim)
    }
}

/// 1 for `plus` alone, -1 for `minus` alone, else 0.
fn axis(plus: bool, minus: bool) -> f32 {
    f32::from(i8::from(plus) - i8::from(minus))
}

/// What the other keys (and the gamepad's buttons) do.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Action {
    /// P or Space (Start on a gamepad): pause or go on.
    Pause,
    /// M: sound off or on.
    Mute,
    /// F1: the help overlay.
    Help,
    /// R (A on a gamepad): a new game, once this one is over.
    Restart,
    /// F11: fullscreen or windowed.
    Fullscreen,
    /// Esc: the end.
    Quit,
    /// `.` or N: one step, while a replay is paused.
    Step,
    /// 1, 2, 3, 4: a replay at this many times its speed (1, 2, 4, 8).
    Speed(u32),
    /// `+` (or `=`): the camera closer.
    ZoomIn,
    /// `−`: the camera farther, down to the whole field.
    ZoomOut,
    /// Tab: the whole field, or back to following the ship.
    Overview,
}

/// How much one press of `+`/`−`, or one notch of the mouse wheel, zooms.
pub const ZOOM_STEP: f32 = 1.25;

impl Action {
    /// The action of `key`, if it has one.
    pub fn of(key: KeyCode) -> Option<Action> {
        Some(match key {
            KeyCode::KeyP | KeyCode::Space => Action::Pause,
            KeyCode::KeyM => Action::Mute,
            KeyCode::F1 => Action::Help,
            KeyCode::KeyR => Action::Restart,
            KeyCode::F11 => Action::Fullscreen,
            KeyCode::Escape => Action::Quit,
            KeyCode::Period | KeyCode::KeyN => Action::Step,
            KeyCode::Digit1 => Action::Speed(1),
            KeyCode::Digit2 => Action::Speed(2),
            KeyCode::Digit3 => Action::Speed(4),
            KeyCode::Digit4 => Action::Speed(8),
            KeyCode::Equal | KeyCode::NumpadAdd => Action::ZoomIn,
            KeyCode::Minus | KeyCode::NumpadSubtract => Action::ZoomOut,
            KeyCode::Tab => Action::Overview,
            _ => return None,
        })
    }
}

/// The help overlay's lines in a game.
pub const HELP: [&str; 13] = [
    "W A S D      move the ship (or the left stick, the D-pad)",
    "arrow keys   aim and fire (8 directions)",
    "mouse        aim at the cursor, left button fires",
    "right stick  aim and fire",
    "P, Space     pause (Start on a gamepad)",
    "M            sound on/off",
    "F1           this help (the game waits)",
    "R            new game after game over (A on a gamepad)",
    "+ - wheel    zoom in and out (down to the whole field)",
    "Tab          the whole field, or back to the ship",
    "F11          fullscreen",
    "Esc          quit",
    "leaving the window pauses the game",
];

/// The help overlay's lines while a replay plays.
pub const REPLAY_HELP: [&str; 9] = [
    "P, Space     pause",
    ". or N       one step, while paused",
    "1 2 3 4      speed x1 x2 x4 x8",
    "+ - wheel    zoom in and out",
    "Tab          the whole field, or back to the ship",
    "M            sound on/off",
    "F1           this help",
    "F11          fullscreen",
    "Esc          quit",
];
