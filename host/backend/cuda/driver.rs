//! The driver calls cudarc's safe API does not make: launches with attributes
//! (`cuLaunchKernelEx`), a module's functions by the registry's names, the device's
//! properties.

use std::collections::HashMap;
use std::sync::Arc;

use cudarc::driver::{CudaContext, CudaFunction, CudaStream, DriverError, LaunchConfig, sys};
use cudarc::nvrtc::Ptx;
use gpuwars_kernels::{KernelArgs, KernelInfo};

use super::{GpuProperties, Param};

/// The functions `kernels` of the PTX module `source`, loaded into `ctx`.
pub(super) fn load(
    ctx: &Arc<CudaContext>,
    source: &str,
    kernels: &[KernelInfo],
) -> Result<HashMap<&'static str, CudaFunction>, DriverError> {
    let module = ctx.load_module(Ptx::from_src(source))?;
    kernels
        .iter()
        .map(|info| Ok((info.name, module.load_function(info.name)?)))
        .collect()
}

/// Programmatic stream serialization: the launch's blocks may start once every block of the
/// launch before it has signalled its dependents or ended (each entry of the sm_90 module
/// signals right after waiting for its own predecessor to finish, `griddepcontrol.wait`,
/// before touching memory). Captured into a graph, the edge from the previous kernel node
/// becomes a programmatic one. Only for the sm_90 module's kernels.
pub(super) fn dependent() -> sys::CUlaunchAttribute {
    attribute(
        sys::CUlaunchAttributeID::CU_LAUNCH_ATTRIBUTE_PROGRAMMATIC_STREAM_SERIALIZATION,
        sys::CUlaunchAttributeValue {
            programmaticStreamSerializationAllowed: 1,
        },
    )
}

/// A cooperative launch: every block resident at once, so that they may wait for one
/// another (the driver refuses a grid larger than the device holds).
pub(super) fn cooperative() -> sys::CUlaunchAttribute {
    attribute(
        sys::CUlaunchAttributeID::CU_LAUNCH_ATTRIBUTE_COOPERATIVE,
        sys::CUlaunchAttributeValue { cooperative: 1 },
    )
}

/// The launch attribute `id` of `value`.
fn attribute(
    id: sys::CUlaunchAttributeID,
    value: sys::CUlaunchAttributeValue,
) -> sys::CUlaunchAttribute {
    sys::CUlaunchAttribute {
        id,
        pad: [0; 4],
        value,
    }
}

/// Launches `function` on `stream` with one launch attribute (`cuLaunchKernelEx`, where
/// cudarc's launch builder takes none).
///
/// # Safety
/// `param` is the argument struct of `function`, whose views are valid for the launch, and
/// the attribute is one `function` can be launched with.
pub(super) unsafe fn launch_with<A: KernelArgs>(
    function: &CudaFunction,
    stream: &CudaStream,
    config: LaunchConfig,
    param: &Param<A>,
    mut attribute: sys::CUlaunchAttribute,
) -> Result<(), DriverError> {
    stream.context().bind_to_thread()?;
    let launch = sys::CUlaunchConfig {
        gridDimX: config.grid_dim.0,
        gridDimY: config.grid_dim.1,
        gridDimZ: config.grid_dim.2,
        blockDimX: config.block_dim.0,
        blockDimY: config.block_dim.1,
        blockDimZ: config.block_dim.2,
        sharedMemBytes: config.shared_mem_bytes,
        hStream: stream.cu_stream(),
        attrs: &mut attribute,
        numAttrs: 1,
    };
    let mut params = [param as *const Param<A> as *mut core::ffi::c_void];
    // SAFETY: the configuration and its one attribute live through the call; the driver
    // copies the parameter it points to (the caller vouches for what it views).
    unsafe {
        sys::cuLaunchKernelEx(
            &launch,
            function.cu_function(),
            params.as_mut_ptr(),
            core::ptr::null_mut(),
        )
    }
    .result()
}

pub(super) fn properties(
    ctx: &Arc<CudaContext>,
    ptx_arch: &str,
) -> Result<GpuProperties, DriverError> {
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
        threads_per_multiprocessor: ctx
            .attribute(CU_DEVICE_ATTRIBUTE_MAX_THREADS_PER_MULTIPROCESSOR)?
            as u32,
        driver_cuda_version: format!("{}.{}", version / 1000, (version % 1000) / 10),
        ptx_arch: ptx_arch.to_string(),
    })
}
