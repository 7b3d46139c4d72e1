//! Runs `pipestats` on a small compute shader: the SPIR-V must appear whatever the device, then
//! either statistics (a driver with VK_KHR_pipeline_executable_properties, e.g. NVIDIA) or exit
//! status 1 naming the extension (lavapipe).

use std::process::Command;

const SHADER: &str = "
@group(0) @binding(0) var<storage, read_write> data: array<u32>;
@group(0) @binding(1) var<storage, read_write> total: atomic<u32>;
var<workgroup> tile: array<u32, 64>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(local_invocation_index) i: u32) {
    tile[i] = data[id.x];
    workgroupBarrier();
    var s = 0u;
    for (var k = 0u; k < 64u; k++) { s += tile[(i + k) % 64u]; }
    data[id.x] = s;
    atomicAdd(&total, s);
}
";

#[test]
fn spirv_then_statistics_or_missing_extension() {
    let dir = tempfile::tempdir().unwrap();
    let wgsl = dir.path().join("sum.wgsl");
    std::fs::write(&wgsl, SHADER).unwrap();
    let (spv, json) = (dir.path().join("spv"), dir.path().join("stats.json"));
    let out = Command::new(env!("CARGO_BIN_EXE_pipestats"))
        .arg("--spv")
        .arg(&spv)
        .arg("--json")
        .arg(&json)
        .arg(&wgsl)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    let words =
        std::fs::read(spv.join("sum-main.spv")).expect("SPIR-V written before any Vulkan work");
    assert!(
        words.len() > 20 && words.len() % 4 == 0,
        "{} bytes",
        words.len()
    );
    assert_eq!(
        u32::from_le_bytes(words[..4].try_into().unwrap()),
        0x0723_0203,
        "SPIR-V magic"
    );
    match out.status.code() {
        Some(0) => {
            let report: serde_json::Value =
                serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
            let stats = &report["pipelines"][0]["executables"][0]["statistics"];
            assert!(
                stats.as_array().is_some_and(|s| !s.is_empty()),
                "no statistics: {report}"
            );
        }
        Some(1) => assert!(
            stderr.contains("VK_KHR_pipeline_executable_properties"),
            "{stderr}"
        ),
        code => panic!("exit status {code:?}: {stderr}"),
    }
}

#[test]
fn bad_wgsl_names_file_and_line() {
    let dir = tempfile::tempdir().unwrap();
    let wgsl = dir.path().join("bad.wgsl");
    std::fs::write(
        &wgsl,
        "@compute @workgroup_size(1)\nfn main() {\n    let x: u32 = nope;\n}\n",
    )
    .unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_pipestats"))
        .arg(&wgsl)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("bad.wgsl") && stderr.contains(":3:") && stderr.contains("nope"),
        "{stderr}"
    );
}
