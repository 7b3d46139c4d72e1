//! The Reyes pipeline on the scheduler: Bound, SplitU, SplitV and DiceShade (which samples its
//! own grid, so micropolygons never leave workgroup memory) registered as procedures, run by
//! either strategy, then a resolve pass from sub-samples to pixels.

use crate::frame::{FrameData, Material, PatchItem};
use crate::image::FrameImage;
use crate::shaders;
use crate::stages::COUNTERS;
use scheduler::pipeline::storage_entry;
use scheduler::timing::PassTimer;
use scheduler::{
    Gpu, ItemType, Procedure, Program, RunError, RunStats, Scheduler, Seed, StrategyKind,
    UserBindings,
};
use std::time::Instant;

/// Procedure names, in registration order. The default queue policy gives the last the highest
/// priority: dice before split, which keeps the queues short.
pub const PROCEDURES: [&str; 4] = ["bound", "splitu", "splitv", "diceshade"];

/// Device features the pipeline needs: 64-bit atomicMax for the depth-and-colour samples.
pub fn required_features() -> wgpu::Features {
    wgpu::Features::SHADER_INT64 | wgpu::Features::SHADER_INT64_ATOMIC_MIN_MAX
}

pub fn program() -> Result<Program, RunError> {
    let item = ItemType::new("PatchItem", shaders::PATCH_ITEM);
    let bound = Procedure::new("bound", item.clone(), 16)
        .shared("vec4<f32>", 16)
        .emits("splitu", 1)
        .emits("splitv", 1)
        .emits("diceshade", 1)
        .body(shaders::BOUND);
    let splitu = Procedure::new("splitu", item.clone(), 4)
        .emits("bound", 2)
        .body(shaders::SPLIT);
    // splitv_execute is defined in split.wgsl, given once as SplitU's body.
    let splitv = Procedure::new("splitv", item.clone(), 4)
        .emits("bound", 2)
        .body("");
    let diceshade = Procedure::new("diceshade", item, 256)
        .shared("vec4<f32>", 256)
        .body(shaders::DICE_SHADE);
    let user = UserBindings {
        wgsl: [shaders::COMMON, shaders::SHADE, shaders::SAMPLE].concat(),
        layout: (0..6).map(|b| storage_entry(b, b < 4)).collect(),
    };
    Program::new(vec![bound, splitu, splitv, diceshade], user)
}

/// What one GPU frame produced and cost.
pub struct GpuFrame {
    pub image: FrameImage,
    pub counters: [u64; COUNTERS],
    pub run: RunStats,
    /// GPU time of the resolve pass, when timestamps exist.
    pub resolve_gpu_ms: Option<f64>,
    /// Bytes of the sample buffer.
    pub sample_bytes: u64,
    pub wall_ms: f64,
}

pub struct GpuRenderer {
    pub program: Program,
    pub scheduler: Scheduler,
    user_layout: wgpu::BindGroupLayout,
    resolve: wgpu::ComputePipeline,
}

impl GpuRenderer {
    pub fn new(gpu: &Gpu, strategy: StrategyKind) -> Result<GpuRenderer, RunError> {
        let program = program()?;
        let scheduler = Scheduler::new(gpu, &program, strategy, 1 << 14)?;
        let user_layout = gpu
            .device
            .create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("reyes scene"),
                entries: &program.user.layout,
            });
        let module = gpu.shader("reyes resolve", shaders::RESOLVE)?;
        let resolve = gpu
            .device
            .create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some("reyes resolve"),
                layout: None,
                module: &module,
                entry_point: Some("resolve"),
                compilation_options: Default::default(),
                cache: None,
            });
        Ok(GpuRenderer {
            program,
            scheduler,
            user_layout,
            resolve,
        })
    }

    pub fn render(&self, gpu: &Gpu, data: &FrameData) -> Result<GpuFrame, RunError> {
        let start = Instant::now();
        let f = &data.frame;
        let pixels = f.width as u64 * f.height as u64;
        let spp = (f.spp_x * f.spp_y) as u64;
        let upload = |label: &str, bytes: &[u8]| -> Result<wgpu::Buffer, RunError> {
            let b = gpu.storage_buffer(label, (bytes.len() as u64).div_ceil(4).max(1))?;
            gpu.queue.write_buffer(&b, 0, bytes);
            Ok(b)
        };
        let frame = upload("frame", bytemuck::bytes_of(f))?;
        let mut materials = data.materials.clone();
        if materials.is_empty() {
            materials.push(Material::zeroed());
        }
        let materials = upload("materials", bytemuck::cast_slice(&materials))?;
        let lights = upload("lights", bytemuck::cast_slice(&data.lights))?;
        let infos = upload("patch info", bytemuck::cast_slice(&data.patch_info))?;
        let samples = gpu.storage_buffer("samples", pixels * spp * 2)?;
        let counters = gpu.storage_buffer("counters", COUNTERS as u64)?;
        let bind = gpu.bind_buffers(
            "reyes scene",
            &self.user_layout,
            &[&frame, &materials, &lights, &infos, &samples, &counters],
        );
        let seeds = [Seed::new::<PatchItem>("bound", &data.items)];
        let run = self.scheduler.run(gpu, &seeds, Some(&bind))?;
        let (image, resolve_gpu_ms) = self.resolve(gpu, f.width, f.height, spp as u32, &samples)?;
        let c = gpu.read_words(&counters, 0, COUNTERS as u64)?;
        let mut counters = [0u64; COUNTERS];
        for (d, s) in counters.iter_mut().zip(c) {
            *d = s as u64;
        }
        Ok(GpuFrame {
            image,
            counters,
            run,
            resolve_gpu_ms,
            sample_bytes: pixels * spp * 8,
            wall_ms: start.elapsed().as_secs_f64() * 1e3,
        })
    }

    fn resolve(
        &self,
        gpu: &Gpu,
        width: u32,
        height: u32,
        spp: u32,
        samples: &wgpu::Buffer,
    ) -> Result<(FrameImage, Option<f64>), RunError> {
        let pixels = width as u64 * height as u64;
        let groups = pixels.div_ceil(256) as u32;
        let (gx, gy) = (groups.min(32768), groups.div_ceil(32768));
        let params = gpu.storage_buffer("resolve params", 4)?;
        gpu.queue.write_buffer(
            &params,
            0,
            bytemuck::cast_slice(&[width, height, spp, gx * 256]),
        );
        let rgba = gpu.storage_buffer("rgba", pixels * 4)?;
        let depth = gpu.storage_buffer("depth", pixels)?;
        let layout = self.resolve.get_bind_group_layout(0);
        let bind = gpu.bind_buffers("resolve", &layout, &[&params, samples, &rgba, &depth]);
        let mut timer = PassTimer::new(gpu);
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        {
            let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("resolve"),
                timestamp_writes: timer.writes(),
            });
            pass.set_pipeline(&self.resolve);
            pass.set_bind_group(0, &bind, &[]);
            pass.dispatch_workgroups(gx, gy, 1);
        }
        timer.resolve(&mut enc);
        gpu.queue.submit([enc.finish()]);
        let words = gpu.read_words(&rgba, 0, pixels * 4)?;
        let z = gpu.read_words(&depth, 0, pixels)?;
        timer.collect(gpu)?;
        let floats: Vec<f32> = bytemuck::cast_slice(&words).to_vec();
        let image = FrameImage {
            width,
            height,
            rgba: floats.chunks(4).map(|c| [c[0], c[1], c[2], c[3]]).collect(),
            depth: z.into_iter().map(f32::from_bits).collect(),
        };
        Ok((image, timer.total_ms()))
    }
}

use bytemuck::Zeroable;
