//! The rows and columns of a query's 3×3 block (`Space::neighbourhood`,
//! `Space::neighbourhood_within`), checked against the block listed by hand: the cells at
//! offsets -1, 0, +1, wrapped or cut at the edges, each once (a wrapping grid narrower than
//! three lists its indices from 0), and their runs of consecutive indices. With a finite
//! reach, the block keeps the cell of every point within reach (as the queries measure it,
//! in `f32`), and no neighbour lying farther.

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

/// A square grid of `n × n` cells of side `side`.
fn grid(n: u32, side: f32, wraps: bool) -> Space {
    let size = n as f32 * side;
    Space {
        size: Vec2::splat(size),
        inv_cell: Vec2::splat(n as f32 / size),
        cols: n,
        rows: n,
        wrap: u32::from(wraps),
        reserved: 0,
    }
}

/// `x` moved by `ulps` units in the last place.
fn nudged(x: f32, ulps: i32) -> f32 {
    let mut y = x;
    for _ in 0..ulps.unsigned_abs() {
        y = if ulps > 0 { y.next_up() } else { y.next_down() };
    }
    y
}

#[test]
fn a_reach_keeps_every_cell_within_it_and_no_neighbour_beyond() {
    for wraps in [false, true] {
        for n in 1u32..7 {
            for side in [10.0f32, 37.3, 140.0] {
                let space = grid(n, side, wraps);
                let size = space.size.x;
                // Queries across the world and beyond its edges, on and next to the cells'
                // borders; points near every border a query's reach can cross.
                let mut queries: Vec<f32> = (-8..=(16 * n as i32 + 8))
                    .map(|k| k as f32 * side / 16.0)
                    .collect();
                let borders: Vec<f32> = (0..=n).map(|j| j as f32 * side).collect();
                for &b in &borders {
                    queries.extend([-3, -1, 1, 3].map(|u| nudged(b, u)));
                }
                for &x in &queries {
                    if wraps && !(0.0..size).contains(&x) {
                        continue; // a wrapping world holds no point outside it
                    }
                    for fraction in [0.0f32, 0.1, 0.3, 0.5, 0.77, 0.999, 1.0] {
                        let reach = fraction * side;
                        check_reach(&space, x, reach, &borders);
                    }
                }
            }
        }
    }
}

/// One query at `(x, x)` within `reach` (a check along the columns; rows are the same).
fn check_reach(space: &Space, x: f32, reach: f32, borders: &[f32]) {
    let pos = Vec2::splat(x);
    let (rows, cols) = space.neighbourhood_within(pos, reach);
    assert_eq!(
        listed(&rows),
        listed(&cols),
        "a square grid's rows and columns"
    );
    let at = format!(
        "{} cells of {}, wraps {}, x {x}, reach {reach}",
        space.cols,
        space.size.x / space.cols as f32,
        space.wraps()
    );
    let list = listed(&cols);
    let (i, _) = space.cell_coords(pos);
    let full = expected(i, space.cols, space.wraps());
    // In the full block's order, less some neighbours, and never the query's own cell.
    let kept: Vec<u32> = full.iter().copied().filter(|j| list.contains(j)).collect();
    assert_eq!(list, kept, "a part of the full block, in its order: {at}");
    assert!(list.contains(&i), "its own cell: {at}");
    let runs: Vec<(u32, u32)> = (0..cols.runs()).map(|k| cols.run(k)).collect();
    assert_eq!(runs, runs_of(&list), "column runs: {at}");
    // No loss: every point a query would find within reach lies in a listed cell.
    let mut points: Vec<f32> = Vec::new();
    for &b in borders {
        points.extend((-40..=40).map(|u| nudged(b, u)));
    }
    points.extend(
        [x - reach, x + reach]
            .iter()
            .flat_map(|&e| (-40..=40).map(move |u| nudged(e, u))),
    );
    for e in points {
        if !(0.0..space.size.x).contains(&e) && space.wraps() {
            continue;
        }
        let d = space.offset(pos, Vec2::new(e, x)).x;
        if d.abs() <= reach {
            let (cell, _) = space.cell_coords(Vec2::new(e, x));
            assert!(
                list.contains(&cell),
                "point {e} at {d} in cell {cell} lost: {at}"
            );
        }
    }
    // No waste: a neighbour is kept only if some of it lies within reach (and a margin far
    // below a cell's side).
    let side = f64::from(space.size.x) / f64::from(space.cols);
    let t = f64::from(x) / side;
    let slack = (t.abs() + f64::from(space.cols) + 3.0) * side / 100_000.0;
    let own = f64::from(i);
    for (k, &j) in full.iter().enumerate() {
        if j == i || !list.contains(&j) || (space.wraps() && space.cols < 3) {
            continue;
        }
        // The neighbour before the own cell in the block's order lies below it.
        let gap = if k == 0 {
            (t - own) * side
        } else {
            (own + 1.0 - t) * side
        };
        assert!(
            gap <= f64::from(reach) + slack,
            "neighbour {j} kept {gap} away: {at}"
        );
    }
}
