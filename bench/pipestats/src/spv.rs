//! WGSL to SPIR-V as wgpu-hal 30.0.1's Vulkan backend writes it (`naga_options` in
//! `vulkan/adapter.rs`, changed per stage by `compile_stage` in `vulkan/device.rs`).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use naga::back::spv;
use naga::proc::{BoundsCheckPolicies, BoundsCheckPolicy};
use naga::valid::{Capabilities, ValidationFlags, Validator};
use serde::Serialize;

/// One parsed and validated WGSL file.
pub struct Shader {
    /// The file, as given.
    pub path: PathBuf,
    /// The parsed module.
    pub module: naga::Module,
    /// The validator's analysis of `module`.
    pub info: naga::valid::ModuleInfo,
}

/// Parses and validates `path`; the error names the file and shows naga's message at its location.
pub fn load(path: &Path) -> Result<Shader, String> {
    let shown = path.display().to_string();
    let source = std::fs::read_to_string(path).map_err(|e| format!("{shown}: {e}"))?;
    // wgpu-core parses with the device's capabilities; allow them all, as `capabilities: None`
    // does for the writer.
    let module = naga::front::wgsl::parse_str(&source).map_err(|e| {
        format!(
            "{shown}: WGSL parse error\n{}",
            e.emit_to_string_with_path(&source, &shown)
        )
    })?;
    let info = Validator::new(ValidationFlags::all(), Capabilities::all())
        .validate(&module)
        .map_err(|e| {
            format!(
                "{shown}: validation error\n{}",
                e.emit_to_string_with_path(&source, &shown)
            )
        })?;
    Ok(Shader {
        path: path.to_owned(),
        module,
        info,
    })
}

/// What the device decides in wgpu's SPIR-V options.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct Target {
    /// SPIR-V version written (from the device's Vulkan API version).
    pub lang_version: (u8, u8),
    /// `robustBufferAccess2` (VK_EXT_robustness2): buffer accesses left unchecked, else clamped.
    pub robust_buffer_access2: bool,
    /// `robustImageAccess2`, else `robustImageAccess`: image loads left unchecked, else clamped.
    pub robust_image_access: bool,
    /// `shaderZeroInitializeWorkgroupMemory`: the driver zeroes workgroup memory, else a polyfill.
    pub zero_initialize_workgroup_memory_native: bool,
    /// wgpu's `force_loop_bounding` (a counter and a break in every loop).
    pub force_loop_bounding: bool,
}

impl Target {
    /// The SPIR-V version wgpu picks for a device of Vulkan version `api` (`vk::make_api_version`).
    pub fn lang_version(api: u32) -> (u8, u8) {
        match (api >> 22 & 0x7f, api >> 12 & 0x3ff) {
            (1, 0) => (1, 0),
            (1, 1) => (1, 3),
            (1, 2) => (1, 5),
            _ => (1, 6),
        }
    }
}

/// Kind of descriptor a global needs.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub enum Descriptor {
    /// `var<storage>`.
    Storage,
    /// `var<uniform>`.
    Uniform,
}

/// The module's resources as a pipeline layout sees them.
#[derive(Clone, Debug, Default)]
pub struct Layout {
    /// Per group (0..=max, empty for gaps): (Vulkan binding, descriptor) sorted by binding.
    pub sets: Vec<Vec<(u32, Descriptor)>>,
    /// Bytes of the `var<immediate>` (push constant) block, if any.
    pub push_constant_bytes: Option<u32>,
    /// WGSL (group, binding) to Vulkan (set, binding), as wgpu builds it from a pipeline layout.
    binding_map: spv::BindingMap,
}

/// Reflects the layout: every buffer binding, numbered like wgpu-hal numbers a bind group
/// layout's entries (0, 1, 2... in binding order, assuming the layout lists the shader's
/// bindings), and the push-constant block.
pub fn layout(module: &naga::Module) -> Result<Layout, String> {
    let mut groups: BTreeMap<u32, BTreeMap<u32, Descriptor>> = BTreeMap::new();
    let mut out = Layout::default();
    for (_, var) in module.global_variables.iter() {
        let name = var.name.as_deref().unwrap_or("?");
        if var.space == naga::AddressSpace::Immediate {
            let bytes = module.types[var.ty].inner.size(module.to_ctx());
            out.push_constant_bytes = Some(bytes.next_multiple_of(4));
        }
        let Some(rb) = var.binding else { continue };
        let kind = match var.space {
            naga::AddressSpace::Storage { .. } => Descriptor::Storage,
            naga::AddressSpace::Uniform => Descriptor::Uniform,
            space => {
                return Err(format!(
                    "global `{name}` (@group({}) @binding({})) is in address space {space:?}; \
                     only storage and uniform buffers are supported",
                    rb.group, rb.binding
                ));
            }
        };
        if let naga::TypeInner::BindingArray { .. } = module.types[var.ty].inner {
            return Err(format!("global `{name}` is a binding array; not supported"));
        }
        groups.entry(rb.group).or_default().insert(rb.binding, kind);
    }
    let max = groups.keys().next_back().map_or(0, |&g| g as usize + 1);
    out.sets = vec![Vec::new(); max];
    for (group, bindings) in groups {
        for (vk_binding, (binding, kind)) in (0u32..).zip(bindings) {
            out.sets[group as usize].push((vk_binding, kind));
            let info = spv::BindingInfo {
                descriptor_set: group,
                binding: vk_binding,
                binding_array_size: None,
            };
            out.binding_map
                .insert(naga::ResourceBinding { group, binding }, info);
        }
    }
    Ok(out)
}

/// Writes the SPIR-V of compute entry point `entry` with wgpu-hal's options for `target`.
pub fn write(
    shader: &Shader,
    entry: &str,
    target: &Target,
    layout: &Layout,
) -> Result<Vec<u32>, String> {
    let unchecked_if = |robust| {
        if robust {
            BoundsCheckPolicy::Unchecked
        } else {
            BoundsCheckPolicy::Restrict
        }
    };
    let options = spv::Options {
        lang_version: target.lang_version,
        // wgpu: DEBUG only with InstanceFlags::DEBUG (no debug info here), LABEL_VARYINGS unless
        // Qualcomm, FORCE_POINT_SIZE always; neither matters to a compute shader.
        flags: spv::WriterFlags::LABEL_VARYINGS | spv::WriterFlags::FORCE_POINT_SIZE,
        fake_missing_bindings: false,
        binding_map: layout.binding_map.clone(),
        // wgpu lists the capabilities its enabled features allow; the module's own are the same.
        capabilities: None,
        bounds_check_policies: BoundsCheckPolicies {
            index: BoundsCheckPolicy::Restrict,
            buffer: unchecked_if(target.robust_buffer_access2),
            image_load: unchecked_if(target.robust_image_access),
            binding_array: BoundsCheckPolicy::Unchecked,
        },
        zero_initialize_workgroup_memory: if target.zero_initialize_workgroup_memory_native {
            spv::ZeroInitializeWorkgroupMemoryMode::Native
        } else {
            spv::ZeroInitializeWorkgroupMemoryMode::Polyfill
        },
        force_loop_bounding: target.force_loop_bounding,
        ray_query_initialization_tracking: true,
        trace_ray_argument_validation: true,
        use_storage_input_output_16: false,
        debug_info: None,
        // Task shaders only.
        task_dispatch_limits: None,
        mesh_shader_primitive_indices_clamp: true,
        emit_int_div_checks: true,
    };
    let stage = naga::ShaderStage::Compute;
    let constants = naga::back::PipelineConstants::default();
    let (module, info) = naga::back::pipeline_constants::process_overrides(
        &shader.module,
        &shader.info,
        Some((stage, entry)),
        &constants,
    )
    .map_err(|e| format!("{}: {entry}: overrides: {e}", shader.path.display()))?;
    let pipeline = spv::PipelineOptions {
        shader_stage: stage,
        entry_point: entry.to_owned(),
    };
    spv::write_vec(&module, &info, &options, Some(&pipeline))
        .map_err(|e| format!("{}: {entry}: SPIR-V writer: {e}", shader.path.display()))
}

/// SPIR-V words as the bytes of a `.spv` file (little-endian).
pub fn bytes(words: &[u32]) -> Vec<u8> {
    words.iter().flat_map(|w| w.to_le_bytes()).collect()
}
