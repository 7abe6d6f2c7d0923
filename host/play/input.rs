//! The player's side: each step's input (the controls, the autopilot, nobody, or the
//! recording), what the keys and buttons ask for, and the zoom.

use std::time::Instant;

use glam::Vec2;
use gpuwars_kernels::game::control::{Input, Status};
use gpuwars_kernels::render::Framing;
use winit::event_loop::ActiveEventLoop;
use winit::window::Fullscreen;

use super::keys::{Action, ZOOM_STEP};
use super::{App, Flyer, Round};
use crate::game::Scene;

impl App<'_> {
    /// The input of the next step, by the pilot (or the recording).
    pub(super) fn input(&mut self) -> Option<Input> {
        if let Some(watch) = &self.watch {
            return Some(watch.replay.inputs[self.round.submitted as usize]);
        }
        match self.options.pilot {
            Flyer::Human => {
                let ship = self.aim_view.as_ref().map_or(Vec2::ZERO, |view| {
                    ship_on_screen(&self.scene, &self.round.record.last, view)
                });
                Some(self.controls.input(ship))
            }
            Flyer::Auto => None,
            Flyer::None => Some(Input::default()),
        }
    }

    /// Does what a key asks.
    pub(super) fn act(
        &mut self,
        action: Action,
        event_loop: &ActiveEventLoop,
    ) -> anyhow::Result<()> {
        match action {
            Action::Pause => self.paused = !self.paused,
            Action::Step => {
                if let Some(watch) = self.watch.as_mut().filter(|_| self.paused) {
                    watch.single += 1;
                    self.round.clock.bank_step();
                }
            }
            Action::Speed(speed) => {
                if let Some(watch) = &mut self.watch {
                    watch.speed = speed;
                    self.round.clock.set_rate(speed, Instant::now());
                }
            }
            Action::Mute => {
                self.sound.toggle_muted();
            }
            Action::Help => self.help = !self.help,
            Action::Restart if self.round.record.over && self.watch.is_none() => {
                self.round = Round::new(self.device, &self.scene, &self.options)?;
                self.hud_at = None;
            }
            Action::Restart => {}
            Action::Fullscreen => {
                if let Some(screen) = &self.screen {
                    let full = screen.window.fullscreen().is_some();
                    let mode = (!full).then_some(Fullscreen::Borderless(None));
                    screen.window.set_fullscreen(mode);
                }
            }
            Action::Quit => event_loop.exit(),
            Action::ZoomIn => self.zoom(ZOOM_STEP),
            Action::ZoomOut => self.zoom(1.0 / ZOOM_STEP),
            Action::Overview => self.camera.toggle_overview(),
        }
        self.hud_at = None;
        Ok(())
    }

    /// Zooms the camera by `factor`, no farther out than the whole field in the window.
    pub(super) fn zoom(&mut self, factor: f32) {
        if let Some(screen) = &self.screen {
            let size = screen.window.inner_size().into();
            self.camera.zoom_within(factor, self.scene.world.size, size);
        }
    }
}

/// Where the ship of `status` is on the screen shown through `view`, in pixels (x right, y
/// down): the mouse aims from there. Before the first status, where it is born: the world's
/// middle.
fn ship_on_screen(scene: &Scene, status: &Status, view: &Framing) -> Vec2 {
    view.to_image(ship_position(scene, status))
}

/// The ship's position by `status`; before the first status, where it is born: the world's
/// middle.
pub(super) fn ship_position(scene: &Scene, status: &Status) -> Vec2 {
    match status.step {
        0 => scene.world.size * 0.5,
        _ => status.ship,
    }
}
