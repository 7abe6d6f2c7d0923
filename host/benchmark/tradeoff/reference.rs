//! The reference the choices are measured against: the same world in f64, every pair tested
//! (no grid, no cap), the contact model of the kernels (full push, restitution impulse)
//! taken in many small steps of semi-implicit Euler. Written independently of the kernels:
//! only the physical rules are shared, not the code.

use glam::DVec2;

use crate::sim::{Boundary, Shape, Snapshot, WorldSpec};

/// A world of circles in f64.
#[derive(Clone, Debug)]
pub struct Reference {
    size: DVec2,
    wrap: bool,
    gravity: DVec2,
    centre: DVec2,
    strength: f64,
    /// Each body's slot in the snapshot it came from.
    pub slots: Vec<usize>,
    /// Positions.
    pub pos: Vec<DVec2>,
    /// Velocities.
    pub vel: Vec<DVec2>,
    force: Vec<DVec2>,
    inv_mass: Vec<f64>,
    radius: Vec<f64>,
    restitution: Vec<f64>,
    max_speed: Vec<f64>,
    /// Each body's collision mask over the kinds, and its kind.
    masks: Vec<(u32, u32)>,
}

impl Reference {
    /// The live bodies of `snapshot`, a state of `spec`'s world (circles only; rectangles
    /// and contact damage are not modelled, and the error runs have neither).
    pub fn new(spec: &WorldSpec, snapshot: &Snapshot) -> anyhow::Result<Self> {
        let masks = spec.collision_masks();
        let mut r = Reference {
            size: spec.size.as_dvec2(),
            wrap: spec.boundary == Boundary::Wrap,
            gravity: spec.field.gravity.as_dvec2(),
            centre: spec.field.centre.as_dvec2(),
            strength: f64::from(spec.field.strength),
            slots: Vec::new(),
            pos: Vec::new(),
            vel: Vec::new(),
            force: Vec::new(),
            inv_mass: Vec::new(),
            radius: Vec::new(),
            restitution: Vec::new(),
            max_speed: Vec::new(),
            masks: Vec::new(),
        };
        for slot in snapshot.live() {
            let kind = snapshot.bodies.kind[slot];
            let spec_kind = &spec.kinds[kind as usize];
            let Shape::Circle { radius } = spec_kind.shape else {
                anyhow::bail!("the f64 reference models circles only");
            };
            r.slots.push(slot);
            r.pos.push(snapshot.bodies.pos[slot].as_dvec2());
            r.vel.push(snapshot.bodies.vel[slot].as_dvec2());
            r.force.push(snapshot.bodies.force[slot].as_dvec2());
            r.inv_mass.push(1.0 / f64::from(snapshot.bodies.mass[slot]));
            r.radius.push(f64::from(radius));
            r.restitution.push(f64::from(spec_kind.restitution));
            r.max_speed.push(f64::from(spec_kind.max_speed));
            r.masks.push((masks[kind as usize], kind));
        }
        Ok(r)
    }

    /// Advances by `dt` in `substeps` equal steps.
    pub fn advance(&mut self, dt: f64, substeps: u32) {
        let h = dt / f64::from(substeps);
        for _ in 0..substeps {
            self.substep(h);
        }
    }

    /// The shortest offset from `a` to `b`.
    fn offset(&self, a: DVec2, b: DVec2) -> DVec2 {
        let d = b - a;
        if !self.wrap {
            return d;
        }
        let short = |d: f64, period: f64| d - period * (d / period).round();
        DVec2::new(short(d.x, self.size.x), short(d.y, self.size.y))
    }

    /// Pairs `(i, j)`, `i < j`, that overlap now, with their offset.
    pub fn overlapping(&self) -> Vec<(usize, usize, DVec2)> {
        let n = self.pos.len();
        let mut out = Vec::new();
        for i in 0..n {
            for j in i + 1..n {
                if self.masks[i].0 & (1 << self.masks[j].1) == 0 {
                    continue;
                }
                let d = self.offset(self.pos[i], self.pos[j]);
                let reach = self.radius[i] + self.radius[j];
                if d.length_squared() < reach * reach {
                    out.push((i, j, d));
                }
            }
        }
        out
    }

    fn substep(&mut self, h: f64) {
        let n = self.pos.len();
        let mut push = vec![DVec2::ZERO; n];
        let mut kick = vec![DVec2::ZERO; n];
        for (i, j, d) in self.overlapping() {
            let dist = d.length();
            // Same spot: the lower body goes -x, the higher +x, as in the kernels.
            let normal = if dist > 0.0 { d / dist } else { DVec2::X };
            let depth = self.radius[i] + self.radius[j] - dist;
            let (wi, wj) = (self.inv_mass[i], self.inv_mass[j]);
            let weight = wi + wj;
            if weight <= 0.0 {
                continue;
            }
            push[i] -= normal * depth * (wi / weight);
            push[j] += normal * depth * (wj / weight);
            let approach = (self.vel[j] - self.vel[i]).dot(normal);
            if approach < 0.0 {
                let e = self.restitution[i].max(self.restitution[j]);
                let impulse = -(1.0 + e) * approach / weight;
                kick[i] -= normal * impulse * wi;
                kick[j] += normal * impulse * wj;
            }
        }
        for i in 0..n {
            let accel = self.force[i] * self.inv_mass[i] + self.field(self.pos[i]);
            let mut v = self.vel[i] + kick[i] + accel * h;
            let speed = v.length();
            if speed > self.max_speed[i] {
                v *= self.max_speed[i] / speed;
            }
            let p = self.pos[i] + v * h + push[i];
            (self.pos[i], self.vel[i]) = self.confine(p, v);
        }
    }

    fn field(&self, pos: DVec2) -> DVec2 {
        let r = self.centre - pos;
        let r2 = r.length_squared();
        if self.strength == 0.0 || r2 <= 0.0 {
            self.gravity
        } else {
            self.gravity + r * (self.strength / (r2 * r2.sqrt()))
        }
    }

    fn confine(&self, p: DVec2, v: DVec2) -> (DVec2, DVec2) {
        if self.wrap {
            return (p.rem_euclid(self.size), v);
        }
        let axis = |x: f64, v: f64, limit: f64| {
            if x < 0.0 {
                (0.0, v.max(0.0))
            } else if x > limit {
                (limit, v.min(0.0))
            } else {
                (x, v)
            }
        };
        let (x, vx) = axis(p.x, v.x, self.size.x);
        let (y, vy) = axis(p.y, v.y, self.size.y);
        (DVec2::new(x, y), DVec2::new(vx, vy))
    }
}
