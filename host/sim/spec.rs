//! What a world is made of, as the host describes it: size, time step, boundary rule, and the
//! kinds of body with their bounds, masses, capacities and contacts. Scene files (TOML) are
//! read into this; [`WorldSpec::validate`] says precisely what is wrong with one.

use std::fmt;

use glam::Vec2;
pub use gpuwars_kernels::sim::integrate::Field;

use crate::files::{excerpt, figure, number, thousands};

/// Most kinds a world may have: collision masks are 32-bit.
pub const MAX_KINDS: usize = 32;
/// Most slots a world may have, all kinds together (after aligning each range to 32).
pub const MAX_SLOTS: u32 = 1 << 24;
/// Largest world side: beyond it, f32 positions are too coarse for small bodies.
pub const MAX_SIDE: f32 = 1.0e6;

/// Lightest mass a body may have: lighter, `1 / mass` overflows in the kernels' arithmetic.
pub const MIN_MASS: f32 = 1.0e-30;
/// Heaviest finite mass: heavier, a contact's impulse overflows (infinity stands for an
/// immovable body).
pub const MAX_MASS: f32 = 1.0e30;
/// Largest magnitude of a field's components and strength.
pub const MAX_FIELD: f32 = 1.0e12;
/// Most substeps a step may be split into.
pub const MAX_SUBSTEPS: u32 = 64;
/// Largest grid cell scale.
pub const MAX_CELL_SCALE: f32 = 64.0;
/// Largest vision scale.
pub const MAX_VISION_SCALE: f32 = 4.0;
/// The bodies of one kind an enemy's look examines at most unless the scene says otherwise:
/// enough that the built-in scenes' looks meet it only once enemies crowd the ship, few
/// enough that a crowd on one spot costs each look a bounded amount.
pub const DEFAULT_SIGHT_BUDGET: u32 = 128;
/// Longest period of the renumbering, in steps.
pub const MAX_RENUMBER_EVERY: u32 = 1 << 16;
/// Slots from which a world renumbers its bodies unless its physics says otherwise (the
/// paper's game has 8,288): smaller hand-made worlds keep their bodies where they put them.
pub const RENUMBER_FROM_SLOTS: u32 = 1 << 13;
/// The renumbering's period where the world's size chooses it: bodies move a small part of a
/// cell a step, so the order holds for many steps (measured at 8K, 1M and 16.76M enemies on
/// an H100: every 4 steps 2–4% slower than every 16, every 64 within 0.5% of it).
pub const RENUMBER_EVERY: u32 = 16;

/// The integrator of the equations of motion.
#[derive(
    Clone,
    Copy,
    Debug,
    Default,
    PartialEq,
    Eq,
    Hash,
    clap::ValueEnum,
    serde::Serialize,
    serde::Deserialize,
)]
pub enum Integrator {
    /// The paper's order, velocity then position (semi-implicit, symplectic Euler).
    #[default]
    #[value(name = "euler")]
    #[serde(rename = "euler")]
    SemiImplicitEuler,
    /// Position from the old velocity, then velocity (explicit, forward Euler).
    #[value(name = "explicit")]
    #[serde(rename = "explicit")]
    ExplicitEuler,
    /// Velocity Verlet (the field's acceleration at both ends of the step).
    #[value(name = "verlet")]
    #[serde(rename = "verlet")]
    VelocityVerlet,
}

impl Integrator {
    /// Every integrator, the default first.
    pub const ALL: [Integrator; 3] = [
        Integrator::SemiImplicitEuler,
        Integrator::ExplicitEuler,
        Integrator::VelocityVerlet,
    ];

    /// The name scene files and flags use.
    pub fn name(self) -> &'static str {
        match self {
            Integrator::SemiImplicitEuler => "euler",
            Integrator::ExplicitEuler => "explicit",
            Integrator::VelocityVerlet => "verlet",
        }
    }

    /// The kernels' code for it.
    pub fn code(self) -> u32 {
        use gpuwars_kernels::sim::integrate as k;
        match self {
            Integrator::SemiImplicitEuler => k::SEMI_IMPLICIT_EULER,
            Integrator::ExplicitEuler => k::EXPLICIT_EULER,
            Integrator::VelocityVerlet => k::VELOCITY_VERLET,
        }
    }
}

impl fmt::Display for Integrator {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// How a world's physics is computed: the choices that trade speed against accuracy. The
/// default reproduces the paper's game bit for bit.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Physics {
    /// The integrator.
    pub integrator: Integrator,
    /// Substeps per step (1 to [`MAX_SUBSTEPS`]): the grid, the narrow phase and the
    /// integrator run this many times a step with `dt / substeps`; the machines, the master
    /// thread and contact damage once a step.
    pub substeps: u32,
    /// Fraction of the contacts' push applied per substep, in `(0, 1]`.
    pub relaxation: f32,
    /// Whether a body's pushes are averaged over its contacts instead of summed.
    pub averaged: bool,
    /// Grid cells this many times the smallest safe size, `[1, MAX_CELL_SCALE]`.
    pub cell_scale: f32,
    /// The most grid entries one query (contacts, vision) examines; 0 for no limit.
    pub neighbour_cap: u32,
    /// The enemies' vision radii scaled by this, `(0, MAX_VISION_SCALE]` (games only).
    pub vision_scale: f32,
    /// The most bodies of one kind an enemy's look examines, a third of them from each row
    /// of its block, taken evenly from a crowd beyond that
    /// (`gpuwars_kernels::sim::broad::Sample`); 0 for all (games only).
    pub sight_budget: u32,
    /// The most bodies of one kind a body's contacts are sought among, a third of them from
    /// each row of its block, taken evenly from a crowd beyond that, each contact found
    /// standing for as many as it was taken among (`gpuwars_kernels::sim::broad::Sample`);
    /// 0 (the default) for all: every contact, as a fast swept body in a dense field needs.
    pub contact_budget: u32,
    /// Every how many steps the bodies move to slots in the grid's order (0: never, at most
    /// [`MAX_RENUMBER_EVERY`]); `None` lets the world's size choose (see
    /// [`Physics::renumber_period`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub renumber_every: Option<u32>,
    /// Whether each body's last path is kept even where no pair is swept, and the narrow
    /// phase logs every contact it counts, for an audit of the contacts
    /// (`crate::sim::audit`): a store a body a step and one a contact, nothing else changes.
    #[serde(skip)]
    pub trace_paths: bool,
    /// Records the contact log holds a slot, where `trace_paths` logs contacts (each contact
    /// logged from both sides): [`LOGGED_PER_SLOT`] unless an audit asked for more room
    /// after a step of denser contacts (`crate::game::accuracy::audit_game`).
    #[serde(skip)]
    pub log_room: u32,
}

/// The contact log's room a slot unless an audit asks for more ([`Physics::log_room`]).
pub const LOGGED_PER_SLOT: u32 = 16;

impl Default for Physics {
    fn default() -> Self {
        Physics {
            integrator: Integrator::SemiImplicitEuler,
            substeps: 1,
            relaxation: 1.0,
            averaged: false,
            cell_scale: 1.0,
            neighbour_cap: 0,
            vision_scale: 1.0,
            sight_budget: DEFAULT_SIGHT_BUDGET,
            contact_budget: 0,
            renumber_every: None,
            trace_paths: false,
            log_room: LOGGED_PER_SLOT,
        }
    }
}

impl Physics {
    /// Records the contact log holds a slot: [`Physics::log_room`] where the world logs its
    /// contacts ([`Physics::trace_paths`]), none elsewhere.
    pub fn logged_per_slot(&self) -> usize {
        match self.trace_paths {
            true => self.log_room as usize,
            false => 0,
        }
    }

    /// Checks every choice; fields are named `physics.<name>`.
    pub fn validate(&self) -> Result<(), SpecError> {
        if !(1..=MAX_SUBSTEPS).contains(&self.substeps) {
            return Err(error(
                "physics.substeps",
                format!(
                    "{} is out of range (allowed 1 to {MAX_SUBSTEPS})",
                    self.substeps
                ),
            ));
        }
        check_range("physics.relaxation", self.relaxation, (0.0, false), 1.0)?;
        check_range(
            "physics.cell_scale",
            self.cell_scale,
            (1.0, true),
            MAX_CELL_SCALE,
        )?;
        check_up_to(
            "physics.neighbour_cap",
            self.neighbour_cap,
            "no limit",
            MAX_SLOTS,
        )?;
        check_up_to(
            "physics.sight_budget",
            self.sight_budget,
            "no limit",
            MAX_SLOTS,
        )?;
        check_up_to(
            "physics.contact_budget",
            self.contact_budget,
            "no limit",
            MAX_SLOTS,
        )?;
        if let Some(every) = self.renumber_every {
            check_up_to("physics.renumber_every", every, "never", MAX_RENUMBER_EVERY)?;
        }
        check_range(
            "physics.vision_scale",
            self.vision_scale,
            (0.0, false),
            MAX_VISION_SCALE,
        )
    }

    /// Every how many steps a world of `slots` slots renumbers its bodies (0: never): the
    /// scene's choice, or [`RENUMBER_EVERY`] from [`RENUMBER_FROM_SLOTS`] slots. It changes
    /// which slot holds which body, so it depends on the scene alone, never on the device.
    pub fn renumber_period(&self, slots: u32) -> u32 {
        self.renumber_every
            .unwrap_or(if slots >= RENUMBER_FROM_SLOTS {
                RENUMBER_EVERY
            } else {
                0
            })
    }

    /// A short label of the choices that differ from the default (`default` if none).
    pub fn label(&self) -> String {
        let d = Physics::default();
        let mut parts = Vec::new();
        if self.integrator != d.integrator {
            parts.push(self.integrator.name().to_owned());
        }
        if self.substeps != d.substeps {
            parts.push(format!("{} substeps", self.substeps));
        }
        if self.relaxation != d.relaxation {
            parts.push(format!("relax {}", number(self.relaxation)));
        }
        if self.averaged {
            parts.push("averaged".to_owned());
        }
        if self.cell_scale != d.cell_scale {
            parts.push(format!("cell x{}", number(self.cell_scale)));
        }
        if self.neighbour_cap != 0 {
            parts.push(format!("cap {}", self.neighbour_cap));
        }
        if self.vision_scale != d.vision_scale {
            parts.push(format!("vision x{}", number(self.vision_scale)));
        }
        if self.sight_budget != d.sight_budget {
            parts.push(match self.sight_budget {
                0 => "sight unbudgeted".to_owned(),
                budget => format!("sight budget {budget}"),
            });
        }
        if self.contact_budget != 0 {
            parts.push(format!("contact budget {}", self.contact_budget));
        }
        if let Some(every) = self.renumber_every {
            parts.push(format!("renumber every {every}"));
        }
        if parts.is_empty() {
            "default".to_owned()
        } else {
            parts.join(", ")
        }
    }
}

/// How the world treats bodies that leave it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Boundary {
    /// They come back on the opposite side (a torus); contacts reach across the seams.
    Wrap,
    /// They stop at the edge, losing the velocity that points outwards.
    Clamp,
}

/// The narrow-phase bound of a kind.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Shape {
    /// A circle of this radius.
    Circle {
        /// Radius.
        radius: f32,
    },
    /// An axis-aligned rectangle of these half extents.
    Rect {
        /// Half the width and half the height.
        half: Vec2,
    },
}

impl Shape {
    /// Radius of the smallest circle around the bound, centred on the body.
    pub fn reach(&self) -> f32 {
        match *self {
            Shape::Circle { radius } => radius,
            Shape::Rect { half } => half.length(),
        }
    }
}

/// One kind of body.
#[derive(Clone, Debug, PartialEq)]
pub struct KindSpec {
    /// Unique name (used by `collides_with`).
    pub name: String,
    /// Bound used by the narrow phase.
    pub shape: Shape,
    /// Mass of each body ([`MIN_MASS`] to [`MAX_MASS`]; `f32::INFINITY` for immovable
    /// bodies).
    pub mass: f32,
    /// Slots reserved for this kind: the most bodies of it alive at once.
    pub capacity: u32,
    /// Energy at birth (≥ 1).
    pub energy: i32,
    /// Energy a body touching one of this kind loses per step of contact (≥ 0).
    pub damage: i32,
    /// Coefficient of restitution, 0 (no bounce) to 1 (elastic).
    pub restitution: f32,
    /// Speed limit (> 0; `f32::INFINITY` for none).
    pub max_speed: f32,
    /// Names of the kinds this one collides with (the relation is made symmetric).
    pub collides_with: Vec<String>,
    /// Seconds a body lives (> 0; `f32::INFINITY` for ever).
    pub lifetime: f32,
    /// Whether a controller (the game's machines) drives bodies of this kind: they die when
    /// it says so, not when their energy runs out.
    pub controlled: bool,
    /// Whether its contacts are swept over each step's motion (see [`Sweep`]).
    pub sweep: Sweep,
    /// How fast its bodies can move where the speed limit does not say (the ship's and the
    /// shots' speeds in a game), in units per second; `f32::INFINITY` when unknown. It
    /// decides and sizes swept contacts (see [`KindSpec::speed_bound`]).
    pub top_speed: f32,
}

impl KindSpec {
    /// The fastest its bodies are known to move: the smaller of its speed limit and its
    /// [`KindSpec::top_speed`] (`f32::INFINITY` when neither says).
    pub fn speed_bound(&self) -> f32 {
        self.max_speed.min(self.top_speed)
    }
}

/// Whether a kind's contacts are swept: tested over the whole of each step's motion (the
/// earliest time of impact), not only at its end, so that a fast body cannot pass through
/// what it should hit between two steps. A pair is swept if either kind says `On`, or
/// neither says `Off` and the rule of [`WorldSpec::pair_sweeps`] finds that it needs it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Sweep {
    /// Where the pair's speeds could carry it past a contact (a scene's default).
    Auto,
    /// Always (`swept = true`).
    On,
    /// Never (`swept = false`; the default of worlds made in code).
    #[default]
    Off,
}

/// Most contacts per thousand that a pair may miss between step ends before the automatic
/// rule sweeps it (see [`miss_fraction`]).
pub const SWEEP_ABOVE: f64 = 1.0e-3;

/// A swept pair is followed up to this many times the two kinds' top speeds: a kick can
/// carry a body a little past its speed for a step. Each body's own travel is followed as
/// far as it went; the margin bounds its partners', and the reach of its query.
pub const SWEEP_MARGIN: f32 = 1.25;

/// The fraction of straight passes through a disk of radius `reach` (at a uniformly random
/// offset from its centre) that a path sampled every `travel` units, at a random phase,
/// crosses without any sample inside it: the contacts a test at step ends misses. A chord
/// `c` is missed with probability `max(0, 1 − c / travel)`; integrated over the offsets.
///
/// With `s = travel / (2·reach)` and the chords shorter than the travel written by their
/// half-angle `φ` (`sin φ = half chord / reach`, up to `Φ = asin s`), the integral is
/// `(1 − cos Φ) − (w − sin w) / (4s)` with `w = 2Φ`, each part computed without
/// cancellation (`s² / (1 + cos Φ)`, and `w − sin w` by its series where `w` is small): it
/// is right to f64's precision for every travel from 0 to the largest f32 against any reach
/// (about `s² / 6` where the travel is small). From `s = 1` every chord is shorter than the
/// travel: `1 − π / (4s)`.
pub fn miss_fraction(travel: f64, reach: f64) -> f64 {
    // NaN fails too.
    if !(travel > 0.0 && reach > 0.0) {
        return 0.0;
    }
    let s = travel / (2.0 * reach);
    if s >= 1.0 {
        return 1.0 - std::f64::consts::FRAC_PI_4 / s;
    }
    let cos = (1.0 - s * s).sqrt();
    let w = 2.0 * s.asin();
    (s * s / (1.0 + cos) - w_minus_sin(w) / (4.0 * s)).max(0.0)
}

/// `w − sin w` for `w` in `[0, π]`, by its Taylor series below 0.1 (where the difference
/// would cancel; the first term left out is under 10⁻¹⁹ of the sum).
fn w_minus_sin(w: f64) -> f64 {
    if w >= 0.1 {
        return w - w.sin();
    }
    let w2 = w * w;
    // w³/3! − w⁵/5! + w⁷/7! − w⁹/9! + w¹¹/11!, by Horner.
    let series = 1.0 / 6.0
        - w2 * (1.0 / 120.0 - w2 * (1.0 / 5040.0 - w2 * (1.0 / 362_880.0 - w2 / 39_916_800.0)));
    w * w2 * series
}

/// Whether one colliding pair of kinds is swept, and why (see [`WorldSpec::pair_sweeps`]).
#[derive(Clone, Debug, PartialEq)]
pub struct PairSweep {
    /// The two kinds (the first index is the smaller, or both the same).
    pub kinds: (usize, usize),
    /// Whether their contacts are swept.
    pub swept: bool,
    /// The rule that decided it, in words.
    pub rule: String,
    /// The most the pair closes in a (sub)step at the kinds' top speeds, units (0 where
    /// neither speed is known).
    pub travel: f64,
    /// Their contact distance (the sum of their bounding circles' radii).
    pub reach: f64,
    /// The fraction of passes a test at step ends would miss at that travel
    /// ([`miss_fraction`]).
    pub misses: f64,
}

/// A whole world, before validation.
#[derive(Clone, Debug, PartialEq)]
pub struct WorldSpec {
    /// Width and height; the world is `[0, size.x) × [0, size.y)`.
    pub size: Vec2,
    /// Fixed time step in seconds.
    pub dt: f32,
    /// What happens at the edges.
    pub boundary: Boundary,
    /// The largest radius at which anything looks around (0 if none): the grid cells are made
    /// at least this large.
    pub vision: f32,
    /// The kinds of body, in slot order.
    pub kinds: Vec<KindSpec>,
    /// How the physics is computed.
    pub physics: Physics,
    /// The force field every body feels (none in the game's worlds).
    pub field: Field,
}

/// A value that breaks a rule, named by its path in the spec.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{field}: {problem}")]
pub struct SpecError {
    /// Where: `dt`, `kinds[2].radius`, …
    pub field: String,
    /// What is wrong and what is allowed.
    pub problem: String,
}

/// A [`SpecError`] for `field`.
pub(crate) fn error(field: impl fmt::Display, problem: impl fmt::Display) -> SpecError {
    SpecError {
        field: field.to_string(),
        problem: problem.to_string(),
    }
}

/// `value` at most `max`, where 0 means `zero` ("no limit", "never").
fn check_up_to(field: &str, value: u32, zero: &str, max: u32) -> Result<(), SpecError> {
    if value <= max {
        return Ok(());
    }
    Err(error(
        field,
        format!(
            "{} is out of range (allowed 0 for {zero}, or up to {})",
            thousands(value),
            thousands(max)
        ),
    ))
}

/// `value` must be in `(low, high]` (or `[low, high]` if `low_inclusive`); NaN never is.
pub(crate) fn check_range(
    field: impl fmt::Display,
    value: f32,
    (low, low_inclusive): (f32, bool),
    high: f32,
) -> Result<(), SpecError> {
    let above = if low_inclusive {
        value >= low
    } else {
        value > low
    };
    if above && value <= high {
        Ok(())
    } else {
        let open = if low_inclusive { '[' } else { '(' };
        let [value, low, high] = [value, low, high].map(number);
        Err(error(
            field,
            format!("{value} is out of range (allowed {open}{low}, {high}])"),
        ))
    }
}

impl WorldSpec {
    /// Whether any kind is bounded by a rectangle (else the narrow phase tests circles only).
    pub fn has_rects(&self) -> bool {
        self.kinds
            .iter()
            .any(|k| matches!(k.shape, Shape::Rect { .. }))
    }

    /// Checks every rule; the first broken one is the error.
    pub fn validate(&self) -> Result<(), SpecError> {
        check_range("size.x", self.size.x, (0.0, false), MAX_SIDE)?;
        check_range("size.y", self.size.y, (0.0, false), MAX_SIDE)?;
        check_range("dt", self.dt, (0.0, false), 1.0)?;
        check_range("vision", self.vision, (0.0, true), MAX_SIDE)?;
        self.physics.validate()?;
        let field = [
            ("field.gravity.x", self.field.gravity.x),
            ("field.gravity.y", self.field.gravity.y),
            ("field.centre.x", self.field.centre.x),
            ("field.centre.y", self.field.centre.y),
            ("field.strength", self.field.strength),
        ];
        for (name, value) in field {
            check_range(name, value, (-MAX_FIELD, true), MAX_FIELD)?;
        }
        if self.kinds.is_empty() || self.kinds.len() > MAX_KINDS {
            return Err(error(
                "kinds",
                format!("{} kinds (allowed 1 to {MAX_KINDS})", self.kinds.len()),
            ));
        }
        let mut slots = 0u64;
        for (k, kind) in self.kinds.iter().enumerate() {
            let at = |field: &str| format!("kinds[{k}] ({}).{field}", excerpt(&kind.name));
            if kind.name.trim().is_empty() {
                return Err(error(format!("kinds[{k}].name"), "must not be empty"));
            }
            if self.kinds[..k].iter().any(|other| other.name == kind.name) {
                return Err(error(at("name"), "is used by an earlier kind"));
            }
            match kind.shape {
                Shape::Circle { radius } => {
                    check_range(at("radius"), radius, (0.0, false), MAX_SIDE)?
                }
                Shape::Rect { half } => {
                    check_range(at("half.x"), half.x, (0.0, false), MAX_SIDE)?;
                    check_range(at("half.y"), half.y, (0.0, false), MAX_SIDE)?;
                }
            }
            // inf: an immovable body. Finite masses outside [MIN_MASS, MAX_MASS] would
            // overflow the kernels' arithmetic (1 / mass, or a contact's impulse).
            if kind.mass != f32::INFINITY && !(MIN_MASS..=MAX_MASS).contains(&kind.mass) {
                return Err(error(
                    at("mass"),
                    format!(
                        "{} is out of range (allowed {} to {}, or inf for an immovable body)",
                        number(kind.mass),
                        number(MIN_MASS),
                        number(MAX_MASS)
                    ),
                ));
            }
            if kind.capacity == 0 {
                return Err(error(
                    at("capacity"),
                    "0 is out of range (allowed at least 1)",
                ));
            }
            if kind.energy < 1 {
                return Err(error(
                    at("energy"),
                    format!("{} is out of range (allowed at least 1)", kind.energy),
                ));
            }
            if kind.damage < 0 {
                return Err(error(
                    at("damage"),
                    format!("{} is out of range (allowed at least 0)", kind.damage),
                ));
            }
            check_range(at("restitution"), kind.restitution, (0.0, true), 1.0)?;
            // inf: no speed limit.
            check_range(at("max_speed"), kind.max_speed, (0.0, false), f32::INFINITY)?;
            for (c, other) in kind.collides_with.iter().enumerate() {
                if !self.kinds.iter().any(|k| &k.name == other) {
                    return Err(error(
                        at(&format!("collides_with[{c}]")),
                        format!("no kind is named `{}`", excerpt(other)),
                    ));
                }
            }
            // inf: lives for ever.
            check_range(at("lifetime"), kind.lifetime, (0.0, false), f32::INFINITY)?;
            // inf: unknown.
            check_range(at("top_speed"), kind.top_speed, (0.0, false), f32::INFINITY)?;
            if kind.sweep == Sweep::On && !kind.speed_bound().is_finite() {
                return Err(error(
                    at("swept"),
                    "needs a speed limit (max_speed): a swept test reaches as far as the \
                     kind can travel in a step",
                ));
            }
            slots += u64::from(kind.capacity).next_multiple_of(32);
        }
        if slots > u64::from(MAX_SLOTS) {
            return Err(error(
                "kinds",
                format!(
                    "{} slots in all (allowed at most {}; each kind takes a multiple of 32)",
                    thousands(slots),
                    thousands(MAX_SLOTS)
                ),
            ));
        }
        Ok(())
    }

    /// Every colliding pair of kinds, each once, and whether its contacts are swept: always
    /// if either kind says [`Sweep::On`], never if either says [`Sweep::Off`], and otherwise
    /// where a test at step ends would miss more than [`SWEEP_ABOVE`] of the pair's contacts
    /// ([`miss_fraction`] of the distance the pair closes in a (sub)step at the kinds' top
    /// speeds, against their contact distance; a kind whose speed is unknown counts as
    /// still). Assumes a valid spec.
    pub fn pair_sweeps(&self) -> Vec<PairSweep> {
        let masks = self.collision_masks();
        let step = self.dt / self.physics.substeps as f32;
        let bound = |k: &KindSpec| {
            let b = k.speed_bound();
            if b.is_finite() { b } else { 0.0 }
        };
        let mut pairs = Vec::new();
        for (i, a) in self.kinds.iter().enumerate() {
            for (j, b) in self.kinds.iter().enumerate().skip(i) {
                if masks[i] & (1 << j) == 0 {
                    continue;
                }
                // In f64: two speed limits near f32's largest sum past it.
                let travel = (f64::from(bound(a)) + f64::from(bound(b))) * f64::from(step);
                let reach = f64::from(a.shape.reach()) + f64::from(b.shape.reach());
                let misses = miss_fraction(travel, reach);
                let names = |k: &KindSpec| excerpt(&k.name).to_string();
                let (swept, rule) = match (a.sweep, b.sweep) {
                    (Sweep::On, _) => (true, format!("swept = true for {}", names(a))),
                    (_, Sweep::On) => (true, format!("swept = true for {}", names(b))),
                    (Sweep::Off, _) => (false, format!("swept = false for {}", names(a))),
                    (_, Sweep::Off) => (false, format!("swept = false for {}", names(b))),
                    _ => (
                        misses > SWEEP_ABOVE,
                        format!(
                            "auto: closes {} units a step against a contact of {}, {} per \
                             thousand passes missed at step ends",
                            figure(travel),
                            figure(reach),
                            figure(misses * 1000.0)
                        ),
                    ),
                };
                pairs.push(PairSweep {
                    kinds: (i, j),
                    swept,
                    rule,
                    travel,
                    reach,
                    misses,
                });
            }
        }
        pairs
    }

    /// Each kind's mask of the kinds its contacts with are swept (symmetric; see
    /// [`WorldSpec::pair_sweeps`]).
    pub fn sweep_masks(&self) -> Vec<u32> {
        let mut masks = vec![0u32; self.kinds.len()];
        for pair in self.pair_sweeps().iter().filter(|p| p.swept) {
            let (i, j) = pair.kinds;
            masks[i] |= 1 << j;
            masks[j] |= 1 << i;
        }
        masks
    }

    /// Whether some pair of kinds is swept (see [`WorldSpec::pair_sweeps`]).
    pub fn has_swept_pairs(&self) -> bool {
        self.pair_sweeps().iter().any(|p| p.swept)
    }

    /// Whether the world keeps each body's last path: some pair is swept, or the physics
    /// asks for it ([`Physics::trace_paths`]).
    pub fn traces(&self) -> bool {
        self.physics.trace_paths || self.has_swept_pairs()
    }

    /// Index of the kind called `name`.
    pub fn kind_index(&self, name: &str) -> Option<usize> {
        self.kinds.iter().position(|k| k.name == name)
    }

    /// Collision masks (bit `j` of entry `i`: kinds `i` and `j` collide), made symmetric.
    /// Assumes a valid spec.
    pub fn collision_masks(&self) -> Vec<u32> {
        let mut masks = vec![0u32; self.kinds.len()];
        for (i, kind) in self.kinds.iter().enumerate() {
            for j in kind.collides_with.iter().filter_map(|n| self.kind_index(n)) {
                masks[i] |= 1 << j;
                masks[j] |= 1 << i;
            }
        }
        masks
    }
}
