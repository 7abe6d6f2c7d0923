//! winit's calls into the window: it opens on resume, each window event becomes input or an
//! action, and each redraw is a frame: the due steps, then the drawing.

use std::time::Instant;

use glam::Vec2;
use winit::application::ApplicationHandler;
use winit::event::{ElementState, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::ActiveEventLoop;
use winit::keyboard::PhysicalKey;
use winit::window::WindowId;

use super::keys::{Action, ZOOM_STEP};
use super::{App, Flyer};

impl App<'_> {
    /// Whether a person flies the ship (not the autopilot, nobody, a recording or the
    /// benchmark).
    fn player(&self) -> bool {
        self.options.pilot == Flyer::Human && self.watch.is_none() && self.bench.is_none()
    }

    /// Leaves the start screen; returns whether this call did.
    fn begin(&mut self) -> bool {
        !std::mem::replace(&mut self.begun, true)
    }

    /// One frame: the due steps, then the drawing; in the benchmark's loop, counted.
    fn frame(&mut self, event_loop: &ActiveEventLoop) -> anyhow::Result<()> {
        if let Some(gamepads) = &mut self.gamepads {
            for action in gamepads.poll(&mut self.controls) {
                if !self.begin()
                    && let Some(action) = action
                {
                    self.act(action, event_loop)?;
                }
            }
        }
        let now = Instant::now();
        let sample = self
            .bench
            .as_ref()
            .is_some_and(|b| b.seconds.wants_sample(now));
        let profile = self.advance(now, sample)?;
        let (render, gl) = self.draw(profile.is_some())?;
        let alive = self.round.record.last.enemies_alive;
        if let Some(bench) = &mut self.bench {
            if let Some(profile) = profile {
                bench.seconds.sampled(profile, render, gl);
            }
            let now = Instant::now();
            bench.seconds.frame(now, alive);
            if *bench.until.get_or_insert(now + bench.duration) <= now {
                event_loop.exit();
            }
        }
        Ok(())
    }

    /// Notes a failure and closes the window.
    fn fail(&mut self, error: anyhow::Error, event_loop: &ActiveEventLoop) {
        self.failure.get_or_insert(error);
        event_loop.exit();
    }
}

impl ApplicationHandler for App<'_> {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.screen.is_none()
            && let Err(e) = self.open(event_loop)
        {
            self.fail(e, event_loop);
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _: WindowId, event: WindowEvent) {
        let result = match event {
            WindowEvent::CloseRequested => {
                event_loop.exit();
                Ok(())
            }
            WindowEvent::Resized(size) => {
                if let Some(screen) = &self.screen {
                    screen.display.resize(size.into());
                }
                Ok(())
            }
            WindowEvent::Focused(false) => {
                // The releases go to another window; a game in play waits for its player.
                self.controls.release_all();
                if self.player() && self.begun && !self.round.record.over {
                    self.paused = true;
                    self.hud_at = None;
                }
                Ok(())
            }
            WindowEvent::CursorMoved { position, .. } => {
                self.controls
                    .cursor(Vec2::new(position.x as f32, position.y as f32));
                Ok(())
            }
            WindowEvent::MouseWheel { delta, .. } => {
                // Lines from a wheel, pixels from a touchpad (about 40 to a notch).
                let notches = match delta {
                    MouseScrollDelta::LineDelta(_, y) => y,
                    MouseScrollDelta::PixelDelta(p) => p.y as f32 / 40.0,
                };
                self.zoom(ZOOM_STEP.powf(notches));
                Ok(())
            }
            WindowEvent::MouseInput {
                state,
                button: MouseButton::Left,
                ..
            } => {
                let down = state == ElementState::Pressed;
                if down {
                    self.begin();
                }
                self.controls.click(down);
                Ok(())
            }
            WindowEvent::KeyboardInput { event, .. } => {
                let PhysicalKey::Code(key) = event.physical_key else {
                    return;
                };
                let pressed = event.state == ElementState::Pressed;
                let action = Action::of(key);
                // Esc quits from the start screen without starting; the key that starts the
                // game does nothing else (but move or aim).
                let quit = action == Some(Action::Quit);
                let starting = pressed && !event.repeat && !quit && self.begin();
                let moving = self.controls.key(key, pressed);
                match action {
                    Some(action) if pressed && !event.repeat && !moving && !starting => {
                        self.act(action, event_loop)
                    }
                    _ => Ok(()),
                }
            }
            WindowEvent::RedrawRequested => self.frame(event_loop),
            _ => Ok(()),
        };
        if let Err(e) = result {
            self.fail(e, event_loop);
        }
    }

    fn about_to_wait(&mut self, _: &ActiveEventLoop) {
        if let Some(screen) = &self.screen {
            screen.window.request_redraw();
        }
    }
}
