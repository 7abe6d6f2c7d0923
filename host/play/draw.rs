//! Drawing into the window: opening it with the renderer asked for, each frame of the world
//! (drawn by the kernels or by GL), the hit flash, and the text over it: the HUD, the start
//! screen, the help, the game-over banner.

use std::time::{Duration, Instant};

use anyhow::Context as _;
use glium::{Rect, Surface};
use gpuwars_kernels::game::control::{DESTROYED, Status};
use winit::event_loop::ActiveEventLoop;

use super::input::ship_position;
use super::keys::{HELP, REPLAY_HELP};
use super::{App, Screen, window};
use crate::BackendKind;
use crate::backend::device_name;
use crate::camera::{self, Camera};
use crate::game::Game;
use crate::graphics::bodies::BodyRenderer;
use crate::graphics::headless::Target;
use crate::graphics::hud::text_image;
use crate::graphics::picture::{Blit, DeviceImage, Upload};
use crate::graphics::{Renderer, unpack};

/// How often the HUD's figures are redrawn.
const HUD_EVERY: Duration = Duration::from_millis(250);
/// Frames the red border shows after the ship was hit.
pub(super) const FLASH_FRAMES: u32 = 8;
/// The hit flash's colour and border width in pixels.
const FLASH: (f32, f32, f32, f32) = (0.9, 0.1, 0.1, 1.0);
const FLASH_WIDTH: u32 = 6;
/// The HUD's text colour.
const TEXT: u32 = crate::game::looks::rgb(230, 235, 245);

impl App<'_> {
    /// Opens the window and sets up the renderer.
    pub(super) fn open(&mut self, event_loop: &ActiveEventLoop) -> anyhow::Result<()> {
        let title = format!("GpuWars — {}", self.scene.name);
        let (window, display) =
            window::open(event_loop, &title, self.options.size, self.options.vsync)?;
        let bodies = match self.options.renderer {
            Renderer::Kernel => {
                self.renderer = match self.device.kind() {
                    BackendKind::Cuda => "kernel, into a GL pixel buffer registered with CUDA",
                    BackendKind::Cpu => "kernel, image uploaded to GL each frame",
                }
                .into();
                None
            }
            Renderer::Interop => {
                let renderer = BodyRenderer::for_game(&display, &self.round.game)?;
                self.renderer = match (renderer.is_interop(), renderer.fallback()) {
                    (true, _) => "GL from a CUDA–GL interop vertex buffer".into(),
                    (false, Some(why)) => {
                        eprintln!("gpuwars: {why}: the vertices are uploaded");
                        "GL from uploaded vertices (interop unavailable)".into()
                    }
                    (false, None) => "GL from vertices the emulator wrote".into(),
                };
                Some(renderer)
            }
        };
        let device_image = match self.device.kind() {
            BackendKind::Cuda => Ok(None),
            BackendKind::Cpu => Err(()),
        };
        self.screen = Some(Screen {
            bodies,
            device_image,
            target: None,
            picture: Upload::default(),
            hud: Upload::default(),
            overlay: Upload::default(),
            overlay_shown: None,
            blit: Blit::new(&display)?,
            display,
            window,
        });
        Ok(())
    }

    /// Draws one frame. When `timed`, waits and returns the renderer's device seconds and
    /// the seconds GL took after them (the HUD, and the swap); zeros otherwise.
    pub(super) fn draw(&mut self, timed: bool) -> anyhow::Result<(f64, f64)> {
        let Some(screen) = &mut self.screen else {
            return Ok((0.0, 0.0));
        };
        let (width, height) = screen.window.inner_size().into();
        if width == 0 || height == 0 {
            return Ok((0.0, 0.0));
        }
        let device = self.device;
        let start = timed.then(|| device.mark()).transpose()?;
        let now = Instant::now();
        let frame_dt = self
            .drawn_at
            .replace(now)
            .map_or(0.0, |then| (now - then).as_secs_f32());
        let lens = self.round.game.lens(&self.camera, width, height, frame_dt);
        let ship = ship_position(&self.scene, &self.round.record.last);
        self.aim_view = Some(camera::view(&lens, Some(ship), &mut self.aim_camera));
        let mut frame = screen.display.draw();
        match &mut screen.bodies {
            None => {
                let (game, at) = (&mut self.round.game, ((width, height), frame_dt));
                show_kernel_frame(screen, game, &mut frame, &self.camera, at)?;
            }
            Some(bodies) => {
                let fits = screen
                    .target
                    .as_ref()
                    .is_some_and(|t| t.size() == (width, height));
                if !fits {
                    screen.target = Some(Target::new(&screen.display, width, height)?);
                }
                let target = screen.target.as_ref().expect("made above");
                let mut surface = target.surface(&screen.display)?;
                surface.clear_color_and_depth(unpack(lens.background), 0.0);
                bodies.update(&screen.display, &mut self.round.game.drawing(), &lens)?;
                bodies.draw(&mut surface, &lens)?;
                screen
                    .blit
                    .draw(&mut frame, target.colour(), false, (0, 0), height, false)?;
            }
        }
        let device_s = match start {
            Some(start) => device.mark()?.seconds_since(&start)?,
            None => 0.0,
        };
        let gl_start = Instant::now();
        if self.flash > 0 {
            self.flash -= 1;
            let w = FLASH_WIDTH.min(width).min(height);
            for rect in [
                (0, 0, width, w),
                (0, height - w, width, w),
                (0, 0, w, height),
                (width - w, 0, w, height),
            ] {
                let (left, bottom, width, height) = rect;
                let rect = Rect {
                    left,
                    bottom,
                    width,
                    height,
                };
                frame.clear(Some(&rect), Some(FLASH), false, None, None);
            }
        }
        self.draw_text(&mut frame, width, height)?;
        frame.finish().context("showing the frame")?;
        self.frames += 1;
        self.rates.0 += 1;
        let gl_s = if timed {
            gl_start.elapsed().as_secs_f64()
        } else {
            0.0
        };
        Ok((device_s, gl_s))
    }

    /// The HUD, and the help or the game-over banner when they show.
    fn draw_text(
        &mut self,
        frame: &mut glium::Frame,
        width: u32,
        height: u32,
    ) -> anyhow::Result<()> {
        let now = Instant::now();
        let scale = if width >= 1600 { 2 } else { 1 };
        if self.screen.is_none() {
            return Ok(());
        }
        if self.hud_at.is_none_or(|at| now - at >= HUD_EVERY) {
            let (frames, steps, since) = self.rates;
            let seconds = (now - since).as_secs_f64().max(1e-9);
            if self.hud_at.is_some() {
                self.shown = (frames as f64 / seconds, steps as f64 / seconds);
            }
            self.rates = (0, 0, now);
            self.hud_at = Some(now);
            let lines = hud_lines(self, &self.round.record.last);
            let image = text_image(&lines, TEXT, scale);
            let screen = self.screen.as_mut().expect("checked above");
            screen.hud.set(&screen.display, &image)?;
        }
        let screen = self.screen.as_mut().expect("checked above");
        if let Some(texture) = screen.hud.texture() {
            screen
                .blit
                .draw(frame, texture, true, (8, 8), height, true)?;
        }
        let help: &[&str] = match self.watch {
            Some(_) => &REPLAY_HELP,
            None => &HELP,
        };
        let overlay: Option<Vec<String>> = if !self.begun {
            let mut lines = vec![
                format!("GpuWars: {}", self.scene.name),
                "press a key, click, or press a gamepad button to start".into(),
                String::new(),
            ];
            lines.extend(help.iter().map(|l| l.to_string()));
            Some(lines)
        } else if self.help {
            Some(help.iter().map(|l| l.to_string()).collect())
        } else if let Some(watch) = self.watch.as_ref().filter(|w| w.checked) {
            Some(vec![
                "end of the replay: the state matches the recording".into(),
                format!("{:#018x}", watch.replay.state_hash),
                "Esc quit".into(),
            ])
        } else if self.round.record.over && self.watch.is_none() {
            Some(game_over_lines(self))
        } else if self.paused && self.watch.is_some() {
            Some(vec!["paused: P or Space to go on, . or N one step".into()])
        } else if self.paused {
            Some(vec!["paused: P, Space or Start to go on".into()])
        } else {
            None
        };
        let screen = self.screen.as_mut().expect("checked above");
        if let Some(lines) = overlay {
            // Drawn into its texture only when its text or size changes, not every frame.
            let shown = (lines, scale);
            if screen.overlay_shown.as_ref() != Some(&shown) {
                let image = text_image(&shown.0, TEXT, scale);
                screen.overlay.set(&screen.display, &image)?;
                screen.overlay_shown = Some(shown);
            }
            if let Some(texture) = screen.overlay.texture() {
                let at = (
                    width.saturating_sub(texture.width()) / 2,
                    height.saturating_sub(texture.height()) / 2,
                );
                screen.blit.draw(frame, texture, true, at, height, true)?;
            }
        }
        Ok(())
    }
}

/// Draws the kernel renderer's frame of `game` after the queued steps, `width × height`,
/// through `camera` `dt` seconds after the previous frame, onto `frame`: written on the GPU
/// into a GL pixel buffer where CUDA–GL interop works, else read back and uploaded.
fn show_kernel_frame(
    screen: &mut Screen,
    game: &mut Game,
    frame: &mut glium::Frame,
    camera: &Camera,
    ((width, height), dt): ((u32, u32), f32),
) -> anyhow::Result<()> {
    if let Ok(image) = &mut screen.device_image
        && image.as_ref().is_none_or(|i| i.size() != (width, height))
    {
        let device = game.pipeline().device();
        match DeviceImage::new(&screen.display, device, width, height) {
            Ok(made) => *image = Some(made),
            Err(e) => {
                eprintln!("gpuwars: CUDA–GL interop is not available ({e}): frames are uploaded");
                screen.device_image = Err(());
            }
        }
    }
    if let Ok(Some(image)) = &mut screen.device_image {
        // SAFETY: the view goes only into the launches `render_into` queues; the mapped
        // pixel buffer holds `width × height` pixels and only they touch it until the unmap.
        let texture =
            unsafe { image.set(|pixels| game.render_into(width, height, camera, dt, pixels)) }?;
        screen
            .blit
            .draw(frame, texture, true, (0, 0), height, false)?;
        return Ok(());
    }
    game.render(width, height, camera, dt)?;
    let image = game.pipeline().frame()?;
    screen.picture.set(&screen.display, &image)?;
    let texture = screen.picture.texture().expect("set above");
    screen
        .blit
        .draw(frame, texture, true, (0, 0), height, false)?;
    Ok(())
}

/// The HUD's lines.
fn hud_lines(app: &App, status: &Status) -> Vec<String> {
    let best = best_score(app).max(status.score);
    let (frame_rate, step_rate) = app.shown;
    let mut flags = Vec::new();
    if app.paused {
        flags.push("paused");
    }
    if app.sound.is_silent() {
        flags.push("no sound device");
    } else if app.sound.is_muted() {
        flags.push("muted");
    }
    flags.push("F1 help");
    let replay = app.watch.as_ref().map(|w| {
        format!(
            "REPLAY of {}   step {} of {}   speed x{}",
            w.file,
            app.round.submitted,
            w.replay.inputs.len(),
            w.speed
        )
    });
    replay
        .into_iter()
        .chain([
            format!("score {}   best {best}", status.score),
            format!(
                "FPS meter {:.1} (over below {})",
                status.fps_meter, app.scene.game.fps.min
            ),
            format!("frame rate {frame_rate:.0}/s   steps {step_rate:.0}/s"),
            format!(
                "enemies {} alive, {} processed",
                status.enemies_alive, status.enemies_killed
            ),
            format!(
                "game time {:.1} s",
                f64::from(status.step) * f64::from(app.scene.world.dt)
            ),
            format!("{}: {}", app.device.kind(), device_name(app.device)),
            format!(
                "{} renderer   {}",
                app.options.renderer.name(),
                flags.join("   ")
            ),
        ])
        .collect()
}

/// The scene's high score (0 when none is kept).
fn best_score(app: &App) -> u32 {
    let best = app.scores.as_ref().and_then(|s| s.best(&app.scene.name));
    best.map_or(0, |e| e.score)
}

/// The game-over banner's lines.
fn game_over_lines(app: &App) -> Vec<String> {
    let status = &app.round.record.last;
    let why = if status.game_over == DESTROYED {
        "the ship was destroyed"
    } else {
        "too slow: the FPS meter fell too low"
    };
    let best = best_score(app);
    vec![
        "GAME OVER".into(),
        why.into(),
        format!("score {}   best {best}", status.score),
        "R (A on a gamepad) new game   Esc quit".into(),
    ]
}
