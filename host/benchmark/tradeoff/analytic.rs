//! Cases with known answers, run by the kernels under each integrator and time step: a
//! constant force, a head-on collision of two bodies, a circular orbit under a central force.

use glam::{DVec2, Vec2};

use serde::{Deserialize, Serialize};

use crate::Device;
use crate::pipeline::{Pipeline, Simulation};
use crate::sim::{Boundary, Field, Integrator, KindSpec, Physics, Shape, Sweep, WorldSpec};

/// One case under one integrator and time step.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct AnalyticRow {
    /// `constant force`, `head-on collision` or `circular orbit`.
    pub case: String,
    /// The integrator.
    pub integrator: String,
    /// The time step (s).
    pub dt: f64,
    /// What `error` measures.
    pub measure: String,
    /// The error against the closed form.
    pub error: f64,
}

/// A body kind for the cases: a circle of `radius` and `mass`, colliding with `with`.
fn body(name: &str, radius: f32, mass: f32, restitution: f32, with: &[&str]) -> KindSpec {
    KindSpec {
        name: name.into(),
        shape: Shape::Circle { radius },
        mass,
        capacity: 1,
        energy: 1,
        damage: 0,
        restitution,
        max_speed: f32::INFINITY,
        collides_with: with.iter().map(|s| s.to_string()).collect(),
        lifetime: f32::INFINITY,
        controlled: false,
        sweep: Sweep::Off,
        top_speed: f32::INFINITY,
    }
}

/// A world of `side × side` with the given kinds, field, step and integrator.
fn world(
    side: f32,
    kinds: Vec<KindSpec>,
    field: Field,
    dt: f32,
    integrator: Integrator,
) -> WorldSpec {
    WorldSpec {
        size: Vec2::splat(side),
        dt,
        boundary: Boundary::Clamp,
        vision: 0.0,
        kinds,
        physics: Physics {
            integrator,
            ..Physics::default()
        },
        field,
    }
}

/// Steps in `seconds` of `dt`.
fn steps(seconds: f64, dt: f32) -> u32 {
    (seconds / f64::from(dt)).round() as u32
}

/// Queues `n` steps of `sim` and waits for them once.
fn advance(sim: &mut Simulation, n: u32) -> anyhow::Result<()> {
    for _ in 0..n {
        Pipeline::step(sim)?;
    }
    sim.device().synchronize()?;
    Ok(())
}

/// Gravity of 98.1 units/s² on a body thrown from (10, 10) at (40, 120) units/s, for 2 s:
/// the distance from `x0 + v0 t + g t² / 2`. Small coordinates keep f32 spacing (below
/// 10⁻⁵) under the methods' errors.
fn constant_force(device: &Device, dt: f32, integrator: Integrator) -> anyhow::Result<f64> {
    let field = Field {
        gravity: Vec2::new(0.0, -98.1),
        ..Field::default()
    };
    let spec = world(
        1000.0,
        vec![body("b", 1.0, 1.0, 0.0, &[])],
        field,
        dt,
        integrator,
    );
    let mut sim = Simulation::new(device, &spec, 1)?;
    let (x0, v0) = (Vec2::new(10.0, 10.0), Vec2::new(40.0, 120.0));
    sim.place(&[(0, x0, v0)])?;
    let n = steps(2.0, dt);
    advance(&mut sim, n)?;
    let t = f64::from(n) * f64::from(dt);
    let g = field.gravity.as_dvec2();
    let exact = x0.as_dvec2() + v0.as_dvec2() * t + g * (t * t / 2.0);
    Ok((sim.snapshot()?.bodies.pos[0].as_dvec2() - exact).length())
}

/// Masses 1 and 3 meeting head-on at ±50 units/s with restitution 0.5: the largest error of
/// the two velocities after they part, against momentum conservation and Newton's rule.
fn head_on(device: &Device, dt: f32, integrator: Integrator) -> anyhow::Result<f64> {
    let (m1, m2, e) = (1.0f32, 3.0f32, 0.5f32);
    let kinds = vec![body("a", 10.0, m1, e, &["b"]), body("b", 10.0, m2, e, &[])];
    let spec = world(1.0e4, kinds, Field::default(), dt, integrator);
    let mut sim = Simulation::new(device, &spec, 1)?;
    let b = sim.layout().ranges[1].start;
    let (v1, v2) = (50.0f32, -50.0f32);
    sim.place(&[
        (0, Vec2::new(4900.0, 5000.0), Vec2::new(v1, 0.0)),
        (b, Vec2::new(5100.0, 5000.0), Vec2::new(v2, 0.0)),
    ])?;
    // They meet after 1.8 s; 3 s leaves time to part.
    advance(&mut sim, steps(3.0, dt))?;
    let s = sim.snapshot()?;
    let (m1, m2, e, v1, v2) = (
        f64::from(m1),
        f64::from(m2),
        f64::from(e),
        f64::from(v1),
        f64::from(v2),
    );
    let p = m1 * v1 + m2 * v2;
    let after1 = (p - m2 * e * (v1 - v2)) / (m1 + m2);
    let after2 = (p + m1 * e * (v1 - v2)) / (m1 + m2);
    let got1 = s.bodies.vel[0].as_dvec2() - DVec2::new(after1, 0.0);
    let got2 = s.bodies.vel[b as usize].as_dvec2() - DVec2::new(after2, 0.0);
    Ok(got1.length().max(got2.length()))
}

/// A body on a circular orbit of radius 100 around a centre of strength `G·M = 4·10⁵`
/// (period ≈ 9.9 s; small coordinates, so that f32 spacing stays below the error measured),
/// for 5 periods: the largest relative error of its energy
/// `v²/2 − GM/r`, sampled every 8 steps.
fn orbit(device: &Device, dt: f32, integrator: Integrator) -> anyhow::Result<f64> {
    let (r, gm) = (100.0f32, 4.0e5f32);
    let centre = Vec2::splat(150.0);
    let field = Field {
        centre,
        strength: gm,
        ..Field::default()
    };
    let spec = world(
        300.0,
        vec![body("b", 1.0, 1.0, 0.0, &[])],
        field,
        dt,
        integrator,
    );
    let mut sim = Simulation::new(device, &spec, 1)?;
    let (x0, v0) = (centre + Vec2::new(r, 0.0), Vec2::new(0.0, (gm / r).sqrt()));
    sim.place(&[(0, x0, v0)])?;
    let energy = |pos: Vec2, vel: Vec2| {
        vel.as_dvec2().length_squared() / 2.0
            - f64::from(gm) / (pos.as_dvec2() - centre.as_dvec2()).length()
    };
    let start = energy(x0, v0);
    let period = std::f64::consts::TAU * (f64::from(r).powi(3) / f64::from(gm)).sqrt();
    let mut worst = 0.0f64;
    for _ in 0..steps(5.0 * period, dt).div_ceil(8) {
        advance(&mut sim, 8)?;
        let s = sim.snapshot()?;
        worst = worst.max(((energy(s.bodies.pos[0], s.bodies.vel[0]) - start) / start).abs());
    }
    Ok(worst)
}

/// Every case under every integrator and each time step of `steps`.
pub fn run(device: &Device, dts: &[f32]) -> anyhow::Result<Vec<AnalyticRow>> {
    type Case = fn(&Device, f32, Integrator) -> anyhow::Result<f64>;
    let cases: [(&str, &str, Case); 3] = [
        ("constant force", "position error after 2 s", constant_force),
        ("head-on collision", "velocity error after parting", head_on),
        (
            "circular orbit",
            "largest relative energy error, 5 orbits",
            orbit,
        ),
    ];
    let mut rows = Vec::new();
    for (case, measure, run) in cases {
        for integrator in Integrator::ALL {
            for &dt in dts {
                rows.push(AnalyticRow {
                    case: case.into(),
                    integrator: integrator.name().into(),
                    dt: f64::from(dt),
                    measure: measure.into(),
                    error: run(device, dt, integrator)?,
                });
            }
        }
    }
    Ok(rows)
}
