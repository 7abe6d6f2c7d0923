//! Where things go: each kind's slot range (grouped warps) and the grid over the world.

use gpuwars_kernels::sim::{KindInfo, SlotRange, Space, kinds};

use super::spec::{Boundary, SWEEP_MARGIN, Shape, WorldSpec};

/// Slots per warp: each kind's range starts on a multiple of it.
pub const WARP: u32 = gpuwars_kernels::warp::WARP;
/// Most grid cells: a world of tiny bodies gets coarser cells rather than a huge grid.
pub const MAX_CELLS: u32 = 1 << 22;
/// Most grid buckets (a cell's bucket for each kind) a world gets per slot: a field far
/// larger than its bodies need gets coarser cells, so that the grid costs what the bodies
/// do, not what the field's area does (the cells a query reads stay the 3×3 around it).
pub const BUCKETS_PER_SLOT: u64 = 8;
/// Cells are made this much larger than the largest reach, so that rounding in the cell
/// arithmetic can never separate two touching bodies by more than one cell.
const CELL_MARGIN: f32 = 1.0 + 1.0 / 1024.0;

/// The slot ranges of a world, one per kind, in the spec's order.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Layout {
    /// Range of each kind.
    pub ranges: Vec<SlotRange>,
    /// Total slots, padding included.
    pub slots: u32,
}

impl Layout {
    /// Ranges for the spec's capacities, each aligned to [`WARP`].
    pub fn new(spec: &WorldSpec) -> Self {
        let mut start = 0;
        let ranges = spec
            .kinds
            .iter()
            .map(|kind| {
                let range = SlotRange {
                    start,
                    capacity: kind.capacity,
                };
                start = range.padded_end();
                range
            })
            .collect();
        Layout {
            ranges,
            slots: start,
        }
    }

    /// The kind of every slot (padding belongs to the range before it).
    pub fn slot_kinds(&self) -> Vec<u32> {
        let mut kinds = vec![0; self.slots as usize];
        for (k, range) in self.ranges.iter().enumerate() {
            kinds[range.start as usize..range.padded_end() as usize].fill(k as u32);
        }
        kinds
    }
}

/// The kernels' table of kinds.
pub fn kind_table(spec: &WorldSpec) -> Vec<KindInfo> {
    let swept_kinds = spec.sweep_masks();
    let step = spec.dt / spec.physics.substeps as f32;
    // How far a body of each kind may travel in a (sub)step, for swept pairs' reach.
    let travel: Vec<f32> = (spec.kinds.iter())
        .map(|k| match k.speed_bound() {
            b if b.is_finite() => SWEEP_MARGIN * b * step,
            _ => 0.0,
        })
        .collect();
    spec.kinds
        .iter()
        .enumerate()
        .zip(spec.collision_masks())
        .map(|((i, kind), collides_with)| {
            // Rectangles lie inside their circles, so the circles' sum bounds every pair; a
            // swept pair's query reaches as far as both can travel besides.
            let reach = kind.shape.reach();
            let partner = (0..spec.kinds.len())
                .filter(|&k| collides_with & (1 << k) != 0)
                .map(|k| {
                    let swept = swept_kinds[i] & (1 << k) != 0;
                    let extra = if swept { travel[i] + travel[k] } else { 0.0 };
                    spec.kinds[k].shape.reach() + extra
                })
                .reduce(f32::max);
            let (shape, half) = match kind.shape {
                Shape::Circle { radius } => (kinds::SHAPE_CIRCLE, glam::Vec2::splat(radius)),
                Shape::Rect { half } => (kinds::SHAPE_RECT, half),
            };
            KindInfo {
                half,
                reach,
                shape,
                collides_with,
                damage: kind.damage,
                restitution: kind.restitution,
                max_speed: kind.max_speed,
                energy: kind.energy,
                lifetime: steps(kind.lifetime, spec.dt),
                // The kernels only ask whether a controller decides deaths: the game hands
                // its machines to its own kernels.
                controlled: u32::from(kind.controlled),
                contact_reach: partner.map_or(0.0, |partner| reach + partner),
                swept_kinds: swept_kinds[i],
                travel: travel[i],
            }
        })
        .collect()
}

/// The world and its grid: cells no smaller than the largest distance at which two bodies
/// can touch or a body can see, as many as fit, up to [`MAX_CELLS`] and to
/// [`BUCKETS_PER_SLOT`] buckets a slot.
pub fn space(spec: &WorldSpec) -> Space {
    let masks = spec.collision_masks();
    // Two bodies touch only if their centres are closer than the sum of their reaches.
    let touch = spec
        .kinds
        .iter()
        .zip(&masks)
        .filter(|(_, mask)| **mask != 0)
        .map(|(kind, _)| 2.0 * kind.shape.reach())
        .fold(0.0f32, f32::max);
    // A swept pair's query reaches farther: as far as both can travel in a (sub)step.
    let swept = kind_table(spec)
        .iter()
        .map(|k| k.contact_reach)
        .fold(0.0f32, f32::max);
    let cell = touch.max(swept).max(spec.vision) * CELL_MARGIN * spec.physics.cell_scale;
    let fit = |side: f32| {
        if cell > 0.0 {
            ((side / cell) as u32).clamp(1, MAX_CELLS)
        } else {
            1
        }
    };
    let (mut cols, mut rows) = (fit(spec.size.x), fit(spec.size.y));
    let kinds = spec.kinds.len().max(1) as u64;
    let per_slots = BUCKETS_PER_SLOT * u64::from(Layout::new(spec).slots) / kinds;
    let most = per_slots.clamp(1, u64::from(MAX_CELLS));
    while u64::from(cols) * u64::from(rows) > most {
        if cols >= rows {
            cols = cols.div_ceil(2);
        } else {
            rows = rows.div_ceil(2);
        }
    }
    Space {
        size: spec.size,
        inv_cell: glam::Vec2::new(cols as f32 / spec.size.x, rows as f32 / spec.size.y),
        cols,
        rows,
        wrap: u32::from(spec.boundary == Boundary::Wrap),
        reserved: 0,
    }
}

/// Whole steps of `dt` in `seconds`, at least 1; 0 for an infinite time (no limit).
pub fn steps(seconds: f32, dt: f32) -> u32 {
    if seconds.is_finite() {
        // `as` saturates: absurdly long times become the longest representable.
        ((seconds / dt).round() as u32).max(1)
    } else {
        0
    }
}
