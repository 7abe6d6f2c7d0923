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

/// The scenes `tune` wrote for docs/tradeoff.md's worked examples read and validate, and
/// differ from the built-in they were tuned from only where the docs say: each is that
/// scene with one choice, so its name is the built-in's.
#[test]
fn the_tuned_scenes_in_the_docs_read() {
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/docs/tuned");
    let mut read = 0;
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        let scene = Scene::load(path.to_str().unwrap()).unwrap_or_else(|e| panic!("{e}"));
        scene.validate().unwrap();
        let given = built_in(&scene.name).unwrap().unwrap();
        assert_ne!(
            scene.world,
            given.world,
            "{}: nothing tuned",
            path.display()
        );
        assert_eq!(scene.game, given.game, "{}", path.display());
        read += 1;
    }
    assert!(read >= 3, "{read} tuned scenes in {dir}");
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
    assert_eq!(e.to_string(), "paper.toml: missing key `name`");
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
        &["missing key `boundary`"],
    );
}

/// A key written twice is named, at the line of its second writing; so is a table.
#[test]
fn a_duplicate_key_is_named() {
    let text = mutate("capacity = 64", "capacity = 64\ncapacity = 65");
    let line = line_of(&text, "capacity = 65");
    assert_error(&text, line, "", &["duplicate key `capacity`"]);
    let text = format!("{}\n[fps]\nstart = 60.0\n", paper());
    let line = text.lines().count() - 1;
    assert_error(&text, line, "", &["duplicate key `fps`"]);
}

#[test]
fn wrong_types() {
    let text = mutate("capacity = 1\n", "capacity = \"ten\"\n");
    let line = line_of(&text, "\"ten\"");
    assert_error(
        &text,
        line,
        "kinds[0].capacity",
        &["expected a whole number from 1 to 16,777,216, found \"ten\""],
    );

    let text = mutate("size = [4096.0, 4096.0]", "size = [1.0]");
    let line = line_of(&text, "size");
    assert_error(
        &text,
        line,
        "world.size",
        &["has 1 value (allowed exactly 2: [width, height], each in (0, 1000000])"],
    );

    let text = mutate("boundary = \"clamp\"", "boundary = 3");
    let line = line_of(&text, "boundary");
    assert_error(
        &text,
        line,
        "world.boundary",
        &["expected a boundary in quotes (`clamp` or `wrap`), found 3"],
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
    assert_error(
        &text,
        line,
        "spawn.waves[0].count",
        &["expected a whole number from 1 to 4,294,967,295, found 5.5"],
    );
}

#[test]
fn out_of_range() {
    let cases = [
        // (from, to, field, allowed)
        (
            "mass = 0.1",
            "mass = 0.0",
            "kinds[1].mass",
            "0.0 is out of range (allowed (0, inf])",
        ),
        (
            "dt = 0.016666668",
            "dt = 2.0",
            "world.dt",
            "2.0 is out of range (allowed (0, 1])",
        ),
        (
            "min = 12.0",
            "min = 70.0",
            "fps.min",
            "70.0 is out of range (allowed [0, 60]: at most fps.start)",
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
            "-64 is out of range (allowed a whole number from 1 to 16,777,216)",
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
            "0 is out of range (allowed a whole number from 1 to 4,294,967,295)",
        ),
        (
            "circle = 2.0",
            "circle = -2.0",
            "kinds[1].circle",
            "-2.0 is out of range (allowed (0, 1000000])",
        ),
        (
            "fire_rate = 10.0",
            "fire_rate = nan",
            "ship.fire_rate",
            "nan is out of range (allowed (0, 1000])",
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
            "0.0 is out of range (allowed (0, 1000000])",
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

    // A rectangle's half extents are one key, whose element is named.
    let text = mutate("circle = 2.0", "rect = [2.0, 0.0]");
    let line = line_of(&text, "rect");
    assert_error(&text, line, "kinds[1].rect[1]", &["allowed (0, 1000000]"]);
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
        assert_error(
            &text,
            line_of(&text, inserted),
            field,
            &["unknown key (allowed `"],
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

/// Names and the description are one line of printable text: a control character (the
/// first and the last of C0, DEL, a C1 one, a newline) is refused, naming its code and
/// place; text beyond ASCII is kept.
#[test]
fn names_hold_no_control_characters() {
    let name = "name = \"paper\"";
    let kind = "name = \"ship\"";
    let first = paper()
        .lines()
        .find(|l| l.starts_with("description"))
        .unwrap();
    for (field, from, escape, code) in [
        ("name", name, "\\u0000", "U+0000"),
        ("name", name, "\\u001f", "U+001F"),
        ("name", name, "\\u007f", "U+007F"),
        ("description", first, "\\u009b", "U+009B"),
        ("kinds[0].name", kind, "\\n", "U+000A"),
        ("kinds[0].name", kind, "\\u001b[31m", "U+001B"),
    ] {
        // The character after the value's first: character 2.
        let at = from.find('"').unwrap() + 2;
        let to = format!("{}{escape}{}", &from[..at], &from[at..]);
        let text = mutate(from, &to);
        let message = format!("control character ({code}, character 2) is not allowed");
        assert_error(&text, line_of(&text, &to), field, &[&message]);
    }
    let text = mutate(name, "name = \"paper · 论文\"");
    let scene = Scene::from_toml(&text, "paper.toml").unwrap();
    assert_eq!(scene.name, "paper · 论文");
}

/// The spawn distance reaches at most as far as a place can be from the ship: the field's
/// diagonal, or half of it on a torus; one unit past it is refused naming the bound.
#[test]
fn the_spawn_distance_fits_the_field() {
    let from = "distance = 400.0";
    for (boundary, fits, past, bound) in [
        ("clamp", "5792.0", "5793.0", "allowed 0 to 5792.6187"),
        ("wrap", "2896.0", "2897.0", "allowed 0 to 2896.3093"),
    ] {
        let base = mutate(
            "boundary = \"clamp\"",
            &format!("boundary = \"{boundary}\""),
        );
        let at = |distance: &str| base.replacen(from, &format!("distance = {distance}"), 1);
        let scene = Scene::from_toml(&at(fits), "paper.toml").unwrap();
        assert_eq!(scene.game.spawn.distance, fits.parse::<f32>().unwrap());
        let text = at(past);
        assert_error(
            &text,
            line_of(&text, "distance = "),
            "spawn.distance",
            &["farther than any place of the 4096 x 4096 field", bound],
        );
    }
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
        &["75.0 is out of range (allowed (0, 70]: at most the kind's max_speed)"],
    );
}

#[test]
fn numbers_are_checked_as_written_before_rounding() {
    // Beyond an f32: a finite mass is not "infinite" (immovable).
    let text = mutate("mass = 0.1", "mass = 1e39");
    assert_error(
        &text,
        line_of(&text, "1e39"),
        "kinds[1].mass",
        &["1e39 is too large to store (allowed (0, inf], finite numbers at most 3.4028235e38)"],
    );
    // Beyond an f64 too.
    let text = mutate("mass = 0.1", "mass = 1e400");
    assert_error(
        &text,
        line_of(&text, "1e400"),
        "kinds[1].mass",
        &["1e400 is too large"],
    );
    // So small that it would round to 0 (or lose its precision): not "0".
    // Just under the smallest normal number, which it would round up to: refused, and the
    // bound said in full.
    for tiny in ["1e-50", "1e-40", "1e-400", "1.1754943e-38"] {
        let text = mutate("dt = 0.016666668", &format!("dt = {tiny}"));
        let says = format!("{tiny} is too close to 0 to store (allowed (0, 1]");
        let bound = "at least 1.1754943508222875e-38 in size";
        assert_error(&text, line_of(&text, tiny), "world.dt", &[&says, bound]);
    }
    // Just above a bound: out of range, not rounded into it.
    let text = mutate("dt = 0.016666668", "dt = 1.00000001");
    assert_error(
        &text,
        line_of(&text, "1.00000001"),
        "world.dt",
        &["1.00000001 is out"],
    );
    let text = mutate("restitution = 0.2", "restitution = 1.0000000001");
    let line = line_of(&text, "1.0000000001");
    assert_error(&text, line, "kinds[0].restitution", &["out of range"]);
    // An integer as large as TOML allows, or larger: a range error, not a type's name.
    for huge in [
        "9223372036854775807",
        "99999999999999999999",
        "-99999999999999999999",
    ] {
        let text = mutate("capacity = 1\n", &format!("capacity = {huge}\n"));
        let says = format!("{huge} is out of range (allowed a whole number from 1 to 16,777,216)");
        assert_error(&text, line_of(&text, huge), "kinds[0].capacity", &[&says]);
    }
    // Other spellings of a number TOML allows.
    let text = mutate("capacity = 64", "capacity = 0x40");
    assert_eq!(
        Scene::from_toml(&text, "hex").unwrap().world.kinds[1].capacity,
        64
    );
    let text = mutate("speed = 240.0", "speed = 2_4_0");
    assert_eq!(
        Scene::from_toml(&text, "underscores")
            .unwrap()
            .game
            .ship
            .speed,
        240.0
    );
    let text = mutate("lifetime = 1.0", "lifetime = inf");
    assert!(
        Scene::from_toml(&text, "inf").unwrap().world.kinds[1]
            .lifetime
            .is_infinite()
    );
    let text = mutate("lifetime = 1.0", "lifetime = -inf");
    assert_error(
        &text,
        line_of(&text, "-inf"),
        "kinds[1].lifetime",
        &["-inf is out"],
    );
}

/// Ways of writing `v` that TOML reads and that round to `v` in an `f32`: the shortest,
/// in scientific notation, with ten significant digits, and with digits past those f32
/// keeps.
fn spellings(v: f32) -> Vec<String> {
    let mut out = vec![format!("{v:?}"), format!("{v:e}"), format!("{v:.9e}")];
    let long = format!("{:.12e}", f64::from(v) * (1.0 + 1e-11));
    assert_eq!(long.parse::<f32>().unwrap(), v, "{long}");
    out.push(long);
    out
}

proptest! {
    /// A bound that is another value of the file is compared with the same rounding on
    /// both sides: an enemy's `speed` equal to its kind's `max_speed`, and `fps.min` equal
    /// to `fps.start`, are read in every spelling of every value (70.7 was refused against
    /// 70.7, its limit rounded down by f32 and the speed compared as written); the next
    /// f32 above the bound is refused, naming it.
    #[test]
    fn a_bound_from_another_value_is_compared_as_stored(
        v in 1.0e-3f32..1.0e6,
        a in 0usize..4,
        b in 0usize..4,
    ) {
        let (limit, speed) = (&spellings(v)[a], &spellings(v)[b]);
        let text = mutate("max_speed = 70.0", &format!("max_speed = {limit}"))
            .replacen("\nspeed = 70.0", &format!("\nspeed = {speed}"), 1);
        let scene = Scene::from_toml(&text, "paper.toml");
        prop_assert!(scene.is_ok(), "{limit} against {speed}: {}", scene.unwrap_err());
        let over = v.next_up();
        let text = mutate("max_speed = 70.0", &format!("max_speed = {limit}"))
            .replacen("\nspeed = 70.0", &format!("\nspeed = {over:?}"), 1);
        let says = format!("{over:?} is out of range");
        prop_assert!(error(&text).to_string().contains(&says), "{}", error(&text));

        let v = v.min(1000.0);
        let (start, min) = (&spellings(v)[a], &spellings(v)[b]);
        let text = mutate("start = 60.0", &format!("start = {start}"))
            .replacen("min = 12.0", &format!("min = {min}"), 1);
        let scene = Scene::from_toml(&text, "paper.toml");
        prop_assert!(scene.is_ok(), "{start} against {min}: {}", scene.unwrap_err());
    }
}

#[test]
fn arrays_have_exactly_their_length() {
    for (to, says) in [
        ("[4096.0, 4096.0, \"x\"]", "has 3 values"),
        ("[4096.0, 4096.0, 1.0]", "has 3 values"),
        ("[]", "has 0 values"),
        (
            "4096.0",
            "expected an array [width, height] of two numbers in (0, 1000000]",
        ),
    ] {
        let text = mutate("[4096.0, 4096.0]", to);
        assert_error(&text, line_of(&text, "size"), "world.size", &[says]);
    }
    // An element's error names the element.
    for (to, field, says) in [
        (
            "[4096.0, \"x\"]",
            "world.size[1]",
            "expected a number in (0, 1000000], found \"x\"",
        ),
        (
            "[-0.0, 4096.0]",
            "world.size[0]",
            "-0.0 is out of range (allowed (0, 1000000])",
        ),
        (
            "[4096.0, 1000000.1]",
            "world.size[1]",
            "1000000.1 is out of range",
        ),
    ] {
        let text = mutate("[4096.0, 4096.0]", to);
        assert_error(&text, line_of(&text, "size"), field, &[says]);
    }
    let text = mutate("circle = 2.0", "rect = [1.0, 2.0, 3.0]");
    assert_error(
        &text,
        line_of(&text, "rect"),
        "kinds[1].rect",
        &["has 3 values"],
    );
}

#[test]
fn a_byte_order_mark_is_skipped() {
    let text = format!("\u{feff}{}", paper());
    let scene = Scene::from_toml(&text, "bom.toml").expect("reads like the file without it");
    assert_eq!(scene.world, Scene::load("paper").unwrap().world);
    // Lines still count from the first.
    let text = format!("\u{feff}{}", mutate("dt = 0.016666668", "dt = 2.0"));
    assert_error(
        &text,
        line_of(&text, "dt = 2.0"),
        "world.dt",
        &["2.0 is out"],
    );
}

#[test]
fn errors_speak_of_the_file_not_of_rust() {
    let cases = [
        (
            "[world]\nsize = [4096.0, 4096.0]\ndt = 0.016666668\nboundary = \"clamp\"\n",
            "world = 1\n",
            "world",
            "expected a table, found 1",
        ),
        (
            "name = \"paper\"",
            "name = 5",
            "name",
            "expected a name in quotes, found 5",
        ),
        ("name = \"paper\"", "name = [1]", "name", "found an array"),
        (
            "name = \"paper\"",
            "name = {a = 1}",
            "name",
            "found a table",
        ),
        (
            "name = \"paper\"",
            "name = 1979-05-27",
            "name",
            "found 1979-05-27",
        ),
        (
            "machine = \"kamikaze\"\n",
            "machine = \"kamikaze\"\navoid_bullets = 1\n",
            "kinds[2].behaviour.avoid_bullets",
            "expected true or false, found 1",
        ),
        (
            "collides_with = [\"polygon\"",
            "collides_with = [7, \"polygon\"",
            "kinds[0].collides_with[0]",
            "expected a kind's name in quotes, found 7",
        ),
        (
            "capacity = 64",
            "capacity = true",
            "kinds[1].capacity",
            "found true",
        ),
        (
            "mass = 0.1",
            "mass = \"heavy\"",
            "kinds[1].mass",
            "expected a number in (0, inf]",
        ),
    ];
    for (from, to, field, says) in cases {
        let text = mutate(from, to);
        let line = line_of(&text, to.lines().last().unwrap());
        assert_error(&text, line, field, &[says]);
        let message = error(&text).to_string();
        for rust in [
            "i64",
            "f32",
            "u32",
            "i128",
            "struct",
            "sequence",
            "map",
            "invalid type",
        ] {
            assert!(!message.contains(rust), "{message:?} speaks of `{rust}`");
        }
    }
}

#[test]
fn errors_quote_only_an_excerpt_of_a_huge_value() {
    let huge = "x".repeat(100_000);
    let cases = [
        ("kind = \"ship\"", format!("kind = \"{huge}\""), "ship.kind"),
        (
            "boundary = \"clamp\"",
            format!("boundary = \"{huge}\""),
            "world.boundary",
        ),
        (
            "capacity = 64",
            format!("capacity = \"{huge}\""),
            "kinds[1].capacity",
        ),
        (
            "capacity = 64",
            format!("capacity = 1{}", "0".repeat(100_000)),
            "kinds[1].capacity",
        ),
    ];
    for (from, to, field) in cases {
        let text = mutate(from, &to);
        let e = error(&text);
        assert_eq!(e.field, field, "{e}");
        assert!(
            e.to_string().len() < 400,
            "{} bytes: {e}",
            e.to_string().len()
        );
        assert!(e.problem.contains('…'), "{e}");
    }
    // An unknown key of any length, and a kind's name of any length.
    let text = mutate("[world]\n", &format!("[world]\n{huge} = 1\n"));
    assert!(error(&text).to_string().len() < 400);
    let text = mutate("name = \"polygon\"", &format!("name = \"{huge}\""));
    assert!(error(&text).to_string().len() < 400);
    // Control characters are shown escaped, never sent to the terminal.
    let text = mutate("kind = \"ship\"", "kind = \"\\u001b[2J\"");
    let e = error(&text);
    assert!(!e.to_string().contains('\u{1b}'), "{e}");
    assert!(e.to_string().contains("\\u001b[2J"), "{e}");
}

#[test]
fn deep_dotted_keys_have_a_line() {
    let key = format!("x{}", ".x".repeat(200));
    for deep in [format!("{key} = 1"), format!("[{key}]")] {
        let text = format!("{}\n{deep}\n", paper());
        let e = error(&text);
        assert_eq!(e.line, Some(line_of(&text, &deep)), "{e}");
        assert!(e.problem.contains("nested too deeply"), "{e}");
    }
}

#[test]
fn only_regular_files_of_a_bounded_size_are_read() {
    let dir = tempfile::tempdir().unwrap();
    let folder = dir.path().display().to_string();
    let e = Scene::load(&folder).unwrap_err();
    assert_eq!(
        e.to_string(),
        format!("{folder}: cannot read: it is a folder (allowed a regular file)")
    );
    // Devices as files in a folder are Unix's (`/dev`).
    if cfg!(unix) {
        let e = Scene::load("/dev/null").unwrap_err();
        assert!(e.problem.contains("it is a device"), "{e}");
    }
    // A named pipe is refused without being opened: opening it would wait for a writer.
    let fifo = dir.path().join("pipe.toml");
    let made = std::process::Command::new("mkfifo").arg(&fifo).status();
    if made.is_ok_and(|status| status.success()) {
        let e = Scene::load(fifo.to_str().unwrap()).unwrap_err();
        assert!(e.problem.contains("it is a named pipe"), "{e}");
    }
    let big = dir.path().join("big.toml");
    let limit = gpuwars::files::MAX_SCENE_BYTES as usize;
    std::fs::write(&big, format!("{}\n{}", paper(), "#".repeat(limit))).unwrap();
    let e = Scene::load(big.to_str().unwrap()).unwrap_err();
    assert!(e.problem.contains("(allowed at most 1,048,576)"), "{e}");
}

#[test]
fn invalid_utf8_has_a_line_and_column() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("latin1.toml");
    let mut bytes = mutate("name = \"paper\"", "name = \"p\u{e9}per\"").into_bytes();
    let at = bytes.iter().position(|&b| b == 0xc3).unwrap();
    bytes[at] = 0xe9;
    bytes.remove(at + 1);
    std::fs::write(&path, &bytes).unwrap();
    let e = Scene::load(path.to_str().unwrap()).unwrap_err();
    assert_eq!(e.line, Some(2), "{e}");
    assert!(e.problem.contains("byte 0xe9 at column 10"), "{e}");
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

/// `paper.toml` with a `[physics]` table of `body` appended.
fn with_physics(body: &str) -> String {
    format!("{}\n[physics]\n{body}\n", paper())
}

#[test]
fn the_physics_table_reads_every_choice() {
    use gpuwars::sim::{Integrator, Physics};
    let text = with_physics(
        "integrator = \"verlet\"\nsubsteps = 4\nrelaxation = 0.5\naveraged = true\n\
         cell_scale = 2\nneighbour_cap = 16\nvision_scale = 0.75\nsight_budget = 24\n\
         contact_budget = 48\nrenumber_every = 4",
    );
    let scene = Scene::from_toml(&text, "paper.toml").unwrap();
    assert_eq!(
        scene.world.physics,
        Physics {
            integrator: Integrator::VelocityVerlet,
            substeps: 4,
            relaxation: 0.5,
            averaged: true,
            cell_scale: 2.0,
            neighbour_cap: 16,
            vision_scale: 0.75,
            sight_budget: 24,
            contact_budget: 48,
            renumber_every: Some(4),
            ..Physics::default()
        }
    );
    // Without the table, and with an empty one, the paper's defaults.
    let plain = Scene::from_toml(paper(), "paper.toml").unwrap();
    assert_eq!(plain.world.physics, Physics::default());
    let empty = Scene::from_toml(&with_physics(""), "paper.toml").unwrap();
    assert_eq!(empty.world.physics, Physics::default());
}

#[test]
fn bad_physics_choices_name_the_key_and_the_allowed_values() {
    let cases: [(&str, &str, &[&str]); 11] = [
        ("substeps = 0", "physics.substeps", &["from 1 to 64"]),
        ("substeps = 65", "physics.substeps", &["from 1 to 64"]),
        ("substeps = 2.0", "physics.substeps", &["whole number"]),
        ("relaxation = 0", "physics.relaxation", &["(0, 1]"]),
        ("cell_scale = 0.5", "physics.cell_scale", &["[1, 64]"]),
        (
            "neighbour_cap = -1",
            "physics.neighbour_cap",
            &["from 0 to"],
        ),
        (
            "sight_budget = 1.5",
            "physics.sight_budget",
            &["whole number"],
        ),
        (
            "contact_budget = 16777217",
            "physics.contact_budget",
            &["from 0 to 16,777,216"],
        ),
        (
            "integrator = \"rk4\"",
            "physics.integrator",
            &["euler", "explicit", "verlet"],
        ),
        ("averaged = 1", "physics.averaged", &["true or false"]),
        (
            "renumber_every = 65537",
            "physics.renumber_every",
            &["from 0 to 65,536"],
        ),
    ];
    for (body, field, says) in cases {
        let text = with_physics(body);
        let key = body.split(' ').next().unwrap();
        assert_error(&text, line_of(&text, &format!("{key} =")), field, says);
    }
    let text = with_physics("gravity = 9.81");
    assert_error(
        &text,
        line_of(&text, "gravity ="),
        "physics.gravity",
        &["unknown key", "substeps"],
    );
}

#[test]
fn the_effects_table_reads_every_key_and_defaults_the_rest() {
    use gpuwars::game::spec::EffectsSpec;
    let scene = Scene::from_toml(paper(), "paper.toml").unwrap();
    let written = EffectsSpec {
        particles: 12,
        lifetime: 0.7,
        speed: 260.0,
        speed_kept: 0.1,
    };
    assert_eq!(scene.game.effects, Some(written));
    let text = mutate("particles = 12\n", "");
    let scene = Scene::from_toml(&text, "paper.toml").unwrap();
    assert_eq!(
        scene.game.effects.unwrap().particles,
        EffectsSpec::default().particles
    );
    let start = paper().find("[effects]").unwrap();
    let end = start + paper()[start..].find("\n\n").unwrap();
    let text = format!("{}{}", &paper()[..start], &paper()[end..]);
    assert_eq!(
        Scene::from_toml(&text, "paper.toml").unwrap().game.effects,
        None
    );
}

#[test]
fn bad_effects_name_the_key_and_the_allowed_range() {
    let cases: [(&str, &str, &str, &[&str]); 6] = [
        (
            "particles = 12",
            "particles = 0",
            "effects.particles",
            &["from 1 to 64"],
        ),
        (
            "particles = 12",
            "particles = 65",
            "effects.particles",
            &["from 1 to 64"],
        ),
        (
            "lifetime = 0.7",
            "lifetime = 0",
            "effects.lifetime",
            &["(0, 10]"],
        ),
        ("speed = 260.0", "speed = -1", "effects.speed", &["[0, "]),
        (
            "speed_kept = 0.1",
            "speed_kept = 1.5",
            "effects.speed_kept",
            &["(0, 1]"],
        ),
        (
            "speed_kept = 0.1",
            "drag = 0.1",
            "effects.drag",
            &["unknown key", "speed_kept"],
        ),
    ];
    for (from, to, field, says) in cases {
        let text = mutate(&format!("\n{from}\n"), &format!("\n{to}\n"));
        assert_error(&text, line_of(&text, &format!("\n{to}\n")) + 1, field, says);
    }
    // Every enemy slot owns a kill's particles: 64 a kill for 300,000 enemies is too many.
    let text = mutate("capacity = 2048", "capacity = 300000").replacen(
        "particles = 12",
        "particles = 64",
        1,
    );
    assert_error(
        &text,
        line_of(&text, "particles = 64"),
        "effects.particles",
        &["64 a kill makes", "at most 16,777,216"],
    );
}
