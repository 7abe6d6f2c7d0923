//! The game's accuracy in game terms: a scene played by the autopilot, every step's contacts
//! audited against an exact continuous-time check of the bodies' paths
//! ([`crate::sim::audit`]). The machines make the game chaotic, so two runs that differ in
//! anything drift apart: events are compared, not trajectories.

use super::{Game, Options, Scene};
use gpuwars_kernels::sim::Touched;

use crate::sim::audit::{Accuracy, Roles, StepEnd};
use crate::sim::{Snapshot, WorldSpec};
use crate::{Device, Error};

/// How long an audit plays: `warmup` steps unaudited (the field fills up), more until the
/// ship has fired (up to `busy_within`), then `steps` audited ones.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct AuditLength {
    /// Steps played before the audit starts.
    pub warmup: u32,
    /// Most steps played past the warm-up until the ship fires its first shot, so that a
    /// short audit sees shots meet enemies (0: none).
    pub busy_within: u32,
    /// Steps whose motion is audited.
    pub steps: u32,
}

/// A game's audit: its contacts, and what the player saw of them over the same steps.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct GameAudit {
    /// The contacts against the exact check.
    pub contacts: Accuracy,
    /// Shots the ship fired over the audited steps.
    pub shots_fired: u64,
    /// Enemies that died over them.
    pub kills: u64,
}

impl GameAudit {
    /// Enemies killed per shot fired, the player's figure of the contacts; `None` when no
    /// shot was fired.
    pub fn kills_per_shot(&self) -> Option<f64> {
        (self.shots_fired > 0).then(|| self.kills as f64 / self.shots_fired as f64)
    }
}

/// `scene` played from `seed` by the autopilot on `device`, the contacts of `length.steps`
/// steps audited after the warm-up (see [`AuditLength`]). The world keeps its bodies' paths for the audit
/// ([`crate::sim::Physics::trace_paths`]), which changes nothing it computes: the game is
/// the one `scene` plays, bit for bit. It stops early if the game ends. A step of contacts
/// denser than the contact log has room for plays the game again with room for them (the
/// same game, as the log's size changes nothing it computes).
pub fn audit_game(
    device: &Device,
    scene: &Scene,
    seed: u32,
    length: AuditLength,
) -> anyhow::Result<GameAudit> {
    let mut traced = scene.clone();
    traced.world.physics.trace_paths = true;
    loop {
        match audit_traced(device, &traced, seed, length) {
            Err(e) => match e.downcast_ref::<Error>() {
                Some(&Error::ContactLogFull { logged, room, .. }) => {
                    // The log holds fewer than twice its slots' room, so this much more
                    // room a slot holds what overflowed it.
                    let more = logged.div_ceil(room).next_power_of_two() * 2;
                    let physics = &mut traced.world.physics;
                    physics.log_room = u32::try_from(more)
                        .ok()
                        .and_then(|m| physics.log_room.checked_mul(m))
                        .ok_or(e)?;
                }
                _ => return Err(e),
            },
            audit => return audit,
        }
    }
}

/// [`audit_game`] of a scene whose world logs its contacts.
fn audit_traced(
    device: &Device,
    traced: &Scene,
    seed: u32,
    length: AuditLength,
) -> anyhow::Result<GameAudit> {
    let world = &traced.world;
    let index = |name: &str| world.kind_index(name).map(|k| k as u32);
    let roles = Roles::of(
        world,
        index(&traced.game.ship.kind),
        index(&traced.game.ship.shot),
    );
    let mut game = Game::with_options(device, traced, seed, Options::default())?;
    let mut fired = false;
    for _ in 0..length.warmup {
        game.submit(None)?;
        while let Some(status) = game.next_status()? {
            fired |= status.events.shots_fired > 0;
        }
    }
    for _ in 0..length.busy_within {
        if fired || game.status().is_over() {
            break;
        }
        fired = game.step(None)?.events.shots_fired > 0;
    }
    let start = game.snapshot()?;
    let cursor = game.pipeline().contact_log_cursor()?;
    let (mut shots_fired, mut kills) = (0, 0);
    let contacts = audit_steps(world, &roles, (start, cursor), length.steps, |since| {
        if game.status().is_over() {
            return anyhow::Ok(None);
        }
        let renumbered = game.pipeline().renumbers_next();
        let events = game.step(None)?.events;
        shots_fired += u64::from(events.shots_fired);
        kills += u64::from(events.kills);
        Ok(Some(Stepped {
            end: game.snapshot()?,
            log: game.pipeline().contact_log(since)?,
            renumbered,
        }))
    })?;
    Ok(GameAudit {
        contacts,
        shots_fired,
        kills,
    })
}

/// One step as the audit takes it.
#[derive(Clone, Debug)]
pub struct Stepped {
    /// Its end.
    pub end: Snapshot,
    /// The contacts its narrow phase logged, and the log's cursor after them (see
    /// [`crate::pipeline::Pipeline::contact_log`]).
    pub log: (Vec<Touched>, u32),
    /// Whether it moved bodies between slots before its narrow phase.
    pub renumbered: bool,
}

/// The audit of up to `steps` steps from the step end `start`, the contact log's cursor
/// then beside it: `step` plays one, given the cursor, and gives what it did, or `None` to
/// stop early.
pub fn audit_steps<E>(
    spec: &WorldSpec,
    roles: &Roles,
    (start, cursor): (Snapshot, u32),
    steps: u32,
    mut step: impl FnMut(u32) -> Result<Option<Stepped>, E>,
) -> Result<Accuracy, E> {
    let mut accuracy = Accuracy::default();
    let (mut this, mut cursor) = (start, cursor);
    for _ in 0..steps {
        let Some(next) = step(cursor)? else {
            break;
        };
        accuracy.add_step(
            spec,
            roles,
            &step_end(&this, &[], false),
            &step_end(&next.end, &next.log.0, next.renumbered),
        );
        (this, cursor) = (next.end, next.log.1);
    }
    Ok(accuracy)
}

/// A snapshot as the audit reads it, with the contacts its step's narrow phase logged;
/// `renumbered` if its step moved bodies between slots.
pub fn step_end<'a>(snapshot: &'a Snapshot, log: &'a [Touched], renumbered: bool) -> StepEnd<'a> {
    let b = &snapshot.bodies;
    StepEnd {
        alive: &b.alive,
        kind: &b.kind,
        prev: &b.prev,
        pos: &b.pos,
        vel: &b.vel,
        energy: &b.energy,
        log,
        renumbered,
    }
}
