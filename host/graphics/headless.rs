//! OpenGL without a window or a display: an EGL device context made current with no
//! surface (NVIDIA's EGL device on a GPU machine, Mesa's software device elsewhere), and
//! offscreen targets that are read back as [`Frame`]s.

use std::ffi::{CString, c_void};
use std::rc::Rc;

use glium::backend::{Backend, Context, Facade};
use glium::debug::DebugCallbackBehavior;
use glium::framebuffer::{DepthRenderBuffer, SimpleFrameBuffer};
use glium::texture::{DepthFormat, MipmapsOption, RawImage2d, Texture2d, UncompressedFloatFormat};
use glutin::api::egl;
use glutin::config::{ConfigSurfaceTypes, ConfigTemplateBuilder};
use glutin::context::{ContextApi, ContextAttributesBuilder, Version};
use glutin::prelude::*;

use glium::Surface;
use gpuwars_kernels::render::camera::Lens;

use super::bodies::BodyRenderer;
use super::{gl_error, unpack};
use crate::game::Game;
use crate::pipeline::{Drawing, Frame};
use crate::{BackendKind, Error};

/// The EGL extension of NVIDIA's devices (those CUDA can share buffers with).
const NVIDIA_DEVICE: &str = "EGL_NV_device_cuda";

/// A glium backend over an EGL context current without a surface.
struct Surfaceless {
    display: egl::display::Display,
    context: egl::context::PossiblyCurrentContext,
}

// SAFETY: the proc addresses come from the context's own display, and the context is made
// current only on the thread that made it (glium's contexts are not `Send`).
unsafe impl Backend for Surfaceless {
    fn swap_buffers(&self) -> Result<(), glium::SwapBuffersError> {
        Ok(())
    }

    unsafe fn get_proc_address(&self, symbol: &str) -> *const c_void {
        CString::new(symbol).map_or(std::ptr::null(), |name| {
            self.display.get_proc_address(&name)
        })
    }

    fn get_framebuffer_dimensions(&self) -> (u32, u32) {
        // No default framebuffer: everything is drawn into offscreen targets.
        (1, 1)
    }

    fn resize(&self, _: (u32, u32)) {}

    fn is_current(&self) -> bool {
        self.context.is_current()
    }

    unsafe fn make_current(&self) {
        // Glium calls this only to restore the context it was made with, which worked then.
        let _ = self.context.make_current_surfaceless();
    }
}

/// A GL context with no window.
pub struct Headless {
    context: Rc<Context>,
    device: String,
}

impl Headless {
    /// A context on the first EGL device that makes one; an NVIDIA device first when
    /// `nvidia_first` (so that CUDA can share buffers with it).
    pub fn new(nvidia_first: bool) -> Result<Self, Error> {
        let mut devices: Vec<_> = egl::device::Device::query_devices()
            .map_err(gl_error(
                "listing the EGL devices (headless GL needs libEGL, which Windows lacks; \
                 `--render kernel` draws without GL)",
            ))?
            .collect();
        devices.sort_by_key(|d| d.extensions().contains(NVIDIA_DEVICE) != nvidia_first);
        let mut tried = Vec::new();
        for device in &devices {
            let name = device_name(device);
            match surfaceless(device) {
                Ok(backend) => {
                    // SAFETY: a new context, current on this thread, used only from it.
                    let context =
                        unsafe { Context::new(backend, false, DebugCallbackBehavior::Ignore) }
                            .map_err(gl_error("starting glium on the EGL context"))?;
                    let device = format!("{}, {name}", context.get_opengl_renderer_string());
                    return Ok(Headless { context, device });
                }
                Err(e) => tried.push(format!("{name}: {e}")),
            }
        }
        Err(Error::Graphics {
            during: "making a GL context without a window".into(),
            message: if tried.is_empty() {
                "no EGL device (install Mesa's EGL: libegl1 libegl-mesa0 libgl1-mesa-dri)".into()
            } else {
                tried.join("; ")
            },
        })
    }

    /// The GL renderer and the EGL device it runs on.
    pub fn device(&self) -> &str {
        &self.device
    }

    /// The context, for making buffers, textures and programs.
    pub fn facade(&self) -> &Rc<Context> {
        &self.context
    }

    /// A context for `game`'s device (NVIDIA's EGL device on the CUDA backend, so that
    /// interop works) and a renderer of its bodies; says once on stderr if the GPU's
    /// vertices must be uploaded.
    pub fn with_renderer(game: &Game) -> Result<(Headless, BodyRenderer), Error> {
        let device = game.pipeline().device();
        let gl = Headless::new(device.kind() == BackendKind::Cuda)?;
        let bodies = BodyRenderer::for_game(gl.facade(), game)?;
        if let Some(why) = bodies.fallback() {
            eprintln!("gpuwars: {why}: the vertices are uploaded");
        }
        Ok((gl, bodies))
    }

    /// `pipeline`'s bodies after the steps queued, drawn by `renderer` as the camera of
    /// `lens` shows the world, offscreen, and read back.
    pub fn draw(
        &self,
        renderer: &mut BodyRenderer,
        drawing: &mut Drawing,
        lens: &Lens,
    ) -> Result<Frame, Error> {
        let target = Target::new(&self.context, lens.width, lens.height)?;
        renderer.update(&self.context, drawing, lens)?;
        let mut surface = target.surface(&self.context)?;
        surface.clear_color_and_depth(unpack(lens.background), 0.0);
        renderer.draw(&mut surface, lens)?;
        Ok(target.read())
    }
}

/// What an EGL device is, in a few words.
fn device_name(device: &egl::device::Device) -> String {
    let extensions = device.extensions();
    if extensions.contains(NVIDIA_DEVICE) {
        "NVIDIA's EGL device".into()
    } else if extensions.contains("EGL_MESA_device_software") {
        "Mesa's software EGL device".into()
    } else {
        match device.name().or(device.vendor()) {
            Some(name) => format!("EGL device {name}"),
            None => "an EGL device".into(),
        }
    }
}

/// An OpenGL 3.3 context on `device`, current with no surface.
fn surfaceless(device: &egl::device::Device) -> Result<Surfaceless, glutin::error::Error> {
    // SAFETY: the device comes from EGL's own list; no native display is involved.
    let display = unsafe { egl::display::Display::with_device(device, None) }?;
    let template = ConfigTemplateBuilder::new()
        .with_surface_type(ConfigSurfaceTypes::empty())
        .build();
    // SAFETY: the template is complete.
    let config = unsafe { display.find_configs(template) }?
        .next()
        .ok_or(glutin::error::ErrorKind::NotFound)?;
    let attributes = ContextAttributesBuilder::new()
        .with_context_api(ContextApi::OpenGl(Some(Version::new(3, 3))))
        .build(None);
    // SAFETY: no window handle is involved.
    let context = unsafe { display.create_context(&config, &attributes) }?;
    let context = context.make_current_surfaceless()?;
    Ok(Surfaceless { display, context })
}

/// An offscreen colour and depth target, read back as a [`Frame`].
pub struct Target {
    colour: Texture2d,
    depth: DepthRenderBuffer,
}

impl Target {
    /// A `width × height` target.
    pub fn new(facade: &impl Facade, width: u32, height: u32) -> Result<Self, Error> {
        let colour = Texture2d::empty_with_format(
            facade,
            UncompressedFloatFormat::U8U8U8U8,
            MipmapsOption::NoMipmap,
            width,
            height,
        )
        .map_err(gl_error("making an offscreen image"))?;
        let depth = DepthRenderBuffer::new(facade, DepthFormat::I24, width, height)
            .map_err(gl_error("making an offscreen depth buffer"))?;
        Ok(Target { colour, depth })
    }

    /// The colour image (row 0 at the bottom, as GL has it).
    pub fn colour(&self) -> &Texture2d {
        &self.colour
    }

    /// The target's width and height in pixels.
    pub fn size(&self) -> (u32, u32) {
        (self.colour.width(), self.colour.height())
    }

    /// A surface that draws into the target.
    pub fn surface<'a>(&'a self, facade: &impl Facade) -> Result<SimpleFrameBuffer<'a>, Error> {
        SimpleFrameBuffer::with_depth_buffer(facade, &self.colour, &self.depth)
            .map_err(gl_error("binding the offscreen target"))
    }

    /// What was drawn, as a frame (row 0 at the top, as the kernel renderer's).
    pub fn read(&self) -> Frame {
        let image: RawImage2d<u8> = self.colour.read();
        let (width, height) = (image.width, image.height);
        let row = width as usize * 4;
        // GL's rows go up from the bottom.
        let pixels = image
            .data
            .chunks_exact(row)
            .rev()
            .flat_map(|r| {
                r.chunks_exact(4)
                    .map(|p| u32::from_le_bytes([p[0], p[1], p[2], p[3]]))
            })
            .collect();
        Frame {
            width,
            height,
            pixels,
        }
    }
}
