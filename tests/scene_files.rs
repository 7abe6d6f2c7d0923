//! Scene files: the built-in scenes read, and each way of breaking `paper.toml` gives an
//! error that names the right line and field (and the allowed range, for ranges).

use std::io::Write;

use gpuwars::game::scene::{BUILT_IN, SceneError, built_in};
use gpuwars::game::spec::Scene;
use proptest::prelude::*;

/// The file the mutations start from.
fn paper() -> &'static str {
    BUILT_IN[0].source
}

/// `paper.toml` with the first `from` replaced by `to`.
fn mutate(from: &str, to: &str) -> String {
    assert!(paper().contains(from), "paper.toml lacks {from:?}");
    paper().replacen(from, to, 1)
}

/// 1-based line of the first `needle` in `text`.
fn line_of(text: &str, needle: &str) -> usize {
    let at = text.find(needle).unwrap_or_else(|| panic!("no {needle:?}"));
    text[..at].matches('\n').count() + 1
}

/// The error reading `text` gives.
fn error(text: &str) -> SceneError {
    match Scene::from_toml(text, "paper.toml") {
        Ok(_) => panic!("read without error:\n{text}"),
        Err(e) => e,
    }
}

/// Reading `text` fails at `line` on `field`, and the message holds each of `says`.
fn assert_error(text: &str, line: usize, field: &str, says: &[&str]) {
    let e = error(text);
    let message = e.to_string();
    assert_eq!(e.line, Some(line), "{message}");
    assert_eq!(e.field, field, "{message}");
    let prefix = match field {
        "" => format!("paper.toml:{line}: "),
        field => format!("paper.toml:{line}: {field}: "),
    };
    assert!(message.starts_with(&prefix), "{message}");
    for part in says {
        assert!(message.contains(part), "{message:?} lacks {part:?}");
    }
}

#[test]
fn every_built_in_reads() {
    let names: Vec<_> = BUILT_IN.iter().map(|b| b.name).collect();
    assert_eq!(
        names,
        [
            "paper",
            "kamikaze",
            "group",
            "tricky",
            "arena",
            "scale-1m",
            "scale-16m"
        ]
    );
    for b in BUILT_IN {
        let scene = b.scene().unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(scene.name, b.name);
        assert_eq!(scene.source, b.source);
        scene.world.validate().unwrap();
    }
    assert!(built_in("nope").is_none());
}

#[test]
fn paper_reads_as_written() {
    let scene = Scene::load("paper").unwrap();
    assert_eq!(scene.world.kinds.len(), 9);
    assert_eq!(scene.world.vision, 0.0);
    assert_eq!(scene.game.spawn.waves.len(), 7);
    let ship = &scene.world.kinds[0];
    assert_eq!(
        (ship.max_speed, ship.lifetime),
        (f32::INFINITY, f32::INFINITY)
    );
    let polygon = scene.game.behaviours[2].unwrap();
    let texel = scene.game.behaviours[4].unwrap();
    assert!(!polygon.avoid_bullets && texel.avoid_bullets);
    assert_eq!(scene.game.behaviours[7].unwrap().low_energy, 1);
    // The world knows only which kinds the enemies' machines drive.
    let controlled: Vec<bool> = scene.world.kinds.iter().map(|k| k.controlled).collect();
    let behaving: Vec<bool> = scene.game.behaviours.iter().map(Option::is_some).collect();
    assert_eq!(controlled, behaving);
}

#[test]
fn loads_a_file_by_path() {
    let mut file = tempfile::NamedTempFile::new().unwrap();
    file.write_all(paper().as_bytes()).unwrap();
    let path = file.path().to_str().unwrap();
    assert_eq!(Scene::load(path).unwrap(), Scene::load("paper").unwrap());

    let broken = mutate("dt = 0.016666668", "dt = 2.0");
    std::fs::write(file.path(), &broken).unwrap();
    let message = Scene::load(path).unwrap_err().to_string();
    let line = line_of(&broken, "dt = 2.0");
    assert!(
        message.starts_with(&format!("{path}:{line}: world.dt: ")),
        "{message}"
    );
}

#[test]
fn a_missing_file_has_no_line() {
    let e = Scene::load("no/such/scene.toml").unwrap_err();
    assert_eq!((e.line, e.field.as_str()), (None, ""));
    assert!(e.to_string().starts_with("no/such/scene.toml: "), "{e}");
}

#[test]
fn a_missing_top_level_key_has_no_line() {
    let e = error(&mutate("name = \"paper\"\n", ""));
    assert_eq!((e.line, e.field.as_str()), (None, ""));
    assert_eq!(e.to_string(), "paper.toml: missing field `name`");
}

#[test]
fn truncated_files() {
    // In the middle of a string: a syntax error at the end, with no field.
    let cut = &paper()[..paper().find("benchmark").unwrap()];
    assert_error(cut, cut.lines().count(), "", &["string"]);

    // In the middle of a key: a syntax error on the last line.
    let cut = &paper()[..paper().rfind("recovery").unwrap() + 5];
    assert_error(cut, cut.lines().count(), "", &["expected `=`"]);

    // In the middle of `dt = 0.016666668`: it parses, but `[world]` lacks `boundary`.
    let cut = &paper()[..paper().find("0.0166").unwrap() + 4];
    assert_error(
        cut,
        line_of(cut, "[world]"),
        "world",
        &["missing field `boundary`"],
    );
}

#[test]
fn wrong_types() {
    let text = mutate("capacity = 1\n", "capacity = \"ten\"\n");
    let line = line_of(&text, "\"ten\"");
    assert_error(
        &text,
        line,
        "kinds[0].capacity",
        &["invalid type", "\"ten\""],
    );

    let text = mutate("size = [4096.0, 4096.0]", "size = [1.0]");
    let line = line_of(&text, "size");
    assert_error(&text, line, "world.size", &["invalid length 1"]);

    let text = mutate("boundary = \"clamp\"", "boundary = 3");
    let line = line_of(&text, "boundary");
    assert_error(
        &text,
        line,
        "world.boundary",
        &["invalid type: integer `3`"],
    );

    let text = mutate("boundary = \"clamp\"", "boundary = \"bounce\"");
    let line = line_of(&text, "boundary");
    assert_error(
        &text,
        line,
        "world.boundary",
        &["`bounce`", "`clamp` or `wrap`"],
    );

    // Integers stand for floats, not the other way round.
    assert!(Scene::from_toml(&mutate("speed = 240.0", "speed = 240"), "paper.toml").is_ok());
    let text = mutate("count = 512", "count = 5.5");
    let line = line_of(&text, "count = 5.5");
    assert_error(&text, line, "spawn.waves[0].count", &["invalid type"]);
}

#[test]
fn out_of_range() {
    let cases = [
        // (from, to, field, allowed)
        (
            "mass = 0.1",
            "mass = 0.0",
            "kinds[1].mass",
            "0 is out of range (allowed (0, inf])",
        ),
        (
            "dt = 0.016666668",
            "dt = 2.0",
            "world.dt",
            "2 is out of range (allowed (0, 1])",
        ),
        (
            "min = 12.0",
            "min = 70.0",
            "fps.min",
            "70 is out of range (allowed [0, 60])",
        ),
        (
            "restitution = 0.2",
            "restitution = 1.5",
            "kinds[0].restitution",
            "1.5 is out of range (allowed [0, 1])",
        ),
        (
            "capacity = 64",
            "capacity = -64",
            "kinds[1].capacity",
            "-64 is out of range (allowed 1 to 16777216)",
        ),
        (
            "low_energy = 1",
            "low_energy = 3",
            "kinds[7].behaviour.low_energy",
            "3 is out of range (allowed 0 to 2, below the birth energy)",
        ),
        (
            "times = 100",
            "times = 0",
            "spawn.waves[0].times",
            "0 is out of range (allowed 1 to 4294967295)",
        ),
        (
            "circle = 2.0",
            "circle = -2.0",
            "kinds[1].circle",
            "-2 is out of range (allowed (0, 1000000])",
        ),
        (
            "fire_rate = 10.0",
            "fire_rate = nan",
            "ship.fire_rate",
            "NaN is out of range (allowed (0, 1000])",
        ),
        (
            "distance = 400.0",
            "distance = -1",
            "spawn.distance",
            "-1 is out of range (allowed [0, 1000000])",
        ),
        (
            "every = 4.0",
            "every = 0.0",
            "spawn.waves[0].every",
            "0 is out of range (allowed (0, 1000000])",
        ),
    ];
    for (from, to, field, allowed) in cases {
        let text = mutate(from, to);
        assert_error(&text, line_of(&text, to), field, &[allowed]);
    }

    // Repeating needs `every`; the line is the first wave's `times`.
    let text = mutate("every = 4.0\n", "");
    let line = line_of(&text, "times = 100");
    assert_error(
        &text,
        line,
        "spawn.waves[0].times",
        &["allowed 1 without `every`"],
    );

    // A rectangle's half extents are one key.
    let text = mutate("circle = 2.0", "rect = [2.0, 0.0]");
    let line = line_of(&text, "rect");
    assert_error(&text, line, "kinds[1].rect", &["allowed (0, 1000000]"]);
}

#[test]
fn unknown_keys() {
    let cases = [
        // (after, inserted, field)
        ("description = ", "colour = \"red\"", "colour"),
        ("boundary = \"clamp\"\n", "gravity = 9.8", "world.gravity"),
        ("name = \"shot\"\n", "speed = 3.0", "kinds[1].speed"),
        (
            "machine = \"kamikaze\"\n",
            "aggression = 1",
            "kinds[2].behaviour.aggression",
        ),
        ("times = 100\n", "jitter = 1.0", "spawn.waves[0].jitter"),
    ];
    for (after, inserted, field) in cases {
        // Insert on a line of its own after the first line holding `after`.
        let at = paper().find(after).unwrap();
        let end = at + paper()[at..].find('\n').unwrap() + 1;
        let text = format!("{}{inserted}\n{}", &paper()[..end], &paper()[end..]);
        let key = inserted.split(' ').next().unwrap();
        assert_error(
            &text,
            line_of(&text, inserted),
            field,
            &[&format!("unknown field `{key}`")],
        );
    }
}

#[test]
fn bad_references() {
    let text = mutate("kind = \"ship\"", "kind = \"boat\"");
    let line = line_of(&text, "\"boat\"");
    assert_error(&text, line, "ship.kind", &["no kind is named `boat`"]);

    let text = mutate("\"polygon\", \"vertex\"", "\"polygon\", \"vortex\"");
    let line = line_of(&text, "\"vortex\"");
    assert_error(
        &text,
        line,
        "kinds[0].collides_with[1]",
        &["no kind is named `vortex`"],
    );

    let text = mutate("kind = \"polygon\"\nat", "kind = \"shot\"\nat");
    let line = line_of(&text, "kind = \"shot\"");
    assert_error(
        &text,
        line,
        "spawn.waves[0].kind",
        &["`shot` is the shots' kind"],
    );

    let text = mutate("shot = \"shot\"", "shot = \"polygon\"");
    let line = line_of(&text, "shot = \"polygon\"");
    assert_error(&text, line, "ship.shot", &["has a behaviour"]);

    let text = mutate("kind = \"ship\"", "kind = \"shot\"");
    let line = line_of(&text, "kind = \"shot\"");
    assert_error(&text, line, "ship.kind", &["capacity 64 (allowed 1"]);
}

#[test]
fn shapes() {
    let text = mutate("circle = 2.0\n", "circle = 2.0\nrect = [2.0, 2.0]\n");
    let line = line_of(&text, "rect");
    assert_error(&text, line, "kinds[1].rect", &["conflicts with `circle`"]);

    // No shape: the line is the kind's header.
    let text = mutate("circle = 2.0\n", "");
    let line = line_of(&text, "name = \"shot\"") - 1;
    assert_error(&text, line, "kinds[1]", &["has no shape"]);
}

#[test]
fn duplicate_kind_names() {
    let text = format!(
        "{}\n[[kinds]]\nname = \"shot\"\ncircle = 1.0\nmass = 1.0\ncapacity = 1\nenergy = 1\n",
        paper()
    );
    let line = text[..text.rfind("name = \"shot\"").unwrap()]
        .matches('\n')
        .count()
        + 1;
    assert_error(
        &text,
        line,
        "kinds[9].name",
        &["is used by an earlier kind"],
    );
}

#[test]
fn behaviours() {
    let text = mutate("machine = \"kamikaze\"", "machine = \"berserk\"");
    let line = line_of(&text, "berserk");
    assert_error(
        &text,
        line,
        "kinds[2].behaviour.machine",
        &["unknown machine `berserk`"],
    );

    let text = mutate(
        "machine = \"kamikaze\"",
        "machine = \"kamikaze\"\navoid_bullets = true",
    );
    let line = line_of(&text, "avoid_bullets");
    assert_error(
        &text,
        line,
        "kinds[2].behaviour.avoid_bullets",
        &["kamikaze does not avoid bullets"],
    );
    let text = mutate(
        "machine = \"kamikaze\"",
        "machine = \"kamikaze\"\navoid_bullets = false",
    );
    assert!(Scene::from_toml(&text, "paper.toml").is_ok());

    let text = mutate("machine = \"group\"", "machine = \"group\"\nlow_energy = 1");
    let line = line_of(&text, "low_energy = 1");
    assert_error(
        &text,
        line,
        "kinds[4].behaviour.low_energy",
        &["allowed 0 for a group"],
    );

    // A rule across the world and the game: `behaviour.speed` above the kind's `max_speed`.
    let text = mutate("speed = 70.0\n\n", "speed = 75.0\n\n");
    let line = line_of(&text, "speed = 75.0");
    assert_error(
        &text,
        line,
        "kinds[2].behaviour.speed",
        &["75 is out of range (allowed (0, 70])"],
    );
}

#[test]
fn deep_nesting_is_an_error() {
    let deep = format!("{}1{}", "[".repeat(100_000), "]".repeat(100_000));
    let text = mutate("[4096.0, 4096.0]", &deep);
    let e = error(&text);
    assert_eq!(e.line, Some(line_of(&text, "size")), "{e}");
}

/// A char index of `text` as a byte offset (the files may hold non-ASCII text).
fn byte_at(text: &str, index: prop::sample::Index) -> usize {
    let chars = text.chars().count();
    text.char_indices()
        .nth(index.index(chars))
        .map_or(text.len(), |(at, _)| at)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn truncation_never_panics(scene in 0..BUILT_IN.len(), cut in any::<prop::sample::Index>()) {
        let text = BUILT_IN[scene].source;
        let _ = Scene::from_toml(&text[..byte_at(text, cut)], "cut.toml");
    }

    #[test]
    fn a_changed_char_never_panics(
        scene in 0..BUILT_IN.len(),
        at in any::<prop::sample::Index>(),
        by in prop_oneof![
            prop::sample::select(b"[]{}=\".,#\n0-+eil ".to_vec()).prop_map(char::from),
            any::<char>(),
        ],
    ) {
        let mut text = BUILT_IN[scene].source.to_owned();
        let at = byte_at(&text, at);
        if let Some(old) = text[at..].chars().next() {
            text.replace_range(at..at + old.len_utf8(), by.encode_utf8(&mut [0; 4]));
        }
        let _ = Scene::from_toml(&text, "changed.toml");
    }
}
