//! The kernel renderer's host half: a frame of the world drawn on the device by
//! `gpuwars_kernels::render`, read back, hashed and written as a PNG.

use std::path::Path;

use gpuwars_kernels::registry;
use gpuwars_kernels::render::{Look, ResolveArgs, SplatArgs, View};
use xxhash_rust::xxh3::xxh3_64;

use super::{Pipeline, op};
use crate::{Buffer, Error};

/// Largest image side, in pixels.
pub const MAX_SIDE: u32 = 16384;

/// The device buffers of frames of one size.
pub(super) struct Canvas {
    width: u32,
    height: u32,
    keys: Buffer<u32>,
    image: Buffer<u32>,
    looks: Buffer<Look>,
}

/// A drawn frame: RGBA8 pixels, row-major from the top-left corner.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Frame {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// One RGBA8 colour per pixel, packed little-endian (red in the low byte).
    pub pixels: Vec<u32>,
}

impl Frame {
    /// The colour of pixel `(x, y)`.
    pub fn pixel(&self, x: u32, y: u32) -> u32 {
        self.pixels[(y * self.width + x) as usize]
    }

    /// XXH3-64 of the pixels: equal only if two frames agree pixel for pixel.
    pub fn hash(&self) -> u64 {
        xxh3_64(bytemuck::cast_slice(&self.pixels))
    }

    /// Writes the frame as a PNG, atomically: a temporary file beside `path`, renamed over
    /// it once complete.
    pub fn save_png(&self, path: &Path) -> Result<(), std::io::Error> {
        let dir = match path.parent() {
            Some(dir) if !dir.as_os_str().is_empty() => dir,
            _ => Path::new("."),
        };
        let file = tempfile::Builder::new()
            .prefix(".gpuwars-frame")
            .suffix(".png")
            .tempfile_in(dir)?;
        image::save_buffer_with_format(
            file.path(),
            bytemuck::cast_slice(&self.pixels),
            self.width,
            self.height,
            image::ExtendedColorType::Rgba8,
            image::ImageFormat::Png,
        )
        .map_err(std::io::Error::other)?;
        file.persist(path).map_err(|e| e.error)?;
        Ok(())
    }
}

impl Pipeline<'_> {
    /// Draws every live body as `view` shows the world, each kind as `looks` says (one look
    /// per kind), with the kernel renderer, and reads the frame back. Waits for the steps
    /// queued before.
    pub fn draw(&mut self, view: &View, looks: &[Look]) -> Result<Frame, Error> {
        self.render(view, looks)?;
        self.frame()
    }

    /// The last frame rendered, read back (waits for it).
    pub(crate) fn frame(&self) -> Result<Frame, Error> {
        let canvas = self
            .canvas
            .as_ref()
            .ok_or_else(|| Error::Invalid("no frame has been rendered".into()))?;
        Ok(Frame {
            width: canvas.width,
            height: canvas.height,
            pixels: self.device.download(&canvas.image)?,
        })
    }

    /// Queues the drawing of a frame as [`Pipeline::draw`] does, and leaves it in device
    /// memory (for a display that takes it from there) without waiting.
    pub fn render(&mut self, view: &View, looks: &[Look]) -> Result<(), Error> {
        let (width, height) = (view.width, view.height);
        if !(1..=MAX_SIDE).contains(&width) || !(1..=MAX_SIDE).contains(&height) {
            return Err(Error::Invalid(format!(
                "a frame of {width}x{height} pixels (allowed 1 to {MAX_SIDE} on each side)"
            )));
        }
        if !(view.scale.is_finite() && view.scale > 0.0 && view.origin.is_finite()) {
            return Err(Error::Invalid(format!(
                "a view at {} with {} pixels per unit (allowed: finite, scale above 0)",
                view.origin, view.scale
            )));
        }
        let kinds = self.spec.kinds.len();
        if looks.len() != kinds {
            return Err(Error::Invalid(format!(
                "{} looks for a world of {kinds} kinds",
                looks.len()
            )));
        }
        let device = self.device;
        let fits = self
            .canvas
            .as_ref()
            .is_some_and(|c| (c.width, c.height) == (width, height));
        if !fits {
            let pixels = width as usize * height as usize;
            self.canvas = Some(Canvas {
                width,
                height,
                keys: device.alloc_zeroed(pixels)?,
                image: device.alloc_zeroed(pixels)?,
                looks: device.alloc_zeroed(kinds)?,
            });
        }
        let canvas = self.canvas.as_mut().expect("made above");
        device.write(&mut canvas.looks, looks)?;
        let splat = SplatArgs {
            bodies: self.state.bodies(),
            kinds: self.state.kinds.view(),
            looks: canvas.looks.view(),
            view: *view,
            keys: canvas.keys.view(),
        };
        let resolve = ResolveArgs {
            looks: canvas.looks.view(),
            keys: canvas.keys.view(),
            image: canvas.image.view(),
            background: view.background,
            reserved: 0,
        };
        // SAFETY: the views are of this pipeline's buffers, sized for the world's slots and
        // the frame's pixels, and the ops run (and are dropped) before this borrow ends.
        let ops = unsafe {
            vec![
                op(registry::SPLAT_BODIES, self.layout.slots, splat, 64),
                op(registry::RESOLVE_PIXELS, width * height, resolve, 12),
            ]
        };
        device.run(&device.plan(ops, false)?)
    }
}
