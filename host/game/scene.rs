//! Scene files: a scene's world and rules in TOML (see `scenes/paper.toml`), read into a
//! [`Scene`] and checked. Every error names the file, the line, the field (as the file spells
//! it) and what is allowed; no input makes the reader panic.
//!
//! Reading has two stages, each with its own errors:
//! 1. the toml crate reads the text into plain structures (syntax, types, missing and
//!    unknown keys); its error's span gives the line, and the key found there the field;
//! 2. those become a [`WorldSpec`] and a [`GameSpec`] (enum names, integer ranges, rules only
//!    the file's form can break), which [`WorldSpec::validate`] and the game's rules check;
//!    these errors name a field, whose line a span-preserving parse of the text gives.

use std::fmt;
use std::ops::Range;

use glam::Vec2;
use serde::Deserialize;
use toml::Spanned;
use toml::de::{DeTable, DeValue};

use crate::files::line_of;

use super::spec::{Behaviour, FpsSpec, GameSpec, Machine, Scene, ShipSpec, SpawnSpec, WaveSpec};
// Errors of the file's own rules read like the world's: a field and what is allowed.
use crate::sim::spec::{
    Boundary, KindSpec, MAX_SIDE, MAX_SLOTS, Shape, SpecError, WorldSpec, check_range as check,
    error as invalid,
};

/// Largest speed, distance or time (seconds) in a scene: as far as f32 world coordinates go.
const MAX: f32 = MAX_SIDE;
/// Most shots per second.
const MAX_FIRE_RATE: f32 = 1000.0;
/// Largest FPS meter and FPS recovery per second.
const MAX_FPS: f32 = 10000.0;

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
        let error = |line, field, problem: &str| SceneError::new(origin, line, field, problem);
        let doc = DeTable::parse(text)
            .map_err(|e| error(line_at(text, e.span()), String::new(), e.message()))?;
        let root = doc.span();
        let raw = RawScene::deserialize(toml::de::Deserializer::from(doc)).map_err(|e| {
            let (line, field) = match e.span() {
                // The whole document's (empty) span: a top-level key is missing, nowhere.
                Some(span) if span != root => (
                    line_at(text, Some(span.clone())),
                    field_at(text, span.start),
                ),
                _ => (None, String::new()),
            };
            error(line, field, e.message())
        })?;
        raw.into_scene(text)
            .map_err(|SpecError { field, problem }| {
                error(line_of_field(text, &field), field, &problem)
            })
    }

    /// The built-in scene called `name_or_path` if there is one, else the TOML file at that
    /// path (a file that cannot be read is an error without a line).
    pub fn load(name_or_path: &str) -> Result<Scene, SceneError> {
        if let Some(scene) = built_in(name_or_path) {
            return scene;
        }
        let text = std::fs::read_to_string(name_or_path)
            .map_err(|e| SceneError::new(name_or_path, None, "", e))?;
        Scene::from_toml(&text, name_or_path)
    }
}

// The file as written: everything the toml crate checks (types, required and unknown keys).
// Integers are read as i64 so that a negative or huge one gets a range message, not a type one.

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawScene {
    name: String,
    description: String,
    world: RawWorld,
    ship: ShipSpec,
    fps: FpsSpec,
    spawn: RawSpawn,
    kinds: Vec<RawKind>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawWorld {
    size: [f32; 2],
    dt: f32,
    boundary: String,
    #[serde(default)]
    cell: f32,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawSpawn {
    distance: f32,
    #[serde(default)]
    waves: Vec<RawWave>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawWave {
    kind: String,
    at: f32,
    count: i64,
    every: Option<f32>,
    #[serde(default = "one")]
    times: i64,
    #[serde(default)]
    speed: f32,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawKind {
    name: String,
    circle: Option<f32>,
    rect: Option<[f32; 2]>,
    mass: f32,
    capacity: i64,
    energy: i64,
    #[serde(default)]
    damage: i64,
    #[serde(default)]
    restitution: f32,
    #[serde(default = "infinity")]
    max_speed: f32,
    #[serde(default = "infinity")]
    lifetime: f32,
    #[serde(default)]
    collides_with: Vec<String>,
    behaviour: Option<RawBehaviour>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawBehaviour {
    machine: String,
    vision: f32,
    speed: f32,
    avoid_bullets: Option<bool>,
    #[serde(default)]
    low_energy: i64,
    #[serde(default)]
    recovery: f32,
}

fn one() -> i64 {
    1
}

fn infinity() -> f32 {
    f32::INFINITY
}

/// `value` as a `T`, if it is in `low..=high` (which `T` must hold).
fn integer<T: TryFrom<i64>>(
    field: impl fmt::Display,
    value: i64,
    low: i64,
    high: i64,
) -> Result<T, SpecError> {
    match T::try_from(value) {
        Ok(v) if (low..=high).contains(&value) => Ok(v),
        _ => Err(invalid(
            field,
            format!("{value} is out of range (allowed {low} to {high})"),
        )),
    }
}

fn unknown_kind(field: impl fmt::Display, name: &str) -> SpecError {
    invalid(field, format!("no kind is named `{name}`"))
}

impl RawScene {
    /// The scene, checked; `text` becomes its source.
    fn into_scene(self, text: &str) -> Result<Scene, SpecError> {
        if self.name.trim().is_empty() {
            return Err(invalid("name", "must not be empty"));
        }
        let (world, behaviours) = self.world.into_spec(self.kinds)?;
        world.validate().map_err(|e| toml_field(&world, e))?;
        let game = GameSpec {
            ship: self.ship,
            fps: self.fps,
            spawn: self.spawn.into_spec()?,
            behaviours,
        };
        check_game(&world, &game)?;
        Ok(Scene {
            name: self.name,
            description: self.description,
            world,
            game,
            source: text.to_owned(),
        })
    }
}

impl RawWorld {
    /// The world, and each kind's behaviour (which belongs to the game).
    fn into_spec(
        self,
        kinds: Vec<RawKind>,
    ) -> Result<(WorldSpec, Vec<Option<Behaviour>>), SpecError> {
        let boundary = match self.boundary.as_str() {
            "clamp" => Boundary::Clamp,
            "wrap" => Boundary::Wrap,
            other => {
                return Err(invalid(
                    "world.boundary",
                    format!("unknown boundary `{other}` (allowed `clamp` or `wrap`)"),
                ));
            }
        };
        let (kinds, behaviours) = kinds
            .into_iter()
            .enumerate()
            .map(|(k, kind)| kind.into_spec(k))
            .collect::<Result<_, _>>()?;
        let world = WorldSpec {
            size: Vec2::from(self.size),
            dt: self.dt,
            boundary,
            vision: self.cell,
            kinds,
        };
        Ok((world, behaviours))
    }
}

impl RawKind {
    /// Kind number `k`, and its behaviour.
    fn into_spec(self, k: usize) -> Result<(KindSpec, Option<Behaviour>), SpecError> {
        let at = |field: &str| format!("kinds[{k}].{field}");
        let shape = match (self.circle, self.rect) {
            (Some(radius), None) => Shape::Circle { radius },
            (None, Some(half)) => Shape::Rect {
                half: Vec2::from(half),
            },
            (Some(_), Some(_)) => {
                return Err(invalid(
                    at("rect"),
                    "conflicts with `circle` (allowed exactly one of `circle = radius` \
                     or `rect = [half_x, half_y]`)",
                ));
            }
            (None, None) => {
                return Err(invalid(
                    format!("kinds[{k}]"),
                    "has no shape (allowed exactly one of `circle = radius` \
                     or `rect = [half_x, half_y]`)",
                ));
            }
        };
        let behaviour = match self.behaviour {
            Some(b) => Some(b.into_spec(|field| at(&format!("behaviour.{field}")))?),
            None => None,
        };
        let kind = KindSpec {
            name: self.name,
            shape,
            mass: self.mass,
            capacity: integer(at("capacity"), self.capacity, 1, i64::from(MAX_SLOTS))?,
            energy: integer(at("energy"), self.energy, 1, i32::MAX.into())?,
            damage: integer(at("damage"), self.damage, 0, i32::MAX.into())?,
            restitution: self.restitution,
            max_speed: self.max_speed,
            collides_with: self.collides_with,
            lifetime: self.lifetime,
            controlled: behaviour.is_some(),
        };
        Ok((kind, behaviour))
    }
}

impl RawBehaviour {
    /// The behaviour; `at` names its fields. Settings the machine ignores must be left at
    /// their defaults, so that a file never says something the game does not do.
    fn into_spec(self, at: impl Fn(&str) -> String) -> Result<Behaviour, SpecError> {
        let machine = match self.machine.as_str() {
            "kamikaze" => Machine::Kamikaze,
            "group" => Machine::Group,
            "tricky" => Machine::Tricky,
            other => {
                return Err(invalid(
                    at("machine"),
                    format!("unknown machine `{other}` (allowed `kamikaze`, `group` or `tricky`)"),
                ));
            }
        };
        let avoid_bullets = match (machine, self.avoid_bullets) {
            (Machine::Kamikaze, Some(true)) => {
                return Err(invalid(
                    at("avoid_bullets"),
                    "a kamikaze does not avoid bullets (allowed false, or leave it out)",
                ));
            }
            (Machine::Kamikaze, _) => false,
            (_, avoid) => avoid.unwrap_or(true),
        };
        let low_energy = integer(at("low_energy"), self.low_energy, 0, i32::MAX.into())?;
        if machine != Machine::Tricky {
            let name = &self.machine;
            if low_energy != 0 {
                return Err(invalid(
                    at("low_energy"),
                    format!("only a tricky enemy escapes (allowed 0 for a {name})"),
                ));
            }
            if self.recovery != 0.0 {
                return Err(invalid(
                    at("recovery"),
                    format!("only a tricky enemy recovers (allowed 0 for a {name})"),
                ));
            }
        }
        Ok(Behaviour {
            machine,
            vision: self.vision,
            speed: self.speed,
            avoid_bullets,
            low_energy,
            recovery: self.recovery,
        })
    }
}

impl RawSpawn {
    fn into_spec(self) -> Result<SpawnSpec, SpecError> {
        let waves = self.waves.into_iter().enumerate().map(|(w, wave)| {
            let at = |field: &str| format!("spawn.waves[{w}].{field}");
            let max = u32::MAX.into();
            Ok(WaveSpec {
                count: integer(at("count"), wave.count, 1, max)?,
                times: integer(at("times"), wave.times, 1, max)?,
                kind: wave.kind,
                at: wave.at,
                every: wave.every,
                speed: wave.speed,
            })
        });
        Ok(SpawnSpec {
            distance: self.distance,
            waves: waves.collect::<Result<_, _>>()?,
        })
    }
}

/// [`WorldSpec::validate`]'s error with its field in TOML terms: `size.x` → `world.size`,
/// `kinds[2] (shot).radius` → `kinds[2].circle`, …
fn toml_field(world: &WorldSpec, e: SpecError) -> SpecError {
    let field = match e.field.as_str() {
        "size.x" | "size.y" => "world.size".to_owned(),
        "dt" => "world.dt".to_owned(),
        "vision" => "world.cell".to_owned(),
        field => world
            .kinds
            .iter()
            .enumerate()
            // Matching the whole prefix, name included, copes with any character in a name.
            .find_map(|(k, kind)| {
                let rest = field.strip_prefix(&format!("kinds[{k}] ({}).", kind.name))?;
                let rest = match rest {
                    "radius" => "circle",
                    "half.x" | "half.y" => "rect",
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

/// The rules of [`GameSpec`]'s docs, given a valid `world`.
fn check_game(world: &WorldSpec, game: &GameSpec) -> Result<(), SpecError> {
    for (k, (kind, behaviour)) in world.kinds.iter().zip(&game.behaviours).enumerate() {
        if let Some(b) = behaviour {
            b.validate(kind, |field| format!("kinds[{k}].behaviour.{field}"))?;
        }
    }
    let ShipSpec {
        kind,
        speed,
        fire_rate,
        shot,
        shot_speed,
        autopilot_sight,
    } = &game.ship;
    let ship_kind = world
        .kind_index(kind)
        .ok_or_else(|| unknown_kind("ship.kind", kind))?;
    let ship = &world.kinds[ship_kind];
    if ship.capacity != 1 {
        return Err(invalid(
            "ship.kind",
            format!(
                "kind `{kind}` has capacity {} (allowed 1 for the ship's kind)",
                ship.capacity
            ),
        ));
    }
    if game.behaviours[ship_kind].is_some() {
        return Err(invalid(
            "ship.kind",
            format!("kind `{kind}` has a behaviour (the ship's kind must have none)"),
        ));
    }
    let shot_kind = world
        .kind_index(shot)
        .ok_or_else(|| unknown_kind("ship.shot", shot))?;
    if shot_kind == ship_kind {
        return Err(invalid(
            "ship.shot",
            format!("`{shot}` is the ship's kind (shots need a kind of their own)"),
        ));
    }
    if game.behaviours[shot_kind].is_some() {
        return Err(invalid(
            "ship.shot",
            format!("kind `{shot}` has a behaviour (the shots' kind must have none)"),
        ));
    }
    check("ship.speed", *speed, (0.0, false), MAX)?;
    check("ship.fire_rate", *fire_rate, (0.0, false), MAX_FIRE_RATE)?;
    check("ship.shot_speed", *shot_speed, (0.0, false), MAX)?;
    check("ship.autopilot_sight", *autopilot_sight, (0.0, false), MAX)?;

    let fps = &game.fps;
    check("fps.start", fps.start, (0.0, false), MAX_FPS)?;
    check("fps.min", fps.min, (0.0, true), fps.start)?;
    check("fps.recovery", fps.recovery, (0.0, true), MAX_FPS)?;

    check("spawn.distance", game.spawn.distance, (0.0, true), MAX)?;
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
                    wave.kind
                ),
            ));
        }
        check(at("at"), wave.at, (0.0, true), MAX)?;
        match wave.every {
            Some(every) => check(at("every"), every, (0.0, false), MAX)?,
            None if wave.times != 1 => {
                return Err(invalid(
                    at("times"),
                    format!("{} is out of range (allowed 1 without `every`)", wave.times),
                ));
            }
            None => {}
        }
        check(at("speed"), wave.speed, (0.0, true), MAX)?;
    }
    Ok(())
}

/// 1-based line of the byte `span` starts at.
fn line_at(text: &str, span: Option<Range<usize>>) -> Option<usize> {
    Some(line_of(text.as_bytes(), span?.start))
}

/// The dotted path (`kinds[3].capacity`) of the smallest key or value around byte `pos` of
/// `text`, or empty. A table's span is its header only, so every node is visited.
fn field_at(text: &str, pos: usize) -> String {
    /// The best so far: span length and path.
    type Best = Option<(usize, String)>;
    fn consider(best: &mut Best, span: Range<usize>, pos: usize, path: &str) {
        let inside =
            span.start <= pos && (pos < span.end || (span.is_empty() && pos == span.start));
        // `<=`: children come after their parent, and the deeper path says more.
        if inside && best.as_ref().is_none_or(|(len, _)| span.len() <= *len) {
            *best = Some((span.len(), path.to_owned()));
        }
    }
    fn visit(value: &DeValue<'_>, path: &str, pos: usize, best: &mut Best) {
        match value {
            DeValue::Table(table) => {
                for (key, child) in table.iter() {
                    let path = if path.is_empty() {
                        key.get_ref().to_string()
                    } else {
                        format!("{path}.{}", key.get_ref())
                    };
                    consider(best, key.span(), pos, &path);
                    consider(best, child.span(), pos, &path);
                    visit(child.get_ref(), &path, pos, best);
                }
            }
            DeValue::Array(array) => {
                for (i, child) in array.iter().enumerate() {
                    let path = format!("{path}[{i}]");
                    consider(best, child.span(), pos, &path);
                    visit(child.get_ref(), &path, pos, best);
                }
            }
            _ => {}
        }
    }
    let Ok(doc) = DeTable::parse(text) else {
        return String::new();
    };
    let mut best = None;
    visit(&DeValue::Table(doc.into_inner()), "", pos, &mut best);
    best.map(|(_, path)| path).unwrap_or_default()
}

/// The line of the value at the TOML path `field` (`kinds[1].collides_with[0]`), or of the
/// deepest table or array element on the way that is present (a defaulted key's table).
fn line_of_field(text: &str, field: &str) -> Option<usize> {
    let doc = DeTable::parse(text).ok()?;
    let root = Spanned::new(doc.span(), DeValue::Table(doc.into_inner()));
    let mut node = &root;
    let mut span = None;
    'walk: for part in field.split('.') {
        let mut steps = part.split('[');
        let key = steps.next().unwrap_or_default();
        match node.get_ref().get(key) {
            Some(child) => node = child,
            None => break,
        }
        span = Some(node.span());
        for index in steps {
            let Some(child) = index
                .strip_suffix(']')
                .and_then(|i| i.parse::<usize>().ok())
                .and_then(|i| node.get_ref().get(i))
            else {
                break 'walk;
            };
            node = child;
            span = Some(node.span());
        }
    }
    line_at(text, span)
}
