//! The rows and columns of a query's 3×3 block (`Space::neighbourhood`), checked against
//! the block listed by hand: the cells at offsets -1, 0, +1, wrapped or cut at the edges,
//! each once (a wrapping grid narrower than three lists its indices from 0), and their runs
//! of consecutive indices.

use glam::Vec2;
use gpuwars_kernels::sim::Space;
use gpuwars_kernels::sim::space::Span;

/// The indices a span lists, in order.
fn listed(span: &Span) -> Vec<u32> {
    (0..span.count).map(|k| span.at(k)).collect()
}

/// The maximal runs of consecutive indices in `list`, in order.
fn runs_of(list: &[u32]) -> Vec<(u32, u32)> {
    let mut runs: Vec<(u32, u32)> = Vec::new();
    for &i in list {
        match runs.last_mut() {
            Some(run) if run.1 + 1 == i => run.1 = i,
            _ => runs.push((i, i)),
        }
    }
    runs
}

/// The block's indices along an axis of `n` cells around `i`, by hand.
fn expected(i: u32, n: u32, wraps: bool) -> Vec<u32> {
    if wraps && n < 3 {
        return (0..n).collect();
    }
    let mut out = Vec::new();
    for offset in [-1i64, 0, 1] {
        let j = i64::from(i) + offset;
        let j = match (wraps, (0..i64::from(n)).contains(&j)) {
            (_, true) => j,
            (true, false) => j.rem_euclid(i64::from(n)),
            (false, false) => continue,
        };
        out.push(j as u32);
    }
    out
}

#[test]
fn every_cell_of_every_small_grid_gets_its_block() {
    for wraps in [false, true] {
        for cols in 1u32..7 {
            for rows in 1u32..5 {
                let space = Space {
                    size: Vec2::new(cols as f32 * 10.0, rows as f32 * 10.0),
                    inv_cell: Vec2::splat(0.1),
                    cols,
                    rows,
                    wrap: u32::from(wraps),
                    reserved: 0,
                };
                for col in 0..cols {
                    for row in 0..rows {
                        let pos = Vec2::new(col as f32 * 10.0 + 5.0, row as f32 * 10.0 + 5.0);
                        let (r, c) = space.neighbourhood(pos);
                        let at = format!("{cols}×{rows} grid, wraps {wraps}, cell ({col}, {row})");
                        assert_eq!(listed(&r), expected(row, rows, wraps), "rows, {at}");
                        let cols_listed = listed(&c);
                        assert_eq!(cols_listed, expected(col, cols, wraps), "columns, {at}");
                        let runs: Vec<(u32, u32)> = (0..c.runs()).map(|k| c.run(k)).collect();
                        assert_eq!(runs, runs_of(&cols_listed), "column runs, {at}");
                    }
                }
            }
        }
    }
}
