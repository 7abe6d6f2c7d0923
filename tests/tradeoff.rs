//! `gpuwars tradeoff --quick`: its files parse and agree, and its figures obey what the
//! physics says they must (closed forms of each method's error, more substeps being more
//! accurate, caps missing contacts and no cap missing none); and the f64 reference itself
//! against closed forms.

mod common;

use std::collections::HashMap;
use std::process::Command;

use glam::{DVec2, Vec2};
use gpuwars::benchmark::tradeoff::reference::Reference;
use gpuwars::benchmark::tradeoff::{PhysicsRow, TradeoffSummary, crowd};
use gpuwars::kernels::rng::RngStreams;
use gpuwars::kernels::sim::Bodies;
use gpuwars::kernels::sim::free_list::FreeSlots;
use gpuwars::sim::{Physics, Snapshot};

/// Runs the quick matrix on `backend`; the summary it printed, checked against its files.
fn quick(backend: &str) -> TradeoffSummary {
    quick_of(backend, "paper")
}

/// [`quick`] of the game scene `scene` (a built-in name or a file).
fn quick_of(backend: &str, scene: &str) -> TradeoffSummary {
    let dir = tempfile::tempdir().unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_gpuwars"))
        .args([
            "--backend",
            backend,
            "tradeoff",
            "--quick",
            "--scene",
            scene,
            "--json",
            "--out",
        ])
        .arg(dir.path())
        .output()
        .expect("the binary runs");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let printed: TradeoffSummary = serde_json::from_slice(&out.stdout).unwrap();
    let file = |ext: &str| dir.path().join(format!("bench-tradeoff.{ext}"));
    let written: TradeoffSummary =
        serde_json::from_slice(&std::fs::read(file("json")).unwrap()).unwrap();
    assert_eq!(printed, written);
    let csv: Vec<PhysicsRow> = csv::Reader::from_path(file("csv"))
        .unwrap()
        .deserialize()
        .collect::<Result<_, _>>()
        .unwrap();
    assert_eq!(csv, printed.physics);
    let markdown = std::fs::read_to_string(file("md")).unwrap();
    for row in &printed.physics {
        assert!(
            markdown.contains(&format!("| {} |", row.choice)),
            "{}",
            row.choice
        );
    }
    // The game table prints each choice's accuracy columns.
    assert!(markdown.contains("| choice | steps/s | simulated s/s | contacts | between ends |"));
    for row in &printed.game {
        assert!(markdown.contains(&format!("| {} | ", row.choice)));
    }
    for name in ["bench-tradeoff.png", "bench-tradeoff-game.png"] {
        let path = dir.path().join(name);
        let plot = image::open(&path).unwrap();
        assert_eq!(
            (plot.width(), plot.height()),
            (1280, 720),
            "{}",
            path.display()
        );
    }
    printed
}

/// What every run's figures must satisfy, whatever the machine.
fn check(summary: &TradeoffSummary) {
    let rows: HashMap<&str, &PhysicsRow> = summary
        .physics
        .iter()
        .map(|r| (r.choice.as_str(), r))
        .collect();
    let rms = |choice: &str| rows[choice].position_rms;
    for row in &summary.physics {
        assert!(
            row.position_rms.is_finite() && row.steps_per_s > 0.0,
            "{row:?}"
        );
        // Every speed is a median inside its rounds' range.
        assert!(row.steps_per_s_low <= row.steps_per_s && row.steps_per_s <= row.steps_per_s_high);
        // Without a cap, the grid finds every contact brute force finds.
        if row.neighbour_cap == 0 {
            assert_eq!(row.contacts_missed, 0.0, "{}", row.choice);
        }
    }
    // A cap of 4 in a crowd where bodies have more than 3 neighbours misses contacts, and
    // a larger cap misses no more.
    assert!(rows["cap 4"].contacts_missed > 0.0);
    assert!(rows["cap 8"].contacts_missed <= rows["cap 4"].contacts_missed);
    // Substeps converge on the reference.
    assert!(rms("8 substeps") < rms("2 substeps"));
    assert!(rms("2 substeps") < rms("default"));
    // Two substeps are two steps of half the time step, bit for bit.
    assert_eq!(rms("2 substeps"), rms("dt 1/120"));
    // The Pareto flags: a row is on the frontier exactly when no row is as accurate and
    // faster in every round than it in any, or more accurate and not slower so.
    for a in &summary.physics {
        let sim = |r: &PhysicsRow| (r.steps_per_s_low * r.dt, r.steps_per_s_high * r.dt);
        let dominated = summary.physics.iter().any(|b| {
            let (faster, slower) = (sim(b).0 > sim(a).1, sim(a).0 > sim(b).1);
            (b.position_rms <= a.position_rms && faster)
                || (b.position_rms < a.position_rms && !slower)
        });
        assert_eq!(a.pareto, !dominated, "{}", a.choice);
        // What it cannot be told apart from beats it by the medians.
        for name in a.unseparated.split("; ").filter(|n| !n.is_empty()) {
            let b = rows[name];
            assert!(b.position_rms <= a.position_rms && b.sim_seconds_per_s >= a.sim_seconds_per_s);
        }
    }

    let analytic = |case: &str, integrator: &str, dt: f32| {
        let dt = f64::from(dt);
        summary
            .analytic
            .iter()
            .find(|r| r.case == case && r.integrator == integrator && r.dt == dt)
            .unwrap_or_else(|| panic!("{case} {integrator} {dt}"))
            .error
    };
    for &dt in &summary.sizes.analytic_dts {
        // Euler's position error under a constant g is exactly g t dt / 2, either order.
        let expected = 98.1 * 2.0 * f64::from(dt) / 2.0;
        for integrator in ["euler", "explicit"] {
            let error = analytic("constant force", integrator, dt);
            assert!(
                (error - expected).abs() < 0.01 * expected,
                "{integrator}: {error}"
            );
        }
        assert!(analytic("constant force", "verlet", dt) < 0.01 * expected);
        for integrator in ["euler", "explicit", "verlet"] {
            assert!(analytic("head-on collision", integrator, dt) < 1e-3);
        }
        // Energy: explicit Euler gains, the symplectic methods stay close; Verlet closest.
        let orbit = |integrator| analytic("circular orbit", integrator, dt);
        assert!(orbit("explicit") > 10.0 * orbit("euler"), "dt {dt}");
        assert!(orbit("verlet") < orbit("euler"), "dt {dt}");
    }
    assert!(!summary.game.is_empty() && !summary.features.is_empty());
    assert!(summary.features.iter().all(|r| r.steps_per_s > 0.0));
    // Every game choice is audited; the features are timed only.
    assert!(summary.game.iter().all(|r| r.accuracy.is_some()));
    assert!(summary.features.iter().all(|r| r.accuracy.is_none()));
    for r in &summary.game {
        let a = r.accuracy.as_ref().unwrap();
        assert!(a.tunnelling <= a.expected, "{}", r.choice);
        assert!((r.sim_seconds_per_s - r.steps_per_s * r.dt).abs() < 1e-9);
        let (low, high) = r.steps_per_s_range;
        assert!(
            low > 0.0 && low <= r.steps_per_s && r.steps_per_s <= high,
            "{r:?}"
        );
        // The quick audit starts where the ship fires: every choice's audit has contacts,
        // and a missed figure.
        assert!(a.expected > 0 && a.missed.is_some(), "{}: {a:?}", r.choice);
    }
    assert!(
        summary
            .game
            .iter()
            .chain(&summary.features)
            .all(|r| r.skipped.is_none())
    );
    // The choices that turn sweeping off or on are offered for the scene's swept kinds.
    let choices: Vec<&str> = summary.game.iter().map(|r| r.choice.as_str()).collect();
    for choice in [
        "nothing swept",
        "shot not swept",
        "ship not swept",
        "every kind swept",
    ] {
        assert!(choices.contains(&choice), "{choice} in {choices:?}");
    }
}

#[test]
fn the_quick_tradeoff_runs_on_the_cpu() {
    check(&quick("cpu"));
}

/// `arena` at a step of 0.6 s: the coarser step's choices (1.2 s) do not apply, and are
/// rows that say so while the run goes on; every row that was measured has its figures,
/// and the tables and plots are written (`quick_of` checks the files).
#[test]
fn a_choice_that_does_not_apply_is_a_row_that_says_why() {
    let dir = tempfile::tempdir().unwrap();
    let arena = gpuwars::game::scene::BUILT_IN
        .iter()
        .find(|b| b.name == "arena")
        .unwrap()
        .source;
    assert!(arena.contains("dt = 0.016666668"));
    let file = dir.path().join("slow arena.toml");
    std::fs::write(&file, arena.replace("dt = 0.016666668", "dt = 0.6")).unwrap();
    let summary = quick_of("cpu", file.to_str().unwrap());
    assert!(
        summary.scene.contains("slow arena.toml"),
        "{}",
        summary.scene
    );
    let skipped: Vec<_> = (summary.game.iter())
        .filter(|r| r.skipped.is_some())
        .collect();
    assert!(
        skipped.iter().any(|r| r.choice == "dt 1.2 s"),
        "{skipped:?}"
    );
    for r in &skipped {
        let why = r.skipped.as_ref().unwrap();
        assert!(
            why.contains("world.dt") || why.contains("autopilot lost"),
            "{why}"
        );
    }
    for r in summary.game.iter().filter(|r| r.skipped.is_none()) {
        assert!(r.steps_per_s > 0.0 && r.accuracy.is_some(), "{r:?}");
    }
}

#[test]
fn the_quick_tradeoff_runs_on_the_gpu() {
    if common::gpu().is_none() {
        return;
    }
    check(&quick("cuda"));
}

/// A snapshot of `bodies` (pos, vel) of the crowd's only kind, every other slot free.
fn snapshot(spec_bodies: u32, bodies: &[(Vec2, Vec2)]) -> Snapshot {
    let n = spec_bodies as usize;
    let mut alive = vec![0; n];
    let (mut pos, mut vel) = (vec![Vec2::ZERO; n], vec![Vec2::ZERO; n]);
    for (i, &(p, v)) in bodies.iter().enumerate() {
        (alive[i], pos[i], vel[i]) = (1, p, v);
    }
    Snapshot {
        steps: 0,
        bodies: Bodies {
            pos,
            vel,
            force: vec![Vec2::ZERO; n],
            dir: vec![Vec2::X; n],
            kind: vec![0; n],
            energy: vec![1; n],
            mass: vec![1.0; n],
            alive,
            state: vec![0; n],
            age: vec![0; n],
            prev: Vec::new(),
            frozen: vec![0],
            rng: RngStreams {
                params: Vec::new(),
                words: Vec::new(),
                index: Vec::new(),
            },
        },
        contacts: vec![0; n],
        free: FreeSlots {
            list: Vec::new(),
            count: Vec::new(),
        },
    }
}

#[test]
fn the_reference_orbits_and_collides_as_the_closed_forms_say() {
    // A circular orbit in the crowd's field: after one period, back where it started.
    let spec = crowd(4096, 1.0 / 60.0, Physics::default());
    let (centre, gm) = (spec.field.centre.as_dvec2(), f64::from(spec.field.strength));
    let r = f64::from(spec.size.x) / 4.0;
    let speed = (gm / r).sqrt();
    let start = centre + DVec2::new(r, 0.0);
    let mut world = Reference::new(
        &spec,
        &snapshot(4096, &[(start.as_vec2(), Vec2::new(0.0, speed as f32))]),
    )
    .unwrap();
    let period = std::f64::consts::TAU * r / speed;
    let steps = 1000;
    for _ in 0..steps {
        world.advance(period / f64::from(steps), 64);
    }
    let error = (world.pos[0] - start).length();
    assert!(error < 1e-3 * r, "{error} after one period of radius {r}");

    // Two equal balls head-on with restitution 0.5: they swap half their velocities.
    let spec = crowd(4096, 1.0 / 60.0, Physics::default());
    let mut spec = spec;
    spec.field.strength = 0.0;
    let bodies = [
        (Vec2::new(100.0, 200.0), Vec2::new(30.0, 0.0)),
        (Vec2::new(120.0, 200.0), Vec2::new(-30.0, 0.0)),
    ];
    let mut world = Reference::new(&spec, &snapshot(4096, &bodies)).unwrap();
    for _ in 0..60 {
        world.advance(1.0 / 60.0, 32);
    }
    // v1' = (v1 + v2 − e (v1 − v2)) / 2 for equal masses.
    let (after1, after2) = ((0.0 - 0.5 * 60.0) / 2.0, (0.0 + 0.5 * 60.0) / 2.0);
    assert!(
        (world.vel[0] - DVec2::new(after1, 0.0)).length() < 1e-9,
        "{}",
        world.vel[0]
    );
    assert!(
        (world.vel[1] - DVec2::new(after2, 0.0)).length() < 1e-9,
        "{}",
        world.vel[1]
    );
}

/// The pixels of a 1280x720 plot where `label` drawn at `at` in the plots' labels' font
/// puts ink, grown by one pixel each way: two labels whose sets meet touch or overlap.
fn inked(label: &str, at: (i32, i32)) -> std::collections::HashSet<(i32, i32)> {
    use plotters::prelude::*;
    let (w, h) = (1280i32, 720i32);
    let mut rgb = vec![255u8; (w * h * 3) as usize];
    {
        let area = BitMapBackend::with_buffer(&mut rgb, (w as u32, h as u32)).into_drawing_area();
        area.draw(&Text::new(label.to_owned(), at, ("sans-serif", 14)))
            .unwrap();
    }
    let mut ink = std::collections::HashSet::new();
    for (i, px) in rgb.chunks_exact(3).enumerate() {
        if px != [255, 255, 255] {
            let (x, y) = (i as i32 % w, i as i32 / w);
            for dx in -1..=1 {
                for dy in -1..=1 {
                    ink.insert((x + dx, y + dy));
                }
            }
        }
    }
    assert!(!ink.is_empty(), "{label:?} drew nothing");
    ink
}

#[test]
fn labels_of_a_cluster_of_points_do_not_overlap() {
    use gpuwars::benchmark::plot::{label_extent, place_labels};
    // Six choices plotted on one spot, as the default's neighbours often are, and one near
    // the plot's corner: each name goes to its own place, and the pixels each one inks
    // when drawn there (drawn here, one name at a time) meet no other name's, all of them
    // inside the plot.
    let names = [
        "default",
        "explicit",
        "verlet",
        "averaged",
        "cap 32",
        "cell x2",
        "dt 1/30, nothing swept",
    ];
    let extents: Vec<_> = names.iter().map(|n| label_extent(n).unwrap()).collect();
    let mut points = vec![(600, 300); names.len() - 1];
    points.push((1275, 5));
    let at = place_labels(&points, &extents, (0, 0, 1280, 720));
    let inks: Vec<_> = (names.iter().zip(&at)).map(|(n, &p)| inked(n, p)).collect();
    for (i, a) in inks.iter().enumerate() {
        assert!(
            a.iter()
                .all(|&(x, y)| (-1..=1280).contains(&x) && (-1..=720).contains(&y))
        );
        for (j, b) in inks.iter().enumerate().skip(i + 1) {
            assert!(
                a.is_disjoint(b),
                "{} at {:?} and {} at {:?} meet",
                names[i],
                at[i],
                names[j],
                at[j]
            );
        }
    }
}
