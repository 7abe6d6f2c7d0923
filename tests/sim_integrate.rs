//! The integrator against the closed form of Euler's method, and the boundary rules.

mod common;

use common::sim::{circle, kind, world};
use glam::{DVec2, Vec2};
use gpuwars::Device;
use gpuwars::pipeline::Simulation;
use gpuwars::sim::Boundary;

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
            after.pos[slot as usize].as_dvec2(),
            after.vel[slot as usize].as_dvec2(),
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
        (after.pos[0] - Vec2::new(0.5, 25.0)).length() < 1e-4,
        "{}",
        after.pos[0]
    );
    assert!(
        (after.pos[1] - Vec2::new(50.0, 49.7)).length() < 1e-4,
        "{}",
        after.pos[1]
    );
    assert_eq!(after.vel[0], Vec2::new(10.0, 0.0));
    assert_eq!(after.dir[1], Vec2::NEG_Y);
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
    assert_eq!(after.pos[0], Vec2::new(100.0, 0.0));
    assert_eq!(after.vel[0], Vec2::ZERO);
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
        (after.vel[0] - Vec2::new(3.0, 4.0)).length() < 1e-5,
        "{}",
        after.vel[0]
    );
}

on_both_backends!(
    euler_follows_the_closed_form_under_constant_force,
    bodies_leaving_a_wrapping_world_come_back_on_the_other_side,
    bodies_reaching_a_clamped_edge_stop_there,
    a_speed_limit_caps_the_velocity,
);
