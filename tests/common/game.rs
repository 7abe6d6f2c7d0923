//! Small scenes for the game tests, written as TOML the way a user would, and a driver that
//! plays them with a scripted pilot.

use glam::Vec2;
use gpuwars::Device;
use gpuwars::backend::Schedule;
use gpuwars::game::Scene;
use gpuwars::game::{Game, Options};
use gpuwars::kernels::game::control::{Input, Status};
use gpuwars::pipeline::Lanes;
use gpuwars::sim::Snapshot;

/// One enemy kind of a test scene.
pub struct Enemy {
    /// Kind name.
    pub name: &'static str,
    /// `kamikaze`, `group` or `tricky`.
    pub machine: &'static str,
    /// How many, all spawned at the start.
    pub count: u32,
    /// Birth energy.
    pub energy: i32,
    /// Vision radius.
    pub vision: f32,
    /// Speed.
    pub speed: f32,
    /// Extra lines of the `[kinds.behaviour]` table.
    pub extra: &'static str,
}

/// A scene of `size`² with the standard ship and shots, the ship's enemies spawned at least
/// `distance` away from it. The ship does not recover FPS and never loses (minimum 0).
pub fn scene(size: f32, boundary: &str, distance: f32, enemies: &[Enemy]) -> Scene {
    let names: Vec<String> = enemies.iter().map(|e| format!("\"{}\"", e.name)).collect();
    let names = names.join(", ");
    let mut text = format!(
        r#"name = "test"
description = "a test scene"
[world]
size = [{size}, {size}]
dt = 0.016666668
boundary = "{boundary}"
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
distance = {distance}
"#
    );
    for e in enemies {
        text += &format!(
            "[[spawn.waves]]\nkind = \"{}\"\nat = 0.0\ncount = {}\n",
            e.name, e.count
        );
    }
    text += &format!(
        r#"[[kinds]]
name = "ship"
circle = 10.0
mass = 20.0
capacity = 1
energy = 6000
damage = 100
collides_with = [{names}]
[[kinds]]
name = "shot"
circle = 2.0
mass = 0.1
capacity = 64
energy = 1
damage = 1
lifetime = 1.5
collides_with = [{names}]
"#
    );
    for e in enemies {
        text += &format!(
            "[[kinds]]\nname = \"{}\"\ncircle = 5.0\nmass = 1.0\ncapacity = {}\nenergy = {}\ndamage = 10\nmax_speed = {}\n[kinds.behaviour]\nmachine = \"{}\"\nvision = {}\nspeed = {}\n{}\n",
            e.name, e.count, e.energy, e.speed, e.machine, e.vision, e.speed, e.extra
        );
    }
    Scene::from_toml(&text, "test scene").unwrap_or_else(|e| panic!("{e}\n{text}"))
}

/// Plays `steps` steps; before each, `pilot` sees the state and picks the input (`None`: the
/// autopilot's) and after each `watch` sees the status and the state.
pub fn play<'d>(
    device: &'d Device,
    scene: &Scene,
    seed: u32,
    steps: u32,
    mut pilot: impl FnMut(&Snapshot) -> Option<Input>,
    mut watch: impl FnMut(&Status, &Snapshot),
) -> Game<'d> {
    let mut game = Game::new(device, scene, seed).unwrap();
    let mut snapshot = game.snapshot().unwrap();
    for _ in 0..steps {
        let status = game.step(pilot(&snapshot)).unwrap();
        snapshot = game.snapshot().unwrap();
        watch(&status, &snapshot);
    }
    game
}

/// The first enemy kind's index in [`scene`]'s scenes (after the ship and the shots).
pub const FIRST_ENEMY: u32 = 2;

/// 48 enemies of `machine` of wide sight (150 units), born at least 400 units from the ship
/// on a 1,024-unit torus.
pub fn gathering(machine: &'static str) -> Scene {
    let enemies = [Enemy {
        name: "texel",
        machine,
        count: 48,
        energy: 2,
        vision: 150.0,
        speed: 60.0,
        extra: "",
    }];
    scene(1024.0, "wrap", 400.0, &enemies)
}

/// Mean distance from each enemy of a [`gathering`] scene to its nearest fellow, at the
/// start and after 10 s of a ship that does nothing.
pub fn spread_after_ten_seconds(device: &Device, scene: &Scene) -> (f32, f32) {
    let mut spread = Vec::new();
    play(
        device,
        scene,
        3,
        600,
        |_| Some(Input::default()),
        |status, snap| {
            if status.step == 1 || status.step == 600 {
                let slots = live_of(snap, FIRST_ENEMY);
                spread.push(mean_nearest(snap, &slots, 1024.0, true));
            }
        },
    );
    (spread[0], spread[1])
}

/// Plays `steps` autopilot steps of `scene` and returns the game's state hash.
pub fn hash_after(device: &Device, scene: &Scene, seed: u32, steps: u32) -> u64 {
    hash_with(device, scene, seed, steps, Options::default())
}

/// [`hash_after`], the game run as `options` say.
pub fn hash_with(device: &Device, scene: &Scene, seed: u32, steps: u32, options: Options) -> u64 {
    let mut game = Game::with_options(device, scene, seed, options).unwrap();
    for _ in 0..steps {
        game.step(None).unwrap();
    }
    game.state_hash().unwrap()
}

/// [`hash_after`] (seed 1) on the CPU emulation's shuffled schedules (two workers, shuffle
/// seeds 1 and 2), with teams chosen as usual and of 8 lanes: each hash with its label.
pub fn shuffled_hashes(scene: &Scene, steps: u32) -> Vec<(String, u64)> {
    let mut hashes = Vec::new();
    for seed in [1, 2] {
        let device = Device::cpu_scheduled(Some(2), Schedule::Shuffled { seed }, "tests").unwrap();
        for lanes in [Lanes::Auto, Lanes::Fixed(8)] {
            let options = Options {
                lanes,
                ..Options::default()
            };
            let label = format!("shuffle seed {seed}, {lanes:?}");
            hashes.push((label, hash_with(&device, scene, 1, steps, options)));
        }
    }
    hashes
}

/// Input that keeps the ship still and aims at `target` from the ship's slot, firing if
/// `fire`.
pub fn aim_at(snapshot: &Snapshot, ship: usize, target: Vec2, fire: bool) -> Input {
    Input {
        aim: Input::aim_towards(target - snapshot.bodies.pos[ship]),
        fire: u32::from(fire),
        ..Input::default()
    }
}

/// Live slots of kind `kind`.
pub fn live_of(snapshot: &Snapshot, kind: u32) -> Vec<usize> {
    snapshot
        .live()
        .filter(|&s| snapshot.bodies.kind[s] == kind)
        .collect()
}

/// Distance from `a` to `b` on a wrapping square world of side `size`.
pub fn torus_distance(a: Vec2, b: Vec2, size: f32) -> f32 {
    let d = (b - a).abs();
    d.min(Vec2::splat(size) - d).length()
}

/// Mean distance from each body in `slots` to its nearest other one (on a torus of `size`
/// when `wrap`).
pub fn mean_nearest(snapshot: &Snapshot, slots: &[usize], size: f32, wrap: bool) -> f32 {
    let gap = |a: Vec2, b: Vec2| {
        if wrap {
            torus_distance(a, b, size)
        } else {
            a.distance(b)
        }
    };
    let total: f32 = slots
        .iter()
        .map(|&a| {
            slots
                .iter()
                .filter(|&&b| b != a)
                .map(|&b| gap(snapshot.bodies.pos[a], snapshot.bodies.pos[b]))
                .fold(f32::INFINITY, f32::min)
        })
        .sum();
    total / slots.len() as f32
}

/// The `kamikaze` scene's text with its enemies born close to the ship and seeing the whole
/// field: they crash into it from the first seconds.
pub fn crashing_text() -> String {
    gpuwars::game::scene::BUILT_IN
        .iter()
        .find(|b| b.name == "kamikaze")
        .unwrap()
        .source
        .replace("distance = 300.0", "distance = 60.0")
        .replace("vision = 100.0", "vision = 700.0")
}

/// Kamikazes that crash into the ship and die from the first seconds (see
/// [`crashing_text`]): a burst of particles nearly every step.
pub fn crashing() -> Scene {
    Scene::from_toml(&crashing_text(), "crashing").unwrap()
}

/// `scene` with its `[effects]` table taken out.
pub fn without_effects(scene: &Scene) -> Scene {
    let text = &scene.source;
    let start = text.find("[effects]").expect("the scene has explosions");
    let end = start + text[start..].find("\n\n").unwrap();
    let text = format!("{}{}", &text[..start], &text[end..]);
    let scene = Scene::from_toml(&text, &scene.name).unwrap();
    assert!(scene.game.effects.is_none());
    scene
}
