//! The renderers' device work: the kernel renderer's frame of the world drawn on the device
//! by `gpuwars_kernels::render`, read back, hashed and written as a PNG; and the vertices
//! the GL renderer draws.

use std::path::Path;

use gpuwars_kernels::render::{BodyVertex, Look, ResolveArgs, SplatArgs, VertexArgs, View};
use gpuwars_kernels::{DevSlice, registry};
use xxhash_rust::xxh3::xxh3_64;

use super::{Pipeline, op};
use crate::files::FileError;
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

    /// Writes the frame as a PNG, atomically and only where a file may be written (see
    /// [`crate::files::write_atomically`]).
    pub fn save_png(&self, path: &Path) -> Result<(), FileError> {
        use image::ImageEncoder;
        let mut png = Vec::new();
        image::codecs::png::PngEncoder::new(&mut png)
            .write_image(
                bytemuck::cast_slice(&self.pixels),
                self.width,
                self.height,
                image::ExtendedColorType::Rgba8,
            )
            .map_err(|e| {
                let problem = format!("cannot encode the frame as PNG: {e}");
                FileError::new(&path.display().to_string(), None, "", problem)
            })?;
        crate::files::write_atomically(path, &png)
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
        // SAFETY: no outside image.
        unsafe { self.render_to(view, looks, None) }
    }

    /// As [`Pipeline::render`], the pixels written into `image` (row-major from the top-left
    /// corner) instead of the pipeline's own frame: a GL pixel buffer mapped for CUDA, so
    /// that the frame never leaves the device.
    ///
    /// # Safety
    /// `image` views memory of this pipeline's device that holds at least `view.width ×
    /// view.height` pixels and that nothing else touches until the launches complete.
    pub unsafe fn render_into(
        &mut self,
        view: &View,
        looks: &[Look],
        image: DevSlice<u32>,
    ) -> Result<(), Error> {
        let pixels = u64::from(view.width) * u64::from(view.height);
        if u64::from(image.len()) < pixels {
            return Err(Error::Invalid(format!(
                "an image of {} pixels for a {}x{} frame",
                image.len(),
                view.width,
                view.height
            )));
        }
        // SAFETY: forwarded; `resolve_pixels` writes one pixel per thread of the frame.
        unsafe { self.render_to(view, looks, Some(image.range(0, pixels as u32))) }
    }

    /// # Safety
    /// As for [`Pipeline::render_into`], for `image` when given.
    unsafe fn render_to(
        &mut self,
        view: &View,
        looks: &[Look],
        image: Option<DevSlice<u32>>,
    ) -> Result<(), Error> {
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
            image: image.unwrap_or_else(|| canvas.image.view()),
            background: view.background,
            reserved: 0,
        };
        // SAFETY: the views are of this pipeline's buffers (or the caller's image), sized
        // for the world's slots and the frame's pixels, and the ops run (and are dropped)
        // before this borrow ends.
        let ops = unsafe {
            vec![
                op(registry::SPLAT_BODIES, self.layout.slots, splat, 64),
                op(registry::RESOLVE_PIXELS, width * height, resolve, 12),
            ]
        };
        device.run(&device.plan(ops, false)?)
    }
}

impl Pipeline<'_> {
    /// The number of vertices [`Pipeline::write_vertices`] writes: one per slot.
    pub fn vertex_count(&self) -> u32 {
        self.layout.slots
    }

    /// Queues the writing of every slot's vertex after the steps queued before, without
    /// waiting.
    ///
    /// # Safety
    /// `vertices` views memory of this pipeline's device (a mapped GL buffer, a buffer)
    /// that holds at least [`Pipeline::vertex_count`] vertices and that nothing else
    /// touches until the launch completes.
    pub unsafe fn write_vertices(&self, vertices: DevSlice<BodyVertex>) -> Result<(), Error> {
        if vertices.len() < self.layout.slots {
            return Err(Error::Invalid(format!(
                "a vertex buffer of {} vertices for {} slots",
                vertices.len(),
                self.layout.slots
            )));
        }
        let args = VertexArgs {
            bodies: self.state.bodies(),
            kinds: self.state.kinds.view(),
            vertices,
        };
        let device = self.device;
        // SAFETY: the body views are this pipeline's; the caller vouches for `vertices`.
        let ops = unsafe { vec![op(registry::WRITE_VERTICES, self.layout.slots, args, 24)] };
        device.run(&device.plan(ops, false)?)
    }

    /// Every slot's vertex, written into `vertices` (a buffer of this pipeline's device).
    pub fn vertices_into(&self, vertices: &mut Buffer<BodyVertex>) -> Result<(), Error> {
        // SAFETY: the buffer is borrowed mutably for the launch, which `run` completes on
        // the CPU and orders before any later use of the buffer on the GPU's one stream.
        unsafe { self.write_vertices(vertices.view()) }
    }
}
