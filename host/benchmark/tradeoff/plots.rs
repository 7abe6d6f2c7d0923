//! The tradeoff's plots: the crowd's error against its speed, and the game scene's contacts
//! missed against its speed, each choice a labelled point and the Pareto frontier in red.

use std::path::Path;

use anyhow::anyhow;
use plotters::prelude::*;

use super::{PhysicsRow, TradeoffSummary};
use crate::benchmark::plot::{legend, log_range, png, points_with_labels};

/// The crowd's Pareto plot: position error against simulated seconds per wall second, both
/// log, each choice labelled; the frontier joined by a line.
pub fn pareto(path: &Path, summary: &TradeoffSummary) -> anyhow::Result<()> {
    png(path, |area| {
        let rows = &summary.physics;
        let x = log_range(rows.iter().map(|r| r.sim_seconds_per_s), &[]);
        // A run that matches the reference exactly still plots, at the smallest error.
        let floor = rows
            .iter()
            .map(|r| r.position_rms)
            .filter(|e| *e > 0.0)
            .fold(f64::INFINITY, f64::min);
        let floor = if floor.is_finite() { floor } else { 1e-6 };
        let error = |r: &PhysicsRow| r.position_rms.max(floor);
        let y = log_range(rows.iter().map(error), &[]);
        let title = format!(
            "speed against accuracy: {} balls ({}, {})",
            summary.sizes.error_bodies, summary.machine.device, summary.machine.backend
        );
        let mut chart = ChartBuilder::on(area)
            .caption(title, ("sans-serif", 22))
            .margin(16)
            .x_label_area_size(48)
            .y_label_area_size(80)
            .build_cartesian_2d(x.log_scale(), y.log_scale())
            .map_err(|e| anyhow!("{e}"))?;
        chart
            .configure_mesh()
            .x_desc("simulated seconds per wall second (log)")
            .y_desc("position RMS against the f64 reference (log)")
            .label_style(("sans-serif", 16))
            .draw()
            .map_err(|e| anyhow!("{e}"))?;
        let choices = rows.iter().map(|r| {
            let point = (r.sim_seconds_per_s, error(r));
            (point, r.pareto, r.choice.clone())
        });
        choices_and_frontier(area, &mut chart, choices.collect())
    })
}

/// The game scene's trade: contacts missed per thousand (its audit) against simulated
/// seconds per wall second, a point per choice of the game table, the Pareto frontier in
/// red.
pub fn game_pareto(path: &Path, summary: &TradeoffSummary) -> anyhow::Result<()> {
    png(path, |area| {
        let rows: Vec<_> = (summary.game.iter())
            .filter_map(|r| Some((r, r.accuracy.as_ref()?.missed?)))
            .collect();
        let x = log_range(rows.iter().map(|(r, _)| r.sim_seconds_per_s), &[]);
        let top = rows.iter().map(|&(_, m)| m).fold(1.0, f64::max) * 1.15;
        let title = format!(
            "{}: contacts missed against speed ({}, {})",
            summary.scene, summary.machine.device, summary.machine.backend
        );
        let mut chart = ChartBuilder::on(area)
            .caption(title, ("sans-serif", 22))
            .margin(16)
            .x_label_area_size(48)
            .y_label_area_size(80)
            .build_cartesian_2d(x.log_scale(), -0.04 * top..top)
            .map_err(|e| anyhow!("{e}"))?;
        chart
            .configure_mesh()
            .x_desc("simulated seconds per wall second (log)")
            .y_desc("contacts missed per thousand (audit)")
            .label_style(("sans-serif", 16))
            .draw()
            .map_err(|e| anyhow!("{e}"))?;
        let choices =
            (rows.iter()).map(|&(r, m)| ((r.sim_seconds_per_s, m), r.pareto, r.choice.clone()));
        choices_and_frontier(area, &mut chart, choices.collect())
    })
}

/// Each choice's point, labelled (red on the Pareto frontier, blue off it), the frontier
/// joined by a red line, and the legend: the part both plots share.
fn choices_and_frontier<'a, Y>(
    area: &DrawingArea<BitMapBackend<'a>, plotters::coord::Shift>,
    chart: &mut ChartContext<'a, BitMapBackend<'a>, Cartesian2d<LogCoord<f64>, Y>>,
    choices: Vec<((f64, f64), bool, String)>,
) -> anyhow::Result<()>
where
    Y: Ranged<ValueType = f64>,
{
    let mut frontier: Vec<(f64, f64)> = (choices.iter())
        .filter(|(_, on, _)| *on)
        .map(|(point, _, _)| *point)
        .collect();
    frontier.sort_by(|a, b| a.0.total_cmp(&b.0));
    chart
        .draw_series(LineSeries::new(frontier, RED.stroke_width(2)))
        .map_err(|e| anyhow!("{e}"))?
        .label("Pareto frontier")
        .legend(|(x, y)| PathElement::new([(x, y), (x + 16, y)], RED.stroke_width(2)));
    let points: Vec<(f64, f64)> = choices.iter().map(|(point, _, _)| *point).collect();
    let on: Vec<bool> = choices.iter().map(|(_, on, _)| *on).collect();
    let names: Vec<String> = choices.into_iter().map(|(_, _, name)| name).collect();
    points_with_labels(area, chart, &points, (&on, &names))?;
    legend(chart, SeriesLabelPosition::UpperRight)
}
