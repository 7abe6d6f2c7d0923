//! CUDA–OpenGL interop (paper, section 5): a GL vertex buffer registered with the CUDA
//! context once, then each frame mapped, written by a kernel and unmapped, so the bodies
//! never travel through the host.
//!
//! cudarc has the generic graphics calls but not `cuGraphicsGLRegisterBuffer` (it lives in
//! `cudaGL.h`): that one symbol is loaded from the driver library with `libloading`.

use std::ffi::c_uint;
use std::sync::{Arc, OnceLock};

use cudarc::driver::{CudaContext, CudaStream, sys};
use gpuwars_kernels::DevSlice;

use super::cuda::{InFlight, Order};
use super::{Device, Element, Error, Imp};

/// `CU_GRAPHICS_REGISTER_FLAGS_WRITE_DISCARD`: CUDA overwrites the whole buffer each time.
const WRITE_DISCARD: c_uint = 2;

type RegisterBuffer =
    unsafe extern "C" fn(*mut sys::CUgraphicsResource, c_uint, c_uint) -> sys::CUresult;

/// `cuGraphicsGLRegisterBuffer`, loaded once (with the library that holds it, kept open).
fn register_buffer() -> Result<RegisterBuffer, Error> {
    static LOADED: OnceLock<Result<(libloading::Library, RegisterBuffer), String>> =
        OnceLock::new();
    let loaded = LOADED.get_or_init(|| {
        // SAFETY: the NVIDIA driver library, already loaded by cudarc: its initialisers have
        // run, and the symbol's type is the one `cudaGL.h` declares.
        unsafe {
            let library =
                libloading::Library::new(super::CUDA_LIBRARY).map_err(|e| e.to_string())?;
            let symbol = *library
                .get::<RegisterBuffer>(b"cuGraphicsGLRegisterBuffer\0")
                .map_err(|e| e.to_string())?;
            Ok((library, symbol))
        }
    });
    match loaded {
        Ok((_, symbol)) => Ok(*symbol),
        Err(e) => Err(Error::CudaUnavailable(format!(
            "cuGraphicsGLRegisterBuffer could not be loaded: {e}"
        ))),
    }
}

/// Turns a driver status into a result.
fn check(in_flight: &InFlight, status: sys::CUresult, during: &str) -> Result<(), Error> {
    status.result().map_err(in_flight.failed(during))
}

/// A GL buffer object registered with the GPU's context. Kernels write it between a map
/// and an unmap queued on the device's stream, so they see the steps queued before; each
/// holds the device's order, as every other queued call does, so that neither lands
/// between another thread's fork and join or inside its capture.
pub struct GlBuffer {
    resource: sys::CUgraphicsResource,
    ctx: Arc<CudaContext>,
    stream: Arc<CudaStream>,
    order: Order,
    in_flight: Arc<InFlight>,
}

impl Device {
    /// Registers the GL buffer object `id` for kernels to write. The GL context that owns
    /// it must be current on this thread and be the NVIDIA driver's (a Mesa context cannot
    /// be registered). The CUDA backend only.
    pub fn register_gl_buffer(&self, id: u32) -> Result<GlBuffer, Error> {
        let Imp::Cuda(gpu) = &self.imp else {
            return Err(Error::Invalid(
                "GL buffers are registered only with the CUDA backend".into(),
            ));
        };
        let (ctx, stream, order, in_flight) = gpu.raw_access();
        ctx.bind_to_thread()
            .map_err(in_flight.failed("binding the context"))?;
        let register = register_buffer()?;
        let mut resource = std::ptr::null_mut();
        // SAFETY: `resource` is a valid out-pointer; GL reports a bad id as an error.
        check(
            &in_flight,
            unsafe { register(&mut resource, id, WRITE_DISCARD) },
            "registering the GL vertex buffer with CUDA",
        )?;
        Ok(GlBuffer {
            resource,
            ctx,
            stream,
            order,
            in_flight,
        })
    }
}

impl GlBuffer {
    /// Maps the buffer, lends its memory to `write` as a slice of `T` (for launches on the
    /// same device), and unmaps it; GL draws see what the launches wrote.
    ///
    /// # Safety
    /// `write` uses the view only as an argument of launches it queues on this device (see
    /// [`super::Op::launch`]), and keeps no copy of it: after the unmap the address means
    /// nothing.
    pub unsafe fn with_mapped<T: Element, R>(
        &mut self,
        write: impl FnOnce(DevSlice<T>) -> Result<R, Error>,
    ) -> Result<R, Error> {
        let stream = self.stream.cu_stream();
        // SAFETY: a registered resource, mapped and unmapped on the device's stream; the
        // pointer is used only by launches queued before the unmap.
        unsafe {
            // The order for the map and for the unmap, not between: the launches `write`
            // queues take it themselves.
            let map = {
                let _order = self.order.hold();
                sys::cuGraphicsMapResources(1, &mut self.resource, stream)
            };
            check(&self.in_flight, map, "mapping the GL vertex buffer")?;
            let mut addr = 0;
            let mut bytes = 0usize;
            let mapped = check(
                &self.in_flight,
                sys::cuGraphicsResourceGetMappedPointer_v2(&mut addr, &mut bytes, self.resource),
                "taking the mapped GL vertex buffer's address",
            );
            let len = u32::try_from(bytes / size_of::<T>()).unwrap_or(u32::MAX);
            let written = mapped.and_then(|()| write(DevSlice::from_raw_parts(addr, len)));
            let unmap = {
                let _order = self.order.hold();
                sys::cuGraphicsUnmapResources(1, &mut self.resource, stream)
            };
            let unmapped = check(&self.in_flight, unmap, "unmapping the GL vertex buffer");
            let result = written?;
            unmapped.map(|()| result)
        }
    }
}

impl Drop for GlBuffer {
    fn drop(&mut self) {
        let _ = self.ctx.bind_to_thread();
        // SAFETY: registered in `register_gl_buffer`, not mapped outside `with_mapped`.
        let _ = unsafe { sys::cuGraphicsUnregisterResource(self.resource) };
    }
}
