//! The user's resources: bind group 1 of every scheduler kernel (group 0 is the scheduler's own
//! queues). A program declares them once, as WGSL plus layout entries; each run gets the
//! matching `wgpu::BindGroup`.
//!
//! ```
//! # fn main() -> Result<(), scheduler::RunError> {
//! use scheduler::{Gpu, UserBindings};
//! let gpu = Gpu::from_env()?;
//! // Binding 0: a read-write counter array; binding 1: read-only parameters.
//! let user = UserBindings::storage(
//!     "@group(1) @binding(0) var<storage, read_write> out: array<atomic<u32>>;\n\
//!      @group(1) @binding(1) var<storage, read> cfg: array<u32>;",
//!     &[(0, false), (1, true)],
//! );
//! let out = gpu.storage_buffer("out", 64)?; // 64 zeroed u32 words
//! let cfg = gpu.upload("cfg", &[5u32, 4])?;
//! let bind_group = user.bind_group(&gpu, &[&out, &cfg])?; // in layout order: 0, then 1
//! # Ok(()) }
//! ```

use crate::error::RunError;
use crate::gpu::Gpu;

/// The layout entry of a compute-visible storage buffer at `binding` of its group, read-only
/// (`var<storage, read>`) or not (`var<storage, read_write>`), any size.
pub fn storage_entry(binding: u32, read_only: bool) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

/// User resources for bind group 1: WGSL declarations (and helper functions, constants,
/// structs) that bodies may use, plus the layout entries of the `@group(1)` bindings.
///
/// [`crate::Program::new`] checks that every `@group(1)` variable the WGSL declares has a
/// layout entry with the same binding, and that a `read_write` storage variable is not given a
/// read-only entry. The default is no user resources: runs then take `None` as bind group.
#[derive(Debug, Clone, Default)]
pub struct UserBindings {
    /// WGSL added to every kernel: the `@group(1)` declarations and any helpers.
    pub wgsl: String,
    /// One entry per `@group(1)` binding (compute visibility). [`storage_entry`] makes the
    /// usual storage-buffer entry.
    pub layout: Vec<wgpu::BindGroupLayoutEntry>,
}

impl UserBindings {
    /// No user resources: no bind group 1, runs take `None`.
    pub fn none() -> UserBindings {
        UserBindings::default()
    }

    /// WGSL `wgsl` whose `@group(1)` storage buffers sit at the bindings of `buffers`, each
    /// `(binding, read_only)`, in the order [`UserBindings::bind_group`] will take the buffers.
    pub fn storage(wgsl: &str, buffers: &[(u32, bool)]) -> UserBindings {
        UserBindings {
            wgsl: wgsl.into(),
            layout: buffers
                .iter()
                .map(|&(b, read_only)| storage_entry(b, read_only))
                .collect(),
        }
    }

    /// The bind group layout of group 1, or `None` when nothing is declared. Layouts with the
    /// same entries are interchangeable, so this one fits every scheduler compiled from the
    /// program.
    pub fn bind_group_layout(&self, gpu: &Gpu) -> Option<wgpu::BindGroupLayout> {
        (!self.layout.is_empty()).then(|| {
            gpu.device
                .create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                    label: Some("user"),
                    entries: &self.layout,
                })
        })
    }

    /// The bind group for [`crate::Scheduler::run`]: `buffers[i]`, whole, at the binding of
    /// `layout[i]`. Buffers need `STORAGE` usage ([`Gpu::storage_buffer`] and [`Gpu::upload`]
    /// make such buffers).
    ///
    /// Errors ([`RunError::Program`]): no bindings declared, a buffer count different from the
    /// entry count, or an entry that is not a buffer (build such a bind group with wgpu from
    /// [`UserBindings::bind_group_layout`]). wgpu's own checks (usage, size) are reported by
    /// the next [`Gpu::wait`].
    pub fn bind_group(
        &self,
        gpu: &Gpu,
        buffers: &[&wgpu::Buffer],
    ) -> Result<wgpu::BindGroup, RunError> {
        let Some(layout) = self.bind_group_layout(gpu) else {
            return Err(RunError::Program(
                "the program declares no user bindings: run with `None` as bind group".into(),
            ));
        };
        if buffers.len() != self.layout.len() {
            return Err(RunError::Program(format!(
                "the user bindings declare {} entries but {} buffers were given",
                self.layout.len(),
                buffers.len()
            )));
        }
        let mut entries = Vec::new();
        for (e, b) in self.layout.iter().zip(buffers) {
            if !matches!(e.ty, wgpu::BindingType::Buffer { .. }) {
                return Err(RunError::Program(format!(
                    "user binding {} is not a buffer; build this bind group with wgpu from \
                     UserBindings::bind_group_layout",
                    e.binding
                )));
            }
            entries.push(wgpu::BindGroupEntry {
                binding: e.binding,
                resource: b.as_entire_binding(),
            });
        }
        Ok(gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("user"),
            layout: &layout,
            entries: &entries,
        }))
    }
}
