//! `gpuwars play`: the game in a window. A fixed-step loop submits the steps that real time
//! has made due, each with the input of the moment (keyboard, mouse and gamepad merged by
//! [`controls::Controls`]), draws the world with the renderer asked for, and puts the HUD,
//! the start screen, the help and the game-over banner over it; sound effects follow each
//! step's events. The game waits for a first key, click or button, and pauses while the help
//! shows or the window is left.
//!
//! A slow frame never changes the outcome: the simulation's dt is the scene's, and a frame
//! that falls behind plays its due steps late (at most [`MAX_CATCH_UP`] per frame, after
//! which the game slows down rather than skipping). The inputs of every step are recorded,
//! so `--record` writes a replay that `gpuwars replay` plays headless to the same state, and
//! [`watch`] plays in the same window loop (`gpuwars replay --window`).

pub mod controls;
mod gamepad;
mod guard;
pub mod keys;
mod window;

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use anyhow::{Context as _, anyhow, bail};
use glam::Vec2;
use glium::{Display, Rect, Surface};
use glutin::surface::WindowSurface;
use gpuwars_kernels::game::control::{DESTROYED, Input, Status};
use gpuwars_kernels::render::View;
use gpuwars_kernels::render::camera::CameraState;
use serde::Serialize;
use winit::application::ApplicationHandler;
use winit::event::{ElementState, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop};
use winit::keyboard::PhysicalKey;
use winit::window::{Fullscreen, Window, WindowId};

use crate::backend::device_name;
use crate::camera::{self, Camera};
use crate::demo::Record;
use crate::game::highscore::{self, HighScores};
use crate::game::replay::Replay;
use crate::game::{Game, Options, Scene};
use crate::graphics::bodies::BodyRenderer;
use crate::graphics::headless::Target;
use crate::graphics::hud::text_image;
use crate::graphics::picture::{Blit, DeviceImage, Upload};
use crate::graphics::{Renderer, unpack};
use crate::meter::Seconds;
use crate::pipeline::Profile;
use crate::sound::Sound;
use crate::{BackendKind, Device};
use controls::Controls;
use gamepad::Gamepads;
use keys::{Action, HELP, REPLAY_HELP, ZOOM_STEP};

/// The most steps one frame plays (times a replay's speed); beyond it the game slows down
/// instead.
pub const MAX_CATCH_UP: u64 = 8;
/// How often the HUD's figures are redrawn.
const HUD_EVERY: Duration = Duration::from_millis(250);
/// Frames the red border shows after the ship was hit.
const FLASH_FRAMES: u32 = 8;
/// The hit flash's colour and border width in pixels.
const FLASH: (f32, f32, f32, f32) = (0.9, 0.1, 0.1, 1.0);
const FLASH_WIDTH: u32 = 6;
/// The HUD's text colour.
const TEXT: u32 = crate::game::looks::rgb(230, 235, 245);

/// Who flies the ship in the window.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Pilot {
    /// The player, at the keyboard.
    #[default]
    Human,
    /// The autopilot.
    Auto,
    /// Nobody: the ship never moves and never fires.
    None,
}

/// How `play` runs.
#[derive(Clone, Debug)]
pub struct PlayOptions {
    /// Seed of the generators.
    pub seed: u32,
    /// Who flies the ship.
    pub pilot: Pilot,
    /// Start with the sound off.
    pub muted: bool,
    /// Swap frames with the display's refresh.
    pub vsync: bool,
    /// The renderer.
    pub renderer: Renderer,
    /// Write the last game's replay here on exit.
    pub record: Option<PathBuf>,
    /// The window's size in pixels.
    pub size: (u32, u32),
    /// Steps in flight before a status is read back.
    pub lag: usize,
}

/// What `play` prints when the window closes: the last game's figures.
#[derive(Clone, Debug, Serialize)]
pub struct PlayReport {
    /// The backend that ran the kernels.
    pub backend: BackendKind,
    /// The GPU's name, or the CPU emulation.
    pub device: String,
    /// The renderer and how its data reached GL.
    pub renderer: String,
    /// The scene.
    pub scene: String,
    /// The seed.
    pub seed: u32,
    /// Steps the last game played.
    pub steps: u64,
    /// Its game seconds.
    pub game_seconds: f64,
    /// The final state hash (`0x` and 16 hex digits), as `demo` and `replay` print it.
    pub state_hash: String,
    /// Points scored.
    pub score: u32,
    /// Enemies that died.
    pub enemies_killed: u32,
    /// The FPS meter at the end.
    pub fps_meter: f32,
    /// Whether the game ended.
    pub game_over: bool,
    /// Frames drawn in the whole session.
    pub frames: u64,
    /// Frames per second over the session.
    pub frame_rate: f64,
    /// For a replay: whether its end state matched the recording, or where it stopped.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub replay: Option<String>,
}

impl PlayReport {
    /// The report as aligned lines of text.
    pub fn to_text(&self) -> String {
        let rows = [
            ("backend:", self.backend.to_string()),
            ("device:", self.device.clone()),
            ("renderer:", self.renderer.clone()),
            ("scene:", self.scene.clone()),
            ("seed:", self.seed.to_string()),
            (
                "steps:",
                format!("{} ({:.1} s of game time)", self.steps, self.game_seconds),
            ),
            ("state_hash:", self.state_hash.clone()),
            ("score:", self.score.to_string()),
            ("enemies_killed:", self.enemies_killed.to_string()),
            ("fps_meter:", format!("{:.2}", self.fps_meter)),
            (
                "game_over:",
                if self.game_over { "yes" } else { "no" }.into(),
            ),
            (
                "frames:",
                format!("{} ({:.1} per second)", self.frames, self.frame_rate),
            ),
        ];
        let replay = self.replay.iter().map(|r| ("replay:", r.clone()));
        let rows = rows.into_iter().chain(replay);
        rows.map(|(k, v)| format!("{k:<18}{v}\n")).collect()
    }
}

/// Whether a display to open a window on is there (X11 or Wayland).
pub fn display_present() -> bool {
    ["DISPLAY", "WAYLAND_DISPLAY"]
        .iter()
        .any(|v| std::env::var_os(v).is_some_and(|d| !d.is_empty()))
}

/// Plays `scene` in a window until Esc or the window is closed; returns the last game's
/// report (and writes its replay if asked).
pub fn play(device: &Device, scene: &Scene, options: PlayOptions) -> anyhow::Result<PlayReport> {
    // winit's error quotes its own source file: the user is told what to do instead.
    let event_loop = EventLoop::new()
        .map_err(|_| anyhow!("no display to open a window on; `gpuwars demo` plays without one"))?;
    event_loop.set_control_flow(ControlFlow::Poll);
    let mut app = App::new(device, scene, options, None)?;
    if let Some(ran) = guard::surviving_winit(|| event_loop.run_app(&mut app)) {
        ran.context("running the window")?;
    }
    app.finish()
}

/// Plays `replay` (read from `file`, its scene already read from it) in a window, with
/// pause, single steps and speeds, until Esc or the window is closed; at its end, checks the
/// state against the recording's hash (a mismatch is an error). `options.seed` is ignored
/// for the replay's own.
pub fn watch(
    device: &Device,
    scene: &Scene,
    replay: Replay,
    file: &Path,
    options: PlayOptions,
) -> anyhow::Result<PlayReport> {
    let headless = format!(
        "`gpuwars replay {}` (without --window) checks it headless",
        file.display()
    );
    if !display_present() {
        bail!(
            "no display to open a window on (neither DISPLAY nor WAYLAND_DISPLAY is set): {headless}"
        );
    }
    // winit's error quotes its own source file: the user is told what to do instead.
    let event_loop =
        EventLoop::new().map_err(|_| anyhow!("no display to open a window on: {headless}"))?;
    event_loop.set_control_flow(ControlFlow::Poll);
    let options = PlayOptions {
        seed: replay.seed,
        record: None,
        ..options
    };
    let watch = Watch {
        replay,
        file: file.display().to_string(),
        speed: 1,
        single: 0,
        checked: false,
    };
    let mut app = App::new(device, scene, options, Some(watch))?;
    if let Some(ran) = guard::surviving_winit(|| event_loop.run_app(&mut app)) {
        ran.context("running the window")?;
    }
    app.finish()
}

/// Runs `scene` in the window for `duration` as the benchmark's loop does (one step per
/// frame, whatever the time), counting frames second by second with one profiled frame per
/// second; returns the seconds and whether the game ended.
pub fn measure(
    device: &Device,
    scene: &Scene,
    options: PlayOptions,
    duration: Duration,
) -> anyhow::Result<(Seconds, bool)> {
    let event_loop = EventLoop::new().map_err(|_| {
        anyhow!("no display to open a window on; leave out --window to render offscreen")
    })?;
    event_loop.set_control_flow(ControlFlow::Poll);
    let mut app = App::new(device, scene, options, None)?;
    app.begun = true;
    // The paper's experiment draws the whole field (see `benchmark::paper`).
    app.camera = Camera::field();
    app.bench = Some(Bench {
        seconds: Seconds::new(Instant::now()),
        duration,
        until: None,
    });
    event_loop.run_app(&mut app).context("running the window")?;
    app.screen = None;
    if let Some(error) = app.failure.take() {
        return Err(error);
    }
    let bench = app.bench.take().expect("set above");
    Ok((bench.seconds, app.round.record.over))
}

/// The benchmark's loop in the window: its frame counter, and when it ends.
struct Bench {
    seconds: Seconds,
    duration: Duration,
    /// Set at the first frame, so that opening the window is not counted.
    until: Option<Instant>,
}

/// Game time: runs while the game is neither paused nor over, `rate` times as fast as real
/// time, and tells how many steps are due.
struct Clock {
    dt: f64,
    /// Game time banked before `since`.
    banked: f64,
    /// When it last started running, if it runs.
    since: Option<Instant>,
    /// Game seconds per real second.
    rate: u32,
}

impl Clock {
    fn new(dt: f32) -> Self {
        Clock {
            dt: f64::from(dt),
            banked: 0.0,
            since: None,
            rate: 1,
        }
    }

    fn run(&mut self, running: bool, now: Instant) {
        match (running, self.since) {
            (true, None) => self.since = Some(now),
            (false, Some(since)) => {
                self.banked += (now - since).as_secs_f64() * f64::from(self.rate);
                self.since = None;
            }
            _ => {}
        }
    }

    /// Runs `rate` times as fast as real time from `now` on.
    fn set_rate(&mut self, rate: u32, now: Instant) {
        let running = self.since.is_some();
        self.run(false, now);
        self.rate = rate;
        self.run(running, now);
    }

    /// Counts one step played out of time (a single step while paused), so that the steps
    /// due later do not wait for it.
    fn bank_step(&mut self) {
        self.banked += self.dt;
    }

    /// Steps due at `now` when `played` have been played; the time of the steps beyond
    /// [`MAX_CATCH_UP`] (times the rate) is given up (the game slows down, it does not skip).
    fn due(&mut self, played: u64, now: Instant) -> u64 {
        let rate = f64::from(self.rate);
        let elapsed = self.banked + self.since.map_or(0.0, |s| (now - s).as_secs_f64() * rate);
        let due = ((elapsed / self.dt) as u64).saturating_sub(played);
        let most = MAX_CATCH_UP * u64::from(self.rate);
        if due > most {
            self.banked -= (due - most) as f64 * self.dt;
        }
        due.min(most)
    }
}

/// A replay playing in the window: the pilot is the recording.
struct Watch {
    replay: Replay,
    /// The file it came from, for messages.
    file: String,
    /// Times real time.
    speed: u32,
    /// Steps asked for one at a time while paused, not yet played.
    single: u64,
    /// The end state has been checked against the recording.
    checked: bool,
}

/// The window and what draws into it.
struct Screen {
    // Dropped in this order: GL objects before the display, the display before the window.
    bodies: Option<BodyRenderer>,
    /// The kernel renderer's frames on the GPU, in a GL pixel buffer registered with CUDA:
    /// `Err` once that failed (GL not on the NVIDIA driver), and frames are uploaded.
    device_image: Result<Option<DeviceImage>, ()>,
    target: Option<Target>,
    picture: Upload,
    hud: Upload,
    overlay: Upload,
    /// The text and scale the overlay texture holds.
    overlay_shown: Option<(Vec<String>, u32)>,
    blit: Blit,
    display: Display<WindowSurface>,
    window: Window,
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

/// One game in progress and what the loop knows of it.
struct Round<'d> {
    game: Game<'d>,
    record: Record,
    submitted: u64,
    clock: Clock,
    scored: bool,
}

struct App<'d> {
    device: &'d Device,
    scene: Scene,
    options: PlayOptions,
    screen: Option<Screen>,
    round: Round<'d>,
    controls: Controls,
    /// The gamepads, when a player flies the ship.
    gamepads: Option<Gamepads>,
    /// A replay playing instead of a game.
    watch: Option<Watch>,
    /// The first key, click or button has come (the start screen is gone).
    begun: bool,
    paused: bool,
    help: bool,
    sound: Sound,
    /// The high scores, where the user has a data folder.
    scores: Option<HighScores>,
    flash: u32,
    frames: u64,
    started: Instant,
    /// Frames and steps over the last HUD period, for its rates.
    rates: (u64, u64, Instant),
    shown: (f64, f64),
    hud_at: Option<Instant>,
    renderer: String,
    failure: Option<anyhow::Error>,
    /// The benchmark's loop, when `measure` runs the window.
    bench: Option<Bench>,
    /// What the frames show.
    camera: Camera,
    /// When the last frame was drawn: the camera glides by the time since.
    drawn_at: Option<Instant>,
    /// The camera as the host follows it, from the statuses read back, with the device's
    /// own functions: the view the mouse aims through (the device's, a few steps late).
    aim_camera: CameraState,
    /// The last frame's view by [`App::aim_camera`].
    aim_view: Option<View>,
}

impl<'d> App<'d> {
    fn new(
        device: &'d Device,
        scene: &Scene,
        options: PlayOptions,
        watch: Option<Watch>,
    ) -> anyhow::Result<Self> {
        let round = Round::new(device, scene, &options)?;
        let scores = match highscore::default_path() {
            Some(path) => {
                let (scores, problem) = HighScores::load(path);
                if let Some(problem) = problem {
                    eprintln!("gpuwars: {problem}: it will be replaced");
                }
                Some(scores)
            }
            None => None,
        };
        let now = Instant::now();
        Ok(App {
            device,
            scene: scene.clone(),
            sound: Sound::open(options.muted),
            scores,
            screen: None,
            round,
            controls: Controls::new(),
            gamepads: (options.pilot == Pilot::Human && watch.is_none()).then(Gamepads::open),
            // A replay plays at once: nobody is there to start it.
            begun: watch.is_some(),
            watch,
            paused: false,
            help: false,
            flash: 0,
            frames: 0,
            started: now,
            rates: (0, 0, now),
            shown: (0.0, 0.0),
            hud_at: None,
            renderer: String::new(),
            failure: None,
            bench: None,
            camera: Camera::default(),
            drawn_at: None,
            aim_camera: CameraState::default(),
            aim_view: None,
            options,
        })
    }

    /// Opens the window and sets up the renderer.
    fn open(&mut self, event_loop: &ActiveEventLoop) -> anyhow::Result<()> {
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

    /// The input of the next step, by the pilot (or the recording).
    fn input(&mut self) -> Option<Input> {
        if let Some(watch) = &self.watch {
            return Some(watch.replay.inputs[self.round.submitted as usize]);
        }
        match self.options.pilot {
            Pilot::Human => {
                let ship = self.aim_view.as_ref().map_or(Vec2::ZERO, |view| {
                    ship_on_screen(&self.scene, &self.round.record.last, view)
                });
                Some(self.controls.input(ship))
            }
            Pilot::Auto => None,
            Pilot::None => Some(Input::default()),
        }
    }

    /// Whether game time runs: the game has started and is neither paused, nor behind the
    /// help, nor over; a replay has steps left.
    fn running(&self) -> bool {
        self.begun && !self.paused && !self.help && !self.round.record.over && !self.at_end()
    }

    /// Whether a replay has submitted its every step.
    fn at_end(&self) -> bool {
        self.watch
            .as_ref()
            .is_some_and(|w| self.round.submitted >= w.replay.inputs.len() as u64)
    }

    /// Whether a person flies the ship (not the autopilot, nobody, a recording or the
    /// benchmark).
    fn player(&self) -> bool {
        self.options.pilot == Pilot::Human && self.watch.is_none() && self.bench.is_none()
    }

    /// Leaves the start screen; returns whether this call did.
    fn begin(&mut self) -> bool {
        !std::mem::replace(&mut self.begun, true)
    }

    /// Plays the due steps (the benchmark's one step, profiled when `profiled`) and takes
    /// the statuses that came back; returns the profile of a profiled step.
    fn advance(&mut self, now: Instant, profiled: bool) -> anyhow::Result<Option<Profile>> {
        let running = self.running();
        self.round.clock.run(running, now);
        let due = match (running, &self.bench) {
            (false, _) => 0,
            (true, Some(_)) => 1,
            (true, None) => self.round.clock.due(self.round.submitted, now),
        };
        let due = match &mut self.watch {
            Some(watch) => {
                let left = watch.replay.inputs.len() as u64 - self.round.submitted;
                (due + std::mem::take(&mut watch.single)).min(left)
            }
            None => due,
        };
        let mut profile = None;
        for _ in 0..due {
            let input = self.input();
            if profiled {
                let mut p = Profile::default();
                self.round.game.submit_profiled(input, &mut p)?;
                profile = Some(p);
            } else {
                self.round.game.submit(input)?;
            }
            self.round.submitted += 1;
            self.rates.1 += 1;
        }
        while let Some(status) = self.round.game.ready_status() {
            self.take(status);
        }
        if self.at_end() || (self.watch.is_some() && self.round.record.over) {
            self.check_replay()?;
        }
        Ok(profile)
    }

    /// At a replay's end (once): every status taken, the state's hash compared with the
    /// recording's; a mismatch is an error.
    fn check_replay(&mut self) -> anyhow::Result<()> {
        let Some(watch) = self.watch.as_mut().filter(|w| !w.checked) else {
            return Ok(());
        };
        watch.checked = true;
        while let Some(status) = self.round.game.next_status()? {
            self.take(status);
        }
        let hash = self.round.game.state_hash()?;
        let watch = self.watch.as_ref().expect("checked above");
        let recorded = watch.replay.state_hash;
        if hash != recorded {
            bail!(
                "{}: the replay ended in state {hash:#018x} but was recorded ending in {recorded:#018x}",
                watch.file
            );
        }
        eprintln!(
            "gpuwars: the replay ended after {} steps in the recorded state {hash:#018x}",
            self.round.submitted
        );
        self.hud_at = None;
        Ok(())
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
            .is_some_and(|b| b.seconds.wants_sample());
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

    /// One status back from the device: recorded, heard, and the end of the game noted.
    fn take(&mut self, status: Status) {
        if self.round.record.over {
            return;
        }
        self.round.record.take(status);
        self.sound.play(&status);
        if status.events.ship_hits > 0 {
            self.flash = FLASH_FRAMES;
        }
        if self.round.record.over {
            self.keep_score();
        }
    }

    /// Records the game's score as the scene's best if it is, once per game: at game over,
    /// or when the window closes mid-game. A replay's is not the player's.
    fn keep_score(&mut self) {
        if std::mem::replace(&mut self.round.scored, true) || self.watch.is_some() {
            return;
        }
        let score = self.round.record.last.score;
        if let Some(scores) = &mut self.scores
            && scores.record(&self.scene.name, score, Some(self.options.seed))
            && let Err(e) = scores.save()
        {
            eprintln!("gpuwars: the high score was not saved: {e}");
        }
    }

    /// Draws one frame. When `timed`, waits and returns the renderer's device seconds and
    /// the seconds GL took after them (the HUD, and the swap); zeros otherwise.
    fn draw(&mut self, timed: bool) -> anyhow::Result<(f64, f64)> {
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
                let pipeline = self.round.game.pipeline_mut();
                bodies.update(&screen.display, pipeline, &lens)?;
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

    /// Does what a key asks.
    fn act(&mut self, action: Action, event_loop: &ActiveEventLoop) -> anyhow::Result<()> {
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
    fn zoom(&mut self, factor: f32) {
        if let Some(screen) = &self.screen {
            let size = screen.window.inner_size().into();
            self.camera.zoom_within(factor, self.scene.world.size, size);
        }
    }

    /// Notes a failure and closes the window.
    fn fail(&mut self, error: anyhow::Error, event_loop: &ActiveEventLoop) {
        self.failure.get_or_insert(error);
        event_loop.exit();
    }

    /// The last game's report, its replay written if asked; the window's failure if one
    /// closed it.
    fn finish(mut self) -> anyhow::Result<PlayReport> {
        // GL goes before the game's device buffers that interop registered.
        self.screen = None;
        if let Some(error) = self.failure.take() {
            return Err(error);
        }
        while let Some(status) = self.round.game.next_status()? {
            self.take(status);
        }
        if self.at_end() {
            self.check_replay()?;
        }
        self.keep_score();
        let hash = self.round.game.state_hash()?;
        let record = &self.round.record;
        let status = record.last;
        let played = record.inputs.len() as u64;
        if let Some(path) = &self.options.record {
            let replay = Replay {
                version: crate::game::replay::VERSION,
                scene: self.scene.name.clone(),
                scene_toml: self.scene.source.clone(),
                seed: self.options.seed,
                backend: self.device.kind().to_string(),
                state_hash: hash,
                inputs: record.inputs.clone(),
            };
            replay.save(path)?;
        }
        let seconds = self.started.elapsed().as_secs_f64().max(1e-9);
        Ok(PlayReport {
            backend: self.device.kind(),
            device: device_name(self.device),
            renderer: self.renderer,
            scene: self.scene.name.clone(),
            seed: self.options.seed,
            steps: played,
            game_seconds: played as f64 * f64::from(self.scene.world.dt),
            state_hash: format!("{hash:#018x}"),
            score: status.score,
            enemies_killed: status.enemies_killed,
            fps_meter: status.fps_meter,
            game_over: status.is_over(),
            frames: self.frames,
            frame_rate: self.frames as f64 / seconds,
            replay: self.watch.as_ref().map(|w| match w.checked {
                true => "the end state matches the recording".into(),
                false => format!(
                    "stopped at step {} of {}: the end state was not checked",
                    played,
                    w.replay.inputs.len()
                ),
            }),
        })
    }
}

impl<'d> Round<'d> {
    fn new(device: &'d Device, scene: &Scene, options: &PlayOptions) -> anyhow::Result<Self> {
        let game = Game::with_options(
            device,
            scene,
            options.seed,
            Options {
                lag: options.lag,
                ..Options::default()
            },
        )?;
        Ok(Round {
            game,
            record: Record::default(),
            submitted: 0,
            clock: Clock::new(scene.world.dt),
            scored: false,
        })
    }
}

/// Where the ship of `status` is on the screen shown through `view`, in pixels (x right, y
/// down): the mouse aims from there. Before the first status, where it is born: the world's
/// middle.
fn ship_on_screen(scene: &Scene, status: &Status, view: &View) -> Vec2 {
    view.to_image(ship_position(scene, status))
}

/// The ship's position by `status`; before the first status, where it is born: the world's
/// middle.
fn ship_position(scene: &Scene, status: &Status) -> Vec2 {
    match status.step {
        0 => scene.world.size * 0.5,
        _ => status.ship,
    }
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

#[cfg(test)]
mod tests {
    use super::*;

    /// A clock of 10 ms steps, started at `t0`.
    fn running(t0: Instant) -> Clock {
        let mut clock = Clock::new(0.01);
        clock.run(true, t0);
        clock
    }

    #[test]
    fn a_faster_clock_makes_steps_due_faster_from_the_change_on() {
        let t0 = Instant::now();
        let ms = Duration::from_millis;
        let mut clock = running(t0);
        assert_eq!(clock.due(0, t0 + ms(45)), 4);
        // Four times real time from 50 ms on: 50 ms at x1 and 10 ms at x4 make 9 steps of
        // game time, 4 of them played.
        clock.set_rate(4, t0 + ms(50));
        assert_eq!(clock.due(4, t0 + ms(60)), 5);
        // Catching up is capped at MAX_CATCH_UP times the rate, the rest given up.
        assert_eq!(clock.due(9, t0 + ms(1050)), MAX_CATCH_UP * 4);
        assert_eq!(clock.due(9 + MAX_CATCH_UP * 4, t0 + ms(1050)), 0);
    }

    #[test]
    fn single_steps_while_paused_do_not_delay_the_steps_after() {
        let t0 = Instant::now();
        let ms = Duration::from_millis;
        let mut clock = running(t0);
        assert_eq!(clock.due(0, t0 + ms(30)), 3);
        clock.run(false, t0 + ms(30));
        // Paused for a second: nothing due; three single steps are banked.
        assert_eq!(clock.due(3, t0 + ms(1030)), 0);
        for _ in 0..3 {
            clock.bank_step();
        }
        clock.run(true, t0 + ms(1030));
        // 10 ms after going on: one step due after the six played.
        assert_eq!(clock.due(6, t0 + ms(1040)), 1);
    }
}
