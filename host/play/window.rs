//! The window and its GL context: glutin over winit, with a config chosen here (glium's
//! own builder panics where this returns an error).

use std::num::NonZeroU32;
use std::panic::{AssertUnwindSafe, catch_unwind};

use anyhow::{Context as _, anyhow};
use glium::Display;
use glutin::config::{ConfigTemplateBuilder, GlConfig};
use glutin::context::{ContextApi, ContextAttributesBuilder, Version};
use glutin::display::{GetGlDisplay, GlDisplay};
use glutin::prelude::*;
use glutin::surface::{SwapInterval, WindowSurface};
use glutin_winit::{DisplayBuilder, GlWindow};
use raw_window_handle::HasWindowHandle;
use winit::dpi::PhysicalSize;
use winit::event_loop::ActiveEventLoop;
use winit::window::Window;

/// Opens a resizable `width × height` window titled `title`, with an OpenGL 3.3 context
/// current on it, swapping with the display's refresh when `vsync`.
pub fn open(
    event_loop: &ActiveEventLoop,
    title: &str,
    (width, height): (u32, u32),
    vsync: bool,
) -> anyhow::Result<(Window, Display<WindowSurface>)> {
    let attributes = Window::default_attributes()
        .with_title(title)
        .with_resizable(true)
        .with_inner_size(PhysicalSize::new(width, height));
    // Any config will do (the bodies are drawn offscreen with their own depth buffer): the
    // picker never sees an empty list unless the platform has no GL at all, and that panic
    // becomes an error here.
    let built = catch_unwind(AssertUnwindSafe(|| {
        DisplayBuilder::new()
            .with_window_attributes(Some(attributes))
            .build(event_loop, ConfigTemplateBuilder::new(), |configs| {
                configs
                    .max_by_key(|c| (c.alpha_size() == 8, c.num_samples() == 0))
                    .expect("no GL framebuffer config")
            })
            .map_err(|e| anyhow!("{e}"))
    }))
    .map_err(|_| anyhow!("the display offers no OpenGL framebuffer config"))?;
    let (window, config) = built.context("opening the window")?;
    let window = window.context("opening the window: no window was made")?;
    let surface_attributes = window
        .build_surface_attributes(Default::default())
        .context("describing the window's surface")?;
    let handle = window
        .window_handle()
        .context("taking the window's handle")?
        .as_raw();
    let display = config.display();
    let context_attributes = ContextAttributesBuilder::new()
        .with_context_api(ContextApi::OpenGl(Some(Version::new(3, 3))))
        .build(Some(handle));
    // SAFETY: the window outlives the surface and the context (both go with the display,
    // which the caller drops before the window).
    let (surface, context) = unsafe {
        let surface = display
            .create_window_surface(&config, &surface_attributes)
            .context("making the window's GL surface")?;
        let context = display
            .create_context(&config, &context_attributes)
            .context("making an OpenGL 3.3 context")?;
        (surface, context)
    };
    let context = context
        .make_current(&surface)
        .context("making the GL context current")?;
    let interval = if vsync {
        SwapInterval::Wait(NonZeroU32::MIN)
    } else {
        SwapInterval::DontWait
    };
    if let Err(e) = surface.set_swap_interval(&context, interval) {
        eprintln!("gpuwars: the swap interval could not be set ({e}): frames are not paced");
    }
    let display = Display::from_context_surface(context, surface)
        .map_err(|e| anyhow!("{e}"))
        .context("starting glium on the window's context")?;
    Ok((window, display))
}
