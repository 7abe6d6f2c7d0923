//! The CUDA backend: the kernels' PTX loaded into the first GPU through the driver API.
//!
//! `cudarc` loads libcuda at run time, so the binary starts without the NVIDIA driver; opening
//! this backend then fails with [`Error::CudaUnavailable`] and a reason, never a panic.

use std::collections::HashMap;
use std::sync::Arc;

use cudarc::driver::{
    CudaContext, CudaFunction, CudaSlice, CudaStream, DevicePtr, DeviceRepr, DriverError,
    LaunchConfig, PushKernelArg, sys,
};
use cudarc::nvrtc::Ptx;
use gpuwars_kernels::{Kernel, KernelArgs, registry};
use serde::Serialize;

use super::{Element, Error};
use crate::ptx;

/// What the driver reports about the GPU.
#[derive(Clone, Debug, Serialize)]
pub struct GpuProperties {
    /// Marketing name, e.g. "NVIDIA H200".
    pub name: String,
    /// Compute capability as "major.minor".
    pub compute_capability: String,
    /// Global memory in bytes.
    pub memory_bytes: u64,
    /// Multiprocessors.
    pub multiprocessors: u32,
    /// Driver's CUDA version, e.g. "13.0".
    pub driver_cuda_version: String,
}

/// An open GPU: context, stream and every kernel of the module.
pub(super) struct Gpu {
    stream: Arc<CudaStream>,
    functions: HashMap<&'static str, CudaFunction>,
    properties: GpuProperties,
}

/// The kernel's argument struct as its single by-value parameter.
#[repr(transparent)]
struct Param<A>(A);
// SAFETY: `KernelArgs` are repr(C) plain data, laid out as the PTX parameter expects.
unsafe impl<A: KernelArgs> DeviceRepr for Param<A> {}

fn driver(during: &str) -> impl FnOnce(DriverError) -> Error + '_ {
    move |source| Error::Driver {
        during: during.to_string(),
        source,
    }
}

fn unavailable(what: &str) -> impl FnOnce(DriverError) -> Error + '_ {
    move |e| Error::CudaUnavailable(format!("{what}: {e}"))
}

impl Gpu {
    pub(super) fn open() -> Result<Self, Error> {
        // SAFETY: only tries to dlopen libcuda.
        if !unsafe { sys::is_culib_present() } {
            return Err(Error::CudaUnavailable(
                "the NVIDIA driver library (libcuda) was not found".into(),
            ));
        }
        let count = CudaContext::device_count().map_err(unavailable("CUDA initialisation"))?;
        if count < 1 {
            return Err(Error::CudaUnavailable(
                "the NVIDIA driver reports no CUDA device".into(),
            ));
        }
        // From here on a GPU is present: a failure is an error to report, not an absence.
        let ctx = CudaContext::new(0).map_err(driver("opening CUDA device 0"))?;
        // One stream orders every launch and copy; the per-buffer events cudarc keeps for
        // multi-stream use would only cost time.
        // SAFETY: this backend never uses a second stream.
        unsafe { ctx.disable_event_tracking() };
        let module = ctx
            .load_module(Ptx::from_src(ptx::PTX))
            .map_err(driver("loading the kernels' PTX"))?;
        let mut functions = HashMap::new();
        for info in registry::ALL {
            let function = module
                .load_function(info.name)
                .map_err(driver("finding a kernel in the PTX"))?;
            functions.insert(info.name, function);
        }
        let properties = properties(&ctx).map_err(driver("querying device 0"))?;
        Ok(Gpu {
            stream: ctx.default_stream(),
            functions,
            properties,
        })
    }

    pub(super) fn properties(&self) -> &GpuProperties {
        &self.properties
    }

    // Buffers are untyped bytes here, so that any plain-data element type (including the
    // kernels' own structs) can live in device memory without cudarc's marker traits.

    pub(super) fn alloc_zeroed(&self, bytes: usize) -> Result<CudaSlice<u8>, Error> {
        self.stream
            .alloc_zeros(bytes)
            .map_err(driver("allocating device memory"))
    }

    pub(super) fn upload<T: Element>(&self, data: &[T]) -> Result<CudaSlice<u8>, Error> {
        self.stream
            .clone_htod(bytemuck::cast_slice::<T, u8>(data))
            .map_err(driver("copying to the device"))
    }

    pub(super) fn write<T: Element>(
        &self,
        dst: &mut CudaSlice<u8>,
        data: &[T],
    ) -> Result<(), Error> {
        let bytes = bytemuck::cast_slice::<T, u8>(data);
        let mut prefix = dst.slice_mut(..bytes.len());
        self.stream
            .memcpy_htod(bytes, &mut prefix)
            .map_err(driver("copying to the device"))
    }

    pub(super) fn download<T: Element>(&self, src: &CudaSlice<u8>) -> Result<Vec<T>, Error> {
        let mut out = vec![T::zeroed(); src.len() / size_of::<T>()];
        self.stream
            .memcpy_dtoh(src, bytemuck::cast_slice_mut::<T, u8>(&mut out))
            .map_err(driver("copying from the device"))?;
        Ok(out)
    }

    pub(super) fn zero(&self, dst: &mut CudaSlice<u8>) -> Result<(), Error> {
        self.stream
            .memset_zeros(dst)
            .map_err(driver("clearing device memory"))
    }

    pub(super) fn copy(&self, src: &CudaSlice<u8>, dst: &mut CudaSlice<u8>) -> Result<(), Error> {
        let mut prefix = dst.slice_mut(..src.len());
        self.stream
            .memcpy_dtod(src, &mut prefix)
            .map_err(driver("copying on the device"))
    }

    /// # Safety
    /// See [`super::Device::launch`].
    pub(super) unsafe fn launch<A: KernelArgs>(
        &self,
        kernel: Kernel<A>,
        grid: u32,
        block: u32,
        args: &A,
    ) -> Result<(), Error> {
        let function = self.functions.get(kernel.name).ok_or_else(|| {
            Error::Invalid(format!("kernel `{}` is not in the PTX module", kernel.name))
        })?;
        let config = LaunchConfig {
            grid_dim: (grid, 1, 1),
            block_dim: (block, 1, 1),
            shared_mem_bytes: 0,
        };
        let param = Param(*args);
        let mut launch = self.stream.launch_builder(function);
        launch.arg(&param);
        // SAFETY: the parameter is the kernel's argument struct; the caller vouches for the
        // buffers it views.
        unsafe { launch.launch(config) }
            .map(drop)
            .map_err(|e| Error::KernelFault {
                kernel: kernel.name,
                message: e.to_string(),
            })
    }

    pub(super) fn synchronize(&self) -> Result<(), Error> {
        self.stream
            .synchronize()
            .map_err(driver("waiting for the GPU (a kernel may have faulted)"))
    }
}

/// The device address of a buffer.
pub(super) fn address<T>(slice: &CudaSlice<T>) -> u64 {
    // Event tracking is off, so the returned guard records nothing.
    let (addr, _guard) = slice.device_ptr(slice.stream());
    addr
}

fn properties(ctx: &Arc<CudaContext>) -> Result<GpuProperties, DriverError> {
    use sys::CUdevice_attribute::*;
    let (major, minor) = ctx.compute_capability()?;
    let mut version = 0i32;
    // SAFETY: writes one int.
    unsafe { sys::cuDriverGetVersion(&mut version) }.result()?;
    Ok(GpuProperties {
        name: ctx.name()?,
        compute_capability: format!("{major}.{minor}"),
        memory_bytes: ctx.total_mem()? as u64,
        multiprocessors: ctx.attribute(CU_DEVICE_ATTRIBUTE_MULTIPROCESSOR_COUNT)? as u32,
        driver_cuda_version: format!("{}.{}", version / 1000, (version % 1000) / 10),
    })
}
