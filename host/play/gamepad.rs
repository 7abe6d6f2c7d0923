//! Gamepads, through gilrs: polled once a frame, their sticks and D-pad fed to
//! [`Controls`], their buttons returned as [`Action`]s. Without gamepad support (no udev, an
//! unsupported platform) the game goes on with the keyboard and mouse, as stderr says once.

use gilrs::{Axis, Button, EventType, Gilrs};
use glam::Vec2;

use super::controls::{Controls, Pad};
use super::keys::Action;

/// The gamepads, and the sticks' latest deflections (gilrs reports each axis on its own).
pub struct Gamepads {
    /// `None` where gilrs could not start.
    gilrs: Option<Gilrs>,
    left: Vec2,
    right: Vec2,
}

impl Gamepads {
    /// Starts gilrs; says on stderr, once, when it cannot or when no gamepad is connected
    /// yet (one plugged in later is picked up).
    pub fn open() -> Self {
        let gilrs = match Gilrs::new() {
            Ok(gilrs) => {
                if gilrs.gamepads().next().is_none() {
                    eprintln!(
                        "gpuwars: no gamepad connected: keyboard and mouse only until one is"
                    );
                }
                Some(gilrs)
            }
            Err(e) => {
                eprintln!("gpuwars: gamepads cannot be read ({e}): keyboard and mouse only");
                None
            }
        };
        Gamepads {
            gilrs,
            left: Vec2::ZERO,
            right: Vec2::ZERO,
        }
    }

    /// Takes every event since the last poll: sticks and D-pad into `controls`; returns one
    /// entry per other button pressed, in order: its action, if it has one.
    pub fn poll(&mut self, controls: &mut Controls) -> Vec<Option<Action>> {
        let mut pressed = Vec::new();
        let Some(gilrs) = &mut self.gilrs else {
            return pressed;
        };
        while let Some(event) = gilrs.next_event() {
            match event.event {
                EventType::ButtonPressed(button, _) => {
                    if let Some(direction) = pad_of(button) {
                        controls.pad(direction, true);
                    } else {
                        pressed.push(action_of(button));
                    }
                }
                EventType::ButtonReleased(button, _) => {
                    if let Some(direction) = pad_of(button) {
                        controls.pad(direction, false);
                    }
                }
                EventType::AxisChanged(axis, value, _) => {
                    match axis {
                        Axis::LeftStickX => self.left.x = value,
                        Axis::LeftStickY => self.left.y = value,
                        Axis::RightStickX => self.right.x = value,
                        Axis::RightStickY => self.right.y = value,
                        // Pads whose D-pad is a pair of axes (y up, as the sticks).
                        Axis::DPadX => {
                            controls.pad(Pad::Right, value > 0.5);
                            controls.pad(Pad::Left, value < -0.5);
                        }
                        Axis::DPadY => {
                            controls.pad(Pad::Up, value > 0.5);
                            controls.pad(Pad::Down, value < -0.5);
                        }
                        _ => {}
                    }
                    match axis {
                        Axis::LeftStickX | Axis::LeftStickY => controls.left_stick(self.left),
                        Axis::RightStickX | Axis::RightStickY => controls.right_stick(self.right),
                        _ => {}
                    }
                }
                EventType::Disconnected => {
                    // Its releases will never come.
                    self.left = Vec2::ZERO;
                    self.right = Vec2::ZERO;
                    controls.release_all();
                }
                _ => {}
            }
        }
        pressed
    }
}

/// The D-pad direction of `button`, if it is one.
fn pad_of(button: Button) -> Option<Pad> {
    Some(match button {
        Button::DPadUp => Pad::Up,
        Button::DPadDown => Pad::Down,
        Button::DPadLeft => Pad::Left,
        Button::DPadRight => Pad::Right,
        _ => return None,
    })
}

/// What a gamepad button does: Start pauses, South (A) starts a new game after game over.
fn action_of(button: Button) -> Option<Action> {
    match button {
        Button::Start => Some(Action::Pause),
        Button::South => Some(Action::Restart),
        _ => None,
    }
}
