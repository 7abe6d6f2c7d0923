//! The backdrop of a followed frame: faint lines at the world's multiples of [`SPACING`]
//! and the field's border, under everything drawn, so that a player sees the ship move
//! when the camera moves with it (the genre's look).
//!
//! [`on_grid`] decides a pixel from the frame's view alone. The kernel renderer calls it in
//! `resolve_pixels` for pixels no body or particle covers; the GL renderer's backdrop pass
//! (`host/graphics/bodies.rs`) is a line-for-line copy, so both draw the same lines. A line
//! is one pixel wide: the column (row) whose extent holds the multiple, found by the same
//! two roundings (a difference, a product) on both; the border is the first and the last
//! pixel whose centre lies inside the field, which no rounding near the image's edges moves.

use glam::Vec2;

use super::Framing;

/// World units between grid lines.
pub const SPACING: f32 = 64.0;
/// Fewest pixels between lines on screen: a view that packs them closer shows the border
/// only.
pub const MIN_GAP_PX: f32 = 24.0;
/// Colour of the grid's lines, RGBA8.
pub const LINE: u32 = u32::from_le_bytes([22, 26, 52, 255]);
/// Colour of the field's border, RGBA8.
pub const BORDER: u32 = u32::from_le_bytes([60, 70, 130, 255]);

/// What one axis of a pixel lies on.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Mark {
    /// Its centre is outside the field.
    Out,
    /// Inside the field, on no line.
    Clear,
    /// On a grid line.
    Line,
    /// The first or the last pixel inside the field.
    Border,
}

/// Along one axis: the pixel numbered `p` from the view's `origin` (at `scale` pixels per
/// unit) in a field `field` long, with lines when `lines`.
#[inline(always)]
fn mark(origin: f32, scale: f32, field: f32, lines: bool, p: f32) -> Mark {
    let centre = p + 0.5;
    // The field's edges in pixels from the view's origin.
    let (low, high) = ((0.0 - origin) * scale, (field - origin) * scale);
    if centre < low || centre >= high {
        return Mark::Out;
    }
    if centre - 1.0 < low || centre + 1.0 >= high {
        return Mark::Border;
    }
    // The multiple nearest the pixel's centre: lines are far apart, so no rounding changes
    // which one; the pixel is on it if the multiple falls in its extent.
    let k = crate::math::floor((origin + centre / scale) / SPACING + 0.5);
    if lines && crate::math::floor((k * SPACING - origin) * scale) == p {
        Mark::Line
    } else {
        Mark::Clear
    }
}

/// What an image row lies on (see [`row`]): the part of a pixel's backdrop that its
/// column does not change, worked out once for a row's pixels.
#[derive(Clone, Copy, PartialEq, Eq)]
pub struct Row(Mark);

impl Row {
    /// A row outside the field: nothing of the backdrop on it.
    pub const OUT: Row = Row(Mark::Out);
}

/// Whether lines are drawn in `view`: only when they are at least [`MIN_GAP_PX`] apart.
#[inline(always)]
fn lines(view: &Framing) -> bool {
    SPACING * view.scale >= MIN_GAP_PX
}

/// What image row `y` (row 0 at the top) of `view` over a `field`-sized world lies on.
#[inline(always)]
pub fn row(view: &Framing, field: Vec2, y: u32) -> Row {
    // Rows from the bottom, as the world's y runs.
    let up = (view.height - 1 - y) as f32;
    Row(mark(view.origin.y, view.scale, field.y, lines(view), up))
}

/// The backdrop's colour at pixel `x` of a row of `view` that lies on `row` (see
/// [`on_grid`]).
#[inline(always)]
pub fn on_row(view: &Framing, field: Vec2, row: Row, x: u32) -> Option<u32> {
    if row.0 == Mark::Out {
        return None;
    }
    let across = mark(view.origin.x, view.scale, field.x, lines(view), x as f32);
    match (across, row.0) {
        (Mark::Out, _) | (_, Mark::Out) => None,
        (Mark::Border, _) | (_, Mark::Border) => Some(BORDER),
        (Mark::Line, _) | (_, Mark::Line) => Some(LINE),
        _ => None,
    }
}

/// The backdrop's colour at image pixel `(x, y)` (row 0 at the top) of `view` over a
/// `field`-sized world: [`BORDER`] on the field's border, [`LINE`] on a grid line (when
/// lines are at least [`MIN_GAP_PX`] apart), `None` elsewhere and outside the field.
#[inline(always)]
pub fn on_grid(view: &Framing, field: Vec2, x: u32, y: u32) -> Option<u32> {
    on_row(view, field, row(view, field, y), x)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A `width × height` view of world units from `origin` at `scale` pixels per unit.
    fn view(origin: Vec2, scale: f32, width: u32, height: u32) -> Framing {
        Framing {
            origin,
            scale,
            width,
            height,
            background: 0,
        }
    }

    #[test]
    fn lines_fall_on_the_multiples_and_the_border_inside_the_field() {
        let field = Vec2::splat(1000.0);
        let v = view(Vec2::ZERO, 1.0, 200, 100);
        let at = |x, y| on_grid(&v, field, x, y);
        // The field's left and bottom edges are the image's: its first pixels.
        assert_eq!(at(0, 50), Some(BORDER));
        assert_eq!(at(50, 99), Some(BORDER));
        // Columns 64 and 128 hold x = 64 and 128; row 99 − 64 holds y = 64.
        for x in [64, 128] {
            assert_eq!(at(x, 10), Some(LINE), "column {x}");
            assert_eq!(at(x - 1, 10), None);
            assert_eq!(at(x + 1, 10), None);
        }
        assert_eq!(at(10, 35), Some(LINE));
        assert_eq!(at(10, 34), None);
        assert_eq!(at(10, 36), None);
        // Half a unit further on, at two pixels a unit: x = 64 is column 127.
        let v = view(Vec2::new(0.5, 0.5), 2.0, 200, 100);
        assert_eq!(on_grid(&v, field, 127, 10), Some(LINE));
        assert_eq!(on_grid(&v, field, 126, 10), None);
        assert_eq!(on_grid(&v, field, 128, 10), None);
        assert_eq!(
            on_grid(&v, field, 0, 10),
            None,
            "the border is off the image"
        );
    }

    #[test]
    fn lines_packed_closer_than_the_gap_leave_the_border_alone() {
        // 64 units at 0.3 pixels a unit: 19.2 pixels apart.
        let field = Vec2::new(400.0, 200.0);
        let v = view(Vec2::new(-50.0, -50.0), 0.3, 200, 100);
        let marks: usize = (0..100)
            .flat_map(|y| (0..200).map(move |x| (x, y)))
            .filter(|&(x, y)| on_grid(&v, field, x, y) == Some(LINE))
            .count();
        assert_eq!(marks, 0);
        // The field spans pixels 15 to 134 across (its centres from 15.5 to 134.5), rows
        // from the bottom 15 to 74; outside it nothing is drawn.
        assert_eq!(on_grid(&v, field, 15, 50), Some(BORDER));
        assert_eq!(on_grid(&v, field, 134, 50), Some(BORDER));
        assert_eq!(on_grid(&v, field, 16, 50), None);
        assert_eq!(on_grid(&v, field, 14, 50), None);
        assert_eq!(on_grid(&v, field, 135, 50), None);
        assert_eq!(on_grid(&v, field, 50, 99 - 15), Some(BORDER));
        assert_eq!(on_grid(&v, field, 50, 99 - 74), Some(BORDER));
        assert_eq!(on_grid(&v, field, 50, 99 - 75), None);
    }
}
