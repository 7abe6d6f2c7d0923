//! The renderers' device work: the kernel renderer's frame of the world drawn on the device
//! by `gpuwars_kernels::render` (the camera kernel first, so that the view follows the ship
//! without the host waiting), read back, hashed and written as a PNG; and the vertices and
//! the radar image the GL renderer draws.

use std::path::Path;

use gpuwars_kernels::render::camera::{self, CameraArgs, CameraState, Lens};
use gpuwars_kernels::render::particles::{ParticleSplatArgs, ParticleVertexArgs};
use gpuwars_kernels::render::radar::{
    self, RadarArgs, RadarBox, RadarCounts, RadarCountsAccess, RadarImageArgs,
};
use gpuwars_kernels::render::{
    self, BodyVertex, FirstSplatArgs, LARGE_LANES, Look, NO_SHIP, ResolveArgs, Shown, SplatArgs,
    VertexArgs,
};
use gpuwars_kernels::{DevSlice, registry};
use xxhash_rust::xxh3::xxh3_64;

use super::Pipeline;
use super::still::{Source, Still};
use crate::backend::{Binder, Buffers, Plan};
use crate::files::FileError;
use crate::primitives::threads;
use crate::sim::state::made;
use crate::{Buffer, Device, Error, Op};

/// Largest image side, in pixels.
pub const MAX_SIDE: u32 = 16384;

gpuwars_kernels::device_data! {
    /// The kernel renderer's device buffers that outlive a frame's size: the looks, the
    /// camera between frames, the frame's [`Shown`], the radar's counts and image, and the
    /// bodies too large for one thread.
    pub struct CanvasData(kinds, slots): CanvasDataAccess {
        /// Each kind's look.
        looks: [Look; kinds],
        /// The camera between frames, and after the frame being drawn (see
        /// `gpuwars_kernels::render::FirstSplatArgs::camera`).
        camera: [CameraState; 2],
        /// What the last frame showed.
        shown: [Shown; 1],
        /// The radar's pixels, its frame included.
        radar_image: [u32; RADAR_BOX],
        /// The slots of the bodies too large for one thread (see
        /// `gpuwars_kernels::render::splat_large`).
        large: [u32; slots],
        /// How many of them.
        large_count: [u32; 1],
    } nested {
        /// The radar's per-pixel counts.
        radar: RadarCounts(RADAR_CELLS): RadarCountsAccess,
    }
}

gpuwars_kernels::device_data! {
    /// A frame's pixels, made again when its size changes.
    pub struct FramePixels(pixels): FramePixelsAccess {
        /// Each pixel's depth key of the splats.
        keys: [u32; pixels],
        /// The frame's colours.
        image: [u32; pixels],
    }
}

/// The kernel renderer's device buffers, for frames of one size.
pub(super) struct Canvas {
    width: u32,
    height: u32,
    data: CanvasData<Buffers>,
    pixels: FramePixels<Buffers>,
    /// The looks last written to the device, so that they travel only when they change.
    looks: Vec<Look>,
    /// The last frame's arguments, and its plan.
    last: Option<KeptFrames<1>>,
    /// What frames drawn beside the step read, made by the first of them.
    pub(super) still: Option<Still>,
    /// The lens of the last frame drawn beside the step, and the plans of such frames:
    /// one beside a step that does not renumber, one beside a step that does (see
    /// `super::beside`).
    pub(super) beside: Option<KeptFrames<2>>,
}

/// What a frame's launches take that can change from one frame to the next: the lens (in
/// the camera's arguments) and the image written (its address and length; none for the
/// canvas's own). Everything else they take (the world's and the canvas's buffers) lasts
/// as long as the canvas. Frames of a constant lens (a benchmark, a headless run, a window
/// whose frame time is steady) replay one graph; a lens that changes every frame runs its
/// launches one by one, as recording a graph for one replay would cost more than it saves.
#[derive(Clone, Copy, PartialEq)]
pub(super) struct FrameKey {
    lens: [u32; std::mem::size_of::<Lens>() / 4],
    image: Option<(u64, u32)>,
}

impl FrameKey {
    /// The key of a frame of `lens` into `image` (the canvas's own if none).
    pub(super) fn of(lens: &Lens, image: Option<DevSlice<u32>>) -> FrameKey {
        FrameKey {
            lens: bytemuck::cast(*lens),
            image: image.map(|image| (image.addr(), image.len())),
        }
    }
}

/// The plans of the frames of the last [`FrameKey`], kept from frame to frame: `N` of
/// them, for frames of one key whose launches differ otherwise (beside a step that
/// renumbers and one that does not). A key that comes twice in a row has its plans made as
/// CUDA graphs and kept; the first frame of a key runs its launches one by one.
pub(super) struct KeptFrames<const N: usize> {
    key: FrameKey,
    plans: [Option<Plan>; N],
}

impl<const N: usize> KeptFrames<N> {
    /// Runs plan `index` of a frame of `key` on `device`: the one in `kept` if `kept` is of
    /// `key`, else the one `make` makes, told whether to make a graph. Returns what to keep
    /// for the next frame (nothing where `make` failed) and how the run went.
    pub(super) fn run(
        kept: Option<Self>,
        key: FrameKey,
        index: usize,
        device: &Device,
        make: impl FnOnce(bool) -> Result<Plan, Error>,
    ) -> (Option<Self>, Result<(), Error>) {
        let (again, mut plans) = match kept {
            Some(kept) if kept.key == key => (true, kept.plans),
            _ => (false, std::array::from_fn(|_| None)),
        };
        let plan = match plans[index].take() {
            Some(plan) => plan,
            None => match make(again) {
                Ok(plan) => plan,
                Err(e) => return (None, Err(e)),
            },
        };
        let ran = device.run(&plan);
        if again {
            plans[index] = Some(plan);
        }
        (Some(Self { key, plans }), ran)
    }
}

/// Most threads the large bodies' launch has: a group of threads each for a thousand
/// bodies at once, more than a frame shows close up.
const LARGE_THREADS: u32 = LARGE_LANES * 1024;

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
    /// The ship's slot, for [`Lens::ship`]: [`NO_SHIP`] in a world without a game.
    pub fn ship(&self) -> u32 {
        (self.world.game.as_ref()).map_or(NO_SHIP, |g| g.config.rules.ship.start)
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
            pixels: self.device.download(&canvas.pixels.image)?,
        })
    }

    /// What the last frame drawn (or the last vertices written) showed, as the camera
    /// kernel decided it (waits for it).
    pub fn shown(&self) -> Result<Shown, Error> {
        Ok(self.device.download(&self.canvas()?.data.shown)?[0])
    }

    /// The radar's pixels after the last vertices written (see [`Pipeline::write_vertices`]),
    /// row-major from the top-left corner of `radar` (the box of that frame); this clears
    /// the radar's counts. Waits for them.
    pub fn radar_image(&self, radar: RadarBox) -> Result<Vec<u32>, Error> {
        let canvas = self.canvas()?;
        // SAFETY: the view goes into this op only.
        let mut b = unsafe { Binder::new() };
        let image = b.view(&canvas.data.radar_image);
        // SAFETY: the canvas's radar image holds the largest radar's box.
        self.device.launch(unsafe { self.radar_op(image, b) }?)?;
        let mut pixels = self.device.download(&canvas.data.radar_image)?;
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
        // SAFETY: the binder's views go into this op only; the caller vouches for `image`.
        let op = unsafe { self.radar_op(image, Binder::new()) }?;
        self.device.launch(op)
    }

    /// The launch that writes the radar's pixels into `image`, its views made by `b`.
    ///
    /// # Safety
    /// `image` was made by `b`, or is memory as [`Pipeline::radar_into`] asks.
    unsafe fn radar_op(&self, image: DevSlice<u32>, mut b: Binder) -> Result<Op, Error> {
        let canvas = self.canvas()?;
        let args = RadarImageArgs {
            looks: b.view(&canvas.data.looks),
            shown: b.view(&canvas.data.shown),
            radar: made(canvas.data.radar.convert(&mut b)),
            image,
            stride: radar::stride(self.world.layout.slots),
            reserved: 0,
        };
        // SAFETY: the canvas's buffers, sized as the kernel asks; the caller vouches for
        // `image`; one thread per pixel of the largest box.
        Ok(unsafe {
            threads(
                registry::RADAR_IMAGE,
                RADAR_BOX as u32,
                args,
                b,
                12 * u64::from(RADAR_BOX as u32),
            )
        })
    }

    pub(super) fn canvas(&self) -> Result<&Canvas, Error> {
        self.canvas
            .as_ref()
            .ok_or_else(|| Error::Invalid("no frame has been rendered".into()))
    }

    /// The canvas, once [`Pipeline::ready`] made it.
    pub(super) fn canvas_mut(&mut self) -> &mut Canvas {
        self.canvas.as_mut().expect("made ready")
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
        // SAFETY: forwarded; `resolve_pixels` writes the frame's pixels, and no others.
        unsafe { self.render_to(lens, looks, Some(image.range(0, pixels as u32))) }
    }

    /// Checks `lens` and `looks`, makes or resizes the canvas, and writes the looks if they
    /// changed.
    pub(super) fn ready(&mut self, lens: &Lens, looks: &[Look]) -> Result<(), Error> {
        check_lens(lens)?;
        let kinds = self.world.spec.kinds.len();
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
                c.pixels = FramePixels::build(&mut device.zeroed(), pixels)?;
                (c.last, c.beside) = (None, None);
            }
            None => {
                let slots = self.world.layout.slots as usize;
                self.canvas = Some(Canvas {
                    width,
                    height,
                    data: CanvasData::build(&mut device.zeroed(), kinds, slots)?,
                    pixels: FramePixels::build(&mut device.zeroed(), pixels)?,
                    looks: Vec::new(),
                    last: None,
                    still: None,
                    beside: None,
                })
            }
        }
        let canvas = self.canvas.as_mut().expect("made above");
        if canvas.looks != looks {
            device.write(&mut canvas.data.looks, looks)?;
            canvas.looks = looks.to_vec();
        }
        Ok(())
    }

    /// The camera's own launch (see `gpuwars_kernels::render::camera::camera`), once the
    /// canvas is ready.
    fn camera_op(&self, lens: &Lens, source: Source) -> Op {
        let canvas = self.canvas.as_ref().expect("made ready");
        // SAFETY: the views go into the op made with the binder.
        let mut b = unsafe { Binder::new() };
        let camera = CameraArgs {
            bodies: self.drawn_bodies(source, &mut b),
            input: self.drawn_input(source, &mut b),
            state: b.view(&canvas.data.camera),
            shown: b.view(&canvas.data.shown),
            lens: *lens,
        };
        // SAFETY: the world's and the canvas's buffers, sized for the world's slots, two
        // camera states and one `Shown`.
        unsafe { threads(registry::CAMERA, 1, camera, b, 64) }
    }

    /// The first ops of a frame of vertices, once the canvas is ready: the camera, then the
    /// radar's counts (the kernel renderer's first launch counts them itself).
    fn vertex_camera_ops(&self, lens: &Lens) -> Vec<Op> {
        let canvas = self.canvas.as_ref().expect("made ready");
        let (world, slots) = (&self.world, self.world.layout.slots);
        let mut ops = vec![self.camera_op(lens, Source::World)];
        // A frame without a radar (the whole field) has nothing to count.
        if lens.radar != 0 {
            let stride = radar::stride(slots);
            // SAFETY: the views go into the op below only.
            let mut b = unsafe { Binder::new() };
            let radar = RadarArgs {
                bodies: world.state.bodies(&mut b),
                looks: b.view(&canvas.data.looks),
                shown: b.view(&canvas.data.shown),
                radar: made(canvas.data.radar.convert(&mut b)),
                stride,
                reserved: 0,
            };
            let samples = slots.div_ceil(stride);
            // SAFETY: the views go into this op only; the world's and the canvas's buffers,
            // sized for the world's slots and the largest radar.
            ops.push(unsafe {
                threads(
                    registry::RADAR_BODIES,
                    samples,
                    radar,
                    b,
                    24 * u64::from(samples),
                )
            });
        }
        ops
    }

    /// # Safety
    /// As for [`Pipeline::render_into`], for `image` when given.
    unsafe fn render_to(
        &mut self,
        lens: &Lens,
        looks: &[Look],
        image: Option<DevSlice<u32>>,
    ) -> Result<(), Error> {
        let key = FrameKey::of(lens, image);
        self.ready(lens, looks)?;
        let device = self.device;
        let kept = self.canvas_mut().last.take();
        let (kept, ran) = KeptFrames::run(kept, key, 0, device, |graph| {
            // SAFETY: forwarded from the caller.
            let ops = unsafe { self.frame_ops(lens, image, Source::World) };
            device.plan(ops, graph)
        });
        self.canvas_mut().last = kept;
        ran
    }

    /// A frame's launches: the splats (the first with the camera and the radar's counts)
    /// and the resolve, into `image` if given, of the world as `source` holds it.
    ///
    /// # Safety
    /// As for [`Pipeline::render_into`], for `image` when given.
    pub(super) unsafe fn frame_ops(
        &self,
        lens: &Lens,
        image: Option<DevSlice<u32>>,
        source: Source,
    ) -> Vec<Op> {
        let mut ops = Vec::new();
        let canvas = self.canvas.as_ref().expect("made ready");
        let (world, slots) = (&self.world, self.world.layout.slots);
        let splat = |b: &mut Binder| SplatArgs {
            bodies: self.drawn_bodies(source, b),
            kinds: b.view(&world.state.tables.info),
            looks: b.view(&canvas.data.looks),
            shown: b.view(&canvas.data.shown),
            keys: b.view(&canvas.pixels.keys),
            large: b.view(&canvas.data.large),
            large_count: b.view(&canvas.data.large_count),
        };
        // SAFETY (every binder below): the views go into the op made with it. (Every op
        // below): the world's and the canvas's buffers, sized for the world's slots and the
        // frame's pixels, or the caller's image (see `render_into`).
        unsafe {
            // A large world's threads would cost more working the camera out each than a
            // launch of its own does.
            let camera_ready = slots > render::FOLD_CAMERA_SLOTS;
            if camera_ready {
                ops.push(self.camera_op(lens, source));
            }
            let mut b = Binder::new();
            let args = FirstSplatArgs {
                splat: splat(&mut b),
                input: self.drawn_input(source, &mut b),
                camera: b.view(&canvas.data.camera),
                radar: made(canvas.data.radar.convert(&mut b)),
                lens: *lens,
                stride: radar::stride(slots),
                camera_ready: u32::from(camera_ready),
            };
            // Thread 0 writes the camera, whatever the world's size.
            let threads_first = slots.max(1);
            ops.push(threads(
                registry::SPLAT_BODIES,
                threads_first,
                args,
                b,
                64 * u64::from(threads_first),
            ));
            let large = (slots * LARGE_LANES).min(LARGE_THREADS);
            let mut b = Binder::new();
            let args = splat(&mut b);
            ops.push(threads(registry::SPLAT_LARGE, large, args, b, 0));
            let mut b = Binder::new();
            if let Some((particles, lifetime)) = self.drawn_particles(source, &mut b) {
                let args = ParticleSplatArgs {
                    particles,
                    shown: b.view(&canvas.data.shown),
                    keys: b.view(&canvas.pixels.keys),
                    lifetime,
                    reserved: 0,
                };
                ops.push(threads(
                    registry::SPLAT_PARTICLES,
                    particles.len(),
                    args,
                    b,
                    24 * u64::from(particles.len()),
                ));
            }
            let mut b = Binder::new();
            let resolve = ResolveArgs {
                looks: b.view(&canvas.data.looks),
                keys: b.view(&canvas.pixels.keys),
                image: image.unwrap_or_else(|| b.view(&canvas.pixels.image)),
                shown: b.view(&canvas.data.shown),
                radar: made(canvas.data.radar.convert(&mut b)),
                camera: b.view(&canvas.data.camera),
                large_count: b.view(&canvas.data.large_count),
                stride: radar::stride(slots),
                reserved: 0,
            };
            let pixels = lens.width * lens.height;
            ops.push(threads(
                registry::RESOLVE_PIXELS,
                render::resolve_threads(pixels),
                resolve,
                b,
                12 * u64::from(pixels),
            ));
        }
        ops
    }
}

impl Pipeline<'_> {
    /// The number of vertices [`Pipeline::write_vertices`] writes: one per slot, the
    /// backdrop's, and one per explosion particle.
    pub fn vertex_count(&self) -> u32 {
        let particles = self.world.game.as_ref().and_then(|g| g.effects.as_ref());
        let particles = particles.map_or(0, |(_, burst)| burst.particles());
        self.world.layout.slots + 1 + particles
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
        // SAFETY: forwarded.
        unsafe { self.vertices_to(lens, looks, Vertices::Mapped(vertices)) }
    }

    /// [`Pipeline::write_vertices`] into a mapped view or a buffer.
    ///
    /// # Safety
    /// As for [`Pipeline::write_vertices`], for a mapped view.
    unsafe fn vertices_to(
        &mut self,
        lens: &Lens,
        looks: &[Look],
        target: Vertices<'_>,
    ) -> Result<(), Error> {
        let (slots, count) = (self.world.layout.slots, self.vertex_count());
        let len = match target {
            Vertices::Mapped(view) => view.len(),
            Vertices::Buffer(buffer) => buffer.len() as u32,
        };
        // Each op views a buffer through its own binder, which holds it.
        let vertices = |b: &mut Binder| match target {
            Vertices::Mapped(view) => view,
            Vertices::Buffer(buffer) => b.view(buffer),
        };
        if len < count {
            return Err(Error::Invalid(format!(
                "a vertex buffer of {len} vertices for {count} (of {slots} slots)",
            )));
        }
        self.ready(lens, looks)?;
        let mut ops = self.vertex_camera_ops(lens);
        let (canvas, world) = (self.canvas.as_ref().expect("made ready"), &self.world);
        // SAFETY (both binders): the views go into the op made with each. (Both ops): the
        // world's and the canvas's buffers; the caller vouches for `vertices`, which holds
        // them all (checked above).
        unsafe {
            let mut b = Binder::new();
            let args = VertexArgs {
                bodies: world.state.bodies(&mut b),
                kinds: b.view(&world.state.tables.info),
                looks: b.view(&canvas.data.looks),
                shown: b.view(&canvas.data.shown),
                vertices: vertices(&mut b).range(0, slots + 1),
            };
            ops.push(threads(
                registry::WRITE_VERTICES,
                slots + 1,
                args,
                b,
                40 * u64::from(slots + 1),
            ));
            let mut b = Binder::new();
            if let Some((particles, lifetime)) = world.particles(&mut b) {
                let args = ParticleVertexArgs {
                    particles,
                    shown: b.view(&canvas.data.shown),
                    vertices: vertices(&mut b).range(slots + 1, particles.len()),
                    lifetime,
                    reserved: 0,
                };
                let n = particles.len();
                ops.push(threads(
                    registry::WRITE_PARTICLE_VERTICES,
                    n,
                    args,
                    b,
                    60 * u64::from(n),
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
        // SAFETY: a buffer, viewed by each op's binder.
        unsafe { self.vertices_to(lens, looks, Vertices::Buffer(vertices)) }
    }
}

/// Where vertices are written: memory mapped from OpenGL, or a buffer.
#[derive(Clone, Copy)]
enum Vertices<'a> {
    Mapped(DevSlice<BodyVertex>),
    Buffer(&'a Buffer<BodyVertex>),
}

/// A world's drawing without its step: the frames, vertices and radar of
/// [`Pipeline`]'s drawing methods, and every `&self` method of the pipeline (through
/// `Deref`), but not [`Pipeline::step`]. What a game lends to whatever draws it
/// ([`crate::game::Game::drawing`]), so that nothing that draws can step the world past
/// the game's ring of steps in flight:
/// ```compile_fail,E0596
/// fn step_past_the_ring(game: &mut gpuwars::game::Game) {
///     game.drawing().step().unwrap();
/// }
/// ```
pub struct Drawing<'p, 'd> {
    pipeline: &'p mut Pipeline<'d>,
}

impl<'d> std::ops::Deref for Drawing<'_, 'd> {
    type Target = Pipeline<'d>;

    fn deref(&self) -> &Pipeline<'d> {
        self.pipeline
    }
}

impl<'d> Pipeline<'d> {
    /// The pipeline's drawing, for as long as it is borrowed.
    pub fn drawing(&mut self) -> Drawing<'_, 'd> {
        Drawing { pipeline: self }
    }
}

impl Drawing<'_, '_> {
    /// See [`Pipeline::draw`].
    pub fn draw(&mut self, lens: &Lens, looks: &[Look]) -> Result<Frame, Error> {
        self.pipeline.draw(lens, looks)
    }

    /// See [`Pipeline::render`].
    pub fn render(&mut self, lens: &Lens, looks: &[Look]) -> Result<(), Error> {
        self.pipeline.render(lens, looks)
    }

    /// See [`Pipeline::render_into`].
    ///
    /// # Safety
    /// As for [`Pipeline::render_into`].
    pub unsafe fn render_into(
        &mut self,
        lens: &Lens,
        looks: &[Look],
        image: DevSlice<u32>,
    ) -> Result<(), Error> {
        // SAFETY: forwarded.
        unsafe { self.pipeline.render_into(lens, looks, image) }
    }

    /// See [`Pipeline::write_vertices`].
    ///
    /// # Safety
    /// As for [`Pipeline::write_vertices`].
    pub unsafe fn write_vertices(
        &mut self,
        lens: &Lens,
        looks: &[Look],
        vertices: DevSlice<BodyVertex>,
    ) -> Result<(), Error> {
        // SAFETY: forwarded.
        unsafe { self.pipeline.write_vertices(lens, looks, vertices) }
    }

    /// See [`Pipeline::vertices_into`].
    pub fn vertices_into(
        &mut self,
        lens: &Lens,
        looks: &[Look],
        vertices: &mut Buffer<BodyVertex>,
    ) -> Result<(), Error> {
        self.pipeline.vertices_into(lens, looks, vertices)
    }
}
