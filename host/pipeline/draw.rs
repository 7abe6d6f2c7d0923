//! The renderers' device work: the kernel renderer's frame of the world drawn on the device
//! by `gpuwars_kernels::render` (the camera kernel first, so that the view follows the ship
//! without the host waiting), read back, hashed and written as a PNG; and the vertices and
//! the radar image the GL renderer draws.

use std::path::Path;

use gpuwars_kernels::render::camera::{self, CameraArgs, CameraState, Lens};
use gpuwars_kernels::render::particles::{ParticleSplatArgs, ParticleVertexArgs};
use gpuwars_kernels::render::radar::{self, RadarArgs, RadarBox, RadarCounts, RadarImageArgs};
use gpuwars_kernels::render::{
    BodyVertex, LARGE_LANES, Look, ResolveArgs, Shown, SplatArgs, VertexArgs,
};
use gpuwars_kernels::{DevSlice, registry};
use xxhash_rust::xxh3::xxh3_64;

use super::{Pipeline, op};
use crate::files::FileError;
use crate::{Buffer, Error, Op};

/// Largest image side, in pixels.
pub const MAX_SIDE: u32 = 16384;

/// The kernel renderer's device buffers: the camera between frames, the frame's
/// [`Shown`], the radar's counts and image, and the keys and pixels of frames of one size.
pub(super) struct Canvas {
    width: u32,
    height: u32,
    keys: Buffer<u32>,
    image: Buffer<u32>,
    looks: Buffer<Look>,
    camera: Buffer<CameraState>,
    shown: Buffer<Shown>,
    counts: Buffer<u32>,
    top: Buffer<u32>,
    radar_image: Buffer<u32>,
    /// The slots of the bodies too large for one thread, and how many (see
    /// `gpuwars_kernels::render::splat_large`).
    large: Buffer<u32>,
    large_count: Buffer<u32>,
}

/// Most threads the large bodies' launch has: a warp each for a thousand bodies at once,
/// more than a frame shows close up.
const LARGE_THREADS: u32 = 32 * 1024;

/// Pixels of the largest radar's inside.
const RADAR_CELLS: usize = (radar::MAX_SIDE * radar::MAX_SIDE) as usize;
/// Pixels of the largest radar's box (its frame included).
const RADAR_BOX: usize = ((radar::MAX_SIDE + 2) * (radar::MAX_SIDE + 2)) as usize;

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

/// Checks what `lens` asks for, naming the problem and the allowed range.
fn check_lens(lens: &Lens) -> Result<(), Error> {
    let (width, height) = (lens.width, lens.height);
    if !(1..=MAX_SIDE).contains(&width) || !(1..=MAX_SIDE).contains(&height) {
        return Err(Error::Invalid(format!(
            "a frame of {width}x{height} pixels (allowed 1 to {MAX_SIDE} on each side)"
        )));
    }
    if !(lens.zoom.is_finite() && lens.zoom > 0.0) {
        return Err(Error::Invalid(format!(
            "a zoom of {} (allowed: a finite number above 0)",
            lens.zoom
        )));
    }
    if !(lens.dt.is_finite() && lens.dt >= 0.0) {
        return Err(Error::Invalid(format!(
            "a frame time of {} s (allowed: a finite number from 0)",
            lens.dt
        )));
    }
    if lens.mode != camera::FOLLOW && lens.mode != camera::FIELD {
        return Err(Error::Invalid(format!(
            "camera mode {} (allowed {} to follow, {} for the field)",
            lens.mode,
            camera::FOLLOW,
            camera::FIELD
        )));
    }
    Ok(())
}

impl Pipeline<'_> {
    /// The ship's slot, for [`Lens::ship`]: [`camera::NO_SHIP`] in a world without a game.
    pub fn ship(&self) -> u32 {
        self.game
            .as_ref()
            .map_or(camera::NO_SHIP, |g| g.config.rules.ship.start)
    }

    /// Draws every live body as the camera of `lens` shows the world, each kind as `looks`
    /// says (one look per kind), with the kernel renderer, and reads the frame back. Waits
    /// for the steps queued before.
    pub fn draw(&mut self, lens: &Lens, looks: &[Look]) -> Result<Frame, Error> {
        self.render(lens, looks)?;
        self.frame()
    }

    /// The last frame rendered, read back (waits for it).
    pub fn frame(&self) -> Result<Frame, Error> {
        let canvas = self.canvas()?;
        Ok(Frame {
            width: canvas.width,
            height: canvas.height,
            pixels: self.device.download(&canvas.image)?,
        })
    }

    /// What the last frame drawn (or the last vertices written) showed, as the camera
    /// kernel decided it (waits for it).
    pub fn shown(&self) -> Result<Shown, Error> {
        Ok(self.device.download(&self.canvas()?.shown)?[0])
    }

    /// The radar's pixels after the last vertices written (see [`Pipeline::write_vertices`]),
    /// row-major from the top-left corner of `radar` (the box of that frame); this clears
    /// the radar's counts. Waits for them.
    pub fn radar_image(&self, radar: RadarBox) -> Result<Vec<u32>, Error> {
        let canvas = self.canvas()?;
        // SAFETY: the canvas's radar image holds the largest radar's box, and only this
        // launch touches it until `download` has waited for it.
        unsafe { self.radar_into(canvas.radar_image.view()) }?;
        let mut pixels = self.device.download(&canvas.radar_image)?;
        pixels.truncate((radar.width * radar.height) as usize);
        Ok(pixels)
    }

    /// Queues the writing of the radar's pixels after the last vertices written into
    /// `image` (row-major from its box's top-left corner), which clears the radar's counts,
    /// without waiting.
    ///
    /// # Safety
    /// `image` views memory of this pipeline's device (a GL pixel buffer mapped for CUDA, a
    /// buffer) that holds the frame's radar box and that nothing else touches until the
    /// launch completes.
    pub unsafe fn radar_into(&self, image: DevSlice<u32>) -> Result<(), Error> {
        let canvas = self.canvas()?;
        let args = RadarImageArgs {
            looks: canvas.looks.view(),
            shown: canvas.shown.view(),
            radar: canvas.radar(),
            image,
            stride: radar::stride(self.layout.slots),
            reserved: 0,
        };
        // SAFETY: the views are this pipeline's, sized as the kernel's contract asks; the
        // caller vouches for `image`; one thread per pixel of the largest box.
        let ops = unsafe { vec![op(registry::RADAR_IMAGE, RADAR_BOX as u32, args, 12)] };
        let device = self.device;
        device.run(&device.plan(ops, false)?)
    }

    fn canvas(&self) -> Result<&Canvas, Error> {
        self.canvas
            .as_ref()
            .ok_or_else(|| Error::Invalid("no frame has been rendered".into()))
    }

    /// Queues the drawing of a frame as [`Pipeline::draw`] does, and leaves it in device
    /// memory (for a display that takes it from there) without waiting.
    pub fn render(&mut self, lens: &Lens, looks: &[Look]) -> Result<(), Error> {
        // SAFETY: no outside image.
        unsafe { self.render_to(lens, looks, None) }
    }

    /// As [`Pipeline::render`], the pixels written into `image` (row-major from the top-left
    /// corner) instead of the pipeline's own frame: a GL pixel buffer mapped for CUDA, so
    /// that the frame never leaves the device.
    ///
    /// # Safety
    /// `image` views memory of this pipeline's device that holds at least `lens.width ×
    /// lens.height` pixels and that nothing else touches until the launches complete.
    pub unsafe fn render_into(
        &mut self,
        lens: &Lens,
        looks: &[Look],
        image: DevSlice<u32>,
    ) -> Result<(), Error> {
        let pixels = u64::from(lens.width) * u64::from(lens.height);
        if u64::from(image.len()) < pixels {
            return Err(Error::Invalid(format!(
                "an image of {} pixels for a {}x{} frame",
                image.len(),
                lens.width,
                lens.height
            )));
        }
        // SAFETY: forwarded; `resolve_pixels` writes one pixel per thread of the frame.
        unsafe { self.render_to(lens, looks, Some(image.range(0, pixels as u32))) }
    }

    /// Checks `lens` and `looks`, makes or resizes the canvas, writes the looks, and
    /// returns the frame's first ops: the camera, then the radar's counts.
    fn prepare(&mut self, lens: &Lens, looks: &[Look]) -> Result<Vec<Op>, Error> {
        check_lens(lens)?;
        let kinds = self.spec.kinds.len();
        if looks.len() != kinds {
            return Err(Error::Invalid(format!(
                "{} looks for a world of {kinds} kinds",
                looks.len()
            )));
        }
        let device = self.device;
        let (width, height) = (lens.width, lens.height);
        let pixels = width as usize * height as usize;
        match &mut self.canvas {
            Some(c) if (c.width, c.height) == (width, height) => {}
            Some(c) => {
                // The camera's state outlives a change of size.
                (c.width, c.height) = (width, height);
                c.keys = device.alloc_zeroed(pixels)?;
                c.image = device.alloc_zeroed(pixels)?;
            }
            None => {
                self.canvas = Some(Canvas {
                    width,
                    height,
                    keys: device.alloc_zeroed(pixels)?,
                    image: device.alloc_zeroed(pixels)?,
                    looks: device.alloc_zeroed(kinds)?,
                    camera: device.alloc_zeroed(1)?,
                    shown: device.alloc_zeroed(1)?,
                    counts: device.alloc_zeroed(RADAR_CELLS)?,
                    top: device.alloc_zeroed(RADAR_CELLS)?,
                    radar_image: device.alloc_zeroed(RADAR_BOX)?,
                    large: device.alloc_zeroed(self.layout.slots as usize)?,
                    large_count: device.alloc_zeroed(1)?,
                })
            }
        }
        let canvas = self.canvas.as_mut().expect("made above");
        device.write(&mut canvas.looks, looks)?;
        let bodies = self.state.bodies();
        let camera = CameraArgs {
            bodies,
            input: self
                .game
                .as_ref()
                .map_or(DevSlice::EMPTY, |g| g.input.view()),
            state: canvas.camera.view(),
            shown: canvas.shown.view(),
            lens: *lens,
        };
        let stride = radar::stride(self.layout.slots);
        let radar = RadarArgs {
            bodies,
            looks: canvas.looks.view(),
            shown: canvas.shown.view(),
            radar: canvas.radar(),
            stride,
            reserved: 0,
        };
        // SAFETY: the views are of this pipeline's buffers, sized for the world's slots,
        // one camera state and one `Shown`, and the largest radar; the ops run (and are
        // dropped) before the caller's borrow ends.
        Ok(unsafe {
            let mut ops = vec![op(registry::CAMERA, 1, camera, 64)];
            // A frame without a radar (the whole field) has nothing to count.
            if lens.radar != 0 {
                let samples = self.layout.slots.div_ceil(stride);
                ops.push(op(registry::RADAR_BODIES, samples, radar, 24));
            }
            ops
        })
    }

    /// # Safety
    /// As for [`Pipeline::render_into`], for `image` when given.
    unsafe fn render_to(
        &mut self,
        lens: &Lens,
        looks: &[Look],
        image: Option<DevSlice<u32>>,
    ) -> Result<(), Error> {
        let mut ops = self.prepare(lens, looks)?;
        let canvas = self.canvas.as_ref().expect("made by prepare");
        let splat = SplatArgs {
            bodies: self.state.bodies(),
            kinds: self.state.kinds.view(),
            looks: canvas.looks.view(),
            shown: canvas.shown.view(),
            keys: canvas.keys.view(),
            large: canvas.large.view(),
            large_count: canvas.large_count.view(),
        };
        let resolve = ResolveArgs {
            looks: canvas.looks.view(),
            keys: canvas.keys.view(),
            image: image.unwrap_or_else(|| canvas.image.view()),
            shown: canvas.shown.view(),
            radar: canvas.radar(),
            stride: radar::stride(self.layout.slots),
            reserved: 0,
        };
        let pixels = lens.width * lens.height;
        // SAFETY: the views are of this pipeline's buffers (or the caller's image), sized
        // for the world's slots and the frame's pixels, and the ops run (and are dropped)
        // before this borrow ends.
        unsafe {
            ops.push(Op::clear(canvas.large_count.view()));
            ops.push(op(registry::SPLAT_BODIES, self.layout.slots, splat, 64));
            let large = (self.layout.slots * LARGE_LANES).min(LARGE_THREADS);
            ops.push(op(registry::SPLAT_LARGE, large, splat, 0));
            if let Some((particles, lifetime)) = self.particle_view() {
                let args = ParticleSplatArgs {
                    particles,
                    shown: canvas.shown.view(),
                    keys: canvas.keys.view(),
                    lifetime,
                    reserved: 0,
                };
                ops.push(op(registry::SPLAT_PARTICLES, particles.len(), args, 24));
            }
            ops.push(op(registry::RESOLVE_PIXELS, pixels, resolve, 12));
        }
        let device = self.device;
        device.run(&device.plan(ops, false)?)
    }
}

impl Canvas {
    /// Views of the radar's counts.
    fn radar(&self) -> RadarCounts {
        RadarCounts {
            counts: self.counts.view(),
            top: self.top.view(),
        }
    }
}

impl Pipeline<'_> {
    /// The number of vertices [`Pipeline::write_vertices`] writes: one per slot, the
    /// backdrop's, and one per explosion particle.
    pub fn vertex_count(&self) -> u32 {
        let particles = self.particle_view().map_or(0, |(p, _)| p.len());
        self.layout.slots + 1 + particles
    }

    /// Queues, after the steps queued before and without waiting: the camera of `lens`,
    /// the radar's counts, and every slot's vertex in its view, each kind as `looks` says,
    /// then the backdrop's and every particle's (see [`Pipeline::vertex_count`]).
    /// The radar's pixels follow with [`Pipeline::radar_image`] or
    /// [`Pipeline::radar_into`].
    ///
    /// # Safety
    /// `vertices` views memory of this pipeline's device (a mapped GL buffer, a buffer)
    /// that holds at least [`Pipeline::vertex_count`] vertices and that nothing else
    /// touches until the launches complete.
    pub unsafe fn write_vertices(
        &mut self,
        lens: &Lens,
        looks: &[Look],
        vertices: DevSlice<BodyVertex>,
    ) -> Result<(), Error> {
        let (slots, count) = (self.layout.slots, self.vertex_count());
        if vertices.len() < count {
            return Err(Error::Invalid(format!(
                "a vertex buffer of {} vertices for {count} (of {slots} slots)",
                vertices.len(),
            )));
        }
        let mut ops = self.prepare(lens, looks)?;
        let canvas = self.canvas.as_ref().expect("made by prepare");
        let args = VertexArgs {
            bodies: self.state.bodies(),
            kinds: self.state.kinds.view(),
            looks: canvas.looks.view(),
            shown: canvas.shown.view(),
            vertices: vertices.range(0, slots + 1),
        };
        // SAFETY: the body and particle views are this pipeline's; the caller vouches for
        // `vertices`, which holds them all (checked above).
        unsafe {
            ops.push(op(registry::WRITE_VERTICES, slots + 1, args, 40));
            if let Some((particles, lifetime)) = self.particle_view() {
                let args = ParticleVertexArgs {
                    particles,
                    shown: canvas.shown.view(),
                    vertices: vertices.range(slots + 1, particles.len()),
                    lifetime,
                    reserved: 0,
                };
                ops.push(op(
                    registry::WRITE_PARTICLE_VERTICES,
                    particles.len(),
                    args,
                    60,
                ));
            }
        }
        let device = self.device;
        device.run(&device.plan(ops, false)?)
    }

    /// Every slot's vertex, written into `vertices` (a buffer of this pipeline's device),
    /// as [`Pipeline::write_vertices`] writes them.
    pub fn vertices_into(
        &mut self,
        lens: &Lens,
        looks: &[Look],
        vertices: &mut Buffer<BodyVertex>,
    ) -> Result<(), Error> {
        // SAFETY: the buffer is borrowed mutably for the launch, which `run` completes on
        // the CPU and orders before any later use of the buffer on the GPU's one stream.
        unsafe { self.write_vertices(lens, looks, vertices.view()) }
    }
}
