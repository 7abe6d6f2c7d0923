//! What the benchmarks' plots share: a canvas drawn with plotters into memory and written as
//! PNG atomically, log axes, legends and labelled points; each benchmark draws its own
//! figures with them. Text uses DejaVu Sans, compiled in (the `dejavu` crate): nothing
//! depends on the system's fonts.

use std::path::Path;
use std::sync::Once;

use anyhow::anyhow;
use image::ImageEncoder;
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::{FontStyle, register_font};

use crate::files::write_atomically;

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
pub(crate) fn png(
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
pub(crate) fn log_range(
    values: impl IntoIterator<Item = f64>,
    also: &[f64],
) -> std::ops::Range<f64> {
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
pub(crate) fn legend<'a, DB: DrawingBackend + 'a, CT: CoordTranslate>(
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

/// Each of `points` on `chart` (red where `frontier` says, else blue), with its name of
/// `names` beside it where the names do not overlap (see [`place_labels`]).
pub(crate) fn points_with_labels<'a, X, Y>(
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
    let extents = names
        .iter()
        .map(|n| label_extent(n))
        .collect::<Result<Vec<_>, _>>()?;
    for (at, name) in place_labels(&pixels, &extents, bounds)
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

/// A label's ink relative to where it is drawn: left, top, right and bottom, in pixels.
pub type Extent = (i32, i32, i32, i32);

/// Where `label`, written in the plots' labels' font at (0, 0), puts ink: found by drawing it
/// (the font's layout box leaves out the ascenders above the anchor and the descenders).
pub fn label_extent(label: &str) -> anyhow::Result<Extent> {
    font();
    let size = LABEL_SIZE as i32;
    let (w, h) = ((label.chars().count() as i32 + 2) * size, 4 * size);
    let origin = (size, 2 * size);
    let mut rgb = vec![255u8; (w * h * 3) as usize];
    {
        let area = BitMapBackend::with_buffer(&mut rgb, (w as u32, h as u32)).into_drawing_area();
        area.draw(&Text::new(
            label.to_owned(),
            origin,
            ("sans-serif", LABEL_SIZE),
        ))
        .map_err(|e| anyhow!("measuring the label {label:?}: {e}"))?;
    }
    let mut ink = (i32::MAX, i32::MAX, i32::MIN, i32::MIN);
    for (i, px) in rgb.chunks_exact(3).enumerate() {
        if px != [255, 255, 255] {
            let (x, y) = (i as i32 % w, i as i32 / w);
            ink = (
                ink.0.min(x),
                ink.1.min(y),
                ink.2.max(x + 1),
                ink.3.max(y + 1),
            );
        }
    }
    Ok(match ink.0 <= ink.2 {
        true => (
            ink.0 - origin.0,
            ink.1 - origin.1,
            ink.2 - origin.0,
            ink.3 - origin.1,
        ),
        false => (0, 0, 0, 0),
    })
}

/// Where to draw each label (see [`label_extent`]: `extents`, its ink around that place)
/// beside its point of `points`, its ink inside `bounds` (left, top, right, bottom): of the
/// places around the point (beside it, in rows stacked a few deep, or above or below it),
/// nearest first, the first whose ink overlaps no label placed before and no point, else the
/// one that overlaps least.
pub fn place_labels(
    points: &[(i32, i32)],
    extents: &[Extent],
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
        .zip(extents)
        .map(|(&(x, y), &extent)| {
            let (w, h) = (extent.2 - extent.0, extent.3 - extent.1);
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
            // Drawn where its ink's corner lands there.
            (best.0 - extent.0, best.1 - extent.1)
        })
        .collect()
}
