//! The one way every GPU test opens a device: the adapter the environment names
//! (`WGPU_ADAPTER_NAME`, `WGPU_BACKEND`, as wgpu's own tests pick it), with the features the
//! test needs. No adapter is a failure that says what to install, never a skip. The scheduler's
//! and the workloads' tests open a device per test with it; the Reyes tests share one
//! (`common::gpu`).

use scheduler::Gpu;

/// A new device on the environment's adapter with `features`; panics naming the cause when
/// there is none (e.g. no Vulkan driver: `apt-get install mesa-vulkan-drivers`).
pub fn open_gpu(features: scheduler::wgpu::Features) -> Gpu {
    let mut gpu = Gpu::from_env_requiring(features)
        .unwrap_or_else(|e| panic!("GPU tests need an adapter with {features:?}: {e}"));
    // SAFETY: the tests compile the scheduler's, its workloads' and reyes's shaders and test
    // procedures whose loops all end (`Gpu::trust_loops`): they test what the commands run.
    #[allow(
        unsafe_code,
        reason = "Gpu::trust_loops: every loop of this device's shaders ends"
    )]
    unsafe {
        gpu.trust_loops()
    };
    gpu
}
