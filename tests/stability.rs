//! Stability at the extremes: time steps from 10⁻⁵ s to the largest allowed, bodies fast
//! enough to cross a thin wall or several cells in a step, every body in one cell, bodies on
//! cell borders and world edges, worlds where f32 spacing matters, bodies on one spot,
//! extreme masses, kinds at capacity, random worlds under random physics choices, swept
//! contacts at the extremes (counted against an exact continuous-time audit), and an
//! opt-in hour of `paper` (`GPUWARS_SOAK=1`). `docs/stability.md` says what each
//! test checks.
//!
//! Every scenario ends in the same invariants ([`assert_invariants`]): every live body finite
//! and inside the world, every kind's live bodies and free slots adding up to its capacity,
//! its free list holding exactly its free slots; and in the same state hash when it is run
//! again, on one emulator thread, on three threads in a shuffled order, and (for the GPU
//! variant) on the CPU ([`same_everywhere`]). Expectations come from geometry and mechanics
//! worked out here (a brute-force pair count by plain distance, the tie-break's pushes, the
//! sampled path of a ball), not from the kernels.

mod common;

use std::collections::hash_map::DefaultHasher;
use std::fmt::Debug;
use std::hash::{Hash, Hasher};
use std::sync::OnceLock;

use common::sim::{circle, kind, rect, world};
use glam::{DVec2, Vec2};
use gpuwars::Device;
use gpuwars::backend::Schedule;
use gpuwars::game::accuracy::{Stepped, audit_steps};
use gpuwars::game::{Game, Scene};
use gpuwars::pipeline::Simulation;
use gpuwars::sim::audit::{Accuracy, Roles};
use gpuwars::sim::layout::{Layout, space};
use gpuwars::sim::spec::{MAX_MASS, MAX_SIDE, MIN_MASS};
use gpuwars::sim::{Boundary, Field, Integrator, KindSpec, Shape, Snapshot, Sweep, WorldSpec};
use proptest::prelude::*;

// ---------------------------------------------------------------------------------------
// Invariants, energy and determinism
// ---------------------------------------------------------------------------------------

/// The invariants every scenario ends with:
/// - every slot keeps its kind, and no padding slot is alive;
/// - each kind's live bodies plus its free count make its capacity, and its free list holds
///   exactly its free slots, in slot order;
/// - every live body's position, velocity, force and facing are finite, its position inside
///   the world (`[0, size]` when clamped, `[0, size)` when wrapped), its mass its kind's.
fn assert_invariants(spec: &WorldSpec, s: &Snapshot) {
    let layout = Layout::new(spec);
    assert_eq!(s.slots(), layout.slots as usize, "slots");
    assert_eq!(
        s.bodies.kind,
        layout.slot_kinds(),
        "every slot keeps its kind"
    );
    assert_eq!(
        s.free.count.len(),
        spec.kinds.len(),
        "one free count per kind"
    );
    for (k, range) in layout.ranges.iter().enumerate() {
        let (start, end) = (range.start as usize, range.end() as usize);
        let padded = start + range.capacity.next_multiple_of(32) as usize;
        assert!(
            s.bodies.alive[end..padded].iter().all(|&a| a == 0),
            "kind {k}: a padding slot is alive"
        );
        let free: Vec<u32> = (start..end)
            .filter(|&i| s.bodies.alive[i] == 0)
            .map(|i| i as u32)
            .collect();
        let alive = range.capacity as usize - free.len();
        assert_eq!(
            alive + s.free.count[k] as usize,
            range.capacity as usize,
            "kind {k}: {alive} alive and {} free in {} slots",
            s.free.count[k],
            range.capacity
        );
        assert_eq!(
            &s.free.list[start..start + free.len()],
            free.as_slice(),
            "kind {k}'s free list"
        );
    }
    for slot in s.live() {
        let (p, v) = (s.bodies.pos[slot], s.bodies.vel[slot]);
        assert!(
            p.is_finite() && v.is_finite(),
            "slot {slot}: position {p}, velocity {v}"
        );
        assert!(
            s.bodies.force[slot].is_finite() && s.bodies.dir[slot].is_finite(),
            "slot {slot}: force {}, facing {}",
            s.bodies.force[slot],
            s.bodies.dir[slot]
        );
        let inside = match spec.boundary {
            Boundary::Clamp => p.cmpge(Vec2::ZERO).all() && p.cmple(spec.size).all(),
            Boundary::Wrap => p.cmpge(Vec2::ZERO).all() && p.cmplt(spec.size).all(),
        };
        assert!(inside, "slot {slot} at {p} is outside {}", spec.size);
        let mass = spec.kinds[s.bodies.kind[slot] as usize].mass;
        assert_eq!(
            s.bodies.mass[slot].to_bits(),
            mass.to_bits(),
            "slot {slot}'s mass"
        );
    }
}

/// Kinetic energy of the movable live bodies, in f64 (a mass of 10³⁰ at any speed would
/// overflow f32).
fn kinetic(s: &Snapshot) -> f64 {
    s.live()
        .filter(|&i| s.bodies.mass[i].is_finite())
        .map(|i| 0.5 * f64::from(s.bodies.mass[i]) * s.bodies.vel[i].as_dvec2().length_squared())
        .sum()
}

/// Total momentum of the movable live bodies, and the sum of its terms' sizes (the scale
/// against which rounding is judged).
fn momentum(s: &Snapshot) -> (DVec2, f64) {
    s.live()
        .filter(|&i| s.bodies.mass[i].is_finite())
        .map(|i| f64::from(s.bodies.mass[i]) * s.bodies.vel[i].as_dvec2())
        .fold((DVec2::ZERO, 0.0), |(p, size), m| {
            (p + m, size + m.length())
        })
}

/// The emulator on one thread, blocks and threads in order.
fn one_thread() -> &'static Device {
    static DEVICE: OnceLock<Device> = OnceLock::new();
    DEVICE.get_or_init(|| Device::cpu(Some(1), "tests").unwrap())
}

/// The emulator on three threads, every launch's blocks and threads in a shuffled order.
fn shuffled() -> &'static Device {
    static DEVICE: OnceLock<Device> = OnceLock::new();
    DEVICE.get_or_init(|| {
        Device::cpu_scheduled(Some(3), Schedule::Shuffled { seed: 0x5eed }, "tests").unwrap()
    })
}

/// Runs `run` on `device` twice, then on one emulator thread and on three shuffled ones (the
/// CPU variant) or on the CPU emulation (the GPU variant): every run must give the same
/// result (a state hash, usually with what the scenario measured). Returns it.
fn same_everywhere<T: PartialEq + Debug>(device: &Device, run: impl Fn(&Device) -> T) -> T {
    let first = run(device);
    assert_eq!(run(device), first, "the same run twice");
    let others: Vec<(&str, &Device)> = if device.cpu_threads().is_some() {
        vec![("one thread", one_thread()), ("shuffled", shuffled())]
    } else {
        vec![("the CPU", common::cpu())]
    };
    for (name, other) in others {
        assert_eq!(run(other), first, "on {name}");
    }
    first
}

/// A short digest of a snapshot: its state hash and a hash of its contact counts.
fn digest(s: &Snapshot) -> (u64, u64) {
    let mut h = DefaultHasher::new();
    s.contacts.hash(&mut h);
    (s.state_hash(), h.finish())
}

/// The shortest displacement from `a` to `b` in f64 (across the seams of a wrapping world).
fn offset(spec: &WorldSpec, a: Vec2, b: Vec2) -> DVec2 {
    let d = (b - a).as_dvec2();
    if spec.boundary == Boundary::Clamp {
        return d;
    }
    let size = spec.size.as_dvec2();
    let short = |d: f64, period: f64| {
        if d > period / 2.0 {
            d - period
        } else if d < -period / 2.0 {
            d + period
        } else {
            d
        }
    };
    DVec2::new(short(d.x, size.x), short(d.y, size.y))
}

/// Contacts per slot by brute force over every pair of live circles, by plain distance:
/// two circles overlap when their centres are closer than the sum of their radii (touching
/// is not overlapping). Panics if a pair is so close to touching, without touching exactly,
/// that f32 rounding could decide it (the scenario would be ambiguous, not the kernels
/// wrong): nearby f32 positions subtract exactly, so the kernels' squared distance is off by
/// three roundings at most, under 1.8·10⁻⁷ of it; a gap under 4·10⁻⁷ of the reach² is
/// ambiguous. (A pair the narrow phase has just resolved sits at the contact distance up to
/// rounding, a few parts in 10⁷ away, so a tolerance much larger would call such pairs
/// ambiguous.)
fn circle_contacts(spec: &WorldSpec, s: &Snapshot) -> Vec<u32> {
    let masks = spec.collision_masks();
    let radius = |slot: usize| match spec.kinds[s.bodies.kind[slot] as usize].shape {
        Shape::Circle { radius } => f64::from(radius),
        Shape::Rect { .. } => panic!("circles only"),
    };
    let live: Vec<usize> = s.live().collect();
    let mut count = vec![0u32; s.slots()];
    for &a in &live {
        for &b in &live {
            let (ka, kb) = (s.bodies.kind[a] as usize, s.bodies.kind[b] as usize);
            if a == b || masks[ka] & (1 << kb) == 0 {
                continue;
            }
            let reach = radius(a) + radius(b);
            let dist2 = offset(spec, s.bodies.pos[a], s.bodies.pos[b]).length_squared();
            let gap = (dist2 - reach * reach).abs();
            assert!(
                gap == 0.0 || gap > 4e-7 * reach * reach,
                "slots {a} and {b} are {} apart, too close to touching ({reach}) to tell",
                dist2.sqrt()
            );
            count[a] += u32::from(dist2 < reach * reach);
        }
    }
    count
}

/// Asserts that the contacts the step counted are the expected ones, naming the first slots
/// that differ.
fn assert_contacts(got: &[u32], expected: &[u32], what: &str) {
    let wrong: Vec<String> = (0..got.len())
        .filter(|&i| got[i] != expected[i])
        .map(|i| format!("slot {i}: {} instead of {}", got[i], expected[i]))
        .collect();
    assert!(
        wrong.is_empty(),
        "{what}: {} slots counted the wrong contacts, e.g. {:?}",
        wrong.len(),
        &wrong[..wrong.len().min(8)]
    );
}

/// A colliding gas: `n` circles of radius 5, restitution 0.5, in a 400 × 400 box.
fn gas(n: u32, boundary: Boundary, dt: f32) -> WorldSpec {
    let mut spec = world(
        Vec2::splat(400.0),
        boundary,
        vec![kind("b", circle(5.0), n, &["b"])],
    );
    spec.dt = dt;
    spec
}

// ---------------------------------------------------------------------------------------
// 1. Time steps
// ---------------------------------------------------------------------------------------

/// Time steps from 10⁻⁵ s to the largest allowed.
const TIME_STEPS: [f32; 7] = [1.0e-5, 1.0e-4, 1.0e-3, 1.0 / 60.0, 0.1, 0.5, 1.0];

/// A gas of 256 bodies at 100 units/s per axis (about 100 units, a quarter of the box, in
/// a step of 1 s) is stepped 20 times at every time step, wrapped and clamped. Every step:
/// the invariants; contacts happen; the kinetic energy never exceeds its start (collisions
/// of restitution 0.5 lose energy, pushes move bodies without changing their velocity, and
/// walls only take velocity away); on the wrapping world (no walls, no field, no cap, equal
/// masses) the total momentum is conserved up to rounding. Each run gives the same hash on
/// every schedule.
fn every_time_step_keeps_a_colliding_world_finite_inside_and_bounded(device: &Device) {
    for boundary in [Boundary::Wrap, Boundary::Clamp] {
        for dt in TIME_STEPS {
            let spec = gas(256, boundary, dt);
            same_everywhere(device, |device| {
                let mut sim = Simulation::new(device, &spec, 7).unwrap();
                sim.scatter(0, 256, 100.0).unwrap();
                let start = sim.snapshot().unwrap();
                let (energy, (p0, scale)) = (kinetic(&start), momentum(&start));
                let mut touched = 0u32;
                for step in 1..=20 {
                    sim.step().unwrap();
                    let s = sim.snapshot().unwrap();
                    assert_invariants(&spec, &s);
                    assert_eq!(s.live().count(), 256);
                    touched += s.contacts.iter().sum::<u32>();
                    let e = kinetic(&s);
                    assert!(
                        e <= energy * (1.0 + 1e-6),
                        "{boundary:?}, dt {dt}, step {step}: kinetic energy {e} > {energy}"
                    );
                    if boundary == Boundary::Wrap {
                        let drift = (momentum(&s).0 - p0).length();
                        assert!(
                            drift <= 1e-6 * scale,
                            "dt {dt}, step {step}: momentum drifted by {drift} (of {scale})"
                        );
                    }
                }
                assert!(touched > 0, "{boundary:?}, dt {dt}: nothing collided");
                sim.state_hash().unwrap()
            });
        }
    }
}

// ---------------------------------------------------------------------------------------
// 2. Fast bodies
// ---------------------------------------------------------------------------------------

/// Where the ball starts, and the wall's middle.
const BALL_X: f32 = 287.3;
const WALL_X: f32 = 500.0;

/// Whether the ball of [`ball_at_a_wall`] is stopped by the wall, from its sampled path:
/// the narrow phase sees the ball only where a substep leaves it, `BALL_X + k·s` with
/// `s = speed·dt / substeps`. It is pushed back (and its velocity turned round) if one of
/// those places overlaps the wall on the near side of its middle,
/// `WALL_X - half - radius < x < WALL_X`; past the middle the push sends it on through.
fn predicted_stop(speed: f64, dt: f64, substeps: u32, half: f64, radius: f64) -> bool {
    let s = speed * dt / f64::from(substeps);
    let (near, middle) = (f64::from(WALL_X) - half - radius, f64::from(WALL_X));
    let path = (0..).map(|k| f64::from(BALL_X) + k as f64 * s);
    for x in path.take_while(|&x| x < middle + half + radius) {
        assert!(
            (x - near).abs() > 1e-3 && (x - middle).abs() > 1e-3,
            "{substeps} substeps: the path passes {x}, too close to an edge to tell"
        );
        if x > near && x < middle {
            return true;
        }
    }
    false
}

/// A ball of radius `radius` fired along +x at `speed` at an immovable wall `2·half` thick
/// (restitution 1), with `substeps`; returns the ball's position and velocity after 8 steps
/// of 1/60 s (the ball reaches the wall in its 5th).
fn ball_at_a_wall(
    device: &Device,
    speed: f32,
    (half, radius): (f32, f32),
    substeps: u32,
    sweep: Sweep,
) -> (Vec2, Vec2, u64) {
    let mut ball = kind("ball", circle(radius), 1, &["wall"]);
    ball.restitution = 1.0;
    // Its speed exactly: the limit changes nothing, and sizes the swept test's reach.
    ball.max_speed = speed;
    ball.sweep = sweep;
    let mut wall = kind("wall", rect(half, 300.0), 1, &[]);
    wall.mass = f32::INFINITY;
    let mut spec = world(Vec2::splat(1000.0), Boundary::Clamp, vec![ball, wall]);
    spec.physics.substeps = substeps;
    let mut sim = Simulation::new(device, &spec, 1).unwrap();
    let wall_slot = sim.layout().ranges[1].start;
    sim.place(&[
        (0, Vec2::new(BALL_X, 500.0), Vec2::new(speed, 0.0)),
        (wall_slot, Vec2::new(WALL_X, 500.0), Vec2::ZERO),
    ])
    .unwrap();
    for _ in 0..8 {
        sim.step().unwrap();
    }
    let s = sim.snapshot().unwrap();
    assert_invariants(&spec, &s);
    assert_eq!(
        s.bodies.pos[wall_slot as usize],
        Vec2::new(WALL_X, 500.0),
        "the wall moved"
    );
    (s.bodies.pos[0], s.bodies.vel[0], s.state_hash())
}

/// Tunnelling, measured: a ball of radius 1 at 3,000 units/s (50 units a step, 33 times the
/// 1.5 units in which it can be caught) against a wall 1 unit thick. With one substep it
/// passes through; with `n` substeps it is stopped exactly when its sampled path predicts
/// ([`predicted_stop`]), for every `n` up to a few past `⌈speed·dt / (half + radius)⌉`, the
/// count from which no path can skip the catching zone (a substep moves it less than the
/// zone is long). A stopped ball comes back at the speed it came (restitution 1); one that
/// tunnelled is beyond the wall.
fn tunnelling_through_a_thin_wall_stops_at_the_predicted_substeps(device: &Device) {
    let (speed, half, radius, dt) = (3000.0f32, 0.5f32, 1.0f32, 1.0f32 / 60.0);
    let needed = (f64::from(speed) * f64::from(dt) / f64::from(half + radius)).ceil() as u32;
    assert_eq!(needed, 34);
    let mut tunnelled = Vec::new();
    for substeps in 1..=needed + 4 {
        let expected = predicted_stop(
            speed.into(),
            dt.into(),
            substeps,
            half.into(),
            radius.into(),
        );
        let (pos, vel, _) = ball_at_a_wall(device, speed, (half, radius), substeps, Sweep::Off);
        if expected {
            assert!(
                pos.x < WALL_X && vel == Vec2::new(-speed, 0.0),
                "{substeps} substeps: expected a stop, the ball is at {pos} moving {vel}"
            );
        } else {
            assert!(
                pos.x > WALL_X,
                "{substeps} substeps: expected tunnelling, the ball is at {pos}"
            );
            tunnelled.push(substeps);
        }
        if substeps >= needed {
            assert!(expected, "{substeps} substeps must catch the ball");
        }
    }
    assert_eq!(tunnelled.first(), Some(&1), "one substep tunnels");
    eprintln!(
        "tunnelled with {tunnelled:?} substeps of 1..={}",
        needed + 4
    );
    same_everywhere(device, |device| {
        ball_at_a_wall(device, speed, (half, radius), needed, Sweep::Off).2
    });
}

/// The thin wall of [`tunnelling_through_a_thin_wall_stops_at_the_predicted_substeps`] with
/// the ball's contacts swept: every substep count stops it, since the swept test finds the
/// contact wherever the sampled path skips it. The ball comes back at the speed it came,
/// on the near side, and the result is the same on every backend and schedule.
fn a_swept_ball_never_tunnels_through_a_thin_wall(device: &Device) {
    let (speed, half, radius) = (3000.0f32, 0.5f32, 1.0f32);
    for substeps in 1..=38 {
        let (pos, vel, _) = ball_at_a_wall(device, speed, (half, radius), substeps, Sweep::On);
        assert!(
            pos.x < WALL_X && vel == Vec2::new(-speed, 0.0),
            "{substeps} substeps, swept: expected a stop, the ball is at {pos} moving {vel}"
        );
    }
    same_everywhere(device, |device| {
        ball_at_a_wall(device, speed, (half, radius), 1, Sweep::On).2
    });
}

/// A gas of 500 small bodies (radius 2: cells of about 4 units) at 3,000 units/s per axis,
/// about 12 cells a step: the grid still finds every contact the pairs' distances say,
/// every step, wrapped and clamped.
fn bodies_crossing_many_cells_a_step_lose_no_contact(device: &Device) {
    for boundary in [Boundary::Wrap, Boundary::Clamp] {
        let spec = world(
            Vec2::splat(200.0),
            boundary,
            vec![kind("b", circle(2.0), 500, &["b"])],
        );
        let cell = spec.size.x / space(&spec).cols as f32;
        assert!(3000.0 * spec.dt > 10.0 * cell);
        same_everywhere(device, |device| {
            let mut sim = Simulation::new(device, &spec, 3).unwrap();
            sim.scatter(0, 500, 3000.0).unwrap();
            let mut found = 0;
            for _ in 0..10 {
                let before = sim.snapshot().unwrap();
                sim.step().unwrap();
                let after = sim.snapshot().unwrap();
                assert_invariants(&spec, &after);
                assert_contacts(
                    &after.contacts,
                    &circle_contacts(&spec, &before),
                    &format!("{boundary:?}"),
                );
                found += after.contacts.iter().sum::<u32>();
            }
            assert!(found > 0, "{boundary:?}: no contact to find");
            sim.state_hash().unwrap()
        });
    }
}

/// The kinds of the swept scenarios: shots (radius 2, swept, at most `shot_speed`) and
/// enemies (radius 5) that collide with them and with walls (rectangles of half extents 1
/// by 50, immovable), in a clamped 2000 × 2000 world with time step `dt`, paths traced.
fn swept_world(shot_speed: f32, dt: f32) -> WorldSpec {
    let mut shot = kind("shot", circle(2.0), 64, &["enemy", "wall"]);
    shot.max_speed = shot_speed;
    shot.sweep = Sweep::On;
    shot.restitution = 1.0;
    let mut enemy = kind("enemy", circle(5.0), 64, &["wall"]);
    enemy.max_speed = 100.0;
    let mut wall = kind("wall", rect(1.0, 50.0), 8, &[]);
    wall.mass = f32::INFINITY;
    let mut spec = world(
        Vec2::splat(2000.0),
        Boundary::Clamp,
        vec![shot, enemy, wall],
    );
    spec.dt = dt;
    spec
}

/// `spec`'s world with `bodies` placed (kind, position, velocity, each kind's slots in
/// order), stepped `steps` times, each step's contacts logged and audited against the exact
/// check of `gpuwars::sim::audit` (independent of the kernels); the audit and the final
/// digest.
fn audited(
    device: &Device,
    spec: &WorldSpec,
    bodies: &[(usize, Vec2, Vec2)],
    steps: u32,
) -> (Accuracy, (u64, u64)) {
    audited_with(device, spec, bodies, steps, |_| {})
}

/// [`audited`], with `check` given every step's end.
fn audited_with(
    device: &Device,
    spec: &WorldSpec,
    bodies: &[(usize, Vec2, Vec2)],
    steps: u32,
    mut check: impl FnMut(&Snapshot),
) -> (Accuracy, (u64, u64)) {
    let mut logged = spec.clone();
    logged.physics.trace_paths = true;
    let spec = &logged;
    let mut sim = Simulation::new(device, spec, 1).unwrap();
    let mut next_slot = sim
        .layout()
        .ranges
        .iter()
        .map(|r| r.start)
        .collect::<Vec<_>>();
    let placed: Vec<(u32, Vec2, Vec2)> = bodies
        .iter()
        .map(|&(k, pos, vel)| {
            next_slot[k] += 1;
            (next_slot[k] - 1, pos, vel)
        })
        .collect();
    sim.place(&placed).unwrap();
    // Kind 0 shoots at kind 1; kind 2 is the walls (where there is one).
    let roles = Roles {
        ship: None,
        shot: Some(0),
        enemies: 1 << 1,
        walls: 1 << 2,
    };
    let start = sim.snapshot().unwrap();
    let cursor = sim.contact_log_cursor().unwrap();
    let mut last = digest(&start);
    let accuracy = audit_steps(spec, &roles, (start, cursor), steps, |since| {
        let renumbered = sim.renumbers_next();
        sim.step()?;
        let end = sim.snapshot()?;
        assert_invariants(spec, &end);
        check(&end);
        last = digest(&end);
        let log = sim.contact_log(since)?;
        Ok::<_, gpuwars::Error>(Some(Stepped {
            end,
            log,
            renumbered,
        }))
    })
    .unwrap();
    (accuracy, last)
}

/// Every contact the exact check is sure of was counted with its partner at its moment,
/// and nothing was counted that it is sure did not happen: the kernels' contacts are the
/// audit's, pair by pair, but for the grazing pairs f32 cannot decide.
fn assert_exact(case: &str, a: &Accuracy) {
    let t = a.all;
    assert_eq!(
        (t.missed, t.extra, t.wrong_partner, t.late),
        (0, 0, 0, 0),
        "{case}: missed, extra, wrong partner or late contacts ({t:?})"
    );
}

/// Swept shots at the extremes, each case's contacts counted exactly as the audit finds
/// them (and its expected count worked out here where the geometry is plain):
/// - grazing passes: shots at 3,000 units/s (50 a step) crossing enemies at lateral offsets
///   on both sides of the contact distance 7 (6.9, 6.99, 6.999; 7; 7.001, 7.01, 7.1): the
///   first three are contacts (sure ones), 7 touches without overlapping, the rest miss;
/// - a shot exactly on a wall's face, at rest and sliding along it: touching, no contact;
///   half a unit into it: a contact, which pushes it out to touching;
/// - zero relative speed: a shot and an enemy moving together at 90 units/s, overlapping
///   (a contact every step) or 7.5 apart (none);
/// - a shot born inside an enemy: a contact at once;
/// - the largest time step (1 s), shots at 500 units a step through enemies;
/// - shots at exactly their speed limit.
///
/// The same digests everywhere.
fn swept_contacts_at_the_extremes_are_counted_exactly(device: &Device) {
    let fast = Vec2::new(3000.0, 0.0);
    same_everywhere(device, |device| {
        let mut digests = Vec::new();
        // Grazing passes: seven lanes 100 apart, each a shot starting 25 left of its enemy.
        let spec = swept_world(3000.0, 1.0 / 60.0);
        let offsets = [6.9f32, 6.99, 6.999, 7.0, 7.001, 7.01, 7.1];
        let mut bodies = Vec::new();
        for (i, &dy) in offsets.iter().enumerate() {
            let y = 200.0 + 100.0 * i as f32;
            bodies.push((0, Vec2::new(475.0, y + dy), fast));
            bodies.push((1, Vec2::new(500.0, y), Vec2::ZERO));
        }
        let (a, d) = audited(device, &spec, &bodies, 3);
        assert_exact("grazing", &a);
        assert_eq!(a.classes["shot→enemy"].expected, 3, "grazing: {a:?}");
        assert_eq!(a.classes["shot→enemy"].tunnelling, 3, "grazing: {a:?}");
        digests.push(d);

        // On a wall's face (the wall at x = 1000, faces at 999 and 1001; a shot of radius
        // 2 touches the face from 997): at rest, sliding along, and half a unit in.
        let spec = swept_world(100.0, 1.0 / 60.0);
        let bodies = [
            (2, Vec2::new(1000.0, 1000.0), Vec2::ZERO),
            (0, Vec2::new(997.0, 980.0), Vec2::ZERO),
            (0, Vec2::new(997.0, 1000.0), Vec2::new(0.0, 60.0)),
            (0, Vec2::new(1002.5, 1010.0), Vec2::ZERO),
        ];
        let (a, d) = audited(device, &spec, &bodies, 4);
        assert_exact("on a wall", &a);
        assert!(a.classes["body→wall"].expected >= 1, "on a wall: {a:?}");
        digests.push(d);

        // Zero relative speed.
        let with = Vec2::new(90.0, 0.0);
        let bodies = [
            (0, Vec2::new(100.0, 100.0), with),
            (1, Vec2::new(106.0, 100.0), with),
            (0, Vec2::new(100.0, 300.0), with),
            (1, Vec2::new(107.5, 300.0), with),
        ];
        let (a, d) = audited(device, &spec, &bodies, 4);
        assert_exact("moving together", &a);
        assert!(
            a.classes["shot→enemy"].expected >= 1,
            "moving together: {a:?}"
        );
        assert_eq!(
            a.classes["shot→enemy"].tunnelling, 0,
            "moving together: {a:?}"
        );
        digests.push(d);

        // Born inside an enemy.
        let bodies = [
            (1, Vec2::new(700.0, 700.0), Vec2::ZERO),
            (0, Vec2::new(701.0, 700.0), Vec2::new(100.0, 0.0)),
        ];
        let (a, d) = audited(device, &spec, &bodies, 2);
        assert_exact("born inside", &a);
        assert!(a.classes["shot→enemy"].expected >= 1, "born inside: {a:?}");
        digests.push(d);

        // The largest time step, and shots at their speed limit.
        for (dt, speed) in [(1.0, 500.0), (1.0 / 60.0, 3000.0)] {
            let spec = swept_world(speed, dt);
            let bodies: Vec<_> = (0..20)
                .flat_map(|i| {
                    let y = 100.0 + 90.0 * i as f32;
                    let lane = (i % 7) as f32;
                    [
                        (0, Vec2::new(300.0, y + lane), Vec2::new(speed, 0.0)),
                        (
                            1,
                            Vec2::new(300.0 + speed * dt * 0.5 + 3.0 * lane, y),
                            Vec2::ZERO,
                        ),
                    ]
                })
                .collect();
            let (a, d) = audited(device, &spec, &bodies, 3);
            assert_exact(&format!("dt {dt}, {speed} units/s"), &a);
            assert!(a.classes["shot→enemy"].tunnelling >= 10, "dt {dt}: {a:?}");
            digests.push(d);
        }
        digests
    });
}

/// A shot left touching a crate's corner (as `arena` left one, to the last bit) and moving
/// off along the tangent, which f32 sees closing in by a rounding while the velocities do
/// not approach: the contact moves nothing, and the shot goes on its way at its speed every
/// step (it was put back where it began, step after step, frozen until its lifetime ran out).
fn a_shot_grazing_a_corner_is_not_frozen(device: &Device) {
    let mut shot = kind("shot", circle(2.0), 32, &["crate"]);
    shot.max_speed = 650.0;
    shot.sweep = Sweep::On;
    shot.mass = 0.1;
    let mut crate_kind = kind("crate", rect(24.0, 12.0), 32, &[]);
    crate_kind.mass = f32::INFINITY;
    let mut spec = world(Vec2::splat(1024.0), Boundary::Wrap, vec![shot, crate_kind]);
    spec.dt = 1.0 / 120.0;
    let vel = Vec2::new(-228.28195, -0.024383143);
    let bodies = [
        (1, Vec2::new(348.8497, 913.1666), Vec2::ZERO),
        (0, Vec2::new(324.8499, 899.1666), vel),
    ];
    let mut last = Vec2::new(324.8499, 899.1666);
    let (a, _) = audited_with(device, &spec, &bodies, 8, |end| {
        let at = end.bodies.prev[0];
        let moved = (at - last).length();
        assert!(
            moved > 0.99 * vel.length() * spec.dt || end.steps == 1,
            "frozen at {at}"
        );
        last = at;
    });
    assert_exact("grazing a corner", &a);
}

/// The pile's wall: its centre, and its half extents.
const PILE_WALL: (Vec2, Vec2) = (Vec2::new(1500.0, 1000.0), Vec2::new(4.0, 600.0));

/// A pile: 256 enemies (radius 5, colliding with each other) in a block pressed against a
/// wall, and 64 swept shots (radius 2, restitution 1) fired into them at 2,400 units/s (40
/// units a step, ten times the wall's half thickness), in a wrapping world, for 2,000
/// steps: the shots bounce between the crowd and both faces of the wall (round the world's
/// seam) and through the crowd as it scatters. Where each step's contacts have been
/// resolved: no shot lies inside the wall by more than rounding (a swept shot is put back
/// where it began to touch, never into it), and none has crossed it; and the swept
/// contacts are exactly the audit's: none missed, none counted twice or with the wrong body,
/// none late.
fn a_pile_of_swept_bodies_against_a_wall_stays_exact(device: &Device) {
    let mut shot = kind("shot", circle(2.0), 64, &["enemy", "wall", "shot"]);
    shot.max_speed = 2400.0;
    shot.sweep = Sweep::On;
    shot.restitution = 1.0;
    shot.mass = 0.1;
    let mut enemy = kind("enemy", circle(5.0), 256, &["enemy", "wall"]);
    enemy.max_speed = 600.0;
    let (centre, half) = PILE_WALL;
    let mut wall = kind("wall", rect(half.x, half.y), 1, &[]);
    wall.mass = f32::INFINITY;
    let spec = world(Vec2::splat(2000.0), Boundary::Wrap, vec![shot, enemy, wall]);
    let mut bodies = vec![(2, centre, Vec2::ZERO)];
    for i in 0..256 {
        let (col, row) = ((i % 8) as f32, (i / 8) as f32);
        let at = Vec2::new(centre.x - half.x - 5.0 - 10.5 * col, 830.0 + 10.5 * row);
        bodies.push((1, at, Vec2::new(60.0, 0.0)));
    }
    for i in 0..64 {
        let y = 830.0 + 5.3 * i as f32;
        bodies.push((
            0,
            Vec2::new(600.0, y),
            Vec2::new(2400.0, 13.0 * (i % 7) as f32),
        ));
    }
    // Which side of the wall each shot was on, where it was level with the wall.
    let mut side = [0.0f32; 64];
    let mut deepest = f32::NEG_INFINITY;
    let (a, _) = audited_with(device, &spec, &bodies, 2000, |end| {
        let b = &end.bodies;
        // A step's end is where its integration left the bodies, before the next narrow
        // phase resolves them; `prev` is where the last one left them.
        for s in (0..64).filter(|&s| b.alive[s] != 0) {
            let d = b.prev[s] - centre;
            if d.y.abs() >= half.y + 2.0 {
                side[s] = 0.0;
                continue;
            }
            // Its depth into the wall grown by its radius (rounded corners ignored: the
            // shots that matter meet the faces).
            deepest = deepest.max((half + 2.0 - d.abs()).min_element());
            // Only round the seam, 500 units from the wall, may a shot change sides.
            let now = d.x.signum();
            assert!(
                side[s] * now >= 0.0 || d.x.abs() > 400.0,
                "shot {s} crossed the wall to {}",
                b.prev[s]
            );
            side[s] = now;
        }
    });
    eprintln!("pile: {a:?}; deepest shot into the wall {deepest}");
    let s = &a.swept;
    assert_eq!(
        (s.missed, s.extra, s.wrong_partner, s.late),
        (0, 0, 0, 0),
        "pile: swept pairs {s:?}"
    );
    let wall_hits = a.classes["body→wall"];
    assert!(
        s.expected > 1000 && s.tunnelling > 100,
        "pile: too few swept contacts {s:?}"
    );
    assert!(
        wall_hits.expected > 100,
        "pile: too few at the wall {wall_hits:?}"
    );
    // f32 spacing at x = 1500 is 1.2e-4: a few units in the last place at most.
    assert!(deepest < 1e-3, "a shot {deepest} into the wall");
}

/// A million still bodies (radius 1, on a grid 3 apart) crossed by 256 swept shots at
/// 3,000 units/s in a wrapping world: every contact the exact check finds is counted, on
/// the CPU and the GPU alike.
fn a_million_bodies_under_swept_shots_are_counted_exactly(device: &Device) {
    let side = 1024u32;
    let mut shot = kind("shot", circle(1.0), 256, &["dust"]);
    shot.max_speed = 3000.0;
    shot.sweep = Sweep::On;
    let dust = kind("dust", circle(1.0), side * side, &[]);
    let mut spec = world(
        Vec2::splat(3.0 * side as f32),
        Boundary::Wrap,
        vec![shot, dust],
    );
    // Bodies stay in their slots, so that every step is audited.
    spec.physics.renumber_every = Some(0);
    let mut bodies: Vec<(usize, Vec2, Vec2)> = (0..side * side)
        .map(|i| {
            let (x, y) = ((i % side) as f32, (i / side) as f32);
            (1, Vec2::new(3.0 * x + 1.5, 3.0 * y + 1.5), Vec2::ZERO)
        })
        .collect();
    for i in 0..256 {
        let y = 12.0 * i as f32 + 1.5 + 0.37 * (i % 5) as f32;
        bodies.push((0, Vec2::new(5.0, y), Vec2::new(3000.0, 40.0)));
    }
    let run = |device: &Device| audited(device, &spec, &bodies, 2);
    let (a, d) = run(device);
    assert_exact("a million bodies", &a);
    assert!(a.all.tunnelling > 1000, "{:?}", a.all);
    if device.cpu_threads().is_none() {
        assert_eq!(run(common::cpu()), (a, d), "the GPU's counts are the CPU's");
    }
}

// ---------------------------------------------------------------------------------------
// 3. Every body in one cell
// ---------------------------------------------------------------------------------------

/// 4,096 bodies of radius 4 on one spot of a clamped 20,000 × 20,000 world, stepped `steps`
/// times (the invariants and the cap checked after each step).
fn crowd(device: &Device, cap: u32, averaged: bool, relaxation: f32, steps: u32) -> Snapshot {
    budgeted_crowd(device, (cap, 0), averaged, relaxation, steps)
}

/// [`crowd`] with a contact budget as well: `bounds` is `(neighbour_cap, contact_budget)`.
fn budgeted_crowd(
    device: &Device,
    (cap, budget): (u32, u32),
    averaged: bool,
    relaxation: f32,
    steps: u32,
) -> Snapshot {
    let n = 4096;
    let mut spec = world(
        Vec2::splat(20_000.0),
        Boundary::Clamp,
        vec![kind("b", circle(CROWD_RADIUS), n, &["b"])],
    );
    spec.physics.neighbour_cap = cap;
    spec.physics.contact_budget = budget;
    spec.physics.averaged = averaged;
    spec.physics.relaxation = relaxation;
    let mut sim = Simulation::new(device, &spec, 1).unwrap();
    let all: Vec<_> = (0..n).map(|s| (s, CROWD_AT, Vec2::ZERO)).collect();
    sim.place(&all).unwrap();
    for _ in 0..steps {
        sim.step().unwrap();
        let s = sim.snapshot().unwrap();
        assert_invariants(&spec, &s);
        if cap != 0 {
            let most = s.contacts.iter().copied().max().unwrap();
            assert!(
                most <= cap,
                "a body counted {most} contacts, past the cap {cap}"
            );
        }
    }
    sim.snapshot().unwrap()
}

/// Radius and spot of the crowd.
const CROWD_RADIUS: f32 = 4.0;
const CROWD_AT: Vec2 = Vec2::new(10_000.0, 10_000.0);

/// Where slot `slot` of the crowd is after one step, worked out from the tie-break: bodies
/// on one spot part along ±x, the lower slot towards −x, each contact pushing each body by
/// half the depth (`2r / 2 = r`). A query visits slots in increasing order and stops after
/// `cap` entries, so slot `s` meets slots `0..cap` (itself excluded) if `cap > 0`: those
/// below push it +r, those above −r. The pushes are summed, or averaged over the contacts,
/// then scaled by `relaxation`.
fn crowd_push(slot: u32, n: u32, cap: u32, averaged: bool, relaxation: f32) -> (u32, f32) {
    let seen = if cap == 0 { n } else { cap.min(n) };
    let (below, above) = if slot < seen {
        (slot, seen - 1 - slot)
    } else {
        (seen, 0)
    };
    let count = below + above;
    let sum = (below as f32 - above as f32) * CROWD_RADIUS;
    let push = if averaged && count > 1 {
        sum / count as f32
    } else {
        sum
    };
    (count, push * relaxation)
}

/// Every body in one cell. Without a cap each of the 4,096 bodies counts the other 4,095;
/// with a cap of 32, no body counts more than 32: the work of a crowded cell is bounded by
/// the cap. Summed pushes throw bodies 32 radii (the cap's 32 contacts, all the same way);
/// averaged and halved, no body moves more than half a radius, far less than the crowd's
/// diameter (one body's, 2r), a contrast of 64 times. Each slot's count and place are those
/// [`crowd_push`] works out.
fn a_crowded_cell_is_bounded_by_the_cap(device: &Device) {
    let n = 4096;
    let check = |s: &Snapshot, cap: u32, averaged: bool, relaxation: f32| -> f32 {
        let mut farthest = 0.0f32;
        for slot in 0..n {
            let (count, push) = crowd_push(slot, n, cap, averaged, relaxation);
            let i = slot as usize;
            assert_eq!(s.contacts[i], count, "slot {slot}'s contacts");
            let moved = s.bodies.pos[i] - CROWD_AT;
            let expected = Vec2::new(push, 0.0);
            assert!(
                (moved - expected).length() <= 1e-3,
                "slot {slot} moved {moved}, expected {expected}"
            );
            farthest = farthest.max(moved.length());
        }
        farthest
    };
    let uncapped = crowd(device, 0, false, 1.0, 1);
    assert!(uncapped.contacts.iter().all(|&c| c == n - 1));
    let summed = check(&crowd(device, 32, false, 1.0, 1), 32, false, 1.0);
    let relaxed = check(&crowd(device, 32, true, 0.5, 1), 32, true, 0.5);
    let diameter = 2.0 * CROWD_RADIUS;
    assert_eq!(summed, 32.0 * CROWD_RADIUS);
    assert!(relaxed <= diameter, "averaged: {relaxed}");
    assert_eq!(relaxed, CROWD_RADIUS / 2.0);
    assert!(
        summed >= 60.0 * relaxed,
        "summed {summed}, averaged {relaxed}"
    );
    eprintln!(
        "one step of 4,096 on a spot, cap 32: summed pushes move a body up to {summed}, averaged at 0.5 {relaxed}"
    );
    // Ten steps: the bodies stay at rest (pushes change no velocity, and bodies at rest do
    // not approach), so each step moves a body at most half the largest push (r / 2).
    let spread = same_everywhere(device, |device| {
        let s = crowd(device, 32, true, 0.5, 10);
        assert!(s.bodies.vel.iter().all(|&v| v == Vec2::ZERO));
        let spread = s
            .live()
            .map(|i| (s.bodies.pos[i] - CROWD_AT).length())
            .fold(0.0f32, f32::max);
        (s.state_hash(), spread.to_bits())
    });
    let spread = f32::from_bits(spread.1);
    assert!(
        spread <= 10.0 * CROWD_RADIUS / 2.0,
        "after 10 steps: {spread}"
    );
}

/// Slot `slot`'s weighted count of contacts in a crowd of `n` on one spot under a contact
/// budget of `budget`, and its averaged push, worked out from the sampling rule alone: the
/// crowd is one run of `n` entries in slot order, of which the slot takes every
/// `every = ⌈n / ⌈budget / 3⌉⌉`-th from `slot mod every` (itself among them), each contact
/// standing for `every`; below it `slot / every` of them push it +r, the others −r.
fn sampled_push(slot: u32, n: u32, budget: u32) -> (u32, f32) {
    let every = n.div_ceil(budget.div_ceil(3));
    let taken = (n - slot % every).div_ceil(every);
    let below = slot / every;
    let above = taken - 1 - below;
    let sum = (below as f32 - above as f32) * CROWD_RADIUS * every as f32;
    let count = every * (taken - 1);
    (count, sum / count as f32)
}

/// Every body in one cell under the contact budget: each of the 4,096 bodies tests 128 of
/// them (a stride of 32) instead of 4,096, and each contact found stands for 32, so the
/// weighted count (4,064) estimates the 4,095 a brute-force pass over the pairs counts to
/// within one stride. Each slot's count and (averaged) place are those [`sampled_push`]
/// works out from the rule; a budget the crowd fits in is the plain narrow phase, bit for bit; and the
/// sampled crowd is the same on every backend and schedule.
fn a_crowded_cell_is_bounded_by_the_contact_budget(device: &Device) {
    let n = 4096;
    let budget = 384;
    let s = budgeted_crowd(device, (0, budget), true, 1.0, 1);
    for slot in 0..n {
        let (count, push) = sampled_push(slot, n, budget);
        let i = slot as usize;
        assert_eq!(s.contacts[i], count, "slot {slot}'s contacts");
        assert!(count.abs_diff(n - 1) <= 32, "slot {slot}: {count}");
        let moved = s.bodies.pos[i] - CROWD_AT;
        let expected = Vec2::new(push, 0.0);
        assert!(
            (moved - expected).length() <= 1e-3,
            "slot {slot} moved {moved}, expected {expected}"
        );
    }
    let plain = digest(&budgeted_crowd(device, (0, 0), false, 1.0, 2));
    let roomy = digest(&budgeted_crowd(device, (0, 3 * n), false, 1.0, 2));
    assert_eq!(roomy, plain, "a budget the crowd fits in");
    same_everywhere(device, |device| {
        digest(&budgeted_crowd(device, (0, budget), true, 0.5, 3))
    });
}

// ---------------------------------------------------------------------------------------
// 4. Cell borders and world edges
// ---------------------------------------------------------------------------------------

/// A 120 × 120 world of circles of radius 3 (19 × 19 cells of 6.3 units): a body on every
/// cell corner, on both world edges (at `size` when clamped, at the largest f32 below it
/// when wrapped), and partners around each at distances clearly inside and outside the
/// contact distance (5.9 and 6.1 of 6), along both axes and the diagonal. The contacts the
/// step counts are those a brute-force pass over all pairs finds by plain distance.
fn contacts_on_cell_borders_and_world_edges_match_brute_force(device: &Device) {
    for boundary in [Boundary::Wrap, Boundary::Clamp] {
        let spec = world(
            Vec2::splat(120.0),
            boundary,
            vec![kind("b", circle(3.0), 2000, &["b"])],
        );
        let grid = space(&spec);
        let (cols, rows) = (grid.cols, grid.rows);
        let last = match boundary {
            Boundary::Clamp => spec.size.x,
            Boundary::Wrap => spec.size.x.next_down(),
        };
        let border = |i: u32, n: u32| {
            if i == n {
                last
            } else {
                i as f32 * spec.size.x / n as f32
            }
        };
        let mut places = Vec::new();
        for i in 0..=cols {
            for j in 0..=rows {
                let corner = Vec2::new(border(i, cols), border(j, rows));
                places.push(corner);
                // Partners every other corner, so that they do not crowd one another.
                if (i + j) % 2 == 0 {
                    for d in [
                        Vec2::new(5.9, 0.0),
                        Vec2::new(0.0, -6.1),
                        Vec2::new(-4.1, 4.1),
                    ] {
                        let p = corner + d;
                        let p = match boundary {
                            Boundary::Wrap => p.rem_euclid(spec.size),
                            Boundary::Clamp => p.clamp(Vec2::ZERO, spec.size),
                        };
                        places.push(if p.x >= spec.size.x && boundary == Boundary::Wrap {
                            Vec2::new(0.0, p.y)
                        } else {
                            p
                        });
                    }
                }
            }
        }
        assert!(places.len() <= 2000);
        let bodies: Vec<_> = places
            .iter()
            .enumerate()
            .map(|(s, &p)| (s as u32, p, Vec2::ZERO))
            .collect();
        let (contacts, expected) = same_everywhere(device, |device| {
            let mut sim = Simulation::new(device, &spec, 1).unwrap();
            sim.place(&bodies).unwrap();
            let before = sim.snapshot().unwrap();
            assert_invariants(&spec, &before);
            sim.step().unwrap();
            let after = sim.snapshot().unwrap();
            assert_invariants(&spec, &after);
            (after.contacts, circle_contacts(&spec, &before))
        });
        assert_contacts(&contacts, &expected, &format!("{boundary:?}"));
        let pairs: u32 = expected.iter().sum::<u32>() / 2;
        assert!(pairs > 100, "{boundary:?}: only {pairs} pairs");
    }
}

// ---------------------------------------------------------------------------------------
// 5. Where f32 spacing matters
// ---------------------------------------------------------------------------------------

/// Bodies near the far corner of worlds of the largest side, where f32 positions are 1/16
/// apart: the square world (10⁶ × 10⁶, cells of about 500 units) and a long one (10⁶ × 8, a
/// row of cells barely larger than the contact distance, where rounding is largest against
/// a cell). Pairs at the largest distance below the contact distance that f32 can hold
/// there (3.9375 of 4), at offsets that step across cell borders, pairs closing in on each
/// other, and pairs across the seam or on the edge itself: for 10 steps at 30 units/s (8
/// ulps a step) the contacts are those brute force finds, and everything stays finite and
/// inside.
fn where_f32_spacing_is_coarse_contacts_are_still_found(device: &Device) {
    for size in [Vec2::splat(MAX_SIDE), Vec2::new(MAX_SIDE, 8.0)] {
        for boundary in [Boundary::Wrap, Boundary::Clamp] {
            let spec = world(size, boundary, vec![kind("b", circle(2.0), 300, &["b"])]);
            let edge = match boundary {
                Boundary::Clamp => size.x,
                Boundary::Wrap => size.x - 1.0,
            };
            let y = size.y.min(999_990.0) / 2.0;
            let mut bodies = Vec::new();
            let mut add = |p: Vec2, v: Vec2| bodies.push((bodies.len() as u32, p, v));
            for i in 0..90 {
                // 20.0625 apart: the pairs drift across the cells' borders.
                let a = Vec2::new(998_000.0 + 20.0625 * i as f32, y);
                add(a, Vec2::new(30.0, 0.0));
                add(a + Vec2::new(3.9375, 0.0), Vec2::new(30.0, 0.0));
            }
            for i in 0..40 {
                // Approaching pairs 4.5 apart closing at 1 unit a step: they meet in the
                // first steps, at offsets that differ by 1/16 from pair to pair.
                let a = Vec2::new(999_000.0 + 20.0625 * i as f32, y);
                add(a, Vec2::new(30.0, 0.0));
                add(a + Vec2::new(4.5, 0.0), Vec2::new(-30.0, 0.0));
            }
            add(Vec2::new(edge, y), Vec2::ZERO);
            add(Vec2::new(edge - 3.0, y), Vec2::ZERO);
            if boundary == Boundary::Wrap {
                // Across the seam: 1 + 2.9375 apart.
                add(Vec2::new(2.9375, y), Vec2::ZERO);
            }
            same_everywhere(device, |device| {
                let mut sim = Simulation::new(device, &spec, 1).unwrap();
                sim.place(&bodies).unwrap();
                let mut found = 0;
                for _ in 0..10 {
                    let before = sim.snapshot().unwrap();
                    sim.step().unwrap();
                    let after = sim.snapshot().unwrap();
                    assert_invariants(&spec, &after);
                    let expected = circle_contacts(&spec, &before);
                    assert_contacts(&after.contacts, &expected, &format!("{size} {boundary:?}"));
                    found += expected.iter().sum::<u32>();
                }
                // The 90 pairs, the 40 that meet, the edge's pair (and the seam's).
                assert!(
                    found >= 2 * (90 + 40 + 1),
                    "{size} {boundary:?}: {found} contacts"
                );
                sim.state_hash().unwrap()
            });
        }
    }
}

// ---------------------------------------------------------------------------------------
// 6. Bodies on one spot
// ---------------------------------------------------------------------------------------

/// `n` circles of radius 3 on exactly one spot part along x, deterministically: the body of
/// rank `i` is pushed `r·(2i − n + 1)` (each pair's tie-break sends the lower slot to −x,
/// half the depth `2r` each), so they end a diameter apart, centred on the spot, and touch
/// without overlapping: a second step finds no contact and moves nothing. A circle and two
/// rectangles on one spot part too, to distinct places. Same hash on every schedule.
fn bodies_on_one_spot_part_deterministically(device: &Device) {
    let r = 3.0f32;
    let spot = Vec2::new(200.0, 150.0);
    for n in [2u32, 3, 17] {
        let spec = world(
            Vec2::splat(400.0),
            Boundary::Clamp,
            vec![kind("b", circle(r), n, &["b"])],
        );
        same_everywhere(device, |device| {
            let mut sim = Simulation::new(device, &spec, 1).unwrap();
            let all: Vec<_> = (0..n).map(|s| (s, spot, Vec2::ZERO)).collect();
            sim.place(&all).unwrap();
            sim.step().unwrap();
            let first = sim.snapshot().unwrap();
            assert_invariants(&spec, &first);
            for i in 0..n {
                let expected = spot + Vec2::new(r * (2.0 * i as f32 - n as f32 + 1.0), 0.0);
                assert_eq!(first.bodies.pos[i as usize], expected, "n {n}, slot {i}");
                assert_eq!(first.contacts[i as usize], n - 1);
            }
            sim.step().unwrap();
            let second = sim.snapshot().unwrap();
            assert!(second.contacts.iter().all(|&c| c == 0), "n {n}");
            assert_eq!(second.bodies.pos, first.bodies.pos, "n {n}: the row moved");
            second.state_hash()
        });
    }
    // Mixed bounds on one spot.
    let spec = world(
        Vec2::splat(400.0),
        Boundary::Wrap,
        vec![
            kind("c", circle(r), 1, &["c", "r"]),
            kind("r", rect(4.0, 2.0), 2, &["c", "r"]),
        ],
    );
    same_everywhere(device, |device| {
        let mut sim = Simulation::new(device, &spec, 1).unwrap();
        let rects = sim.layout().ranges[1].start;
        sim.place(&[
            (0, spot, Vec2::ZERO),
            (rects, spot, Vec2::ZERO),
            (rects + 1, spot, Vec2::ZERO),
        ])
        .unwrap();
        sim.step().unwrap();
        let s = sim.snapshot().unwrap();
        assert_invariants(&spec, &s);
        let places = [
            s.bodies.pos[0],
            s.bodies.pos[rects as usize],
            s.bodies.pos[rects as usize + 1],
        ];
        for (a, pa) in places.iter().enumerate() {
            for pb in &places[a + 1..] {
                assert!(pa.distance(*pb) > 1.0, "{places:?}");
            }
        }
        s.state_hash()
    });
}

// ---------------------------------------------------------------------------------------
// 7. Extreme masses
// ---------------------------------------------------------------------------------------

/// Masses from the smallest normal f32 (1.2·10⁻³⁸, below which `1 / mass` overflows) to
/// 10³⁰ and immovable (`inf`), 40 bodies of each of five masses colliding in a crowded
/// wrapping box for 30 steps: the invariants hold, immovable bodies keep their
/// velocity, and contacts happen. Then two head-on collisions whose outcome mechanics gives:
/// a body of 10³⁰ meeting one of 10⁻³⁰ at rest keeps its velocity, and the light one leaves
/// at `(1 + e)·u`, as from a wall moving at `u`.
fn extreme_masses_stay_finite(device: &Device) {
    let masses = [MIN_MASS, 1.0e-10, 1.0, 1.0e10, MAX_MASS, f32::INFINITY];
    let names: Vec<String> = (0..masses.len()).map(|k| format!("m{k}")).collect();
    let all: Vec<&str> = names.iter().map(String::as_str).collect();
    let kinds = masses
        .iter()
        .zip(&names)
        .map(|(&m, name)| {
            let mut spec = kind(name, circle(5.0), 40, &all);
            spec.mass = m;
            spec
        })
        .collect();
    let spec = world(Vec2::splat(150.0), Boundary::Wrap, kinds);
    same_everywhere(device, |device| {
        let mut sim = Simulation::new(device, &spec, 3).unwrap();
        for k in 0..masses.len() {
            sim.scatter(k, 40, 30.0).unwrap();
        }
        let start = sim.snapshot().unwrap();
        let immovable = sim.layout().ranges[masses.len() - 1];
        let mut touched = 0;
        for _ in 0..30 {
            sim.step().unwrap();
            let s = sim.snapshot().unwrap();
            assert_invariants(&spec, &s);
            touched += s.contacts.iter().sum::<u32>();
            for slot in immovable.start..immovable.end() {
                let slot = slot as usize;
                assert_eq!(
                    s.bodies.vel[slot], start.bodies.vel[slot],
                    "immovable slot {slot}"
                );
            }
        }
        assert!(touched > 1000, "{touched} contacts");
        sim.state_hash().unwrap()
    });

    // Head on: heavy at 10 units/s into light at rest, restitution 0.5.
    let (u, e) = (10.0f32, 0.5f32);
    let mut heavy = kind("heavy", circle(5.0), 1, &["light"]);
    heavy.mass = 1.0e30;
    heavy.restitution = e;
    let mut light = kind("light", circle(5.0), 1, &["heavy"]);
    light.mass = 1.0e-30;
    light.restitution = e;
    let spec = world(Vec2::splat(400.0), Boundary::Clamp, vec![heavy, light]);
    let mut sim = Simulation::new(device, &spec, 1).unwrap();
    let light_slot = sim.layout().ranges[1].start;
    sim.place(&[
        (0, Vec2::new(191.0, 200.0), Vec2::new(u, 0.0)),
        (light_slot, Vec2::new(200.0, 200.0), Vec2::ZERO),
    ])
    .unwrap();
    sim.step().unwrap();
    let s = sim.snapshot().unwrap();
    assert_invariants(&spec, &s);
    assert_eq!(
        s.bodies.vel[0],
        Vec2::new(u, 0.0),
        "the heavy body was deflected"
    );
    let v = s.bodies.vel[light_slot as usize];
    assert!(
        (v - Vec2::new((1.0 + e) * u, 0.0)).length() <= 1e-4 * u,
        "the light body leaves at {v}"
    );
}

/// Masses whose arithmetic would overflow in the kernels are refused before a world is made:
/// below `MIN_MASS`, `1 / mass` is infinite (a subnormal mass froze its body and a contact
/// threw it to the origin); above `MAX_MASS`, a contact's impulse overflows (a body of mass
/// 10³⁸ meeting an immovable one stopped both dead). The limits themselves, and infinity (an
/// immovable body), are accepted.
#[test]
fn masses_that_would_overflow_are_refused_with_the_allowed_range() {
    let with_mass = |mass: f32| {
        let mut dust = kind("dust", circle(2.0), 2, &["dust"]);
        dust.mass = mass;
        world(Vec2::splat(100.0), Boundary::Clamp, vec![dust])
    };
    for mass in [
        f32::from_bits(1),
        f32::MIN_POSITIVE,
        1.0e-31,
        1.0e31,
        1.0e38,
        f32::MAX,
    ] {
        let spec = with_mass(mass);
        let e = spec.validate().unwrap_err().to_string();
        assert!(e.starts_with("kinds[0] (dust).mass: "), "{e}");
        assert!(e.contains("or inf for an immovable body"), "{e}");
        assert!(Simulation::new(common::cpu(), &spec, 1).is_err());
    }
    for mass in [MIN_MASS, MAX_MASS, f32::INFINITY] {
        assert!(with_mass(mass).validate().is_ok(), "{mass}");
    }
}

// ---------------------------------------------------------------------------------------
// 8. Kinds at capacity
// ---------------------------------------------------------------------------------------

/// A world whose kinds are full refuses to scatter more, with an error in words and the
/// state untouched; placing bodies in slots already alive changes no count.
fn a_full_world_refuses_more_bodies(device: &Device) {
    let spec = world(
        Vec2::splat(200.0),
        Boundary::Wrap,
        vec![
            kind("a", circle(2.0), 50, &["a", "b"]),
            kind("b", rect(2.0, 1.0), 33, &["a"]),
        ],
    );
    let mut sim = Simulation::new(device, &spec, 4).unwrap();
    sim.scatter(0, 50, 10.0).unwrap();
    sim.scatter(1, 30, 10.0).unwrap();
    let refused = sim.scatter(1, 4, 10.0).unwrap_err().to_string();
    assert!(refused.contains("3 of its 33 slots are free"), "{refused}");
    sim.scatter(1, 3, 10.0).unwrap();
    let full = sim.snapshot().unwrap();
    assert_invariants(&spec, &full);
    assert_eq!(full.free.count, vec![0, 0]);
    for kind in 0..2 {
        let refused = sim.scatter(kind, 1, 10.0).unwrap_err().to_string();
        assert!(refused.contains("0 of its"), "{refused}");
    }
    assert_eq!(
        sim.snapshot().unwrap(),
        full,
        "a refused scatter changed the state"
    );
    sim.place(&[(0, Vec2::splat(5.0), Vec2::ZERO)]).unwrap();
    for _ in 0..5 {
        sim.step().unwrap();
    }
    let s = sim.snapshot().unwrap();
    assert_invariants(&spec, &s);
    assert_eq!(s.live().count(), 83);
}

/// A scene whose waves ask for far more than their kinds hold: `swarm` (capacity 40, a
/// lifetime of 0.6 s so that slots come free) gets waves of 30 and 25 at once every half
/// second and 25 more every quarter; `crowd` (capacity 100) gets 1,000 a second; three
/// shots (the gun wants ten in flight).
const FULL_SCENE: &str = r#"
name = "full"
description = "waves larger than their kinds"
[world]
size = [600.0, 600.0]
dt = 0.016666668
boundary = "wrap"
[ship]
kind = "ship"
speed = 200.0
fire_rate = 10.0
shot = "shot"
shot_speed = 600.0
autopilot_sight = 150.0
[fps]
start = 60.0
min = 0.0
recovery = 0.0
[spawn]
distance = 100.0
[[spawn.waves]]
kind = "swarm"
at = 0.0
count = 30
every = 0.5
times = 20
[[spawn.waves]]
kind = "swarm"
at = 0.0
count = 25
every = 0.25
times = 40
[[spawn.waves]]
kind = "crowd"
at = 0.1
count = 1000
every = 1.0
times = 10
[[kinds]]
name = "ship"
circle = 10.0
mass = 20.0
capacity = 1
energy = 60000
damage = 100
collides_with = ["swarm", "crowd"]
[[kinds]]
name = "shot"
circle = 2.0
mass = 0.1
capacity = 3
energy = 1
damage = 1
lifetime = 1.0
collides_with = ["swarm", "crowd"]
[[kinds]]
name = "swarm"
circle = 5.0
mass = 1.0
capacity = 40
energy = 1
damage = 1
lifetime = 0.6
max_speed = 60.0
[kinds.behaviour]
machine = "kamikaze"
vision = 80.0
speed = 60.0
[[kinds]]
name = "crowd"
circle = 4.0
mass = 1.0
capacity = 100
energy = 2
damage = 1
max_speed = 40.0
[kinds.behaviour]
machine = "group"
vision = 60.0
speed = 40.0
"#;

/// Plays [`FULL_SCENE`] for 4 s with the autopilot. Before every step, the births it should
/// make follow from the schedule and the free counts alone: each due wave, in order, takes
/// `min(count, what its kind has left)`. The step's spawn event must be that sum, no kind
/// ever holds more than its capacity, the status's counts are the snapshot's, and the
/// invariants hold. The kinds do fill up, and slots freed by deaths are spawned into again.
fn waves_larger_than_capacity_spawn_only_into_free_slots(device: &Device) {
    let scene = Scene::from_toml(FULL_SCENE, "full").unwrap();
    let world = &scene.world;
    let dt = world.dt;
    let ship = world.kind_index(&scene.game.ship.kind).unwrap();
    let shot = world.kind_index(&scene.game.ship.shot).unwrap();
    let due = |step: u32| -> Vec<(usize, u32)> {
        let mut due = Vec::new();
        for w in &scene.game.spawn.waves {
            let first = (w.at / dt).round() as u32;
            let every = w.every.map_or(0, |e| ((e / dt).round() as u32).max(1));
            let since = step.checked_sub(first);
            let on = match since {
                Some(since) if every == 0 => since == 0,
                Some(since) => since % every == 0 && since / every < w.times,
                None => false,
            };
            if on {
                due.push((world.kind_index(&w.kind).unwrap(), w.count));
            }
        }
        due
    };
    same_everywhere(device, |device| {
        let mut game = Game::new(device, &scene, 11).unwrap();
        let mut before = game.snapshot().unwrap();
        let (mut filled, mut refilled) = (vec![false; world.kinds.len()], 0u32);
        for step in 0..240u32 {
            let mut free = before.free.count.clone();
            let mut births = 0;
            for (k, count) in due(step) {
                let n = count.min(free[k]);
                free[k] -= n;
                births += n;
            }
            let status = game.step(None).unwrap();
            assert_eq!(status.step, step + 1);
            assert_eq!(status.events.spawned, births, "step {step}'s births");
            let s = game.snapshot().unwrap();
            assert_invariants(world, &s);
            let alive = |k: usize| world.kinds[k].capacity - s.free.count[k];
            let enemies: u32 = (0..world.kinds.len())
                .filter(|&k| k != ship && k != shot)
                .map(alive)
                .sum();
            assert_eq!(status.enemies_alive, enemies, "step {step}");
            assert_eq!(status.shots_alive, alive(shot), "step {step}");
            for (k, f) in filled.iter_mut().enumerate() {
                *f |= s.free.count[k] == 0;
            }
            if births > 0 && step > 0 {
                refilled += 1;
            }
            assert!(!status.is_over(), "the ship must live through the test");
            before = s;
        }
        assert!(
            filled.iter().all(|&f| f),
            "every kind filled up: {filled:?}"
        );
        assert!(refilled >= 4, "freed slots spawned into {refilled} times");
        game.state_hash().unwrap()
    });
}

/// With a cap the grid orders large buckets in runs and merges them: the grid it builds is
/// the counting order's, bit for bit. A cap too large to bind changes nothing else, so the
/// two worlds (piles of 1 to 700 bodies on a few spots, and bodies scattered between) step
/// to the same state.
fn the_bounded_grid_order_is_the_counting_order(device: &Device) {
    let run = |cap: u32| {
        let mut spec = world(
            Vec2::splat(600.0),
            Boundary::Wrap,
            vec![
                kind("a", circle(3.0), 1500, &["a", "b"]),
                kind("b", circle(5.0), 300, &["a"]),
            ],
        );
        spec.physics.neighbour_cap = cap;
        let mut sim = Simulation::new(device, &spec, 8).unwrap();
        sim.scatter(1, 300, 20.0).unwrap();
        // Piles of 700, 300, 129, 65, 64, 1 and 241 bodies of kind a, in one cell each.
        let mut slot = 0u32;
        let mut piles = Vec::new();
        for (k, size) in [700u32, 300, 129, 65, 64, 1, 241].into_iter().enumerate() {
            let spot = Vec2::new(40.0 + 80.0 * k as f32, 300.0);
            piles.extend((0..size).map(|i| (slot + i, spot, Vec2::ZERO)));
            slot += size;
        }
        sim.place(&piles).unwrap();
        for _ in 0..3 {
            sim.step().unwrap();
        }
        sim.snapshot().unwrap()
    };
    let (counted, merged) = (run(0), run(gpuwars::sim::spec::MAX_SLOTS));
    assert_eq!(counted.state_hash(), merged.state_hash());
    assert_eq!(counted.contacts, merged.contacts);
}

on_both_backends!(
    the_bounded_grid_order_is_the_counting_order,
    every_time_step_keeps_a_colliding_world_finite_inside_and_bounded,
    tunnelling_through_a_thin_wall_stops_at_the_predicted_substeps,
    a_swept_ball_never_tunnels_through_a_thin_wall,
    swept_contacts_at_the_extremes_are_counted_exactly,
    a_million_bodies_under_swept_shots_are_counted_exactly,
    a_pile_of_swept_bodies_against_a_wall_stays_exact,
    a_shot_grazing_a_corner_is_not_frozen,
    bodies_crossing_many_cells_a_step_lose_no_contact,
    a_crowded_cell_is_bounded_by_the_cap,
    a_crowded_cell_is_bounded_by_the_contact_budget,
    contacts_on_cell_borders_and_world_edges_match_brute_force,
    where_f32_spacing_is_coarse_contacts_are_still_found,
    bodies_on_one_spot_part_deterministically,
    extreme_masses_stay_finite,
    a_full_world_refuses_more_bodies,
    waves_larger_than_capacity_spawn_only_into_free_slots,
);

// ---------------------------------------------------------------------------------------
// 9. An hour of `paper` (opt-in)
// ---------------------------------------------------------------------------------------

/// An hour of game time of `paper` on the CPU emulation, the autopilot playing: 216,000
/// steps at 60 Hz (`GPUWARS_SOAK_STEPS` for another count), games back to back, each new
/// game seeded with the next number. Every minute of game time: the invariants, and the
/// status's counts against the snapshot's. At the end it prints the steps per second and the
/// final hash; with `GPUWARS_SOAK_HASH=0x…` it checks that hash (the one recorded in
/// `docs/stability.md`).
#[test]
#[ignore = "an hour of game time: GPUWARS_SOAK=1 cargo test --release --test stability -- --ignored soak --nocapture"]
fn soak_an_hour_of_paper() {
    if std::env::var_os("GPUWARS_SOAK").is_none() {
        eprintln!("skipped: set GPUWARS_SOAK=1 to play an hour of paper");
        return;
    }
    let scene = Scene::load("paper").unwrap();
    let world = &scene.world;
    let per_second = (1.0 / world.dt).round() as u64;
    let total: u64 = std::env::var("GPUWARS_SOAK_STEPS")
        .map(|s| s.parse().expect("GPUWARS_SOAK_STEPS: a whole number"))
        .unwrap_or(3600 * per_second);
    let check_every = 60 * per_second;
    let (ship, shot) = (
        world.kind_index(&scene.game.ship.kind).unwrap(),
        world.kind_index(&scene.game.ship.shot).unwrap(),
    );
    let device = common::cpu();
    let start = std::time::Instant::now();
    let (mut played, mut seed, mut checks) = (0u64, 1u32, 0u32);
    let mut hashes = Vec::new();
    let mut most_enemies = 0;
    while played < total {
        let mut game = Game::new(device, &scene, seed).unwrap();
        loop {
            let status = game.step(None).unwrap();
            played += 1;
            most_enemies = most_enemies.max(status.enemies_alive);
            let end = status.is_over() || played == total;
            if played.is_multiple_of(check_every) || end {
                let s = game.snapshot().unwrap();
                assert_invariants(world, &s);
                let alive = |k: usize| world.kinds[k].capacity - s.free.count[k];
                let enemies: u32 = (0..world.kinds.len())
                    .filter(|&k| k != ship && k != shot)
                    .map(alive)
                    .sum();
                assert_eq!(status.enemies_alive, enemies, "step {played}");
                assert_eq!(status.shots_alive, alive(shot), "step {played}");
                checks += 1;
            }
            if end {
                break;
            }
        }
        hashes.push(game.state_hash().unwrap());
        seed += 1;
    }
    let seconds = start.elapsed().as_secs_f64();
    let last = *hashes.last().unwrap();
    let hashes: Vec<String> = hashes.iter().map(|h| format!("{h:#018x}")).collect();
    eprintln!(
        "soak: {played} steps of paper ({} games) in {seconds:.0} s on {} threads: \
         {:.0} steps/s; {checks} checks, at most {most_enemies} enemies; game hashes [{}]; \
         final {last:#018x}",
        hashes.len(),
        device.cpu_threads().unwrap_or(0),
        played as f64 / seconds,
        hashes.join(", "),
    );
    if let Ok(expected) = std::env::var("GPUWARS_SOAK_HASH") {
        let expected = u64::from_str_radix(expected.trim_start_matches("0x"), 16)
            .expect("GPUWARS_SOAK_HASH: a hexadecimal hash");
        assert_eq!(last, expected, "final hash {last:#018x}");
    }
}

// ---------------------------------------------------------------------------------------
// Random worlds under random choices
// ---------------------------------------------------------------------------------------

/// A world of 1 to 3 kinds (circles or rectangles, masses from 0.01 to 100 or immovable,
/// any restitution and speed limit), wrapping or clamped, any time step, sometimes a field,
/// under any integrator, 1 to 8 substeps, relaxation, averaging, cell scale and cap.
fn random_world() -> impl Strategy<Value = (WorldSpec, u32, f32)> {
    let kinds = prop::collection::vec(
        (
            prop::bool::ANY,
            0.5f32..12.0,
            prop_oneof![Just(f32::INFINITY), 0.01f32..100.0],
            0.0f32..=1.0,
            prop_oneof![Just(f32::INFINITY), 1.0f32..500.0],
            1u32..100,
        ),
        1..=3,
    );
    let physics = (
        0usize..3,
        1u32..=8,
        prop_oneof![Just(1.0f32), 0.01f32..=1.0],
        prop::bool::ANY,
        prop_oneof![Just(1.0f32), 1.0f32..8.0],
        prop_oneof![Just(0u32), 1u32..64],
    );
    let field = prop_oneof![
        Just(Field::default()),
        (-500.0f32..500.0, -500.0f32..500.0).prop_map(|(x, y)| Field {
            gravity: Vec2::new(x, y),
            ..Field::default()
        }),
    ];
    (
        kinds,
        physics,
        field,
        prop::bool::ANY,
        30.0f32..500.0,
        prop_oneof![Just(1.0e-5f32), Just(1.0f32), 1.0e-4f32..=1.0],
        any::<u32>(),
        0.0f32..400.0,
    )
        .prop_map(|(kinds, physics, field, wraps, side, dt, seed, speed)| {
            let names: Vec<String> = (0..kinds.len()).map(|k| format!("k{k}")).collect();
            let all: Vec<&str> = names.iter().map(String::as_str).collect();
            let kinds: Vec<KindSpec> = kinds
                .into_iter()
                .zip(&names)
                .map(
                    |((round, size, mass, restitution, max_speed, capacity), name)| {
                        let shape = if round {
                            circle(size)
                        } else {
                            rect(size, size / 2.0)
                        };
                        let mut spec = kind(name, shape, capacity, &all);
                        spec.mass = mass;
                        spec.restitution = restitution;
                        spec.max_speed = max_speed;
                        spec
                    },
                )
                .collect();
            let boundary = if wraps {
                Boundary::Wrap
            } else {
                Boundary::Clamp
            };
            let mut spec = world(Vec2::splat(side), boundary, kinds);
            spec.dt = dt;
            spec.field = field;
            let (integrator, substeps, relaxation, averaged, cell_scale, cap) = physics;
            let p = &mut spec.physics;
            p.integrator = Integrator::ALL[integrator];
            p.substeps = substeps;
            p.relaxation = relaxation;
            p.averaged = averaged;
            p.cell_scale = cell_scale;
            p.neighbour_cap = cap;
            (spec, seed, speed)
        })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(128))]

    /// Random worlds, filled to capacity, under random choices, 6 steps: valid, every step
    /// invariant, and the same bits on one emulator thread and on three in a shuffled order.
    #[test]
    fn random_worlds_under_random_choices_stay_finite_consistent_and_deterministic(
        (spec, seed, speed) in random_world()
    ) {
        prop_assert!(spec.validate().is_ok(), "{:?}", spec.validate());
        let run = |device: &Device| {
            let mut sim = Simulation::new(device, &spec, seed).unwrap();
            for (k, kind) in spec.kinds.iter().enumerate() {
                sim.scatter(k, kind.capacity, speed).unwrap();
            }
            for _ in 0..6 {
                sim.step().unwrap();
                assert_invariants(&spec, &sim.snapshot().unwrap());
            }
            digest(&sim.snapshot().unwrap())
        };
        let three = Device::cpu_scheduled(
            Some(3),
            Schedule::Shuffled { seed: u64::from(seed) },
            "tests",
        )
        .unwrap();
        prop_assert_eq!(run(one_thread()), run(&three));
    }
}
