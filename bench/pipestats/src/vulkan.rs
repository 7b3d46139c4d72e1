//! The Vulkan side: device choice, a device with every feature it has, compute pipelines
//! created with statistics capture, and what VK_KHR_pipeline_executable_properties reports.

use std::ffi::{CStr, c_char};

use ash::{ext, khr, vk};
use serde::Serialize;

use crate::spv::{Descriptor, Layout, Target};

/// Formats a failed Vulkan call.
fn fail(call: &'static str) -> impl Fn(vk::Result) -> String {
    move |r| format!("{call} failed: {r} ({})", r.as_raw())
}

/// A fixed-size Vulkan string.
fn text(s: Result<&CStr, std::ffi::FromBytesUntilNulError>) -> String {
    s.map_or_else(|_| "?".into(), |s| s.to_string_lossy().into_owned())
}

/// The feature structs queried from the device and enabled again, as one chain.
#[derive(Clone, Default)]
struct Features {
    core: vk::PhysicalDeviceFeatures,
    v11: vk::PhysicalDeviceVulkan11Features<'static>,
    v12: vk::PhysicalDeviceVulkan12Features<'static>,
    v13: vk::PhysicalDeviceVulkan13Features<'static>,
    robustness2: vk::PhysicalDeviceRobustness2FeaturesEXT<'static>,
    executable: vk::PhysicalDevicePipelineExecutablePropertiesFeaturesKHR<'static>,
}

impl Features {
    /// `VkPhysicalDeviceFeatures2` with the structs the device's version and extensions allow.
    fn chain(
        &mut self,
        api: u32,
        robustness2: bool,
        executable: bool,
    ) -> vk::PhysicalDeviceFeatures2<'_> {
        self.v11.p_next = std::ptr::null_mut();
        self.v12.p_next = std::ptr::null_mut();
        self.v13.p_next = std::ptr::null_mut();
        self.robustness2.p_next = std::ptr::null_mut();
        self.executable.p_next = std::ptr::null_mut();
        let mut f = vk::PhysicalDeviceFeatures2::default().features(self.core);
        if api >= vk::API_VERSION_1_2 {
            f = f.push_next(&mut self.v11).push_next(&mut self.v12);
        }
        if api >= vk::API_VERSION_1_3 {
            f = f.push_next(&mut self.v13);
        }
        if robustness2 {
            f = f.push_next(&mut self.robustness2);
        }
        if executable {
            f = f.push_next(&mut self.executable);
        }
        f
    }
}

/// The instance and the chosen physical device.
pub struct Gpu {
    _entry: ash::Entry,
    instance: ash::Instance,
    physical: vk::PhysicalDevice,
    /// Device name.
    pub name: String,
    /// Driver name and version string (VkPhysicalDeviceDriverProperties), when known.
    pub driver: String,
    /// Vulkan version the device reports.
    pub device_api: u32,
    /// Vulkan version used: the device's, at most the instance's.
    api: u32,
    extensions: Vec<&'static CStr>,
    has_executable_properties: bool,
    has_robustness2: bool,
    features: Features,
}

impl Drop for Gpu {
    fn drop(&mut self) {
        // SAFETY: every child object (the `Device`) borrows `self` and is gone by now.
        unsafe { self.instance.destroy_instance(None) };
    }
}

/// Version as "1.3.280".
pub fn version(v: u32) -> String {
    format!(
        "{}.{}.{}",
        vk::api_version_major(v),
        vk::api_version_minor(v),
        vk::api_version_patch(v)
    )
}

impl Gpu {
    /// Loads Vulkan and picks the device whose name contains `adapter` (case-insensitive), else the
    /// first discrete GPU, else the first device.
    pub fn open(adapter: Option<&str>) -> Result<Gpu, String> {
        // SAFETY: loads the system's Vulkan loader library, whose initialisation we trust.
        let entry =
            unsafe { ash::Entry::load() }.map_err(|e| format!("cannot load Vulkan: {e}"))?;
        // SAFETY: a global command of a loaded entry.
        let loader = unsafe { entry.try_enumerate_instance_version() }
            .map_err(fail("vkEnumerateInstanceVersion"))?
            .unwrap_or(vk::API_VERSION_1_0);
        let instance_api = loader.min(vk::API_VERSION_1_3);
        let app = vk::ApplicationInfo::default()
            .application_name(c"pipestats")
            .api_version(instance_api);
        let info = vk::InstanceCreateInfo::default().application_info(&app);
        // SAFETY: `info` and `app` are valid and outlive the call.
        let instance =
            unsafe { entry.create_instance(&info, None) }.map_err(fail("vkCreateInstance"))?;
        let mut gpu = Gpu {
            _entry: entry,
            instance,
            physical: vk::PhysicalDevice::null(),
            name: String::new(),
            driver: String::new(),
            device_api: 0,
            api: 0,
            extensions: Vec::new(),
            has_executable_properties: false,
            has_robustness2: false,
            features: Features::default(),
        };
        // SAFETY: a valid instance (dropped by `gpu` on any error below).
        let devices = unsafe { gpu.instance.enumerate_physical_devices() }
            .map_err(fail("vkEnumeratePhysicalDevices"))?;
        // SAFETY: handles just enumerated from this instance.
        let props: Vec<_> = devices
            .iter()
            .map(|&d| unsafe { gpu.instance.get_physical_device_properties(d) })
            .collect();
        let names: Vec<String> = props
            .iter()
            .map(|p| text(p.device_name_as_c_str()))
            .collect();
        let index = match adapter {
            Some(want) => names
                .iter()
                .position(|n| n.to_lowercase().contains(&want.to_lowercase())),
            None => props
                .iter()
                .position(|p| p.device_type == vk::PhysicalDeviceType::DISCRETE_GPU)
                .or((!devices.is_empty()).then_some(0)),
        };
        let Some(index) = index else {
            return Err(format!(
                "no Vulkan device{} (devices: {})",
                adapter
                    .map(|a| format!(" named like \"{a}\""))
                    .unwrap_or_default(),
                if names.is_empty() {
                    "none".into()
                } else {
                    names.join(", ")
                }
            ));
        };
        gpu.physical = devices[index];
        gpu.name = names[index].clone();
        gpu.device_api = props[index].api_version;
        gpu.api = gpu.device_api.min(instance_api);
        // SAFETY: a valid physical device.
        let available = unsafe {
            gpu.instance
                .enumerate_device_extension_properties(gpu.physical)
        }
        .map_err(fail("vkEnumerateDeviceExtensionProperties"))?;
        let has = |name: &CStr| {
            available
                .iter()
                .any(|e| e.extension_name_as_c_str() == Ok(name))
        };
        gpu.has_robustness2 = has(ext::robustness2::NAME);
        let executable_ext = has(khr::pipeline_executable_properties::NAME);
        if gpu.has_robustness2 {
            gpu.extensions.push(ext::robustness2::NAME);
        }
        if executable_ext {
            gpu.extensions
                .push(khr::pipeline_executable_properties::NAME);
        }
        if gpu.api >= vk::API_VERSION_1_2 {
            let mut driver = vk::PhysicalDeviceDriverProperties::default();
            let mut p2 = vk::PhysicalDeviceProperties2::default().push_next(&mut driver);
            // SAFETY: a valid physical device and a well-formed chain (core in 1.2).
            unsafe {
                gpu.instance
                    .get_physical_device_properties2(gpu.physical, &mut p2)
            };
            gpu.driver = format!(
                "{} {}",
                text(driver.driver_name_as_c_str()),
                text(driver.driver_info_as_c_str())
            );
        }
        let core = {
            let (api, r2) = (gpu.api, gpu.has_robustness2);
            let mut chain = gpu.features.chain(api, r2, executable_ext);
            // SAFETY: valid physical device; the chain holds only structs its version and
            // extensions allow.
            unsafe {
                gpu.instance
                    .get_physical_device_features2(gpu.physical, &mut chain)
            };
            chain.features
        };
        gpu.features.core = core;
        gpu.has_executable_properties =
            executable_ext && gpu.features.executable.pipeline_executable_info == vk::TRUE;
        Ok(gpu)
    }

    /// wgpu's device-dependent SPIR-V choices for this device.
    pub fn target(&self, force_loop_bounding: bool) -> Target {
        let f = &self.features;
        let api13 = self.api >= vk::API_VERSION_1_3;
        Target {
            lang_version: Target::lang_version(self.device_api),
            robust_buffer_access2: self.has_robustness2
                && f.robustness2.robust_buffer_access2 == vk::TRUE,
            robust_image_access: if self.has_robustness2 {
                f.robustness2.robust_image_access2 == vk::TRUE
            } else {
                api13 && f.v13.robust_image_access == vk::TRUE
            },
            zero_initialize_workgroup_memory_native: api13
                && f.v13.shader_zero_initialize_workgroup_memory == vk::TRUE,
            force_loop_bounding,
        }
    }

    /// Opens a device with every feature the physical device has, or says why it cannot report
    /// pipeline statistics.
    pub fn device(&self) -> Result<Device<'_>, String> {
        if !self.has_executable_properties {
            return Err(format!(
                "device \"{}\" (driver {}) lacks VK_KHR_pipeline_executable_properties \
                 (extension or its pipelineExecutableInfo feature): \
                 the driver cannot report pipeline statistics",
                self.name, self.driver
            ));
        }
        // SAFETY: a valid physical device.
        let families = unsafe {
            self.instance
                .get_physical_device_queue_family_properties(self.physical)
        };
        let family = families
            .iter()
            .position(|q| q.queue_flags.contains(vk::QueueFlags::COMPUTE))
            .ok_or_else(|| format!("device \"{}\" has no compute queue", self.name))?
            as u32;
        let queues = [vk::DeviceQueueCreateInfo::default()
            .queue_family_index(family)
            .queue_priorities(&[1.0])];
        let names: Vec<*const c_char> = self.extensions.iter().map(|e| e.as_ptr()).collect();
        let subgroup_size_control =
            self.api >= vk::API_VERSION_1_3 && self.features.v13.subgroup_size_control == vk::TRUE;
        let mut features = self.features.clone();
        let mut chain = features.chain(self.api, self.has_robustness2, true);
        let info = vk::DeviceCreateInfo::default()
            .queue_create_infos(&queues)
            .enabled_extension_names(&names)
            .push_next(&mut chain);
        // SAFETY: every struct in `info` lives to the end of the call; the features and
        // extensions are those the device reported.
        let device = unsafe { self.instance.create_device(self.physical, &info, None) }
            .map_err(fail("vkCreateDevice"))?;
        let executable = khr::pipeline_executable_properties::Device::new(&self.instance, &device);
        Ok(Device {
            device,
            executable,
            subgroup_size_control,
            _gpu: std::marker::PhantomData,
        })
    }
}

/// A logical device with VK_KHR_pipeline_executable_properties.
pub struct Device<'g> {
    device: ash::Device,
    executable: khr::pipeline_executable_properties::Device,
    subgroup_size_control: bool,
    _gpu: std::marker::PhantomData<&'g Gpu>,
}

impl Drop for Device<'_> {
    fn drop(&mut self) {
        // SAFETY: every object made from it is destroyed by `Objects` before `compile` returns.
        unsafe { self.device.destroy_device(None) };
    }
}

/// Objects of one pipeline, destroyed (null handles are ignored) when dropped.
struct Objects<'d> {
    device: &'d ash::Device,
    module: vk::ShaderModule,
    sets: Vec<vk::DescriptorSetLayout>,
    layout: vk::PipelineLayout,
    pipeline: vk::Pipeline,
}

impl Drop for Objects<'_> {
    fn drop(&mut self) {
        // SAFETY: handles made from `device` (or null), used by no pending work.
        unsafe {
            self.device.destroy_pipeline(self.pipeline, None);
            self.device.destroy_pipeline_layout(self.layout, None);
            for &set in &self.sets {
                self.device.destroy_descriptor_set_layout(set, None);
            }
            self.device.destroy_shader_module(self.module, None);
        }
    }
}

/// A statistic's value, in the format the driver gave.
#[derive(Clone, Copy, Debug, Serialize)]
#[serde(untagged)]
pub enum Value {
    /// `BOOL32`.
    Bool(bool),
    /// `INT64`.
    I64(i64),
    /// `UINT64`.
    U64(u64),
    /// `FLOAT64`.
    F64(f64),
}

/// One statistic of an executable.
#[derive(Debug, Serialize)]
pub struct Statistic {
    /// Driver's name, e.g. "Register Count".
    pub name: String,
    /// Driver's description.
    pub description: String,
    /// Format the driver gave: bool32, int64, uint64 or float64.
    pub format: &'static str,
    /// Value.
    pub value: Value,
}

/// One internal representation (e.g. the driver's IR or machine code).
#[derive(Debug, Serialize)]
pub struct Representation {
    /// Driver's name.
    pub name: String,
    /// Driver's description.
    pub description: String,
    /// Whether `data` is text.
    pub is_text: bool,
    /// Bytes.
    pub bytes: usize,
    /// The file it was written to, if any.
    pub file: Option<String>,
    /// Contents.
    #[serde(skip)]
    pub data: Vec<u8>,
}

/// One executable of a pipeline (for a compute pipeline usually one).
#[derive(Debug, Serialize)]
pub struct Executable {
    /// Driver's name.
    pub name: String,
    /// Driver's description.
    pub description: String,
    /// Subgroup size it runs with.
    pub subgroup_size: u32,
    /// Its statistics.
    pub statistics: Vec<Statistic>,
    /// Its internal representations.
    pub representations: Vec<Representation>,
}

impl Device<'_> {
    /// Builds a compute pipeline of `entry` in `spirv` with statistics capture and reads what the
    /// driver reports about it.
    pub fn compile(
        &self,
        spirv: &[u32],
        entry: &str,
        layout: &Layout,
    ) -> Result<Vec<Executable>, String> {
        let d = &self.device;
        let mut o = Objects {
            device: d,
            module: vk::ShaderModule::null(),
            sets: Vec::new(),
            layout: vk::PipelineLayout::null(),
            pipeline: vk::Pipeline::null(),
        };
        // SAFETY (every call in this function): `d` is a valid device and each create info and
        // what it points to lives to the end of the call; `o` destroys what is made.
        o.module = unsafe {
            d.create_shader_module(&vk::ShaderModuleCreateInfo::default().code(spirv), None)
        }
        .map_err(fail("vkCreateShaderModule"))?;
        for set in &layout.sets {
            let bindings: Vec<_> = set
                .iter()
                .map(|&(binding, kind)| {
                    vk::DescriptorSetLayoutBinding::default()
                        .binding(binding)
                        .descriptor_type(match kind {
                            Descriptor::Storage => vk::DescriptorType::STORAGE_BUFFER,
                            Descriptor::Uniform => vk::DescriptorType::UNIFORM_BUFFER,
                        })
                        .descriptor_count(1)
                        .stage_flags(vk::ShaderStageFlags::COMPUTE)
                })
                .collect();
            let info = vk::DescriptorSetLayoutCreateInfo::default().bindings(&bindings);
            let set = unsafe { d.create_descriptor_set_layout(&info, None) }
                .map_err(fail("vkCreateDescriptorSetLayout"))?;
            o.sets.push(set);
        }
        let push: Vec<_> = layout
            .push_constant_bytes
            .map(|size| vk::PushConstantRange {
                stage_flags: vk::ShaderStageFlags::COMPUTE,
                offset: 0,
                size,
            })
            .into_iter()
            .collect();
        let info = vk::PipelineLayoutCreateInfo::default()
            .set_layouts(&o.sets)
            .push_constant_ranges(&push);
        o.layout = unsafe { d.create_pipeline_layout(&info, None) }
            .map_err(fail("vkCreatePipelineLayout"))?;
        let name = std::ffi::CString::new(entry)
            .map_err(|_| format!("entry point name {entry:?} has a NUL"))?;
        let mut stage_flags = vk::PipelineShaderStageCreateFlags::empty();
        if self.subgroup_size_control {
            // As wgpu-hal does when the device has wgpu's SUBGROUP feature (the scheduler
            // asks for it).
            stage_flags |= vk::PipelineShaderStageCreateFlags::ALLOW_VARYING_SUBGROUP_SIZE;
        }
        let stage = vk::PipelineShaderStageCreateInfo::default()
            .flags(stage_flags)
            .stage(vk::ShaderStageFlags::COMPUTE)
            .module(o.module)
            .name(&name);
        let info = vk::ComputePipelineCreateInfo::default()
            .flags(
                vk::PipelineCreateFlags::CAPTURE_STATISTICS_KHR
                    | vk::PipelineCreateFlags::CAPTURE_INTERNAL_REPRESENTATIONS_KHR,
            )
            .stage(stage)
            .layout(o.layout);
        o.pipeline =
            match unsafe { d.create_compute_pipelines(vk::PipelineCache::null(), &[info], None) } {
                Ok(p) => p[0],
                Err((p, r)) => {
                    o.pipeline = p.first().copied().unwrap_or_default();
                    return Err(fail("vkCreateComputePipelines")(r));
                }
            };
        let x = &self.executable;
        let props = unsafe {
            x.get_pipeline_executable_properties(
                &vk::PipelineInfoKHR::default().pipeline(o.pipeline),
            )
        }
        .map_err(fail("vkGetPipelineExecutablePropertiesKHR"))?;
        let mut out = Vec::new();
        for (index, p) in (0u32..).zip(&props) {
            let info = vk::PipelineExecutableInfoKHR::default()
                .pipeline(o.pipeline)
                .executable_index(index);
            let stats = unsafe { x.get_pipeline_executable_statistics(&info) }
                .map_err(fail("vkGetPipelineExecutableStatisticsKHR"))?;
            let statistics = stats
                .iter()
                .map(|s| Statistic {
                    name: text(s.name_as_c_str()),
                    description: text(s.description_as_c_str()),
                    format: match s.format {
                        vk::PipelineExecutableStatisticFormatKHR::BOOL32 => "bool32",
                        vk::PipelineExecutableStatisticFormatKHR::INT64 => "int64",
                        vk::PipelineExecutableStatisticFormatKHR::FLOAT64 => "float64",
                        _ => "uint64",
                    },
                    // SAFETY: the union member named by `format`.
                    value: unsafe {
                        match s.format {
                            vk::PipelineExecutableStatisticFormatKHR::BOOL32 => {
                                Value::Bool(s.value.b32 != 0)
                            }
                            vk::PipelineExecutableStatisticFormatKHR::INT64 => {
                                Value::I64(s.value.i64)
                            }
                            vk::PipelineExecutableStatisticFormatKHR::FLOAT64 => {
                                Value::F64(s.value.f64)
                            }
                            _ => Value::U64(s.value.u64),
                        }
                    },
                })
                .collect();
            out.push(Executable {
                name: text(p.name_as_c_str()),
                description: text(p.description_as_c_str()),
                subgroup_size: p.subgroup_size,
                statistics,
                representations: self.representations(&info)?,
            });
        }
        Ok(out)
    }

    /// The executable's internal representations: one call for their sizes, one for their data.
    fn representations(
        &self,
        info: &vk::PipelineExecutableInfoKHR<'_>,
    ) -> Result<Vec<Representation>, String> {
        let x = &self.executable;
        let call = fail("vkGetPipelineExecutableInternalRepresentationsKHR");
        // SAFETY: valid device and pipeline; ash passes null data pointers, so only sizes return.
        let mut irs =
            unsafe { x.get_pipeline_executable_internal_representations(info) }.map_err(&call)?;
        let mut data: Vec<Vec<u8>> = irs.iter().map(|r| vec![0; r.data_size]).collect();
        for (ir, buf) in irs.iter_mut().zip(&mut data) {
            ir.p_data = buf.as_mut_ptr().cast();
        }
        let mut count = irs.len() as u32;
        // SAFETY: `irs` holds `count` structs whose `p_data` point at `data_size` bytes each.
        let r = unsafe {
            (x.fp().get_pipeline_executable_internal_representations_khr)(
                x.device(),
                info,
                &mut count,
                irs.as_mut_ptr(),
            )
        };
        if r != vk::Result::SUCCESS && r != vk::Result::INCOMPLETE {
            return Err(call(r));
        }
        Ok(irs
            .iter()
            .zip(data)
            .take(count as usize)
            .map(|(ir, mut buf)| {
                buf.truncate(ir.data_size);
                if ir.is_text != 0 {
                    while buf.last() == Some(&0) {
                        buf.pop();
                    }
                }
                Representation {
                    name: text(ir.name_as_c_str()),
                    description: text(ir.description_as_c_str()),
                    is_text: ir.is_text != 0,
                    bytes: buf.len(),
                    file: None,
                    data: buf,
                }
            })
            .collect())
    }
}
