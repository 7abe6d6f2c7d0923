//! The HUD's text: lines drawn with the public-domain 8×8 bitmap font compiled into the
//! `font8x8` crate (nothing is fetched at run time), on a translucent backdrop.

use font8x8::{BASIC_FONTS, UnicodeFonts};

use crate::pipeline::Frame;

/// Pixels of a glyph cell's side before scaling.
const CELL: u32 = 8;
/// Backdrop behind the text: dark and see-through.
const BACKDROP: u32 = u32::from_le_bytes([0, 0, 0, 150]);
/// Blank pixels around the text.
const MARGIN: u32 = 4;

/// `lines` drawn in `colour` (RGBA8 packed little-endian) with each font pixel `scale`
/// pixels wide, on the backdrop; characters outside the font show as `?`.
pub fn text_image(lines: &[String], colour: u32, scale: u32) -> Frame {
    let scale = scale.max(1);
    let columns = lines.iter().map(|l| l.chars().count()).max().unwrap_or(0) as u32;
    let width = columns * CELL * scale + 2 * MARGIN;
    let height = lines.len() as u32 * (CELL + 2) * scale + 2 * MARGIN;
    let mut pixels = vec![BACKDROP; (width * height) as usize];
    for (row, line) in lines.iter().enumerate() {
        let top = MARGIN + row as u32 * (CELL + 2) * scale;
        for (column, c) in line.chars().enumerate() {
            let glyph = BASIC_FONTS.get(c).or_else(|| BASIC_FONTS.get('?'));
            let Some(glyph) = glyph else { continue };
            let left = MARGIN + column as u32 * CELL * scale;
            for (gy, bits) in glyph.iter().enumerate() {
                for gx in 0..CELL {
                    if bits >> gx & 1 == 0 {
                        continue;
                    }
                    for dy in 0..scale {
                        let y = top + gy as u32 * scale + dy;
                        let start = (y * width + left + gx * scale) as usize;
                        pixels[start..start + scale as usize].fill(colour);
                    }
                }
            }
        }
    }
    Frame {
        width,
        height,
        pixels,
    }
}
