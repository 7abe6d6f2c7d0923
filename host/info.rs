//! `gpuwars info`: what this build and this machine offer.

use serde::Serialize;

use crate::backend::GpuProperties;
use crate::{BackendKind, Device, kernels, ptx};

/// Everything `gpuwars info` prints.
#[derive(Debug, Serialize)]
pub struct Info {
    /// Version of the gpuwars package.
    pub version: &'static str,
    /// The backend that runs the kernels.
    pub backend: BackendKind,
    /// Why that backend was chosen.
    pub backend_reason: String,
    /// The GPU, when the backend is CUDA.
    pub device: Option<GpuProperties>,
    /// The embedded PTX module the GPU loaded (the baseline one without a GPU).
    pub ptx: PtxInfo,
    /// Whether kernels are launched before the one they follow ends (programmatic
    /// dependent launch, GPU of sm_90 or newer only).
    pub dependent_launch: bool,
    /// Worker threads of the CPU emulation (when it is the backend).
    pub cpu_threads: Option<usize>,
    /// Logical CPUs of this machine.
    pub host_cpus: usize,
}

/// Facts about the embedded PTX module.
#[derive(Debug, Serialize)]
pub struct PtxInfo {
    /// Size of the PTX text in bytes.
    pub bytes: usize,
    /// The architecture it targets.
    pub arch: &'static str,
    /// The `.entry` points found in it.
    pub entry_points: Vec<String>,
    /// Kernels of the registry that have no entry point in it (empty in a sound build).
    pub missing_kernels: Vec<&'static str>,
}

impl Info {
    /// Gathers the report for an open device.
    pub fn gather(device: &Device) -> Info {
        let loaded = device.gpu_properties().map(|d| d.ptx_arch.as_str());
        let (module, arch) = match loaded {
            Some(arch) if arch == ptx::DEPENDENT_ARCH => (ptx::DEPENDENT_PTX, ptx::DEPENDENT_ARCH),
            _ => (ptx::PTX, ptx::ARCH),
        };
        let entry_points = ptx::entry_points(module);
        let missing_kernels = kernels::registry::ALL
            .iter()
            .map(|k| k.name)
            .filter(|name| !entry_points.contains(name))
            .collect();
        Info {
            version: env!("CARGO_PKG_VERSION"),
            backend: device.kind(),
            backend_reason: device.reason().to_string(),
            device: device.gpu_properties().cloned(),
            ptx: PtxInfo {
                bytes: module.len(),
                arch,
                entry_points: entry_points.into_iter().map(str::to_string).collect(),
                missing_kernels,
            },
            dependent_launch: device.dependent_launch(),
            cpu_threads: device.cpu_threads(),
            host_cpus: std::thread::available_parallelism().map_or(1, usize::from),
        }
    }

    /// The report as lines of text.
    pub fn to_text(&self) -> String {
        let mut out = format!("gpuwars {}\n", self.version);
        out += &format!("backend:      {} ({})\n", self.backend, self.backend_reason);
        if let Some(d) = &self.device {
            out += &format!(
                "device:       {} (compute capability {}, {} multiprocessors, {:.1} GiB, driver CUDA {})\n",
                d.name,
                d.compute_capability,
                d.multiprocessors,
                d.memory_bytes as f64 / (1u64 << 30) as f64,
                d.driver_cuda_version
            );
            out += &format!(
                "launches:     the {} module, {}\n",
                d.ptx_arch,
                if self.dependent_launch {
                    "each kernel launched before the one it follows ends (programmatic dependent launch)"
                } else {
                    "each kernel launched when the one it follows ends"
                }
            );
        }
        if let Some(threads) = self.cpu_threads {
            out += &format!(
                "cpu threads:  {threads} (of {} logical CPUs)\n",
                self.host_cpus
            );
        }
        out += &format!(
            "ptx:          {} bytes for {}, {} entry points: {}\n",
            self.ptx.bytes,
            self.ptx.arch,
            self.ptx.entry_points.len(),
            self.ptx.entry_points.join(", ")
        );
        if !self.ptx.missing_kernels.is_empty() {
            out += &format!(
                "MISSING from the PTX: {}\n",
                self.ptx.missing_kernels.join(", ")
            );
        }
        out
    }
}
