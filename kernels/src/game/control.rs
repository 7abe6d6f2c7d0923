//! What crosses between the CPU and the GPU each step (paper section 5): the player's
//! [`Input`] going up, the [`Status`] coming back. Both are small `#[repr(C)]` structs, and
//! they cross through a [`Mailbox`].

use core::f32::consts::TAU;

use glam::Vec2;

use crate::access::{Access, Read, Readable, Unused, Write};
use crate::{DevSlice, math};

/// Steps of [`Input::move_x`] / [`Input::move_y`] per unit of stick deflection.
pub const MOVE_SCALE: i32 = 1000;
/// Steps of [`Input::aim`] per full turn.
pub const AIM_STEPS: u32 = 1 << 16;

/// One step's commands. Integers only, so a replay stores them exactly.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, bytemuck::Pod, bytemuck::Zeroable)]
pub struct Input {
    /// Movement along x, in `[-MOVE_SCALE, MOVE_SCALE]`.
    pub move_x: i32,
    /// Movement along y, in `[-MOVE_SCALE, MOVE_SCALE]`.
    pub move_y: i32,
    /// Shooting direction: `aim / AIM_STEPS` of a turn counter-clockwise from `+x`, below
    /// [`AIM_STEPS`].
    pub aim: u32,
    /// 1 while the fire key is held, else 0.
    pub fire: u32,
}

impl Input {
    /// The movement as a vector no longer than 1.
    #[inline(always)]
    pub fn movement(&self) -> Vec2 {
        let v = Vec2::new(self.move_x as f32, self.move_y as f32) / MOVE_SCALE as f32;
        math::clamp_length_max(v, 1.0)
    }

    /// Unit vector of the shooting direction.
    #[inline(always)]
    pub fn aim_dir(&self) -> Vec2 {
        let angle = (self.aim % AIM_STEPS) as f32 * (TAU / AIM_STEPS as f32);
        Vec2::new(libm::cosf(angle), libm::sinf(angle))
    }

    /// Whether the fire key is held.
    #[inline(always)]
    pub fn firing(&self) -> bool {
        self.fire != 0
    }

    /// The [`Input::aim`] nearest the direction of `dir` (0 for a zero vector).
    #[inline(always)]
    pub fn aim_towards(dir: Vec2) -> u32 {
        let turns = libm::atan2f(dir.y, dir.x) / TAU;
        let turns = if turns < 0.0 { turns + 1.0 } else { turns };
        ((turns * AIM_STEPS as f32 + 0.5) as u32) % AIM_STEPS
    }

    /// The [`Input::move_x`], [`Input::move_y`] pair for a movement vector (clamped to the
    /// allowed range; NaN reads as 0).
    #[inline(always)]
    pub fn move_towards(v: Vec2) -> (i32, i32) {
        let scale = |c: f32| {
            let s = c * MOVE_SCALE as f32;
            // `as` saturates and maps NaN to 0.
            (if s < 0.0 { s - 0.5 } else { s + 0.5 } as i32).clamp(-MOVE_SCALE, MOVE_SCALE)
        };
        (scale(v.x), scale(v.y))
    }

    /// Why this input is out of range, if it is (which field, and the allowed range).
    pub fn problem(&self) -> Option<(&'static str, &'static str)> {
        let stick = -MOVE_SCALE..=MOVE_SCALE;
        if !stick.contains(&self.move_x) {
            Some(("move_x", "-1000 to 1000"))
        } else if !stick.contains(&self.move_y) {
            Some(("move_y", "-1000 to 1000"))
        } else if self.aim >= AIM_STEPS {
            Some(("aim", "0 to 65535"))
        } else if self.fire > 1 {
            Some(("fire", "0 or 1"))
        } else {
            None
        }
    }
}

/// What the host sends up each step: the player's input, or word that the autopilot flies.
/// Either way the step launches the same kernels; the choice is made on the device.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct Order {
    /// The input to apply when the autopilot does not fly.
    pub input: Input,
    /// Non-zero: the autopilot flies this step and `input` is ignored.
    pub autopilot: u32,
}

impl Order {
    /// The player's `input`.
    pub fn input(input: Input) -> Self {
        Order {
            input,
            autopilot: 0,
        }
    }

    /// The autopilot flies.
    pub fn autopilot() -> Self {
        Order {
            input: Input::default(),
            autopilot: 1,
        }
    }
}

/// Things that happened in one step, for the sound effects and the HUD.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct Events {
    /// Shots fired.
    pub shots_fired: u32,
    /// Enemies that died.
    pub kills: u32,
    /// Enemies touching the ship.
    pub ship_hits: u32,
    /// Enemies spawned.
    pub spawned: u32,
    /// Waves of the spawn schedule that brought enemies this step.
    pub waves: u32,
    /// Shots that struck an enemy this step (took damage from a contact; obstacles do none).
    pub shot_hits: u32,
}

/// [`Status::game_over`]: still playing.
pub const PLAYING: u32 = 0;
/// [`Status::game_over`]: the FPS meter fell below the scene's minimum.
pub const TOO_SLOW: u32 = 1;
/// [`Status::game_over`]: the ship was destroyed.
pub const DESTROYED: u32 = 2;

/// The game's state as the master thread keeps it on the device; the host reads this one
/// struct back each frame.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct Status {
    /// Steps played.
    pub step: u32,
    /// Points: every enemy that died, worth its birth energy.
    pub score: u32,
    /// The ship's frame rate: the scene's starting FPS scaled by the ship's remaining energy.
    pub fps_meter: f32,
    /// [`PLAYING`], [`TOO_SLOW`] or [`DESTROYED`].
    pub game_over: u32,
    /// Enemies alive.
    pub enemies_alive: u32,
    /// Enemies that died since the start.
    pub enemies_killed: u32,
    /// Shots in flight.
    pub shots_alive: u32,
    /// Steps until the ship may fire again.
    pub cooldown: u32,
    /// What happened this step.
    pub events: Events,
    /// The input this step applied (what a replay records).
    pub input: Input,
    /// Where the ship is after the step (where it was last, once it is destroyed); while a
    /// step is under way, where it is as the step's grid is built.
    pub ship: Vec2,
}

impl Status {
    /// Whether the game has ended.
    #[inline(always)]
    pub fn is_over(&self) -> bool {
        self.game_over != PLAYING
    }
}

/// Where the host and the steps in flight meet: the commands the host writes and the
/// statuses the steps leave, one of each per step in flight, in memory both reach without a
/// copy (the host's ring), and the device's count of the steps tallied, which picks the
/// slot: step `n` (counted modulo 2³²) uses element `n % depth` of both. Each part's access
/// is a parameter: the master reads its command ([`Reading`]), the tally posts its status
/// and counts the step ([`Posting`]). So the master cannot post:
/// ```compile_fail,E0599
/// use gpuwars_kernels::game::{control::Status, master::MasterArgs};
/// fn post(args: &MasterArgs) {
///     args.mailbox.post(Status::default());
/// }
/// ```
/// nor the tally read a command:
/// ```compile_fail,E0599
/// use gpuwars_kernels::game::{control::Order, master::TallyArgs};
/// fn command(args: &TallyArgs) -> Order {
///     args.mailbox.command()
/// }
/// ```
/// while the master reads it:
/// ```
/// use gpuwars_kernels::game::{control::Order, master::MasterArgs};
/// fn command(args: &MasterArgs) -> Order {
///     args.mailbox.command()
/// }
/// ```
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct Mailbox<C: Access = Write, S: Access = Write, T: Access = Write> {
    /// The commands, one per step in flight (at least one).
    pub commands: DevSlice<Order, C>,
    /// The statuses, as many.
    pub statuses: DevSlice<Status, S>,
    /// Steps tallied so far, modulo 2³² (one element): the step under way is the next.
    pub tallied: DevSlice<u32, T>,
}

// SAFETY: `repr(C)`: three 16-byte views (each a `NoUninit` whatever its access), 48 bytes
// with no padding (checked below).
unsafe impl<C: Access, S: Access, T: Access> bytemuck::NoUninit for Mailbox<C, S, T> {}
const _: () = assert!(size_of::<Mailbox>() == 48);
const _: () = assert!(size_of::<Reading>() == 48);

/// The mailbox as the master uses it: the command of the step under way, read.
pub type Reading = Mailbox<Read, Unused, Read>;

/// The mailbox as the tally uses it: the step's status written, the step counted.
pub type Posting = Mailbox<Unused, Write, Write>;

impl<C: Readable, S: Access, T: Readable> Mailbox<C, S, T> {
    /// The command of the step under way.
    #[inline(always)]
    pub fn command(&self) -> Order {
        self.commands.get(self.tallied.get(0) % self.commands.len())
    }
}

impl<C: Access> Mailbox<C, Write, Write> {
    /// Leaves `status` as the step's and counts the step: the step's last write (one
    /// thread's).
    #[inline(always)]
    pub fn post(&self, status: Status) {
        let step = self.tallied.get(0);
        self.statuses.set(step % self.statuses.len(), status);
        self.tallied.set(0, step.wrapping_add(1));
    }
}
