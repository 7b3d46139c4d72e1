//! `pipestats`: what the Vulkan driver's compiler made of WGSL compute shaders (registers,
//! instructions, spills, shared memory...), to see, e.g., why a persistent megakernel gets few
//! workgroups per SM.
//!
//! wgpu cannot read the driver's pipeline statistics, so this tool writes each compute entry
//! point's SPIR-V with the options wgpu-hal 30.0.1's Vulkan backend uses (from the device's
//! features, as wgpu picks them), builds the pipeline with `ash` and asks the driver through
//! `VK_KHR_pipeline_executable_properties`. The driver must support that extension: NVIDIA, AMD
//! (RADV) and Intel (ANV) do; lavapipe (Mesa 22.3) does not, and the tool then says so and exits 1.
//!
//! ```sh
//! cargo build --release -p pipestats
//! target/release/pipestats --json stats.json --ir ir/ --spv spv/ shader.wgsl
//! # on the NVIDIA machine, where the ICD is not in a standard place:
//! VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json \
//!     target/release/pipestats megakernel.wgsl
//! ```
//!
//! `--loop-bounding off`, the default, matches pipelines made by `create_shader_module_trusted`
//! with `force_loop_bounding: false`: every module of the project's commands and tests, whose
//! devices trust their loops (`Gpu::trust_loops`), and every module on lavapipe. `on` matches
//! wgpu's default, a library user's device that has not vouched for its loops. Dump the
//! scheduler's generated modules with `SCHED_DUMP_WGSL=DIR` (`scheduler::gpu::DUMP_WGSL_ENV`).
//! The device is chosen by `--adapter`, else `WGPU_ADAPTER_NAME`, else the first discrete GPU.
//! Exit status: 0, 1 on any error (bad WGSL, no device, missing extension, a failed Vulkan
//! call), 2 on a bad command line.
#![allow(
    unsafe_code,
    reason = "Vulkan through ash: wgpu has no way to read the driver's pipeline statistics"
)]

mod spv;
mod vulkan;

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use clap::{Parser, ValueEnum};
use serde::Serialize;

/// Command line.
#[derive(Parser)]
#[command(about = "What the Vulkan driver's compiler made of WGSL compute shaders")]
struct Args {
    /// wgpu's `force_loop_bounding`: off by default, as the project's commands compile every
    /// module (`Gpu::trust_loops`); on as wgpu compiles a module by default.
    #[arg(long, value_enum, default_value_t = OnOff::Off)]
    loop_bounding: OnOff,
    /// Write everything as JSON here (text representations go beside it unless `--ir`).
    #[arg(long, value_name = "OUT.json")]
    json: Option<PathBuf>,
    /// Folder for the driver's internal representations (FILE-ENTRY-EXECUTABLE-NAME.txt).
    #[arg(long, value_name = "DIR")]
    ir: Option<PathBuf>,
    /// Folder for the SPIR-V given to the driver (FILE-ENTRY.spv), written before any Vulkan work.
    #[arg(long, value_name = "DIR")]
    spv: Option<PathBuf>,
    /// Device whose name contains this (case-insensitive); default `WGPU_ADAPTER_NAME`, else
    /// the first discrete GPU, else the first device.
    #[arg(long, value_name = "SUBSTRING")]
    adapter: Option<String>,
    /// Also print each statistic's description.
    #[arg(short, long)]
    verbose: bool,
    /// WGSL files.
    #[arg(required = true, value_name = "FILE.wgsl")]
    files: Vec<PathBuf>,
}

/// `on` or `off`.
#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
enum OnOff {
    On,
    Off,
}

/// The JSON written by `--json`.
#[derive(Serialize)]
struct Report {
    device: String,
    driver: String,
    vulkan: String,
    spirv_options: spv::Target,
    pipelines: Vec<Pipeline>,
}

/// One compute entry point.
#[derive(Serialize)]
struct Pipeline {
    file: String,
    entry_point: String,
    workgroup_size: [u32; 3],
    spirv_words: usize,
    executables: Vec<vulkan::Executable>,
}

fn main() -> ExitCode {
    match run(&Args::parse()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("pipestats: {e}");
            ExitCode::FAILURE
        }
    }
}

/// A name made safe for a file name.
fn slug(s: &str) -> String {
    s.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || "-_.".contains(c) {
                c
            } else {
                '_'
            }
        })
        .collect()
}

fn write(path: &Path, data: &[u8]) -> Result<(), String> {
    std::fs::write(path, data).map_err(|e| format!("cannot write {}: {e}", path.display()))
}

/// The folder a file is in (`.` for a bare name).
fn folder(path: &Path) -> &Path {
    path.parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."))
}

fn mkdir(dir: &Path) -> Result<(), String> {
    std::fs::create_dir_all(dir).map_err(|e| format!("cannot create {}: {e}", dir.display()))
}

fn run(args: &Args) -> Result<(), String> {
    let shaders = args
        .files
        .iter()
        .map(|f| spv::load(f))
        .collect::<Result<Vec<_>, _>>()?;
    let adapter = args
        .adapter
        .clone()
        .or_else(|| std::env::var("WGPU_ADAPTER_NAME").ok());
    let gpu = vulkan::Gpu::open(adapter.as_deref());
    let loop_bounding = args.loop_bounding == OnOff::On;
    let target = match &gpu {
        Ok(gpu) => gpu.target(loop_bounding),
        Err(_) => {
            if args.spv.is_some() {
                eprintln!(
                    "pipestats: no device to take SPIR-V options from; \
                     --spv as for a Vulkan 1.3 device without robustness2"
                );
            }
            spv::Target {
                lang_version: (1, 6),
                robust_buffer_access2: false,
                robust_image_access: false,
                zero_initialize_workgroup_memory_native: true,
                force_loop_bounding: loop_bounding,
            }
        }
    };
    // SPIR-V of every compute entry point first, so `--spv` has it whatever the device lacks.
    let mut units = Vec::new();
    for shader in &shaders {
        let layout =
            spv::layout(&shader.module).map_err(|e| format!("{}: {e}", shader.path.display()))?;
        let stem = shader
            .path
            .file_stem()
            .map_or("shader".into(), |s| s.to_string_lossy().into_owned());
        let compute = |e: &&naga::EntryPoint| e.stage == naga::ShaderStage::Compute;
        for ep in shader.module.entry_points.iter().filter(compute) {
            let words = spv::write(shader, &ep.name, &target, &layout)?;
            if let Some(dir) = &args.spv {
                mkdir(dir)?;
                write(
                    &dir.join(format!("{}-{}.spv", slug(&stem), slug(&ep.name))),
                    &spv::bytes(&words),
                )?;
            }
            let pipeline = Pipeline {
                file: shader.path.display().to_string(),
                entry_point: ep.name.clone(),
                workgroup_size: ep.workgroup_size,
                spirv_words: words.len(),
                executables: Vec::new(),
            };
            units.push((pipeline, stem.clone(), words, layout.clone()));
        }
        if !shader.module.entry_points.iter().any(|e| compute(&e)) {
            eprintln!(
                "pipestats: {}: no compute entry point",
                shader.path.display()
            );
        }
    }
    let gpu = gpu?;
    let device = gpu.device()?;
    let ir_dir = args
        .ir
        .clone()
        .or_else(|| args.json.as_deref().map(|j| folder(j).to_owned()));
    let mut pipelines = Vec::new();
    for (mut pipeline, stem, words, layout) in units {
        pipeline.executables = device
            .compile(&words, &pipeline.entry_point, &layout)
            .map_err(|e| format!("{}: {}: {e}", pipeline.file, pipeline.entry_point))?;
        for exe in &mut pipeline.executables {
            let Some(dir) = &ir_dir else { break };
            mkdir(dir)?;
            for ir in &mut exe.representations {
                let ext = if ir.is_text { "txt" } else { "bin" };
                let name = [&stem, &pipeline.entry_point, &exe.name, &ir.name]
                    .map(|s| slug(s))
                    .join("-");
                let path = dir.join(format!("{name}.{ext}"));
                write(&path, &ir.data)?;
                ir.file = Some(path.display().to_string());
            }
        }
        print(&pipeline, args.verbose);
        pipelines.push(pipeline);
    }
    drop(device);
    if let Some(path) = &args.json {
        let report = Report {
            device: gpu.name.clone(),
            driver: gpu.driver.clone(),
            vulkan: vulkan::version(gpu.device_api),
            spirv_options: target,
            pipelines,
        };
        let json = serde_json::to_string_pretty(&report).map_err(|e| e.to_string())?;
        let dir = folder(path);
        let fail = |e: std::io::Error| format!("cannot write {}: {e}", path.display());
        let mut tmp = tempfile::NamedTempFile::new_in(dir).map_err(fail)?;
        std::io::Write::write_all(&mut tmp, json.as_bytes()).map_err(fail)?;
        tmp.persist(path).map_err(|e| fail(e.error))?;
    }
    Ok(())
}

/// The table: one block per executable, one line per statistic.
fn print(p: &Pipeline, verbose: bool) {
    for exe in &p.executables {
        let [x, y, z] = p.workgroup_size;
        println!(
            "{}  {}  @workgroup_size({x},{y},{z})  [{}, subgroup {}]",
            p.file, p.entry_point, exe.name, exe.subgroup_size
        );
        let width = exe
            .statistics
            .iter()
            .map(|s| s.name.len())
            .max()
            .unwrap_or(0);
        for s in &exe.statistics {
            let value = serde_json::to_string(&s.value).unwrap_or_default();
            println!("  {:width$}  {value:>12}", s.name);
            if verbose {
                println!("  {:width$}    {}", "", s.description);
            }
        }
    }
}
