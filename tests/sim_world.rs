//! World set-up: validation errors that name the field, grouped-warp slot ranges, free lists
//! that follow births and deaths.

mod common;

use common::sim::{circle, kind, rect, world};
use glam::Vec2;
use gpuwars::Device;
use gpuwars::pipeline::Simulation;
use gpuwars::sim::layout::{Layout, WARP, space};
use gpuwars::sim::state;
use gpuwars::sim::{Boundary, WorldSpec};

fn valid() -> WorldSpec {
    world(
        Vec2::new(800.0, 600.0),
        Boundary::Wrap,
        vec![
            kind("ship", circle(8.0), 1, &["enemy"]),
            kind("enemy", rect(4.0, 2.0), 70, &[]),
            kind("shot", circle(1.0), 33, &["enemy"]),
        ],
    )
}

/// A change that makes a valid world invalid.
type Breaks = fn(&mut WorldSpec);

#[test]
fn invalid_worlds_are_refused_with_the_field_and_the_allowed_range() {
    let cases: Vec<(Breaks, &str)> = vec![
        (
            |w| w.dt = f32::NAN,
            "dt: NaN is out of range (allowed (0, 1])",
        ),
        (|w| w.size.x = -3.0, "size.x: -3 is out of range"),
        (|w| w.size.y = f32::INFINITY, "size.y: inf is out of range"),
        (
            |w| w.vision = -1.0,
            "vision: -1 is out of range (allowed [0,",
        ),
        (|w| w.kinds.clear(), "kinds: 0 kinds (allowed 1 to 32)"),
        (
            |w| w.kinds[0].shape = circle(0.0),
            "kinds[0] (ship).radius: 0 is out of range",
        ),
        (
            |w| w.kinds[1].shape = rect(1.0, f32::NAN),
            "kinds[1] (enemy).half.y: NaN",
        ),
        (
            |w| w.kinds[2].mass = 0.0,
            "kinds[2] (shot).mass: 0 is out of range",
        ),
        (|w| w.kinds[2].capacity = 0, "kinds[2] (shot).capacity: 0"),
        (|w| w.kinds[2].energy = 0, "kinds[2] (shot).energy: 0"),
        (|w| w.kinds[2].damage = -1, "kinds[2] (shot).damage: -1"),
        (
            |w| w.kinds[1].restitution = 1.5,
            "kinds[1] (enemy).restitution: 1.5",
        ),
        (
            |w| w.kinds[1].max_speed = 0.0,
            "kinds[1] (enemy).max_speed: 0",
        ),
        (
            |w| w.kinds[2].name = "ship".into(),
            "kinds[2] (ship).name: is used",
        ),
        (
            |w| w.kinds[0].name = " ".into(),
            "kinds[0].name: must not be empty",
        ),
        (
            |w| w.kinds[0].collides_with.push("ghost".into()),
            "kinds[0] (ship).collides_with[1]: no kind is named `ghost`",
        ),
        (
            |w| w.kinds[1].capacity = 1 << 24,
            "kinds: 16,777,312 slots in all (allowed at most 16,777,216",
        ),
    ];
    for (break_it, expected) in cases {
        let mut spec = valid();
        break_it(&mut spec);
        let rule = spec.validate().expect_err(expected);
        assert!(
            rule.to_string().contains(expected),
            "`{rule}` lacks `{expected}`"
        );
        // A world is refused with the same words, before anything is allocated.
        let err = Simulation::new(common::cpu(), &spec, 1)
            .err()
            .expect(expected);
        assert!(
            err.to_string().contains(expected),
            "`{err}` lacks `{expected}`"
        );
    }
    // Immovable bodies and no speed limit are allowed.
    let mut spec = valid();
    spec.kinds[1].mass = f32::INFINITY;
    spec.kinds[1].max_speed = f32::INFINITY;
    spec.validate().unwrap();
}

#[test]
fn each_kind_gets_its_own_warp_aligned_range() {
    let layout = Layout::new(&valid());
    let starts: Vec<u32> = layout.ranges.iter().map(|r| r.start).collect();
    assert_eq!(starts, [0, 32, 128]);
    assert!(starts.iter().all(|s| s % WARP == 0));
    assert_eq!(layout.slots, 128 + 64);
    let kinds = layout.slot_kinds();
    assert_eq!(
        (kinds[0], kinds[31], kinds[32], kinds[127], kinds[128]),
        (0, 0, 1, 1, 2)
    );
}

#[test]
fn grid_cells_cover_the_largest_contact_and_vision() {
    let mut spec = valid();
    // Its 192 slots may have 512 cells of their 3 kinds' buckets (8 a slot): the 50 × 37
    // cells of 16 units that fit the field would be more, so they are coarser.
    let s = space(&spec);
    let cell = spec.size / Vec2::new(s.cols as f32, s.rows as f32);
    assert!(cell.min_element() >= 16.0, "{cell}");
    assert!(s.cells() * 3 <= 8 * 192, "{} cells", s.cells());
    // With enough bodies for them, the cells are as small as the contacts allow.
    spec.kinds[1].capacity = 1000;
    let s = space(&spec);
    // The ship (radius 8) touches enemies: cells of at least 16.
    let cell = spec.size / Vec2::new(s.cols as f32, s.rows as f32);
    assert!(
        cell.min_element() >= 16.0 && cell.max_element() < 17.0,
        "{cell}"
    );
    spec.vision = 100.0;
    let s = space(&spec);
    assert_eq!((s.cols, s.rows), (7, 5));
    // Nothing collides and nothing looks: one cell.
    for k in &mut spec.kinds {
        k.collides_with.clear();
    }
    spec.vision = 0.0;
    assert_eq!(space(&spec).cells(), 1);
}

fn free_lists_follow_births_and_deaths(device: &Device) {
    let mut spec = valid();
    spec.kinds[2].energy = 1;
    spec.kinds[1].damage = 1;
    let mut sim = Simulation::new(device, &spec, 9).unwrap();
    assert_eq!(sim.free_counts().unwrap(), [1, 70, 33]);
    // Enemies in slots 40 and 41 (far apart), shots in 128, 130 and 160: shot 128 sits on
    // enemy 40 and dies in the step; the others stay.
    sim.place(&[
        (40, Vec2::new(100.0, 100.0), Vec2::ZERO),
        (41, Vec2::new(400.0, 300.0), Vec2::ZERO),
        (128, Vec2::new(100.5, 100.0), Vec2::ZERO),
        (130, Vec2::new(700.0, 500.0), Vec2::ZERO),
        (160, Vec2::new(10.0, 500.0), Vec2::ZERO),
    ])
    .unwrap();
    let s = sim.snapshot().unwrap();
    assert_eq!(s.free.count, [1, 68, 30]);
    let enemies_free: Vec<u32> = (32..102).filter(|&i| i != 40 && i != 41).collect();
    assert_eq!(s.free.list[32..100], enemies_free[..]);
    sim.step().unwrap();
    let s = sim.snapshot().unwrap();
    assert_eq!(s.bodies.alive[128], 0, "the shot died on the enemy");
    assert_eq!(s.bodies.energy[40], 100 - spec.kinds[2].damage);
    assert_eq!(s.free.count, [1, 68, 31]);
    let shots_free: Vec<u32> = (128..161).filter(|&i| i != 130 && i != 160).collect();
    assert_eq!(s.free.list[128..159], shots_free[..]);
    // New shots take the lowest free slots: 128 again, then 129, 131.
    sim.scatter(2, 3, 1.0).unwrap();
    let s = sim.snapshot().unwrap();
    assert!([128, 129, 131].iter().all(|&i| s.bodies.alive[i] == 1));
    assert_eq!(s.free.count, [1, 68, 28]);
}

/// In the 10,000-body world, where bodies die and are renumbered every third step, each
/// kind's free list is, after every step, exactly its usable slots without a live body in
/// slot order, and its count their number: a brute force over the snapshot. Scattering
/// half the bodies leaves free slots in every tile of some ranges.
fn free_lists_are_every_free_slot_in_order(device: &Device) {
    let (mut spec, scatter) = common::sim::ten_thousand();
    spec.physics.renumber_every = Some(3);
    let mut sim = Simulation::new(device, &spec, 5).unwrap();
    for (kind, count, speed) in scatter {
        sim.scatter(kind, count / 2, speed).unwrap();
    }
    let ranges = sim.layout().ranges.clone();
    let mut holes = 0;
    for step in 0..40 {
        sim.step().unwrap();
        let s = sim.snapshot().unwrap();
        for free in common::sim::checked_free_lists(&s, &ranges, step) {
            // A free slot before a live one of its kind: the list is not just the range's tail.
            holes += free.windows(2).filter(|w| w[1] != w[0] + 1).count();
        }
    }
    assert!(holes > 0, "no free slot between live ones");
}

fn placing_into_padding_or_missing_slots_is_an_error(device: &Device) {
    let mut sim = Simulation::new(device, &valid(), 9).unwrap();
    let padding = sim.place(&[(5, Vec2::ZERO, Vec2::ZERO)]).unwrap_err();
    assert!(
        padding.to_string().contains("slot 5 is padding"),
        "{padding}"
    );
    let missing = sim.place(&[(500, Vec2::ZERO, Vec2::ZERO)]).unwrap_err();
    assert!(
        missing.to_string().contains("slot 500 does not exist"),
        "{missing}"
    );
    let too_many = sim.scatter(0, 2, 1.0).unwrap_err();
    assert!(
        too_many.to_string().contains("1 of its 1 slots are free"),
        "{too_many}"
    );
    assert!(sim.scatter(7, 1, 1.0).is_err());
    assert!(sim.scatter(1, 1, f32::NAN).is_err());
}

/// A world's buffers take exactly the bytes its memory check asks for: measured by the
/// device's own count of what it allocated, on a device of its own.
#[test]
fn a_world_takes_the_bytes_its_memory_check_counts() {
    let mut dense = common::sim::ten_thousand().0;
    dense.vision = 3.0;
    // 10,000 slots renumber unless the physics says never.
    let mut in_place = dense.clone();
    in_place.physics.renumber_every = Some(0);
    // A world that keeps its bodies' paths, for an audit.
    let mut traced = valid();
    traced.physics.trace_paths = true;
    // Worlds without a game, whose grids keep no velocities of their entries.
    for (spec, renumbers) in [
        (valid(), false),
        (in_place, false),
        (dense, true),
        (traced, false),
    ] {
        let device = Device::cpu(Some(1), "tests").unwrap();
        let sim = Simulation::new(&device, &spec, 1).unwrap();
        let (layout, kinds) = (sim.layout(), spec.kinds.len());
        let extras = state::Extras {
            renumbers,
            moving: false,
            traces: spec.traces(),
            logs: spec.physics.logged_per_slot(),
        };
        let expected = state::bytes_needed(layout, sim.space(), kinds, extras);
        assert_eq!(device.allocated_bytes(), expected);
    }
}

/// More than the device has free is refused with the bytes needed and the bytes free.
fn a_world_too_large_for_the_device_is_refused(device: &Device) {
    // Twice what was free: the CPU's free memory moves with the other processes between
    // the two reads, by far less than that. Wine in a container can report no available
    // memory at all, and then a figure again a moment later: where it reports none, nothing
    // is checked before the allocations (as `host_memory` documents), so the most bytes
    // there are either pass or are refused in words.
    let reported = device.memory().unwrap();
    let huge = reported.map_or(u64::MAX, |(free, _)| free * 2 + 1);
    let err = match device.check_fits("a huge world", huge) {
        Err(err) => err,
        Ok(()) => {
            assert!(reported.is_none(), "{huge} bytes fit in {reported:?}");
            println!("the free-memory check: skipped: this system does not report its free memory");
            return;
        }
    };
    let text = err.to_string();
    assert!(text.starts_with("a huge world needs"), "{text}");
    let needed = gpuwars::files::thousands(huge);
    assert!(text.contains(&format!("{needed} bytes")), "{text}");
    assert!(text.contains("but only"), "{text}");
    device.check_fits("a small world", 1).unwrap();
}

on_both_backends!(
    free_lists_follow_births_and_deaths,
    free_lists_are_every_free_slot_in_order,
    placing_into_padding_or_missing_slots_is_an_error,
    a_world_too_large_for_the_device_is_refused,
);
