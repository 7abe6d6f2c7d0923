//! The benchmarks' plots, drawn with plotters into memory and written as PNG atomically.
//! Text uses DejaVu Sans, compiled in (the `dejavu` crate): nothing depends on the system's
//! fonts.

use std::path::Path;
use std::sync::Once;

use anyhow::anyhow;
use image::ImageEncoder;
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::{FontStyle, register_font};

use super::paper::{PAPER_BANDS, PaperSummary};
use super::scale::{ScaleRow, ScaleSummary};
use super::tradeoff::{PhysicsRow as TradeoffRow, TradeoffSummary};
use crate::files::write_atomically;
use crate::meter::Second;

/// Width and height of every plot.
const SIZE: (u32, u32) = (1280, 720);

/// Registers the plots' font once.
fn font() {
    static REGISTER: Once = Once::new();
    REGISTER.call_once(|| {
        // The font is a valid TrueType file compiled into the `dejavu` crate.
        let _ = register_font("sans-serif", FontStyle::Normal, dejavu::sans::regular());
    });
}

/// Draws with `draw` onto a white canvas and writes it to `path` as a PNG.
fn png(
    path: &Path,
    draw: impl FnOnce(&DrawingArea<BitMapBackend, Shift>) -> anyhow::Result<()>,
) -> anyhow::Result<()> {
    font();
    let (w, h) = SIZE;
    let mut rgb = vec![0u8; (w * h * 3) as usize];
    {
        let area = BitMapBackend::with_buffer(&mut rgb, SIZE).into_drawing_area();
        area.fill(&WHITE).map_err(|e| anyhow!("{e}"))?;
        draw(&area)?;
        area.present().map_err(|e| anyhow!("{e}"))?;
    }
    let mut bytes = Vec::new();
    image::codecs::png::PngEncoder::new(&mut bytes).write_image(
        &rgb,
        w,
        h,
        image::ExtendedColorType::Rgb8,
    )?;
    Ok(write_atomically(path, &bytes)?)
}

/// A range `[low, high]` for a log axis that holds `values` and `also`, with some margin.
fn log_range(values: impl IntoIterator<Item = f64>, also: &[f64]) -> std::ops::Range<f64> {
    let all: Vec<f64> = values
        .into_iter()
        .chain(also.iter().copied())
        .filter(|v| v.is_finite() && *v > 0.0)
        .collect();
    let low = all.iter().copied().fold(f64::INFINITY, f64::min);
    let high = all.iter().copied().fold(0.0, f64::max);
    if all.is_empty() {
        return 1.0..10.0;
    }
    low / 1.5..high * 1.5
}

/// The legend of `chart`'s labelled series, at `position`.
fn legend<'a, DB: DrawingBackend + 'a, CT: CoordTranslate>(
    chart: &mut ChartContext<'a, DB, CT>,
    position: SeriesLabelPosition,
) -> anyhow::Result<()> {
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font(("sans-serif", 16))
        .position(position)
        .draw()
        .map_err(|e| anyhow!("{e}"))
}

/// Figure 8 of the paper, redrawn: frames per second against time (log scale), with the
/// paper's two cards as bands.
pub fn frames_over_time(
    path: &Path,
    summary: &PaperSummary,
    rows: &[Second],
) -> anyhow::Result<()> {
    png(path, |area| {
        let bands: Vec<f64> = PAPER_BANDS
            .iter()
            .flat_map(|&(_, lo, hi)| [lo, hi])
            .collect();
        let y = log_range(rows.iter().map(|r| r.frames_per_s), &bands);
        let x_end = rows.len().max(1) as f64;
        let title = format!(
            "paper: frames/s, one step per frame, {} renderer {}x{} ({}, {})",
            summary.renderer.name(),
            summary.size.0,
            summary.size.1,
            summary.machine.device,
            summary.machine.backend
        );
        let mut chart = ChartBuilder::on(area)
            .caption(title, ("sans-serif", 22))
            .margin(16)
            .x_label_area_size(48)
            .y_label_area_size(80)
            .build_cartesian_2d(0.0..x_end, y.log_scale())
            .map_err(|e| anyhow!("{e}"))?;
        chart
            .configure_mesh()
            .x_desc("time (s)")
            .y_desc("frames per second (log)")
            .label_style(("sans-serif", 16))
            .draw()
            .map_err(|e| anyhow!("{e}"))?;
        let colours = [RGBColor(230, 140, 60), RGBColor(90, 160, 90)];
        for (&(name, lo, hi), colour) in PAPER_BANDS.iter().zip(colours) {
            chart
                .draw_series([Rectangle::new(
                    [(0.0, lo), (x_end, hi)],
                    colour.mix(0.3).filled(),
                )])
                .map_err(|e| anyhow!("{e}"))?
                .label(format!("{name}: {lo:.0}–{hi:.0}"))
                .legend(move |(x, y)| {
                    Rectangle::new([(x, y - 6), (x + 16, y + 6)], colour.filled())
                });
        }
        chart
            .draw_series(LineSeries::new(
                rows.iter().map(|r| (f64::from(r.second), r.frames_per_s)),
                BLUE.stroke_width(2),
            ))
            .map_err(|e| anyhow!("{e}"))?
            .label(format!(
                "this run: median {:.0} frames/s",
                summary.frames_per_s.median
            ))
            .legend(|(x, y)| PathElement::new([(x, y), (x + 16, y)], BLUE.stroke_width(2)));
        legend(&mut chart, SeriesLabelPosition::LowerRight)?;
        Ok(())
    })
}

/// One figure of a scale row.
type Figure = fn(&ScaleRow) -> f64;

/// Steps per second and frames per second against enemies, log-log.
pub fn scaling(path: &Path, summary: &ScaleSummary) -> anyhow::Result<()> {
    png(path, |area| {
        let rows = &summary.rows;
        let x_low = rows.first().map_or(1024.0, |r| r.enemies as f64);
        let x_high = rows
            .last()
            .map_or(2048.0, |r| r.enemies as f64)
            .max(x_low * 2.0);
        let y = log_range(
            rows.iter().flat_map(|r| [r.steps_per_s, r.frames_per_s]),
            &[],
        );
        let title = format!(
            "scaling: the paper's mix and density ({}, {})",
            summary.machine.device, summary.machine.backend
        );
        let mut chart = ChartBuilder::on(area)
            .caption(title, ("sans-serif", 22))
            .margin(16)
            .x_label_area_size(48)
            .y_label_area_size(80)
            .build_cartesian_2d((x_low / 1.2..x_high * 1.2).log_scale(), y.log_scale())
            .map_err(|e| anyhow!("{e}"))?;
        chart
            .configure_mesh()
            .x_desc("enemies (log)")
            .y_desc("per second (log)")
            .label_style(("sans-serif", 16))
            .draw()
            .map_err(|e| anyhow!("{e}"))?;
        let series: [(&str, RGBColor, Figure); 2] = [
            ("simulation steps/s", BLUE, |r| r.steps_per_s),
            (
                "frames/s (a step and a kernel-rendered frame each)",
                RED,
                |r| r.frames_per_s,
            ),
        ];
        for (name, colour, value) in series {
            let points: Vec<(f64, f64)> =
                rows.iter().map(|r| (r.enemies as f64, value(r))).collect();
            chart
                .draw_series(LineSeries::new(points.clone(), colour.stroke_width(2)))
                .map_err(|e| anyhow!("{e}"))?
                .label(name)
                .legend(move |(x, y)| {
                    PathElement::new([(x, y), (x + 16, y)], colour.stroke_width(2))
                });
            chart
                .draw_series(
                    points
                        .into_iter()
                        .map(|p| Circle::new(p, 4, colour.filled())),
                )
                .map_err(|e| anyhow!("{e}"))?;
        }
        legend(&mut chart, SeriesLabelPosition::UpperRight)?;
        Ok(())
    })
}

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
        let error = |r: &TradeoffRow| r.position_rms.max(floor);
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
        let mut frontier: Vec<(f64, f64)> = rows
            .iter()
            .filter(|r| r.pareto)
            .map(|r| (r.sim_seconds_per_s, error(r)))
            .collect();
        frontier.sort_by(|a, b| a.0.total_cmp(&b.0));
        chart
            .draw_series(LineSeries::new(frontier, RED.stroke_width(2)))
            .map_err(|e| anyhow!("{e}"))?
            .label("Pareto frontier")
            .legend(|(x, y)| PathElement::new([(x, y), (x + 16, y)], RED.stroke_width(2)));
        let points: Vec<(f64, f64)> = rows
            .iter()
            .map(|r| (r.sim_seconds_per_s, error(r)))
            .collect();
        let frontier: Vec<bool> = rows.iter().map(|r| r.pareto).collect();
        let names: Vec<String> = rows.iter().map(|r| r.choice.clone()).collect();
        points_with_labels(area, &mut chart, &points, (&frontier, &names))?;
        legend(&mut chart, SeriesLabelPosition::UpperRight)?;
        Ok(())
    })
}

/// Each of `points` on `chart` (red where `frontier` says, else blue), with its name of
/// `names` beside it where the names do not overlap (see [`place_labels`]).
fn points_with_labels<'a, X, Y>(
    area: &DrawingArea<BitMapBackend<'a>, Shift>,
    chart: &mut ChartContext<'a, BitMapBackend<'a>, Cartesian2d<X, Y>>,
    points: &[(X::ValueType, Y::ValueType)],
    (frontier, names): (&[bool], &[String]),
) -> anyhow::Result<()>
where
    X: Ranged,
    Y: Ranged,
    X::ValueType: Clone + 'static,
    Y::ValueType: Clone + 'static,
{
    for (p, on_frontier) in points.iter().zip(frontier) {
        let colour = if *on_frontier { RED } else { BLUE };
        chart
            .draw_series([Circle::new(p.clone(), 5, colour.filled())])
            .map_err(|e| anyhow!("{e}"))?;
    }
    let pixels: Vec<(i32, i32)> = points.iter().map(|p| chart.backend_coord(p)).collect();
    let bounds = chart.plotting_area().get_pixel_range();
    let bounds = (bounds.0.start, bounds.1.start, bounds.0.end, bounds.1.end);
    for (at, name) in place_labels(&pixels, names, LABEL_SIZE, bounds)
        .into_iter()
        .zip(names)
    {
        area.draw(&Text::new(name.clone(), at, ("sans-serif", LABEL_SIZE)))
            .map_err(|e| anyhow!("{e}"))?;
    }
    Ok(())
}

/// Height in pixels of the points' names.
const LABEL_SIZE: u32 = 14;

/// Rows of names stacked above and below a point's own beside it (see [`place_labels`]).
const STACKED: i32 = 4;

/// Where to write each of `labels` (its top-left corner, in pixels) beside its point of
/// `points`, inside `bounds` (left, top, right, bottom): of the places around the point
/// (beside it, in rows stacked a few deep, or above or below it), nearest
/// first, the first that overlaps no label placed before and no point, else the one that
/// overlaps least. Widths are estimated from the character count (a proportional
/// font's average), so the check is conservative, not exact.
pub fn place_labels(
    points: &[(i32, i32)],
    labels: &[String],
    size: u32,
    bounds: (i32, i32, i32, i32),
) -> Vec<(i32, i32)> {
    type Rect = (i32, i32, i32, i32);
    let overlap = |a: Rect, b: Rect| {
        let w = (a.2.min(b.2) - a.0.max(b.0)).max(0);
        let h = (a.3.min(b.3) - a.1.max(b.1)).max(0);
        i64::from(w) * i64::from(h)
    };
    let dots: Vec<Rect> = points
        .iter()
        .map(|&(x, y)| (x - 6, y - 6, x + 6, y + 6))
        .collect();
    let mut placed: Vec<Rect> = Vec::new();
    points
        .iter()
        .zip(labels)
        .map(|(&(x, y), label)| {
            let h = size as i32;
            let w = (label.chars().count() as f32 * size as f32 * 0.6).ceil() as i32;
            let gap = 8;
            // Beside the point, left or right, in rows stacked up and down from its own
            // height, nearest first; above and below it after the first rows.
            let row = |k: i32| y - h / 2 + k * (h + 2);
            let mut candidates = vec![(x + gap, row(0)), (x - gap - w, row(0))];
            candidates.extend([(x - w / 2, y - gap - h), (x - w / 2, y + gap)]);
            for k in 1..=STACKED {
                for k in [-k, k] {
                    candidates.extend([(x + gap, row(k)), (x - gap - w, row(k))]);
                }
            }
            let cost = |&(cx, cy): &(i32, i32)| {
                let r = (cx, cy, cx + w, cy + h);
                let outside = i64::from(w) * i64::from(h) - overlap(r, bounds);
                let others: i64 = placed.iter().chain(&dots).map(|&o| overlap(r, o)).sum();
                // Leaving the plot is worse than covering another label.
                others + 4 * outside
            };
            let best = candidates
                .iter()
                .copied()
                .min_by_key(cost)
                .expect("a place to try");
            placed.push((best.0, best.1, best.0 + w, best.1 + h));
            best
        })
        .collect()
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
        let mut frontier: Vec<(f64, f64)> = (rows.iter())
            .filter(|(r, _)| r.pareto)
            .map(|&(r, m)| (r.sim_seconds_per_s, m))
            .collect();
        frontier.sort_by(|a, b| a.0.total_cmp(&b.0));
        chart
            .draw_series(LineSeries::new(frontier, RED.stroke_width(2)))
            .map_err(|e| anyhow!("{e}"))?
            .label("Pareto frontier")
            .legend(|(x, y)| PathElement::new([(x, y), (x + 16, y)], RED.stroke_width(2)));
        let points: Vec<(f64, f64)> = (rows.iter())
            .map(|&(r, m)| (r.sim_seconds_per_s, m))
            .collect();
        let on: Vec<bool> = rows.iter().map(|(r, _)| r.pareto).collect();
        let names: Vec<String> = rows.iter().map(|(r, _)| r.choice.clone()).collect();
        points_with_labels(area, &mut chart, &points, (&on, &names))?;
        legend(&mut chart, SeriesLabelPosition::UpperRight)?;
        Ok(())
    })
}
