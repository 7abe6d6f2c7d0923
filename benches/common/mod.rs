//! What every benchmark shares: the device it runs on.

use gpuwars::{BackendRequest, Device};

/// The backend `GPUWARS_BACKEND` names (`cuda`, `cpu`; anything else: auto).
pub fn device() -> Device {
    let request = match std::env::var("GPUWARS_BACKEND").as_deref() {
        Ok("cpu") => BackendRequest::Cpu,
        Ok("cuda") => BackendRequest::Cuda,
        _ => BackendRequest::Auto,
    };
    Device::select(request, None).expect("the backend opens")
}
