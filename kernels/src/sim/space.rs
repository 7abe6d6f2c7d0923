//! The world's geometry: its size, its boundary rule and the uniform grid over it.

use glam::Vec2;

/// The world `[0, size.x) × [0, size.y)`, its boundary rule, and the uniform grid that
/// serves the broad phase and the enemies' vision.
///
/// The grid has `cols × rows` equal cells that tile the world exactly; the host picks the
/// cell at least as large as the largest collision diameter and the largest vision radius, so
/// anything a body can touch or see lies in its own cell or one of the eight around it.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct Space {
    /// Width and height of the world.
    pub size: Vec2,
    /// Cells per unit length along each axis (`cols / size.x`, `rows / size.y`).
    pub inv_cell: Vec2,
    /// Grid columns (at least 1).
    pub cols: u32,
    /// Grid rows (at least 1).
    pub rows: u32,
    /// Non-zero: the world wraps around (a torus); zero: bodies are clamped to its edges.
    pub wrap: u32,
    /// Keeps the struct free of implicit padding.
    pub reserved: u32,
}

impl Space {
    /// Number of grid cells.
    #[inline(always)]
    pub fn cells(&self) -> u32 {
        self.cols * self.rows
    }

    /// Whether the world wraps around.
    #[inline(always)]
    pub fn wraps(&self) -> bool {
        self.wrap != 0
    }

    /// Column and row of the cell holding `pos`. Positions outside the world (and NaN, which
    /// the float-to-integer conversion maps to 0) land in the nearest border cell.
    #[inline(always)]
    pub fn cell_coords(&self, pos: Vec2) -> (u32, u32) {
        // `as` saturates on both targets: negative and NaN become 0.
        let col = ((pos.x * self.inv_cell.x) as u32).min(self.cols - 1);
        let row = ((pos.y * self.inv_cell.y) as u32).min(self.rows - 1);
        (col, row)
    }

    /// Index of the cell holding `pos`, row-major.
    #[inline(always)]
    pub fn cell_of(&self, pos: Vec2) -> u32 {
        let (col, row) = self.cell_coords(pos);
        row * self.cols + col
    }

    /// The displacement from `from` to `to`: on a wrapping world the shortest one, across
    /// the seams if that is shorter (both points inside the world).
    #[inline(always)]
    pub fn offset(&self, from: Vec2, to: Vec2) -> Vec2 {
        let d = to - from;
        if self.wraps() {
            Vec2::new(shortest(d.x, self.size.x), shortest(d.y, self.size.y))
        } else {
            d
        }
    }

    /// The offset `d` moved by whole periods to the one nearest `near`, on a wrapping world
    /// (`d` itself elsewhere): two offsets of a pair taken apart (a step's start and end)
    /// then describe one straight relative path, even where the pair lies about half the
    /// world apart and each offset alone could be either way round.
    #[inline(always)]
    pub fn image_near(&self, d: Vec2, near: Vec2) -> Vec2 {
        if self.wraps() {
            near + self.offset(near, d)
        } else {
            d
        }
    }

    /// Brings a position back into the world by the boundary rule: wrapped around, or clamped
    /// to the edges with the velocity component that points out of the world removed.
    #[inline(always)]
    pub fn confine(&self, pos: Vec2, vel: Vec2) -> (Vec2, Vec2) {
        if self.wraps() {
            (
                Vec2::new(wrap(pos.x, self.size.x), wrap(pos.y, self.size.y)),
                vel,
            )
        } else {
            let (x, vx) = clamp(pos.x, vel.x, self.size.x);
            let (y, vy) = clamp(pos.y, vel.y, self.size.y);
            (Vec2::new(x, y), Vec2::new(vx, vy))
        }
    }

    /// The rows and the columns of the 3×3 block around the cell of `pos`, each as its
    /// distinct indices in order of offset (-1, 0, +1): on a wrapping world the block wraps
    /// around (and a grid narrower than three cells lists each index once, from 0),
    /// otherwise it stops at the edges.
    #[inline(always)]
    pub fn neighbourhood(&self, pos: Vec2) -> (Span, Span) {
        let (col, row) = self.cell_coords(pos);
        (
            Span::around(row, self.rows, self.wraps()),
            Span::around(col, self.cols, self.wraps()),
        )
    }

    /// [`Space::neighbourhood`] less the neighbouring rows and columns that lie wholly
    /// farther than `reach` from `pos` (at most a cell's side): what a query that finds
    /// nothing farther than `reach` along either axis needs to read.
    #[inline(always)]
    pub fn neighbourhood_within(&self, pos: Vec2, reach: f32) -> (Span, Span) {
        let (col, row) = self.cell_coords(pos);
        // The same products `cell_coords` rounds down, so the grid's cells and the spans'
        // bounds agree.
        let at = pos * self.inv_cell;
        let reach = Vec2::splat(reach) * self.inv_cell;
        (
            Span::within(row, self.rows, self.wraps(), at.y, reach.y),
            Span::within(col, self.cols, self.wraps(), at.x, reach.x),
        )
    }
}

/// The relative margin by which a neighbouring row or column must lie beyond a query's reach
/// to be left out: many times the rounding of the grid coordinates and of the distances the
/// queries test, so that leaving it out never loses a body the full block would have found.
const SLACK: f32 = 1.0 / 524_288.0;

/// At most three distinct grid indices below `n`, consecutive but for a wrap from `n - 1`
/// to 0: the rows or the columns of a query's block. Plain numbers rather than a list, so
/// that a kernel keeps them in registers (a list indexed at run time goes to local memory).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Span {
    /// The first index.
    pub first: u32,
    /// How many (1 to 3).
    pub count: u32,
    /// The indices' range, `0..n`.
    pub n: u32,
}

impl Span {
    /// The distinct indices among `i - 1, i, i + 1` in `0..n` (`i < n`), wrapped or cut at
    /// the ends, in increasing order of offset.
    #[inline(always)]
    fn around(i: u32, n: u32, wraps: bool) -> Span {
        match (wraps, n < 3) {
            // Every index is a neighbour; each once.
            (true, true) => Span {
                first: 0,
                count: n,
                n,
            },
            (true, false) => Span {
                first: if i == 0 { n - 1 } else { i - 1 },
                count: 3,
                n,
            },
            (false, _) => {
                let first = i.saturating_sub(1);
                Span {
                    first,
                    count: (i + 1).min(n - 1) - first + 1,
                    n,
                }
            }
        }
    }

    /// [`Span::around`] without the neighbour below `i` when nothing within `reach` of `t`
    /// lies in it, and likewise above (`t`: the position in cells, whose cell is `i`;
    /// `reach` in cells). NaN keeps both.
    #[inline(always)]
    fn within(i: u32, n: u32, wraps: bool, t: f32, reach: f32) -> Span {
        let full = Span::around(i, n, wraps);
        if wraps && n < 3 {
            // The same index lies both below and above.
            return full;
        }
        let slack = (t.abs() + reach + 2.0) * SLACK;
        let below = full.first != i;
        let above = full.count > 1 + u32::from(below);
        // Cell `i - 1` ends at `i`, cell `i + 1` starts at `i + 1`.
        let skip_below = below && t - reach - slack >= i as f32;
        let skip_above = above && t + reach + slack < (i + 1) as f32;
        Span {
            first: if skip_below { i } else { full.first },
            count: full.count - u32::from(skip_below) - u32::from(skip_above),
            n,
        }
    }

    /// The `k`-th index (`k < count`).
    #[inline(always)]
    pub fn at(&self, k: u32) -> u32 {
        let i = self.first + k;
        if i >= self.n { i - self.n } else { i }
    }

    /// Runs of consecutive indices: 1, or 2 where the span wraps.
    #[inline(always)]
    pub fn runs(&self) -> u32 {
        1 + u32::from(self.first + self.count > self.n)
    }

    /// Run `r`'s first and last index (`r < runs()`): the span up to `n - 1`, then the
    /// wrapped part from 0.
    #[inline(always)]
    pub fn run(&self, r: u32) -> (u32, u32) {
        let end = self.first + self.count;
        if r == 0 {
            (self.first, end.min(self.n) - 1)
        } else {
            (0, end - self.n - 1)
        }
    }
}

/// `d` moved by a whole period towards zero when that makes it shorter.
#[inline(always)]
fn shortest(d: f32, period: f32) -> f32 {
    let half = 0.5 * period;
    if d > half {
        d - period
    } else if d < -half {
        d + period
    } else {
        d
    }
}

/// `x` wrapped into `[0, period)`. A non-finite `x` becomes 0, so no NaN reaches the grid.
#[inline(always)]
fn wrap(x: f32, period: f32) -> f32 {
    let x = if x >= 0.0 && x < period {
        x
    } else {
        x - period * crate::math::floor(x / period)
    };
    // The subtraction can round up to `period` itself.
    if x >= 0.0 && x < period { x } else { 0.0 }
}

/// `x` clamped to `[0, limit]`, and `v` without the part that pushes further out.
#[inline(always)]
fn clamp(x: f32, v: f32, limit: f32) -> (f32, f32) {
    if x < 0.0 {
        (0.0, v.max(0.0))
    } else if x > limit {
        (limit, v.min(0.0))
    } else if x >= 0.0 {
        (x, v)
    } else {
        // NaN: back to the origin, at rest along this axis.
        (0.0, 0.0)
    }
}
