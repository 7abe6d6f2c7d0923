//! The integrator against the closed form of Euler's method, and the boundary rules.

mod common;

use common::sim::{circle, kind, world};
use glam::{DVec2, Vec2};
use gpuwars::Device;
use gpuwars::pipeline::Simulation;
use gpuwars::sim::{Boundary, Integrator};

/// With a constant force F on mass m, Euler in the paper's order (velocity first) gives
/// v_n = v_0 + n a dt and x_n = x_0 + n dt v_0 + a dt² n (n + 1) / 2, a = F / m. The f32
/// run must follow that f64 formula to within the rounding its steps accumulate.
fn euler_follows_the_closed_form_under_constant_force(device: &Device) {
    let mut spec = world(
        Vec2::splat(1.0e5),
        Boundary::Clamp,
        vec![kind("b", circle(1.0), 3, &[])],
    );
    spec.kinds[0].mass = 2.5;
    spec.dt = 1.0 / 120.0;
    let mut sim = Simulation::new(device, &spec, 3).unwrap();
    let start = [
        (
            0,
            Vec2::new(100.0, 200.0),
            Vec2::new(3.0, -1.0),
            Vec2::new(5.0, 2.0),
        ),
        (
            1,
            Vec2::new(5.0e4, 5.0e4),
            Vec2::ZERO,
            Vec2::new(-40.0, 7.5),
        ),
        (
            2,
            Vec2::new(3.0e4, 6.0e4),
            Vec2::new(-20.0, 12.0),
            Vec2::new(0.5, -0.25),
        ),
    ];
    sim.place(&start.map(|(s, p, v, _)| (s, p, v))).unwrap();
    sim.set_forces(&start.map(|(s, _, _, f)| (s, f))).unwrap();
    let n = 600u32;
    for _ in 0..n {
        sim.step().unwrap();
    }
    let after = sim.snapshot().unwrap();
    let (dt, nf) = (f64::from(spec.dt), f64::from(n));
    for (slot, x0, v0, force) in start {
        let a = force.as_dvec2() / f64::from(spec.kinds[0].mass);
        let v = v0.as_dvec2() + a * nf * dt;
        let x = x0.as_dvec2() + v0.as_dvec2() * nf * dt + a * dt * dt * nf * (nf + 1.0) / 2.0;
        let (got_x, got_v) = (
            after.bodies.pos[slot as usize].as_dvec2(),
            after.bodies.vel[slot as usize].as_dvec2(),
        );
        // Each step rounds each coordinate by a relative 2^-24 or so.
        let tolerance = |scale: DVec2| nf * 4.0 * f64::from(f32::EPSILON) * scale.length().max(1.0);
        assert!(
            (got_v - v).length() <= tolerance(v),
            "slot {slot}: v {got_v} vs {v}"
        );
        assert!(
            (got_x - x).length() <= tolerance(x),
            "slot {slot}: x {got_x} vs {x}"
        );
        // And it differs from the exact motion by the method's own error, a dt t / 2.
        let exact = x0.as_dvec2() + v0.as_dvec2() * nf * dt + a * (nf * dt).powi(2) / 2.0;
        let method_error = a * dt * nf * dt / 2.0;
        assert!(
            ((got_x - exact) - method_error).length() <= tolerance(x),
            "slot {slot}"
        );
    }
}

fn bodies_leaving_a_wrapping_world_come_back_on_the_other_side(device: &Device) {
    let mut spec = world(
        Vec2::new(100.0, 50.0),
        Boundary::Wrap,
        vec![kind("b", circle(1.0), 2, &[])],
    );
    spec.dt = 0.1;
    let mut sim = Simulation::new(device, &spec, 3).unwrap();
    sim.place(&[
        (0, Vec2::new(99.5, 25.0), Vec2::new(10.0, 0.0)),
        (1, Vec2::new(50.0, 0.2), Vec2::new(0.0, -5.0)),
    ])
    .unwrap();
    sim.step().unwrap();
    let after = sim.snapshot().unwrap();
    assert!(
        (after.bodies.pos[0] - Vec2::new(0.5, 25.0)).length() < 1e-4,
        "{}",
        after.bodies.pos[0]
    );
    assert!(
        (after.bodies.pos[1] - Vec2::new(50.0, 49.7)).length() < 1e-4,
        "{}",
        after.bodies.pos[1]
    );
    assert_eq!(after.bodies.vel[0], Vec2::new(10.0, 0.0));
    assert_eq!(after.bodies.dir[1], Vec2::NEG_Y);
}

fn bodies_reaching_a_clamped_edge_stop_there(device: &Device) {
    let mut spec = world(
        Vec2::new(100.0, 50.0),
        Boundary::Clamp,
        vec![kind("b", circle(1.0), 1, &[])],
    );
    spec.dt = 0.1;
    let mut sim = Simulation::new(device, &spec, 3).unwrap();
    sim.place(&[(0, Vec2::new(99.5, 0.5), Vec2::new(10.0, -10.0))])
        .unwrap();
    sim.step().unwrap();
    let after = sim.snapshot().unwrap();
    assert_eq!(after.bodies.pos[0], Vec2::new(100.0, 0.0));
    assert_eq!(after.bodies.vel[0], Vec2::ZERO);
}

fn a_speed_limit_caps_the_velocity(device: &Device) {
    let mut spec = world(
        Vec2::splat(1000.0),
        Boundary::Wrap,
        vec![kind("b", circle(1.0), 1, &[])],
    );
    spec.kinds[0].max_speed = 5.0;
    let mut sim = Simulation::new(device, &spec, 3).unwrap();
    sim.place(&[(0, Vec2::splat(500.0), Vec2::new(30.0, 40.0))])
        .unwrap();
    sim.step().unwrap();
    let after = sim.snapshot().unwrap();
    assert!(
        (after.bodies.vel[0] - Vec2::new(3.0, 4.0)).length() < 1e-5,
        "{}",
        after.bodies.vel[0]
    );
}

/// Explicit Euler under a constant field `g`: `x_n = x_0 + n dt v_0 + g dt² n (n − 1) / 2`
/// (the position moves with the old velocity); velocity Verlet is exact for a constant
/// acceleration: `x_n = x_0 + v_0 t + g t² / 2`. Both against f64 closed forms.
fn explicit_euler_and_verlet_follow_their_closed_forms(device: &Device) {
    let g = Vec2::new(3.0, -9.81);
    let (x0, v0) = (Vec2::new(500.0, 900.0), Vec2::new(-4.0, 20.0));
    let n = 240u32;
    for integrator in [Integrator::ExplicitEuler, Integrator::VelocityVerlet] {
        let mut spec = world(
            Vec2::splat(1000.0),
            Boundary::Clamp,
            vec![kind("b", circle(1.0), 1, &[])],
        );
        spec.physics.integrator = integrator;
        spec.field.gravity = g;
        let mut sim = Simulation::new(device, &spec, 3).unwrap();
        sim.place(&[(0, x0, v0)]).unwrap();
        for _ in 0..n {
            sim.step().unwrap();
        }
        let got = sim.snapshot().unwrap();
        let (dt, nf, g) = (f64::from(spec.dt), f64::from(n), g.as_dvec2());
        let x = match integrator {
            Integrator::ExplicitEuler => {
                x0.as_dvec2() + v0.as_dvec2() * nf * dt + g * dt * dt * nf * (nf - 1.0) / 2.0
            }
            _ => x0.as_dvec2() + v0.as_dvec2() * nf * dt + g * (nf * dt).powi(2) / 2.0,
        };
        let v = v0.as_dvec2() + g * nf * dt;
        let tolerance = nf * 4.0 * f64::from(f32::EPSILON) * x.length();
        let (got_x, got_v) = (got.bodies.pos[0].as_dvec2(), got.bodies.vel[0].as_dvec2());
        assert!(
            (got_x - x).length() <= tolerance,
            "{integrator}: x {got_x} vs {x}"
        );
        assert!(
            (got_v - v).length() <= tolerance,
            "{integrator}: v {got_v} vs {v}"
        );
    }
}

/// A step split into k substeps is k steps of dt / k, bit for bit, in a colliding world
/// where nothing dies (ageing and contact damage happen once a step, the rest per substep).
fn substeps_are_steps_of_a_smaller_dt(device: &Device) {
    let k = 4u32;
    let mut split = world(
        Vec2::splat(300.0),
        Boundary::Wrap,
        vec![kind("b", circle(6.0), 200, &["b"])],
    );
    split.physics.substeps = k;
    split.field.centre = Vec2::splat(150.0);
    split.field.strength = 2.0e5;
    let mut fine = split.clone();
    fine.physics.substeps = 1;
    fine.dt = split.dt / k as f32;
    let mut a = Simulation::new(device, &split, 9).unwrap();
    let mut b = Simulation::new(device, &fine, 9).unwrap();
    a.scatter(0, 200, 40.0).unwrap();
    b.scatter(0, 200, 40.0).unwrap();
    for _ in 0..10 {
        a.step().unwrap();
        for _ in 0..k {
            b.step().unwrap();
        }
    }
    let (a, b) = (a.snapshot().unwrap(), b.snapshot().unwrap());
    assert!(a.contacts.iter().any(|&c| c > 0), "the world must collide");
    assert_eq!(a.bodies.pos, b.bodies.pos);
    assert_eq!(a.bodies.vel, b.bodies.vel);
}

/// Twenty bodies on one spot around a centre body: summed, the centre body is pushed by
/// every contact; averaged and relaxed by one half, by half the mean push.
fn relaxation_averages_and_scales_the_push(device: &Device) {
    let centre = Vec2::splat(100.0);
    let push_of = |averaged: bool, relaxation: f32| {
        let mut spec = world(
            Vec2::splat(200.0),
            Boundary::Clamp,
            vec![kind("b", circle(5.0), 21, &["b"])],
        );
        spec.physics.averaged = averaged;
        spec.physics.relaxation = relaxation;
        let mut sim = Simulation::new(device, &spec, 1).unwrap();
        // Slot 0 at the centre, twenty bodies 2 units to its right (depth 8 each).
        let mut bodies = vec![(0, centre, Vec2::ZERO)];
        bodies.extend((1..21).map(|s| (s, centre + Vec2::new(2.0, 0.0), Vec2::ZERO)));
        sim.place(&bodies).unwrap();
        sim.step().unwrap();
        let s = sim.snapshot().unwrap();
        assert_eq!(s.contacts[0], 20);
        (s.bodies.pos[0] - centre).x
    };
    // Each contact pushes slot 0 left by half the depth of 8 (equal masses).
    assert_eq!(push_of(false, 1.0), -80.0);
    assert_eq!(push_of(true, 1.0), -4.0);
    assert_eq!(push_of(true, 0.5), -2.0);
    assert_eq!(push_of(false, 0.5), -40.0);
}

on_both_backends!(
    explicit_euler_and_verlet_follow_their_closed_forms,
    substeps_are_steps_of_a_smaller_dt,
    relaxation_averages_and_scales_the_push,
    euler_follows_the_closed_form_under_constant_force,
    bodies_leaving_a_wrapping_world_come_back_on_the_other_side,
    bodies_reaching_a_clamped_edge_stop_there,
    a_speed_limit_caps_the_velocity,
);
