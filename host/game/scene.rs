//! Scene files: a scene's world and rules in TOML (see `scenes/paper.toml`), read into a
//! [`Scene`] and checked. Every error names the file, the line, the field (as the file spells
//! it) and what is allowed; no input makes the reader panic.
//!
//! Reading has three stages, each with its own errors:
//! 1. the toml crate parses the text, keeping the place of every key and value (syntax
//!    errors, with their line);
//! 2. each value is read as written, on its own line: its type, its range (a number is
//!    checked before it is rounded to an `f32`, and must survive the rounding), the length
//!    of an array, missing and unknown keys, and the rules only the file's form can break;
//! 3. the [`WorldSpec`] and [`GameSpec`] this makes are checked against the rules across
//!    values ([`WorldSpec::validate`], the game's), whose errors name a field, found again
//!    in the text for its line.
//!
//! Errors speak of what the file holds (a whole number from 1 to 16,777,216, a table, an
//! array of two numbers), quote a value as written and at most a few dozen characters of it.

use std::fmt;
use std::path::Path;

use glam::Vec2;
use gpuwars_kernels::game::effects::{MAX_PARTICLES, MAX_PER_KILL};
use toml::Spanned;
use toml::de::{DeTable, DeValue};

use crate::files::positioned::{Doc, Interval, Node, Value, above, within};
use crate::files::{MAX_SCENE_BYTES, excerpt, line_of, number, read_text, thousands};

use super::spec::{
    Behaviour, EffectsSpec, FpsSpec, GameSpec, Machine, Scene, ShipSpec, SpawnSpec, WaveSpec,
};
// Errors of the file's own rules read like the world's: a field and what is allowed.
use crate::sim::spec::{
    Boundary, Field, Integrator, KindSpec, MAX_CELL_SCALE, MAX_MASS, MAX_RENUMBER_EVERY, MAX_SIDE,
    MAX_SLOTS, MAX_SUBSTEPS, MAX_VISION_SCALE, MIN_MASS, Physics, Shape, SpecError, Sweep,
    WorldSpec, error as invalid,
};

/// Largest speed, distance or time (seconds) in a scene: as far as f32 world coordinates go.
const MAX: f32 = MAX_SIDE;
/// Most shots per second.
const MAX_FIRE_RATE: f32 = 1000.0;
/// Largest FPS meter and FPS recovery per second.
const MAX_FPS: f32 = 10000.0;
/// Longest life of an explosion's particle, in seconds.
const MAX_LIFETIME: f32 = 10.0;

/// What is wrong with a scene, and where (see [`crate::files::FileError`]).
pub type SceneError = crate::files::FileError;

/// A scene shipped in the binary.
#[derive(Clone, Copy, Debug)]
pub struct BuiltIn {
    /// The name [`Scene::load`] knows it by.
    pub name: &'static str,
    /// Its TOML text.
    pub source: &'static str,
}

impl BuiltIn {
    /// Parses and validates it; an error here is a bug in the shipped file.
    pub fn scene(&self) -> Result<Scene, SceneError> {
        Scene::from_toml(self.source, &format!("built-in scene `{}`", self.name))
    }
}

/// Every built-in scene: the files of `scenes/`, embedded.
pub const BUILT_IN: &[BuiltIn] = &[
    BuiltIn {
        name: "paper",
        source: include_str!("../../scenes/paper.toml"),
    },
    BuiltIn {
        name: "kamikaze",
        source: include_str!("../../scenes/kamikaze.toml"),
    },
    BuiltIn {
        name: "group",
        source: include_str!("../../scenes/group.toml"),
    },
    BuiltIn {
        name: "tricky",
        source: include_str!("../../scenes/tricky.toml"),
    },
    BuiltIn {
        name: "arena",
        source: include_str!("../../scenes/arena.toml"),
    },
    BuiltIn {
        name: "scale-1m",
        source: include_str!("../../scenes/scale-1m.toml"),
    },
    BuiltIn {
        name: "scale-16m",
        source: include_str!("../../scenes/scale-16m.toml"),
    },
];

/// The built-in scene called `name`: `None` if there is none, `Some(Err(_))` if it does not
/// read (a bug in the shipped file, which the tests rule out).
pub fn built_in(name: &str) -> Option<Result<Scene, SceneError>> {
    BUILT_IN.iter().find(|b| b.name == name).map(BuiltIn::scene)
}

impl Scene {
    /// Parses and validates TOML text; `origin` names the file in errors.
    pub fn from_toml(text: &str, origin: &str) -> Result<Scene, SceneError> {
        let doc = Doc { text, origin };
        let root = DeTable::parse(text).map_err(|e| {
            let line = match e.span() {
                Some(span) => Some(line_of(text.as_bytes(), span.start)),
                None => spanless_error_line(text, e.message()),
            };
            let at = e.span().and_then(|span| text.get(span));
            SceneError::new(origin, line, "", parse_problem(e.message(), at))
        })?;
        let root = Spanned::new(root.span(), DeValue::Table(root.into_inner()));
        let root = Node::toml(&doc, &root);
        let scene = read_scene(&root)?;
        scene.validate().map_err(|SpecError { field, problem }| {
            SceneError::new(origin, line_of_field(&root, &field), field, &problem)
        })?;
        Ok(scene)
    }

    /// Checks the world's rules, then the game's: an error names the field as a scene file
    /// writes it (`world.dt`, `kinds[2].max_speed`).
    pub fn validate(&self) -> Result<(), SpecError> {
        let world = &self.world;
        world
            .validate()
            .map_err(|e| toml_field(world, e))
            .and_then(|()| check_game(world, &self.game))
    }

    /// The built-in scene called `name_or_path` if there is one, else the TOML file at that
    /// path: a regular file of at most [`MAX_SCENE_BYTES`] bytes of UTF-8 (any other is an
    /// error without a line, but for the line of a byte that is not UTF-8).
    pub fn load(name_or_path: &str) -> Result<Scene, SceneError> {
        if let Some(scene) = built_in(name_or_path) {
            return scene;
        }
        let text = read_text(Path::new(name_or_path), MAX_SCENE_BYTES)?;
        Scene::from_toml(&text, name_or_path)
    }
}

/// Where `name` is a built-in scene's and also a file here, which of the two `--scene name`
/// plays (the built-in) and how to give the file instead; `None` elsewhere.
pub fn shadowed(name: &str) -> Option<String> {
    let file = Path::new(name);
    (BUILT_IN.iter().any(|b| b.name == name) && file.exists()).then(|| {
        let dot = Path::new(".").join(file);
        format!(
            "`{name}` is a built-in scene, played as such; to play the file of that name \
             here, give `--scene {}`",
            excerpt(&dot.display().to_string())
        )
    })
}

/// What the toml crate's parse error `message` says, in the scene's terms; `at` is the text
/// its span covers, if any.
fn parse_problem(message: &str, at: Option<&str>) -> String {
    // The parser's own words for its nesting limit (80 levels of tables, arrays or dotted
    // keys), which no scene comes near.
    if message == "recursion limit" || message.contains("max recursion depth") {
        "nested too deeply (allowed at most 80 levels of tables, arrays and dotted keys)".to_owned()
    } else if let (true, Some(key)) = (message.starts_with("duplicate key"), at) {
        // The parser's span is the key written the second time.
        format!(
            "duplicate key `{}` (allowed once in a table)",
            excerpt(key.trim())
        )
    } else {
        message.trim_end().to_owned()
    }
}

/// The line of a parse error the toml crate gives no place for (a dotted key nested too
/// deeply): the first line at which the text up to it gives the same error. Earlier lines
/// never give it and later ones always do, so a binary search over the lines finds it.
fn spanless_error_line(text: &str, message: &str) -> Option<usize> {
    let ends: Vec<usize> = text
        .match_indices('\n')
        .map(|(at, _)| at)
        .chain([text.len()])
        .collect();
    let fails = |line: usize| {
        let (_, errors) = DeTable::parse_recoverable(&text[..ends[line]]);
        errors
            .iter()
            .any(|e| e.span().is_none() && e.message() == message)
    };
    let (mut low, mut high) = (0, ends.len());
    while low < high {
        let mid = (low + high) / 2;
        if fails(mid) {
            high = mid;
        } else {
            low = mid + 1;
        }
    }
    (low < ends.len()).then_some(low + 1)
}

/// Most of a distance, speed or time.
fn side() -> Interval {
    above(0.0, MAX)
}

/// Zero or a distance, speed or time.
fn side_or_zero() -> Interval {
    within(0.0, MAX)
}

/// Reads the whole document: every value's type and range, and the rules only the file's
/// form can break. The world's and the game's rules across values come after.
fn read_scene(root: &Node<'_>) -> Result<Scene, SceneError> {
    let top = root.table(&[
        "name",
        "description",
        "world",
        "ship",
        "fps",
        "spawn",
        "kinds",
        "physics",
        "effects",
    ])?;
    let name_node = top.need("name")?;
    let name = name_node.line_of_text("a name in quotes")?;
    if name.trim().is_empty() {
        return Err(name_node.fail("must not be empty"));
    }
    let description = top
        .need("description")?
        .line_of_text("a description in quotes")?;

    let world = top
        .need("world")?
        .table(&["size", "dt", "boundary", "cell"])?;
    let size = Vec2::from(world.need("size")?.pair(side(), "[width, height]")?);
    let dt = world.need("dt")?.real(above(0.0, 1.0))?;
    let boundary = world.need("boundary")?.choice(
        "boundary",
        &[("clamp", Boundary::Clamp), ("wrap", Boundary::Wrap)],
    )?;
    let vision = world.or("cell", 0.0, |n| n.real(side_or_zero()))?;
    let physics = top.or("physics", Physics::default(), read_physics)?;

    let ship = read_ship(&top.need("ship")?)?;
    let fps = read_fps(&top.need("fps")?)?;
    let spawn = read_spawn(&top.need("spawn")?, (size, boundary))?;
    let effects = top.or("effects", None, |n| read_effects(n).map(Some))?;
    let (mut kinds, behaviours): (Vec<KindSpec>, _) = top
        .need("kinds")?
        .array("an array of tables ([[kinds]])")?
        .iter()
        .map(read_kind)
        .collect::<Result<_, _>>()?;
    // The game knows how fast the ship and its shots go, which sizes their swept contacts.
    for kind in &mut kinds {
        if kind.name == ship.kind {
            kind.top_speed = ship.speed;
        } else if kind.name == ship.shot {
            kind.top_speed = ship.shot_speed;
        }
    }
    Ok(Scene {
        name,
        description,
        world: WorldSpec {
            size,
            dt,
            boundary,
            vision,
            kinds,
            physics,
            field: Field::default(),
        },
        game: GameSpec {
            ship,
            fps,
            spawn,
            behaviours,
            effects,
        },
        source: root.text().to_owned(),
    })
}

/// A kind's mass: from [`MIN_MASS`] to [`MAX_MASS`] as written, or `inf` (immovable).
fn read_mass(node: &Node<'_>) -> Result<f32, SceneError> {
    let mass = node.real(above(0.0, f32::INFINITY))?;
    if mass.is_finite() && !(MIN_MASS..=MAX_MASS).contains(&mass) {
        return Err(node.fail(format!(
            "{} is out of range (allowed {} to {}, or inf for an immovable body)",
            node.written(),
            number(MIN_MASS),
            number(MAX_MASS)
        )));
    }
    Ok(mass)
}

/// The `[physics]` table: every key optional, the default reproducing the paper's game.
fn read_physics(node: &Node<'_>) -> Result<Physics, SceneError> {
    let table = node.table(&[
        "integrator",
        "substeps",
        "relaxation",
        "averaged",
        "cell_scale",
        "neighbour_cap",
        "vision_scale",
        "sight_budget",
        "contact_budget",
        "renumber_every",
    ])?;
    let d = Physics::default();
    let integrators = Integrator::ALL.map(|i| (i.name(), i));
    Ok(Physics {
        integrator: table.or("integrator", d.integrator, |n| {
            n.choice("integrator", &integrators)
        })?,
        substeps: table.or("substeps", d.substeps, |n| n.whole(1, MAX_SUBSTEPS))?,
        relaxation: table.or("relaxation", d.relaxation, |n| n.real(above(0.0, 1.0)))?,
        averaged: table.or("averaged", d.averaged, Node::flag)?,
        cell_scale: table.or("cell_scale", d.cell_scale, |n| {
            n.real(within(1.0, MAX_CELL_SCALE))
        })?,
        neighbour_cap: table.or("neighbour_cap", d.neighbour_cap, |n| n.whole(0, MAX_SLOTS))?,
        vision_scale: table.or("vision_scale", d.vision_scale, |n| {
            n.real(above(0.0, MAX_VISION_SCALE))
        })?,
        sight_budget: table.or("sight_budget", d.sight_budget, |n| n.whole(0, MAX_SLOTS))?,
        contact_budget: table.or("contact_budget", d.contact_budget, |n| {
            n.whole(0, MAX_SLOTS)
        })?,
        renumber_every: table.or("renumber_every", d.renumber_every, |n| {
            n.whole(0, MAX_RENUMBER_EVERY).map(Some)
        })?,
        // Kept for audits, which ask for them; a scene has no say.
        trace_paths: false,
        log_room: d.log_room,
    })
}

fn read_ship(node: &Node<'_>) -> Result<ShipSpec, SceneError> {
    let ship = node.table(&[
        "kind",
        "speed",
        "fire_rate",
        "shot",
        "shot_speed",
        "autopilot_sight",
    ])?;
    Ok(ShipSpec {
        kind: ship.need("kind")?.string("a kind's name in quotes")?,
        speed: ship.need("speed")?.real(side())?,
        fire_rate: ship.need("fire_rate")?.real(above(0.0, MAX_FIRE_RATE))?,
        shot: ship.need("shot")?.string("a kind's name in quotes")?,
        shot_speed: ship.need("shot_speed")?.real(side())?,
        autopilot_sight: ship.need("autopilot_sight")?.real(side())?,
    })
}

fn read_fps(node: &Node<'_>) -> Result<FpsSpec, SceneError> {
    let fps = node.table(&["start", "min", "recovery"])?;
    let start = fps.need("start")?.real(above(0.0, MAX_FPS))?;
    Ok(FpsSpec {
        start,
        min: fps
            .need("min")?
            .real(within(0.0, start).up_to_stored("fps.start"))?,
        recovery: fps.need("recovery")?.real(within(0.0, MAX_FPS))?,
    })
}

/// The `[effects]` table: every key optional (see [`EffectsSpec::default`]).
fn read_effects(node: &Node<'_>) -> Result<EffectsSpec, SceneError> {
    let table = node.table(&["particles", "lifetime", "speed", "speed_kept"])?;
    let d = EffectsSpec::default();
    Ok(EffectsSpec {
        particles: table.or("particles", d.particles, |n| n.whole(1, MAX_PER_KILL))?,
        lifetime: table.or("lifetime", d.lifetime, |n| n.real(above(0.0, MAX_LIFETIME)))?,
        speed: table.or("speed", d.speed, |n| n.real(side_or_zero()))?,
        speed_kept: table.or("speed_kept", d.speed_kept, |n| n.real(above(0.0, 1.0)))?,
    })
}

/// `[spawn]`, in a field of `size` and `boundary`.
fn read_spawn(
    node: &Node<'_>,
    (size, boundary): (Vec2, Boundary),
) -> Result<SpawnSpec, SceneError> {
    let spawn = node.table(&["distance", "waves"])?;
    let distance_node = spawn.need("distance")?;
    let distance = distance_node.real(side_or_zero())?;
    // The farthest a place can be from the ship: across the field, or half across a torus
    // (its offsets go the short way round); beyond it no place is far enough.
    let (farthest, across) = match boundary {
        Boundary::Clamp => (size.length(), "its diagonal"),
        Boundary::Wrap => (
            (size / 2.0).length(),
            "half its diagonal, the short way round",
        ),
    };
    if distance > farthest {
        return Err(distance_node.fail(format!(
            "{} is farther than any place of the {} x {} field can be from the ship \
             (allowed 0 to {}: {across})",
            number(distance),
            number(size.x),
            number(size.y),
            number(farthest)
        )));
    }
    let waves = spawn.or("waves", Vec::new(), |n| {
        n.array("an array of tables ([[spawn.waves]])")
    })?;
    let waves = waves
        .iter()
        .map(|node| {
            let wave = node.table(&["kind", "at", "count", "every", "times", "speed"])?;
            let every = wave.or("every", None, |n| n.real(side()).map(Some))?;
            let times = wave.or("times", 1, |n| n.whole(1, u32::MAX))?;
            if every.is_none() && times != 1 {
                let times = wave.need("times")?;
                return Err(times.fail(format!(
                    "{} is out of range (allowed 1 without `every`)",
                    times.written()
                )));
            }
            Ok(WaveSpec {
                kind: wave.need("kind")?.string("a kind's name in quotes")?,
                at: wave.need("at")?.real(side_or_zero())?,
                count: wave.need("count")?.whole(1, u32::MAX)?,
                every,
                times,
                speed: wave.or("speed", 0.0, |n| n.real(side_or_zero()))?,
            })
        })
        .collect::<Result<_, _>>()?;
    Ok(SpawnSpec { distance, waves })
}

/// A kind, and its behaviour.
fn read_kind(node: &Node<'_>) -> Result<(KindSpec, Option<Behaviour>), SceneError> {
    let kind = node.table(&[
        "name",
        "circle",
        "rect",
        "mass",
        "capacity",
        "energy",
        "damage",
        "restitution",
        "max_speed",
        "lifetime",
        "collides_with",
        "swept",
        "behaviour",
    ])?;
    let name = kind.need("name")?.line_of_text("a name in quotes")?;
    let shape = match (kind.get("circle"), kind.get("rect")) {
        (Some(radius), None) => Shape::Circle {
            radius: radius.real(side())?,
        },
        (None, Some(half)) => Shape::Rect {
            half: Vec2::from(half.pair(side(), "[half_width, half_height]")?),
        },
        (Some(_), Some(rect)) => {
            return Err(rect.fail(
                "conflicts with `circle` (allowed exactly one of `circle = radius` \
                 or `rect = [half_width, half_height]`)",
            ));
        }
        (None, None) => {
            return Err(node.fail(
                "has no shape (allowed exactly one of `circle = radius` \
                 or `rect = [half_width, half_height]`)",
            ));
        }
    };
    let collides_with = kind.or("collides_with", Vec::new(), |n| {
        n.array("an array of kinds' names")?
            .iter()
            .map(|name| name.string("a kind's name in quotes"))
            .collect()
    })?;
    // inf: no speed limit.
    let max_speed = kind.or("max_speed", f32::INFINITY, |n| {
        n.real(above(0.0, f32::INFINITY))
    })?;
    let behaviour = kind.or("behaviour", None, |n| {
        read_behaviour(n, max_speed).map(Some)
    })?;
    let spec = KindSpec {
        name,
        shape,
        // inf: an immovable body.
        mass: read_mass(&kind.need("mass")?)?,
        capacity: kind.need("capacity")?.whole(1, MAX_SLOTS)?,
        energy: kind.need("energy")?.whole(1, i32::MAX)?,
        damage: kind.or("damage", 0, |n| n.whole(0, i32::MAX))?,
        restitution: kind.or("restitution", 0.0, |n| n.real(within(0.0, 1.0)))?,
        max_speed,
        collides_with,
        // inf: lives for ever.
        lifetime: kind.or("lifetime", f32::INFINITY, |n| {
            n.real(above(0.0, f32::INFINITY))
        })?,
        controlled: behaviour.is_some(),
        // Left out: the rule decides (`WorldSpec::pair_sweeps`).
        sweep: kind.or("swept", Sweep::Auto, |n| {
            n.flag().map(|on| if on { Sweep::On } else { Sweep::Off })
        })?,
        // The ship's and the shots' come from `[ship]` (see `Scene::from_toml`).
        top_speed: f32::INFINITY,
    };
    Ok((spec, behaviour))
}

/// A kind's behaviour, for a kind of `max_speed`. Settings the machine ignores must be left
/// at their defaults, so that a file never says something the game does not do.
fn read_behaviour(node: &Node<'_>, max_speed: f32) -> Result<Behaviour, SceneError> {
    let b = node.table(&[
        "machine",
        "vision",
        "speed",
        "avoid_bullets",
        "low_energy",
        "recovery",
    ])?;
    let machine_node = b.need("machine")?;
    let machine = machine_node.choice(
        "machine",
        &[
            ("kamikaze", Machine::Kamikaze),
            ("group", Machine::Group),
            ("tricky", Machine::Tricky),
        ],
    )?;
    let name = machine_node.string("a machine in quotes")?;
    let avoid_bullets = match b.get("avoid_bullets") {
        Some(avoid) => match (machine, avoid.flag()?) {
            (Machine::Kamikaze, true) => {
                return Err(avoid
                    .fail("a kamikaze does not avoid bullets (allowed false, or leave it out)"));
            }
            (_, avoid) => avoid,
        },
        None => machine != Machine::Kamikaze,
    };
    let low_energy = b.or("low_energy", 0, |n| n.whole(0, i32::MAX))?;
    let recovery = b.or("recovery", 0.0, |n| n.real(side_or_zero()))?;
    if machine != Machine::Tricky {
        if low_energy != 0 {
            return Err(b.need("low_energy")?.fail(format!(
                "only a tricky enemy escapes (allowed 0 for a {name})"
            )));
        }
        if recovery != 0.0 {
            return Err(b.need("recovery")?.fail(format!(
                "only a tricky enemy recovers (allowed 0 for a {name})"
            )));
        }
    }
    Ok(Behaviour {
        machine,
        vision: b.need("vision")?.real(side())?,
        // At most the kind's speed limit, both as stored.
        speed: b
            .need("speed")?
            .real(above(0.0, max_speed.min(MAX)).up_to_stored("the kind's max_speed"))?,
        avoid_bullets,
        low_energy,
        recovery,
    })
}

/// [`WorldSpec::validate`]'s error with its field in TOML terms: `size.x` → `world.size[0]`,
/// `kinds[2] (shot).radius` → `kinds[2].circle`, …
fn toml_field(world: &WorldSpec, e: SpecError) -> SpecError {
    let field = match e.field.as_str() {
        "size.x" => "world.size[0]".to_owned(),
        "size.y" => "world.size[1]".to_owned(),
        "dt" => "world.dt".to_owned(),
        "vision" => "world.cell".to_owned(),
        field => world
            .kinds
            .iter()
            .enumerate()
            // Matching the whole prefix, name included, copes with any character in a name.
            .find_map(|(k, kind)| {
                let prefix = format!("kinds[{k}] ({}).", excerpt(&kind.name));
                let rest = field.strip_prefix(&prefix)?;
                let rest = match rest {
                    "radius" => "circle",
                    "half.x" => "rect[0]",
                    "half.y" => "rect[1]",
                    rest => rest,
                };
                Some(format!("kinds[{k}].{rest}"))
            })
            .unwrap_or_else(|| field.to_owned()),
    };
    SpecError {
        field,
        problem: e.problem,
    }
}

/// The error for a reference to a kind the scene lacks.
fn unknown_kind(field: impl fmt::Display, name: &str) -> SpecError {
    invalid(field, format!("no kind is named `{}`", excerpt(name)))
}

/// The rules of [`GameSpec`]'s docs, given a valid `world`.
fn check_game(world: &WorldSpec, game: &GameSpec) -> Result<(), SpecError> {
    for (k, (kind, behaviour)) in world.kinds.iter().zip(&game.behaviours).enumerate() {
        if let Some(b) = behaviour {
            b.validate(kind, |field| format!("kinds[{k}].behaviour.{field}"))?;
        }
    }
    let ShipSpec { kind, shot, .. } = &game.ship;
    let (kind_name, shot_name) = (excerpt(kind), excerpt(shot));
    let ship_kind = world
        .kind_index(kind)
        .ok_or_else(|| unknown_kind("ship.kind", kind))?;
    let ship = &world.kinds[ship_kind];
    if ship.capacity != 1 {
        return Err(invalid(
            "ship.kind",
            format!(
                "kind `{kind_name}` has capacity {} (allowed 1 for the ship's kind)",
                ship.capacity
            ),
        ));
    }
    if game.behaviours[ship_kind].is_some() {
        return Err(invalid(
            "ship.kind",
            format!("kind `{kind_name}` has a behaviour (the ship's kind must have none)"),
        ));
    }
    let shot_kind = world
        .kind_index(shot)
        .ok_or_else(|| unknown_kind("ship.shot", shot))?;
    if shot_kind == ship_kind {
        return Err(invalid(
            "ship.shot",
            format!("`{shot_name}` is the ship's kind (shots need a kind of their own)"),
        ));
    }
    if game.behaviours[shot_kind].is_some() {
        return Err(invalid(
            "ship.shot",
            format!("kind `{shot_name}` has a behaviour (the shots' kind must have none)"),
        ));
    }
    if let Some(effects) = &game.effects {
        let particles = super::engine::particles(world, game);
        if particles > u64::from(MAX_PARTICLES) {
            return Err(invalid(
                "effects.particles",
                format!(
                    "{} a kill makes {} particles in all (allowed at most {})",
                    effects.particles,
                    thousands(particles),
                    thousands(u64::from(MAX_PARTICLES))
                ),
            ));
        }
    }
    for (w, wave) in game.spawn.waves.iter().enumerate() {
        let at = |field: &str| format!("spawn.waves[{w}].{field}");
        let k = world
            .kind_index(&wave.kind)
            .ok_or_else(|| unknown_kind(at("kind"), &wave.kind))?;
        if k == ship_kind || k == shot_kind {
            let whose = if k == ship_kind { "ship's" } else { "shots'" };
            return Err(invalid(
                at("kind"),
                format!(
                    "`{}` is the {whose} kind (waves spawn other kinds)",
                    excerpt(&wave.kind)
                ),
            ));
        }
    }
    Ok(())
}

/// The line of the value at the TOML path `field` (`kinds[1].collides_with[0]`), or of the
/// deepest table or array element on the way that is present (a defaulted key's table).
fn line_of_field(root: &Node<'_>, field: &str) -> Option<usize> {
    let (mut node, mut line) = (root.clone(), None);
    for step in field.split(['.', '[']) {
        let next = match step.strip_suffix(']').and_then(|i| i.parse().ok()) {
            Some(i) => node.items("").ok().and_then(|mut items| items.nth(i)),
            None => match node.value() {
                Ok(Value::Table(entries)) => entries.into_iter().find(|e| e.key == step),
                _ => None,
            }
            .map(|entry| entry.node),
        };
        let Some(next) = next else { break };
        node = next;
        line = node.line();
    }
    line
}
